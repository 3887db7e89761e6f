#pragma once
// Internal: the combined geodesic/signal distance of Iso-charts §7 (eq. 6) in a chart's
// landmark embedding.

#include <vector>

#include "chart.h"
#include "isochart/embedding.h"

namespace isochart::detail {

/// Replaces the geodesic landmark rows of `geo` (an embedding of chart g) by the combined
/// distance of eq. 6, d = β·d_geo/avg_geo + (1 − β)·d_sig/avg_sig, scaled by avg_geo so it
/// keeps units of length, and recomputes the spectral embedding (double centring, top
/// eigenpairs, placement) from them. d_sig is the sum of signal differences |f(a) − f(b)| over
/// the edges of the path of least signal change (Dijkstra); avg_* are the means over all
/// landmark rows. `vertex_signal` is #V(parent) × dim. Returns `geo` unchanged when β ≥ 1 or
/// the signal is constant over the chart.
Embedding combined_embedding(const ChartGeometry& g, const Embedding& geo,
                             const std::vector<double>& vertex_signal, int dim, double beta,
                             int max_dimensions = 10);

}  // namespace isochart::detail
