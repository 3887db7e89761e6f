#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "aabb.h"
#include "closest_point.h"
#include "isochart/error.h"
#include "mcgim/psnr.h"
#include "isochart/rng.h"

namespace mcgim {

namespace {

using detail::AabbPrimitive;
using detail::Kernel;
using detail::Point3;
using detail::Triangle3;
using detail::TriangleIterator;
using isochart::Mesh;
using isochart::Vec3d;

// Area-weighted points on a mesh: face f receives floor(C_f·n/A + u) − floor(C_{f−1}·n/A + u)
// points (systematic sampling with one random offset u, so the counts follow the areas
// exactly up to one), each uniform inside its face.
std::vector<Vec3d> sample_surface(const Mesh& m, long long n, std::uint64_t seed, const char* which) {
  std::vector<double> areas(m.num_faces());
  double total = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    const auto& v = m.faces[f];
    areas[f] = isochart::triangle_area(m.positions[v[0]], m.positions[v[1]], m.positions[v[2]]);
    total += areas[f];
  }
  if (!(total > 0)) throw isochart::InputError("", std::string("mesh ") + which + " has no face of positive area");
  isochart::Rng rng(seed);
  const double u = rng.uniform();
  std::vector<Vec3d> pts;
  pts.reserve(static_cast<std::size_t>(n));
  double cum = 0;
  long long before = static_cast<long long>(std::floor(u));
  for (int f = 0; f < m.num_faces(); ++f) {
    cum += areas[f];
    const long long upto = static_cast<long long>(std::floor(cum / total * static_cast<double>(n) + u));
    const auto& v = m.faces[f];
    for (long long k = before; k < upto; ++k) {
      const double s = std::sqrt(rng.uniform()), t = rng.uniform();
      pts.push_back(m.positions[v[0]] * (1 - s) + m.positions[v[1]] * (s * (1 - t)) +
                    m.positions[v[2]] * (s * t));
    }
    before = std::max(before, upto);
  }
  return pts;
}

// Squared distance from q to a box [lo, hi] (0 inside), per axis.
inline double axis_gap2(double q, double lo, double hi) {
  const double d = q < lo ? lo - q : (q > hi ? q - hi : 0.0);
  return d * d;
}
inline double box_distance2(const Point3& q, const CGAL::Bbox_3& b) {
  return axis_gap2(q.x(), b.xmin(), b.xmax()) + axis_gap2(q.y(), b.ymin(), b.ymax()) +
         axis_gap2(q.z(), b.zmin(), b.zmax());
}
inline double triangle_box_distance2(const Point3& q, const Triangle3& t) {
  const Point3 &a = t[0], &b = t[1], &c = t[2];
  return axis_gap2(q.x(), std::min({a.x(), b.x(), c.x()}), std::max({a.x(), b.x(), c.x()})) +
         axis_gap2(q.y(), std::min({a.y(), b.y(), c.y()}), std::max({a.y(), b.y(), c.y()})) +
         axis_gap2(q.z(), std::min({a.z(), b.z(), c.z()}), std::max({a.z(), b.z(), c.z()}));
}

// Closest-point search for AABB_tree::traversal_with_priority: nearer boxes first, and a
// triangle is projected only when its own box is nearer than the best point so far (CGAL's
// own closest-point traits project every triangle of a visited leaf, in tree order).
struct NearestFirst {
  using Priority = double;
  Point3 best;
  double best2;
  TriangleIterator best_id;

  bool go_further() const { return true; }
  void intersection(const Point3& q, const AabbPrimitive& pr) {
    const Triangle3& t = pr.datum();
    if (triangle_box_distance2(q, t) > best2) return;
    const Point3 c = Kernel::Construct_projected_point_3()(t, q);
    const double d2 = CGAL::squared_distance(q, c);
    // On a tie the later triangle wins, as in CGAL's own search.
    if (d2 < best2 || (d2 == best2 && c != best)) {
      best = c;
      best2 = d2;
      best_id = pr.id();
    }
  }
  template <class Node>
  bool do_intersect(const Point3& q, const Node& node) const {
    return box_distance2(q, node.bbox()) < best2;
  }
  template <class Node>
  std::pair<bool, double> do_intersect_with_priority(const Point3& q, const Node& node) const {
    const double d2 = box_distance2(q, node.bbox());
    return {d2 < best2, -d2};
  }
};

// The closest point of `set` to q, from a start (best, best2, best_id) that is a point of the
// surface, or from none (best2 infinite).
NearestFirst nearest_point(const detail::TriangleSet& set, const Point3& q, NearestFirst start) {
  set.tree.traversal_with_priority(q, start);
  return start;
}

// Squared distances from `pts` to the surface, in parallel; the caller reduces in order.
std::vector<double> distances2(const std::vector<Vec3d>& pts, const detail::TriangleSet& target,
                               const isochart::Progress& progress, double f0, double f1) {
  std::vector<double> d2(pts.size());
  const std::size_t chunk = 16384;
  const std::size_t chunks = (pts.size() + chunk - 1) / chunk;
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    const std::size_t end = std::min(pts.size(), (c + 1) * chunk);
    // Consecutive points lie close together (sample_surface goes face by face), so each
    // search starts from the previous point's answer.
    NearestFirst prev{detail::to_point(pts[c * chunk]), std::numeric_limits<double>::infinity(),
                      target.triangles.cbegin()};
    for (std::size_t i = c * chunk; i < end; ++i) {
      const Point3 q = detail::to_point(pts[i]);
      NearestFirst start = prev;
      if (i > c * chunk) start.best2 = CGAL::squared_distance(q, prev.best);
      prev = nearest_point(target, q, start);
      d2[i] = prev.best2;
    }
    const std::size_t n = ++done;
    isochart::report(progress, isochart::Stage::Distance, f0 + (f1 - f0) * static_cast<double>(n) / chunks);
  });
  return d2;
}

}  // namespace

namespace detail {

struct ClosestPoints::Impl {
  explicit Impl(const Mesh& m) : set(m, false) {}
  TriangleSet set;
};

ClosestPoints::ClosestPoints(const Mesh& mesh) : impl_(std::make_unique<Impl>(mesh)) {}
ClosestPoints::~ClosestPoints() = default;
bool ClosestPoints::empty() const { return impl_->set.empty(); }

ClosestPoints::Hit ClosestPoints::closest(const Vec3d& p) const {
  const TriangleSet& set = impl_->set;
  const Point3 q = to_point(p);
  // No start: the first triangle reached, nearest box first, sets the bound.
  const NearestFirst hit =
      nearest_point(set, q, {q, std::numeric_limits<double>::infinity(), set.triangles.cbegin()});
  return {set.face_of(hit.best_id), to_vec(hit.best)};
}

ClosestPoints::Hit ClosestPoints::closest(const Vec3d& p, const Hit& near) const {
  const TriangleSet& set = impl_->set;
  const int t = set.triangle_index(near.face);
  if (t < 0) return closest(p);
  const Point3 q = to_point(p);
  const NearestFirst hit = nearest_point(
      set, q,
      {to_point(near.point), CGAL::squared_distance(q, to_point(near.point)), set.triangles.cbegin() + t});
  return {set.face_of(hit.best_id), to_vec(hit.best)};
}

ClosestPoints::Hit ClosestPoints::point_at(int f, const Vec3d& b) const {
  const TriangleSet& set = impl_->set;
  const int t = set.triangle_index(f);
  if (t < 0) return {};
  const Triangle3& tri = set.triangles[t];
  return {f, to_vec(tri[0]) * b.x + to_vec(tri[1]) * b.y + to_vec(tri[2]) * b.z};
}

Vec3d barycentric_of(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d v0 = b - a, v1 = c - a, v2 = p - a;
  const double d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1);
  const double d20 = dot(v2, v0), d21 = dot(v2, v1);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 0)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  double u = 1 - v - w;
  u = std::max(u, 0.0);
  v = std::max(v, 0.0);
  w = std::max(w, 0.0);
  const double s = u + v + w;
  return {u / s, v / s, w / s};
}

}  // namespace detail

double psnr_db(double peak, double d) {
  // Identical surfaces measure rounding, not distance (a mesh against itself: 2.6e-17 of the
  // diagonal, "332 dB"); below 1e-14 of the peak (280 dB) the surfaces are taken as equal.
  if (!(d > 1e-14 * peak)) return std::numeric_limits<double>::infinity();
  return 20.0 * std::log10(peak / d);
}

DistanceResult measure_distance(const Mesh& a, const Mesh& b, const DistanceOptions& o,
                                const isochart::Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (o.samples < 1) throw isochart::InputError("", "the number of distance samples must be at least 1");
  isochart::report(progress, isochart::Stage::Distance, 0.0);
  DistanceResult r;
  const std::vector<Vec3d> pa = sample_surface(a, o.samples, isochart::mix_seed(o.seed, 0xA), "A");
  const std::vector<Vec3d> pb = sample_surface(b, o.samples, isochart::mix_seed(o.seed, 0xB), "B");
  const detail::TriangleSet ta(a, false), tb(b, false);
  const std::vector<double> dab = distances2(pa, tb, progress, 0.0, 0.5);
  const std::vector<double> dba = distances2(pb, ta, progress, 0.5, 1.0);
  double sab = 0, sba = 0, mab = 0, mba = 0;
  for (double d : dab) {
    sab += d;
    mab = std::max(mab, d);
  }
  for (double d : dba) {
    sba += d;
    mba = std::max(mba, d);
  }
  r.samples_a = static_cast<long long>(pa.size());
  r.samples_b = static_cast<long long>(pb.size());
  r.rms_ab = std::sqrt(sab / static_cast<double>(pa.size()));
  r.rms_ba = std::sqrt(sba / static_cast<double>(pb.size()));
  r.max_ab = std::sqrt(mab);
  r.max_ba = std::sqrt(mba);
  r.hausdorff = std::max(r.max_ab, r.max_ba);
  r.diagonal = isochart::bounding_box(a).diagonal();
  r.psnr = psnr_db(r.diagonal, std::max(r.rms_ab, r.rms_ba));
  r.psnr_mean = psnr_db(r.diagonal, 0.5 * (r.rms_ab + r.rms_ba));
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace mcgim
