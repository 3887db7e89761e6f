#pragma once
// Internal: one chart's geometry, parameterization and acceptance test (Iso-charts §3, §6).

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "isochart/mesh.h"

namespace isochart {

struct Embedding;

namespace detail {

/// A chart as its own small mesh. After cut_to_disk some parent vertices appear more than once.
struct ChartGeometry {
  std::vector<int> faces;          ///< parent face ids, in chart face order
  std::vector<Vec3d> positions;    ///< chart vertices
  std::vector<Face> tris;          ///< chart-local triangles
  std::vector<int> vertex_parent;  ///< chart vertex → parent vertex
  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_faces() const { return static_cast<int>(tris.size()); }
};

ChartGeometry make_chart(const Mesh& mesh, const std::vector<int>& faces);

/// Cuts a genus-0 chart with several boundary loops into a disk by slitting it along shortest
/// edge paths that join every loop to the first one (the chart keeps one piece; UVAtlas's
/// "make the chart simple" step). Returns false when the chart is not genus 0 with ≥ 1 loop.
/// `origin` (if given) receives, for every vertex after the cut, the vertex it was copied from.
/// `topo` may pass g's current topology to save rebuilding it.
bool cut_to_disk(ChartGeometry& g, std::vector<int>* origin = nullptr, const Topology* topo = nullptr);

/// Cuts a seam into a disk chart from the vertex farthest (geodesically) from its boundary
/// straight back to the boundary, down the distance field's steepest descent. A sock-shaped
/// chart (a tube closed at one end, like a leg) then unrolls flat instead of folding onto
/// itself. Returns false when g is not a disk or no seam was cut.
/// `boundary_distance` (#V, geodesic distance to the boundary) may be given to save a run.
bool cut_seam(ChartGeometry& g, const Topology& topo, const std::vector<double>* boundary_distance = nullptr);

/// Geodesic distance from every vertex to the boundary of g.
std::vector<double> boundary_distance(const ChartGeometry& g, const Topology& topo);

/// A disk chart shaped like a sock (a tube closed at one end): its farthest point from the
/// boundary is more than 0.4 boundary lengths away (a flat disk: 0.16, a hemisphere: 0.25).
bool is_sock(const ChartGeometry& g, const Topology& topo, const std::vector<double>& boundary_distance);

/// Opens zero-width slits in a start parameterization of a cut chart: every vertex sharing its
/// origin with another moves slightly into its own triangles, so the boundary starts simple.
void open_slits(const ChartGeometry& g, const std::vector<int>& origin, std::vector<Vec2d>& uv);

/// Duplicates vertices along the marked edges (a flag per Topology edge id of g) so the mesh
/// opens there; vertices whose faces form several fans are split too. `origin` as above.
void cut_along_edges(ChartGeometry& g, const std::vector<char>& cut_edge, std::vector<int>* origin = nullptr,
                     const Topology* topo = nullptr);

/// g's topology, after giving each fan of a pinched (non-manifold) vertex its own copy.
Topology chart_topology(ChartGeometry& g);

struct ParamOptions {
  double max_l2 = 1.1;
  double max_linf = 5.0;
  int optimize_passes = 6;
  std::uint64_t seed = 1;
  /// Try an LSCM start when the given start fails by folding, overlap or a narrow miss.
  bool lscm_fallback = true;
  /// ... or whenever the given start fails: for starts that say nothing about the chart's
  /// shape (two merged parameterizations aligned by a similarity), unlike an IsoMap start.
  bool lscm_on_any_failure = false;
  /// A start with more than this fraction of its area covered twice is not optimized (it fails
  /// as overlapping, and LSCM gets its turn); 1 = always optimize.
  double max_start_overlap = 1;
  /// Signal metric per parent face (AtlasOptions::face_metric), or null: the chart's L2 is
  /// then measured in it, and its geometric L2 must still meet max_geometric_l2.
  const std::vector<std::array<double, 3>>* face_metric = nullptr;
  double max_geometric_l2 = 2.0;
  /// The chart's topology if the caller has it, or null (then it is built once per call).
  const Topology* topology = nullptr;
  /// OptimizeOptions::cancel: set when the result is no longer wanted (it is then not accepted).
  const std::atomic<bool>* cancel = nullptr;
};

struct ChartParam {
  std::vector<Vec2d> uv;  ///< per chart vertex; empty when no valid map was found
  double l2 = 0, linf = 0;  ///< l2 in the signal metric when ParamOptions::face_metric is set
  double geometric_l2 = 0;
  int flipped = 0;
  bool overlaps = false;
  bool accepted = false;
  std::string method;     ///< which initialization produced it ("isomap", "lscm", "triangle")
  double initial_l2 = 0;  ///< stretch of the start, before optimization
  double initial_flip_fraction = 0;  ///< flipped fraction of the start, before untangling
  double optimize_seconds = 0;
};

/// Parameterizes a disk chart, starting from `isomap_uv` (the first two IsoMap coordinates per
/// chart vertex; may be empty) and, when that fails by folding, overlap or a narrow miss, from
/// LSCM; each start is untangled and stretch-optimized. Accepted when it has no flip, no
/// self-overlap and meets both bounds. Returns the best attempt.
ChartParam parameterize(const ChartGeometry& g, const std::vector<Vec2d>& isomap_uv, const ParamOptions& o);

/// A lower bound on the Linf stretch of every parameterization of g without flips or overlaps
/// (1 when none is known). Such a layout's angles around an interior vertex sum to 2π, so a
/// vertex whose 3D angles sum to Θ needs its k corners' angles changed by |2π − Θ| in all; a
/// triangle mapped with singular values σ1 ≥ σ2 changes an angle by at most
/// 2·asin((r − 1)/(r + 1)), r = σ1/σ2, and its Linf is at least √r. Vertices on g's boundary
/// (by `topo`) or next to a zero-area face are left out.
double linf_lower_bound(const ChartGeometry& g, const Topology& topo);

/// True when linf_lower_bound shows that no layout of g meets `max_linf` (up to rounding);
/// always false from kLinfDefectTestBelow on. `topo` is g's topology, or null to build it (only
/// when the test runs).
bool linf_bound_unreachable(const ChartGeometry& g, const Topology* topo, double max_linf);

/// The first two embedding coordinates per vertex (empty when the embedding has fewer than two).
std::vector<Vec2d> isomap_uv(const Embedding& e);

/// Fraction of a layout's covered area covered more than once, estimated on a grid of about
/// `cells` cells over its bounding box (cell centres inside a triangle; edges half-open, so
/// triangles sharing an edge cover its centres once). Cheap next to an exact overlap test: it
/// tells a start folded onto itself on a large scale, which local moves cannot undo.
double multiply_covered_fraction(const std::vector<Face>& tris, const std::vector<Vec2d>& uv, double cells);

/// Least squares conformal map (Lévy et al. 2002) with the two farthest boundary vertices pinned.
/// Returns false if the system cannot be solved.
/// `topo` may pass g's topology to save rebuilding it.
bool lscm(const ChartGeometry& g, std::vector<Vec2d>& uv, const Topology* topo = nullptr);

/// Accepted = disk topology (checked by the caller), no flip, no overlap, both bounds met.
/// `topology` may pass g's topology to save rebuilding it.
void evaluate(const ChartGeometry& g, ChartParam& p, const ParamOptions& o, const Topology* topology = nullptr);

}  // namespace detail
}  // namespace isochart
