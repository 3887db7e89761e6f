#include "partition.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "isochart/embedding.h"

namespace isochart::detail {

const char* split_kind_name(SplitKind k) {
  switch (k) {
    case SplitKind::General: return "general";
    case SplitKind::Tubular: return "tubular";
    case SplitKind::Binary: return "binary";
    case SplitKind::Fallback: return "fallback";
  }
  return "?";
}

namespace {

// Geodesic distance from landmark row `row` to vertex v.
inline double row_distance(const Embedding& e, int nv, int row, int v) {
  return e.landmark_distances[static_cast<size_t>(row) * nv + v];
}

// Grows parts around representative landmarks (rows): each face joins the representative with
// the smallest mean distance to its three corners (§5.1 step 6).
std::vector<int> grow(const ChartGeometry& g, const Embedding& e, const std::vector<int>& rep_rows) {
  const int nv = g.num_vertices();
  std::vector<int> labels(g.num_faces(), 0);
  for (int f = 0; f < g.num_faces(); ++f) {
    double best = std::numeric_limits<double>::infinity();
    for (int r = 0; r < static_cast<int>(rep_rows.size()); ++r) {
      const Face& t = g.tris[f];
      const double d = row_distance(e, nv, rep_rows[r], t[0]) + row_distance(e, nv, rep_rows[r], t[1]) +
                       row_distance(e, nv, rep_rows[r], t[2]);
      if (d < best) {
        best = d;
        labels[f] = r;
      }
    }
  }
  return labels;
}

}  // namespace

std::vector<int> spectral_partition(const ChartGeometry& g, const Embedding& e, const SplitOptions& o,
                                    SplitKind& kind, int& num_labels) {
  num_labels = 0;
  const int d = e.dimensions;
  const int q = static_cast<int>(e.landmarks.size());
  if (d < 1 || q < 2) return {};
  auto lam = [&](int i) { return i <= d ? e.eigenvalues[i - 1] : 0.0; };  // 1-based
  const double total = e.eigenvalue_sum > 0 ? e.eigenvalue_sum : std::accumulate(e.eigenvalues.begin(), e.eigenvalues.end(), 0.0);
  const double top3 = total > 0 ? (lam(1) + lam(2) + lam(3)) / total : 1.0;

  std::vector<int> coords;  // 0-based embedding coordinates whose extremes become representatives
  if (o.allow_general && top3 < 0.9 && d >= 4) {
    // §5.1 step 2: n ≥ 3 at the knee, where successive eigenvalues drop fastest.
    int n = 3;
    double best_ratio = -1;
    for (int i = 3; i < d; ++i) {
      const double r = lam(i + 1) > 0 ? lam(i) / lam(i + 1) : std::numeric_limits<double>::infinity();
      if (r > best_ratio) {
        best_ratio = r;
        n = i;
      }
    }
    for (int j = 0; j < n; ++j) coords.push_back(j);
    kind = SplitKind::General;
  } else if (d >= 4 && lam(2) > 0 && lam(3) > 0 && lam(4) > 0 && lam(1) / lam(2) > 3 &&
             lam(2) / lam(3) < 2 && lam(3) / lam(4) > 3) {
    // §5.3: a tube; its third coordinate is the shorter cyclic axis and cuts it lengthwise.
    coords.push_back(2);
    kind = SplitKind::Tubular;
  } else {
    coords.push_back(0);
    kind = SplitKind::Binary;
  }

  // §5.1 step 4–5: max and min landmark along each coordinate, dropping near-duplicates.
  const int nv = g.num_vertices();
  std::vector<int> reps;
  for (int j : coords) {
    int lo = 0, hi = 0;
    for (int r = 0; r < q; ++r) {
      const double c = e.coordinates[static_cast<size_t>(e.landmarks[r]) * d + j];
      if (c < e.coordinates[static_cast<size_t>(e.landmarks[lo]) * d + j]) lo = r;
      if (c > e.coordinates[static_cast<size_t>(e.landmarks[hi]) * d + j]) hi = r;
    }
    for (int cand : {hi, lo}) {
      bool keep = true;
      for (int r : reps)
        if (row_distance(e, nv, r, e.landmarks[cand]) < o.min_rep_distance || r == cand) keep = false;
      if (keep) reps.push_back(cand);
    }
  }
  if (reps.size() < 2) return {};
  num_labels = static_cast<int>(reps.size());
  return grow(g, e, reps);
}

std::vector<int> fallback_partition(const ChartGeometry& g, const Topology& topo, const Embedding& e,
                                    int& num_labels) {
  const int nv = g.num_vertices();
  const int q = static_cast<int>(e.landmarks.size());
  num_labels = 2;
  if (q >= 2) {
    int a = 0, b = 1;
    double best = -1;
    for (int r = 0; r < q; ++r)
      for (int s = r + 1; s < q; ++s) {
        const double dd = row_distance(e, nv, r, e.landmarks[s]);
        if (std::isfinite(dd) && dd > best) {
          best = dd;
          a = r;
          b = s;
        }
      }
    std::vector<int> labels = grow(g, e, {a, b});
    if (std::count(labels.begin(), labels.end(), 0) > 0 && std::count(labels.begin(), labels.end(), 1) > 0)
      return labels;
  }
  // Last resort: breadth-first order from face 0, first half against the rest.
  std::vector<int> order{0}, seen(g.num_faces(), 0);
  seen[0] = 1;
  for (size_t i = 0; i < order.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int nb = topo.opposite_face(order[i], k);
      if (nb >= 0 && !seen[nb]) {
        seen[nb] = 1;
        order.push_back(nb);
      }
    }
  std::vector<int> labels(g.num_faces(), 1);
  for (size_t i = 0; i < std::max<size_t>(1, order.size() / 2); ++i) labels[order[i]] = 0;
  return labels;
}

int smooth_labels(const Topology& topo, std::vector<int>& labels, int passes) {
  const int nf = static_cast<int>(labels.size());
  int total = 0;
  for (int pass = 0; pass < passes; ++pass) {
    // Decide on the labels of the previous sweep so the result does not depend on face order.
    std::vector<int> next = labels;
    int changed = 0;
    for (int f = 0; f < nf; ++f) {
      int nb[3], other = -1, count = 0;
      for (int k = 0; k < 3; ++k) nb[k] = topo.opposite_face(f, k);
      for (int k = 0; k < 3; ++k) {
        if (nb[k] < 0 || labels[nb[k]] == labels[f]) continue;
        if (other < 0) other = labels[nb[k]];
        if (labels[nb[k]] == other) ++count;
      }
      if (count >= 2) {
        next[f] = other;
        ++changed;
      }
    }
    labels.swap(next);
    total += changed;
    if (changed == 0) break;
  }
  return total;
}

int make_labels_connected(const Topology& topo, const std::vector<Vec3d>& positions, std::vector<int>& labels) {
  const int nf = static_cast<int>(labels.size());
  for (int iteration = 0; iteration < 32; ++iteration) {
    // Components of equal label.
    std::vector<int> comp(nf, -1), comp_label, comp_size;
    for (int f = 0; f < nf; ++f) {
      if (comp[f] >= 0) continue;
      const int c = static_cast<int>(comp_size.size());
      comp_size.push_back(0);
      comp_label.push_back(labels[f]);
      std::vector<int> stack{f};
      comp[f] = c;
      while (!stack.empty()) {
        const int x = stack.back();
        stack.pop_back();
        ++comp_size[c];
        for (int k = 0; k < 3; ++k) {
          const int nb = topo.opposite_face(x, k);
          if (nb >= 0 && comp[nb] < 0 && labels[nb] == labels[x]) {
            comp[nb] = c;
            stack.push_back(nb);
          }
        }
      }
    }
    // The largest component of each label keeps it (ties: the earliest).
    std::vector<int> main_comp;
    for (int c = 0; c < static_cast<int>(comp_size.size()); ++c) {
      const int l = comp_label[c];
      if (l >= static_cast<int>(main_comp.size())) main_comp.resize(l + 1, -1);
      if (main_comp[l] < 0 || comp_size[c] > comp_size[main_comp[l]]) main_comp[l] = c;
    }
    std::vector<std::vector<int>> comp_faces(comp_size.size());
    for (int f = 0; f < nf; ++f)
      if (main_comp[comp_label[comp[f]]] != comp[f]) comp_faces[comp[f]].push_back(f);
    bool changed = false;
    for (int c = 0; c < static_cast<int>(comp_size.size()); ++c) {
      if (main_comp[comp_label[c]] == c) continue;
      // Stray piece: give it to the neighbouring label with the longest shared boundary.
      std::vector<std::pair<int, double>> shared;
      for (int f : comp_faces[c]) {
        for (int k = 0; k < 3; ++k) {
          const int nb = topo.opposite_face(f, k);
          if (nb < 0 || comp[nb] == c) continue;
          const auto& ed = topo.edge(topo.face_edge(f, k));
          const double len = norm(positions[ed.v0] - positions[ed.v1]);
          auto it = std::find_if(shared.begin(), shared.end(), [&](const auto& p) { return p.first == labels[nb]; });
          if (it == shared.end())
            shared.emplace_back(labels[nb], len);
          else
            it->second += len;
        }
      }
      if (shared.empty()) continue;  // a separate component of the chart: it stays on its own
      std::sort(shared.begin(), shared.end(), [](const auto& a, const auto& b) {
        return a.second != b.second ? a.second > b.second : a.first < b.first;
      });
      const int target = shared[0].first;
      if (target == comp_label[c]) continue;
      for (int f : comp_faces[c]) labels[f] = target;
      changed = true;
    }
    if (!changed) break;
  }
  // Renumber by first face so labels are compact and in a stable order.
  std::vector<int> remap;
  int m = 0;
  for (int f = 0; f < nf; ++f) {
    const int l = labels[f];
    if (l >= static_cast<int>(remap.size())) remap.resize(l + 1, -1);
    if (remap[l] < 0) remap[l] = m++;
  }
  for (int& l : labels) l = remap[l];
  return m;
}

}  // namespace isochart::detail
