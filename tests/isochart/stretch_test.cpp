#include "isochart/stretch.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <vector>

#include "isochart/baselines.h"
#include "isochart/builtin.h"

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

TEST_CASE("an atlas's mirrored charts are measured unmirrored and counted apart", "[stretch]") {
  // UVAtlas writes v downwards, so every chart is mirrored: stats called all of bunny's faces
  // flipped with infinite stretch. Mirroring a whole chart keeps its stretch.
  const Mesh plain = square_with_map(2, 0, 0, 0.5), mirrored = square_with_map(-2, 0, 0, 0.5);
  const AtlasQuality p = measure_atlas(plain), m = measure_atlas(mirrored);
  CHECK(p.mirrored_charts == 0);
  CHECK(m.mirrored_charts == 1);
  CHECK(m.stretch.flipped == 0);
  CHECK(m.stretch.l2 == Approx(p.stretch.l2));
  CHECK(m.stretch.linf == Approx(p.stretch.linf));
  CHECK(measure_atlas(mirrored, 2.0).stretch.l2 == Approx(measure_texture_stretch(plain, 2.0).l2));
  // A triangle turned against the rest of its chart is flipped; one of zero UV area is
  // counted as degenerate.
  Mesh folded = square_with_map(1, 0, 0, 1);
  folded.uvs[3] = {1.5, 0.5};  // the second triangle turns over, still sharing the diagonal
  const AtlasQuality f = measure_atlas(folded);
  CHECK(f.stretch.flipped == 1);
  CHECK(f.stretch.degenerate == 0);
  Mesh flat = square_with_map(1, 0, 0, 1);
  flat.uvs[3] = {0.5, 0.5};  // on the diagonal
  const AtlasQuality z = measure_atlas(flat);
  CHECK(z.stretch.flipped == 1);
  CHECK(z.stretch.degenerate == 1);
  CHECK(std::isinf(z.stretch.l2));
}

TEST_CASE("the chart with the fewest texels for its surface is found", "[stretch]") {
  // A chart shrunk to a speck by a broken atlas passed every check and collapsed in
  // remesh --keep-chart-sizes.
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0}};
  m.faces = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2}};
  m.uvs = {{0.1, 0.1}, {0.45, 0.1}, {0.45, 0.9}, {0.1, 0.9},
           {0.6, 0.1}, {0.95, 0.1}, {0.95, 0.9}, {0.6, 0.9}};
  m.face_uvs = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  ChartDensity even = sparsest_chart(m);
  CHECK(even.density == Approx(1.0));
  CHECK(even.faces == 2);
  // The second square at a thousandth of its side: a millionth of its share, near enough.
  for (int i : {5, 6, 7}) m.uvs[i] = m.uvs[4] + (m.uvs[i] - m.uvs[4]) * 1e-3;
  const ChartDensity speck = sparsest_chart(m);
  CHECK(speck.first_face == 2);
  CHECK(speck.faces == 2);
  CHECK(speck.density == Approx(2e-6).epsilon(1e-3));
  CHECK(measure_atlas(m).sparsest.density == Approx(speck.density));
  // Texels spread unevenly but not broken: half the density in one chart.
  for (int i : {5, 6, 7}) m.uvs[i] = m.uvs[4] + (m.uvs[i] - m.uvs[4]) * 1e3 * std::sqrt(0.5);
  CHECK(sparsest_chart(m).density == Approx(2 * 0.5 / 1.5));
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

namespace {

// An n×m grid of quads, two counter-clockwise triangles each; vertex (i, j) at index j·(n+1)+i.
std::vector<Face> grid_faces(int n, int m) {
  std::vector<Face> f;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      f.push_back({a, b, c});
      f.push_back({a, c, d});
    }
  return f;
}

std::vector<std::array<Vec2d, 3>> corner_uvs(const std::vector<Face>& faces, const std::vector<Vec2d>& uv) {
  std::vector<std::array<Vec2d, 3>> t(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) t[f][k] = uv[faces[f][k]];
  return t;
}

// The grid's strip bent along an arc of `turns` full turns, radii 1 (row 0) to 2 (row m):
// every triangle keeps its orientation however far the strip winds.
std::vector<Vec2d> arc_layout(int n, int m, double turns) {
  std::vector<Vec2d> uv;
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= n; ++i) {
      const double a = -2 * 3.14159265358979323846 * turns * i / n, r = 1 + static_cast<double>(j) / m;
      uv.push_back({r * std::cos(a), r * std::sin(a)});
    }
  return uv;
}

}  // namespace

TEST_CASE("a chart layout is proven one-to-one from its boundary, or not proven", "[stretch][overlap]") {
  const std::vector<Face> faces = grid_faces(24, 3);
  SECTION("a strip bent along three quarters of a turn is proven") {
    const std::vector<Vec2d> uv = arc_layout(24, 3, 0.75);
    CHECK(uv_layout_is_embedding(faces, uv));
    CHECK(overlapping_uv_pairs(corner_uvs(faces, uv)).empty());
  }
  SECTION("the same strip wound past a full turn overlaps itself with no flipped triangle") {
    const std::vector<Vec2d> uv = arc_layout(24, 3, 1.25);
    CHECK_FALSE(uv_layout_is_embedding(faces, uv));
    CHECK_FALSE(overlapping_uv_pairs(corner_uvs(faces, uv)).empty());
  }
  SECTION("a flipped triangle is not proven") {
    std::vector<Vec2d> uv = arc_layout(24, 3, 0.5);
    uv[25 + 5] = uv[25 + 5] * 3.0;  // an interior vertex dragged far outside
    CHECK_FALSE(uv_layout_is_embedding(faces, uv));
  }
  SECTION("a closed ring (two boundary loops) is not a disk") {
    std::vector<Face> ring = faces;
    for (Face& f : ring)
      for (int& v : f)
        if (v % 25 == 24) v -= 24;  // last column welded to the first
    const std::vector<Vec2d> uv = arc_layout(24, 3, 1.0);
    CHECK_FALSE(uv_layout_is_embedding(ring, uv));
  }
  SECTION("whenever a jittered grid is proven, the exact all-pairs test agrees") {
    const std::vector<Face> square = grid_faces(8, 8);
    std::uint64_t state = 12345;
    auto uniform = [&] {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      return static_cast<double>(state >> 11) / 9007199254740992.0;
    };
    int proven = 0, overlapping = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const double amount = 0.2 + 1.3 * uniform();
      std::vector<Vec2d> uv;
      for (int j = 0; j <= 8; ++j)
        for (int i = 0; i <= 8; ++i) uv.push_back({i + amount * (uniform() - 0.5), j + amount * (uniform() - 0.5)});
      const bool overlaps = !overlapping_uv_pairs(corner_uvs(square, uv), 1).empty();
      const bool is_embedding = uv_layout_is_embedding(square, uv);
      if (is_embedding) CHECK_FALSE(overlaps);
      proven += is_embedding ? 1 : 0;
      overlapping += overlaps ? 1 : 0;
    }
    // Both kinds occur, so the agreement above is tested on both sides.
    CHECK(proven > 30);
    CHECK(overlapping > 30);
  }
}

namespace {

// Two charts, each a 4×4 grid of squares with its own texture coordinates: the first on
// [0, 4]², the second scaled by `s` and moved by `offset`.
Mesh two_charts(double s, Vec2d offset) {
  Mesh m;
  const std::vector<Face> grid = grid_faces(4, 4);
  for (int c = 0; c < 2; ++c) {
    const int base = static_cast<int>(m.positions.size());
    for (int j = 0; j <= 4; ++j)
      for (int i = 0; i <= 4; ++i) {
        m.positions.push_back({static_cast<double>(i), static_cast<double>(j), static_cast<double>(c)});
        m.uvs.push_back(c == 0 ? Vec2d{double(i), double(j)} : Vec2d{s * i, s * j} + offset);
      }
    for (const Face& f : grid) m.faces.push_back({base + f[0], base + f[1], base + f[2]});
  }
  m.face_uvs = m.faces;
  return m;
}

std::vector<std::array<Vec2d, 3>> mesh_corner_uvs(const Mesh& m) {
  std::vector<std::array<Vec2d, 3>> t(m.faces.size());
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) t[f][k] = m.uvs[m.face_uvs[f][k]];
  return t;
}

}  // namespace

TEST_CASE("the whole-atlas overlap count proves charts apart or counts pairs", "[stretch][overlap]") {
  // The mesh overload first tries to prove the charts apart from their boundaries; whatever
  // it concludes must match the all-pairs test of the same triangles.
  struct Case {
    const char* name;
    double s;
    Vec2d offset;
    bool overlaps;
  };
  const Case cases[] = {
      {"side by side", 1.0, {5, 0}, false},
      {"touching along a side", 1.0, {4, 0}, false},
      {"touching at a corner", 1.0, {4, 4}, false},
      {"nested inside without crossing", 0.25, {1.3, 1.7}, true},
      {"around the other without crossing", 3.0, {-4, -4}, true},
      {"boundaries crossing", 1.0, {2.5, 1.5}, true},
      {"in a concave notch of the other's box, apart", 1.0, {-5, 0}, false},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const Mesh m = two_charts(c.s, c.offset);
    const auto all_pairs = overlapping_uv_pairs(mesh_corner_uvs(m));
    CHECK(overlapping_uv_pairs(m) == all_pairs);
    CHECK(all_pairs.empty() == !c.overlaps);
  }
  SECTION("a chart folded onto itself is counted, not proven") {
    Mesh m = two_charts(1.0, {6, 0});
    m.uvs[6] = {3.5, 3.5};  // an interior vertex of the first chart dragged across others
    const auto all_pairs = overlapping_uv_pairs(mesh_corner_uvs(m));
    CHECK_FALSE(all_pairs.empty());
    CHECK(overlapping_uv_pairs(m) == all_pairs);
  }
}

TEST_CASE("the texture aspect an atlas was laid out for is read from its UVs", "[stretch]") {
  const Mesh mesh = make_builtin("sphere");
  LscmOptions o;
  const Atlas a = build_lscm_atlas(mesh, o);
  Mesh m = a.apply_to(mesh);
  // A square texture's atlas reads as exactly 1, powers of two exactly, other shapes as
  // estimated.
  CHECK(detect_texture_aspect(m) == 1.0);
  for (double aspect : {4.0, 2.0, 0.125, 1.25, 0.75}) {
    Mesh squashed = m;
    for (Vec2d& p : squashed.uvs) p.x /= aspect;
    INFO(aspect);
    if (aspect == 1.25 || aspect == 0.75)
      CHECK(detect_texture_aspect(squashed) == Approx(aspect).epsilon(0.03));
    else
      CHECK(detect_texture_aspect(squashed) == aspect);
    // The charts read back from the file keep the square atlas's stretch.
    const Atlas e = atlas_from_uvs(squashed);
    const Atlas f = atlas_from_uvs(m);
    REQUIRE(e.num_charts() == f.num_charts());
    for (int c = 0; c < e.num_charts(); ++c) CHECK(e.charts[c].l2 == Approx(f.charts[c].l2).epsilon(0.02));
  }
  // Half the charts stretched fourfold along u, the others not: the charts disagree, so it is
  // a stretched square atlas, not a 2:1 texture's.
  Mesh stretched = m;
  std::vector<char> moved(stretched.uvs.size(), 0);
  for (int f = 0; f < stretched.num_faces(); ++f)
    if (a.face_chart[f] % 2 == 0)
      for (int t : stretched.face_uvs[f])
        if (!moved[t]) stretched.uvs[t].x *= 4, moved[t] = 1;
  REQUIRE(a.num_charts() >= 2);
  CHECK(detect_texture_aspect(stretched) == 1.0);
  CHECK(detect_texture_aspect(mesh) == 1.0);  // no UVs
}
