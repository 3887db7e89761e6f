#pragma once
/// The triangle mesh and its connectivity.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "isochart/vec.h"

namespace isochart {

using Face = std::array<int, 3>;

/// An indexed triangle mesh with optional per-vertex and per-corner attributes.
/// Faces are counter-clockwise seen from outside. Optional arrays are empty when absent.
struct Mesh {
  std::vector<Vec3d> positions;  ///< #V vertex positions
  std::vector<Face> faces;       ///< #F vertex indices, 0-based

  std::vector<Vec3d> normals;   ///< #V per-vertex normals, or empty
  std::vector<Vec3d> colors;    ///< #V per-vertex RGB in [0, 1], or empty
  std::vector<Vec2d> uvs;       ///< texture coordinates referenced by face_uvs
  std::vector<Face> face_uvs;   ///< #F indices into `uvs`, or empty when the mesh has no UVs
  std::vector<int> face_groups; ///< #F group id per face (OBJ `g`/`o`, glTF primitive), or empty
  /// #F material per face, or empty: an OBJ's `usemtl` names numbered in order of first use,
  /// a glTF's material index; -1 for a face without one. find_material_textures numbers alike.
  std::vector<int> face_materials;
  /// OBJ: the `usemtl` name of each material id of face_materials; empty for other formats.
  std::vector<std::string> material_names;

  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_faces() const { return static_cast<int>(faces.size()); }
  bool has_uvs() const { return !face_uvs.empty(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
};

/// A contiguous range of ints (a row of a CSR array).
struct IndexRange {
  const int* first = nullptr;
  const int* last = nullptr;
  const int* begin() const { return first; }
  const int* end() const { return last; }
  int size() const { return static_cast<int>(last - first); }
  bool empty() const { return first == last; }
  int operator[](int i) const { return first[i]; }
};

/// Connectivity of a triangle soup: edges, edge→faces, vertex 1-rings, boundary loops,
/// connected components, Euler characteristic and genus. Works on non-manifold input (so
/// validation can report it); algorithms that need a manifold check `is_manifold()`.
///
/// Edge k of face f joins corners k and (k+1)%3: (faces[f][k], faces[f][(k+1)%3]).
class Topology {
 public:
  struct Edge {
    int v0, v1;  ///< v0 < v1
  };

  Topology() = default;
  Topology(const std::vector<Face>& faces, int num_vertices);
  explicit Topology(const Mesh& m) : Topology(m.faces, m.num_vertices()) {}

  int num_vertices() const { return num_vertices_; }
  int num_faces() const { return static_cast<int>(face_edges_.size()); }
  int num_edges() const { return static_cast<int>(edges_.size()); }

  const Edge& edge(int e) const { return edges_[e]; }
  const std::vector<Edge>& edges() const { return edges_; }
  /// The edge id of edge k of face f.
  int face_edge(int f, int k) const { return face_edges_[f][k]; }
  /// Faces incident to edge e (1 on the boundary, 2 inside, more when non-manifold).
  IndexRange edge_faces(int e) const { return row(edge_face_offsets_, edge_face_data_, e); }
  /// The face across edge k of f, or -1 if that edge is on the boundary or non-manifold.
  int opposite_face(int f, int k) const { return face_adjacency_[f][k]; }
  const std::vector<Face>& face_adjacency() const { return face_adjacency_; }
  /// Edge id joining vertices a and b, or -1.
  int find_edge(int a, int b) const;

  /// Faces incident to vertex v.
  IndexRange vertex_faces(int v) const { return row(vertex_face_offsets_, vertex_face_data_, v); }
  /// Vertices sharing an edge with v (its 1-ring), sorted by id.
  IndexRange vertex_neighbors(int v) const {
    return row(vertex_neighbor_offsets_, vertex_neighbor_data_, v);
  }
  bool is_referenced(int v) const { return !vertex_faces(v).empty(); }
  int num_referenced_vertices() const { return num_referenced_; }

  bool is_boundary_edge(int e) const { return edge_faces(e).size() == 1; }
  bool is_boundary_vertex(int v) const { return boundary_vertex_[v] != 0; }
  /// Boundary loops as vertex sequences, oriented along the faces' boundary half-edges.
  const std::vector<std::vector<int>>& boundary_loops() const { return boundary_loops_; }

  /// Edges with more than two incident faces.
  const std::vector<int>& nonmanifold_edges() const { return nonmanifold_edges_; }
  /// Vertices whose incident faces form more than one edge-connected fan.
  const std::vector<int>& nonmanifold_vertices() const { return nonmanifold_vertices_; }
  bool is_manifold() const { return nonmanifold_edges_.empty() && nonmanifold_vertices_.empty(); }

  /// Connected component (through shared edges) of every face, numbered from 0.
  const std::vector<int>& face_components() const { return face_component_; }
  int num_components() const { return num_components_; }

  /// χ = V − E + F over referenced vertices.
  int euler_characteristic() const;
  /// Sum over components of (2 − χ_c − b_c)/2, with b_c the component's boundary loops.
  int genus() const;
  /// Genus of one component.
  int component_genus(int c) const;
  /// Number of boundary loops in component c.
  int component_boundary_loops(int c) const;

 private:
  static IndexRange row(const std::vector<int>& off, const std::vector<int>& data, int i) {
    return {data.data() + off[i], data.data() + off[i + 1]};
  }

  int num_vertices_ = 0;
  int num_referenced_ = 0;
  std::vector<Edge> edges_;
  std::vector<Face> face_edges_;
  std::vector<Face> face_adjacency_;
  std::vector<int> edge_face_offsets_, edge_face_data_;
  std::vector<int> vertex_face_offsets_, vertex_face_data_;
  std::vector<int> vertex_neighbor_offsets_, vertex_neighbor_data_;
  std::vector<char> boundary_vertex_;
  std::vector<std::vector<int>> boundary_loops_;
  std::vector<int> nonmanifold_edges_, nonmanifold_vertices_;
  std::vector<int> face_component_;
  int num_components_ = 0;
  // Per component: vertices, edges, faces, boundary loops (for per-component genus).
  std::vector<std::array<int, 4>> component_counts_;
};

/// A sub-mesh with maps back to the parent's ids.
struct SubMesh {
  Mesh mesh;
  std::vector<int> vertex_to_parent;  ///< sub vertex → parent vertex
  std::vector<int> face_to_parent;    ///< sub face → parent face
};

/// Extracts the faces `faces` (parent ids, any order; kept in that order) with the vertices they
/// use. Per-vertex attributes, UVs and groups are carried over.
SubMesh extract_submesh(const Mesh& parent, const std::vector<int>& faces);

/// Per-face unit normals (zero for degenerate faces).
std::vector<Vec3d> face_normals(const Mesh& m);
/// Area-weighted per-vertex unit normals.
std::vector<Vec3d> vertex_normals(const Mesh& m);
/// Per-face areas.
std::vector<double> face_areas(const Mesh& m);
double surface_area(const Mesh& m);

struct BoundingBox {
  Vec3d min, max;
  double diagonal() const { return norm(max - min); }
};
BoundingBox bounding_box(const Mesh& m);
BoundingBox bounding_box(const std::vector<Vec3d>& points);

/// Mean length over the mesh's unique edges.
double mean_edge_length(const Mesh& m, const Topology& t);

}  // namespace isochart
