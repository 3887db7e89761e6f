#pragma once
// Internal: the combined geodesic/signal distance of Iso-charts §7 (eq. 6) in a chart's
// landmark embedding.

#include <vector>

#include "chart.h"
#include "isochart/embedding.h"

namespace isochart::detail {

/// Signal distance from each landmark along its geodesics (Iso-charts §7): for every vertex, the
/// sum of signal differences |Δf| along the geodesic path from the landmark, with f linear over
/// each triangle. The geodesics are read back from the fast-marching distance rows
/// `geo_rows` (#landmarks × #V, as Embedding::landmark_distances): vertices are visited in
/// increasing distance, and each takes the update that best explains its distance from
/// vertices already visited (the same planar point-source update and edge update that fast
/// marching uses): s(C) = s(foot) + |f(C) − f(foot)|, s and f interpolated linearly at the foot
/// of the update on the upwind edge. `vertex_signal` is #V × dim (vertices of `positions`).
/// Returns #landmarks × #V values, +inf where the geodesic distance is infinite. Rows are
/// computed in parallel; the result does not depend on the thread count.
std::vector<double> geodesic_signal_distances(const std::vector<Vec3d>& positions, const std::vector<Face>& tris,
                                              const std::vector<int>& landmarks, const std::vector<double>& geo_rows,
                                              const std::vector<double>& vertex_signal, int dim);

/// Replaces the geodesic landmark rows of `geo` (an embedding of chart g) by the combined
/// distance of eq. 6, d = β·d_geo/avg_geo + (1 − β)·d_sig/avg_sig, scaled by avg_geo so it
/// keeps units of length, and recomputes the spectral embedding (double centring, top
/// eigenpairs, placement) from them. d_sig is geodesic_signal_distances (the signal change
/// along the geodesic paths); avg_* are the means over all landmark rows. The graph cut reads
/// the same rows, so it sees the combined distance too. `vertex_signal` is #V(parent) × dim.
/// Returns `geo` unchanged when β ≥ 1 or the signal is constant over the chart.
Embedding combined_embedding(const ChartGeometry& g, const Embedding& geo,
                             const std::vector<double>& vertex_signal, int dim, double beta,
                             int max_dimensions = 10);

}  // namespace isochart::detail
