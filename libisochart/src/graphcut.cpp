// Chart boundary optimization by graph cut (Iso-charts §5.2, §5.2.1).

// GCC 12 reports -Wmaybe-uninitialized inside Boost.Graph's edge iterators once they are inlined
// here (a known false positive of boost::optional); it is not about our code.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <Eigen/Dense>
#include <algorithm>
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>
#include <cmath>
#include <limits>
#include <set>

#include "isochart/embedding.h"
#include "partition.h"

namespace isochart::detail {

namespace {

using Traits = boost::adjacency_list_traits<boost::vecS, boost::vecS, boost::directedS>;
using FlowGraph = boost::adjacency_list<
    boost::vecS, boost::vecS, boost::directedS,
    boost::property<boost::vertex_index_t, long,
                    boost::property<boost::vertex_color_t, boost::default_color_type,
                                    boost::property<boost::vertex_distance_t, long,
                                                    boost::property<boost::vertex_predecessor_t,
                                                                    Traits::edge_descriptor>>>>,
    boost::property<boost::edge_capacity_t, double,
                    boost::property<boost::edge_residual_capacity_t, double,
                                    boost::property<boost::edge_reverse_t, Traits::edge_descriptor>>>>;

void add_arc_pair(FlowGraph& g, int u, int v, double cap_uv, double cap_vu) {
  auto cap = boost::get(boost::edge_capacity, g);
  auto rev = boost::get(boost::edge_reverse, g);
  const auto e1 = boost::add_edge(u, v, g).first;
  const auto e2 = boost::add_edge(v, u, g).first;
  cap[e1] = cap_uv;
  cap[e2] = cap_vu;
  rev[e1] = e2;
  rev[e2] = e1;
}

// Per-vertex GDD of a 2-D landmark embedding built from the landmarks in `rows` (§5.2.1):
// classical MDS of their distance matrix, then every vertex in `verts` placed by the landmark
// formula from its distances to them. Returns false when fewer than 3 landmarks are usable.
bool side_gdd(const Embedding& e, int nv, const std::vector<int>& rows, const std::vector<int>& verts,
              std::vector<double>& gdd_out) {
  const int q = static_cast<int>(rows.size());
  if (q < 3) return false;
  Eigen::MatrixXd D(q, q);
  for (int i = 0; i < q; ++i)
    for (int j = 0; j < q; ++j) {
      const double d = e.landmark_distances[static_cast<size_t>(rows[i]) * nv + e.landmarks[rows[j]]];
      D(i, j) = d * d;
    }
  D = 0.5 * (D + D.transpose()).eval();  // fast marching is not exactly symmetric
  if (!D.allFinite()) return false;
  const Eigen::VectorXd mean = D.colwise().mean();
  Eigen::MatrixXd B = D;
  B.rowwise() -= mean.transpose();
  B.colwise() -= D.rowwise().mean();
  B.array() += D.mean();
  B *= -0.5;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(B);
  if (es.info() != Eigen::Success) return false;
  const int dims = 2;
  Eigen::MatrixXd Lpinv(dims, q);   // rows v_k / sqrt(λ_k)
  Eigen::MatrixXd Y(q, dims);       // landmark coordinates
  for (int k = 0; k < dims; ++k) {
    const double lambda = es.eigenvalues()[q - 1 - k];
    if (!(lambda > 0)) return false;
    const Eigen::VectorXd v = es.eigenvectors().col(q - 1 - k);
    Lpinv.row(k) = v.transpose() / std::sqrt(lambda);
    Y.col(k) = v * std::sqrt(lambda);
  }
  Eigen::VectorXd delta(q);
  for (int v : verts) {
    for (int i = 0; i < q; ++i) {
      const double d = e.landmark_distances[static_cast<size_t>(rows[i]) * nv + v];
      delta[i] = d * d;
    }
    const Eigen::Vector2d y = 0.5 * Lpinv * (mean - delta);
    double s = 0;
    for (int i = 0; i < q; ++i) {
      const double err = (Y.row(i).transpose() - y).norm() - std::sqrt(delta[i]);
      s += err * err;
    }
    gdd_out[v] = std::sqrt(s / (q - 1));
  }
  return true;
}

}  // namespace

void optimize_boundaries(const ChartGeometry& g, const Topology& topo, const Embedding& e,
                         std::vector<int>& labels, int num_labels, const SplitOptions& o) {
  const int nf = g.num_faces(), nv = g.num_vertices();
  // Face normals and areas, and the landmarks' own vertex ids for membership tests.
  std::vector<Vec3d> normal(nf);
  std::vector<double> area(nf);
  for (int f = 0; f < nf; ++f) {
    const Face& t = g.tris[f];
    const Vec3d c = cross(g.positions[t[1]] - g.positions[t[0]], g.positions[t[2]] - g.positions[t[0]]);
    area[f] = 0.5 * norm(c);
    normal[f] = normalized(c);
  }
  // Adjacent label pairs, in a fixed order.
  std::set<std::pair<int, int>> pairs;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int nb = topo.opposite_face(f, k);
      if (nb >= 0 && labels[nb] != labels[f])
        pairs.insert({std::min(labels[f], labels[nb]), std::max(labels[f], labels[nb])});
    }
  (void)num_labels;

  std::vector<int> level(nf);
  std::vector<double> gdd_a(nv), gdd_b(nv);
  for (const auto& [la, lb] : pairs) {
    // Medial region C: breadth-first bands on both sides of the A|B boundary until they hold
    // medial_fraction of the pair's area; each side keeps a fixed core.
    double area_side[2] = {0, 0};
    std::vector<int> frontier;
    std::fill(level.begin(), level.end(), -1);
    for (int f = 0; f < nf; ++f) {
      if (labels[f] != la && labels[f] != lb) continue;
      area_side[labels[f] == la ? 0 : 1] += area[f];
      for (int k = 0; k < 3; ++k) {
        const int nb = topo.opposite_face(f, k);
        if (nb >= 0 && labels[nb] != labels[f] && (labels[nb] == la || labels[nb] == lb)) {
          if (level[f] < 0) {
            level[f] = 0;
            frontier.push_back(f);
          }
        }
      }
    }
    if (frontier.empty()) continue;
    const double target = o.medial_fraction * (area_side[0] + area_side[1]);
    double in_c[2] = {0, 0};
    std::vector<int> medial;
    std::vector<char> in_medial(nf, 0);
    const double cap_fraction = 0.7;
    for (int depth = 0; !frontier.empty(); ++depth) {
      std::vector<int> next;
      for (int f : frontier) {
        const int side = labels[f] == la ? 0 : 1;
        if (in_c[0] + in_c[1] >= target) break;
        if (in_c[side] + area[f] > cap_fraction * area_side[side]) continue;
        in_medial[f] = 1;
        medial.push_back(f);
        in_c[side] += area[f];
        for (int k = 0; k < 3; ++k) {
          const int nb = topo.opposite_face(f, k);
          if (nb >= 0 && level[nb] < 0 && labels[nb] == labels[f]) {
            level[nb] = depth + 1;
            next.push_back(nb);
          }
        }
      }
      if (in_c[0] + in_c[1] >= target) break;
      frontier.swap(next);
    }
    if (medial.empty()) continue;

    // GDD under each side's landmark embedding (§5.2.1): landmarks in the fixed core of a side.
    std::vector<char> vertex_side(nv, 0);  // bit 0: touches fixed A, bit 1: fixed B, bit 2: medial
    for (int f = 0; f < nf; ++f) {
      if (labels[f] != la && labels[f] != lb) continue;
      const int bit = in_medial[f] ? 4 : (labels[f] == la ? 1 : 2);
      for (int k = 0; k < 3; ++k) vertex_side[g.tris[f][k]] |= bit;
    }
    std::vector<int> rows_a, rows_b, medial_verts;
    for (int r = 0; r < static_cast<int>(e.landmarks.size()); ++r) {
      const int v = e.landmarks[r];
      if (vertex_side[v] == 1) rows_a.push_back(r);
      if (vertex_side[v] == 2) rows_b.push_back(r);
    }
    for (int v = 0; v < nv; ++v)
      if (vertex_side[v] & 4) medial_verts.push_back(v);
    const bool have_distortion = o.alpha < 1 && side_gdd(e, nv, rows_a, medial_verts, gdd_a) &&
                                 side_gdd(e, nv, rows_b, medial_verts, gdd_b);
    const double alpha = have_distortion ? o.alpha : 1.0;
    auto face_gdd_diff = [&](int f) {
      const Face& t = g.tris[f];
      double s = 0;
      for (int k = 0; k < 3; ++k) s += gdd_a[t[k]] - gdd_b[t[k]];
      return s / 3;
    };

    // Capacities (eqs. 2–5) on every edge touching the medial region.
    struct Arc {
      int f, nb;
      double d_ang, d_dist;
    };
    std::vector<Arc> arcs;
    double sum_ang = 0, sum_dist = 0;
    for (int f : medial)
      for (int k = 0; k < 3; ++k) {
        const int nb = topo.opposite_face(f, k);
        if (nb < 0 || (labels[nb] != la && labels[nb] != lb)) continue;
        if (in_medial[nb] && nb < f) continue;  // each medial–medial edge once
        Arc a{f, nb, 1 - dot(normal[f], normal[nb]), 0};
        if (have_distortion) {
          const double df = std::abs(face_gdd_diff(f));
          const double dn = in_medial[nb] ? std::abs(face_gdd_diff(nb)) : 0.0;
          a.d_dist = df + dn;
        }
        sum_ang += a.d_ang;
        sum_dist += a.d_dist;
        arcs.push_back(a);
      }
    const double avg_ang = arcs.empty() ? 1 : std::max(sum_ang / arcs.size(), 1e-12);
    // GDD differences are lengths: no absolute floor, or a mesh 1e-12 across loses them.
    const double avg_dist = sum_dist > 0 ? sum_dist / arcs.size() : 1;

    // Nodes: medial faces, then source (A core) and sink (B core).
    std::vector<int> node(nf, -1);
    for (int i = 0; i < static_cast<int>(medial.size()); ++i) node[medial[i]] = i;
    const int source = static_cast<int>(medial.size()), sink = source + 1;
    FlowGraph fg(sink + 1);
    for (const Arc& a : arcs) {
      const double c_ang = 1.0 / (1.0 + a.d_ang / avg_ang);
      const double c_dist = a.d_dist / avg_dist;
      const double cap = alpha * c_ang + (1 - alpha) * c_dist;
      const int u = node[a.f];
      if (in_medial[a.nb])
        add_arc_pair(fg, u, node[a.nb], cap, cap);
      else if (labels[a.nb] == la)
        add_arc_pair(fg, source, u, cap, 0);
      else
        add_arc_pair(fg, u, sink, cap, 0);
    }
    boost::boykov_kolmogorov_max_flow(fg, source, sink);
    auto color = boost::get(boost::vertex_color, fg);
    // Black vertices are on the source side of the minimum cut.
    int changed = 0;
    for (int f : medial) {
      const int l = color[node[f]] == boost::black_color ? la : lb;
      changed += l != labels[f];
      labels[f] = l;
    }
    (void)changed;
  }
}

}  // namespace isochart::detail
