// Baseline atlases for `isocharts bench`: LSCM charts by Lloyd region growing, their
// stretch-optimized variant, and atlases read from other tools. The only CGAL user here is
// lscm_layout (CGAL's LSCM parameterizer).

#include "atlas_charts.h"
#include "isochart/baselines.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <unordered_map>

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#include <tbb/parallel_for.h>

#include "isochart/error.h"
#include "isochart/stretch.h"

namespace isochart {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ---- LSCM through CGAL ----------------------------------------------------------------------

// LSCM of a disk chart (chart-local positions and faces). Returns false when CGAL fails.
bool lscm_layout(const std::vector<Vec3d>& positions, const std::vector<Face>& faces, std::vector<Vec2d>& uv) {
  using Kernel = CGAL::Simple_cartesian<double>;
  using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
  using VertexIndex = SurfaceMesh::Vertex_index;
  namespace SMP = CGAL::Surface_mesh_parameterization;

  SurfaceMesh sm;
  std::vector<VertexIndex> vid(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v)
    vid[v] = sm.add_vertex(Kernel::Point_3(positions[v].x, positions[v].y, positions[v].z));
  for (const Face& f : faces)
    if (sm.add_face(vid[f[0]], vid[f[1]], vid[f[2]]) == SurfaceMesh::null_face()) return false;
  SurfaceMesh::Halfedge_index border = SurfaceMesh::null_halfedge();
  for (auto h : sm.halfedges())
    if (sm.is_border(h)) {
      border = h;
      break;
    }
  if (border == SurfaceMesh::null_halfedge()) return false;
  auto uv_map = sm.add_property_map<VertexIndex, Kernel::Point_2>("v:uv").first;
  // CGAL 5.5's get_error_message table is off by one: only success matters here.
  const SMP::Error_code err = SMP::parameterize(sm, SMP::LSCM_parameterizer_3<SurfaceMesh>(), border, uv_map);
  if (err != SMP::OK) return false;
  uv.resize(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const auto p = uv_map[vid[v]];
    uv[v] = {p.x(), p.y()};
    if (!is_finite(uv[v])) return false;
  }
  return true;
}

double signed_uv_area(const std::vector<Face>& faces, const std::vector<Vec2d>& uv) {
  double a = 0;
  for (const Face& f : faces) {
    const Vec2d e1 = uv[f[1]] - uv[f[0]], e2 = uv[f[2]] - uv[f[0]];
    a += 0.5 * (e1.x * e2.y - e1.y * e2.x);
  }
  return a;
}

void mirror_if_negative(const std::vector<Face>& faces, std::vector<Vec2d>& uv) {
  if (signed_uv_area(faces, uv) < 0)
    for (Vec2d& p : uv) p.x = -p.x;
}

bool self_overlaps(const std::vector<Face>& faces, const std::vector<Vec2d>& uv) {
  if (uv_layout_is_embedding(faces, uv)) return false;
  std::vector<std::array<Vec2d, 3>> tris(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) tris[i] = {uv[faces[i][0]], uv[faces[i][1]], uv[faces[i][2]]};
  return !overlapping_uv_pairs(tris, 1).empty();
}

bool disk_topology(const Mesh& chart) {
  const Topology t(chart);
  return t.is_manifold() && t.num_components() == 1 && t.boundary_loops().size() == 1 &&
         t.euler_characteristic() == 1;
}

// ---- Region growing -------------------------------------------------------------------------

// A chart in the making: parent face ids, and its accepted layout (chart-local, per sub vertex).
struct Region {
  std::vector<int> faces;
  SubMesh sub;
  std::vector<Vec2d> uv;
  bool accepted = false;
};

class LscmBuilder {
 public:
  LscmBuilder(const Mesh& mesh, const LscmOptions& o, const Progress& progress)
      : mesh_(mesh), o_(o), progress_(progress), topo_(mesh) {
    normals_ = face_normals(mesh);
    areas_ = face_areas(mesh);
    centroids_.resize(mesh.faces.size());
    for (int f = 0; f < mesh.num_faces(); ++f) {
      const Face& t = mesh.faces[f];
      centroids_[f] = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    }
  }

  Atlas run() {
    const auto t0 = Clock::now();
    std::vector<std::vector<int>> pending(topo_.num_components());
    for (int f = 0; f < mesh_.num_faces(); ++f) pending[topo_.face_components()[f]].push_back(f);
    std::vector<Region> done;
    double seconds_clustering = 0, seconds_param = 0;
    int splits = 0;
    // Rounds: every pending region is tried (in parallel); failures are split and retried in the
    // next round. Outputs are stored by index, so the order never depends on threads.
    while (!pending.empty()) {
      std::vector<Region> tried(pending.size());
      const auto tp = Clock::now();
      tbb::parallel_for(std::size_t(0), pending.size(), [&](std::size_t i) {
        tried[i].faces = std::move(pending[i]);
        try_accept(tried[i]);
      });
      seconds_param += since(tp);
      std::vector<std::vector<int>> next;
      std::vector<std::vector<std::vector<int>>> parts(tried.size());
      const auto tc = Clock::now();
      tbb::parallel_for(std::size_t(0), tried.size(), [&](std::size_t i) {
        if (!tried[i].accepted) parts[i] = split(tried[i].faces);
      });
      seconds_clustering += since(tc);
      for (std::size_t i = 0; i < tried.size(); ++i) {
        if (tried[i].accepted) {
          done.push_back(std::move(tried[i]));
        } else {
          ++splits;
          for (auto& p : parts[i]) next.push_back(std::move(p));
        }
      }
      pending = std::move(next);
      long long left = 0;
      for (const auto& p : pending) left += static_cast<long long>(p.size());
      report(progress_, Stage::Clustering, 1.0 - static_cast<double>(left) / mesh_.num_faces());
    }
    // Largest charts first, ties by first face: a stable order independent of the rounds.
    std::sort(done.begin(), done.end(), [](const Region& a, const Region& b) {
      if (a.faces.size() != b.faces.size()) return a.faces.size() > b.faces.size();
      return *std::min_element(a.faces.begin(), a.faces.end()) < *std::min_element(b.faces.begin(), b.faces.end());
    });

    Atlas atlas;
    atlas.face_chart.assign(mesh_.faces.size(), -1);
    atlas.face_uvs.resize(mesh_.faces.size());
    for (std::size_t c = 0; c < done.size(); ++c) {
      const Region& r = done[c];
      const int base = static_cast<int>(atlas.uvs.size());
      atlas.uvs.insert(atlas.uvs.end(), r.uv.begin(), r.uv.end());
      ChartInfo info;
      info.faces = static_cast<int>(r.faces.size());
      for (std::size_t i = 0; i < r.sub.face_to_parent.size(); ++i) {
        const int f = r.sub.face_to_parent[i];
        atlas.face_chart[f] = static_cast<int>(c);
        for (int k = 0; k < 3; ++k) atlas.face_uvs[f][k] = base + r.sub.mesh.faces[i][k];
        info.area_3d += areas_[f];
      }
      const StretchStats st = measure_stretch(r.sub.mesh.positions, r.sub.mesh.faces, r.uv);
      info.l2 = st.l2;
      info.linf = st.linf;
      atlas.charts.push_back(info);
    }
    atlas.stats.charts_before_merge = atlas.num_charts();
    atlas.stats.seconds["clustering"] = seconds_clustering;
    atlas.stats.seconds["parameterization"] = seconds_param;
    const auto tk = Clock::now();
    pack_atlas(mesh_, atlas, o_.pack, progress_);
    atlas.stats.seconds["packing"] = since(tk);
    atlas.stats.seconds["total"] = since(t0);
    atlas.stats.splits = splits;
    return atlas;
  }

 private:
  void try_accept(Region& r) const {
    r.sub = extract_submesh(mesh_, r.faces);
    const Mesh& m = r.sub.mesh;
    if (r.faces.size() == 1) {
      // A single triangle laid out isometrically: nothing left to split.
      const Vec3d a = m.positions[m.faces[0][0]], b = m.positions[m.faces[0][1]], c = m.positions[m.faces[0][2]];
      const Vec3d e1 = b - a, e2 = c - a;
      const double l1 = norm(e1);
      const double x = l1 > 0 ? dot(e2, e1) / l1 : 0;
      const double y = std::sqrt(std::max(squared_norm(e2) - x * x, 0.0));
      r.uv.assign(3, Vec2d{});
      r.uv[m.faces[0][0]] = {0, 0};
      r.uv[m.faces[0][1]] = {l1, 0};
      r.uv[m.faces[0][2]] = {x, y};
      r.accepted = true;
      return;
    }
    if (!disk_topology(m)) return;
    if (!lscm_layout(m.positions, m.faces, r.uv)) return;
    mirror_if_negative(m.faces, r.uv);
    const StretchStats st = measure_stretch(m.positions, m.faces, r.uv);
    if (st.flipped > 0 || !(st.l2 <= o_.max_l2) || !(st.linf <= o_.max_linf)) return;
    if (self_overlaps(m.faces, r.uv)) return;
    r.accepted = true;
  }

  // Splits a region in two by Lloyd clustering; returns the edge-connected pieces.
  std::vector<std::vector<int>> split(const std::vector<int>& faces) const {
    const int n = static_cast<int>(faces.size());
    std::unordered_map<int, int> local;
    local.reserve(faces.size() * 2);
    for (int i = 0; i < n; ++i) local.emplace(faces[i], i);
    std::vector<std::array<int, 3>> adj(n);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const int g = topo_.opposite_face(faces[i], k);
        const auto it = g >= 0 ? local.find(g) : local.end();
        adj[i][k] = it == local.end() ? -1 : it->second;
      }

    // Multi-source Dijkstra with the seed's normal in the cost; label = nearest seed.
    std::vector<int> label(n);
    std::vector<double> dist(n);
    auto grow = [&](const std::vector<int>& seeds) {
      std::fill(label.begin(), label.end(), -1);
      std::fill(dist.begin(), dist.end(), std::numeric_limits<double>::infinity());
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
      for (int s = 0; s < static_cast<int>(seeds.size()); ++s) {
        dist[seeds[s]] = 0;
        label[seeds[s]] = s;
        q.push({0.0, seeds[s]});
      }
      while (!q.empty()) {
        const auto [d, i] = q.top();
        q.pop();
        if (d > dist[i]) continue;
        const Vec3d ns = normals_[faces[seeds[label[i]]]];
        for (int k = 0; k < 3; ++k) {
          const int j = adj[i][k];
          if (j < 0) continue;
          const double step = (o_.normal_lambda - dot(ns, normals_[faces[j]])) *
                              norm(centroids_[faces[j]] - centroids_[faces[i]]);
          const double nd = d + std::max(step, 1e-300);
          if (nd < dist[j] || (nd == dist[j] && label[i] < label[j])) {
            dist[j] = nd;
            label[j] = label[i];
            q.push({nd, j});
          }
        }
      }
    };
    auto farthest = [&](int from) {
      grow({from});
      int best = from;
      for (int i = 0; i < n; ++i)
        if (label[i] >= 0 && dist[i] > dist[best]) best = i;
      return best;
    };
    const int s0 = farthest(0);
    const int s1 = farthest(s0);
    std::vector<int> seeds = {s0, s1};
    if (s0 != s1) {
      grow(seeds);
      for (int it = 0; it < o_.lloyd_iterations; ++it) {
        // Re-centre each seed on the face nearest its region's area-weighted centroid.
        std::vector<Vec3d> c(2);
        std::vector<double> w(2, 0.0);
        for (int i = 0; i < n; ++i)
          if (label[i] >= 0) {
            c[label[i]] += centroids_[faces[i]] * areas_[faces[i]];
            w[label[i]] += areas_[faces[i]];
          }
        std::vector<int> ns = seeds;
        std::vector<double> best(2, std::numeric_limits<double>::infinity());
        for (int i = 0; i < n; ++i) {
          const int l = label[i];
          if (l < 0 || w[l] <= 0) continue;
          const double d = squared_norm(centroids_[faces[i]] - c[l] / w[l]);
          if (d < best[l]) {
            best[l] = d;
            ns[l] = i;
          }
        }
        if (ns == seeds || ns[0] == ns[1]) break;
        seeds = ns;
        grow(seeds);
      }
    } else {
      grow(seeds);
    }
    // Unreached faces (a disconnected region) go with label 1 and become their own pieces.
    for (int i = 0; i < n; ++i)
      if (label[i] < 0) label[i] = 1;
    // A degenerate split (everything on one side) falls back to halving the face order: a
    // region always shrinks, so the recursion ends at single triangles.
    const long long ones = std::count(label.begin(), label.end(), 1);
    if (ones == 0 || ones == n)
      for (int i = 0; i < n; ++i) label[i] = i < n / 2 ? 0 : 1;

    // Edge-connected pieces of each side, in order of their first face.
    std::vector<int> piece(n, -1);
    std::vector<std::vector<int>> out;
    for (int i = 0; i < n; ++i) {
      if (piece[i] >= 0) continue;
      const int p = static_cast<int>(out.size());
      out.emplace_back();
      std::vector<int> stack = {i};
      piece[i] = p;
      while (!stack.empty()) {
        const int a = stack.back();
        stack.pop_back();
        out[p].push_back(faces[a]);
        for (int k = 0; k < 3; ++k) {
          const int b = adj[a][k];
          if (b >= 0 && piece[b] < 0 && label[b] == label[a]) {
            piece[b] = p;
            stack.push_back(b);
          }
        }
      }
      std::sort(out[p].begin(), out[p].end());
    }
    return out;
  }

  const Mesh& mesh_;
  const LscmOptions& o_;
  const Progress& progress_;
  Topology topo_;
  std::vector<Vec3d> normals_, centroids_;
  std::vector<double> areas_;
};

// Chart-local copies of an atlas's charts: positions, faces and layout per chart.
}  // namespace

bool is_disk(const Mesh& mesh, const std::vector<int>& faces) {
  return disk_topology(extract_submesh(mesh, faces).mesh);
}

Atlas build_lscm_atlas(const Mesh& mesh, const LscmOptions& options, const Progress& progress) {
  if (!(options.max_l2 >= 1.0)) throw InputError("", "lscm: max_l2 must be at least 1");
  if (!(options.max_linf >= 1.0)) throw InputError("", "lscm: max_linf must be at least 1");
  if (options.lloyd_iterations < 0) throw InputError("", "lscm: lloyd_iterations must not be negative");
  if (!(options.normal_lambda > 1.0) || !std::isfinite(options.normal_lambda))
    throw InputError("", "lscm: normal_lambda must be a finite number above 1");
  if (mesh.faces.empty()) throw InputError("", "mesh has no faces");
  {
    const Topology t(mesh);
    if (!t.nonmanifold_edges().empty()) {
      const auto& e = t.edge(t.nonmanifold_edges()[0]);
      throw InputError("", "edge (" + std::to_string(e.v0) + "," + std::to_string(e.v1) +
                               ") has more than two faces; the lscm baseline needs a manifold mesh");
    }
  }
  LscmBuilder b(mesh, options, progress);
  return b.run();
}

void optimize_atlas_stretch(const Mesh& mesh, Atlas& atlas, const OptimizeOptions& options,
                            const PackOptions& pack, const Progress& progress) {
  const auto t0 = Clock::now();
  std::vector<detail::AtlasChart> charts = detail::split_atlas_charts(mesh, atlas);
  std::atomic<int> finished{0};
  tbb::parallel_for(std::size_t(0), charts.size(), [&](std::size_t c) {
    detail::AtlasChart& ch = charts[c];
    OptimizeOptions o = options;
    // Per-chart stream from the user seed and the chart's identity (its first face).
    o.seed = options.seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(ch.faces.front());
    std::vector<Vec2d> uv = ch.uv;
    const OptimizeResult r = optimize_stretch(ch.positions, ch.tris, uv, o);
    if (r.after.flipped == 0 && r.after.l2 <= r.before.l2 && !self_overlaps(ch.tris, uv)) ch.uv = std::move(uv);
    report(progress, Stage::Optimization, static_cast<double>(++finished) / charts.size());
  });
  for (std::size_t c = 0; c < charts.size(); ++c) {
    const detail::AtlasChart& ch = charts[c];
    for (std::size_t i = 0; i < ch.uv_ids.size(); ++i) atlas.uvs[ch.uv_ids[i]] = ch.uv[i];
    const StretchStats st = measure_stretch(ch.positions, ch.tris, ch.uv);
    atlas.charts[c].l2 = st.l2;
    atlas.charts[c].linf = st.linf;
  }
  atlas.stats.seconds["optimization"] = since(t0);
  const auto tp = Clock::now();
  pack_atlas(mesh, atlas, pack, progress);
  atlas.stats.seconds["packing"] = since(tp);
  atlas.stats.seconds["total"] += since(t0);
}

Atlas atlas_from_uvs(const Mesh& mesh, double texture_aspect) {
  if (!mesh.has_uvs()) throw InputError("", "the atlas has no texture coordinates");
  int nc = 0;
  const std::vector<int> chart = uv_charts(mesh, nc);
  Atlas atlas;
  atlas.face_chart = chart;
  atlas.face_uvs.resize(mesh.faces.size());
  atlas.charts.resize(nc);
  // One uv per (chart, mesh uv id), so charts never share texture coordinates.
  std::vector<std::unordered_map<int, int>> ids(nc);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int c = chart[f];
    for (int k = 0; k < 3; ++k) {
      const int u = mesh.face_uvs[f][k];
      const auto [it, fresh] = ids[c].emplace(u, static_cast<int>(atlas.uvs.size()));
      if (fresh) atlas.uvs.push_back(mesh.uvs[u]);
      atlas.face_uvs[f][k] = it->second;
    }
    ++atlas.charts[c].faces;
  }
  // Coordinates laid out for a W×H texture are W/H times too short along u for their surface:
  // packed, measured or optimized as they are, every chart would count as flattened.
  if (!(texture_aspect >= 0) || !std::isfinite(texture_aspect))
    throw InputError("", "the texture aspect ratio of an atlas must be 0 (read from the UVs) or positive");
  const double aspect = texture_aspect > 0 ? texture_aspect : detect_texture_aspect(mesh);
  if (aspect != 1.0)
    for (Vec2d& p : atlas.uvs) p.x *= aspect;
  std::vector<detail::AtlasChart> charts = detail::split_atlas_charts(mesh, atlas);
  for (int c = 0; c < nc; ++c) {
    detail::AtlasChart& ch = charts[c];
    const double area = signed_uv_area(ch.tris, ch.uv);
    if (area == 0 || !std::isfinite(area))
      throw InputError("", "chart " + std::to_string(c) + " (face " + std::to_string(ch.faces.front()) +
                               ") has zero texture area");
    if (area < 0) {
      for (Vec2d& p : ch.uv) p.x = -p.x;
      for (std::size_t i = 0; i < ch.uv_ids.size(); ++i) atlas.uvs[ch.uv_ids[i]] = ch.uv[i];
    }
    const StretchStats st = measure_stretch(ch.positions, ch.tris, ch.uv);
    atlas.charts[c].area_3d = st.area_3d;
    atlas.charts[c].l2 = st.l2;
    atlas.charts[c].linf = st.linf;
  }
  atlas.stats.charts = nc;
  atlas.stats.charts_before_merge = nc;
  return atlas;
}

}  // namespace isochart
