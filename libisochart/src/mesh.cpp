#include "isochart/mesh.h"

#include <algorithm>
#include <numeric>
#include <unordered_map>

#include "isochart/union_find.h"

namespace isochart {

namespace {

// Fills a CSR structure from (row, value) pairs, keeping insertion order inside each row.
void build_csr(int rows, const std::vector<std::pair<int, int>>& pairs, std::vector<int>& offsets,
               std::vector<int>& data) {
  offsets.assign(rows + 1, 0);
  for (const auto& p : pairs) ++offsets[p.first + 1];
  for (int i = 0; i < rows; ++i) offsets[i + 1] += offsets[i];
  data.resize(pairs.size());
  std::vector<int> cursor(offsets.begin(), offsets.end() - 1);
  for (const auto& p : pairs) data[cursor[p.first]++] = p.second;
}

}  // namespace

Topology::Topology(const std::vector<Face>& faces, int num_vertices)
    : num_vertices_(num_vertices) {
  const int nf = static_cast<int>(faces.size());

  // Edges: bucket the 3F half-edges by their smaller vertex (counting sort), then sort each
  // small bucket by the larger vertex. Linear apart from the tiny per-vertex sorts.
  struct HalfEdge {
    int b, face, corner;
  };
  std::vector<int> bucket(num_vertices + 1, 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++bucket[std::min(faces[f][k], faces[f][(k + 1) % 3]) + 1];
  for (int v = 0; v < num_vertices; ++v) bucket[v + 1] += bucket[v];
  std::vector<HalfEdge> hes(3 * static_cast<size_t>(nf));
  {
    std::vector<int> cursor(bucket.begin(), bucket.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int u = faces[f][k], v = faces[f][(k + 1) % 3];
        hes[cursor[std::min(u, v)]++] = {std::max(u, v), f, k};
      }
  }
  face_edges_.assign(nf, Face{-1, -1, -1});
  edges_.reserve(3 * static_cast<size_t>(nf) / 2 + 1);
  edge_face_offsets_.assign(1, 0);
  edge_face_data_.resize(hes.size());
  for (int a = 0; a < num_vertices; ++a) {
    const auto first = hes.begin() + bucket[a], last = hes.begin() + bucket[a + 1];
    std::sort(first, last, [](const HalfEdge& x, const HalfEdge& y) {
      return x.b != y.b ? x.b < y.b : (x.face != y.face ? x.face < y.face : x.corner < y.corner);
    });
    for (auto it = first; it != last;) {
      const int e = static_cast<int>(edges_.size());
      edges_.push_back({a, it->b});
      auto jt = it;
      for (; jt != last && jt->b == it->b; ++jt) {
        face_edges_[jt->face][jt->corner] = e;
        edge_face_data_[edge_face_offsets_.back() + (jt - it)] = jt->face;
      }
      edge_face_offsets_.push_back(edge_face_offsets_.back() + static_cast<int>(jt - it));
      it = jt;
    }
  }

  face_adjacency_.assign(nf, Face{-1, -1, -1});
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const IndexRange ef = edge_faces(face_edges_[f][k]);
      if (ef.size() == 2) face_adjacency_[f][k] = ef[0] == f ? ef[1] : ef[0];
    }
  for (int e = 0; e < num_edges(); ++e)
    if (edge_faces(e).size() > 2) nonmanifold_edges_.push_back(e);

  // Vertex → faces (in face order) and vertex → neighbours (sorted).
  std::vector<std::pair<int, int>> vf;
  vf.reserve(3 * static_cast<size_t>(nf));
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) vf.emplace_back(faces[f][k], f);
  build_csr(num_vertices, vf, vertex_face_offsets_, vertex_face_data_);
  std::vector<std::pair<int, int>> vv;
  vv.reserve(2 * edges_.size());
  for (const Edge& e : edges_) {
    vv.emplace_back(e.v0, e.v1);
    vv.emplace_back(e.v1, e.v0);
  }
  build_csr(num_vertices, vv, vertex_neighbor_offsets_, vertex_neighbor_data_);
  for (int v = 0; v < num_vertices; ++v)
    std::sort(vertex_neighbor_data_.begin() + vertex_neighbor_offsets_[v],
              vertex_neighbor_data_.begin() + vertex_neighbor_offsets_[v + 1]);
  num_referenced_ = 0;
  for (int v = 0; v < num_vertices; ++v) num_referenced_ += is_referenced(v) ? 1 : 0;

  // Non-manifold vertices: walk the faces around v through the edges incident to v; if the
  // walk from the first face does not reach them all, they form several fans.
  std::vector<int> stack, walked;
  std::vector<char> seen, edge_walked(edges_.size(), 0);
  for (int v = 0; v < num_vertices; ++v) {
    const IndexRange vfs = vertex_faces(v);
    if (vfs.size() < 2) continue;
    seen.assign(vfs.size(), 0);
    // vfs is in face order: a binary search, since a degenerate fan (every face on one
    // vertex, as UVs all at one point give) made a linear one cubic in the fan's size.
    auto local = [&](int f) {
      const int* it = std::lower_bound(vfs.begin(), vfs.end(), f);
      return it != vfs.end() && *it == f ? static_cast<int>(it - vfs.begin()) : -1;
    };
    stack.assign(1, 0);
    seen[0] = 1;
    int reached = 1;
    while (!stack.empty()) {
      const int f = vfs[stack.back()];
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const int e = face_edges_[f][k];
        if (edges_[e].v0 != v && edges_[e].v1 != v) continue;
        // Each edge's faces once per walk (an edge of many degenerate faces is met from each).
        if (edge_walked[e]) continue;
        edge_walked[e] = 1;
        walked.push_back(e);
        for (int g : edge_faces(e)) {
          const int i = local(g);
          if (i >= 0 && !seen[i]) {
            seen[i] = 1;
            ++reached;
            stack.push_back(i);
          }
        }
      }
    }
    for (int e : walked) edge_walked[e] = 0;
    walked.clear();
    if (reached < vfs.size()) nonmanifold_vertices_.push_back(v);
  }

  // Components through shared edges.
  UnionFind uf(nf);
  for (int e = 0; e < num_edges(); ++e) {
    const IndexRange ef = edge_faces(e);
    for (int i = 1; i < ef.size(); ++i) uf.unite(ef[0], ef[i]);
  }
  face_component_.assign(nf, -1);
  std::vector<int> root_id(nf, -1);
  num_components_ = 0;
  for (int f = 0; f < nf; ++f) {
    const int r = uf.find(f);
    if (root_id[r] < 0) root_id[r] = num_components_++;
    face_component_[f] = root_id[r];
  }

  // Boundary loops from the boundary half-edges (edges with exactly one face).
  boundary_vertex_.assign(num_vertices, 0);
  std::vector<std::pair<int, int>> out;  // (from vertex, to vertex) of boundary half-edges
  std::vector<int> out_face;
  for (int e = 0; e < num_edges(); ++e) {
    if (edge_faces(e).size() != 1) continue;
    const int f = edge_faces(e)[0];
    for (int k = 0; k < 3; ++k)
      if (face_edges_[f][k] == e) {
        out.emplace_back(faces[f][k], faces[f][(k + 1) % 3]);
        out_face.push_back(f);
      }
    boundary_vertex_[edges_[e].v0] = boundary_vertex_[edges_[e].v1] = 1;
  }
  std::vector<int> order(out.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int x, int y) { return out[x] < out[y]; });
  std::unordered_map<int, std::vector<int>> by_start;
  for (int i : order) by_start[out[i].first].push_back(i);
  std::vector<char> used(out.size(), 0);
  std::vector<int> loop_component;
  for (int start : order) {
    if (used[start]) continue;
    std::vector<int> loop;
    int h = start;
    while (h >= 0 && !used[h]) {
      used[h] = 1;
      loop.push_back(out[h].first);
      int next = -1;
      for (int cand : by_start[out[h].second])
        if (!used[cand]) {
          next = cand;
          break;
        }
      h = next;
    }
    loop_component.push_back(face_component_[out_face[start]]);
    boundary_loops_.push_back(std::move(loop));
  }

  // Per-component counts for the genus.
  component_counts_.assign(num_components_, {0, 0, 0, 0});
  for (int f = 0; f < nf; ++f) ++component_counts_[face_component_[f]][2];
  for (int e = 0; e < num_edges(); ++e) ++component_counts_[face_component_[edge_faces(e)[0]]][1];
  for (int c : loop_component) ++component_counts_[c][3];
  std::vector<int> stamp(num_vertices, -1);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = faces[f][k], c = face_component_[f];
      if (stamp[v] != c) {
        stamp[v] = c;
        ++component_counts_[c][0];
      }
    }
}

int Topology::find_edge(int a, int b) const {
  if (a < 0 || a >= num_vertices_) return -1;
  for (int f : vertex_faces(a))
    for (int k = 0; k < 3; ++k) {
      const Edge& e = edges_[face_edges_[f][k]];
      if ((e.v0 == a && e.v1 == b) || (e.v0 == b && e.v1 == a)) return face_edges_[f][k];
    }
  return -1;
}

int Topology::euler_characteristic() const {
  return num_referenced_ - num_edges() + num_faces();
}

int Topology::component_boundary_loops(int c) const { return component_counts_[c][3]; }

int Topology::component_genus(int c) const {
  const auto& k = component_counts_[c];
  const int chi = k[0] - k[1] + k[2];
  return (2 - chi - k[3]) / 2;
}

int Topology::genus() const {
  int g = 0;
  for (int c = 0; c < num_components_; ++c) g += component_genus(c);
  return g;
}

SubMesh extract_submesh(const Mesh& parent, const std::vector<int>& faces) {
  SubMesh s;
  std::unordered_map<int, int> vmap, uvmap;
  vmap.reserve(faces.size());
  s.face_to_parent = faces;
  s.mesh.faces.reserve(faces.size());
  for (int pf : faces) {
    Face nfce;
    for (int k = 0; k < 3; ++k) {
      const int pv = parent.faces[pf][k];
      auto [it, inserted] = vmap.emplace(pv, static_cast<int>(s.vertex_to_parent.size()));
      if (inserted) s.vertex_to_parent.push_back(pv);
      nfce[k] = it->second;
    }
    s.mesh.faces.push_back(nfce);
    if (parent.has_uvs()) {
      Face t;
      for (int k = 0; k < 3; ++k) {
        const int pu = parent.face_uvs[pf][k];
        auto [it, inserted] = uvmap.emplace(pu, static_cast<int>(s.mesh.uvs.size()));
        if (inserted) s.mesh.uvs.push_back(parent.uvs[pu]);
        t[k] = it->second;
      }
      s.mesh.face_uvs.push_back(t);
    }
    if (!parent.face_groups.empty()) s.mesh.face_groups.push_back(parent.face_groups[pf]);
    if (!parent.face_materials.empty()) s.mesh.face_materials.push_back(parent.face_materials[pf]);
  }
  if (!s.mesh.face_materials.empty()) s.mesh.material_names = parent.material_names;
  s.mesh.positions.reserve(s.vertex_to_parent.size());
  for (int pv : s.vertex_to_parent) {
    s.mesh.positions.push_back(parent.positions[pv]);
    if (parent.has_normals()) s.mesh.normals.push_back(parent.normals[pv]);
    if (parent.has_colors()) s.mesh.colors.push_back(parent.colors[pv]);
  }
  return s;
}

std::vector<Vec3d> face_normals(const Mesh& m) {
  std::vector<Vec3d> n(m.faces.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const auto& F = m.faces[f];
    n[f] = normalized(cross(m.positions[F[1]] - m.positions[F[0]], m.positions[F[2]] - m.positions[F[0]]));
  }
  return n;
}

std::vector<Vec3d> vertex_normals(const Mesh& m) {
  std::vector<Vec3d> n(m.positions.size());
  for (const auto& F : m.faces) {
    // The unnormalized cross product weights by area.
    const Vec3d c = cross(m.positions[F[1]] - m.positions[F[0]], m.positions[F[2]] - m.positions[F[0]]);
    for (int k = 0; k < 3; ++k) n[F[k]] += c;
  }
  for (auto& v : n) v = normalized(v);
  return n;
}

std::vector<double> face_areas(const Mesh& m) {
  std::vector<double> a(m.faces.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const auto& F = m.faces[f];
    a[f] = triangle_area(m.positions[F[0]], m.positions[F[1]], m.positions[F[2]]);
  }
  return a;
}

double surface_area(const Mesh& m) {
  double s = 0;
  for (double a : face_areas(m)) s += a;
  return s;
}

BoundingBox bounding_box(const Mesh& m) { return bounding_box(m.positions); }

BoundingBox bounding_box(const std::vector<Vec3d>& points) {
  BoundingBox b;
  if (points.empty()) return b;
  b.min = b.max = points[0];
  for (const auto& p : points)
    for (int i = 0; i < 3; ++i) {
      b.min[i] = std::min(b.min[i], p[i]);
      b.max[i] = std::max(b.max[i], p[i]);
    }
  return b;
}

double mean_edge_length(const Mesh& m, const Topology& t) {
  if (t.num_edges() == 0) return 0;
  double s = 0;
  for (const auto& e : t.edges()) s += norm(m.positions[e.v0] - m.positions[e.v1]);
  return s / t.num_edges();
}

}  // namespace isochart
