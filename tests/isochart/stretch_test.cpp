#include "isochart/stretch.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace isochart;

namespace {

// A unit right triangle pair forming a square, mapped by uv = A * (x, y).
Mesh square_with_map(double a11, double a12, double a21, double a22) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  for (const auto& p : m.positions) m.uvs.push_back({a11 * p.x + a12 * p.y, a21 * p.x + a22 * p.y});
  m.face_uvs = m.faces;
  return m;
}

}  // namespace

TEST_CASE("identity map has stretch 1", "[stretch]") {
  const StretchStats s = measure_stretch(square_with_map(1, 0, 0, 1));
  CHECK(s.l2 == Approx(1.0).epsilon(1e-12));
  CHECK(s.linf == Approx(1.0).epsilon(1e-12));
  CHECK(s.flipped == 0);
}

TEST_CASE("stretch is invariant under uniform texture scaling", "[stretch]") {
  for (double scale : {1e-3, 0.5, 7.0, 1e4}) {
    const StretchStats s = measure_stretch(square_with_map(scale, 0, 0, scale));
    CHECK(std::abs(s.l2 - 1.0) < 1e-9);
    CHECK(std::abs(s.linf - 1.0) < 1e-9);
  }
}

TEST_CASE("known affine map gives the analytic stretch", "[stretch]") {
  // uv = diag(2, 1/2) * xy: area preserved, texture→surface singular values 1/2 and 2.
  const StretchStats s = measure_stretch(square_with_map(2, 0, 0, 0.5));
  CHECK(std::abs(s.l2 - std::sqrt((4 + 0.25) / 2)) < 1e-9);
  CHECK(std::abs(s.linf - 2.0) < 1e-9);  // max(Γ = 2, 1/γ = 2)
  // uv = diag(3, 1): normalized by sqrt(3), singular values become sqrt(3)/3 and sqrt(3).
  const StretchStats t = measure_stretch(square_with_map(3, 0, 0, 1));
  const double g1 = std::sqrt(3.0) / 3, g2 = std::sqrt(3.0);
  CHECK(std::abs(t.l2 - std::sqrt((g1 * g1 + g2 * g2) / 2)) < 1e-9);
  CHECK(std::abs(t.linf - std::max(g2, 1 / g1)) < 1e-9);
  // A rotation is isometric.
  const double c = std::cos(0.3), sn = std::sin(0.3);
  const StretchStats r = measure_stretch(square_with_map(c, -sn, sn, c));
  CHECK(std::abs(r.l2 - 1.0) < 1e-9);
  CHECK(std::abs(r.linf - 1.0) < 1e-9);
}

TEST_CASE("a mirrored map counts as flipped", "[stretch]") {
  const StretchStats s = measure_stretch(square_with_map(-1, 0, 0, 1));
  CHECK(s.flipped == 2);
  CHECK(std::isinf(s.l2));
}

TEST_CASE("exact UV overlap test", "[stretch][overlap]") {
  using T = std::array<Vec2d, 3>;
  const T a{Vec2d{0, 0}, Vec2d{1, 0}, Vec2d{0, 1}};
  SECTION("sharing an edge is not an overlap") {
    const T b{Vec2d{1, 0}, Vec2d{1, 1}, Vec2d{0, 1}};
    CHECK(overlapping_uv_pairs({a, b}).empty());
  }
  SECTION("touching at a vertex is not an overlap") {
    const T b{Vec2d{1, 0}, Vec2d{2, 0}, Vec2d{1, 1}};
    CHECK(overlapping_uv_pairs({a, b}).empty());
  }
  SECTION("an identical copy overlaps") { CHECK(overlapping_uv_pairs({a, a}).size() == 1); }
  SECTION("a triangle inside another overlaps") {
    const T b{Vec2d{0.1, 0.1}, Vec2d{0.2, 0.1}, Vec2d{0.1, 0.2}};
    CHECK(overlapping_uv_pairs({a, b}).size() == 1);
  }
  SECTION("crossing edges overlap") {
    const T b{Vec2d{0.4, -0.5}, Vec2d{0.6, -0.5}, Vec2d{0.5, 0.5}};
    CHECK(overlapping_uv_pairs({a, b}).size() == 1);
  }
  SECTION("a folded neighbour on the same side overlaps") {
    const T b{Vec2d{1, 0}, Vec2d{0, 1}, Vec2d{0.2, 0.2}};
    CHECK(overlapping_uv_pairs({a, b}).size() == 1);
  }
  SECTION("a gap of one ulp is not an overlap") {
    const double x = std::nextafter(1.0, 2.0);
    const T b{Vec2d{x, 0}, Vec2d{x + 1, 0}, Vec2d{x, 1}};
    CHECK(overlapping_uv_pairs({a, b}).empty());
  }
}
