#include "charts.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <limits>
#include <numeric>
#include <queue>
#include <string>
#include <tuple>
#include <utility>

#include "isochart/error.h"
#include "isochart/pack.h"
#include "isochart/stretch.h"
#include "isochart/union_find.h"

namespace mcgim::detail {

namespace {

using isochart::Error;
using isochart::InputError;

std::string describe(int c, const Chart& ch) {
  if (ch.faces.size() == 1)
    return "atlas chart " + std::to_string(c) + " (face " + std::to_string(ch.faces.front()) + ")";
  return "atlas chart " + std::to_string(c) + " (" + std::to_string(ch.faces.size()) + " faces, first face " +
         std::to_string(ch.faces.front()) + ")";
}

const Vec2d& corner_uv(const Mesh& m, int f, int k) { return m.uvs[m.face_uvs[f][k]]; }

int corner_of(const Face& f, int v) {
  for (int k = 0; k < 3; ++k)
    if (f[k] == v) return k;
  return -1;
}

void check_input(const Mesh& m) {
  if (m.num_faces() == 0) throw InputError("", "the atlas mesh has no faces");
  if (!m.has_uvs()) throw InputError("", "the atlas mesh has no texture coordinates");
  if (m.face_uvs.size() != m.faces.size())
    throw InputError("", "the atlas has " + std::to_string(m.face_uvs.size()) +
                             " texture faces for " + std::to_string(m.faces.size()) + " faces");
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int t = m.face_uvs[f][k];
      if (t < 0 || t >= static_cast<int>(m.uvs.size()))
        throw InputError("", "face " + std::to_string(f) + " refers to texture coordinate " +
                                 std::to_string(t) + ", out of range");
      if (!isochart::is_finite(m.uvs[t]))
        throw InputError("", "texture coordinate " + std::to_string(t) + " is not finite");
      const int v = m.faces[f][k];
      if (v < 0 || v >= m.num_vertices())
        throw InputError("", "face " + std::to_string(f) + " refers to vertex " +
                                 std::to_string(v) + ", out of range");
    }
  if (!m.face_groups.empty() && m.face_groups.size() != m.faces.size())
    throw InputError("", "the atlas has " + std::to_string(m.face_groups.size()) +
                             " face groups for " + std::to_string(m.faces.size()) + " faces");
}

// Charts: faces of one label joined through edges whose texture coordinates agree.
std::vector<Chart> split_charts(const Mesh& m, const isochart::Topology& topo) {
  std::vector<int> label = m.face_groups;
  if (label.empty()) {
    int n = 0;
    label = isochart::uv_charts(m, n);
  }
  const int nf = m.num_faces();
  isochart::UnionFind uf(nf);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int g = topo.opposite_face(f, k);
      if (g < f || label[g] != label[f]) continue;
      const int a = m.faces[f][k], b = m.faces[f][(k + 1) % 3];
      const int ka = corner_of(m.faces[g], a), kb = corner_of(m.faces[g], b);
      if (corner_uv(m, f, k) == corner_uv(m, g, ka) &&
          corner_uv(m, f, (k + 1) % 3) == corner_uv(m, g, kb))
        uf.unite(f, g);
    }
  std::vector<int> chart_of_root(nf, -1);
  std::vector<Chart> charts;
  for (int f = 0; f < nf; ++f) {
    const int r = uf.find(f);
    if (chart_of_root[r] < 0) {
      chart_of_root[r] = static_cast<int>(charts.size());
      charts.emplace_back();
    }
    charts[chart_of_root[r]].faces.push_back(f);
  }
  return charts;
}

// Splits chart vertices into one copy per fan: faces around a vertex are joined through the
// edges they share there, except edges in `cuts`. Without cuts this separates a chart that
// touches itself at a vertex (two fans sharing the vertex and its texture coordinate but no
// edge); with cuts it opens the chart along them.
void split_fans(Chart& ch, const std::vector<std::pair<int, int>>& cuts) {
  const int nv = static_cast<int>(ch.mesh_vertex.size());
  const int nf = static_cast<int>(ch.local_faces.size());
  std::vector<std::vector<int>> vf(nv);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) vf[ch.local_faces[f][k]].push_back(f);
  auto is_cut = [&](int a, int b) {
    return std::binary_search(cuts.begin(), cuts.end(), std::make_pair(std::min(a, b), std::max(a, b)));
  };
  for (int v = 0; v < nv; ++v) {
    const auto& fs = vf[v];
    if (fs.size() < 2) continue;
    const int n = static_cast<int>(fs.size());
    isochart::UnionFind uf(n);
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        for (int a : ch.local_faces[fs[i]])
          for (int b : ch.local_faces[fs[j]])
            if (a == b && a != v && !is_cut(v, a)) uf.unite(i, j);
    std::vector<int> copy(n, -1);
    const int first = uf.find(0);
    for (int i = 0; i < n; ++i) {
      const int root = uf.find(i);
      if (root == first) continue;
      if (copy[root] < 0) {
        copy[root] = static_cast<int>(ch.mesh_vertex.size());
        ch.mesh_vertex.push_back(ch.mesh_vertex[v]);
        ch.uv.push_back(ch.uv[v]);
      }
      for (int& c : ch.local_faces[fs[i]])
        if (c == v) c = copy[root];
    }
  }
}

// Boundary loops of a chart (oriented like its faces) and its Euler characteristic.
std::vector<std::vector<int>> chart_loops(int c, const Chart& ch, long long& euler) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(ch.local_faces.size() * 3);
  for (const Face& f : ch.local_faces)
    for (int k = 0; k < 3; ++k) edges.emplace_back(f[k], f[(k + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 1; i < edges.size(); ++i)
    if (edges[i] == edges[i - 1])
      throw InputError("", describe(c, ch) + " is not a manifold chart: its texture edge (" +
                               std::to_string(ch.mesh_vertex[edges[i].first]) + "," +
                               std::to_string(ch.mesh_vertex[edges[i].second]) +
                               ") is used twice in the same direction");
  const int nv = static_cast<int>(ch.mesh_vertex.size());
  std::vector<int> next(nv, -1);
  long long undirected = 0;
  for (const auto& e : edges) {
    if (std::binary_search(edges.begin(), edges.end(), std::make_pair(e.second, e.first))) {
      if (e.first < e.second) ++undirected;
      continue;
    }
    ++undirected;
    if (next[e.first] >= 0) throw Error(describe(c, ch) + ": pinched after splitting fans");
    next[e.first] = e.second;
  }
  std::vector<std::vector<int>> loops;
  std::vector<char> seen(nv, 0);
  for (int v = 0; v < nv; ++v) {
    if (next[v] < 0 || seen[v]) continue;
    std::vector<int> loop;
    for (int u = v; !seen[u]; u = next[u]) {
      if (next[u] < 0) throw Error(describe(c, ch) + ": open boundary chain");
      seen[u] = 1;
      loop.push_back(u);
    }
    loops.push_back(std::move(loop));
  }
  euler = nv - undirected + static_cast<long long>(ch.local_faces.size());
  return loops;
}

// Slits joining every boundary loop to the first, each a shortest path (in texture length) of
// interior edges through interior vertices: they turn a chart with holes into a disk.
std::vector<std::vector<int>> choose_slits(const Chart& ch, const std::vector<std::vector<int>>& loops) {
  const int nv = static_cast<int>(ch.mesh_vertex.size());
  std::map<std::pair<int, int>, int> edge_faces;
  for (const Face& f : ch.local_faces)
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      ++edge_faces[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::vector<int>> adj(nv);
  for (const auto& [e, n] : edge_faces)
    if (n == 2) {
      adj[e.first].push_back(e.second);
      adj[e.second].push_back(e.first);
    }
  std::vector<int> loop_of(nv, -1);
  for (std::size_t l = 0; l < loops.size(); ++l)
    for (int v : loops[l]) loop_of[v] = static_cast<int>(l);
  std::vector<char> joined(loops.size(), 0);
  joined[0] = 1;
  std::vector<std::vector<int>> slits;
  for (std::size_t round = 1; round < loops.size(); ++round) {
    std::vector<double> dist(nv, std::numeric_limits<double>::infinity());
    std::vector<int> from(nv, -1);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    for (int v = 0; v < nv; ++v)
      if (loop_of[v] >= 0 && joined[loop_of[v]]) {
        dist[v] = 0;
        queue.push({0.0, v});
      }
    int target = -1;
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > dist[v]) continue;
      if (loop_of[v] >= 0 && !joined[loop_of[v]]) {
        target = v;
        break;
      }
      // Paths pass through interior vertices only (sources and the target excepted).
      if (loop_of[v] >= 0 && dist[v] > 0) continue;
      for (int u : adj[v]) {
        if (loop_of[u] >= 0 && joined[loop_of[u]]) continue;
        const double nd = d + norm(ch.uv[u] - ch.uv[v]);
        if (nd < dist[u]) {
          dist[u] = nd;
          from[u] = v;
          queue.push({nd, u});
        }
      }
    }
    if (target < 0) return {};
    std::vector<int> path;
    for (int v = target; v >= 0; v = from[v]) path.push_back(v);
    joined[loop_of[target]] = 1;
    slits.push_back(std::move(path));
  }
  return slits;
}

// Chart-local vertices, the boundary loop and the disk check (holes are slit open).
void build_chart(const Mesh& m, int c, Chart& ch) {
  std::map<std::tuple<int, double, double>, int> key_to_vertex;
  double unsigned_uv = 0;
  for (int f : ch.faces) {
    Face lf{};
    for (int k = 0; k < 3; ++k) {
      const Vec2d& uv = corner_uv(m, f, k);
      const auto key = std::make_tuple(m.faces[f][k], uv.x, uv.y);
      auto it = key_to_vertex.find(key);
      if (it == key_to_vertex.end()) {
        it = key_to_vertex.emplace(key, static_cast<int>(ch.mesh_vertex.size())).first;
        ch.mesh_vertex.push_back(m.faces[f][k]);
        ch.uv.push_back(uv);
      }
      lf[k] = it->second;
    }
    ch.local_faces.push_back(lf);
    const double a = isochart::signed_area(ch.uv[lf[0]], ch.uv[lf[1]], ch.uv[lf[2]]);
    ch.area_uv += a;
    unsigned_uv += std::abs(a);
    ch.area_3d += isochart::triangle_area(m.positions[m.faces[f][0]], m.positions[m.faces[f][1]],
                                          m.positions[m.faces[f][2]]);
  }
  // A chart folded onto itself (some triangles mirrored over the others) can sum to nothing.
  if (!(std::abs(ch.area_uv) > 1e-9 * unsigned_uv))
    throw InputError("",
                     describe(c, ch) + (unsigned_uv > 0 ? " folds over itself: its flipped triangles cancel "
                                                          "the texture area of the others"
                                                        : " has zero texture area"));
  split_fans(ch, {});
  long long euler = 0;
  std::vector<std::vector<int>> loops = chart_loops(c, ch, euler);
  if (loops.empty())
    throw InputError("", describe(c, ch) + " is a closed surface; an atlas chart needs a boundary");
  if (loops.size() > 1 && euler == 2 - static_cast<long long>(loops.size())) {
    ch.slits = choose_slits(ch, loops);
    if (!ch.slits.empty()) {
      // The outer loop encloses the largest texture area; the others are holes.
      std::size_t outer = 0;
      std::vector<double> area(loops.size(), 0.0);
      for (std::size_t l = 0; l < loops.size(); ++l) {
        for (std::size_t i = 0; i < loops[l].size(); ++i)
          area[l] += cross(ch.uv[loops[l][i]], ch.uv[loops[l][(i + 1) % loops[l].size()]]);
        if (std::abs(area[l]) > std::abs(area[outer])) outer = l;
      }
      for (std::size_t l = 0; l < loops.size(); ++l)
        if (l != outer) ch.holes.push_back(loops[l]);
      std::vector<std::pair<int, int>> cuts;
      for (const auto& path : ch.slits)
        for (std::size_t i = 0; i + 1 < path.size(); ++i)
          cuts.emplace_back(std::min(path[i], path[i + 1]), std::max(path[i], path[i + 1]));
      std::sort(cuts.begin(), cuts.end());
      split_fans(ch, cuts);
      loops = chart_loops(c, ch, euler);
    }
  }
  if (loops.size() != 1 || euler != 1)
    throw InputError("", describe(c, ch) + " is not a topological disk: " + std::to_string(loops.size()) +
                             " boundary loop(s), Euler characteristic " + std::to_string(euler));
  ch.loop = std::move(loops[0]);
}

double loop_arclen(const Mesh& m, const std::vector<int>& vertices, std::vector<double>& out) {
  out.assign(vertices.size(), 0.0);
  for (std::size_t i = 1; i < vertices.size(); ++i)
    out[i] = out[i - 1] + norm(m.positions[vertices[i]] - m.positions[vertices[i - 1]]);
  return out.empty() ? 0.0 : out.back();
}

// Index in `positions` (ascending arc lengths of candidate vertices) closest to `target`.
int closest_index(const std::vector<double>& arclen, int lo, int hi, double target) {
  int best = lo;
  for (int i = lo; i <= hi; ++i)
    if (std::abs(arclen[i] - target) < std::abs(arclen[best] - target)) best = i;
  return best;
}

}  // namespace

AtlasCharts prepare_atlas(const Mesh& m, double texture_aspect) {
  check_input(m);
  AtlasCharts a;
  a.mesh = &m;
  a.topology = isochart::Topology(m);
  const isochart::Topology& topo = a.topology;
  if (!topo.nonmanifold_edges().empty()) {
    const auto& e = topo.edge(topo.nonmanifold_edges().front());
    throw InputError("", "edge (" + std::to_string(e.v0) + "," + std::to_string(e.v1) + ") has " +
                             std::to_string(topo.edge_faces(topo.nonmanifold_edges().front()).size()) +
                             " faces; the atlas mesh must be manifold");
  }
  if (!topo.nonmanifold_vertices().empty())
    throw InputError("", "vertex " + std::to_string(topo.nonmanifold_vertices().front()) +
                             " joins several fans; the atlas mesh must be manifold");
  a.vertex_normals = isochart::vertex_normals(m);
  a.input_euler = topo.euler_characteristic();
  a.input_boundary_loops = static_cast<int>(topo.boundary_loops().size());
  a.surface_area = isochart::surface_area(m);
  a.uv_aspect = texture_aspect > 0 ? texture_aspect : isochart::detect_texture_aspect(m);

  a.charts = split_charts(m, topo);
  for (std::size_t c = 0; c < a.charts.size(); ++c) build_chart(m, static_cast<int>(c), a.charts[c]);

  // Every loop edge lies on a mesh edge that is either on the mesh boundary (one loop edge) or
  // a cut between two chart sides (two loop edges).
  std::vector<std::array<std::pair<int, int>, 2>> occurrence(topo.num_edges());
  std::vector<int> occurrences(topo.num_edges(), 0);
  for (std::size_t c = 0; c < a.charts.size(); ++c) {
    const Chart& ch = a.charts[c];
    const int L = static_cast<int>(ch.loop.size());
    for (int e = 0; e < L; ++e) {
      const int u = ch.mesh_vertex[ch.loop[e]], v = ch.mesh_vertex[ch.loop[(e + 1) % L]];
      const int id = topo.find_edge(u, v);
      if (id < 0 || occurrences[id] >= 2)
        throw Error("inconsistent chart boundary at edge (" + std::to_string(u) + "," +
                    std::to_string(v) + ")");
      occurrence[id][occurrences[id]++] = {static_cast<int>(c), e};
    }
  }
  std::vector<int> cut_degree(m.num_vertices(), 0), boundary_degree(m.num_vertices(), 0);
  for (int e = 0; e < topo.num_edges(); ++e) {
    if (occurrences[e] == 0) continue;
    const bool boundary = topo.is_boundary_edge(e);
    if (boundary != (occurrences[e] == 1))
      throw Error("inconsistent chart boundary at edge (" + std::to_string(topo.edge(e).v0) + "," +
                  std::to_string(topo.edge(e).v1) + ")");
    auto& deg = boundary ? boundary_degree : cut_degree;
    ++deg[topo.edge(e).v0];
    ++deg[topo.edge(e).v1];
  }
  // Cut-nodes: where three or more chart sides meet, where a cut ends, and where a cut meets
  // the mesh boundary.
  a.is_node.assign(m.num_vertices(), 0);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const int c = cut_degree[v], b = boundary_degree[v];
    if (c >= 3 || c == 1 || (c >= 1 && b >= 1)) a.is_node[v] = 1;
  }
  auto edge_is_cut = [&](int u, int v) { return occurrences[topo.find_edge(u, v)] == 2; };

  // A closed cut without nodes (e.g. the equator between two hemispheres) gets three artificial
  // nodes, so that no cut path is a loop: contracting a loop would change the topology.
  for (const Chart& ch : a.charts) {
    const int L = static_cast<int>(ch.loop.size());
    bool any_node = false, all_cut = true;
    for (int i = 0; i < L; ++i) {
      const int u = ch.mesh_vertex[ch.loop[i]], v = ch.mesh_vertex[ch.loop[(i + 1) % L]];
      any_node = any_node || a.is_node[u];
      all_cut = all_cut && edge_is_cut(u, v);
    }
    if (any_node || !all_cut) continue;
    std::vector<int> verts;
    for (int i = 0; i <= L; ++i) verts.push_back(ch.mesh_vertex[ch.loop[i % L]]);
    std::vector<double> arclen;
    const double len = loop_arclen(m, verts, arclen);
    int prev = 0;
    a.is_node[verts[0]] = 1;
    for (int k = 1; k <= 2; ++k) {
      const int lo = prev + 1, hi = L - (3 - k);
      const int i = closest_index(arclen, lo, std::max(lo, hi), len * k / 3.0);
      a.is_node[verts[i]] = 1;
      prev = i;
    }
    a.num_artificial_nodes += 3;
  }

  // Sides: the loops split at nodes. A two-sided path from a node back to itself gets two
  // artificial nodes for the same reason as above; repeat until no path is such a loop.
  for (bool changed = true; changed;) {
    changed = false;
    a.sides.clear();
    for (std::size_t c = 0; c < a.charts.size(); ++c) {
      Chart& ch = a.charts[c];
      const int L = static_cast<int>(ch.loop.size());
      std::vector<int> node_pos;
      for (int i = 0; i < L; ++i)
        if (a.is_node[ch.mesh_vertex[ch.loop[i]]]) node_pos.push_back(i);
      ch.sides.clear();
      ch.loop_side.assign(L, -1);
      if (node_pos.empty()) {
        Side s;
        s.chart = static_cast<int>(c);
        s.first_edge = 0;
        s.num_edges = L;
        s.has_nodes = false;
        ch.sides.push_back(static_cast<int>(a.sides.size()));
        a.sides.push_back(s);
      } else {
        const int n = static_cast<int>(node_pos.size());
        for (int k = 0; k < n; ++k) {
          Side s;
          s.chart = static_cast<int>(c);
          s.first_edge = node_pos[k];
          const int end = k + 1 < n ? node_pos[k + 1] : node_pos[0] + L;
          s.num_edges = end - node_pos[k];
          ch.sides.push_back(static_cast<int>(a.sides.size()));
          a.sides.push_back(s);
        }
      }
      for (int sid : ch.sides) {
        const Side& s = a.sides[sid];
        for (int j = 0; j < s.num_edges; ++j) ch.loop_side[(s.first_edge + j) % L] = sid;
      }
      if (node_pos.empty()) continue;
      for (int sid : ch.sides) {
        const Side& s = a.sides[sid];
        const int u = ch.mesh_vertex[ch.loop[s.first_edge]];
        const int w = ch.mesh_vertex[ch.loop[(s.first_edge + s.num_edges) % L]];
        const int second = ch.mesh_vertex[ch.loop[(s.first_edge + 1) % L]];
        if (u != w || !edge_is_cut(u, second) || s.num_edges < 2) continue;
        std::vector<int> verts;
        for (int j = 0; j <= s.num_edges; ++j) verts.push_back(ch.mesh_vertex[ch.loop[(s.first_edge + j) % L]]);
        std::vector<double> arclen;
        const double len = loop_arclen(m, verts, arclen);
        if (s.num_edges == 2) {
          a.is_node[verts[1]] = 1;
          a.num_artificial_nodes += 1;
        } else {
          const int i1 = closest_index(arclen, 1, s.num_edges - 2, len / 3.0);
          const int i2 = closest_index(arclen, i1 + 1, s.num_edges - 1, 2.0 * len / 3.0);
          a.is_node[verts[i1]] = a.is_node[verts[i2]] = 1;
          a.num_artificial_nodes += 2;
        }
        changed = true;
      }
    }
  }
  a.num_nodes = static_cast<int>(std::count(a.is_node.begin(), a.is_node.end(), 1));

  // Pair the two sides of every cut path.
  for (std::size_t sid = 0; sid < a.sides.size(); ++sid) {
    Side& s = a.sides[sid];
    if (s.path >= 0) continue;
    const Chart& ch = a.charts[s.chart];
    const int L = static_cast<int>(ch.loop.size());
    CutPath p;
    for (int j = 0; j <= s.num_edges; ++j) p.vertices.push_back(ch.mesh_vertex[ch.loop[(s.first_edge + j) % L]]);
    loop_arclen(m, p.vertices, p.arclen);
    p.side_a = static_cast<int>(sid);
    s.path = static_cast<int>(a.paths.size());
    const int u = p.vertices[0], v = p.vertices[1];
    const int id = topo.find_edge(u, v);
    if (occurrences[id] == 2) {
      const auto& occ = occurrence[id];
      const auto other = (occ[0] == std::make_pair(s.chart, s.first_edge)) ? occ[1] : occ[0];
      const int oid = a.charts[other.first].loop_side[other.second];
      Side& o = a.sides[oid];
      const int Lo = static_cast<int>(a.charts[other.first].loop.size());
      if (o.path >= 0 || o.num_edges != s.num_edges ||
          (o.first_edge + o.num_edges - 1) % Lo != other.second)
        throw Error("inconsistent cut path at edge (" + std::to_string(u) + "," + std::to_string(v) + ")");
      o.path = s.path;
      o.reversed = true;
      p.side_b = oid;
    }
    a.paths.push_back(std::move(p));
  }
  return a;
}

Placement place_charts(const AtlasCharts& a, const LevelOptions& o, const std::vector<double>& area_scale,
                       const isochart::Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  Placement pl;
  pl.width = o.width;
  pl.height = o.height;
  const int nc = static_cast<int>(a.charts.size());
  pl.texel.resize(nc);
  pl.mirrored.assign(nc, 0);
  isochart::report(progress, isochart::Stage::Packing, 0.0);
  if (o.repack) {
    // The same packer for every atlas, ours or external: all charts at one texel density,
    // `gutter` texels apart. Mirrored charts are unmirrored first (the packer only rotates).
    std::vector<isochart::PackChart> pack(nc);
    // The packer sizes charts by area_3d; keeping the atlas's sizes means handing it each
    // chart's texture area in surface units (the total stays the surface area).
    double total_3d = 0, total_uv = 0;
    for (const Chart& ch : a.charts) {
      total_3d += ch.area_3d;
      total_uv += std::abs(ch.area_uv);
    }
    const bool keep = o.keep_chart_sizes && total_uv > 0 && total_3d > 0;
    for (int c = 0; c < nc; ++c) {
      const Chart& ch = a.charts[c];
      pack[c].uv = ch.uv;
      const double sx = ch.area_uv < 0 ? -a.uv_aspect : a.uv_aspect;
      if (sx != 1.0)
        for (Vec2d& uv : pack[c].uv) uv.x *= sx;
      pack[c].faces = ch.local_faces;
      const double size =
          keep && ch.area_uv != 0 ? std::abs(ch.area_uv) * (total_3d / total_uv) : ch.area_3d;
      pack[c].area_3d = size * (area_scale.empty() ? 1.0 : area_scale[c]);
    }
    isochart::PackOptions po;
    po.width = o.width;
    po.height = o.height;
    po.gutter = o.gutter;
    isochart::pack_charts(pack, po, progress);
    for (int c = 0; c < nc; ++c) {
      pl.texel[c].resize(pack[c].uv.size());
      for (std::size_t i = 0; i < pack[c].uv.size(); ++i)
        pl.texel[c][i] = {pack[c].uv[i].x * o.width, pack[c].uv[i].y * o.height};
    }
  } else {
    const double tol = 1e-9;
    for (int c = 0; c < nc; ++c) {
      const Chart& ch = a.charts[c];
      pl.mirrored[c] = ch.area_uv < 0;
      pl.texel[c].resize(ch.uv.size());
      for (std::size_t i = 0; i < ch.uv.size(); ++i) {
        const Vec2d& uv = ch.uv[i];
        if (uv.x < -tol || uv.x > 1 + tol || uv.y < -tol || uv.y > 1 + tol)
          throw InputError("", "atlas chart " + std::to_string(c) + " has texture coordinates (" +
                                   std::to_string(uv.x) + ", " + std::to_string(uv.y) +
                                   ") outside [0,1]²; re-pack the atlas");
        pl.texel[c][i] = {uv.x * o.width, uv.y * o.height};
      }
    }
  }
  isochart::report(progress, isochart::Stage::Packing, 1.0);
  pl.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return pl;
}

PathPoint path_point(const AtlasCharts& a, const CutPath& p, double t) {
  const Mesh& m = *a.mesh;
  const int n = static_cast<int>(p.vertices.size());
  int j = static_cast<int>(std::upper_bound(p.arclen.begin(), p.arclen.end(), t) - p.arclen.begin()) - 1;
  j = std::clamp(j, 0, n - 2);
  const double len = p.arclen[j + 1] - p.arclen[j];
  const double f = len > 0 ? std::clamp((t - p.arclen[j]) / len, 0.0, 1.0) : 0.0;
  const int u = p.vertices[j], v = p.vertices[j + 1];
  PathPoint q;
  q.position = m.positions[u] * (1 - f) + m.positions[v] * f;
  q.normal = normalized(a.vertex_normals[u] * (1 - f) + a.vertex_normals[v] * f);
  const int e = a.topology.find_edge(u, v);
  q.face = a.topology.edge_faces(e)[0];
  const Face& fv = m.faces[q.face];
  q.barycentric[corner_of(fv, u)] = 1 - f;
  q.barycentric[corner_of(fv, v)] = f;
  return q;
}

Vec3d face_point(const Mesh& m, int f, const Vec3d& b) {
  const Face& fv = m.faces[f];
  return m.positions[fv[0]] * b.x + m.positions[fv[1]] * b.y + m.positions[fv[2]] * b.z;
}

}  // namespace mcgim::detail
