#include <algorithm>
#include <array>
#include <cstdlib>
#include <map>
#include <numeric>
#include <string>

#include "isochart/error.h"
#include "isochart/union_find.h"
#include "mcgim/geometry_image.h"

namespace mcgim {

using isochart::Face;
using isochart::Vec2d;
using isochart::Vec3d;

namespace {

// A triangle counts as zero-area when its height is below 1e-9 of its longest edge (collinear
// corners up to rounding: zippered seams produce exactly such triangles).
bool is_degenerate(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double l = std::max({squared_norm(b - a), squared_norm(c - b), squared_norm(a - c)});
  const double cr = norm(cross(b - a, c - a));
  return cr * cr <= 1e-18 * l * l;
}

// Zippering can snap neighbouring samples of different groups onto exactly the same point
// (several samples pulled onto one chart corner at a coarse level); the faces between them
// have zero area, and strict readers, ours included, refuse such a file. Joining the two
// groups removes those faces without moving any point. A join is made only when it keeps the
// surface a manifold of the same topology (the link condition: the two vertices' common
// neighbours are exactly the far corners of the faces on their edge, and two boundary
// vertices are joined only along a boundary edge). Returns the faces dropped; `rep` (the
// identity on entry) maps every group to the group standing for it.
int join_coincident_groups(const GeometryImage& im, const std::vector<int>& group_sample,
                           std::vector<std::array<int, 3>>& tris, std::vector<int>& tri_chart,
                           std::vector<int>& rep) {
  const int ng = im.num_groups, nt = static_cast<int>(tris.size());
  auto pos = [&](int g) -> const Vec3d& { return im.positions[group_sample[g]]; };
  auto same = [&](int a, int b) {
    const Vec3d &p = pos(a), &q = pos(b);
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
  };
  std::vector<std::pair<int, int>> candidates;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) {
      const int a = im.group[t[k]], b = im.group[t[(k + 1) % 3]];
      if (same(a, b)) candidates.push_back({std::min(a, b), std::max(a, b)});
    }
  if (candidates.empty()) return 0;
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  // Faces around each group, and the groups each representative stands for.
  std::vector<int> offset(ng + 1, 0);
  for (const auto& t : tris)
    for (int s : t) ++offset[im.group[s] + 1];
  for (int g = 0; g < ng; ++g) offset[g + 1] += offset[g];
  std::vector<int> incident(offset.back()), fill(offset.begin(), offset.end() - 1);
  for (int i = 0; i < nt; ++i)
    for (int s : tris[i]) incident[fill[im.group[s]]++] = i;
  // Groups joined into a representative (empty: just itself).
  std::map<int, std::vector<int>> members;
  std::vector<char> dead(nt, 0);
  auto corner = [&](int i, int k) { return rep[im.group[tris[i][k]]]; };
  // Calls fn(face) for the live faces around representative v.
  auto for_faces = [&](int v, auto&& fn) {
    auto one = [&](int g) {
      for (int x = offset[g]; x < offset[g + 1]; ++x)
        if (!dead[incident[x]]) fn(incident[x]);
    };
    const auto m = members.find(v);
    if (m == members.end())
      one(v);
    else
      for (int g : m->second) one(g);
  };
  auto has = [&](int i, int v) { return corner(i, 0) == v || corner(i, 1) == v || corner(i, 2) == v; };
  // Neighbours of v with the number of live faces on each edge.
  auto neighbours = [&](int v, std::vector<std::pair<int, int>>& out) {
    out.clear();
    for_faces(v, [&](int i) {
      for (int k = 0; k < 3; ++k)
        if (corner(i, k) != v) out.push_back({corner(i, k), 1});
    });
    std::sort(out.begin(), out.end());
    std::size_t n = 0;
    for (std::size_t x = 0; x < out.size(); ++x)
      if (n > 0 && out[n - 1].first == out[x].first)
        ++out[n - 1].second;
      else
        out[n++] = out[x];
    out.resize(n);
  };
  auto on_boundary = [](const std::vector<std::pair<int, int>>& n) {
    return std::any_of(n.begin(), n.end(), [](const std::pair<int, int>& e) { return e.second == 1; });
  };
  std::vector<std::pair<int, int>> na, nb;
  std::vector<int> far, common;
  int dropped = 0;
  for (const auto& c : candidates) {
    const int a = rep[c.first], b = rep[c.second];
    if (a == b) continue;
    neighbours(a, na);
    neighbours(b, nb);
    const auto ab = std::lower_bound(na.begin(), na.end(), std::make_pair(b, 0));
    if (ab == na.end() || ab->first != b || ab->second > 2) continue;
    if (on_boundary(na) && on_boundary(nb) && ab->second != 1) continue;
    far.clear();
    for_faces(a, [&](int i) {
      if (!has(i, b)) return;
      for (int k = 0; k < 3; ++k)
        if (corner(i, k) != a && corner(i, k) != b) far.push_back(corner(i, k));
    });
    std::sort(far.begin(), far.end());
    common.clear();
    for (std::size_t x = 0, y = 0; x < na.size() && y < nb.size();) {
      if (na[x].first < nb[y].first)
        ++x;
      else if (nb[y].first < na[x].first)
        ++y;
      else {
        common.push_back(na[x].first);
        ++x;
        ++y;
      }
    }
    if (common != far) continue;
    // Faces on both far corners and a, and on both and b, would become one face twice (the
    // edge half of the link condition: a tetrahedron closed over edge ab).
    if (far.size() == 2) {
      bool with_a = false, with_b = false;
      for_faces(far[0], [&](int i) {
        if (!has(i, far[1])) return;
        with_a |= has(i, a);
        with_b |= has(i, b);
      });
      if (with_a && with_b) continue;
    }
    for_faces(a, [&](int i) {
      if (has(i, b)) {
        dead[i] = 1;
        ++dropped;
      }
    });
    auto& ma = members.try_emplace(a, 1, a).first->second;
    auto mb = members.find(b);
    if (mb == members.end()) mb = members.try_emplace(b, 1, b).first;
    for (int g : mb->second) rep[g] = a;
    ma.insert(ma.end(), mb->second.begin(), mb->second.end());
    members.erase(mb);
  }
  std::size_t out = 0;
  for (int i = 0; i < nt; ++i) {
    if (dead[i]) continue;
    tris[out] = tris[i];
    tri_chart[out] = tri_chart[i];
    ++out;
  }
  tris.resize(out);
  tri_chart.resize(out);
  return dropped;
}

}  // namespace

bool GeometryImage::splits_13(int i) const {
  const int c[4] = {i, i + 1, i + 1 + width, i + width};
  // A diagonal whose ends were welded has length 0, so the shorter one takes it and both
  // triangles collapse instead of folding onto each other.
  if (!block_diagonal.empty() && group[c[0]] != group[c[2]] && group[c[1]] != group[c[3]])
    return block_diagonal[i] != 0;
  return squared_norm(positions[c[1]] - positions[c[3]]) < squared_norm(positions[c[0]] - positions[c[2]]);
}

int topology_distance(const TopologyCheck& t, int euler_characteristic, int boundary_loops) {
  return t.nonmanifold_edges + t.nonmanifold_vertices + std::abs(t.euler_characteristic - euler_characteristic) +
         std::abs(t.boundary_loops - boundary_loops);
}

int GeometryImage::defined_samples() const {
  return static_cast<int>(std::count_if(chart.begin(), chart.end(), [](int c) { return c >= 0; }));
}

Remesh reconstruct(const GeometryImage& im, bool join_coincident) {
  const int W = im.width, H = im.height;
  const std::size_t N = static_cast<std::size_t>(W) * H;
  if (W < 1 || H < 1 || im.positions.size() != N || im.normals.size() != N || im.chart.size() != N ||
      im.group.size() != N)
    throw isochart::InputError("", "geometry image arrays do not match its size " +
                                       std::to_string(W) + "x" + std::to_string(H));
  if (!im.block_diagonal.empty() && im.block_diagonal.size() != N)
    throw isochart::InputError("", "geometry image block diagonals (" + std::to_string(im.block_diagonal.size()) +
                                       ") do not match its size " + std::to_string(W) + "x" + std::to_string(H));
  std::vector<int> group_sample(im.num_groups, -1);
  for (std::size_t i = 0; i < N; ++i) {
    if (!im.defined(static_cast<int>(i))) continue;
    const int g = im.group[i];
    if (g < 0 || g >= im.num_groups)
      throw isochart::InputError("", "sample " + std::to_string(i % W) + "," + std::to_string(i / W) +
                                         " has group " + std::to_string(g) + ", out of range");
    if (group_sample[g] < 0) group_sample[g] = static_cast<int>(i);
  }
  Remesh r;
  std::vector<std::array<int, 3>> tris;  // sample triples
  std::vector<int> tri_chart;
  for (int y = 0; y + 1 < H; ++y)
    for (int x = 0; x + 1 < W; ++x) {
      const int c[4] = {im.index(x, y), im.index(x + 1, y), im.index(x + 1, y + 1), im.index(x, y + 1)};
      int n = 0, missing = -1, chart = -1;
      for (int k = 0; k < 4; ++k) {
        if (!im.defined(c[k])) {
          missing = k;
          continue;
        }
        ++n;
        if (chart >= 0 && im.chart[c[k]] != chart)
          throw isochart::InputError("", "block at sample " + std::to_string(x) + "," + std::to_string(y) +
                                             " mixes charts " + std::to_string(chart) + " and " +
                                             std::to_string(im.chart[c[k]]));
        chart = im.chart[c[k]];
      }
      if (n < 3) continue;
      const bool mirrored = chart < static_cast<int>(im.chart_mirrored.size()) && im.chart_mirrored[chart];
      std::array<int, 3> t[2];
      int nt = 0;
      if (n == 4) {
        // Sander et al.'s shorter diagonal after zippering, unless the fit chose one.
        const bool use02 = !im.splits_13(c[0]);
        if (use02) {
          t[0] = {c[0], c[1], c[2]};
          t[1] = {c[0], c[2], c[3]};
        } else {
          t[0] = {c[0], c[1], c[3]};
          t[1] = {c[1], c[2], c[3]};
        }
        nt = 2;
      } else {
        for (int k = 1; k <= 3; ++k) t[0][k - 1] = c[(missing + k) % 4];
        nt = 1;
      }
      for (int i = 0; i < nt; ++i) {
        if (mirrored) std::swap(t[i][1], t[i][2]);
        const int g0 = im.group[t[i][0]], g1 = im.group[t[i][1]], g2 = im.group[t[i][2]];
        if (g0 == g1 || g1 == g2 || g0 == g2) {
          ++r.collapsed_faces;
          continue;
        }
        tris.push_back(t[i]);
        tri_chart.push_back(chart);
      }
    }
  // Where both sides of a seam cut the same corner, the two charts produce the same triangle
  // with opposite orientations: a closed pocket of two faces hanging on an edge. Removing both
  // faces removes the pocket (and leaves the surface manifold).
  {
    // Triangles bucketed by their smallest group (counting sort), then compared in buckets.
    const int nt = static_cast<int>(tris.size());
    std::vector<std::array<int, 3>> rot(nt);
    std::vector<int> offset(im.num_groups + 1, 0);
    for (int i = 0; i < nt; ++i) {
      std::array<int, 3> g = {im.group[tris[i][0]], im.group[tris[i][1]], im.group[tris[i][2]]};
      std::rotate(g.begin(), std::min_element(g.begin(), g.end()), g.end());
      rot[i] = g;
      ++offset[g[0] + 1];
    }
    for (int g = 0; g < im.num_groups; ++g) offset[g + 1] += offset[g];
    std::vector<int> bucket(nt), fill(offset.begin(), offset.end() - 1);
    for (int i = 0; i < nt; ++i) bucket[fill[rot[i][0]]++] = i;
    std::vector<char> drop(nt, 0);
    for (int g = 0; g < im.num_groups; ++g) {
      const int lo = offset[g], hi = offset[g + 1];
      for (int x = lo; x < hi; ++x)
        for (int y = x + 1; y < hi; ++y) {
          const auto& p = rot[bucket[x]];
          const auto& q = rot[bucket[y]];
          if (drop[bucket[x]] || drop[bucket[y]] || p[1] != q[2] || p[2] != q[1]) continue;
          drop[bucket[x]] = drop[bucket[y]] = 1;
        }
    }
    std::size_t out = 0;
    for (int i = 0; i < nt; ++i) {
      if (drop[i]) {
        ++r.pocket_faces;
        continue;
      }
      tris[out] = tris[i];
      tri_chart[out] = tri_chart[i];
      ++out;
    }
    tris.resize(out);
    tri_chart.resize(out);
  }
  // A contracted seam can also close a few triangles into a small closed surface touching the
  // rest only at a vertex. Of the edge-connected pieces that touch at vertices, keep the one
  // with the most faces and drop the other closed ones.
  {
    const int nt = static_cast<int>(tris.size());
    // Undirected edges bucketed by their smaller group: (larger group, triangle).
    std::vector<int> offset(im.num_groups + 1, 0);
    for (int i = 0; i < nt; ++i)
      for (int k = 0; k < 3; ++k)
        ++offset[std::min(im.group[tris[i][k]], im.group[tris[i][(k + 1) % 3]]) + 1];
    for (int g = 0; g < im.num_groups; ++g) offset[g + 1] += offset[g];
    std::vector<std::pair<int, int>> edges(offset.back());
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (int i = 0; i < nt; ++i)
      for (int k = 0; k < 3; ++k) {
        const int a = im.group[tris[i][k]], b = im.group[tris[i][(k + 1) % 3]];
        edges[fill[std::min(a, b)]++] = {std::max(a, b), i};
      }
    isochart::UnionFind pieces(nt);
    std::vector<char> on_boundary(nt, 0);  // the triangle has an edge no other triangle shares
    for (int g = 0; g < im.num_groups; ++g) {
      std::sort(edges.begin() + offset[g], edges.begin() + offset[g + 1]);
      for (int x = offset[g]; x < offset[g + 1]; ++x) {
        const bool same_prev = x > offset[g] && edges[x].first == edges[x - 1].first;
        const bool same_next = x + 1 < offset[g + 1] && edges[x].first == edges[x + 1].first;
        if (same_prev) pieces.unite(edges[x].second, edges[x - 1].second);
        if (!same_prev && !same_next) on_boundary[edges[x].second] = 1;
      }
    }
    std::vector<int> piece_faces(nt, 0);
    std::vector<char> piece_open(nt, 0);
    for (int i = 0; i < nt; ++i) {
      ++piece_faces[pieces.find(i)];
      if (on_boundary[i]) piece_open[pieces.find(i)] = 1;
    }
    // Pieces sharing a vertex: cluster them through the groups.
    isochart::UnionFind clusters(nt);
    std::vector<int> group_piece(im.num_groups, -1);
    for (int i = 0; i < nt; ++i)
      for (int smp : tris[i]) {
        int& gp = group_piece[im.group[smp]];
        if (gp < 0) gp = pieces.find(i);
        else clusters.unite(gp, pieces.find(i));
      }
    std::vector<int> best(nt, -1);
    for (int i = 0; i < nt; ++i) {
      const int p = pieces.find(i), c = clusters.find(p);
      int& bp = best[c];
      if (bp < 0 || piece_faces[p] > piece_faces[bp] || (piece_faces[p] == piece_faces[bp] && p < bp)) bp = p;
    }
    std::size_t out = 0;
    for (int i = 0; i < nt; ++i) {
      const int p = pieces.find(i);
      // Only closed pieces are pockets: an open sheet touching another one at a vertex (two
      // holes pinched together) is surface, not an artefact.
      if (best[clusters.find(p)] != p && !piece_open[p]) {
        ++r.pocket_faces;
        continue;
      }
      tris[out] = tris[i];
      tri_chart[out] = tri_chart[i];
      ++out;
    }
    tris.resize(out);
    tri_chart.resize(out);
  }
  std::vector<int> rep(im.num_groups);
  std::iota(rep.begin(), rep.end(), 0);
  if (join_coincident) r.collapsed_faces += join_coincident_groups(im, group_sample, tris, tri_chart, rep);
  // Vertices in group order.
  std::vector<int> group_vertex(im.num_groups, -1);
  for (const auto& t : tris)
    for (int s : t) group_vertex[rep[im.group[s]]] = 0;
  int nv = 0;
  for (int g = 0; g < im.num_groups; ++g)
    if (group_vertex[g] == 0) group_vertex[g] = nv++;
  isochart::Mesh& m = r.mesh;
  m.positions.resize(nv);
  m.normals.resize(nv);
  for (int g = 0; g < im.num_groups; ++g) {
    if (group_vertex[g] < 0) continue;
    m.positions[group_vertex[g]] = im.positions[group_sample[g]];
    m.normals[group_vertex[g]] = im.normals[group_sample[g]];
  }
  r.sample_vertex.assign(N, -1);
  std::vector<int> sample_uv(N, -1);
  for (std::size_t i = 0; i < N; ++i)
    if (im.defined(static_cast<int>(i))) r.sample_vertex[i] = group_vertex[rep[im.group[i]]];
  m.faces.reserve(tris.size());
  m.face_uvs.reserve(tris.size());
  m.face_groups = tri_chart;
  r.face_samples = tris;
  for (const auto& t : tris) {
    Face f, fu;
    for (int k = 0; k < 3; ++k) {
      f[k] = r.sample_vertex[t[k]];
      if (sample_uv[t[k]] < 0) {
        sample_uv[t[k]] = static_cast<int>(m.uvs.size());
        m.uvs.push_back({(t[k] % W + 0.5) / W, (t[k] / W + 0.5) / H});
      }
      fu[k] = sample_uv[t[k]];
    }
    m.faces.push_back(f);
    m.face_uvs.push_back(fu);
    if (is_degenerate(m.positions[f[0]], m.positions[f[1]], m.positions[f[2]])) ++r.degenerate_faces;
  }
  return r;
}

TopologyCheck check_topology(const isochart::Mesh& mesh) {
  TopologyCheck c;
  const isochart::Topology topo(mesh);
  c.vertices = topo.num_referenced_vertices();
  c.faces = mesh.num_faces();
  c.edges = topo.num_edges();
  for (int e = 0; e < topo.num_edges(); ++e)
    if (topo.edge_faces(e).size() == 1) ++c.boundary_edges;
  c.nonmanifold_edges = static_cast<int>(topo.nonmanifold_edges().size());
  c.nonmanifold_vertices = static_cast<int>(topo.nonmanifold_vertices().size());
  c.boundary_loops = static_cast<int>(topo.boundary_loops().size());
  c.components = topo.num_components();
  c.euler_characteristic = topo.euler_characteristic();
  for (const Face& f : mesh.faces)
    if (is_degenerate(mesh.positions[f[0]], mesh.positions[f[1]], mesh.positions[f[2]])) ++c.degenerate_faces;
  return c;
}

}  // namespace mcgim
