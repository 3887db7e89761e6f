#pragma once
/// Surface spectral analysis with landmark IsoMap (Iso-charts §4.1, §5.2.1, §6): classical MDS
/// of the squared geodesic distances between q landmark vertices, and the landmark-MDS placement
/// of every other vertex from its distances to the landmarks.

#include <functional>
#include <vector>

#include "isochart/geodesic.h"

namespace isochart {

/// How landmark vertices are chosen.
enum class LandmarkMethod {
  /// Farthest-point sampling on geodesic distance where each new landmark's front only visits
  /// its new Voronoi cell (GeodesicSolver::lower_distances), then the q full distance rows in
  /// parallel. Same landmarks as GeodesicFps up to rounding at cell borders, for about ln(q)
  /// sequential runs' worth of marching instead of q. The default.
  FastGeodesicFps,
  /// Plain geodesic farthest-point sampling: q sequential full runs, whose rows are reused.
  GeodesicFps,
  /// Farthest-point sampling on straight-line distance, then the rows in parallel. Cheapest,
  /// but undersamples parts that are close in space and far on the surface (fingers, ears).
  EuclideanFps,
};

/// Options of landmark_isomap.
struct EmbeddingOptions {
  /// q; all referenced vertices when the mesh has fewer (Iso-charts §6). At least 2.
  int landmarks = 100;
  int max_dimensions = 10;  ///< top eigenpairs computed (§6). ≥ 1.
  LandmarkMethod landmark_method = LandmarkMethod::FastGeodesicFps;  ///< how landmarks are chosen
};

/// A landmark IsoMap embedding of one connected mesh or chart. Matrices are row-major.
struct Embedding {
  int num_vertices = 0;        ///< #V of the solver's mesh
  std::vector<int> landmarks;  ///< q vertex ids, in the order chosen (see choose_landmarks)
  /// q × #V geodesic distances, row per landmark (+inf at unreferenced vertices). The q × q
  /// landmark-to-landmark entries hold the mean of both directions (fast marching is not
  /// exactly symmetric), so they form the symmetric D of §4.1.
  std::vector<double> landmark_distances;
  /// Descending: the positive ones among the top max_dimensions eigenvalues of B, where
  /// "positive" means above 1e-6·λ1, so that rounding noise on a flat chart adds no dimension.
  std::vector<double> eigenvalues;
  /// Σ of the positive eigenvalues of B (all q of them, not only the top ones), the total energy
  /// for the eigenvalue-share tests of §5.1/§5.3.
  double eigenvalue_sum = 0;
  int dimensions = 0;  ///< = eigenvalues.size()
  /// dimensions × q unit eigenvectors v_j of B, row per dimension, each with its
  /// largest-magnitude component positive (so results are reproducible).
  std::vector<double> eigenvectors;
  /// q values: the mean over landmarks of the squared landmark–landmark distances (Δ̄ of §5.2.1).
  std::vector<double> mean_squared_distances;
  /// #V × dimensions, row-major. Landmark k: y^j = sqrt(λ_j) v_j^k (§4.1); any other vertex is
  /// placed from its squared distances to the landmarks by place_points (§5.2.1). Unreferenced
  /// vertices are at the origin.
  std::vector<double> coordinates;
  /// Wall-clock seconds, for reports and benchmarks: choosing the landmarks (rows computed by
  /// other threads meanwhile are not counted separately), finishing the distance rows after
  /// that, and the eigen solver plus placement.
  double seconds_landmarks = 0, seconds_rows = 0, seconds_spectral = 0;

  /// Coordinate `dim` of `vertex`.
  double coordinate(int vertex, int dim) const {
    return coordinates[static_cast<std::size_t>(vertex) * dimensions + dim];
  }
  /// Geodesic distance from landmark number `landmark_index` (not a vertex id) to `vertex`.
  double landmark_distance(int landmark_index, int vertex) const {
    return landmark_distances[static_cast<std::size_t>(landmark_index) * num_vertices + vertex];
  }
};

/// Landmark IsoMap embedding (Iso-charts §4.1, §6) of the mesh behind `solver`: choose q
/// landmarks, compute their distance rows by fast marching (in parallel with oneTBB; identical
/// for any thread count), double-centre the squared landmark distances into B = −½ J D J,
/// take its top eigenpairs, place every vertex. Unreferenced vertices are ignored (never
/// landmarks, at the origin).
///
/// \throw InputError when options are out of range or no face uses any vertex.
/// \throw Error when the referenced vertices are not one connected surface (embed each
///        component separately).
Embedding landmark_isomap(const GeodesicSolver& solver, const EmbeddingOptions& options = {});

/// The spectral half of landmark_isomap for any landmark distances (e.g. the combined
/// geodesic/signal distance of §7 eq. 6): from `e.num_vertices`, `e.landmarks` and the q × #V
/// `e.landmark_distances` (symmetrized here on the landmark block), computes the classical MDS
/// of the landmarks (§4.1), at most `max_dimensions` positive eigenpairs, and places every
/// vertex for which `referenced` holds (§5.2.1; non-finite distances contribute nothing).
void embed_landmarks(Embedding& e, int max_dimensions, const std::function<bool(int)>& referenced);

/// Chooses `count` landmarks (all referenced vertices, in id order, when there are no more
/// than `count`). Farthest-point sampling starts at the referenced vertex farthest from the
/// centroid of the referenced vertices (lowest id on ties); each next landmark is the vertex
/// farthest from those chosen (lowest id on ties). With GeodesicFps, `rows` (if not null)
/// receives the count × #V distance rows computed on the way; otherwise, or when all vertices
/// are landmarks, it is cleared.
/// \throw InputError when count < 1 or no face uses any vertex.
/// \throw Error as landmark_isomap when the surface is not connected (geodesic methods).
std::vector<int> choose_landmarks(const GeodesicSolver& solver, int count, LandmarkMethod method,
                                  std::vector<double>* rows = nullptr);

/// Places points given their squared geodesic distances to the landmarks of `e` (§5.2.1
/// formula, v_p = ½ L† (Δ̄ − Δ_p)), using the first `dims` dimensions. Used to embed a medial
/// region w.r.t. a sub-chart. \param squared_distances_to_landmarks q values;
/// \param out `dims` values. \pre 0 ≤ dims ≤ e.dimensions.
void place_points(const Embedding& e, int dims, const double* squared_distances_to_landmarks, double* out);

/// Geodesic distance distortion per vertex (eq. 1), measured against the landmarks:
/// sqrt(1/(q−1) Σ_l (‖y_i − y_l‖ − d_geo(i, l))²) using the first `dims` coordinates.
/// #V values; 0 at unreferenced vertices. \pre 0 ≤ dims ≤ e.dimensions.
std::vector<double> gdd(const Embedding& e, int dims);

}  // namespace isochart
