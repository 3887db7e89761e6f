#include "isochart/pack.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>

#include "isochart/error.h"
#include "isochart/io.h"
#include "isochart/stretch.h"
// Internal header: the fast raster is checked against the per-triangle reference.
#include "../../libisochart/src/pack_canvas.h"
#include "../../libisochart/src/pack_raster.h"

using namespace isochart;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A star-shaped blob with a wavy outline, fan-triangulated counter-clockwise around its
// centre, stretched by `aspect`, rotated and moved anywhere; its 3-D area differs from its
// UV area by a random factor so that the packer has to rescale it.
PackChart blob(std::mt19937& rng, double radius, double aspect, int samples = 48) {
  std::uniform_real_distribution<double> u(0, 1);
  const double p1 = 2 * kPi * u(rng), p2 = 2 * kPi * u(rng), turn = 2 * kPi * u(rng);
  const int k1 = 2 + static_cast<int>(3 * u(rng)), k2 = 5 + static_cast<int>(4 * u(rng));
  const Vec2d shift{100 * u(rng) - 50, 100 * u(rng) - 50};
  PackChart c;
  c.uv.push_back(shift);
  for (int i = 0; i < samples; ++i) {
    const double t = 2 * kPi * i / samples;
    const double r = radius * (1 + 0.35 * std::sin(k1 * t + p1) + 0.2 * std::sin(k2 * t + p2));
    const Vec2d p{r * std::cos(t) * aspect, r * std::sin(t) / aspect};
    c.uv.push_back(shift + Vec2d{p.x * std::cos(turn) - p.y * std::sin(turn),
                                 p.x * std::sin(turn) + p.y * std::cos(turn)});
  }
  for (int i = 0; i < samples; ++i) c.faces.push_back({0, 1 + i, 1 + (i + 1) % samples});
  double area = 0;
  for (const Face& f : c.faces) area += signed_area(c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]);
  c.area_3d = area * (0.5 + 1.5 * u(rng));
  return c;
}

std::vector<PackChart> blobs(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<PackChart> charts;
  for (int i = 0; i < count; ++i) charts.push_back(blob(rng, 1 + 3 * u(rng), 0.5 + 1.5 * u(rng)));
  return charts;
}

double uv_area(const PackChart& c) {
  double a = 0;
  for (const Face& f : c.faces) a += std::abs(signed_area(c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]));
  return a;
}

// Whether the closed triangle meets the closed square [x0, x1] × [y0, y1] (separating axes:
// the two coordinate axes and the three edge normals).
bool touches(const Vec2d t[3], double x0, double y0, double x1, double y1) {
  if (std::max({t[0].x, t[1].x, t[2].x}) < x0 || std::min({t[0].x, t[1].x, t[2].x}) > x1) return false;
  if (std::max({t[0].y, t[1].y, t[2].y}) < y0 || std::min({t[0].y, t[1].y, t[2].y}) > y1) return false;
  const Vec2d corners[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  for (int k = 0; k < 3; ++k) {
    const Vec2d e = t[(k + 1) % 3] - t[k];
    const Vec2d n{-e.y, e.x};
    double tlo = dot(n, t[0]), thi = tlo, slo = dot(n, corners[0]), shi = slo;
    for (int i = 1; i < 3; ++i) {
      tlo = std::min(tlo, dot(n, t[i]));
      thi = std::max(thi, dot(n, t[i]));
    }
    for (int i = 1; i < 4; ++i) {
      slo = std::min(slo, dot(n, corners[i]));
      shi = std::max(shi, dot(n, corners[i]));
    }
    if (thi < slo || shi < tlo) return false;
  }
  return true;
}

// Texels (x, y) of a W×H grid that the chart's triangles touch, as y·W + x; texels outside
// the grid make the chart fail the border check, so they are reported as −1.
std::vector<long long> touched_texels(const PackChart& c, int w, int h) {
  std::vector<long long> out;
  for (const Face& f : c.faces) {
    Vec2d t[3];
    for (int k = 0; k < 3; ++k) t[k] = {c.uv[f[k]].x * w, c.uv[f[k]].y * h};
    const int x0 = static_cast<int>(std::floor(std::min({t[0].x, t[1].x, t[2].x}))) - 1;
    const int x1 = static_cast<int>(std::floor(std::max({t[0].x, t[1].x, t[2].x}))) + 1;
    const int y0 = static_cast<int>(std::floor(std::min({t[0].y, t[1].y, t[2].y}))) - 1;
    const int y1 = static_cast<int>(std::floor(std::max({t[0].y, t[1].y, t[2].y}))) + 1;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        if (touches(t, x, y, x + 1, y + 1))
          out.push_back(x < 0 || y < 0 || x >= w || y >= h ? -1 : static_cast<long long>(y) * w + x);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

struct GutterCheck {
  long long violations = 0;   // texel pairs of different charts closer than the gutter
  long long near_border = 0;  // chart texels closer than the gutter to the border
};

// Conservative rasters of all charts on the W×H grid: no texel of one chart may lie within
// `gutter` texels (square neighbourhood) of another chart's texel or of the border.
GutterCheck check_gutter(const std::vector<PackChart>& charts, int w, int h, int gutter) {
  GutterCheck check;
  std::vector<int> owner(static_cast<std::size_t>(w) * h, -1);
  std::vector<std::vector<long long>> texels(charts.size());
  for (std::size_t i = 0; i < charts.size(); ++i) {
    texels[i] = touched_texels(charts[i], w, h);
    for (const long long t : texels[i]) {
      if (t < 0) {
        ++check.near_border;
        continue;
      }
      const int x = static_cast<int>(t % w), y = static_cast<int>(t / w);
      if (x < gutter || y < gutter || x >= w - gutter || y >= h - gutter) ++check.near_border;
      if (owner[t] >= 0 && owner[t] != static_cast<int>(i)) ++check.violations;
      owner[t] = static_cast<int>(i);
    }
  }
  for (std::size_t i = 0; i < charts.size(); ++i)
    for (const long long t : texels[i]) {
      if (t < 0) continue;
      const int x = static_cast<int>(t % w), y = static_cast<int>(t / w);
      for (int dy = -gutter; dy <= gutter; ++dy)
        for (int dx = -gutter; dx <= gutter; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const int o = owner[static_cast<std::size_t>(ny) * w + nx];
          if (o >= 0 && o != static_cast<int>(i)) ++check.violations;
        }
    }
  return check;
}

// Everything pack_charts promises, checked on its output.
void check_packing(const std::vector<PackChart>& before, const std::vector<PackChart>& after,
                   const PackOptions& o, const PackResult& r) {
  REQUIRE(after.size() == before.size());
  bool inside = true;
  int flipped = 0, turned = 0;
  std::vector<std::array<Vec2d, 3>> tris;
  double total = 0;
  for (std::size_t i = 0; i < after.size(); ++i) {
    const PackChart& c = after[i];
    for (const Vec2d& p : c.uv) inside = inside && p.x >= 0 && p.x <= 1 && p.y >= 0 && p.y <= 1;
    for (std::size_t t = 0; t < c.faces.size(); ++t) {
      const Face& f = c.faces[t];
      tris.push_back({c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]});
      const double now = signed_area(c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]);
      const double was = signed_area(before[i].uv[f[0]], before[i].uv[f[1]], before[i].uv[f[2]]);
      flipped += now <= 0;
      turned += (now > 0) != (was > 0);
    }
    total += uv_area(c);
  }
  CHECK(inside);
  CHECK(flipped == 0);  // every test chart is counter-clockwise...
  CHECK(turned == 0);   // ...and keeps its winding
  CHECK(overlapping_uv_pairs(tris, 1).empty());
  const GutterCheck gutter = check_gutter(after, o.width, o.height, o.gutter);
  CHECK(gutter.violations == 0);
  CHECK(gutter.near_border == 0);
  // One texel density: UV area / 3-D area is the same for every chart, and matches texel_size.
  const double density = 1.0 / (r.texel_size * r.texel_size * o.width * o.height);
  for (std::size_t i = 0; i < after.size(); ++i) {
    const double area_3d = before[i].area_3d > 0 ? before[i].area_3d : uv_area(before[i]);
    CHECK(uv_area(after[i]) / area_3d == Approx(density).epsilon(1e-9));
  }
  CHECK(r.utilization == Approx(total).epsilon(1e-9));
  CHECK(r.packing_ratio >= r.utilization);
  CHECK(r.packing_ratio <= 1);
}

// The charts of an atlas with their own UVs (mirrored ones turned back) and 3-D areas.
std::vector<PackChart> atlas_charts(const Mesh& m) {
  int count = 0;
  const std::vector<int> chart = uv_charts(m, count);
  std::vector<PackChart> charts(count);
  std::vector<int> stamp(m.uvs.size(), -1), id(m.uvs.size(), -1);
  for (int f = 0; f < m.num_faces(); ++f) {
    PackChart& c = charts[chart[f]];
    Face face;
    for (int k = 0; k < 3; ++k) {
      const int t = m.face_uvs[f][k];
      if (stamp[t] != chart[f]) {
        stamp[t] = chart[f];
        id[t] = static_cast<int>(c.uv.size());
        c.uv.push_back(m.uvs[t]);
      }
      face[k] = id[t];
    }
    c.faces.push_back(face);
    c.area_3d +=
        triangle_area(m.positions[m.faces[f][0]], m.positions[m.faces[f][1]], m.positions[m.faces[f][2]]);
  }
  for (PackChart& c : charts) {
    double s = 0;
    for (const Face& f : c.faces) s += signed_area(c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]);
    if (s < 0)
      for (Vec2d& p : c.uv) p.x = -p.x;
  }
  return charts;
}

}  // namespace

TEST_CASE("packed charts keep the gutter, one density and their winding", "[pack]") {
  const std::vector<PackChart> input = blobs(30, 7);
  std::vector<PackChart> charts = input;
  PackOptions o;
  o.width = o.height = 512;
  o.gutter = 2;
  const PackResult r = pack_charts(charts, o);
  check_packing(input, charts, o, r);
  CHECK(r.packing_ratio > 0.6);
  CHECK(r.placements.size() == charts.size());
  // The placement transform reproduces the output UVs.
  for (std::size_t i = 0; i < charts.size(); ++i) {
    const ChartPlacement& p = r.placements[i];
    for (std::size_t v = 0; v < charts[i].uv.size(); ++v) {
      const Vec2d& q = input[i].uv[v];
      const Vec2d t = Vec2d{std::cos(p.angle) * q.x - std::sin(p.angle) * q.y,
                            std::sin(p.angle) * q.x + std::cos(p.angle) * q.y} *
                          p.scale +
                      p.offset;
      CHECK(t.x / o.width == Approx(charts[i].uv[v].x).margin(1e-9));
      CHECK(t.y / o.height == Approx(charts[i].uv[v].y).margin(1e-9));
    }
  }
}

TEST_CASE("a texture larger than the search grid is packed on a coarser grid that divides it", "[pack]") {
  // 1024 × 512 with a 256 grid: packed on 256 × 128 (k = 4), the 3-texel gutter rounded up to
  // one coarse texel, 4 of the texture's; the result must hold on the texture's own grid.
  const std::vector<PackChart> input = blobs(20, 5);
  std::vector<PackChart> charts = input, own = input;
  PackOptions o;
  o.width = 1024;
  o.height = 512;
  o.gutter = 3;
  o.search_size = 256;
  const PackResult r = pack_charts(charts, o);
  check_packing(input, charts, o, r);
  CHECK(check_gutter(charts, o.width, o.height, 4).violations == 0);
  CHECK(r.used_width % 4 == 0);
  for (std::size_t i = 0; i < charts.size(); ++i) {  // the placements describe the texture's texels
    const ChartPlacement& p = r.placements[i];
    const Vec2d& q = input[i].uv[0];
    const Vec2d t = Vec2d{std::cos(p.angle) * q.x - std::sin(p.angle) * q.y,
                          std::sin(p.angle) * q.x + std::cos(p.angle) * q.y} *
                        p.scale +
                    p.offset;
    CHECK(t.x / o.width == Approx(charts[i].uv[0].x).margin(1e-9));
    CHECK(t.y / o.height == Approx(charts[i].uv[0].y).margin(1e-9));
  }
  // On the texture's own grid it packs alike, only slower (measured: 0.604 against 0.618 on
  // this small grid; the atlases of bunny, horse and fertility at 4096² on a 1024 one, -0.021
  // to +0.008).
  PackOptions full = o;
  full.search_size = 0;
  const PackResult f = pack_charts(own, full);
  CHECK(r.packing_ratio > 0.9 * f.packing_ratio);
  // No grid of 128 to 256 divides 1023 × 512: the texture's own is used.
  PackOptions odd = o, odd_own = o;
  odd.width = odd_own.width = 1023;
  odd_own.search_size = 0;
  std::vector<PackChart> again = input, again_own = input;
  check_packing(input, again, odd, pack_charts(again, odd));
  pack_charts(again_own, odd_own);
  for (std::size_t i = 0; i < again.size(); ++i) CHECK(again[i].uv == again_own[i].uv);
}

TEST_CASE("wide gutters, no gutter, one rotation and the paper's plain scheme all hold", "[pack]") {
  for (int variant = 0; variant < 4; ++variant) {
    const std::vector<PackChart> input = blobs(12, 11);
    std::vector<PackChart> charts = input;
    PackOptions o;
    o.width = o.height = 256;
    o.variants = 2;  // the ladder of variants is covered by the other tests
    if (variant == 0) o.gutter = 0;
    if (variant == 1) o.gutter = 5;
    if (variant == 2) o.rotations = 1;
    if (variant == 3) {  // §6 alone: no holes, one order, least waste only
      o.fill_holes = false;
      o.variants = 1;
      o.growth_weight = 0;
    }
    const PackResult r = pack_charts(charts, o);
    INFO("variant " << variant);
    check_packing(input, charts, o, r);
    CHECK(r.packing_ratio > 0.4);
  }
}

TEST_CASE("a long sliver packs with the blobs", "[pack]") {
  // 2000:1, so that most of its rotations do not fit the texture at all.
  std::vector<PackChart> input = blobs(10, 13);
  PackChart sliver;
  sliver.uv = {{0, 0}, {2000, 0}, {2000, 1}, {0, 1}};
  sliver.faces = {{0, 1, 2}, {0, 2, 3}};
  sliver.area_3d = 20;
  input.push_back(sliver);
  std::vector<PackChart> charts = input;
  PackOptions o;
  o.width = o.height = 512;
  o.variants = 2;
  const PackResult r = pack_charts(charts, o);
  check_packing(input, charts, o, r);
}

TEST_CASE("a non-square target gives a packing of about its aspect", "[pack]") {
  const std::vector<PackChart> input = blobs(40, 3);
  std::vector<PackChart> charts = input;
  PackOptions o;
  o.width = 1024;
  o.height = 256;
  const PackResult r = pack_charts(charts, o);
  check_packing(input, charts, o, r);
  const double aspect = static_cast<double>(r.used_width) / r.used_height;
  CHECK(aspect > 4 / 1.3);
  CHECK(aspect < 4 * 1.3);
  // The packing fills the texture in at least one direction.
  CHECK(std::max(static_cast<double>(r.used_width) / (o.width - 2 * o.gutter),
                 static_cast<double>(r.used_height) / (o.height - 2 * o.gutter)) > 0.95);
}

TEST_CASE("packing is identical with 1 and 2 threads", "[pack]") {
  const std::vector<PackChart> input = blobs(25, 5);
  std::vector<PackChart> one = input, two = input;
  PackOptions o;
  o.width = o.height = 512;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    pack_charts(one, o);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    pack_charts(two, o);
  }
  bool same = true;
  for (std::size_t i = 0; i < one.size(); ++i)
    for (std::size_t v = 0; v < one[i].uv.size(); ++v) same = same && one[i].uv[v] == two[i].uv[v];
  CHECK(same);
}

TEST_CASE("a single chart fills the texture", "[pack]") {
  std::mt19937 rng(1);
  const std::vector<PackChart> input{blob(rng, 2, 1.7)};
  std::vector<PackChart> charts = input;
  PackOptions o;
  o.width = o.height = 256;
  const PackResult r = pack_charts(charts, o);
  check_packing(input, charts, o, r);
  // Alone, the chart spans (almost) the whole texture in its long direction.
  CHECK(std::max(r.used_width, r.used_height) >= o.width - 2 * o.gutter - 1);
}

TEST_CASE("many tiny charts pack densely", "[pack][slow]") {
  // 1000 single-triangle charts of similar size, each its own chart.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<PackChart> input;
  for (int i = 0; i < 1000; ++i) {
    PackChart c;
    const Vec2d a{u(rng), u(rng)};
    c.uv = {a, a + Vec2d{0.5 + u(rng), 0.3 * u(rng)}, a + Vec2d{u(rng), 0.4 + u(rng)}};
    c.faces = {{0, 1, 2}};
    if (signed_area(c.uv[0], c.uv[1], c.uv[2]) < 0) std::swap(c.faces[0][1], c.faces[0][2]);
    c.area_3d = uv_area(c) * (0.5 + u(rng));
    input.push_back(c);
  }
  std::vector<PackChart> charts = input;
  PackOptions o;
  const PackResult r = pack_charts(charts, o);
  check_packing(input, charts, o, r);
  CHECK(r.packing_ratio >= 0.5);
}

TEST_CASE("automatic rotations: 16, and 4 above 256 charts", "[pack]") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  auto triangles = [&](int count) {
    std::vector<PackChart> out;
    for (int i = 0; i < count; ++i) {
      PackChart c;
      c.uv = {{0, 0}, {0.5 + u(rng), 0.3 * u(rng)}, {u(rng), 0.4 + u(rng)}};
      c.faces = {{0, 1, 2}};
      if (signed_area(c.uv[0], c.uv[1], c.uv[2]) < 0) std::swap(c.faces[0][1], c.faces[0][2]);
      c.area_3d = uv_area(c);
      out.push_back(c);
    }
    return out;
  };
  // The automatic packing is the fixed one's, placement for placement, and a valid packing.
  auto same = [](int rotations, const std::vector<PackChart>& input) {
    std::vector<PackChart> a = input, b = input;
    PackOptions automatic, fixed;
    fixed.rotations = rotations;
    const PackResult ra = pack_charts(a, automatic), rb = pack_charts(b, fixed);
    check_packing(input, a, automatic, ra);
    bool equal = ra.placements.size() == rb.placements.size();
    for (std::size_t i = 0; equal && i < ra.placements.size(); ++i)
      equal = ra.placements[i].angle == rb.placements[i].angle && ra.placements[i].offset == rb.placements[i].offset;
    return equal;
  };
  CHECK(same(16, triangles(40)));
  CHECK(same(4, triangles(300)));
}

TEST_CASE("charts of a real atlas pack tighter than UVAtlas packed them", "[pack]") {
  const std::string path = std::string(ISOCHARTS_SHARED_DATA) + "/baseline_atlases/bunny_uvatlas.obj";
  const std::vector<PackChart> input = atlas_charts(load_mesh(path).mesh);
  REQUIRE(input.size() == 13);
  std::vector<PackChart> charts = input;
  PackOptions o;
  const PackResult r = pack_charts(charts, o);
  check_packing(input, charts, o, r);
  CHECK(r.packing_ratio > 0.597);  // UVAtlas's own packing of these charts (MANIFEST)
}

TEST_CASE("the outline raster equals the triangle-by-triangle raster", "[pack]") {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 40; ++trial) {
    PackChart c = blob(rng, 3 + 20 * u(rng), 0.5 + u(rng), 12 + trial);
    // Some trials get a flipped fold, a zero-area sliver, an overlapping flap and a lone
    // vertex: the outline path must still cover exactly what the triangles cover.
    if (trial % 4 == 1) std::swap(c.faces[3][1], c.faces[3][2]);
    if (trial % 4 == 2) {
      c.uv.push_back((c.uv[1] + c.uv[2]) * 0.5);
      c.faces.push_back({1, static_cast<int>(c.uv.size()) - 1, 2});
      c.uv.push_back(c.uv[0] + Vec2d{40 * u(rng), 40 * u(rng)});
      c.faces.push_back({0, 5, static_cast<int>(c.uv.size()) - 1});
    }
    if (trial % 4 == 3) c.uv.push_back(c.uv[0] + Vec2d{-30, 7.5});
    for (Vec2d& p : c.uv) p = p + Vec2d{0.37, 0.81};
    const auto outline = pack_detail::chart_outline(c.uv, c.faces);
    const auto fast = pack_detail::rasterize_chart(c.uv, c.faces, outline);
    const auto reference = pack_detail::rasterize_triangles(c.uv, c.faces);
    INFO("trial " << trial);
    REQUIRE(fast.w == reference.w);
    REQUIRE(fast.h == reference.h);
    CHECK(fast.bits == reference.bits);
    CHECK(fast.texels > 0);
  }
}

TEST_CASE("the canvas's free-square map matches a brute-force count", "[pack]") {
  // The map is updated incrementally (row scans that clear whole words of taken texels at
  // once); every entry must equal the largest free square grown from it directly.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  pack_detail::Canvas canvas(120, 100, 2, 0.5);
  for (int k = 0; k < 12; ++k) {
    PackChart c = blob(rng, 10 + 35 * u(rng), 0.4 + u(rng), 24);
    const auto raster =
        pack_detail::rasterize_chart(c.uv, c.faces, pack_detail::chart_outline(c.uv, c.faces));
    const int x = static_cast<int>((canvas.width() - raster.w - 8) * u(rng)) + 4;
    const int y = static_cast<int>((canvas.height() - raster.h - 8) * u(rng)) + 4;
    canvas.place(raster, x, y);  // overlaps allowed: only the map is under test
  }
  const int cap = pack_detail::Canvas::kSquareCap;
  int mismatches = 0, taken = 0;
  for (int y = 0; y < canvas.height(); ++y)
    for (int x = 0; x < canvas.width(); ++x) {
      taken += canvas.occupied(x, y) ? 1 : 0;
      int s = 0;
      while (s < cap && x + s < canvas.width() && y + s < canvas.height()) {
        bool free = true;
        for (int i = 0; i <= s && free; ++i)
          free = !canvas.occupied(x + s, y + i) && !canvas.occupied(x + i, y + s);
        if (!free) break;
        ++s;
      }
      mismatches += canvas.free_square(x, y) != s ? 1 : 0;
    }
  CHECK(taken > 0);
  CHECK(mismatches == 0);
}

TEST_CASE("bad charts and options are reported by name", "[pack]") {
  auto message = [](std::vector<PackChart> charts, const PackOptions& o = {}) -> std::string {
    try {
      pack_charts(charts, o);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  std::mt19937 rng(2);
  const PackChart good = blob(rng, 1, 1);
  PackChart no_faces = good;
  no_faces.faces.clear();
  CHECK_THAT(message({good, no_faces}), Catch::Contains("chart 1 has no faces"));
  PackChart bad_index = good;
  bad_index.faces[2][1] = 99;
  CHECK_THAT(message({bad_index}), Catch::Contains("chart 0: face 2 references vertex 99"));
  PackChart nan = good;
  nan.uv[3].x = std::nan("");
  CHECK_THAT(message({good, good, nan}), Catch::Contains("chart 2: vertex 3 has a non-finite UV"));
  PackChart flat = good;
  for (Vec2d& p : flat.uv) p.y = 0;
  CHECK_THAT(message({flat}), Catch::Contains("chart 0 has zero UV area"));
  PackChart negative = good;
  negative.area_3d = -1;
  CHECK_THAT(message({negative}), Catch::Contains("chart 0: area_3d"));
  PackOptions o;
  o.gutter = -1;
  CHECK_THAT(message({good}, o), Catch::Contains("gutter"));
  o.gutter = 2;
  o.search_size = 10;
  CHECK_THAT(message({good}, o), Catch::Contains("search grid"));
  o.search_size = 0;
  o = {};
  o.width = 4;
  o.gutter = 2;
  CHECK_THAT(message({good}, o), Catch::Contains("leaves no room"));
  o.width = o.height = 3;
  o.gutter = 1;
  CHECK(message({good}, o) == "pack: the chart does not fit a 3x3 texture with a gutter of 1 texel");
  o = {};
  o.rotations = -1;
  CHECK_THAT(message({good}, o), Catch::Contains("rotations"));
  o = {};
  o.growth_weight = -1;
  CHECK_THAT(message({good}, o), Catch::Contains("growth_weight"));
  o = {};
  o.width = 9000;
  CHECK_THAT(message({good}, o), Catch::Contains("outside 1..8192"));
  // More charts than a tiny texture can hold with its gutter.
  o = {};
  o.width = o.height = 16;
  o.gutter = 2;
  CHECK_THAT(message(blobs(40, 9), o), Catch::Contains("do not fit"));
}

TEST_CASE("no charts is a no-op, and the progress callback can cancel", "[pack]") {
  std::vector<PackChart> none;
  const PackResult empty = pack_charts(none);
  CHECK(empty.packing_ratio == 0);
  std::vector<PackChart> charts = blobs(5, 4);
  int calls = 0;
  const Progress stop = [&](Stage s, double) {
    CHECK(s == Stage::Packing);
    return ++calls < 2;
  };
  CHECK_THROWS_AS(pack_charts(charts, {}, stop), Cancelled);
  // Cancelling from inside a packing attempt (reported from TBB tasks) also stops it.
  std::vector<PackChart> many = blobs(100, 8);
  std::atomic<int> count{0};
  const Progress stop_later = [&](Stage, double) { return ++count < 4; };
  CHECK_THROWS_AS(pack_charts(many, {}, stop_later), Cancelled);
  CHECK(count >= 4);
}
