// The combined geodesic/signal distance (Iso-charts §7, eq. 6) for spectral analysis and the
// graph cut of signal-specialized charts.

#include "signal_distance.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace isochart::detail {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Relative tolerance of "the update's ray crosses the upwind edge", as in fast marching.
constexpr double kInsideSlack = 1e-9;

// Per face, its corners laid out in its own plane (corner 0 at the origin, corner 1 on +x).
struct Layout {
  double x[3], y[3];
};

double distance_between(const double* fa, const double* fb, int dim) {
  double d2 = 0;
  for (int c = 0; c < dim; ++c) d2 += (fa[c] - fb[c]) * (fa[c] - fb[c]);
  return std::sqrt(d2);
}

}  // namespace

std::vector<double> geodesic_signal_distances(const std::vector<Vec3d>& positions, const std::vector<Face>& tris,
                                              const std::vector<int>& landmarks, const std::vector<double>& geo_rows,
                                              const std::vector<double>& vertex_signal, int dim) {
  const int nv = static_cast<int>(positions.size());
  const int nf = static_cast<int>(tris.size());
  const size_t stride = static_cast<size_t>(nv);
  const int q = static_cast<int>(landmarks.size());
  std::vector<double> out(static_cast<size_t>(q) * stride, kInf);
  if (nv == 0 || dim < 1 || geo_rows.size() != out.size() ||
      vertex_signal.size() != static_cast<size_t>(nv) * dim)
    return out;
  // Vertex → (face, corner), CSR.
  std::vector<int> off(nv + 1, 0), corner;
  for (const Face& t : tris)
    for (int k = 0; k < 3; ++k) ++off[t[k] + 1];
  for (int v = 0; v < nv; ++v) off[v + 1] += off[v];
  corner.resize(off[nv]);
  {
    std::vector<int> fill(off.begin(), off.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) corner[fill[tris[f][k]]++] = 3 * f + k;
  }
  std::vector<Layout> layout(nf);
  for (int f = 0; f < nf; ++f) {
    const Face& t = tris[f];
    const double l01 = norm(positions[t[1]] - positions[t[0]]);
    const double l02 = norm(positions[t[2]] - positions[t[0]]);
    const double l12 = norm(positions[t[2]] - positions[t[1]]);
    Layout& L = layout[f];
    L.x[0] = L.y[0] = 0;
    L.x[1] = l01;
    L.y[1] = 0;
    L.x[2] = l01 > 0 ? (l01 * l01 + l02 * l02 - l12 * l12) / (2 * l01) : 0;
    L.y[2] = std::sqrt(std::max(0.0, l02 * l02 - L.x[2] * L.x[2]));
  }
  const double* sig = vertex_signal.data();
  auto value = [&](int v) { return sig + static_cast<size_t>(v) * dim; };

  auto row_of = [&](int k) {
    const double* d = geo_rows.data() + k * stride;
    double* s = out.data() + k * stride;
    std::vector<std::pair<double, int>> order;
    order.reserve(stride);
    for (int v = 0; v < nv; ++v)
      if (std::isfinite(d[v])) order.emplace_back(d[v], v);
    std::sort(order.begin(), order.end());
    std::vector<char> done(stride, 0);
    std::vector<double> foot(static_cast<size_t>(dim));
    const int source = landmarks[k];
    // Returns false when no neighbour of c is visited yet.
    auto update = [&](int c) {
      // The update that best explains d(C): an edge from a visited neighbour A, d(A) + |AC|,
      // or a triangle (C, A, B) with A and B visited, whose virtual point source at distances
      // d(A), d(B) sees C through the edge AB (foot at A + t·(B − A)).
      double best = kInf;
      int fa = -1, fb = -1;
      double ft = 0;
      for (int i = off[c]; i < off[c + 1]; ++i) {
        const int f = corner[i] / 3, kc = corner[i] % 3;
        const int ka = (kc + 1) % 3, kb = (kc + 2) % 3;
        const int a = tris[f][ka], b = tris[f][kb];
        const Layout& L = layout[f];
        const double ax = L.x[ka], ay = L.y[ka];
        const double ex = L.x[kb] - ax, ey = L.y[kb] - ay;
        const double len = std::sqrt(ex * ex + ey * ey);
        const double rcx = L.x[kc] - ax, rcy = L.y[kc] - ay;
        const double lac = std::sqrt(rcx * rcx + rcy * rcy);
        if (done[a] && a != c && d[a] + lac < best) {
          best = d[a] + lac;
          fa = fb = a;
          ft = 0;
        }
        if (done[b] && b != c) {
          const double bx = L.x[kc] - L.x[kb], by = L.y[kc] - L.y[kb];
          const double lbc = std::sqrt(bx * bx + by * by);
          if (d[b] + lbc < best) {
            best = d[b] + lbc;
            fa = fb = b;
            ft = 0;
          }
        }
        if (!(done[a] && done[b]) || a == b || a == c || b == c || !(len > 0)) continue;
        // Frame: A = (0, 0), B = (len, 0), C = (cx, cy) below the axis, the source above.
        const double cx = (rcx * ex + rcy * ey) / len;
        const double cy = -std::abs(rcx * ey - rcy * ex) / len;
        if (!(cy < -1e-9 * len)) continue;
        const double da = d[a], db = d[b];
        const double sx = ((da - db) * (da + db) + len * len) / (2 * len);
        const double sy2 = (da - sx) * (da + sx);
        if (sy2 < 0) continue;
        const double sy = std::sqrt(sy2);
        const double num = cx * sy - sx * cy, span = len * (sy - cy);
        if (num < -kInsideSlack * span || num > (1 + kInsideSlack) * span) continue;
        const double cand = std::hypot(cx - sx, cy - sy);
        if (cand < best) {
          best = cand;
          fa = a;
          fb = b;
          ft = std::clamp(num / span, 0.0, 1.0);
        }
      }
      if (fa < 0) return false;
      const double* va = value(fa);
      const double* vb = value(fb);
      for (int j = 0; j < dim; ++j) foot[j] = (1 - ft) * va[j] + ft * vb[j];
      const double s_foot = (1 - ft) * s[fa] + ft * s[fb];
      s[c] = s_foot + distance_between(value(c), foot.data(), dim);
      done[c] = 1;
      return true;
    };
    // A landmark's entries in other landmarks' rows are the mean of both directions, so one
    // can come before all its neighbours: such vertices wait until the rest is visited.
    std::vector<int> waiting;
    for (const auto& [dc, c] : order) {
      if (c == source || dc == 0) {
        s[c] = 0;
        done[c] = 1;
      } else if (!update(c)) {
        waiting.push_back(c);
      }
    }
    // A waiting vertex can need another waiting one first (both next to a landmark reached
    // early): passes repeat while they make progress.
    while (!waiting.empty()) {
      std::vector<int> still;
      for (int c : waiting)
        if (!update(c)) still.push_back(c);
      if (still.size() == waiting.size()) break;
      waiting.swap(still);
    }
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, q, 1), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k != r.end(); ++k) row_of(k);
  });
  return out;
}

Embedding combined_embedding(const ChartGeometry& g, const Embedding& geo,
                             const std::vector<double>& vertex_signal, int dim, double beta,
                             int max_dimensions) {
  const int q = static_cast<int>(geo.landmarks.size());
  const int nv = g.num_vertices();
  if (beta >= 1 || q < 3 || geo.num_vertices != nv || dim < 1) return geo;
  // The chart's own copy of the signal (cut charts repeat parent vertices).
  std::vector<double> local(static_cast<size_t>(nv) * dim);
  for (int v = 0; v < nv; ++v)
    for (int c = 0; c < dim; ++c)
      local[static_cast<size_t>(v) * dim + c] = vertex_signal[static_cast<size_t>(g.vertex_parent[v]) * dim + c];
  bool varies = false;
  for (int v = 1; v < nv && !varies; ++v)
    for (int c = 0; c < dim; ++c)
      if (local[static_cast<size_t>(v) * dim + c] != local[c]) varies = true;
  if (!varies) return geo;
  const std::vector<double> sig =
      geodesic_signal_distances(g.positions, g.tris, geo.landmarks, geo.landmark_distances, local, dim);
  const size_t stride = static_cast<size_t>(nv);
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
  // The landmarks' own matrix must be complete for the spectral analysis; should the signal
  // distances miss one, the chart keeps its geometric embedding rather than failing.
  for (int k = 0; k < q; ++k)
    for (int j = 0; j < q; ++j)
      if (!std::isfinite(e.landmark_distances[k * stride + geo.landmarks[j]])) return geo;
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
