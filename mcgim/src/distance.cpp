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

// Squared distances from `pts` to the surface, in parallel; the caller reduces in order.
std::vector<double> distances2(const std::vector<Vec3d>& pts, const detail::TriangleSet& target,
                               const isochart::Progress& progress, double f0, double f1) {
  std::vector<double> d2(pts.size());
  const std::size_t chunk = 16384;
  const std::size_t chunks = (pts.size() + chunk - 1) / chunk;
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    const std::size_t end = std::min(pts.size(), (c + 1) * chunk);
    for (std::size_t i = c * chunk; i < end; ++i)
      d2[i] = target.tree.squared_distance(detail::to_point(pts[i]));
    const std::size_t n = ++done;
    isochart::report(progress, isochart::Stage::Distance, f0 + (f1 - f0) * static_cast<double>(n) / chunks);
  });
  return d2;
}

}  // namespace

namespace detail {

struct ClosestPoints::Impl {
  explicit Impl(const Mesh& m) : set(m) {}
  TriangleSet set;
};

ClosestPoints::ClosestPoints(const Mesh& mesh) : impl_(std::make_unique<Impl>(mesh)) {}
ClosestPoints::~ClosestPoints() = default;
bool ClosestPoints::empty() const { return impl_->set.empty(); }

ClosestPoints::Hit ClosestPoints::closest(const Vec3d& p) const {
  const auto cp = impl_->set.tree.closest_point_and_primitive(to_point(p));
  return {impl_->set.face_of(cp.second), to_vec(cp.first)};
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
  const detail::TriangleSet ta(a), tb(b);
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
