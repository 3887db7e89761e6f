// The sample fit's closest-point search (internal to mcgim) against a brute-force scan.
#include "../../mcgim/src/closest_point.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "isochart/io.h"
#include "isochart/rng.h"

using isochart::Vec3d;

namespace {

// Squared distance from p to triangle abc, by the region test on the triangle's plane.
double triangle_distance2(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d n = cross(b - a, c - a);
  const double nn = squared_norm(n);
  const Vec3d q = p - n * (dot(p - a, n) / nn);  // onto the plane
  // Inside when q is on the inner side of all three edges.
  if (dot(cross(b - a, q - a), n) >= 0 && dot(cross(c - b, q - b), n) >= 0 &&
      dot(cross(a - c, q - c), n) >= 0)
    return squared_norm(p - q);
  auto segment2 = [&](const Vec3d& u, const Vec3d& v) {
    const Vec3d d = v - u;
    const double t = std::clamp(dot(p - u, d) / squared_norm(d), 0.0, 1.0);
    return squared_norm(u + d * t - p);
  };
  return std::min({segment2(a, b), segment2(b, c), segment2(c, a)});
}

}  // namespace

TEST_CASE("closest points from any start are the exact closest points", "[mcgim][closest]") {
  const isochart::Mesh m = isochart::load_mesh(ISOCHARTS_SHARED_DATA "/meshes/bunny_lowres.off").mesh;
  const mcgim::detail::ClosestPoints cp(m);
  REQUIRE_FALSE(cp.empty());
  Vec3d lo = m.positions[0], hi = lo;
  for (const Vec3d& p : m.positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double diag = norm(hi - lo);
  isochart::Rng rng(7);
  int checked = 0;
  for (int k = 0; k < 400; ++k) {
    // Near the surface (where the fit asks) and anywhere in a box twice the model's size.
    Vec3d p;
    if (k % 2 == 0) {
      const auto& f = m.faces[rng.below(m.faces.size())];
      const double u = rng.uniform(), v = rng.uniform() * (1 - u);
      p = m.positions[f[0]] * (1 - u - v) + m.positions[f[1]] * u + m.positions[f[2]] * v +
          Vec3d{rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5} * (0.02 * diag);
    } else {
      p = lo + Vec3d{(hi.x - lo.x) * (2 * rng.uniform() - 0.5), (hi.y - lo.y) * (2 * rng.uniform() - 0.5),
                     (hi.z - lo.z) * (2 * rng.uniform() - 0.5)};
    }
    double best2 = std::numeric_limits<double>::infinity();
    for (const auto& f : m.faces)
      best2 = std::min(best2, triangle_distance2(p, m.positions[f[0]], m.positions[f[1]], m.positions[f[2]]));
    // No start, a start on a random face (usually far), and a start at the answer's face.
    const int far_face = static_cast<int>(rng.below(m.faces.size()));
    const mcgim::detail::ClosestPoints::Hit plain = cp.closest(p);
    const mcgim::detail::ClosestPoints::Hit far = cp.closest(p, cp.point_at(far_face, {0.2, 0.3, 0.5}));
    const mcgim::detail::ClosestPoints::Hit near =
        cp.closest(p, cp.point_at(plain.face, {1.0 / 3, 1.0 / 3, 1.0 / 3}));
    for (const auto* h : {&plain, &far, &near}) {
      REQUIRE(h->face >= 0);
      CHECK(std::abs(squared_norm(h->point - p) - best2) <= 1e-9 * diag * diag);
      // The point lies on the face it names.
      const auto& f = m.faces[h->face];
      CHECK(triangle_distance2(h->point, m.positions[f[0]], m.positions[f[1]], m.positions[f[2]]) <=
            1e-18 * diag * diag);
    }
    ++checked;
  }
  CHECK(checked == 400);
  // A face of zero area or none is no start: the search still answers.
  CHECK(cp.closest(m.positions[0], {}).face >= 0);
}

TEST_CASE("a face of zero area is never a start or an answer of the closest-point search",
          "[mcgim][closest]") {
  // Two triangles of the unit square at z = 0, and a sliver with collinear corners above them.
  isochart::Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0.5}, {1, 0, 0.5}, {2, 0, 0.5}};
  m.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}};
  const mcgim::detail::ClosestPoints cp(m);
  CHECK(cp.point_at(2, {1.0 / 3, 1.0 / 3, 1.0 / 3}).face == -1);
  CHECK(cp.point_at(-1, {1.0 / 3, 1.0 / 3, 1.0 / 3}).face == -1);
  CHECK(cp.point_at(0, {1.0 / 3, 1.0 / 3, 1.0 / 3}).face == 0);
  // Right on the sliver: the answer is the square below it, from any start.
  const Vec3d p{0.5, 0.0, 0.5};
  for (const auto& start : {mcgim::detail::ClosestPoints::Hit{}, mcgim::detail::ClosestPoints::Hit{2, p},
                            cp.point_at(1, {0.2, 0.3, 0.5})}) {
    const auto h = cp.closest(p, start);
    CHECK(h.face == 0);
    CHECK(norm(h.point - Vec3d{0.5, 0.0, 0.0}) < 1e-12);
  }
}
