#include "isochart/render.h"

#include <sys/wait.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "isochart/atlas.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/image.h"

using namespace isochart;
namespace fs = std::filesystem;

namespace {

bool is_white(const Image& img, int x, int y) {
  for (int c = 0; c < 3; ++c)
    if (img.at(x, y, c) < 0.999f) return false;
  return true;
}

// Chromaticity: a colour's share of each channel; greys sit at (1/3, 1/3, 1/3).
Vec3d chroma(const Image& img, int x, int y) {
  const Vec3d c{img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)};
  const double s = c.x + c.y + c.z;
  return s > 0 ? c / s : Vec3d{};
}

// Number of distinct hues among the saturated pixels: hues binned by 30°, clusters are runs of
// bins holding at least 1% of those pixels. Lighting, highlights and anti-aliasing against
// white change saturation and brightness, not hue, so a flat-coloured chart is one cluster.
int hue_clusters(const Image& img) {
  const double pi = 3.14159265358979323846;
  int bins[12] = {0}, total = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double r = img.at(x, y, 0), g = img.at(x, y, 1), b = img.at(x, y, 2);
      if (std::max({r, g, b}) - std::min({r, g, b}) < 0.1) continue;
      double hue = std::atan2(std::sqrt(3.0) * (g - b), 2 * r - g - b) * 180 / pi;
      if (hue < 0) hue += 360;
      ++bins[std::min(11, static_cast<int>(hue / 30))];
      ++total;
    }
  bool on[12];
  for (int i = 0; i < 12; ++i) on[i] = total > 0 && bins[i] * 100 >= total;
  int clusters = 0;
  for (int i = 0; i < 12; ++i) clusters += on[i] && !on[(i + 11) % 12];
  if (clusters == 0 && on[0]) clusters = 1;  // every bin on
  return clusters;
}

int count_pixels(const Image& img, float below) {
  int n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.at(x, y, 0) < below && img.at(x, y, 1) < below && img.at(x, y, 2) < below) ++n;
  return n;
}

// The unit sphere cut into two hemispheres (z > 0 and z ≤ 0 by face centroid), each
// projected orthographically into one half of the unit square: a two-chart atlas.
Mesh two_chart_sphere() {
  Mesh m = make_builtin("sphere");
  m.face_uvs.resize(m.faces.size());
  m.face_groups.resize(m.faces.size());
  for (int f = 0; f < m.num_faces(); ++f) {
    const Face& t = m.faces[f];
    const bool upper = m.positions[t[0]].z + m.positions[t[1]].z + m.positions[t[2]].z > 0;
    m.face_groups[f] = upper ? 0 : 1;
    for (int k = 0; k < 3; ++k) {
      const Vec3d& p = m.positions[t[k]];
      // Seen from -z the lower half is mirrored, so flip x to keep it counter-clockwise.
      const double u = upper ? 0.25 + 0.24 * p.x : 0.75 - 0.24 * p.x;
      m.uvs.push_back({u, 0.5 + 0.24 * p.y});
      m.face_uvs[f][k] = static_cast<int>(m.uvs.size()) - 1;
    }
  }
  return m;
}

// A unit square in the xy-plane facing +z, UVs over [0, 1]².
Mesh textured_quad() {
  Mesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.face_uvs = m.faces;
  return m;
}

Image checkerboard(int size, int squares) {
  Image img(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const bool dark = ((x * squares / size) + (y * squares / size)) % 2 == 0;
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = dark ? 0.0f : 1.0f;
    }
  return img;
}

}  // namespace

TEST_CASE("render of a sphere covers the centre and leaves the corners white", "[render]") {
  RenderOptions o;
  o.width = 160;
  o.height = 120;
  const Image img = render_mesh(make_builtin("sphere"), o);
  REQUIRE(img.width == 160);
  REQUIRE(img.height == 120);
  REQUIRE(img.channels == 3);
  CHECK_FALSE(is_white(img, 80, 60));
  CHECK(img.at(80, 60, 0) > 0.2f);  // lit, not black
  for (auto [x, y] : {std::pair{0, 0}, {159, 0}, {0, 119}, {159, 119}}) CHECK(is_white(img, x, y));
  // Shaded mode is grey.
  CHECK(hue_clusters(img) == 0);
}

TEST_CASE("a mesh renders the same at any size and place", "[render]") {
  // The camera stood at least 1e-12 units from the model: a sphere 1e-28 across came out
  // blank, one 1e-14 across with noisy edges.
  RenderOptions o;
  o.width = 160;
  o.height = 120;
  const Mesh sphere = make_builtin("sphere");
  const Image ref = render_mesh(sphere, o);
  for (const auto& [scale, offset] : {std::pair{1e-28, 0.0}, {1e-14, 0.0}, {1e12, 0.0}, {1.0, 1e9}}) {
    Mesh m = sphere;
    for (Vec3d& p : m.positions) p = p * scale + Vec3d{offset, 0, 0};
    const Image img = render_mesh(m, o);
    REQUIRE(img.pixels.size() == ref.pixels.size());
    double diff = 0;
    for (std::size_t i = 0; i < img.pixels.size(); ++i) diff += std::abs(img.pixels[i] - ref.pixels[i]);
    INFO("scale " << scale << ", offset " << offset);
    CHECK(diff / img.pixels.size() < 0.002);
  }
}

TEST_CASE("several views are composed side by side", "[render]") {
  RenderOptions o;
  o.views = 4;
  o.width = 400;
  o.height = 100;
  const Image img = render_mesh(make_builtin("torus"), o);
  REQUIRE(img.width == 400);
  REQUIRE(img.height == 100);
  for (int v = 0; v < 4; ++v) {
    // Each column shows the torus: its middle row has surface, its left and right edges none.
    int covered = 0;
    for (int x = v * 100; x < (v + 1) * 100; ++x) covered += !is_white(img, x, 50);
    CHECK(covered > 50);
    for (int y = 0; y < 100; ++y) {
      CHECK(is_white(img, v * 100, y));
      CHECK(is_white(img, v * 100 + 99, y));
    }
  }
  o.views = 8;
  CHECK(render_mesh(make_builtin("torus"), o).width == 400);
}

TEST_CASE("transparent background gives RGBA with alpha coverage", "[render]") {
  RenderOptions o;
  o.width = o.height = 64;
  o.transparent = true;
  const Image img = render_mesh(make_builtin("sphere"), o);
  REQUIRE(img.channels == 4);
  CHECK(img.at(32, 32, 3) == 1.0f);
  CHECK(img.at(0, 0, 3) == 0.0f);
}

TEST_CASE("chart colouring distinguishes adjacent charts", "[render]") {
  const Mesh m = two_chart_sphere();
  const std::vector<Vec3d> colors = chart_colors(m, m.face_groups, 2);
  REQUIRE(colors.size() == 2);
  CHECK(colors[0] != colors[1]);

  RenderOptions o;
  o.width = o.height = 128;
  o.color = ColorMode::Charts;
  // With +z as the model's up the front view looks along -x: the upper hemisphere fills the
  // top half of the image, the lower one the bottom half.
  o.up = {0, 0, 1};
  const Image img = render_mesh(m, o);
  CHECK(hue_clusters(img) == 2);

  // Without groups the UV charts are used, with the same result.
  Mesh no_groups = m;
  no_groups.face_groups.clear();
  const Image from_uv = render_mesh(no_groups, o);
  CHECK(from_uv.pixels == img.pixels);

  // Explicit per-face charts override the groups: one chart is one colour.
  o.face_charts.assign(m.faces.size(), 7);
  CHECK(hue_clusters(render_mesh(m, o)) == 1);
}

TEST_CASE("textured render shows both colours of a checkerboard", "[render]") {
  const Mesh quad = textured_quad();
  const Image tex = checkerboard(64, 8);
  RenderOptions o;
  o.width = o.height = 128;
  o.color = ColorMode::Textured;
  o.texture = &tex;
  const Image img = render_mesh(quad, o);
  const int dark = count_pixels(img, 0.2f);
  int bright = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) bright += !is_white(img, x, y) && img.at(x, y, 0) > 0.6f;
  CHECK(dark > 1000);
  CHECK(bright > 1000);
  // The dark squares come from the texture: the untextured quad has none.
  o.color = ColorMode::Shaded;
  CHECK(count_pixels(render_mesh(quad, o), 0.2f) == 0);
}

TEST_CASE("a texture is wrapped per axis as the material asks", "[render]") {
  Mesh quad = textured_quad();
  quad.uvs = {{0, 0}, {2, 0}, {2, 1}, {0, 1}};  // two tiles along u, one along v
  Image tex(8, 8, 3, 1.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 3; ++c) tex.at(x, y, c) = 0.0f;  // dark left half
  RenderOptions o;
  o.width = o.height = 128;
  o.color = ColorMode::Textured;
  o.texture = &tex;
  const Image repeated = render_mesh(quad, o);  // glTF's default
  o.texture_wrap = {Wrap::Clamp, Wrap::Clamp};
  const Image clamped = render_mesh(quad, o);
  o.texture_wrap = {Wrap::Mirror, Wrap::Clamp};
  const Image mirrored = render_mesh(quad, o);
  // Repeated and mirrored, half the quad is dark; clamped, the second tile is the right edge's
  // bright texels, so a quarter is.
  const int dark_repeated = count_pixels(repeated, 0.2f), dark_clamped = count_pixels(clamped, 0.2f);
  CHECK(dark_repeated > 1000);
  CHECK(dark_clamped < 0.6 * dark_repeated);
  CHECK(count_pixels(mirrored, 0.2f) == Approx(dark_repeated).epsilon(0.1));  // one blurred edge fewer
  // Mirrored, the second tile's dark half is on its right, not its left.
  CHECK(mirrored.pixels != repeated.pixels);
}

TEST_CASE("faces of several materials read each its own texture or colour", "[render]") {
  // The quad's lower-right triangle reads a red image, its upper-left one a material with no
  // image but a blue colour: a multi-material model drawn whole, not in its first texture.
  const Mesh quad = textured_quad();
  Image red(8, 8, 3, 0.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) red.at(x, y, 0) = 0.9f;
  RenderOptions o;
  o.width = o.height = 128;
  o.perspective = false;
  o.color = ColorMode::Textured;
  o.materials = {{&red, {}, {1, 1, 1}}, {nullptr, {}, {0.1, 0.2, 0.9}}};
  o.face_material = {0, 1};
  const Image img = render_mesh(quad, o);
  CHECK(chroma(img, 96, 96).x > 0.6);  // image y runs down: the lower-right triangle
  CHECK(chroma(img, 32, 32).z > 0.6);
  CHECK(chroma(img, 32, 32).x < 0.2);
  // One material for both faces is the single-texture render.
  o.materials = {{&red, {}, {1, 1, 1}}};
  o.face_material = {0, 0};
  const Image one = render_mesh(quad, o);
  RenderOptions plain = o;
  plain.materials.clear();
  plain.face_material.clear();
  plain.texture = &red;
  CHECK(render_mesh(quad, plain).pixels == one.pixels);
  // Materials that do not match the faces are refused.
  o.face_material = {0};
  CHECK_THROWS_AS(render_mesh(quad, o), InputError);
  o.face_material = {0, 1};
  CHECK_THROWS_WITH(render_mesh(quad, o), Catch::Contains("out of range"));
}

TEST_CASE("a transparent texture shows the plain surface beneath it", "[render]") {
  // Black texels with alpha 0 used to render black: the alpha channel was ignored.
  const Mesh quad = textured_quad();
  Image tex(8, 8, 4, 0.0f);  // RGBA, black and fully transparent
  RenderOptions o;
  o.width = o.height = 96;
  o.color = ColorMode::Textured;
  o.texture = &tex;
  const Image clear = render_mesh(quad, o);
  o.color = ColorMode::Shaded;
  const Image plain = render_mesh(quad, o);
  CHECK(clear.pixels == plain.pixels);
  // Opaque black is black; grey with alpha (two channels) follows the same rule.
  for (int i = 3; i < static_cast<int>(tex.pixels.size()); i += 4) tex.pixels[i] = 1.0f;
  o.color = ColorMode::Textured;
  CHECK(count_pixels(render_mesh(quad, o), 0.2f) > 1000);
  Image grey(8, 8, 2, 0.0f);
  o.texture = &grey;
  CHECK(render_mesh(quad, o).pixels == plain.pixels);
}

TEST_CASE("a texture's transparent colour does not bleed along its alpha edge", "[render]") {
  // Left half opaque blue, right half transparent red: filtered straight, the red bled into a
  // purple fringe at the edge; premultiplied, the edge blends blue into the grey surface.
  const Mesh quad = textured_quad();
  Image tex(8, 8, 4, 0.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      tex.at(x, y, 0) = x < 4 ? 0.0f : 1.0f;
      tex.at(x, y, 2) = x < 4 ? 1.0f : 0.0f;
      tex.at(x, y, 3) = x < 4 ? 1.0f : 0.0f;
    }
  RenderOptions o;
  o.width = o.height = 96;
  o.color = ColorMode::Textured;
  o.texture = &tex;
  const Image img = render_mesh(quad, o);
  int fringe = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (!is_white(img, x, y) && img.at(x, y, 0) > img.at(x, y, 1) + 0.05f) ++fringe;  // more red than green
  CHECK(fringe == 0);
}

TEST_CASE("textured interpolation is perspective-correct", "[render]") {
  // A long strip on the ground (y = 0) receding from the front camera, which looks 15° down:
  // the near end (z = 4) is at the bottom of the image, the far end (z = -4) at the top.
  // u runs along it and the texture is black for u < 1/2, white above. Perspective-correct
  // interpolation puts the switch at the strip's 3D midpoint, which projects well above the
  // middle of the strip's image (the far half is foreshortened); affine interpolation would
  // put it at the middle.
  Mesh strip;
  strip.positions = {{-0.2, 0, 4}, {0.2, 0, 4}, {0.2, 0, -4}, {-0.2, 0, -4}};
  strip.faces = {{0, 1, 2}, {0, 2, 3}};
  strip.uvs = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  strip.face_uvs = strip.faces;
  Image tex(64, 4, 3, 1.0f);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 32; ++x)
      for (int c = 0; c < 3; ++c) tex.at(x, y, c) = 0.0f;
  RenderOptions o;
  o.width = 64;
  o.height = 256;
  o.supersample = 1;
  o.transparent = true;  // alpha marks the strip
  o.color = ColorMode::Textured;
  o.texture = &tex;
  const Image img = render_mesh(strip, o);
  int top = -1, bottom = -1, edge = -1;
  for (int y = 0; y < img.height; ++y)
    if (img.at(32, y, 3) > 0.5f) {
      if (top < 0) top = y;
      bottom = y;
    }
  REQUIRE(top >= 0);
  REQUIRE(bottom - top > 100);
  for (int y = top; y <= bottom && edge < 0; ++y)
    if (img.at(32, y, 0) < 0.1f) edge = y;  // first dark row from the far end
  REQUIRE(edge > top);
  // Projecting the strip's ends and midpoint with this camera puts the midpoint 12% of the
  // strip's height above the middle.
  const double middle = 0.5 * (top + bottom);
  CHECK(edge < middle - 0.08 * (bottom - top));
  CHECK(edge > middle - 0.16 * (bottom - top));
}

TEST_CASE("wireframe overlay draws dark edges", "[render]") {
  RenderOptions o;
  o.width = o.height = 200;
  const Mesh m = make_builtin("sphere");
  const int plain = count_pixels(render_mesh(m, o), 0.3f);
  o.wireframe = true;
  const int wired = count_pixels(render_mesh(m, o), 0.3f);
  CHECK(wired > plain + 500);
}

TEST_CASE("rendering is deterministic for any thread count", "[render]") {
  const Mesh m = make_builtin("creature");
  RenderOptions o;
  o.views = 4;
  o.width = 320;
  o.height = 80;
  o.wireframe = true;
  Image one, two;
  tbb::task_arena(1).execute([&] { one = render_mesh(m, o); });
  tbb::task_arena(2).execute([&] { two = render_mesh(m, o); });
  CHECK(one.pixels == two.pixels);
}

TEST_CASE("UV layout draws charts on white with dark boundaries", "[render]") {
  const Mesh m = two_chart_sphere();
  const Image img = render_uv_layout(m, 256, 128);
  REQUIRE(img.width == 256);
  REQUIRE(img.height == 128);
  REQUIRE(img.channels == 3);
  CHECK(is_white(img, 0, 0));
  CHECK(is_white(img, 255, 127));
  // The two discs (centres at u = 1/4 and 3/4, v = 1/2) are filled in different colours.
  const int w = 256, h = 128;
  const int side = std::min(w, h);
  auto pixel_of = [&](double u, double v) {
    const double margin = 0.03 * side;
    const double scale = (side - 2 * margin);
    return std::pair<int, int>{static_cast<int>(0.5 * (w - scale) + u * scale),
                               static_cast<int>(0.5 * (h - scale) + (1 - v) * scale)};
  };
  const auto [x0, y0] = pixel_of(0.25, 0.6);
  const auto [x1, y1] = pixel_of(0.75, 0.6);
  CHECK_FALSE(is_white(img, x0, y0));
  CHECK_FALSE(is_white(img, x1, y1));
  const Vec3d c0 = chroma(img, x0, y0), c1 = chroma(img, x1, y1);
  CHECK(norm(c0 - c1) > 0.05);
  CHECK(hue_clusters(img) == 2);
  // Chart boundaries (the discs' rims) are dark.
  CHECK(count_pixels(img, 0.3f) > 100);
}

TEST_CASE("UVs that leave the unit square are drawn against the texture's tiles", "[render]") {
  // Shifted by 1.5 in u the discs span u 1.5..2.5: the view is the tiles u 1..3, v 0..1, with the
  // tile border u = 2 drawn grey between the discs (it was a bare layout, no texture in sight).
  Mesh m = two_chart_sphere();
  for (Vec2d& p : m.uvs) p.x += 1.5;
  const int w = 256, h = 128;
  const Image img = render_uv_layout(m, w, h);
  const double margin = 0.03 * h, scale = std::min((w - 2 * margin) / 2, h - 2 * margin);
  const double ox = 0.5 * (w - 2 * scale), oy = 0.5 * (h - scale);
  auto pixel_of = [&](double u, double v) {
    return std::pair<int, int>{static_cast<int>(std::lround(ox + (u - 1) * scale)),
                               static_cast<int>(oy + (1 - v) * scale)};
  };
  for (const double v : {0.1, 0.9}) {
    const auto [x, y] = pixel_of(2.0, v);
    INFO(x << "," << y);
    CHECK(img.at(x, y, 0) < 0.95f);
    CHECK(img.at(x, y, 0) > 0.4f);
    CHECK(img.at(x, y, 0) == Approx(img.at(x, y, 2)).margin(0.02));  // grey, not a chart colour
  }
  // The left tile is empty: white inside it.
  const auto [xl, yl] = pixel_of(1.2, 0.5);
  CHECK(is_white(img, xl, yl));
}

TEST_CASE("the UV layout of a non-square texture is drawn in the texture's proportions", "[render]") {
  const Mesh m = two_chart_sphere();  // discs centred at u = 1/4 and 3/4
  const int w = 256, h = 128;
  // Aspect 2: the unit square is a 2:1 rectangle filling the picture but for the margin.
  const Image img = render_uv_layout(m, w, h, 2.0);
  const double margin = 0.03 * h, sy = h - 2 * margin, sx = 2 * sy, ox = 0.5 * (w - sx);
  auto pixel_of = [&](double u, double v) {
    return std::pair<int, int>{static_cast<int>(ox + u * sx), static_cast<int>(margin + (1 - v) * sy)};
  };
  // The discs are stretched sideways with the texture: their centres and points 0.2 to
  // either side in u are covered, which a square drawing (u 0.2 is ~half the width
  // of a disc there) would leave white at the ends.
  for (const double cu : {0.25, 0.75})
    for (const double du : {-0.15, 0.0, 0.15}) {
      const auto [x, y] = pixel_of(cu + du, 0.5);
      CHECK_FALSE(is_white(img, x, y));
    }
  // Outside the frame, left and right, white.
  CHECK(is_white(img, static_cast<int>(ox) - 2, h / 2));
  CHECK(is_white(img, static_cast<int>(ox + sx) + 2, h / 2));
  CHECK_THROWS_AS(render_uv_layout(m, w, h, 0.0), InputError);
}

TEST_CASE("the UV layout is drawn the same for any thread count", "[render]") {
  // Bands of rows are drawn in parallel; a band shorter than the others at the bottom and
  // segments crossing band borders must blend exactly as in one pass.
  const Mesh m = make_builtin("sphere");
  AtlasOptions ao;
  ao.pack.width = ao.pack.height = 256;
  const Atlas atlas = build_atlas(m, ao);
  const Mesh uv = atlas.apply_to(m);
  Image one, two;
  tbb::task_arena(1).execute([&] { one = render_uv_layout(uv, 301, 203); });
  tbb::task_arena(2).execute([&] { two = render_uv_layout(uv, 301, 203); });
  CHECK(one.pixels == two.pixels);
  CHECK(count_pixels(one, 0.3f) > 500);  // boundaries drawn
}

TEST_CASE("render input errors", "[render]") {
  const Mesh sphere = make_builtin("sphere");
  RenderOptions o;
  o.views = 0;
  CHECK_THROWS_AS(render_mesh(sphere, o), InputError);
  o.views = 9;
  CHECK_THROWS_AS(render_mesh(sphere, o), InputError);
  o = {};
  o.width = 0;
  CHECK_THROWS_AS(render_mesh(sphere, o), InputError);
  o = {};
  o.color = ColorMode::Charts;  // no groups, no UVs
  CHECK_THROWS_AS(render_mesh(sphere, o), InputError);
  o.color = ColorMode::Textured;  // no UVs, no texture
  CHECK_THROWS_AS(render_mesh(sphere, o), InputError);
  CHECK_THROWS_AS(render_mesh(textured_quad(), o), InputError);  // UVs but no texture
  CHECK_THROWS_AS(render_uv_layout(sphere, 64, 64), InputError);
  CHECK_THROWS_AS(render_mesh(Mesh{}, RenderOptions{}), InputError);
  Mesh bad = textured_quad();
  bad.faces[1][2] = 17;
  CHECK_THROWS_AS(render_mesh(bad, RenderOptions{}), InputError);
}

TEST_CASE("isocharts render writes the image and reports it", "[render][cli]") {
  const fs::path dir = fs::temp_directory_path() / ("isocharts_render_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "views.png").string();
  const std::string cli = ISOCHARTS_CLI;
  auto run = [&](const std::string& args) {
    const int status =
        std::system((cli + " " + args + " > " + (dir / "stdout.txt").string() + " 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  CHECK(run("render builtin:sphere -o " + out + " --views 2 --width 120 --height 50 --json") == 0);
  const Image img = read_image(out);
  CHECK(img.width == 120);
  CHECK(img.height == 50);
  // Bad input exits with 2: a missing texture, an unknown built-in, views out of range.
  CHECK(run("render builtin:sphere -o " + out + " --texture " + (dir / "none.png").string()) == 2);
  CHECK(run("render builtin:nothing -o " + out) == 2);
  CHECK(run("render builtin:sphere -o " + out + " --views 9") == 2);
  CHECK(run("render builtin:sphere --uv-layout -o " + out) == 2);  // no UVs
  CHECK(run("render builtin:sphere -o " + out + " --up w") == 2);
  // --up turns the views: the creature (y up) seen with z as up is another picture.
  CHECK(run("render builtin:creature -o " + out + " --views 1 --width 80 --height 80") == 0);
  const Image y_up = read_image(out);
  CHECK(run("render builtin:creature -o " + out + " --views 1 --width 80 --height 80 --up z") == 0);
  const Image z_up = read_image(out);
  CHECK(z_up.width == y_up.width);
  CHECK(z_up.pixels != y_up.pixels);
  fs::remove_all(dir);
}
