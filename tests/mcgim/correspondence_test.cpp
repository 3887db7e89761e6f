#include "mcgim/correspondence.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "mcgim/mcgim.h"
#include "synthetic_atlases.h"

using namespace mcgim;
using isochart::Vec2d;
using isochart::Vec3d;

namespace {

LevelOptions keep_layout(int res) {
  LevelOptions o;
  o.width = o.height = res;
  o.repack = false;
  return o;
}

}  // namespace

TEST_CASE("normal shooting between concentric spheres lands radially", "[mcgim][correspondence]") {
  // Fine level on the unit sphere, coarse level on a sphere of radius 1.1: the line along the
  // normal of a fine sample meets the coarse remesh about 0.1 further out, in the same direction.
  const Level fine = build_level(mcgim_test::sphere_atlas(32, 64, 1.0), keep_layout(96));
  const Level coarse = build_level(mcgim_test::sphere_atlas(32, 64, 1.1), keep_layout(48));
  const std::vector<Correspondence> c = shoot_normals(fine.image, coarse.image, coarse.remesh);
  REQUIRE(c.size() == fine.image.chart.size());
  int defined = 0, hits = 0, radial = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!fine.image.defined(static_cast<int>(i))) {
      CHECK(c[i].face == -1);
      continue;
    }
    ++defined;
    REQUIRE(c[i].face >= 0);
    hits += c[i].hit;
    const Vec3d p = fine.image.positions[i];
    const Vec3d q = c[i].point;
    const double angle = std::acos(std::min(1.0, dot(normalized(p), normalized(q))));
    if (std::abs(norm(q) - 1.1) < 0.01 && angle < 0.01 && std::abs(c[i].distance - 0.1) < 0.012) ++radial;
    // The landing point is where the barycentric coordinates say on the coarse face, and the
    // image coordinates fall in the coarse image, on the face's chart.
    const auto& f = coarse.remesh.mesh.faces[c[i].face];
    const Vec3d b = c[i].barycentric;
    const Vec3d r = coarse.remesh.mesh.positions[f[0]] * b.x + coarse.remesh.mesh.positions[f[1]] * b.y +
                    coarse.remesh.mesh.positions[f[2]] * b.z;
    CHECK(norm(r - q) < 1e-9);
    CHECK(c[i].image_xy.x >= 0);
    CHECK(c[i].image_xy.x <= coarse.image.width);
    CHECK(c[i].image_xy.y >= 0);
    CHECK(c[i].image_xy.y <= coarse.image.height);
    CHECK(c[i].chart == coarse.remesh.mesh.face_groups[c[i].face]);
  }
  CHECK(defined == fine.stats.defined_samples);
  CHECK(hits == defined);
  CHECK(radial >= 0.99 * defined);
}

TEST_CASE("a pyramid links every level to the next coarser one", "[mcgim][correspondence]") {
  PyramidOptions o;
  o.sizes = {{32, 32}, {96, 96}, {64, 64}};
  o.level.repack = false;
  const std::vector<Level> levels = build_pyramid(mcgim_test::sphere_atlas(24, 48), o);
  REQUIRE(levels.size() == 3);
  CHECK(levels[0].stats.width == 96);
  CHECK(levels[1].stats.width == 64);
  CHECK(levels[2].stats.width == 32);
  CHECK(levels[2].coarser.empty());
  for (int l = 0; l < 2; ++l) {
    const Level& lv = levels[l];
    REQUIRE(lv.coarser.size() == lv.image.chart.size());
    int linked = 0;
    for (std::size_t i = 0; i < lv.coarser.size(); ++i)
      if (lv.image.defined(static_cast<int>(i))) linked += lv.coarser[i].face >= 0;
    CHECK(linked == lv.stats.defined_samples);
    CHECK(lv.stats.topology.closed());
  }
}
