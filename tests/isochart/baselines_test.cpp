#include <catch2/catch.hpp>

#include <tbb/global_control.h>

#include "isochart/baselines.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/stretch.h"

using namespace isochart;

namespace {

std::vector<std::vector<int>> chart_faces(const Atlas& a) {
  std::vector<std::vector<int>> out(a.num_charts());
  for (std::size_t f = 0; f < a.face_chart.size(); ++f) out[a.face_chart[f]].push_back(static_cast<int>(f));
  return out;
}

void check_valid(const Mesh& mesh, const Atlas& a, double max_l2) {
  REQUIRE(a.face_chart.size() == mesh.faces.size());
  REQUIRE(a.num_charts() > 0);
  for (int c : a.face_chart) REQUIRE((c >= 0 && c < a.num_charts()));
  CHECK(a.stats.flipped == 0);
  CHECK(a.stats.overlapping_pairs == 0);
  const Mesh m = a.apply_to(mesh);
  // Packed into [0,1]².
  for (const Vec2d& p : m.uvs) {
    CHECK(p.x >= 0.0);
    CHECK(p.x <= 1.0);
    CHECK(p.y >= 0.0);
    CHECK(p.y <= 1.0);
  }
  const auto faces = chart_faces(a);
  for (int c = 0; c < a.num_charts(); ++c) {
    INFO("chart " << c << " with " << faces[c].size() << " faces");
    CHECK(is_disk(mesh, faces[c]));
    CHECK(a.charts[c].l2 <= max_l2 + 1e-12);
    CHECK(measure_stretch(m, faces[c]).flipped == 0);
  }
  // The atlas's own chart structure (uv continuity) is the chart partition.
  int n = 0;
  uv_charts(m, n);
  CHECK(n == a.num_charts());
}

}  // namespace

TEST_CASE("lscm baseline: valid disk charts on built-in meshes", "[baselines]") {
  for (const std::string name : {"sphere", "torus", "face"}) {
    INFO(name);
    const Mesh mesh = make_builtin(name);
    LscmOptions o;
    o.pack.width = o.pack.height = 512;
    const Atlas a = build_lscm_atlas(mesh, o);
    check_valid(mesh, a, o.max_l2);
    CHECK(a.stats.l2 <= o.max_l2);
    CHECK(a.stats.linf <= o.max_linf);
    if (name == "face") CHECK(a.num_charts() <= 4);  // a disk of low curvature needs few cuts
    if (name != "face") {
      CHECK(a.num_charts() >= 2);  // closed surfaces must be cut
      CHECK(a.stats.splits >= 1);
    }
  }
}

TEST_CASE("lscm baseline: tighter stretch bound gives more charts", "[baselines]") {
  const Mesh mesh = make_builtin("sphere");
  LscmOptions loose, tight;
  loose.max_l2 = 1.3;
  tight.max_l2 = 1.02;
  loose.pack.width = loose.pack.height = tight.pack.width = tight.pack.height = 512;
  const Atlas a = build_lscm_atlas(mesh, loose);
  const Atlas b = build_lscm_atlas(mesh, tight);
  CHECK(a.num_charts() < b.num_charts());
  CHECK(b.stats.l2 <= 1.02);
}

TEST_CASE("lscm+stretch keeps the charts, lowers L2 and stays valid", "[baselines]") {
  const Mesh mesh = make_builtin("torus");
  LscmOptions o;
  o.max_l2 = 1.3;
  o.pack.width = o.pack.height = 512;
  Atlas a = build_lscm_atlas(mesh, o);
  const Atlas before = a;
  OptimizeOptions oo;
  oo.max_linf = o.max_linf;
  optimize_atlas_stretch(mesh, a, oo, o.pack);
  CHECK(a.face_chart == before.face_chart);
  check_valid(mesh, a, o.max_l2);
  CHECK(a.stats.l2 < before.stats.l2);
  CHECK(a.stats.seconds.count("optimization") == 1);
}

TEST_CASE("lscm baseline is identical for any thread count", "[baselines]") {
  const Mesh mesh = make_builtin("torus");
  LscmOptions o;
  o.pack.width = o.pack.height = 256;
  Atlas a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = build_lscm_atlas(mesh, o);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    b = build_lscm_atlas(mesh, o);
  }
  CHECK(a.face_chart == b.face_chart);
  REQUIRE(a.uvs.size() == b.uvs.size());
  bool same = true;
  for (std::size_t i = 0; i < a.uvs.size(); ++i) same = same && a.uvs[i] == b.uvs[i];
  CHECK(same);
}

TEST_CASE("lscm baseline rejects bad options", "[baselines]") {
  const Mesh mesh = make_builtin("sphere");
  LscmOptions o;
  o.max_l2 = 0.5;
  CHECK_THROWS_AS(build_lscm_atlas(mesh, o), InputError);
  o = {};
  o.normal_lambda = 1.0;
  CHECK_THROWS_AS(build_lscm_atlas(mesh, o), InputError);
  CHECK_THROWS_AS(build_lscm_atlas(Mesh{}, LscmOptions{}), InputError);
}

TEST_CASE("atlas_from_uvs: charts from uv continuity, mirrored charts un-mirrored", "[baselines]") {
  const Mesh mesh = make_builtin("sphere");
  LscmOptions o;
  o.pack.width = o.pack.height = 512;
  const Atlas a = build_lscm_atlas(mesh, o);
  Mesh m = a.apply_to(mesh);
  m.face_groups.clear();
  // Mirror every texture coordinate, as UVAtlas's v flip does: all charts turn clockwise.
  for (Vec2d& p : m.uvs) p.y = 1.0 - p.y;
  REQUIRE(measure_stretch(m).flipped == m.num_faces());
  Atlas e = atlas_from_uvs(m);
  CHECK(e.num_charts() == a.num_charts());
  CHECK(measure_stretch(e.apply_to(mesh)).flipped == 0);
  for (int c = 0; c < e.num_charts(); ++c) CHECK(std::isfinite(e.charts[c].l2));
  PackOptions po;
  po.width = po.height = 512;
  pack_atlas(mesh, e, po);
  CHECK(e.stats.flipped == 0);
  CHECK(e.stats.overlapping_pairs == 0);
  CHECK(e.stats.l2 == Approx(a.stats.l2).epsilon(1e-6));

  Mesh bare = mesh;
  CHECK_THROWS_AS(atlas_from_uvs(bare), InputError);
}
