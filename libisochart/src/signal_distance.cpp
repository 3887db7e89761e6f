// The combined geodesic/signal distance (Iso-charts §7, eq. 6) for spectral analysis and the
// graph cut of signal-specialized charts.

#include "signal_distance.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace isochart::detail {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

Embedding combined_embedding(const ChartGeometry& g, const Embedding& geo,
                             const std::vector<double>& vertex_signal, int dim, double beta,
                             int max_dimensions) {
  const int q = static_cast<int>(geo.landmarks.size());
  const int nv = g.num_vertices();
  if (beta >= 1 || q < 3 || geo.num_vertices != nv || dim < 1) return geo;
  // Chart edges with their signal differences.
  std::vector<std::vector<std::pair<int, double>>> adj(nv);
  double sig_sum = 0;
  long long sig_count = 0;
  for (const Face& t : g.tris)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const double* fa = &vertex_signal[static_cast<size_t>(g.vertex_parent[a]) * dim];
      const double* fb = &vertex_signal[static_cast<size_t>(g.vertex_parent[b]) * dim];
      double d2 = 0;
      for (int c = 0; c < dim; ++c) d2 += (fa[c] - fb[c]) * (fa[c] - fb[c]);
      const double w = std::sqrt(d2);
      adj[a].emplace_back(b, w);
      adj[b].emplace_back(a, w);
      sig_sum += w;
      ++sig_count;
    }
  if (!(sig_sum > 0)) return geo;
  // Signal distance rows by Dijkstra (sequential: charts already run in parallel).
  const size_t stride = static_cast<size_t>(nv);
  std::vector<double> sig(static_cast<size_t>(q) * stride, kInf);
  using Item = std::pair<double, int>;
  for (int k = 0; k < q; ++k) {
    double* row = sig.data() + k * stride;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
    row[geo.landmarks[k]] = 0;
    heap.emplace(0.0, geo.landmarks[k]);
    while (!heap.empty()) {
      const auto [d, v] = heap.top();
      heap.pop();
      if (d > row[v]) continue;
      for (const auto& [w, c] : adj[v])
        if (d + c < row[w]) {
          row[w] = d + c;
          heap.emplace(row[w], w);
        }
    }
  }
  double geo_sum = 0, sig_total = 0;
  long long count = 0;
  for (size_t i = 0; i < sig.size(); ++i)
    if (std::isfinite(geo.landmark_distances[i]) && std::isfinite(sig[i])) {
      geo_sum += geo.landmark_distances[i];
      sig_total += sig[i];
      ++count;
    }
  if (count == 0 || !(sig_total > 0) || !(geo_sum > 0)) return geo;
  const double avg_geo = geo_sum / count, avg_sig = sig_total / count;
  Embedding e;
  e.num_vertices = nv;
  e.landmarks = geo.landmarks;
  e.landmark_distances.resize(sig.size());
  for (size_t i = 0; i < sig.size(); ++i) {
    const double dg = geo.landmark_distances[i];
    e.landmark_distances[i] = std::isfinite(dg) && std::isfinite(sig[i])
                                  ? beta * dg + (1 - beta) * sig[i] * (avg_geo / avg_sig)
                                  : kInf;
  }
  // Vertices with an infinite distance to some landmark stay at the origin, as the geometric
  // embedding leaves them.
  const auto reached = [&](int v) {
    for (int k = 0; k < q; ++k)
      if (!std::isfinite(e.landmark_distances[k * stride + v])) return false;
    return true;
  };
  embed_landmarks(e, max_dimensions, reached);
  if (e.dimensions < 2) return geo;
  return e;
}

}  // namespace isochart::detail
