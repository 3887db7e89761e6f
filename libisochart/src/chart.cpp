#include "chart.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <limits>
#include <numeric>
#include <queue>
#include <unordered_map>

#include "isochart/embedding.h"
#include "isochart/geodesic.h"
#include "isochart/optimize.h"
#include "isochart/signal.h"
#include "isochart/stretch.h"

namespace isochart::detail {

ChartGeometry make_chart(const Mesh& mesh, const std::vector<int>& faces) {
  ChartGeometry g;
  g.faces = faces;
  std::unordered_map<int, int> local;
  local.reserve(faces.size());
  g.tris.reserve(faces.size());
  for (int pf : faces) {
    Face t;
    for (int k = 0; k < 3; ++k) {
      const int pv = mesh.faces[pf][k];
      auto [it, inserted] = local.emplace(pv, g.num_vertices());
      if (inserted) {
        g.positions.push_back(mesh.positions[pv]);
        g.vertex_parent.push_back(pv);
      }
      t[k] = it->second;
    }
    g.tris.push_back(t);
  }
  return g;
}

void cut_along_edges(ChartGeometry& g, const std::vector<char>& cut_edge, std::vector<int>* origin,
                     const Topology* given) {
  const Topology own = given ? Topology() : Topology(g.tris, g.num_vertices());
  const Topology& topo = given ? *given : own;
  const int nv = g.num_vertices();
  if (origin && origin->empty()) {
    origin->resize(nv);
    std::iota(origin->begin(), origin->end(), 0);
  }
  std::vector<int> parent;
  for (int v = 0; v < nv; ++v) {
    const IndexRange vf = topo.vertex_faces(v);
    if (vf.size() < 2) continue;
    // Group the faces around v into fans joined by uncut edges through v.
    parent.resize(vf.size());
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (int i = 0; i < vf.size(); ++i)
      for (int j = i + 1; j < vf.size(); ++j) {
        for (int k = 0; k < 3; ++k) {
          const int e = topo.face_edge(vf[i], k);
          const auto& ed = topo.edge(e);
          if ((ed.v0 != v && ed.v1 != v) || cut_edge[e]) continue;
          if (topo.opposite_face(vf[i], k) == vf[j]) {
            const int a = find(i), b = find(j);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
          }
        }
      }
    // The fan containing the first face keeps v; every other fan gets a copy.
    std::vector<int> copy_of(vf.size(), -1);
    for (int i = 0; i < vf.size(); ++i) {
      const int r = find(i);
      if (r == find(0)) continue;
      if (copy_of[r] < 0) {
        copy_of[r] = g.num_vertices();
        g.positions.push_back(g.positions[v]);
        g.vertex_parent.push_back(g.vertex_parent[v]);
        if (origin) origin->push_back((*origin)[v]);
      }
      Face& t = g.tris[vf[i]];
      for (int k = 0; k < 3; ++k)
        if (t[k] == v) t[k] = copy_of[r];
    }
  }
}

Topology chart_topology(ChartGeometry& g) {
  Topology t(g.tris, g.num_vertices());
  if (t.nonmanifold_vertices().empty()) return t;
  cut_along_edges(g, std::vector<char>(t.num_edges(), 0), nullptr, &t);
  return Topology(g.tris, g.num_vertices());
}

bool cut_to_disk(ChartGeometry& g, std::vector<int>* origin, const Topology* given) {
  const Topology own = given ? Topology() : Topology(g.tris, g.num_vertices());
  const Topology& topo = given ? *given : own;
  const auto& loops = topo.boundary_loops();
  if (origin) {
    origin->resize(g.num_vertices());
    std::iota(origin->begin(), origin->end(), 0);
  }
  if (loops.empty() || topo.num_components() != 1 || topo.genus() != 0) return false;
  if (loops.size() == 1) return true;
  const int nv = g.num_vertices();
  // Label each boundary vertex with its loop.
  std::vector<int> loop_of(nv, -1);
  for (int l = 0; l < static_cast<int>(loops.size()); ++l)
    for (int v : loops[l]) loop_of[v] = l;
  std::vector<char> connected_loop(loops.size(), 0);
  connected_loop[0] = 1;
  std::vector<char> in_tree(nv, 0);
  for (int v : loops[0]) in_tree[v] = 1;
  std::vector<char> cut(topo.num_edges(), 0);
  std::vector<double> dist(nv);
  std::vector<int> pred(nv);
  for (size_t joined = 1; joined < loops.size(); ++joined) {
    // Multi-source Dijkstra along edges from everything already connected to the first loop.
    std::fill(dist.begin(), dist.end(), std::numeric_limits<double>::infinity());
    std::fill(pred.begin(), pred.end(), -1);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
    for (int v = 0; v < nv; ++v)
      if (in_tree[v]) {
        dist[v] = 0;
        heap.push({0.0, v});
      }
    int target = -1;
    while (!heap.empty()) {
      auto [d, v] = heap.top();
      heap.pop();
      if (d > dist[v]) continue;
      if (loop_of[v] >= 0 && !connected_loop[loop_of[v]]) {
        target = v;
        break;
      }
      for (int w : topo.vertex_neighbors(v)) {
        // Paths run through the interior: never along another boundary than their ends.
        if (loop_of[w] >= 0 && connected_loop[loop_of[w]] && !in_tree[w]) continue;
        const double nd = d + norm(g.positions[v] - g.positions[w]);
        if (nd < dist[w]) {
          dist[w] = nd;
          pred[w] = v;
          heap.push({nd, w});
        }
      }
    }
    if (target < 0) return false;
    const int l = loop_of[target];
    connected_loop[l] = 1;
    for (int v : loops[l]) in_tree[v] = 1;
    for (int v = target; pred[v] >= 0; v = pred[v]) {
      cut[topo.find_edge(v, pred[v])] = 1;
      in_tree[v] = in_tree[pred[v]] = 1;
    }
  }
  cut_along_edges(g, cut, origin, &topo);
  const Topology after(g.tris, g.num_vertices());
  return after.boundary_loops().size() == 1 && after.num_components() == 1;
}

std::vector<double> boundary_distance(const ChartGeometry& g, const Topology& topo) {
  std::vector<int> sources;
  for (const auto& loop : topo.boundary_loops()) sources.insert(sources.end(), loop.begin(), loop.end());
  std::vector<double> dist;
  GeodesicSolver(g.positions, g.tris).distances(sources, dist);
  return dist;
}

bool is_sock(const ChartGeometry& g, const Topology& topo, const std::vector<double>& dist) {
  if (topo.boundary_loops().size() != 1) return false;
  const auto& loop = topo.boundary_loops()[0];
  double length = 0, far = 0;
  for (size_t i = 0; i < loop.size(); ++i) length += norm(g.positions[loop[i]] - g.positions[loop[(i + 1) % loop.size()]]);
  for (double d : dist)
    if (std::isfinite(d)) far = std::max(far, d);
  return length > 0 && far > 0.4 * length;
}

bool cut_seam(ChartGeometry& g, const Topology& topo, const std::vector<double>* given) {
  if (topo.boundary_loops().size() != 1 || topo.genus() != 0 || topo.num_components() != 1) return false;
  const std::vector<double> own = given ? std::vector<double>() : boundary_distance(g, topo);
  const std::vector<double>& dist = given ? *given : own;
  int tip = -1;
  for (int v = 0; v < g.num_vertices(); ++v)
    if (std::isfinite(dist[v]) && (tip < 0 || dist[v] > dist[tip])) tip = v;
  if (tip < 0 || !(dist[tip] > 0)) return false;
  std::vector<char> cut(topo.num_edges(), 0);
  int steps = 0;
  for (int v = tip; !topo.is_boundary_vertex(v); ++steps) {
    int next = -1;
    for (int w : topo.vertex_neighbors(v))
      if (next < 0 || dist[w] < dist[next]) next = w;
    // The field decreases towards the boundary from every interior vertex; guard anyway.
    if (next < 0 || !(dist[next] < dist[v]) || steps > g.num_vertices()) return false;
    cut[topo.find_edge(v, next)] = 1;
    v = next;
  }
  if (steps == 0) return false;
  cut_along_edges(g, cut, nullptr, &topo);
  const Topology after(g.tris, g.num_vertices());
  return after.boundary_loops().size() == 1 && after.num_components() == 1;
}

void open_slits(const ChartGeometry& g, const std::vector<int>& origin, std::vector<Vec2d>& uv) {
  std::vector<int> copies(g.num_vertices(), 0);
  for (int o : origin) ++copies[o];
  std::vector<Vec2d> pull(g.num_vertices());
  std::vector<int> count(g.num_vertices(), 0);
  for (const Face& t : g.tris) {
    const Vec2d c = (uv[t[0]] + uv[t[1]] + uv[t[2]]) / 3.0;
    for (int k = 0; k < 3; ++k) {
      pull[t[k]] += c;
      ++count[t[k]];
    }
  }
  for (int v = 0; v < g.num_vertices(); ++v)
    if (copies[origin[v]] > 1 && count[v] > 0) uv[v] += (pull[v] / count[v] - uv[v]) * 0.01;
}

bool lscm(const ChartGeometry& g, std::vector<Vec2d>& uv, const Topology* given) {
  const int nv = g.num_vertices();
  const Topology own = given ? Topology() : Topology(g.tris, nv);
  const Topology& topo = given ? *given : own;
  if (topo.boundary_loops().empty()) return false;
  // Pin the two boundary vertices farthest apart (approximately: farthest from the first, then
  // farthest from that one).
  const auto& loop = topo.boundary_loops()[0];
  auto farthest = [&](int from) {
    int best = loop[0];
    double bd = -1;
    for (int v : loop) {
      const double d = squared_norm(g.positions[v] - g.positions[from]);
      if (d > bd) {
        bd = d;
        best = v;
      }
    }
    return best;
  };
  const int p0 = farthest(loop[0]);
  const int p1 = farthest(p0);
  if (p0 == p1) return false;
  const double pin_len = norm(g.positions[p0] - g.positions[p1]);
  // With z = u + iv per vertex and w_k = ∂φk/∂x + i ∂φk/∂y, a face's Cauchy–Riemann residuals
  // are the real and imaginary parts of Σ w_k z_k, so LSCM is a complex least-squares problem
  // whose normal matrix is Hermitian with one entry per vertex pair: half the unknowns of the
  // real (u, v) system, a quarter of its entries, and no sparse product to form it.
  std::vector<int> index(nv, -1);
  int n = 0;
  for (int v = 0; v < nv; ++v)
    if (v != p0 && v != p1 && topo.is_referenced(v)) index[v] = n++;
  using Complex = std::complex<double>;
  const Complex pinned[2] = {{0, 0}, {pin_len, 0}};
  auto pin_of = [&](int v) { return v == p0 ? pinned[0] : pinned[1]; };
  std::vector<Eigen::Triplet<Complex>> trips;
  trips.reserve(9 * g.tris.size());
  Eigen::VectorXcd rhs = Eigen::VectorXcd::Zero(n);
  for (const Face& t : g.tris) {
    const Vec3d a = g.positions[t[0]], b = g.positions[t[1]], c = g.positions[t[2]];
    const Vec3d e1 = b - a, e2 = c - a;
    const double l1 = norm(e1);
    const double area = 0.5 * norm(cross(e1, e2));
    if (l1 <= 0 || area <= 0) continue;
    const Vec3d ux = e1 / l1;
    const double x[3] = {0, l1, dot(e2, ux)};
    const double y[3] = {0, 0, std::sqrt(std::max(squared_norm(e2) - x[2] * x[2], 0.0))};
    const double s = 1.0 / std::sqrt(2 * area);  // sqrt(A) · 1/(2A): area-weighted residuals
    Complex w[3];
    for (int k = 0; k < 3; ++k)
      w[k] = Complex((y[(k + 1) % 3] - y[(k + 2) % 3]) * s, (x[(k + 2) % 3] - x[(k + 1) % 3]) * s);
    Complex fixed = 0;  // the pinned corners' part of the residual
    for (int k = 0; k < 3; ++k)
      if (index[t[k]] < 0) fixed += w[k] * pin_of(t[k]);
    for (int i = 0; i < 3; ++i) {
      const int r = index[t[i]];
      if (r < 0) continue;
      rhs[r] -= std::conj(w[i]) * fixed;
      for (int k = 0; k < 3; ++k)
        if (index[t[k]] >= 0) trips.emplace_back(r, index[t[k]], std::conj(w[i]) * w[k]);
    }
  }
  Eigen::SparseMatrix<Complex> N(n, n);
  N.setFromTriplets(trips.begin(), trips.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<Complex>> solver(N);
  if (solver.info() != Eigen::Success) return false;
  const Eigen::VectorXcd sol = solver.solve(rhs);
  if (solver.info() != Eigen::Success || !sol.allFinite()) return false;
  uv.assign(nv, Vec2d{});
  for (int v = 0; v < nv; ++v) {
    if (index[v] >= 0)
      uv[v] = {sol[index[v]].real(), sol[index[v]].imag()};
    else if (v == p0 || v == p1)
      uv[v] = {pin_of(v).real(), pin_of(v).imag()};
  }
  return true;
}

std::vector<std::array<double, 3>> chart_metric(const ChartGeometry& g,
                                                const std::vector<std::array<double, 3>>& parent) {
  std::vector<std::array<double, 3>> m(g.faces.size());
  for (size_t f = 0; f < g.faces.size(); ++f) m[f] = parent[g.faces[f]];
  return m;
}

void evaluate(const ChartGeometry& g, ChartParam& p, const ParamOptions& o, const Topology* topology) {
  const StretchStats st = measure_stretch(g.positions, g.tris, p.uv);
  p.l2 = st.l2;
  p.geometric_l2 = st.l2;
  p.linf = st.linf;
  p.flipped = st.flipped;
  p.overlaps = false;
  constexpr double kSlack = kStretchBoundSlack;  // bounds hold up to rounding
  const double max_l2 = o.max_l2 * kSlack, max_linf = o.max_linf * kSlack;
  bool geometric_ok = true;
  if (o.face_metric) {
    // Signal-specialized (§7): the signal-metric L2 decides, the geometric L2 only guards.
    p.l2 = metric_l2_stretch(g.positions, g.tris, p.uv, chart_metric(g, *o.face_metric));
    geometric_ok = st.l2 <= o.max_geometric_l2 * kSlack;
  }
  // The exact overlap test is the expensive part: only charts that meet the bounds need it,
  // and most of those are proven one-to-one by their boundary alone (9 % of a bunny atlas's
  // CPU went to the all-pairs test).
  if (st.flipped == 0 && p.l2 <= max_l2 && st.linf <= max_linf && geometric_ok &&
      !(topology ? uv_layout_is_embedding(g.tris, p.uv, *topology) : uv_layout_is_embedding(g.tris, p.uv))) {
    std::vector<std::array<Vec2d, 3>> tris(g.tris.size());
    for (size_t f = 0; f < g.tris.size(); ++f)
      for (int k = 0; k < 3; ++k) tris[f][k] = p.uv[g.tris[f][k]];
    p.overlaps = !overlapping_uv_pairs(tris, 1).empty();
  }
  p.accepted = st.flipped == 0 && !p.overlaps && p.l2 <= max_l2 && st.linf <= max_linf && geometric_ok;
}

double multiply_covered_fraction(const std::vector<Face>& tris, const std::vector<Vec2d>& uv, double cells) {
  Vec2d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2d hi = -lo;
  for (const Face& t : tris)
    for (int k = 0; k < 3; ++k) {
      lo = {std::min(lo.x, uv[t[k]].x), std::min(lo.y, uv[t[k]].y)};
      hi = {std::max(hi.x, uv[t[k]].x), std::max(hi.y, uv[t[k]].y)};
    }
  const double bw = hi.x - lo.x, bh = hi.y - lo.y;
  if (!(bw > 0) || !(bh > 0) || !std::isfinite(bw * bh)) return 0;
  const double h = std::sqrt(bw * bh / cells);
  const int nx = std::max(1, static_cast<int>(std::ceil(bw / h))), ny = std::max(1, static_cast<int>(std::ceil(bh / h)));
  std::vector<std::uint8_t> cover(static_cast<std::size_t>(nx) * ny, 0);
  for (const Face& t : tris) {
    Vec2d p[3] = {(uv[t[0]] - lo) / h, (uv[t[1]] - lo) / h, (uv[t[2]] - lo) / h};
    const double area = cross(p[1] - p[0], p[2] - p[0]);
    if (area == 0) continue;
    if (area < 0) std::swap(p[1], p[2]);
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].x, p[1].x, p[2].x}) - 0.5)));
    const int x1 = std::min(nx - 1, static_cast<int>(std::ceil(std::max({p[0].x, p[1].x, p[2].x}) - 0.5)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].y, p[1].y, p[2].y}) - 0.5)));
    const int y1 = std::min(ny - 1, static_cast<int>(std::ceil(std::max({p[0].y, p[1].y, p[2].y}) - 0.5)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Vec2d c{x + 0.5, y + 0.5};
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Vec2d a = p[k], b = p[(k + 1) % 3];
          const double e = cross(b - a, c - a);
          // Half-open: a centre on an edge belongs to the triangle on one side only.
          inside = e > 0 || (e == 0 && (b.y > a.y || (b.y == a.y && b.x < a.x)));
        }
        if (inside) {
          auto& n = cover[static_cast<std::size_t>(y) * nx + x];
          if (n < 2) ++n;
        }
      }
  }
  std::size_t once = 0, more = 0;
  for (std::uint8_t n : cover) {
    once += n >= 1;
    more += n >= 2;
  }
  return once ? static_cast<double>(more) / once : 0.0;
}

double linf_lower_bound(const ChartGeometry& g, const Topology& topo) {
  const int nv = g.num_vertices();
  std::vector<double> angle_sum(nv, 0.0);
  std::vector<int> corners(nv, 0);
  std::vector<char> skip(nv, 0);
  for (const Face& t : g.tris)
    for (int k = 0; k < 3; ++k) {
      const int v = t[k];
      const Vec3d a = g.positions[t[(k + 1) % 3]] - g.positions[v],
                  b = g.positions[t[(k + 2) % 3]] - g.positions[v];
      const double c = norm(cross(a, b));
      if (!(c > 0)) {
        for (int j = 0; j < 3; ++j) skip[t[j]] = 1;
        continue;
      }
      angle_sum[v] += std::atan2(c, dot(a, b));
      ++corners[v];
    }
  double need = 0;  // the largest mean angle change per corner, halved
  for (int v = 0; v < nv; ++v)
    if (corners[v] > 0 && !skip[v] && topo.is_referenced(v) && !topo.is_boundary_vertex(v))
      need = std::max(need, std::abs(2 * M_PI - angle_sum[v]) / (2 * corners[v]));
  if (need >= M_PI / 2) return std::numeric_limits<double>::infinity();
  const double s = std::sin(need);
  return std::sqrt((1 + s) / (1 - s));
}

bool linf_bound_unreachable(const ChartGeometry& g, const Topology* topo, double max_linf) {
  // Beyond Linf 2 the bound takes angle changes of over 73° per corner on average, which no
  // vertex of a usual mesh needs: the test would only cost time.
  if (!(max_linf < 2.0)) return false;
  const double bound =
      topo ? linf_lower_bound(g, *topo) : linf_lower_bound(g, Topology(g.tris, g.num_vertices()));
  // The margin over the acceptance slack keeps rounding in the angle sums on the safe side.
  return bound > max_linf * kStretchBoundSlack * (1 + 1e-6);
}

namespace {

// L2 stretch over all but the worst `trim` fraction of the area: tells a globally stretched
// start from one with a few crushed triangles, which optimization repairs quickly.
double trimmed_l2(const ChartGeometry& g, const std::vector<Vec2d>& uv, double trim) {
  std::vector<std::pair<double, double>> tri;  // (l2², 3D area)
  double area3 = 0, area2 = 0;
  tri.reserve(g.tris.size());
  for (const Face& t : g.tris) {
    const Vec3d q[3] = {g.positions[t[0]], g.positions[t[1]], g.positions[t[2]]};
    const Vec2d p[3] = {uv[t[0]], uv[t[1]], uv[t[2]]};
    const double a3 = triangle_area(q[0], q[1], q[2]);
    area3 += a3;
    area2 += std::abs(signed_area(p[0], p[1], p[2]));
    const TriangleStretch ts = triangle_stretch(q, p);
    tri.emplace_back(ts.flipped ? std::numeric_limits<double>::infinity() : ts.l2 * ts.l2, a3);
  }
  if (!(area3 > 0) || !(area2 > 0)) return std::numeric_limits<double>::infinity();
  std::sort(tri.begin(), tri.end());
  double kept = 0, sum = 0;
  for (const auto& [l2sq, a] : tri) {
    if (kept + a > (1 - trim) * area3) break;
    kept += a;
    sum += l2sq * a;
  }
  return kept > 0 ? std::sqrt(sum / kept * area2 / area3) : std::numeric_limits<double>::infinity();
}

// Grid cells of multiply_covered_fraction: about 1/500 of the layout's width each, and at
// most this many per triangle: the grid's cost does not shrink with the chart, and merge
// attempts of a few triangles each spent the same 262,144 cells (38 % of a run where the
// bounds split a sphere into its triangles).
constexpr double kOverlapCells = 262144;
constexpr double kOverlapCellsPerTriangle = 256;

// A start folded over more than this fraction of its triangles is not untangled.
constexpr double kMaxUntangleFraction = 0.25;
// Starts with L2 beyond this multiple of the bound are not optimized (observed: optimization
// lowers L2 by at most about 0.3 on charts that end up accepted).
constexpr double kHopelessL2 = 1.8;
// A failed IsoMap attempt within this multiple of the L2 bound still earns an LSCM attempt.
constexpr double kNearMissL2 = 1.1;

// Counter-clockwise orientation overall: mirror when most of the area is clockwise.
void orient(const ChartGeometry& g, std::vector<Vec2d>& uv) {
  double s = 0;
  for (const Face& t : g.tris) s += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]);
  if (s < 0)
    for (auto& p : uv) p.y = -p.y;
}

// How far a rejected attempt is from acceptance, to keep the best one.
double violation(const ChartParam& p, const ParamOptions& o) {
  if (p.uv.empty()) return std::numeric_limits<double>::infinity();
  double v = p.flipped * 10.0 + (p.overlaps ? 5.0 : 0.0);
  if (std::isfinite(p.l2)) v += std::max(0.0, p.l2 / o.max_l2 - 1);
  else v += 100;
  if (std::isfinite(p.linf)) v += std::max(0.0, p.linf / o.max_linf - 1);
  else v += 100;
  return v;
}

}  // namespace

std::vector<Vec2d> isomap_uv(const Embedding& e) {
  std::vector<Vec2d> uv;
  if (e.dimensions < 2) return uv;
  uv.resize(e.num_vertices);
  for (int v = 0; v < e.num_vertices; ++v) uv[v] = {e.coordinate(v, 0), e.coordinate(v, 1)};
  return uv;
}

ChartParam parameterize(const ChartGeometry& g, const std::vector<Vec2d>& iso_uv, const ParamOptions& o) {
  ChartParam best;
  if (g.num_faces() == 1) {
    // A lone triangle is its own isometric chart.
    const Face& t = g.tris[0];
    const Vec3d e1 = g.positions[t[1]] - g.positions[t[0]], e2 = g.positions[t[2]] - g.positions[t[0]];
    const double l1 = norm(e1);
    const double x2 = l1 > 0 ? dot(e2, e1 / l1) : 0;
    best.uv.assign(g.num_vertices(), Vec2d{});
    best.uv[t[1]] = {l1, 0};
    // The height from the cross product: sqrt(|e2|² − x2²) cancels to 0 on a sliver (height
    // 1e-10 of its length), which then had no UV area and stopped the packer.
    best.uv[t[2]] = {x2, l1 > 0 ? norm(cross(e1, e2)) / l1 : 0.0};
    best.method = "triangle";
    evaluate(g, best, o);
    return best;
  }
  OptimizeOptions opt;
  opt.passes = o.optimize_passes;
  opt.max_linf = o.max_linf;
  opt.seed = o.seed;
  // §6: only vertices whose 1-ring exceeds the user's limit are optimized.
  opt.vertex_l2_threshold = o.max_l2;
  opt.give_up_l2 = o.max_l2;
  opt.cancel = o.cancel;
  if (o.face_metric) {
    opt.face_metric = chart_metric(g, *o.face_metric);
    opt.boundary_clearance = kSignalBoundaryClearance;  // see reoptimize in signal_atlas.cpp
  }
  double seconds = 0;
  // Every start of this chart is untangled, optimized and (for LSCM) pinned on one topology.
  const Topology own = o.topology ? Topology() : Topology(g.tris, g.num_vertices());
  const Topology& topo = o.topology ? *o.topology : own;
  // A chart whose angle defects alone exceed the Linf bound fails whatever the layout: its
  // starts are only measured. With a tight bound (--max-linf near 1) most charts and merge
  // attempts are of this kind, and each optimization and LSCM solve was spent for nothing.
  const bool infeasible = linf_bound_unreachable(g, &topo, o.max_linf);
  auto attempt = [&](std::vector<Vec2d> uv, const char* method) {
    ChartParam p;
    p.method = method;
    orient(g, uv);
    int flips = 0;
    for (const Face& t : g.tris) flips += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) > 0 ? 0 : 1;
    p.initial_flip_fraction = static_cast<double>(flips) / g.num_faces();
    const auto t0 = std::chrono::steady_clock::now();
    // IsoMap folds a few triangles now and then (§4.2); a heavily folded start means the
    // chart is far from flat and will be split anyway.
    if (flips > 0 && p.initial_flip_fraction <= kMaxUntangleFraction) untangle(g.tris, uv, topo);
    p.uv = std::move(uv);
    p.initial_l2 = trimmed_l2(g, p.uv, 0.02);
    // Optimization lowers L2 by a few tenths at most: far worse starts are not worth it. Nor
    // are starts folded onto themselves on a large scale (merged charts whose halves overlap):
    // vertex moves inside 1-ring kernels do not undo that.
    const bool worth =
        !infeasible && p.initial_l2 <= kHopelessL2 * o.max_l2 &&
        (o.max_start_overlap >= 1 ||
         multiply_covered_fraction(g.tris, p.uv,
                                   std::min(kOverlapCells, kOverlapCellsPerTriangle * g.num_faces())) <=
             o.max_start_overlap);
    if (worth) optimize_stretch(g.positions, g.tris, p.uv, opt, topo);
    p.optimize_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    seconds += p.optimize_seconds;
    evaluate(g, p, o, &topo);
    return p;
  };
  bool try_lscm = o.lscm_fallback && !infeasible;
  if (!iso_uv.empty()) {
    best = attempt(iso_uv, "isomap");
    if (best.accepted) return best;
    // LSCM rescues charts IsoMap folds or overlaps, and near misses; a chart IsoMap folds
    // in large part, or that misses the bound by far, needs splitting.
    const bool near_miss = best.flipped == 0 && std::isfinite(best.l2) && best.l2 <= kNearMissL2 * o.max_l2;
    try_lscm = try_lscm && (o.lscm_on_any_failure || (best.initial_flip_fraction <= kMaxUntangleFraction &&
                                                      (best.flipped > 0 || best.overlaps || near_miss)));
  }
  std::vector<Vec2d> uv;
  if (o.cancel && o.cancel->load(std::memory_order_relaxed)) try_lscm = false;
  if (try_lscm && lscm(g, uv, &topo)) {
    ChartParam p = attempt(std::move(uv), "lscm");
    if (p.accepted || violation(p, o) < violation(best, o)) best = std::move(p);
  }
  best.optimize_seconds = seconds;
  return best;
}

}  // namespace isochart::detail
