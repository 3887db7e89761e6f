#pragma once
/// Geodesic distances on triangle meshes by fast marching (Kimmel & Sethian 1998), as used by
/// surface spectral analysis (Iso-charts §4.1) and landmark IsoMap (§6).

#include <limits>
#include <vector>

#include "isochart/mesh.h"
#include "isochart/vec.h"

namespace isochart {

namespace detail {
// Internal to GeodesicSolver (here only because the class stores it). What accepting the owner X
// of one real or virtual triangle (X, y, z) can update: y along the edge from X, and y from
// (X, z) by the planar triangle update in the frame X = (0, 0), z = (|xz|, 0), y = (fy_cx, fy_cy)
// with fy_cy < 0 (0 disables it); the same for z with the frame X = (0, 0), y = (|xy|, 0).
// A negative length disables the edge update along it (a virtual edge, or one another wedge of
// X already covers). 32 bytes in float: runs stream these from memory, so their size sets the
// speed, while float rounding (1e-7 relative) is far below the marching error.
struct GeodesicWedge {
  int y, z;
  float xy, xz;
  float fy_cx, fy_cy;
  float fz_cx, fz_cy;
};
}  // namespace detail

/// Precomputed mesh data for repeated fast-marching runs on one mesh (or chart).
///
/// The front is Dijkstra-ordered; a vertex C is updated from two accepted neighbours A, B of a
/// triangle by unfolding it into the plane and placing the virtual point source that has the
/// distances d(A), d(B) (exact for a point source on a plane); the update is taken only when
/// the source's ray to C crosses the edge AB, otherwise edge updates d(A) + |AC| apply.
///
/// Obtuse triangles (Kimmel & Sethian 1998): a triangle obtuse at C (beyond about 96°; nearly
/// right corners gained nothing measurable) is split once, at construction, by unfolding the
/// triangles across its opposite edge until a vertex V lies in the acute section of the angle;
/// the two virtual triangles (C, A, V) and (C, V, B) then also update C. The obtuse triangle's
/// own update stays: it is still exact on a plane whenever its ray is inside, and keeping it
/// halved the error on a curved torus compared with replacing it. When no such vertex is found
/// within a few unfoldings (mesh boundary, non-manifold edge) only the obtuse triangle is used.
///
/// Works on open meshes, several components (unreachable vertices get +inf), unreferenced
/// vertices (always +inf unless a source) and non-manifold edges (never unfolded across).
/// Construction is O(#F); the solver keeps no reference to its inputs.
class GeodesicSolver {
 public:
  static constexpr double inf = std::numeric_limits<double>::infinity();

  /// \param positions #V vertex positions, \param faces #F triangles (0-based).
  /// \throw InputError when a face index is out of range or a position is not finite.
  GeodesicSolver(const std::vector<Vec3d>& positions, const std::vector<Face>& faces);
  explicit GeodesicSolver(const Mesh& mesh) : GeodesicSolver(mesh.positions, mesh.faces) {}

  /// #V, as given (unreferenced vertices included).
  int num_vertices() const { return static_cast<int>(positions_.size()); }
  /// A copy of the positions given (for landmark seeding and Euclidean sampling).
  const std::vector<Vec3d>& positions() const { return positions_; }
  /// True when some non-degenerate face uses vertex v.
  bool is_referenced(int v) const { return wedge_offsets_[v + 1] > wedge_offsets_[v]; }
  /// Diagnostics: obtuse corners given two acute virtual triangles, and those left without.
  int num_split_obtuse() const { return split_obtuse_; }
  int num_unsplit_obtuse() const { return unsplit_obtuse_; }

  /// Distances from `sources` (0 at each) to every vertex, +inf where unreachable. `out` is
  /// resized to #V. With several sources each vertex gets (close to) the smallest of the
  /// single-source distances: triangle updates never mix two sources' fronts. `max_distance`
  /// stops the front early: vertices beyond it get +inf.
  /// Thread-safe: concurrent calls on one solver are allowed (each thread has its own scratch,
  /// kept between calls, so repeated calls allocate nothing but the output).
  /// \throw Error when a source is not a vertex id.
  void distances(const std::vector<int>& sources, std::vector<double>& out, double max_distance = inf) const;
  /// Same, writing #V values to `out`.
  void distances(const int* sources, int num_sources, double* out, double max_distance = inf) const;

  /// One row of #V distances per source, row-major (#sources × #V), rows computed in parallel
  /// (oneTBB); the result does not depend on the thread count.
  std::vector<double> distance_rows(const std::vector<int>& sources) const;

  /// Lowers `field` (#V values) to the distance from `source` wherever that is smaller, and
  /// returns the number of vertices lowered. The front only visits vertices whose value drops,
  /// so the cost is proportional to the source's new Voronoi cell: this is what makes geodesic
  /// farthest-point sampling cheap. Values at the cell's border may be slightly larger than a
  /// full run would give, because neighbours outside the cell are never accepted.
  int lower_distances(int source, std::vector<double>& field) const;

 private:
  // Fast marching from `sources` over `d`, which holds the starting upper bounds (+inf for a
  // plain run, the current field for lower_distances); a vertex enters the front only when its
  // value drops, and never beyond max_distance. `accepted` receives the vertices accepted.
  template <bool kSeveralSources>
  void march(const int* sources, int num_sources, double* d, double max_distance, int* accepted) const;

  std::vector<Vec3d> positions_;
  std::vector<int> wedge_offsets_;  // #V + 1, CSR rows of wedges_ by owner vertex
  std::vector<detail::GeodesicWedge> wedges_;
  int split_obtuse_ = 0;
  int unsplit_obtuse_ = 0;
};

/// Exact geodesic distances from vertex `source` to every vertex (CGAL's
/// Surface_mesh_shortest_path, Mitchell–Mount–Papadimitriou style; O(#V² log #V)). A reference
/// for tests and benchmarks on small meshes, far too slow for the atlas. Unreachable and
/// unreferenced vertices get +inf.
/// \throw InputError when the faces do not form an oriented 2-manifold CGAL accepts.
std::vector<double> exact_geodesic_distances(const std::vector<Vec3d>& positions,
                                             const std::vector<Face>& faces, int source);

}  // namespace isochart
