// Tests of the synth module: exemplar input and pyramid, neighbourhood taps across seams,
// determinism over thread counts, quality figures, and the CLI's error handling.

#include "synth/synth.h"

#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "isochart/error.h"
#include "isochart/image.h"
#include "mcgim/mcgim.h"
#include "mcgim/synthetic_atlases.h"
#include "synth/exemplar.h"

namespace fs = std::filesystem;
using isochart::Image;
using isochart::Vec3d;

namespace {

struct TempDir {
  fs::path dir;
  explicit TempDir(const std::string& name)
      : dir(fs::temp_directory_path() / ("isocharts_synth_" + name + "_" + std::to_string(::getpid()))) {
    fs::create_directories(dir);
  }
  ~TempDir() { fs::remove_all(dir); }
  std::string operator/(const std::string& f) const { return (dir / f).string(); }
  int run(const std::string& args) const {
    const std::string cmd = std::string(ISOCHARTS_CLI) + " " + args + " > " + (dir / "stdout.txt").string() +
                            " 2> " + (dir / "stderr.txt").string();
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string stderr_text() const {
    std::ifstream in(dir / "stderr.txt");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
};

double channel_mean(const Image& img, int c) {
  double s = 0;
  for (int i = 0; i < img.width * img.height; ++i) s += img.pixels[i * img.channels + c];
  return s / (img.width * img.height);
}

// A small pyramid on the hand-made cube atlas (six charts, sharp creases at every seam).
std::vector<mcgim::Level> cube_pyramid(const isochart::Mesh& atlas, std::vector<std::array<int, 2>> sizes) {
  mcgim::PyramidOptions po;
  po.sizes = std::move(sizes);
  po.level.optimize = false;
  return mcgim::build_pyramid(atlas, po);
}

}  // namespace

TEST_CASE("exemplar pyramid levels keep the colours and shrink by the texel factor", "[synth]") {
  const Image ex = synth::make_exemplar("noise", 64, 3);
  REQUIRE(ex.width == 64);
  REQUIRE(ex.channels == 3);
  const auto levels = synth::exemplar_pyramid(ex, {0.5, 1.0, 2.0, 4.0, 100.0});
  REQUIRE(levels.size() == 5);
  CHECK(levels[0].image.width == 128);
  CHECK(levels[1].image.width == 64);
  CHECK(levels[2].image.width == 32);
  CHECK(levels[3].image.width == 16);
  CHECK(levels[4].image.width == 4);  // never below 4×4
  CHECK(levels[4].actual_factor == Approx(16.0));
  for (const auto& l : levels)
    for (int c = 0; c < 3; ++c) CHECK(channel_mean(l.image, c) == Approx(channel_mean(ex, c)).margin(0.02));
  // Same factor 1: the exemplar itself.
  CHECK(levels[1].image.pixels == ex.pixels);
  // Shrinking smooths: less variance at the coarser level.
  auto variance = [](const Image& img) {
    const double mu = channel_mean(img, 0);
    double v = 0;
    for (int i = 0; i < img.width * img.height; ++i) v += std::pow(img.pixels[i * 3] - mu, 2);
    return v / (img.width * img.height);
  };
  CHECK(variance(levels[3].image) < variance(levels[1].image));
  // Deterministic and distinct per name.
  CHECK(synth::make_exemplar("noise", 64, 3).pixels == ex.pixels);
  for (const auto& name : synth::exemplar_names()) CHECK(synth::make_exemplar(name, 32).width == 32);
  CHECK(synth::make_exemplar("bricks", 32).pixels != synth::make_exemplar("cells", 32).pixels);
}

TEST_CASE("bad exemplars are InputErrors", "[synth]") {
  const TempDir tmp("bad_exemplar");
  CHECK_THROWS_AS(synth::load_exemplar(tmp / "missing.png"), isochart::InputError);
  Image rgba(8, 8, 4, 1.0f);
  rgba.at(3, 2, 3) = 0.5f;
  isochart::write_image(tmp / "transparent.png", rgba);
  CHECK_THROWS_WITH(synth::load_exemplar(tmp / "transparent.png"), Catch::Contains("transparent"));
  isochart::write_image(tmp / "tiny.png", Image(2, 2, 3, 0.5f));
  CHECK_THROWS_AS(synth::load_exemplar(tmp / "tiny.png"), isochart::InputError);
  CHECK_THROWS_AS(synth::to_rgb_exemplar(Image(8, 8, 5, 0.5f), "five"), isochart::InputError);
  CHECK_THROWS_AS(synth::make_exemplar("plaid"), isochart::InputError);
  // Greyscale and opaque RGBA are accepted and become RGB.
  Image grey(8, 8, 1, 0.25f);
  isochart::write_image(tmp / "grey.png", grey);
  const Image g = synth::load_exemplar(tmp / "grey.png");
  CHECK(g.channels == 3);
  CHECK(g.at(4, 4, 2) == Approx(0.25).margin(0.003));
  isochart::write_image(tmp / "opaque.png", Image(8, 8, 4, 1.0f));
  CHECK(synth::load_exemplar(tmp / "opaque.png").channels == 3);
  // Named channels are read by name: a fourth channel that is not "A" is no alpha, and B, G, R
  // order keeps red red.
  Image named(8, 8, 4, 0.0f);
  named.channel_names = {"B", "G", "R", "Z"};
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) named.at(x, y, 2) = 0.75f, named.at(x, y, 3) = 0.1f;
  const Image n = synth::to_rgb_exemplar(named, "named");
  CHECK(n.at(1, 1, 0) == 0.75f);
  CHECK(n.at(1, 1, 2) == 0.0f);
  // With R, G and B named, further channels (a renderer's depth, normals) are left out rather
  // than refusing the image for its channel count.
  Image passes(8, 8, 6, 0.25f);
  passes.channel_names = {"Z", "R", "G", "B", "A", "N.x"};
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) passes.at(x, y, 4) = 1.0f, passes.at(x, y, 1) = 0.5f;
  const Image p = synth::to_rgb_exemplar(passes, "passes.exr");
  CHECK(p.channels == 3);
  CHECK(p.at(2, 3, 0) == 0.5f);
  CHECK(p.at(2, 3, 1) == 0.25f);
  Image two(8, 8, 2, 0.5f);
  two.channel_names = {"U", "V"};
  CHECK_THROWS_WITH(synth::to_rgb_exemplar(two, "uv.exr"), Catch::Contains("2 colour channels (U,V)"));
  // Values outside [0, 1] (an HDR EXR) are clipped and counted, so the CLI can warn: such an
  // exemplar came out all white without a word.
  Image hdr(8, 8, 3, 0.5f);
  hdr.at(1, 1, 0) = 20.0f;
  hdr.at(2, 1, 2) = -1.0f;
  long long clipped = -1;
  const Image h = synth::to_rgb_exemplar(hdr, "hdr", &clipped);
  CHECK(clipped == 2);
  CHECK(h.at(1, 1, 0) == 1.0f);
  CHECK(h.at(2, 1, 2) == 0.0f);
  isochart::write_image(tmp / "hdr.exr", hdr);
  CHECK(tmp.run("--json synth builtin:sphere --levels 64,32 --exemplar " + tmp / "hdr.exr" + " -o " +
                tmp / "hdr.glb") == 0);
  CHECK_THAT(tmp.stderr_text(),
             Catch::Contains("hdr.exr: 2 colour values (1.04 %) lie outside [0, 1] and are clipped"));
  synth::to_rgb_exemplar(Image(8, 8, 3, 1.0f), "white", &clipped);
  CHECK(clipped == 0);
  // The CLI turns them into exit code 2 naming the file.
  CHECK(tmp.run("synth builtin:sphere --exemplar " + tmp / "transparent.png" + " -o " + tmp / "out.glb") == 2);
  CHECK(tmp.stderr_text().find("transparent.png") != std::string::npos);
  CHECK(tmp.run("synth builtin:sphere --exemplar " + tmp / "missing.png" + " -o " + tmp / "out.glb") == 2);
  CHECK(tmp.run("synth builtin:sphere --exemplar builtin:plaid -o " + tmp / "out.glb") == 2);
  // A direction that names none would quietly mean the computed field (or nothing, for NaN).
  CHECK(tmp.run("synth builtin:sphere --direction 0,0,0 -o " + tmp / "out.glb") == 2);
  CHECK(tmp.stderr_text().find("--direction") != std::string::npos);
  CHECK(tmp.run("synth builtin:sphere --direction nan,0,1 -o " + tmp / "out.glb") == 2);
  CHECK(tmp.run("synth builtin:sphere --direction 1,inf,1 -o " + tmp / "out.glb") == 2);
  // Tiny and huge components name a direction too (their squares underflowed or overflowed).
  CHECK(tmp.run("-q synth builtin:sphere --levels 48,24 --atlas-size 64 --direction 1e-300,0,0 -o " +
                tmp / "tiny.glb") == 0);
  CHECK(tmp.run("-q synth builtin:sphere --levels 48,24 --atlas-size 64 --direction 1e308,1e308,0 -o " +
                tmp / "huge.glb") == 0);
  CHECK(!fs::exists(tmp / "out.glb"));
}

TEST_CASE("a tap crossing a chart edge lands at the right 3-D place", "[synth]") {
  // Cube [-1,1]³ with one chart per face: every seam is a 90° crease, so the right place of a
  // tap that leaves a face is found by unfolding the neighbour face about the shared edge.
  const isochart::Mesh atlas = mcgim_test::cube_atlas(8);
  mcgim::LevelOptions lo;
  lo.width = lo.height = 64;
  lo.optimize = false;
  const mcgim::Level level = mcgim::build_level(atlas, lo);
  const mcgim::GeometryImage& g = level.image;
  std::vector<Vec3d> dirs(g.width * g.height, Vec3d{0, 0, 0});
  for (int s = 0; s < g.width * g.height; ++s) dirs[s] = std::fabs(g.normals[s].x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  const synth::LevelGeometry geo(level, dirs);
  const double texel = level.stats.texel_size;
  int crossed = 0;
  double worst = 0;
  for (int s = 0; s < g.width * g.height; ++s) {
    if (!g.defined(s)) continue;
    const Vec3d p = g.positions[s];
    // Samples of the face z = +1, away from the other edges, near the edge x = +1.
    if (std::fabs(p.z - 1) > 1e-9 || p.x > 1 - 1e-6 || std::fabs(p.y) > 0.6 || p.x < 1 - 2 * texel) continue;
    const double along = 3 * texel;  // leave the face in +x by about 2–3 texels
    const synth::Tap t = geo.locate(s, along * isochart::dot(geo.t1(s), Vec3d{1, 0, 0}),
                                    along * isochart::dot(geo.t2(s), Vec3d{1, 0, 0}));
    REQUIRE(t.valid());
    if (!t.crossed) continue;
    ++crossed;
    // Unfolded: the part beyond x = 1 goes down the side face x = +1.
    const double beyond = along - (1 - p.x);
    const Vec3d expected{1, p.y, 1 - beyond};
    const Vec3d got = geo.position(t);
    worst = std::max(worst, isochart::norm(got - expected));
    CHECK(std::fabs(got.x - 1) < 0.3 * texel);  // on the side face
  }
  CHECK(crossed >= 4);
  CHECK(worst < 0.75 * texel);
  // Inside a chart a tap is a plain bilinear lookup at the offset position.
  for (int s = 0; s < g.width * g.height; ++s) {
    if (!g.defined(s) || g.normals[s].z < 0.99 || std::fabs(g.positions[s].x) > 0.5 || std::fabs(g.positions[s].y) > 0.5)
      continue;
    const synth::Tap t = geo.locate(s, texel, 0);
    CHECK_FALSE(t.crossed);
    CHECK(isochart::norm(geo.position(t) - (g.positions[s] + geo.t1(s) * texel)) < 0.05 * texel);
    break;
  }
}

TEST_CASE("synthesis is identical for 1 and 2 threads and keeps zipper groups one colour", "[synth]") {
  const isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  const Image ex = synth::make_exemplar("cells", 48);
  synth::SynthOptions so;
  so.seed = 7;
  synth::SynthResult a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = synth::synthesize(atlas, pyramid, ex, so);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    b = synth::synthesize(atlas, pyramid, ex, so);
  }
  REQUIRE(a.texture.pixels.size() == b.texture.pixels.size());
  CHECK(a.texture.pixels == b.texture.pixels);
  CHECK(a.group_colors == b.group_colors);
  CHECK(a.match_error == b.match_error);
  CHECK(a.seam_error == b.seam_error);
  // Every synthesized colour is an exemplar colour (no blending in the output).
  const auto& g = pyramid[0].image;
  const auto lvl = synth::resample_exemplar(ex, a.levels[0].exemplar_factor);
  REQUIRE(lvl.image.width == a.levels[0].exemplar_width);
  int checked = 0;
  for (int s = 0; s < g.width * g.height && checked < 50; s += 37) {
    if (!g.defined(s)) continue;
    const auto& c = a.group_colors[0][g.group[s]];
    bool found = false;
    for (int i = 0; i < a.levels[0].exemplar_width * a.levels[0].exemplar_height && !found; ++i) {
      found = lvl.image.pixels[i * 3] == c[0] && lvl.image.pixels[i * 3 + 1] == c[1] && lvl.image.pixels[i * 3 + 2] == c[2];
    }
    CHECK(found);
    ++checked;
  }
  // Another seed gives another texture.
  so.seed = 8;
  CHECK(synth::synthesize(atlas, pyramid, ex, so).texture.pixels != a.texture.pixels);
  CHECK(a.seam_pairs > 0);
  CHECK(a.texel_scale_spread < 0.2);  // the cube's charts are isometric
}

TEST_CASE("quality figures on constructed cases", "[synth]") {
  const isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  // A constant exemplar: every neighbourhood matches exactly and no seam shows.
  const Image flat(16, 16, 3, 0.4f);
  const synth::SynthResult r = synth::synthesize(atlas, pyramid, flat);
  CHECK(r.match_error == Approx(0.0).margin(1e-9));
  CHECK(r.seam_error == 0.0);
  CHECK(std::isfinite(r.seam_error));
  for (float v : r.texture.pixels) CHECK(v == Approx(0.4f));
  // A structured exemplar: matches are imperfect but far better than chance, seams near 1.
  // The exemplar spans one face (2 units), about 3 exemplar pixels per texel.
  synth::SynthOptions so;
  so.scale = 32;
  const synth::SynthResult s = synth::synthesize(atlas, pyramid, synth::make_exemplar("weave", 64), so);
  CHECK(s.match_error > 0.0);
  CHECK(s.match_error < 1.0);
  CHECK(s.seam_error > 0.0);
  CHECK(s.seam_error < 1.6);
  // Transfer back onto the atlas covers the whole image (gutter filled) with texture colours.
  const Image t = synth::transfer_to_atlas(atlas, pyramid[0], s.texture, 64);
  CHECK(t.width == 64);
  double lo = 1, hi = 0;
  for (float v : t.pixels) lo = std::min<double>(lo, v), hi = std::max<double>(hi, v);
  CHECK(hi > lo);
  // Bad options are InputErrors.
  synth::SynthOptions bad;
  bad.neighborhood = 4;
  CHECK_THROWS_AS(synth::synthesize(atlas, pyramid, flat, bad), isochart::InputError);
  CHECK_THROWS_AS(synth::synthesize(atlas, {}, flat), isochart::InputError);
}

TEST_CASE("isocharts synth writes textured meshes and its report", "[synth][cli]") {
  const TempDir tmp("cli");
  REQUIRE(tmp.run("synth builtin:sphere --levels 48,24 --atlas-size 128 --json -o " + tmp / "s.glb") == 0);
  std::ifstream in(tmp / "stdout.txt");
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* key : {"seam_error", "match_error", "texel_scale_spread", "seconds", "start_level",
                          "correlation_length", "coarse_footprint", "smoothness", "direction_symmetry"})
    CHECK(j.contains(key));
  // The default exemplar (procedural bricks: rows across the image) starts at the finest level.
  CHECK(j["start_level"] == 0);
  CHECK(j["direction_symmetry"] == 2);
  // The report lists every file written, and nothing else.
  std::set<std::string> listed, written;
  for (const auto& f : j["outputs"]) listed.insert(fs::path(f.get<std::string>()).filename().string());
  for (const auto& e : fs::directory_iterator(tmp.dir))
    if (e.path().filename() != "stdout.txt" && e.path().filename() != "stderr.txt")
      written.insert(e.path().filename().string());
  CHECK(listed == written);
  for (const char* f :
       {"s.glb", "s.obj", "s.mtl", "s.png", "s_mcgim.glb", "s_mcgim.obj", "s_mcgim.mtl", "s_mcgim.png"})
    CHECK(listed.count(f) == 1);
  const Image tex = isochart::read_image(tmp / "s.png");
  CHECK(tex.width == 128);
  CHECK(tmp.run("exemplar bricks --size 32 -o " + tmp / "b.png") == 0);
  CHECK(isochart::read_image(tmp / "b.png").width == 32);
  // The output named keeps the case of its extension (-o U.GLB wrote U.glb).
  REQUIRE(tmp.run("-q synth builtin:sphere --levels 48,24 --atlas-size 64 -o " + tmp / "U.GLB") == 0);
  for (const char* f : {"U.GLB", "U.obj", "U_mcgim.GLB", "U_mcgim.obj"}) CHECK(fs::exists(tmp / f));
  CHECK(!fs::exists(tmp / "U.glb"));
}

TEST_CASE("a tap off the mesh boundary is dropped", "[synth]") {
  // A flat unit square, one chart: taps that leave it have nowhere to go.
  isochart::Mesh m;
  const int n = 8;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      m.positions.push_back({double(i) / n, double(j) / n, 0});
      m.uvs.push_back({0.05 + 0.9 * i / n, 0.05 + 0.9 * j / n});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.faces.push_back({a, b, c});
      m.faces.push_back({a, c, d});
      m.face_uvs.push_back({a, b, c});
      m.face_uvs.push_back({a, c, d});
      m.face_groups.push_back(0);
      m.face_groups.push_back(0);
    }
  mcgim::LevelOptions lo;
  lo.width = lo.height = 32;
  lo.optimize = false;
  const mcgim::Level level = mcgim::build_level(m, lo);
  const mcgim::GeometryImage& g = level.image;
  const synth::LevelGeometry geo(level, std::vector<Vec3d>(g.width * g.height, Vec3d{1, 0, 0}));
  const double texel = level.stats.texel_size;
  int edge = 0;
  for (int s = 0; s < g.width * g.height; ++s) {
    if (!g.defined(s) || g.positions[s].x < 1 - texel || std::fabs(g.positions[s].y - 0.5) > 0.3) continue;
    ++edge;
    CHECK_FALSE(geo.locate(s, 3 * texel, 0).valid());  // beyond x = 1
    const synth::Tap inward = geo.locate(s, -3 * texel, 0);
    REQUIRE(inward.valid());
    // Boundary samples sit on the boundary edge (not on the grid), so the one-sided Jacobian
    // there is off by up to half a texel.
    CHECK(geo.position(inward).x == Approx(g.positions[s].x - 3 * texel).margin(0.6 * texel));
  }
  CHECK(edge > 0);
}

TEST_CASE("synthesis copies coherent exemplar patches", "[synth]") {
  // Coordinate upsampling and coherent candidates keep neighbouring samples on neighbouring
  // exemplar pixels (patches), which is what keeps a structured exemplar legible.
  const isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  synth::SynthOptions so;
  so.scale = 32;
  const synth::SynthResult r = synth::synthesize(atlas, pyramid, synth::make_exemplar("bricks", 64), so);
  const auto& g = pyramid[0].image;
  const int w = r.levels[0].exemplar_width;
  REQUIRE(r.exemplar_pixels.size() == static_cast<std::size_t>(g.num_groups));
  int pairs = 0, coherent = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x + 1 < g.width; ++x) {
      const int s = g.index(x, y), t = g.index(x + 1, y);
      if (!g.defined(s) || !g.defined(t) || g.chart[s] != g.chart[t]) continue;
      const int a = r.exemplar_pixels[g.group[s]], b = r.exemplar_pixels[g.group[t]];
      REQUIRE(a >= 0);
      REQUIRE(b >= 0);
      ++pairs;
      // One texel is about one exemplar pixel here: neighbours of a patch are ≤ 2 pixels apart.
      if (std::abs(a % w - b % w) <= 2 && std::abs(a / w - b / w) <= 2) ++coherent;
    }
  REQUIRE(pairs > 500);
  // Independent picks would land that close with probability 25 / 21² ≈ 0.06 (the finest
  // exemplar level is 21×21 here); measured 0.63.
  REQUIRE(r.levels[0].exemplar_width * r.levels[0].exemplar_height < 30 * 30);
  CHECK(coherent > 0.5 * pairs);
  CHECK(r.seam_error < 1.6);
  // The 24² level has far fewer samples than min_level_samples: reported, not synthesized.
  CHECK(r.levels[1].width == 24);
  CHECK(r.levels[1].groups == 0);
  CHECK(r.group_colors[1].empty());
  so.min_level_samples = 1;
  so.start_level = 1;
  const synth::SynthResult all = synth::synthesize(atlas, pyramid, synth::make_exemplar("bricks", 64), so);
  CHECK(all.levels[1].groups > 0);
  CHECK(all.group_colors[1].size() == static_cast<std::size_t>(pyramid[1].image.num_groups));
}

TEST_CASE("correlation length measures how far the exemplar's structure reaches", "[synth]") {
  // A checkerboard of 4-pixel squares: along x the normalized autocorrelation is about
  // 1 − k/2 (0.49 at k = 1, 0.03 at k = 2), along a diagonal its square: first ≤ 0.1 at
  // k = 2 on every axis, i.e. 2√2 pixels on the diagonals.
  Image checker(64, 64, 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) checker.at(x, y, c) = ((x / 4 + y / 4) % 2) ? 0.9f : 0.1f;
  CHECK(synth::correlation_length(checker) == Approx(2 * std::sqrt(2.0)));
  CHECK(synth::correlation_length(checker, 0.6) == Approx(std::sqrt(2.0)));
  const auto axes = synth::correlation_lengths(checker);
  CHECK(axes[0] == 2.0);
  CHECK(axes[1] == 2.0);
  CHECK(axes[3] == Approx(2 * std::sqrt(2.0)));
  // Horizontal stripes never decorrelate along x: half the exemplar.
  Image stripes(64, 48, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) stripes.at(x, y, c) = (y / 3) % 2 ? 0.8f : 0.2f;
  CHECK(synth::correlation_length(stripes) == Approx(24.0));
  CHECK(synth::correlation_length(Image(16, 16, 3, 0.5f)) == 0.0);
  // The procedural exemplars: rows of bricks reach across, cells and noise do not.
  CHECK(synth::correlation_length(synth::make_exemplar("bricks", 64)) >
        3 * synth::correlation_length(synth::make_exemplar("cells", 64)));
}

TEST_CASE("the automatic start level follows the exemplar's correlation length and smoothness", "[synth]") {
  const isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  synth::SynthOptions so;
  so.scale = 16;
  so.min_level_samples = 1;  // both levels allowed
  // Smooth blobs (period 40 pixels), sharp 4-pixel checks, horizontal stripes.
  Image blobs(80, 80, 3), checker(64, 64, 3), stripes(64, 64, 3);
  for (int y = 0; y < 80; ++y)
    for (int x = 0; x < 80; ++x)
      for (int c = 0; c < 3; ++c)
        blobs.at(x, y, c) = static_cast<float>(0.5 + 0.4 * std::sin(2 * M_PI * (x + 0.5) / 40) *
                                                         std::sin(2 * M_PI * (y + 0.5) / 40));
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) {
        checker.at(x, y, c) = ((x / 4 + y / 4) % 2) ? 0.9f : 0.1f;
        stripes.at(x, y, c) = (y / 3) % 2 ? 0.8f : 0.2f;
      }
  const synth::SynthResult a = synth::synthesize(atlas, pyramid, blobs, so);
  const synth::SynthResult b = synth::synthesize(atlas, pyramid, stripes, so);
  const synth::SynthResult c = synth::synthesize(atlas, pyramid, checker, so);
  // One finest texel is about 2.7 exemplar pixels here; the 24² level's 5×5 footprint is
  // 5·16·0.33 ≈ 27 pixels. The blobs are smooth at 3 pixels (cos(2π·3/40) ≈ 0.89) and
  // decorrelate within about 11: start at 24².
  CHECK(a.smoothness > 0.85);
  CHECK(a.correlation_length < a.coarse_footprint);
  REQUIRE(a.start_level == 1);
  CHECK(a.levels[1].groups > 0);
  CHECK(a.coarse_footprint == Approx(5 * a.levels[1].exemplar_factor));
  // The stripes stay correlated along x for 32 pixels, beyond the footprint: start at 48².
  CHECK(b.correlation_length == Approx(32.0));
  CHECK(b.start_level == 0);
  CHECK(b.levels[1].groups == 0);
  CHECK(b.group_colors[1].empty());
  // The footprint compared is the 24² level's, though synthesis then starts at 48².
  CHECK(b.coarse_footprint == Approx(5 * 16 * pyramid[1].stats.texel_size).epsilon(0.1));
  CHECK(b.coarse_footprint < b.correlation_length);
  // The checks decorrelate within 3 pixels but are sharp at the texel: start at 48².
  CHECK(c.correlation_length == Approx(2 * std::sqrt(2.0)));
  CHECK(c.smoothness < 0.85);
  CHECK(c.start_level == 0);
  // Automatic field symmetry: blobs and checks decorrelate alike along x and y (4-fold), the
  // stripes do not (2-fold).
  CHECK(a.direction_symmetry == 4);
  CHECK(c.direction_symmetry == 4);
  CHECK(b.direction_symmetry == 2);
  // An explicit start level overrides the rule.
  so.start_level = 1;
  CHECK(synth::synthesize(atlas, pyramid, stripes, so).start_level == 1);
  CHECK(synth::exemplar_smoothness(Image(8, 8, 3, 0.3f)) == 1.0);
  // 63 pixel pairs per row, 15 of them across a check edge: (63 − 2·15) / 63.
  CHECK(synth::exemplar_smoothness(checker, 1) == Approx(33.0 / 63));
}

TEST_CASE("an N-symmetric direction field is smoother modulo 360/N degrees", "[synth]") {
  // On a cube a 4-direction field can follow the edges everywhere; a vector field cannot.
  const isochart::Mesh cube = mcgim_test::cube_atlas(6);
  const isochart::Topology topo(cube);
  const auto normals = isochart::vertex_normals(cube);
  // Mean over edges of 1 − cos(N·φ), φ the angle between the two ends' directions after
  // projecting the neighbour into the vertex's tangent plane.
  auto roughness = [&](const std::vector<Vec3d>& d, int sym) {
    double sum = 0;
    long long count = 0;
    for (int i = 0; i < cube.num_vertices(); ++i) {
      const Vec3d b = isochart::cross(normals[i], d[i]);
      for (int j : topo.vertex_neighbors(i)) {
        const Vec3d p = d[j] - normals[i] * isochart::dot(d[j], normals[i]);
        if (isochart::norm(p) < 1e-9) continue;
        sum += 1 - std::cos(sym * std::atan2(isochart::dot(p, b), isochart::dot(p, d[i])));
        ++count;
      }
    }
    return sum / std::max<long long>(1, count);
  };
  const auto d1 = synth::direction_field(cube, {0, 0, 0}, 200, 1);
  const auto d4 = synth::direction_field(cube, {0, 0, 0}, 200, 4);
  REQUIRE(d4.size() == static_cast<std::size_t>(cube.num_vertices()));
  for (int i = 0; i < cube.num_vertices(); ++i) {
    CHECK(isochart::norm(d4[i]) == Approx(1.0));
    CHECK(std::fabs(isochart::dot(d4[i], normals[i])) < 1e-9);
  }
  CHECK(roughness(d4, 4) < 0.5 * roughness(d1, 4));
  CHECK_THROWS_AS(synth::direction_field(cube, {0, 0, 0}, 10, 0), isochart::InputError);
}

TEST_CASE("synthesis with a 2- and 4-direction field is deterministic and seamless", "[synth]") {
  const isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  const Image ex = synth::make_exemplar("weave", 64);
  for (int sym : {2, 4}) {
    synth::SynthOptions so;
    so.scale = 32;
    so.direction_symmetry = sym;
    so.min_level_samples = 1;
    so.start_level = 1;
    synth::SynthResult a, b;
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      a = synth::synthesize(atlas, pyramid, ex, so);
    }
    {
      tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
      b = synth::synthesize(atlas, pyramid, ex, so);
    }
    CHECK(a.texture.pixels == b.texture.pixels);
    CHECK(a.match_error < 1.0);
    CHECK(a.seam_error > 0.0);
    CHECK(a.seam_error < 1.6);
  }
  synth::SynthOptions bad;
  bad.direction_symmetry = -1;
  CHECK_THROWS_AS(synth::synthesize(atlas, pyramid, ex, bad), isochart::InputError);
}

TEST_CASE("the first level's exemplar copy spreads the field's curl instead of shearing", "[synth]") {
  // On a sphere no direction field is integrable: a copy grown breadth-first along the field
  // tears where its fronts meet; the least-squares copy bends smoothly and tears only at the
  // N-direction field's cuts. Counted as neighbour pairs whose exemplar pixels jump.
  const isochart::Mesh atlas = mcgim_test::sphere_atlas(48, 96);
  const auto pyramid = cube_pyramid(atlas, {{96, 96}, {48, 48}});
  const Image ex = synth::make_exemplar("bricks", 128);
  auto jumps = [&](bool relax, int direct_max = 1'100'000) {
    synth::SynthOptions so;
    so.relax_copy_max = direct_max;
    so.pixels_per_texel = 1;
    so.direction_symmetry = 2;
    so.start_level = 0;
    so.coarsest_passes = 0;
    so.relax_copy = relax;
    const synth::SynthResult r = synth::synthesize(atlas, pyramid, ex, so);
    const auto& g = pyramid[0].image;
    const int w = r.levels[0].exemplar_width;
    int pairs = 0, far = 0;
    for (int y = 0; y + 1 < g.height; ++y)
      for (int x = 0; x + 1 < g.width; ++x) {
        const int s = g.index(x, y);
        for (int t : {g.index(x + 1, y), g.index(x, y + 1)}) {
          if (!g.defined(s) || !g.defined(t) || g.chart[s] != g.chart[t]) continue;
          const int a = r.exemplar_pixels[g.group[s]], b = r.exemplar_pixels[g.group[t]];
          REQUIRE(a >= 0);
          REQUIRE(b >= 0);
          ++pairs;
          if (std::abs(a % w - b % w) > 3 || std::abs(a / w - b / w) > 3) ++far;
        }
      }
    REQUIRE(pairs > 5000);
    return static_cast<double>(far) / pairs;
  };
  const double tree = jumps(false), relaxed = jumps(true), over_limit = jumps(true, 100);
  WARN("jumping pairs: breadth-first " << tree << ", relaxed " << relaxed);
  CHECK(relaxed < 0.5 * tree);
  // Levels above the fit's size limit keep the breadth-first copy.
  CHECK(over_limit == tree);
}

TEST_CASE("the rigid copy keeps the exemplar's scale where the field does not close", "[synth]") {
  // On a sphere the least-squares copy shortens the field's offsets (it keeps only their
  // curl-free part), magnifying the exemplar; turning each sample's offsets to fit its
  // neighbours keeps their length.
  const isochart::Mesh atlas = mcgim_test::sphere_atlas(48, 96);
  const auto pyramid = cube_pyramid(atlas, {{96, 96}, {48, 48}});
  const Image ex = synth::make_exemplar("cells", 128);
  auto run = [&](int rounds) {
    synth::SynthOptions so;
    so.pixels_per_texel = 1;
    so.direction_symmetry = 4;
    so.start_level = 0;
    so.coarsest_passes = 0;
    so.rigid_copy_rounds = rounds;
    return synth::synthesize(atlas, pyramid, ex, so);
  };
  const synth::SynthResult plain = run(0), rigid = run(20), automatic = run(-1);
  WARN("copy pairs off scale by > 1.3x: plain " << plain.copy_scale_off << ", rigid " << rigid.copy_scale_off);
  CHECK(plain.copy_scale_off > 0.05);
  CHECK(rigid.copy_scale_off < 0.5 * plain.copy_scale_off);
  // A 4-direction field gets the rigid copy by default.
  CHECK(automatic.exemplar_pixels == rigid.exemplar_pixels);
  synth::SynthOptions bad;
  bad.rigid_copy_rounds = -2;
  CHECK_THROWS_AS(synth::synthesize(atlas, pyramid, ex, bad), isochart::InputError);
}

TEST_CASE("the atlas texture reads the exemplar where the samples' positions continue", "[synth]") {
  // Four exemplar pixels per finest texel: the samples carry a 4x-shrunk exemplar. An atlas
  // texture four times finer than the image can hold the exemplar's own detail; reading the
  // exemplar at the continued positions puts it there, interpolating the samples' colours
  // cannot. Measured as the mean colour step between neighbouring atlas texels.
  const isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  const Image ex = synth::make_exemplar("bricks", 128);
  synth::SynthOptions so;
  so.pixels_per_texel = 4;
  const synth::SynthResult r = synth::synthesize(atlas, pyramid, ex, so);
  REQUIRE(r.exemplar_jacobians.size() == static_cast<std::size_t>(48 * 48));
  const int size = 4 * 48;
  const Image colours = synth::transfer_to_atlas(atlas, pyramid[0], r.texture, size);
  const Image read = synth::transfer_to_atlas(atlas, pyramid[0], r.texture, size, &r, &ex);
  auto roughness = [&](const Image& t) {
    double sum = 0;
    long long n = 0;
    for (int y = 0; y < t.height; ++y)
      for (int x = 0; x + 1 < t.width; ++x, ++n)
        for (int c = 0; c < 3; ++c) sum += std::fabs(t.at(x + 1, y, c) - t.at(x, y, c));
    return sum / static_cast<double>(n);
  };
  double mean_c = 0, mean_r = 0;
  for (std::size_t i = 0; i < colours.pixels.size(); ++i) mean_c += colours.pixels[i], mean_r += read.pixels[i];
  mean_c /= static_cast<double>(colours.pixels.size());
  mean_r /= static_cast<double>(read.pixels.size());
  WARN("atlas texel steps: sample colours " << roughness(colours) << ", exemplar read " << roughness(read));
  CHECK(roughness(read) > 1.5 * roughness(colours));
  // The same texture, only sharper: the mean colour stays, and averaged over 4x4 texels (one
  // image sample) the two agree closely.
  CHECK(mean_r == Approx(mean_c).margin(0.03));
  auto coarse_diff = [&](const Image& p, const Image& q) {
    double sum = 0;
    long long blocks = 0;
    for (int by = 0; by + 4 <= size; by += 4)
      for (int bx = 0; bx + 4 <= size; bx += 4, ++blocks)
        for (int c = 0; c < 3; ++c) {
          double a = 0, b = 0;
          for (int y = by; y < by + 4; ++y)
            for (int x = bx; x < bx + 4; ++x) a += p.at(x, y, c), b += q.at(x, y, c);
          sum += std::fabs(a - b) / 16;
        }
    return sum / (3.0 * static_cast<double>(blocks));
  };
  // Against another synthesis (seed) of the same exemplar: what unrelated patches differ by.
  synth::SynthOptions so2 = so;
  so2.seed = 7;
  const synth::SynthResult r2 = synth::synthesize(atlas, pyramid, ex, so2);
  const Image unrelated = synth::transfer_to_atlas(atlas, pyramid[0], r2.texture, size);
  const double same = coarse_diff(colours, read), other = coarse_diff(colours, unrelated);
  WARN("mean difference of 4x4 averages: exemplar read " << same << ", another seed " << other);
  CHECK(same < 0.5 * other);
  // A result from another level is refused.
  const auto other_level = cube_pyramid(atlas, {{40, 40}, {20, 20}});
  CHECK_THROWS_AS(synth::transfer_to_atlas(atlas, other_level[0], r.texture, size, &r, &ex), isochart::InputError);
}

TEST_CASE("a chart of slivers covering no texel centre still gets the synthesized colour", "[synth]") {
  // One triangle 1 long and 1e-9 high, its chart a needle along the texture's diagonal: no
  // atlas texel centre lies inside it, and the texture came out all black.
  isochart::Mesh atlas;
  atlas.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1e-9, 0}};
  atlas.faces = {{0, 1, 2}};
  atlas.uvs = {{0.01, 0.01}, {0.99, 0.99}, {0.5, 0.5 + 1e-9}};
  atlas.face_uvs = {{0, 1, 2}};
  mcgim::PyramidOptions po;
  po.sizes = {{64, 64}, {32, 32}};
  po.level.optimize = false;
  const auto pyramid = mcgim::build_pyramid(atlas, po);
  REQUIRE(pyramid[0].image.defined_samples() > 0);
  const Image ex = synth::make_exemplar("bricks", 64);
  const synth::SynthResult r = synth::synthesize(atlas, pyramid, ex, {});
  for (const Image& t : {synth::transfer_to_atlas(atlas, pyramid[0], r.texture, 256),
                         synth::transfer_to_atlas(atlas, pyramid[0], r.texture, 256, &r, &ex)}) {
    float darkest = 1;
    for (int y = 0; y < t.height; ++y)
      for (int x = 0; x < t.width; ++x)
        darkest = std::min(darkest, std::max({t.at(x, y, 0), t.at(x, y, 1), t.at(x, y, 2)}));
    CHECK(darkest > 0.05f);
  }
}

TEST_CASE("an exemplar too large to search at the scale asked for is refused with the scale that works",
          "[synth]") {
  // 1100² pixels at one exemplar pixel per texel: 1.21 M pixels to search, over the 1024² that
  // fit in about 1.3 GB (a 4096² photograph reached 17 GB before it was stopped).
  const isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  const Image big = synth::make_exemplar("noise", 1100);
  synth::SynthOptions so;
  so.pixels_per_texel = 1;
  CHECK_THROWS_WITH(
      synth::synthesize(atlas, pyramid, big, so),
      Catch::StartsWith(
          "exemplar too large at this scale: the 1100x1100 exemplar at 1 exemplar pixel per texel") &&
          Catch::Contains("(1.075 per texel)"));
  // The error says which limit it is (the exemplar's size here, the scale alone below), so a
  // caller can name the right input without reading the message.
  auto limit_is_exemplar_size = [&] {
    try {
      synth::synthesize(atlas, pyramid, big, so);
    } catch (const synth::ScaleError& e) {
      return std::optional<bool>(e.exemplar_size());
    }
    return std::optional<bool>();
  };
  CHECK(limit_is_exemplar_size() == std::optional<bool>(true));
  so.pixels_per_texel = 0.5;  // would magnify the exemplar past its own size and the level's
  CHECK(limit_is_exemplar_size() == std::optional<bool>(false));
  // The scale it names works.
  so.pixels_per_texel = 1.075;
  so.full_passes = 0;  // the search tree is built either way; the passes only take time
  so.coarsest_passes = 0;
  const synth::SynthResult r = synth::synthesize(atlas, pyramid, big, so);
  CHECK(r.levels[0].exemplar_width * r.levels[0].exemplar_height <= 1024 * 1024);
  CHECK(r.requested_scale == r.scale);
  // The default scale (the exemplar across a tenth of the diagonal) would shrink it below 4
  // pixels across; it is moved to that limit, and the result says what it was.
  so.pixels_per_texel = 0;
  const synth::SynthResult d = synth::synthesize(atlas, pyramid, big, so);
  CHECK(d.requested_scale == Approx(1100 / (0.1 * isochart::bounding_box(atlas).diagonal())));
  CHECK(d.scale * pyramid[0].stats.texel_size == Approx(1100 / 4.0));
  CHECK(d.scale < d.requested_scale);
}

TEST_CASE("taps cross seams whatever the mesh's units", "[synth]") {
  // The walk across a seam stopped once the offset left was below 1e-12 units: on a mesh whose
  // texels are that small no tap crossed, and the seam error read a perfect 0.
  isochart::Mesh atlas = mcgim_test::cube_atlas(6);
  const auto pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  synth::SynthOptions so;
  so.scale = 32;
  const Image ex = synth::make_exemplar("weave", 64);
  const synth::SynthResult one = synth::synthesize(atlas, pyramid, ex, so);
  for (auto& p : atlas.positions) p = p * 1e-13;
  const auto tiny_pyramid = cube_pyramid(atlas, {{48, 48}, {24, 24}});
  so.scale = 32e13;
  const synth::SynthResult tiny = synth::synthesize(atlas, tiny_pyramid, ex, so);
  REQUIRE(one.seam_pairs > 0);
  CHECK(tiny.seam_pairs == one.seam_pairs);
  CHECK(tiny.seam_error == Approx(one.seam_error).epsilon(0.05));
}

TEST_CASE("the share of the surface where a user direction lies along the normal", "[synth]") {
  isochart::Mesh square;
  square.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  CHECK(synth::direction_along_normal_share(square, {0, 0, 2}) == 1);
  CHECK(synth::direction_along_normal_share(square, {0, 0.2, 1}) == 1);  // 11° off the normal
  CHECK(synth::direction_along_normal_share(square, {0, 0.5, 1}) == 0);  // 27° off
  CHECK(synth::direction_along_normal_share(square, {1, 0, 0}) == 0);
  CHECK(synth::direction_along_normal_share(square, {0, 0, 0}) == 0);
}
