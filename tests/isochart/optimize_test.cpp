#include "isochart/optimize.h"

#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>

using namespace isochart;

namespace {

// A grid over [-1,1]² lifted onto a bump z = h·exp(-(x²+y²)/w), with the planar projection as
// its initial parameterization: valid (no flips) but stretched on the bump's flanks.
struct Patch {
  std::vector<Vec3d> positions;
  std::vector<Face> faces;
  std::vector<Vec2d> uv;
};

Patch bump_patch(int n, double h) {
  Patch p;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = -1 + 2.0 * i / n, y = -1 + 2.0 * j / n;
      p.positions.push_back({x, y, h * std::exp(-(x * x + y * y) / 0.3)});
      p.uv.push_back({x, y});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      p.faces.push_back({a, b, d});
      p.faces.push_back({a, d, c});
    }
  return p;
}

}  // namespace

TEST_CASE("stretch optimization reduces L2 and Linf without flips", "[optimize]") {
  Patch p = bump_patch(24, 1.5);
  OptimizeOptions o;
  o.seed = 7;
  const OptimizeResult r = optimize_stretch(p.positions, p.faces, p.uv, o);
  INFO("L2 " << r.before.l2 << " -> " << r.after.l2 << ", Linf " << r.before.linf << " -> " << r.after.linf);
  CHECK(r.before.flipped == 0);
  CHECK(r.after.flipped == 0);
  CHECK(r.moves > 0);
  CHECK(r.after.l2 < r.before.l2 - 0.05);
  CHECK(r.after.linf < r.before.linf);
  CHECK(overlapping_uv_pairs([&] {
          std::vector<std::array<Vec2d, 3>> t;
          for (const auto& f : p.faces) t.push_back({p.uv[f[0]], p.uv[f[1]], p.uv[f[2]]});
          return t;
        }()).empty());
}

TEST_CASE("a cancelled optimization stops without moving anything", "[optimize]") {
  Patch p = bump_patch(24, 1.5);
  const std::vector<Vec2d> start = p.uv;
  std::atomic<bool> cancel{true};
  OptimizeOptions o;
  o.cancel = &cancel;
  const OptimizeResult r = optimize_stretch(p.positions, p.faces, p.uv, o);
  CHECK(r.moves == 0);
  CHECK(p.uv == start);
  // The same options without the flag set optimize as usual.
  cancel = false;
  CHECK(optimize_stretch(p.positions, p.faces, p.uv, o).moves > 0);
}

TEST_CASE("stretch optimization is deterministic for a seed", "[optimize]") {
  Patch a = bump_patch(12, 0.7), b = bump_patch(12, 0.7);
  OptimizeOptions o;
  o.seed = 3;
  optimize_stretch(a.positions, a.faces, a.uv, o);
  optimize_stretch(b.positions, b.faces, b.uv, o);
  CHECK(a.uv == b.uv);
}

TEST_CASE("an isometric parameterization is left essentially unchanged", "[optimize]") {
  Patch p = bump_patch(10, 0.0);  // flat: the projection is already an isometry
  const OptimizeResult r = optimize_stretch(p.positions, p.faces, p.uv);
  CHECK(std::abs(r.after.l2 - 1.0) < 1e-9);
  CHECK(std::abs(r.after.linf - 1.0) < 1e-9);
}

TEST_CASE("a flipped parameterization is reported and not moved", "[optimize]") {
  Patch p = bump_patch(6, 0.5);
  std::swap(p.uv[8], p.uv[9]);
  const auto before = p.uv;
  const OptimizeResult r = optimize_stretch(p.positions, p.faces, p.uv);
  CHECK(r.after.flipped > 0);
  CHECK(p.uv == before);
}

TEST_CASE("untangle repairs a local fold-over", "[optimize]") {
  Patch p = bump_patch(10, 0.3);
  // Push one interior vertex across its neighbours: its ring folds over.
  const int v = 5 * 11 + 5;
  p.uv[v] = p.uv[v] + Vec2d{0.5, 0.3};
  int flipped = 0;
  for (const auto& f : p.faces) flipped += signed_area(p.uv[f[0]], p.uv[f[1]], p.uv[f[2]]) > 0 ? 0 : 1;
  REQUIRE(flipped > 0);
  CHECK(untangle(p.faces, p.uv) == 0);
  for (const auto& f : p.faces) CHECK(signed_area(p.uv[f[0]], p.uv[f[1]], p.uv[f[2]]) > 0);
}

TEST_CASE("optimization never makes the boundary cross itself", "[optimize]") {
  // A U: two fingers rising from a base with a narrow slot between them. In 3D the fingers are
  // 2.5 times wider than in the texture, so the isometric layout overlaps itself and lowering
  // stretch pushes the fingers into each other; the optimizer must stop at contact.
  Patch p;
  const int n = 10, slot = 2;  // cells per unit; slot width in cells
  const int w = 2 * n + slot;  // cells across
  std::vector<int> id((w + 1) * (2 * n + 1), -1);
  for (int j = 0; j <= 2 * n; ++j)
    for (int i = 0; i <= w; ++i) {
      if (j > n && i > n && i < n + slot) continue;
      const double x = double(i) / n, y = double(j) / n;
      const double right = double(n + slot) / n + 0.5;  // centre of the right finger
      const double x3 = y > 1 ? (i <= n ? 0.5 + (x - 0.5) * 2.5 : right + (x - right) * 2.5) : x;
      id[j * (w + 1) + i] = static_cast<int>(p.uv.size());
      p.positions.push_back({x3, y, 0});
      p.uv.push_back({x, y});
    }
  for (int j = 0; j < 2 * n; ++j)
    for (int i = 0; i < w; ++i) {
      if (j >= n && i >= n && i < n + slot) continue;  // the slot's cells
      const int a = id[j * (w + 1) + i], b = id[j * (w + 1) + i + 1];
      const int c = id[(j + 1) * (w + 1) + i], d = id[(j + 1) * (w + 1) + i + 1];
      p.faces.push_back({a, b, d});
      p.faces.push_back({a, d, c});
    }
  auto tris = [&] {
    std::vector<std::array<Vec2d, 3>> t;
    for (const auto& f : p.faces) t.push_back({p.uv[f[0]], p.uv[f[1]], p.uv[f[2]]});
    return t;
  };
  REQUIRE(overlapping_uv_pairs(tris()).empty());
  OptimizeOptions o;
  o.passes = 30;
  const OptimizeResult r = optimize_stretch(p.positions, p.faces, p.uv, o);
  CHECK(r.after.flipped == 0);
  CHECK(r.after.l2 < r.before.l2);
  CHECK(overlapping_uv_pairs(tris()).empty());
}

TEST_CASE("a caller's topology gives the same optimization and untangling", "[optimize]") {
  Patch a = bump_patch(16, 1.2), b = bump_patch(16, 1.2);
  const Topology topo(b.faces, static_cast<int>(b.uv.size()));
  // A fold for untangle: one interior vertex pushed across its neighbours.
  a.uv[8 * 17 + 8] = b.uv[8 * 17 + 8] = {0.4, 0.05};
  REQUIRE(untangle(a.faces, a.uv) == 0);
  REQUIRE(untangle(b.faces, b.uv, topo) == 0);
  OptimizeOptions o;
  o.seed = 11;
  o.vertex_l2_threshold = 1.05;  // the ordering filter is on, as in the atlas
  const OptimizeResult ra = optimize_stretch(a.positions, a.faces, a.uv, o);
  const OptimizeResult rb = optimize_stretch(b.positions, b.faces, b.uv, o, topo);
  CHECK(ra.moves > 0);
  CHECK(ra.moves == rb.moves);
  CHECK(ra.sweeps == rb.sweeps);
  for (size_t v = 0; v < a.uv.size(); ++v) {
    INFO("vertex " << v);
    CHECK(a.uv[v].x == b.uv[v].x);
    CHECK(a.uv[v].y == b.uv[v].y);
  }
}
