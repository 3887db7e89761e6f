#include "mcgim/psnr.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "isochart/error.h"
#include "isochart/io.h"
#include "synthetic_atlases.h"

using namespace mcgim;

namespace {

// The unit square [0,1]² at height z as an n×n grid of quads.
isochart::Mesh square(int n, double z) {
  isochart::Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back({double(i) / n, double(j) / n, z});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      m.faces.push_back({a, a + 1, a + n + 2});
      m.faces.push_back({a, a + n + 2, a + n + 1});
    }
  return m;
}

}  // namespace

TEST_CASE("PSNR of a mesh against itself is at least 150 dB", "[mcgim][psnr]") {
  const isochart::Mesh m = mcgim_test::sphere_atlas(16, 32);
  DistanceOptions o;
  o.samples = 20000;
  const DistanceResult r = measure_distance(m, m, o);
  // Rounding (about 1e-17 of the diagonal) read as "332 dB"; the surfaces are the same.
  CHECK(std::isinf(r.psnr));
  CHECK(std::isinf(r.psnr_mean));
  CHECK(r.hausdorff < 1e-12);
  CHECK(r.samples_a == 20000);
  CHECK(r.samples_b == 20000);
  // bunny_lowres against itself measured 1.07e-17 of rounding: "327 dB".
  const isochart::Mesh bunny =
      isochart::load_mesh(std::string(ISOCHARTS_SHARED_DATA) + "/meshes/bunny_lowres.off").mesh;
  const DistanceResult b = measure_distance(bunny, bunny, o);
  CHECK(std::isinf(b.psnr));
  CHECK(b.rms_ab < 1e-14 * b.diagonal);
}

TEST_CASE("PSNR of an offset copy matches the analytic value", "[mcgim][psnr]") {
  // Every point of one square is exactly δ from the other (its closest point is straight
  // above or below, as both cover the same footprint): both RMS distances and the Hausdorff
  // distance are δ, the peak is the diagonal √2 of A's bounding box.
  const double delta = 1e-3;
  const isochart::Mesh a = square(10, 0.0), b = square(7, delta);
  DistanceOptions o;
  o.samples = 30000;
  const DistanceResult r = measure_distance(a, b, o);
  const double expected = 20 * std::log10(std::sqrt(2.0) / delta);
  CHECK(std::abs(r.psnr - expected) < 0.1);
  CHECK(std::abs(r.psnr_mean - expected) < 0.1);
  CHECK(r.rms_ab == Approx(delta).epsilon(1e-6));
  CHECK(r.rms_ba == Approx(delta).epsilon(1e-6));
  CHECK(r.hausdorff == Approx(delta).epsilon(1e-6));
  CHECK(r.diagonal == Approx(std::sqrt(2.0)));
}

TEST_CASE("PSNR uses the worse one-sided RMS as its headline", "[mcgim][psnr]") {
  // A half square is within the full one (distance 0 from it), but half of the full square is
  // 0.25 on average away from the half: rms_ab = 0, rms_ba > 0.
  isochart::Mesh half = square(4, 0.0);
  for (auto& p : half.positions) p.x *= 0.5;
  const isochart::Mesh full = square(4, 0.0);
  DistanceOptions o;
  o.samples = 20000;
  const DistanceResult r = measure_distance(half, full, o);
  CHECK(r.rms_ab < 1e-12);
  CHECK(r.rms_ba > 0.1);
  CHECK(r.psnr == Approx(psnr_db(r.diagonal, r.rms_ba)));
  CHECK(r.psnr_mean == Approx(psnr_db(r.diagonal, r.rms_ba / 2)));
  CHECK(r.hausdorff == Approx(0.5).margin(0.01));
}

TEST_CASE("distance sampling is deterministic for a seed", "[mcgim][psnr]") {
  const isochart::Mesh a = mcgim_test::torus_atlas(12, 8), b = mcgim_test::torus_atlas(10, 6);
  DistanceOptions o;
  o.samples = 5000;
  const DistanceResult r1 = measure_distance(a, b, o), r2 = measure_distance(a, b, o);
  CHECK(r1.rms_ab == r2.rms_ab);
  CHECK(r1.rms_ba == r2.rms_ba);
  CHECK(r1.hausdorff == r2.hausdorff);
  o.seed = 7;
  const DistanceResult r3 = measure_distance(a, b, o);
  CHECK(r3.rms_ab != r1.rms_ab);
  CHECK(r3.rms_ab == Approx(r1.rms_ab).epsilon(0.1));
  o.samples = 0;
  CHECK_THROWS_AS(measure_distance(a, b, o), isochart::InputError);
}
