#include "isochart/optimize.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "isochart/error.h"
#include "isochart/rng.h"

namespace isochart {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool cancelled(const OptimizeOptions& o) { return o.cancel && o.cancel->load(std::memory_order_relaxed); }

// The 3D triangle in its own orthonormal frame: q0 = (0,0), q1 = (x1,0), q2 = (x2,y2).
struct FlatTriangle {
  double x1, x2, y2;
  double area;  // 3D area
};

FlatTriangle flatten(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  FlatTriangle t{};
  const Vec3d e1 = b - a, e2 = c - a;
  const double l1 = norm(e1);
  t.area = 0.5 * norm(cross(e1, e2));
  if (l1 <= 0) return t;
  const Vec3d u = e1 / l1;
  t.x1 = l1;
  t.x2 = dot(e2, u);
  t.y2 = std::sqrt(std::max(squared_norm(e2) - t.x2 * t.x2, 0.0));
  return t;
}

// Metric tensor entries of the texture → surface map: a = Ss·Ss, b = Ss·St, c = St·St.
// Returns false for flipped or degenerate texture triangles.
inline bool metric(const FlatTriangle& q, const Vec2d& p0, const Vec2d& p1, const Vec2d& p2, double& a,
                   double& b, double& c, double& area2d, const std::array<double, 3>* g = nullptr,
                   double* trace = nullptr) {
  const double d = (p1.x - p0.x) * (p2.y - p0.y) - (p2.x - p0.x) * (p1.y - p0.y);
  area2d = 0.5 * d;
  if (!(d > 0)) return false;
  const double inv = 1.0 / d;
  // q0 = (0,0) drops out.
  const double ssx = (q.x1 * (p2.y - p0.y) + q.x2 * (p0.y - p1.y)) * inv;
  const double ssy = (q.y2 * (p0.y - p1.y)) * inv;
  const double stx = (q.x1 * (p0.x - p2.x) + q.x2 * (p1.x - p0.x)) * inv;
  const double sty = (q.y2 * (p1.x - p0.x)) * inv;
  a = ssx * ssx + ssy * ssy;
  b = ssx * stx + ssy * sty;
  c = stx * stx + sty * sty;
  // tr(Jᵀ G J) = tr(G J Jᵀ) for the signal metric G.
  if (trace)
    *trace = g ? (*g)[0] * (ssx * ssx + stx * stx) + 2 * (*g)[1] * (ssx * ssy + stx * sty) +
                     (*g)[2] * (ssy * ssy + sty * sty)
               : a + c;
  return true;
}

// The chart-wide constants of linf_above: k² and the squared bounds hi and lo.
struct LinfCut {
  double k2 = 1, hi = -1, lo = kInf;
  double r_hi = -kInf, r_lo = -kInf;  // 2·hi/k2 and 2·lo/k2, for the test without square roots
  LinfCut() = default;
  LinfCut(double k2_, double hi_, double lo_) : k2(k2_), hi(hi_), lo(lo_), r_hi(2 * hi_ / k2_), r_lo(2 * lo_ / k2_) {}
};

// Normalized max(Γ, 1/γ), given the tensor and k² = (UV area / 3D area) of the whole chart,
// where it can exceed `tau`, and 0 where it certainly does not (hi = tau²(1 − 1e−9),
// lo = (1 + 1e−9)/tau²): the optimizer only compares Linf with tau and uses values above it,
// and most triangles of a chart are far inside the bound, so their two square roots and a
// division (the hottest instructions of a sweep) are skipped without changing any decision.
inline double linf_above(double a, double b, double c, const LinfCut& t) {
  // First the test below without its square root: 0.5(a + c ± disc)·k2 against hi and lo is
  // disc against r1 and r2, compared squared. It only decides which values are certainly
  // below tau, so the rare rounding disagreement near hi or lo changes nothing either.
  const double disc2 = (a - c) * (a - c) + 4 * b * b;
  const double r1 = t.r_hi - (a + c), r2 = (a + c) - t.r_lo;
  if (r1 >= 0 && r2 >= 0 && disc2 <= r1 * r1 && disc2 <= r2 * r2) return 0.0;
  const double disc = std::sqrt(disc2);
  const double g2max = 0.5 * (a + c + disc) * t.k2;
  const double g2min = std::max(0.5 * (a + c - disc), 0.0) * t.k2;
  if (g2max <= t.hi && g2min >= t.lo) return 0.0;
  const double big = std::sqrt(g2max);
  const double shrink = g2min > 0 ? 1.0 / std::sqrt(g2min) : kInf;
  return std::max(big, shrink);
}

// atan2(y, x) within kRoughAtanError: atan on [0, 1] by the quadratic-corrected line of Rajan
// et al. (2006; measured maximum error 0.00151 rad), extended by the octant symmetries, which
// keep the error's size.
constexpr double kRoughAtanError = 0.0016;
inline double rough_atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double hi = std::max(ax, ay);
  if (!(hi > 0)) return 0.0;
  const double t = std::min(ax, ay) / hi;
  double a = M_PI / 4 * t - t * (t - 1) * (0.2447 + 0.0663 * t);
  if (ay > ax) a = M_PI / 2 - a;
  if (x < 0) a = M_PI - a;
  return y < 0 ? -a : a;
}

class Optimizer {
 public:
  Optimizer(const std::vector<Vec3d>& positions, const std::vector<Face>& faces, std::vector<Vec2d>& uv,
            const OptimizeOptions& o, const Topology& topology)
      : faces_(faces), uv_(uv), o_(o), rng_(o.seed), topo_(topology) {
    const int nf = static_cast<int>(faces.size());
    flat_.resize(nf);
    for (int f = 0; f < nf; ++f)
      flat_[f] = flatten(positions[faces[f][0]], positions[faces[f][1]], positions[faces[f][2]]);
    area3_ = 0;
    for (const auto& t : flat_) area3_ += t.area;
    marea_ = area3_;
    if (!o.face_metric.empty()) {
      marea_ = 0;
      for (int f = 0; f < nf; ++f) {
        const auto& g = o.face_metric[f];
        marea_ += flat_[f].area * std::sqrt(std::max(g[0] * g[2] - g[1] * g[1], 0.0));
      }
    }
    tau_ = o.linf_margin * o.max_linf;
    if (tau_ > 0 && std::isfinite(tau_)) {
      tau_hi_ = tau_ * tau_ * (1 - 1e-9);
      tau_lo_ = (1 + 1e-9) / (tau_ * tau_);
    }
    init_boundary();
    recompute_sums();
  }

  bool valid() const { return valid_; }

  double current_l2() const { return marea_ > 0 ? std::sqrt(s1_ * s2_) / marea_ : 0.0; }

  OptimizeResult run() {
    OptimizeResult r;
    double last_l2 = current_l2();
    for (int pass = 0; pass < o_.passes && valid_; ++pass) {
      // Worst vertices first (§6).
      std::vector<std::pair<double, int>> order;
      face_terms();
      for (int v = 0; v < static_cast<int>(uv_.size()); ++v) {
        if (!topo_.is_referenced(v)) continue;
        double l2, linf;
        ring_stretch(v, l2, linf);
        if (o_.vertex_l2_threshold > 0 && l2 <= o_.vertex_l2_threshold && linf <= tau_) continue;
        order.emplace_back(-(l2 + (linf > tau_ ? linf : 0.0)), v);
      }
      if (order.empty()) break;
      std::sort(order.begin(), order.end());
      long long moved = 0;
      for (const auto& [score, v] : order) {
        if (cancelled(o_)) return r;
        moved += optimize_vertex(v) ? 1 : 0;
      }
      r.moves += moved;
      ++r.sweeps;
      recompute_sums();  // keep the running sums free of drift
      if (moved == 0) break;
      // Gains shrink from sweep to sweep: a chart that would still miss the bound with the
      // last gain repeated every remaining sweep is rejected whatever happens next.
      const double l2 = current_l2();
      const int remaining = o_.passes - pass - 1;
      if (o_.give_up_l2 > 0 && remaining > 0 && l2 - remaining * std::max(last_l2 - l2, 0.0) > o_.give_up_l2) {
        r.gave_up = true;
        break;
      }
      last_l2 = l2;
    }
    return r;
  }

 private:
  void recompute_sums() {
    s1_ = s2_ = pen_ = 0;
    valid_ = true;
    const int nf = static_cast<int>(faces_.size());
    for (int f = 0; f < nf; ++f) {
      double a, b, c, ar, tr;
      const Face& F = faces_[f];
      if (!metric(flat_[f], uv_[F[0]], uv_[F[1]], uv_[F[2]], a, b, c, ar, face_g(f), &tr)) {
        valid_ = false;
        continue;
      }
      s2_ += ar;
      if (flat_[f].area > 0) s1_ += flat_[f].area * 0.5 * tr;
    }
    cut_ = LinfCut(area3_ > 0 ? s2_ / area3_ : 1.0, tau_hi_, tau_lo_);
    k2m_ = marea_ > 0 ? s2_ / marea_ : 1.0;
    // The penalty depends on the chart-wide normalization, so it needs k2 first.
    for (int f = 0; f < nf; ++f) {
      double a, b, c, ar;
      const Face& F = faces_[f];
      if (flat_[f].area <= 0 || !metric(flat_[f], uv_[F[0]], uv_[F[1]], uv_[F[2]], a, b, c, ar)) continue;
      const double li = linf_above(a, b, c, cut_);
      if (li > tau_) pen_ += flat_[f].area * (li - tau_) * (li - tau_);
    }
  }

  // Per-face terms of ring_stretch for the current layout: a sweep's ordering visits every face
  // from each of its three corners, so they are computed once per sweep.
  void face_terms() {
    const int nf = static_cast<int>(faces_.size());
    terms_.resize(nf);
    for (int f = 0; f < nf; ++f) {
      FaceTerm& t = terms_[f];
      t.state = FaceTerm::kSkip;
      if (flat_[f].area <= 0) continue;
      const Face& F = faces_[f];
      double a, b, c, ar, tr;
      if (!metric(flat_[f], uv_[F[0]], uv_[F[1]], uv_[F[2]], a, b, c, ar, face_g(f), &tr)) {
        t.state = FaceTerm::kFlipped;
        continue;
      }
      t.state = FaceTerm::kValid;
      t.num = flat_[f].area * 0.5 * tr * k2m_;
      t.den = flat_[f].area * metric_weight(f);
      t.linf = linf_above(a, b, c, cut_);
    }
  }

  // Normalized L2 and max Linf over the faces around v (from the terms of face_terms()).
  void ring_stretch(int v, double& l2, double& linf) const {
    double num = 0, den = 0;
    linf = 0;
    for (int f : topo_.vertex_faces(v)) {
      const FaceTerm& t = terms_[f];
      if (t.state == FaceTerm::kSkip) continue;
      if (t.state == FaceTerm::kFlipped) {
        linf = kInf;
        continue;
      }
      num += t.num;
      den += t.den;
      linf = std::max(linf, t.linf);
    }
    l2 = den > 0 ? std::sqrt(num / den) : 0;
  }

  // Objective change terms for vertex v at position x: returns ring sums of the L2 numerator, the
  // UV area and the Linf penalty; false when a ring triangle would flip.
  bool ring_terms(const Vec2d& x, double& s1, double& s2, double& pen) const {
    s1 = s2 = pen = 0;
    for (const RingFace& r : ring_) {
      const Vec2d p0 = r.is_v[0] ? x : r.p[0];
      const Vec2d p1 = r.is_v[1] ? x : r.p[1];
      const Vec2d p2 = r.is_v[2] ? x : r.p[2];
      double a, b, c, ar;
      if (r.flat.area <= 0) {
        if (signed_area(p0, p1, p2) <= 0) return false;
        s2 += signed_area(p0, p1, p2);
        continue;
      }
      double tr;
      if (!metric(r.flat, p0, p1, p2, a, b, c, ar, r.g, &tr)) return false;
      s1 += r.flat.area * 0.5 * tr;
      s2 += ar;
      const double li = linf_above(a, b, c, cut_);
      if (li > tau_) pen += r.flat.area * (li - tau_) * (li - tau_);
    }
    return true;
  }

  // The faces around v with their fixed corners, gathered once per vertex: a line search
  // evaluates the ring some hundred times while only v moves.
  void gather_ring(int v) {
    ring_.clear();
    for (int f : topo_.vertex_faces(v)) {
      const Face& F = faces_[f];
      RingFace r;
      r.flat = flat_[f];
      r.g = face_g(f);
      for (int k = 0; k < 3; ++k) {
        r.is_v[k] = F[k] == v;
        r.p[k] = uv_[F[k]];
      }
      ring_.push_back(r);
    }
  }

  // Global objective if the ring sums (s1, s2, pen) replaced the current ones (r1, r2, rpen).
  double objective(double s1, double s2, double pen, double r1, double r2, double rpen) const {
    const double S1 = s1_ - r1 + s1, S2 = s2_ - r2 + s2;
    return S1 * S2 / (marea_ * marea_) + o_.linf_weight * (pen_ - rpen + pen) / area3_;
  }

  const std::array<double, 3>* face_g(int f) const {
    return o_.face_metric.empty() ? nullptr : &o_.face_metric[f];
  }
  // Metric area per unit surface area of face f (1 without a signal metric).
  double metric_weight(int f) const {
    if (o_.face_metric.empty()) return 1.0;
    const auto& g = o_.face_metric[f];
    return std::sqrt(std::max(g[0] * g[2] - g[1] * g[1], 0.0));
  }

  // Extent [lo, hi] of the line x0 + t d keeping every ring triangle counter-clockwise.
  void kernel_segment(int v, const Vec2d& x0, const Vec2d& d, double& lo, double& hi) const {
    lo = -kInf;
    hi = kInf;
    double reach = 0;
    for (int f : topo_.vertex_faces(v)) {
      const Face& F = faces_[f];
      int k = F[0] == v ? 0 : (F[1] == v ? 1 : 2);
      const Vec2d& a = uv_[F[(k + 1) % 3]];
      const Vec2d& b = uv_[F[(k + 2) % 3]];
      reach = std::max({reach, norm(a - x0), norm(b - x0)});
      // v must stay left of a→b.
      const double c0 = cross(b - a, x0 - a);
      const double c1 = cross(b - a, d);
      if (c1 < 0)
        hi = std::min(hi, c0 / -c1);
      else if (c1 > 0)
        lo = std::max(lo, -c0 / c1);
    }
    // Boundary vertices can be unbounded in some directions: stay within the ring's reach.
    hi = std::min(hi, reach);
    lo = std::max(lo, -reach);
    lo *= o_.conservative;
    hi *= o_.conservative;
  }

  bool optimize_vertex(int v) {
    double r1, r2, rpen;
    const Vec2d x0 = uv_[v];
    gather_ring(v);
    if (!ring_terms(x0, r1, r2, rpen)) return false;
    const double f0 = objective(r1, r2, rpen, r1, r2, rpen);
    double best = f0;
    Vec2d best_x = x0;
    double bs1 = r1, bs2 = r2, bpen = rpen;
    double first_gain = 0;
    for (int attempt = 0; attempt < o_.tries; ++attempt) {
      const double theta = rng_.uniform() * 2 * M_PI;
      const Vec2d d{std::cos(theta), std::sin(theta)};
      double lo, hi;
      kernel_segment(v, best_x, d, lo, hi);
      if (!(hi > lo) || hi - lo < 1e-300) continue;
      // An evaluated point keeps its ring sums, so the winner needs no second evaluation.
      struct Point {
        double t, f, s1, s2, pen;
      };
      auto eval = [&](double t) {
        Point p{t, kInf, 0, 0, 0};
        if (ring_terms(best_x + d * t, p.s1, p.s2, p.pen) && boundary_ok(v, best_x + d * t))
          p.f = objective(p.s1, p.s2, p.pen, r1, r2, rpen);
        return p;
      };
      // Coarse samples, then golden-section refinement around the best one.
      constexpr int kSamples = 5;
      Point coarse[kSamples + 1];
      int bi = -1;
      for (int i = 0; i <= kSamples; ++i) {
        coarse[i] = eval(lo + (hi - lo) * i / kSamples);
        if (bi < 0 || coarse[i].f < coarse[bi].f) bi = i;
      }
      double a = coarse[std::max(bi - 1, 0)].t, b = coarse[std::min(bi + 1, kSamples)].t;
      constexpr double g = 0.6180339887498949;
      Point c = eval(b - g * (b - a)), e = eval(a + g * (b - a));
      for (int it = 0; it < 8; ++it) {
        if (c.f < e.f) {
          b = e.t;
          e = c;
          c = eval(b - g * (b - a));
        } else {
          a = c.t;
          c = e;
          e = eval(a + g * (b - a));
        }
      }
      Point won = c.f < e.f ? c : e;
      if (coarse[bi].f < won.f) won = coarse[bi];
      const double t = won.t, ft = won.f, s1 = won.s1, s2 = won.s2, pen = won.pen;
      const double prev = best;
      if (ft < best) {
        best = ft;
        best_x = best_x + d * t;
        bs1 = s1;
        bs2 = s2;
        bpen = pen;
      }
      // §6: stop once a direction no longer improves the vertex enough; the first useful
      // direction sets the scale of what "enough" means for this vertex.
      const double gain = prev - best;
      if (first_gain == 0) first_gain = gain;
      if (first_gain > 0 && gain < o_.min_improvement * first_gain) break;
    }
    if (best_x == x0 || !(best < f0)) return false;
    move_vertex(v, best_x);
    s1_ += bs1 - r1;
    s2_ += bs2 - r2;
    pen_ += bpen - rpen;
    return true;
  }

  // --- Boundary simplicity. With every triangle counter-clockwise, a simple boundary polygon
  // makes the map injective, so moves of boundary vertices must keep the boundary simple.

  void init_boundary() {
    const int nv = static_cast<int>(uv_.size());
    bprev_.assign(nv, -1);
    bnext_.assign(nv, -1);
    double len = 0;
    int count = 0;
    Vec2d lo = uv_.empty() ? Vec2d{} : uv_[0], hi = lo;
    for (const auto& loop : topo_.boundary_loops())
      for (size_t i = 0; i < loop.size(); ++i) {
        const int a = loop[i], b = loop[(i + 1) % loop.size()];
        bnext_[a] = b;
        bprev_[b] = a;
        len += norm(uv_[a] - uv_[b]);
        ++count;
      }
    for (const auto& p : uv_) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y)};
    }
    if (count == 0) return;
    cell_ = std::max(2 * len / count, 1e-300);
    margin_ = o_.boundary_clearance * len / count;
    const Vec2d pad = (hi - lo) * 0.5;
    grid_lo_ = lo - pad;
    grid_n_ = std::clamp(static_cast<int>((hi.x - lo.x + 2 * pad.x) / cell_) + 1, 1, 2048);
    grid_m_ = std::clamp(static_cast<int>((hi.y - lo.y + 2 * pad.y) / cell_) + 1, 1, 2048);
    grid_.assign(static_cast<size_t>(grid_n_) * grid_m_, {});
    for (int v = 0; v < nv; ++v)
      if (bnext_[v] >= 0) grid_edit(v, uv_[v], uv_[bnext_[v]], true);
    stamp_.assign(nv, 0);
  }

  int cell_x(double x) const { return std::clamp(static_cast<int>((x - grid_lo_.x) / cell_), 0, grid_n_ - 1); }
  int cell_y(double y) const { return std::clamp(static_cast<int>((y - grid_lo_.y) / cell_), 0, grid_m_ - 1); }

  // Adds or removes boundary edge (v → bnext_[v]) with endpoints a, b in every cell its box covers.
  void grid_edit(int v, const Vec2d& a, const Vec2d& b, bool add) {
    for (int i = cell_x(std::min(a.x, b.x)); i <= cell_x(std::max(a.x, b.x)); ++i)
      for (int j = cell_y(std::min(a.y, b.y)); j <= cell_y(std::max(a.y, b.y)); ++j) {
        auto& c = grid_[static_cast<size_t>(j) * grid_n_ + i];
        if (add)
          c.push_back(v);
        else
          c.erase(std::find(c.begin(), c.end(), v));
      }
  }

  static bool segments_touch(const Vec2d& a, const Vec2d& b, const Vec2d& c, const Vec2d& d) {
    const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a);
    const double d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
    // Collinear or endpoint contacts count as touching: conservative, only refuses a move.
    auto on = [](const Vec2d& p, const Vec2d& q, const Vec2d& r, double o) {
      return o == 0 && std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
             r.y <= std::max(p.y, q.y);
    };
    return on(a, b, c, d1) || on(a, b, d, d2) || on(c, d, a, d3) || on(c, d, b, d4);
  }

  // Does segment (p → q) from boundary vertex `from` to `to` touch a boundary edge not incident
  // to either?
  // Squared distance from p to segment ab.
  static double point_segment2(const Vec2d& p, const Vec2d& a, const Vec2d& b) {
    const Vec2d d = b - a;
    const double l2 = squared_norm(d);
    const double t = l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0.0;
    return squared_norm(a + d * t - p);
  }
  // Squared distance between segments that do not touch: from the nearest endpoint.
  static double apart2(const Vec2d& a, const Vec2d& b, const Vec2d& c, const Vec2d& d) {
    return std::min(std::min(point_segment2(a, c, d), point_segment2(b, c, d)),
                    std::min(point_segment2(c, a, b), point_segment2(d, a, b)));
  }

  struct Nearby {
    bool crosses = false;  ///< an edge of v meets another boundary edge
    double clearance = 0;  ///< least distance to a boundary edge off p, v and n, up to margin_
  };
  // Boundary vertex v's two edges with v at x, against the boundary edges near them, in one
  // pass over the grid: whether they meet one (not counting the edges they share an end
  // with), and how close they come to those not incident to v or its boundary neighbours.
  Nearby nearby_boundary(int v, const Vec2d& x) {
    const int p = bprev_[v], n = bnext_[v];
    const Vec2d &a = uv_[p], &b = uv_[n];
    const double m = margin_;
    const double lo_x = std::min({a.x, b.x, x.x}), hi_x = std::max({a.x, b.x, x.x});
    const double lo_y = std::min({a.y, b.y, x.y}), hi_y = std::max({a.y, b.y, x.y});
    double best2 = m * m;
    ++stamp_id_;
    for (int i = cell_x(lo_x - m); i <= cell_x(hi_x + m); ++i)
      for (int j = cell_y(lo_y - m); j <= cell_y(hi_y + m); ++j)
        for (int e : grid_[static_cast<size_t>(j) * grid_n_ + i]) {
          if (stamp_[e] == stamp_id_) continue;
          stamp_[e] = stamp_id_;
          const int c = e, d = bnext_[e];
          const Vec2d &uc = uv_[c], &ud = uv_[d];
          const bool at_pv = c == p || c == v || d == p || d == v;
          const bool at_vn = c == v || c == n || d == v || d == n;
          if ((!at_pv && segments_touch(a, x, uc, ud)) || (!at_vn && segments_touch(x, b, uc, ud)))
            return {true, 0};
          if (m <= 0 || at_pv || at_vn) continue;
          if (std::min(uc.x, ud.x) > hi_x + m || std::max(uc.x, ud.x) < lo_x - m ||
              std::min(uc.y, ud.y) > hi_y + m || std::max(uc.y, ud.y) < lo_y - m)
            continue;
          best2 = std::min(best2, std::min(apart2(a, x, uc, ud), apart2(x, b, uc, ud)));
        }
    return {false, std::sqrt(best2)};
  }

  // Whether the triangle angles at vertex w, with vertex v placed at x, sum to kMaxAngle or more.
  bool angles_close_up(int w, int v, const Vec2d& x) const {
    constexpr double kMaxAngle = 2 * M_PI * (1 - 1e-9);
    auto corner = [&](int f, double& dt, double& cr) {
      const Face& F = faces_[f];
      const int k = F[0] == w ? 0 : (F[1] == w ? 1 : 2);
      auto at = [&](int u) { return u == v ? x : uv_[u]; };
      const Vec2d c = at(F[k]), a = at(F[(k + 1) % 3]) - c, b = at(F[(k + 2) % 3]) - c;
      dt = dot(a, b);
      cr = cross(a, b);
    };
    // First with an arc tangent good to 0.0016 rad: unless the sum comes within that of
    // kMaxAngle per corner the answer is known, and the exact arc tangents (a third of a run at
    // tight bounds, where charts are small and mostly boundary) are not needed.
    double rough = 0, slack = 0;
    for (int f : topo_.vertex_faces(w)) {
      double dt, cr;
      corner(f, dt, cr);
      rough += rough_atan2(cr, dt);
      slack += kRoughAtanError;
    }
    if (rough + slack < kMaxAngle) return false;
    if (rough - slack >= kMaxAngle) return true;
    double sum = 0;
    for (int f : topo_.vertex_faces(w)) {
      double dt, cr;
      corner(f, dt, cr);
      sum += std::atan2(cr, dt);
    }
    return sum >= kMaxAngle;
  }

  // Keeps the boundary simple when boundary vertex v moves to x (interior vertices always pass).
  bool boundary_ok(int v, const Vec2d& x) {
    if (bnext_[v] < 0) return true;
    const int p = bprev_[v], n = bnext_[v];
    if (angles_close_up(v, v, x) || angles_close_up(p, v, x) || angles_close_up(n, v, x)) return false;
    const Nearby moved = nearby_boundary(v, x);
    if (moved.crosses) return false;
    // A boundary that closes in on itself (a notch pinched shut) keeps the chart one-to-one
    // but puts far-apart surface points in the same texels: bilinear reads across the pinch
    // mixed normals from the two sides (creature: 80-94 % of the signal error from 0.01 % of
    // the area). Moves into that margin are refused unless they widen the gap.
    return !(moved.clearance < margin_ && moved.clearance < nearby_boundary(v, uv_[v]).clearance);
  }

  void move_vertex(int v, const Vec2d& x) {
    if (bnext_[v] >= 0 && !grid_.empty()) {
      grid_edit(v, uv_[v], uv_[bnext_[v]], false);
      grid_edit(bprev_[v], uv_[bprev_[v]], uv_[v], false);
      uv_[v] = x;
      grid_edit(v, uv_[v], uv_[bnext_[v]], true);
      grid_edit(bprev_[v], uv_[bprev_[v]], uv_[v], true);
    } else {
      uv_[v] = x;
    }
  }

  const std::vector<Face>& faces_;
  std::vector<Vec2d>& uv_;
  OptimizeOptions o_;
  Rng rng_;
  std::vector<FlatTriangle> flat_;
  const Topology& topo_;
  struct FaceTerm {
    enum State : unsigned char { kSkip, kFlipped, kValid } state = kSkip;
    double num = 0, den = 0, linf = 0;
  };
  std::vector<FaceTerm> terms_;
  struct RingFace {
    FlatTriangle flat;
    const std::array<double, 3>* g;
    Vec2d p[3];       // corner positions, v's own unused
    bool is_v[3];
  };
  std::vector<RingFace> ring_;
  double area3_ = 0, s1_ = 0, s2_ = 0, pen_ = 0, tau_ = 0;
  // Squared Linf bounds of linf_above: -1 and +inf (always exact) unless tau_ is positive.
  double tau_hi_ = -1, tau_lo_ = kInf;
  LinfCut cut_;  // k² follows the chart's UV area: rebuilt with the running sums
  double marea_ = 0, k2m_ = 1;  // metric area and UV area / metric area (signal metric)
  bool valid_ = true;
  std::vector<int> bprev_, bnext_;
  std::vector<std::vector<int>> grid_;
  std::vector<unsigned> stamp_;
  unsigned stamp_id_ = 0;
  Vec2d grid_lo_;
  double cell_ = 1;
  double margin_ = 0;
  int grid_n_ = 0, grid_m_ = 0;
};

// Sutherland–Hodgman clip of a convex polygon by the half-plane left of a→b.
std::vector<Vec2d> clip_left(const std::vector<Vec2d>& poly, const Vec2d& a, const Vec2d& b) {
  std::vector<Vec2d> out;
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec2d& p = poly[i];
    const Vec2d& q = poly[(i + 1) % n];
    const double sp = cross(b - a, p - a), sq = cross(b - a, q - a);
    if (sp >= 0) out.push_back(p);
    if ((sp >= 0) != (sq >= 0)) out.push_back(p + (q - p) * (sp / (sp - sq)));
  }
  return out;
}

}  // namespace

int untangle(const std::vector<Face>& faces, std::vector<Vec2d>& uv, int max_passes) {
  return untangle(faces, uv, Topology(faces, static_cast<int>(uv.size())), max_passes);
}

int untangle(const std::vector<Face>& faces, std::vector<Vec2d>& uv, const Topology& topo, int max_passes) {
  auto flipped = [&](int f) {
    const Face& t = faces[f];
    return !(signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) > 0);
  };
  int remaining = 0;
  for (int pass = 0; pass < max_passes; ++pass) {
    std::vector<int> verts;
    for (int f = 0; f < static_cast<int>(faces.size()); ++f)
      if (flipped(f))
        for (int k = 0; k < 3; ++k) verts.push_back(faces[f][k]);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    remaining = 0;
    for (int f = 0; f < static_cast<int>(faces.size()); ++f) remaining += flipped(f) ? 1 : 0;
    if (remaining == 0) return 0;
    for (int v : verts) {
      // Kernel: the points left of the far edge of every triangle around v.
      double lo_x = kInf, lo_y = kInf, hi_x = -kInf, hi_y = -kInf;
      Vec2d mean;
      int count = 0;
      for (int w : topo.vertex_neighbors(v)) {
        lo_x = std::min(lo_x, uv[w].x);
        hi_x = std::max(hi_x, uv[w].x);
        lo_y = std::min(lo_y, uv[w].y);
        hi_y = std::max(hi_y, uv[w].y);
        mean += uv[w];
        ++count;
      }
      if (count == 0) continue;
      mean /= count;
      const double pad = std::max(hi_x - lo_x, hi_y - lo_y);
      std::vector<Vec2d> poly = {{lo_x - pad, lo_y - pad}, {hi_x + pad, lo_y - pad}, {hi_x + pad, hi_y + pad},
                                 {lo_x - pad, hi_y + pad}};
      for (int f : topo.vertex_faces(v)) {
        const Face& t = faces[f];
        const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
        poly = clip_left(poly, uv[t[(k + 1) % 3]], uv[t[(k + 2) % 3]]);
        if (poly.size() < 3) break;
      }
      double area2 = 0;
      Vec2d c;
      for (size_t i = 0; poly.size() >= 3 && i < poly.size(); ++i) {
        const Vec2d& p = poly[i];
        const Vec2d& q = poly[(i + 1) % poly.size()];
        const double w = cross(p, q);
        area2 += w;
        c += (p + q) * w;
      }
      if (area2 > 1e-12 * pad * pad)
        uv[v] = c / (3 * area2);
      else if (!topo.is_boundary_vertex(v))
        uv[v] = mean;  // no kernel yet: smoothing lets the neighbours unfold first
    }
  }
  remaining = 0;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) remaining += flipped(f) ? 1 : 0;
  return remaining;
}

OptimizeResult optimize_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                                std::vector<Vec2d>& uv, const OptimizeOptions& options) {
  return optimize_stretch(positions, faces, uv, options, Topology(faces, static_cast<int>(uv.size())));
}

OptimizeResult optimize_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                                std::vector<Vec2d>& uv, const OptimizeOptions& options, const Topology& topology) {
  OptimizeResult r;
  if (!options.face_metric.empty() && options.face_metric.size() != faces.size())
    throw Error("optimize_stretch: face_metric has " + std::to_string(options.face_metric.size()) +
                " entries for " + std::to_string(faces.size()) + " faces");
  r.before = measure_stretch(positions, faces, uv);
  Optimizer opt(positions, faces, uv, options, topology);
  if (opt.valid()) {
    const OptimizeResult run = opt.run();
    r.moves = run.moves;
    r.sweeps = run.sweeps;
    r.gave_up = run.gave_up;
  }
  r.after = measure_stretch(positions, faces, uv);
  if (!r.gave_up && r.after.flipped == 0 && r.after.linf > options.max_linf && options.linf_repair_passes > 0 &&
      !cancelled(options)) {
    OptimizeOptions repair = options;
    repair.passes = options.linf_repair_passes;
    repair.linf_weight = 10 * options.linf_weight;
    repair.vertex_l2_threshold = std::numeric_limits<double>::infinity();  // Linf violators only
    repair.give_up_l2 = 0;
    repair.seed = options.seed + 1;
    Optimizer fix(positions, faces, uv, repair, topology);
    const OptimizeResult run = fix.run();
    r.moves += run.moves;
    r.sweeps += run.sweeps;
    r.after = measure_stretch(positions, faces, uv);
  }
  return r;
}

}  // namespace isochart
