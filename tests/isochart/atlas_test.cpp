#include "isochart/atlas.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "geo_test_meshes.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/stretch.h"

using namespace isochart;

namespace {

// Everything an accepted atlas must satisfy, measured on the mesh with its final UVs.
void check_atlas(const Mesh& mesh, const Atlas& atlas, const AtlasOptions& o) {
  const Mesh uv_mesh = atlas.apply_to(mesh);
  REQUIRE(uv_mesh.face_uvs.size() == mesh.faces.size());
  for (const auto& uv : uv_mesh.uvs) {
    CHECK(uv.x >= 0);
    CHECK(uv.x <= 1);
    CHECK(uv.y >= 0);
    CHECK(uv.y <= 1);
  }
  // Stretch is that of the texture: in texels, not in [0,1]² (they differ when W ≠ H).
  Mesh m = uv_mesh;
  for (auto& uv : m.uvs) uv = {uv.x * o.pack.width, uv.y * o.pack.height};
  const StretchStats st = measure_stretch(m);
  CHECK(st.flipped == 0);
  CHECK(overlapping_uv_pairs(m).empty());
  CHECK(st.l2 <= o.max_l2 + 1e-9);
  CHECK(st.linf <= o.max_linf + 1e-9);
  CHECK(atlas.stats.l2 == Approx(st.l2).epsilon(1e-12));
  CHECK(atlas.stats.linf == Approx(st.linf).epsilon(1e-12));
  // Every chart is one disk-topology piece meeting both bounds on its own.
  for (int c = 0; c < atlas.num_charts(); ++c) {
    std::vector<int> faces;
    for (int f = 0; f < mesh.num_faces(); ++f)
      if (atlas.face_chart[f] == c) faces.push_back(f);
    REQUIRE(!faces.empty());
    const StretchStats cs = measure_stretch(m, faces);
    CHECK(cs.l2 <= o.max_l2 + 1e-9);
    CHECK(cs.linf <= o.max_linf + 1e-9);
  }
  int uv_charts_found = 0;
  uv_charts(m, uv_charts_found);
  CHECK(uv_charts_found == atlas.num_charts());
  CHECK(atlas.stats.flipped == 0);
  CHECK(atlas.stats.overlapping_pairs == 0);
  CHECK(atlas.stats.packing_ratio > 0.3);
}

}  // namespace

TEST_CASE("atlas of a sphere meets the stretch bounds", "[atlas]") {
  const Mesh sphere = make_builtin("sphere");
  AtlasOptions o;
  const Atlas a = build_atlas(sphere, o);
  INFO("charts " << a.num_charts() << " L2 " << a.stats.l2 << " Linf " << a.stats.linf);
  check_atlas(sphere, a, o);
  // A closed surface needs at least two charts; a sphere should not need many.
  CHECK(a.num_charts() >= 2);
  CHECK(a.num_charts() <= 8);
}

TEST_CASE("a non-square texture keeps the charts undistorted in texels", "[atlas]") {
  const Mesh sphere = make_builtin("sphere");
  AtlasOptions square, wide;
  wide.pack.width = 512;
  wide.pack.height = 128;
  const Atlas a = build_atlas(sphere, square), b = build_atlas(sphere, wide);
  check_atlas(sphere, b, wide);
  // Charting does not depend on the texture; packing only rotates, moves and scales
  // uniformly in texels, so the reported stretch is that of the square texture's atlas.
  CHECK(b.num_charts() == a.num_charts());
  CHECK(b.stats.l2 == Approx(a.stats.l2).epsilon(1e-9));
  CHECK(b.stats.linf == Approx(a.stats.linf).epsilon(1e-9));
  // In [0,1]² the same UVs are stretched 4:1 (what used to be reported).
  CHECK(measure_stretch(b.apply_to(sphere)).l2 > b.stats.l2 + 0.3);
}

TEST_CASE("atlas of an open disk patch is a single chart", "[atlas]") {
  const Mesh face = make_builtin("face");
  AtlasOptions o;
  const Atlas a = build_atlas(face, o);
  check_atlas(face, a, o);
  CHECK(a.num_charts() == 1);
}

TEST_CASE("a flat polygon filled with a fan of slivers is one isometric chart", "[atlas]") {
  // As CAD files fill a flat n-gon: every triangle from one corner. Geodesics on such slivers
  // are poor and their embedding split a 200-gon into 6 charts with Linf 3.6; a flat chart's
  // own plane is an exact layout.
  Mesh m;
  const int n = 200;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    // A tilted plane, its coordinates rounded to six decimals as a CAD export writes them.
    auto r6 = [](double x) { return std::round(x * 1e6) / 1e6; };
    m.positions.push_back({r6(std::cos(a)), r6(0.3 * std::cos(a) + 0.2 * std::sin(a)), r6(std::sin(a))});
  }
  for (int i = 1; i + 1 < n; ++i) m.faces.push_back({0, i, i + 1});
  AtlasOptions o;
  const Atlas a = build_atlas(m, o);
  check_atlas(m, a, o);
  CHECK(a.num_charts() == 1);
  CHECK(a.stats.l2 == Approx(1.0).epsilon(1e-6));
  CHECK(a.stats.linf == Approx(1.0).epsilon(1e-4));
}

TEST_CASE("a sliver triangle (height 1e-10 of its length) gets a chart with area", "[atlas]") {
  // The lone triangle's height came from sqrt(|e2|² − x2²), which cancels to 0 here: the chart
  // had no UV area and the packer refused the mesh ("chart 2 has zero UV area").
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 1e-10, 0}};
  m.faces = {{0, 4, 3}, {4, 1, 3}, {0, 1, 4}, {0, 3, 2}};
  AtlasOptions o;
  const Atlas a = build_atlas(m, o);
  check_atlas(m, a, o);
}

TEST_CASE("the atlas does not depend on the mesh's scale", "[atlas]") {
  // Scaling by a power of two changes no bit of a coordinate's mantissa, so every decision
  // should come out the same. At 2^-40 (a mesh 1e-12 across) the eigen-solver's absolute
  // convergence floor and the graph cut's floor on distance terms used to change the charts.
  const Mesh m = make_builtin("torus");
  AtlasOptions o;
  const Atlas ref = build_atlas(m, o);
  for (int e : {-40, -100, 60}) {
    INFO("scale 2^" << e);
    Mesh s = m;
    for (auto& p : s.positions) p = p * std::ldexp(1.0, e);
    const Atlas a = build_atlas(s, o);
    CHECK(a.num_charts() == ref.num_charts());
    CHECK(a.face_chart == ref.face_chart);
    CHECK(a.stats.l2 == ref.stats.l2);
  }
}

TEST_CASE("a larger merge limit makes fewer charts on simple shapes, within the bounds", "[atlas]") {
  // §6 merges charts of at most a tenth of the faces: the sphere keeps the 6 its splits made
  // (measured: 3 with a limit of half the faces; the torus 4 and 2).
  for (const char* name : {"sphere", "torus"}) {
    const Mesh mesh = make_builtin(name);
    AtlasOptions paper, wide;
    wide.merge_max_fraction = 0.5;
    const Atlas a = build_atlas(mesh, paper), b = build_atlas(mesh, wide);
    INFO(name << ": " << a.num_charts() << " charts, " << b.num_charts() << " with the larger limit");
    check_atlas(mesh, b, wide);
    CHECK(b.num_charts() < a.num_charts());
  }
}

TEST_CASE("atlas of a torus cuts its handle", "[atlas]") {
  const Mesh torus = make_builtin("torus");
  AtlasOptions o;
  const Atlas a = build_atlas(torus, o);
  INFO("charts " << a.num_charts());
  check_atlas(torus, a, o);
}

TEST_CASE("tighter bounds give more charts and lower stretch", "[atlas]") {
  // The face patch is one chart at the paper's bounds; bounds below its own stretch force splits.
  const Mesh face = make_builtin("face");
  AtlasOptions loose, tight;
  tight.max_l2 = 1.005;
  tight.max_linf = 1.3;
  const Atlas a = build_atlas(face, loose), b = build_atlas(face, tight);
  check_atlas(face, b, tight);
  CHECK(a.num_charts() == 1);
  CHECK(b.num_charts() > a.num_charts());
  CHECK(b.stats.l2 < a.stats.l2);
  CHECK(b.stats.linf < a.stats.linf);
}

TEST_CASE("max_charts splits until the requested count", "[atlas]") {
  const Mesh sphere = make_builtin("sphere");
  AtlasOptions o;
  o.max_charts = 12;
  const Atlas a = build_atlas(sphere, o);
  check_atlas(sphere, a, o);
  CHECK(a.num_charts() == 12);
}

TEST_CASE("pack_cuts trades extra charts for packing, within the bounds", "[atlas]") {
  // Off by default; automatic cuts keep the best of the uncut and cut packings, so the ratio
  // can only rise, and never more than double the charts.
  const Mesh torus = make_builtin("torus");
  AtlasOptions o;
  const Atlas plain = build_atlas(torus, o);
  o.pack_cuts = -1;
  const Atlas cut = build_atlas(torus, o);
  check_atlas(torus, cut, o);
  INFO("charts " << plain.num_charts() << " -> " << cut.num_charts() << ", packing " << plain.stats.packing_ratio
                 << " -> " << cut.stats.packing_ratio);
  CHECK(cut.num_charts() >= plain.num_charts());
  CHECK(cut.num_charts() <= 2 * plain.num_charts());
  CHECK(cut.stats.packing_ratio >= plain.stats.packing_ratio);
  o.pack_cuts = -2;
  CHECK_THROWS_AS(build_atlas(torus, o), isochart::InputError);
}

TEST_CASE("several components are charted separately", "[atlas]") {
  Mesh a = make_builtin("sphere");
  const Mesh b = make_builtin("torus");
  const int offset = a.num_vertices();
  for (const auto& p : b.positions) a.positions.push_back(p + Vec3d{5, 0, 0});
  for (const auto& f : b.faces) a.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  AtlasOptions o;
  const Atlas atlas = build_atlas(a, o);
  check_atlas(a, atlas, o);
  // No chart spans both components.
  const Topology topo(a);
  std::vector<int> comp_of_chart(atlas.num_charts(), -1);
  for (int f = 0; f < a.num_faces(); ++f) {
    int& c = comp_of_chart[atlas.face_chart[f]];
    if (c < 0) c = topo.face_components()[f];
    CHECK(c == topo.face_components()[f]);
  }
}

TEST_CASE("atlas is identical for one and two threads", "[atlas]") {
  const Mesh torus = make_builtin("torus");
  AtlasOptions o;
  o.seed = 42;
  Atlas one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = build_atlas(torus, o);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = build_atlas(torus, o);
  }
  CHECK(one.face_chart == two.face_chart);
  CHECK(one.face_uvs == two.face_uvs);
  CHECK(one.uvs == two.uvs);
}

TEST_CASE("bad atlas options are refused with a message naming the option", "[atlas]") {
  const Mesh sphere = make_builtin("sphere");
  auto fails_with = [&](AtlasOptions o, const std::string& word) {
    try {
      build_atlas(sphere, o);
      FAIL("no error for " << word);
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find(word) != std::string::npos);
    }
  };
  AtlasOptions o;
  o.max_l2 = 0.5;
  fails_with(o, "--max-l2");
  o = {};
  o.max_linf = std::nan("");
  fails_with(o, "--max-linf");
  o = {};
  o.max_charts = -1;
  fails_with(o, "--max-charts");
  o.max_charts = sphere.num_faces() + 1;  // more charts than faces
  fails_with(o, "--max-charts");
  o = {};
  o.alpha = 2;
  fails_with(o, "--alpha");
  o = {};
  o.pack.width = 0;
  fails_with(o, "--width");
  o.pack.width = 8193;  // the packer's limit, checked before the atlas is built
  fails_with(o, "--width");
  o = {};
  o.landmarks = 1;
  fails_with(o, "--landmarks");
}

TEST_CASE("atlas of the creature, without graph cut and without merging", "[atlas][slow]") {
  const Mesh creature = make_builtin("creature");
  for (bool cut : {true, false}) {
    AtlasOptions o;
    o.graph_cut = cut;
    const Atlas a = build_atlas(creature, o);
    INFO("graph cut " << cut << ": charts " << a.num_charts());
    check_atlas(creature, a, o);
    CHECK(a.stats.charts_before_merge >= a.num_charts());
  }
  AtlasOptions no_merge;
  no_merge.merge = false;
  const Atlas b = build_atlas(creature, no_merge);
  check_atlas(creature, b, no_merge);
  CHECK(b.num_charts() == b.stats.charts_before_merge);
}

TEST_CASE("skip_packing keeps every chart's own layout, apart, in the unit square", "[atlas]") {
  const Mesh torus = make_builtin("torus");
  AtlasOptions o;
  const Atlas packed = build_atlas(torus, o);
  o.skip_packing = true;
  Atlas loose = build_atlas(torus, o);
  // The same charts; no packing ran.
  REQUIRE(loose.face_chart == packed.face_chart);
  CHECK(loose.stats.seconds.count("packing") == 0);
  CHECK(loose.stats.packing_ratio == 0);
  CHECK(loose.stats.overlapping_pairs == -1);
  CHECK(loose.stats.flipped == 0);
  CHECK(loose.stats.l2 <= o.max_l2 + 1e-9);
  CHECK(loose.stats.linf <= o.max_linf + 1e-9);
  // Each chart is the packed chart up to a similarity: every UV edge scaled by one factor
  // per chart, and the same winding.
  const Mesh ml = loose.apply_to(torus), mp = packed.apply_to(torus);
  std::vector<double> lo(loose.num_charts(), 1e300), hi(loose.num_charts(), 0);
  for (int f = 0; f < torus.num_faces(); ++f) {
    const Face& fl = ml.face_uvs[f];
    const Face& fp = mp.face_uvs[f];
    for (int k = 0; k < 3; ++k) {
      const double r = norm(ml.uvs[fl[(k + 1) % 3]] - ml.uvs[fl[k]]) / norm(mp.uvs[fp[(k + 1) % 3]] - mp.uvs[fp[k]]);
      lo[loose.face_chart[f]] = std::min(lo[loose.face_chart[f]], r);
      hi[loose.face_chart[f]] = std::max(hi[loose.face_chart[f]], r);
    }
    const double al = signed_area(ml.uvs[fl[0]], ml.uvs[fl[1]], ml.uvs[fl[2]]);
    const double ap = signed_area(mp.uvs[fp[0]], mp.uvs[fp[1]], mp.uvs[fp[2]]);
    CHECK(al * ap > 0);
  }
  for (int c = 0; c < loose.num_charts(); ++c) CHECK(hi[c] <= lo[c] * (1 + 1e-6));
  // Laid out apart inside [0,1]²: no two triangles overlap.
  CHECK(overlapping_uv_pairs(ml).empty());
  for (const auto& uv : ml.uvs) {
    CHECK(uv.x >= 0);
    CHECK(uv.x <= 1 + 1e-12);
    CHECK(uv.y >= 0);
    CHECK(uv.y <= 1 + 1e-12);
  }
  // The caller packs later.
  pack_atlas(torus, loose, o.pack);
  check_atlas(torus, loose, o);
}

TEST_CASE("merging reports its rounds and can be cancelled between them", "[atlas]") {
  // Every chart of the sphere counts as small, so each of them gets a merging round.
  const Mesh sphere = make_builtin("sphere");
  AtlasOptions o;
  o.merge_max_fraction = 1;
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    std::vector<double> fractions;  // Merging is reported from the calling thread only
    const Progress record = [&](Stage s, double f) {
      if (s == Stage::Merging) fractions.push_back(f);
      return true;
    };
    const Atlas a = build_atlas(sphere, o, record);
    INFO(threads << " threads: " << a.stats.charts_before_merge << " charts before merging, "
                 << a.num_charts() << " after, " << fractions.size() << " rounds");
    REQUIRE(fractions.size() >= static_cast<size_t>(a.num_charts()));
    CHECK(std::is_sorted(fractions.begin(), fractions.end()));
    CHECK(fractions.front() == 0);
    CHECK(fractions.back() < 1);
    // Cancelled at the second round, while attempts computed ahead may be running.
    int rounds = 0;
    const Progress stop = [&](Stage s, double) { return s != Stage::Merging || ++rounds < 2; };
    CHECK_THROWS_AS(build_atlas(sphere, o, stop), Cancelled);
    CHECK(rounds == 2);
  }
}

TEST_CASE("bounds of exactly 1 hold up to rounding: a flat patch is one chart", "[atlas]") {
  // Laid out exactly, a plane measures Linf 1 + 4e-15: --max-linf 1 split a 200-triangle grid
  // into 179 charts (eight.off into 1507 of its 1536 faces).
  AtlasOptions o;
  o.max_l2 = 1;
  o.max_linf = 1;
  o.pack.width = o.pack.height = 256;
  const Atlas a = build_atlas(geo_test::grid(10, 10, 1.0, 1.37), o);
  CHECK(a.num_charts() == 1);
  CHECK(a.stats.linf <= 1 + 1e-9);
  CHECK(a.stats.flipped == 0);
}
