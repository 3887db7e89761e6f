// Packing benchmark: re-packs the charts of existing atlases (the Microsoft UVAtlas and
// xatlas baselines in ../shared/data/baseline_atlases) with isochart::pack_charts and
// compares packing ratios. Each chart keeps its own UVs and gets its 3-D area, so the
// packer sees realistic chart shapes.
//
//   pack_bench [options] [atlas.obj ...]     (default: all six baseline atlases)
//     --size N | --width N --height N   target texture (1024×1024)
//     --gutter N      gutter in texels (2)
//     --rotations N   orientations per chart (default 0: automatic, 16; 4 above 256 charts)
//     --no-holes      disable hole filling
//     --variants N    greedy variants per scale (0 = automatic)
//     --growth W      growth weight of side insertions (0.5)
//     --paper         the paper's scheme alone: --no-holes --variants 1 --growth 0
//     --tiny N        pack N random triangles, each its own chart, instead of atlases
//     --threads N     TBB threads (0 = default)
//     --dump PREFIX   write each packed atlas to PREFIX<name>.ppm
//     --atlas         treat each file as an atlas of its mesh: atlas_from_uvs, then pack_atlas,
//                     and print the stretch, flips and exact overlaps of the result too
//     --split         with --atlas: split_and_pack_atlas (--min-gain G, --target-charts N)
//     --check         verify no overlaps, [0,1]² and winding after packing (the gutter
//                     is verified exactly by tests/isochart/pack_test.cpp)

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "isochart/atlas.h"
#include "isochart/baselines.h"
#include "isochart/error.h"
#include "isochart/io.h"
#include "isochart/mesh.h"
#include "isochart/pack.h"
#include "isochart/stretch.h"

using namespace isochart;

namespace {

struct ChartSet {
  std::vector<PackChart> charts;
  double input_ratio = 0;  // Σ UV area / UV bounding box of the input atlas
};

// Splits an atlas into charts with their own UVs and 3-D areas. Charts whose UVs are
// mirrored (UVAtlas writes v flipped) are mirrored back so every chart is counter-clockwise.
ChartSet charts_of(const Mesh& m) {
  ChartSet set;
  int count = 0;
  const std::vector<int> chart = uv_charts(m, count);
  set.charts.resize(count);
  std::vector<std::vector<int>> local(count);  // per chart: uv index → local vertex, lazily
  std::vector<int> stamp(m.uvs.size(), -1), id(m.uvs.size(), -1);
  double uv_area = 0;
  Vec2d lo = m.uvs[m.face_uvs[0][0]], hi = lo;
  for (int f = 0; f < m.num_faces(); ++f) {
    PackChart& c = set.charts[chart[f]];
    Face face;
    for (int k = 0; k < 3; ++k) {
      const int t = m.face_uvs[f][k];
      if (stamp[t] != chart[f]) {
        stamp[t] = chart[f];
        id[t] = static_cast<int>(c.uv.size());
        c.uv.push_back(m.uvs[t]);
      }
      face[k] = id[t];
      lo = {std::min(lo.x, m.uvs[t].x), std::min(lo.y, m.uvs[t].y)};
      hi = {std::max(hi.x, m.uvs[t].x), std::max(hi.y, m.uvs[t].y)};
    }
    c.faces.push_back(face);
    const Vec3d& a = m.positions[m.faces[f][0]];
    c.area_3d += triangle_area(a, m.positions[m.faces[f][1]], m.positions[m.faces[f][2]]);
    uv_area +=
        std::abs(signed_area(m.uvs[m.face_uvs[f][0]], m.uvs[m.face_uvs[f][1]], m.uvs[m.face_uvs[f][2]]));
  }
  set.input_ratio = uv_area / ((hi.x - lo.x) * (hi.y - lo.y));
  for (PackChart& c : set.charts) {
    double signed_sum = 0;
    for (const Face& f : c.faces) signed_sum += signed_area(c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]);
    if (signed_sum < 0)
      for (Vec2d& p : c.uv) p.x = -p.x;
  }
  return set;
}

// N random triangles of similar size, each its own chart (a deterministic generator).
ChartSet random_triangles(int count) {
  ChartSet set;
  std::uint64_t state = 0x9E3779B97F4A7C15ULL;
  auto uniform = [&state]() {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  for (int i = 0; i < count; ++i) {
    PackChart c;
    const Vec2d a{uniform(), uniform()}, b{a.x + 0.5 + uniform(), a.y + 0.3 * uniform()};
    const Vec2d d{a.x + uniform(), a.y + 0.4 + uniform()};
    c.uv = {a, b, d};
    c.faces = {{0, 1, 2}};
    c.area_3d = signed_area(a, b, d) * (0.5 + uniform());
    set.charts.push_back(c);
  }
  set.input_ratio = 0;
  return set;
}

// Writes the packed atlas as a binary PPM (one colour per chart, texel centres inside a
// triangle), for looking at a packing.
void dump_ppm(const std::vector<PackChart>& charts, int w, int h, const std::string& path) {
  std::vector<unsigned char> img(static_cast<std::size_t>(w) * h * 3, 255);
  for (std::size_t i = 0; i < charts.size(); ++i) {
    const unsigned char col[3] = {static_cast<unsigned char>(40 + (i * 97) % 200),
                                  static_cast<unsigned char>(40 + (i * 57) % 200),
                                  static_cast<unsigned char>(40 + (i * 151) % 200)};
    for (const Face& f : charts[i].faces) {
      Vec2d p[3];
      for (int k = 0; k < 3; ++k) p[k] = {charts[i].uv[f[k]].x * w, charts[i].uv[f[k]].y * h};
      const int x0 = std::max(0, static_cast<int>(std::min({p[0].x, p[1].x, p[2].x})));
      const int x1 = std::min(w - 1, static_cast<int>(std::max({p[0].x, p[1].x, p[2].x})));
      const int y0 = std::max(0, static_cast<int>(std::min({p[0].y, p[1].y, p[2].y})));
      const int y1 = std::min(h - 1, static_cast<int>(std::max({p[0].y, p[1].y, p[2].y})));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const Vec2d q{x + 0.5, y + 0.5};
          const double a = signed_area(p[0], p[1], q), b = signed_area(p[1], p[2], q),
                       c = signed_area(p[2], p[0], q);
          if ((a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0))
            for (int k = 0; k < 3; ++k) img[(static_cast<std::size_t>(h - 1 - y) * w + x) * 3 + k] = col[k];
        }
    }
  }
  std::ofstream out(path, std::ios::binary);
  out << "P6\n" << w << " " << h << "\n255\n";
  out.write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
}

}  // namespace

int main(int argc, char** argv) {
  PackOptions options;
  int threads = 0;
  bool check = false;
  std::string dump;
  int tiny = 0;
  bool atlas_mode = false, split = false;
  PackSplitOptions split_options;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> int {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pack_bench: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return std::atoi(argv[++i]);
    };
    if (a == "--size")
      options.width = options.height = next();
    else if (a == "--width")
      options.width = next();
    else if (a == "--height")
      options.height = next();
    else if (a == "--gutter")
      options.gutter = next();
    else if (a == "--rotations")
      options.rotations = next();
    else if (a == "--threads")
      threads = next();
    else if (a == "--no-holes")
      options.fill_holes = false;
    else if (a == "--variants")
      options.variants = next();
    else if (a == "--growth" && i + 1 < argc)
      options.growth_weight = std::atof(argv[++i]);
    else if (a == "--paper") {
      options.fill_holes = false;
      options.variants = 1;
      options.growth_weight = 0;
    } else if (a == "--check")
      check = true;
    else if (a == "--atlas")
      atlas_mode = true;
    else if (a == "--split")
      split = true;
    else if (a == "--target-charts")
      split_options.target_charts = next();
    else if (a == "--min-gain" && i + 1 < argc)
      split_options.min_gain = std::atof(argv[++i]);
    else if (a == "--tiny")
      tiny = next();
    else if (a == "--dump" && i + 1 < argc)
      dump = argv[++i];
    else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "pack_bench: unknown option %s\n", a.c_str());
      return 2;
    } else
      files.push_back(a);
  }
  if (tiny > 0) files.push_back("tiny:" + std::to_string(tiny));
  if (files.empty())
    for (const char* name : {"bunny_uvatlas", "horse_uvatlas", "gargoyle_uvatlas", "bunny_xatlas",
                             "horse_xatlas", "gargoyle_xatlas"})
      files.push_back(std::string(ISOCHARTS_SHARED_DATA) + "/baseline_atlases/" + name + ".obj");
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);

  if (atlas_mode) {
    std::printf("%-16s %6s %6s %8s %8s %8s %6s %8s %8s %8s %8s\n", "atlas", "charts", "added", "input",
                "packing", "L2", "Linf", "flipped", "overlaps", "split s", "pack s");
    try {
      for (const std::string& file : files) {
        const Mesh mesh = load_mesh(file).mesh;
        Atlas atlas = atlas_from_uvs(mesh);
        const int before = atlas.num_charts();
        const double input = measure_atlas(mesh).packing_ratio;
        PackSplitResult sr;
        const PackResult r = split ? split_and_pack_atlas(mesh, atlas, options, split_options, {}, &sr)
                                   : pack_atlas(mesh, atlas, options);
        std::string name = file.substr(file.find_last_of('/') + 1);
        std::printf("%-16s %6d %6d %8.3f %8.3f %8.4f %6.3f %8d %8lld %8.2f %8.2f  rect fill %.3f -> %.3f\n",
                    name.c_str(), atlas.num_charts(), atlas.num_charts() - before, input,
                    atlas.stats.packing_ratio, atlas.stats.l2, atlas.stats.linf, atlas.stats.flipped,
                    atlas.stats.overlapping_pairs, sr.seconds, r.seconds, sr.rect_fill_before,
                    sr.rect_fill_after);
        std::fflush(stdout);
        if (!dump.empty()) {
          int count = 0;
          const Mesh out = atlas.apply_to(mesh);
          std::vector<int> chart = uv_charts(out, count);
          std::vector<PackChart> pcs(count);
          for (int f = 0; f < out.num_faces(); ++f) {
            PackChart& c = pcs[chart[f]];
            const int base = static_cast<int>(c.uv.size());
            for (int k = 0; k < 3; ++k) c.uv.push_back(out.uvs[out.face_uvs[f][k]]);
            c.faces.push_back({base, base + 1, base + 2});
          }
          dump_ppm(pcs, options.width, options.height, dump + name.substr(0, name.size() - 4) + ".ppm");
        }
      }
    } catch (const Error& e) {
      std::fprintf(stderr, "pack_bench: error: %s\n", e.what());
      return 1;
    }
    return 0;
  }
  std::printf("%-22s %6s %9s %9s %8s %9s %8s %8s %s\n", "atlas", "charts", "theirs", "ours", "util",
              "seconds", "scales", "variant", check ? "check" : "");
  try {
    for (const std::string& file : files) {
      ChartSet set = file.rfind("tiny:", 0) == 0 ? random_triangles(tiny) : charts_of(load_mesh(file).mesh);
      const PackResult r = pack_charts(set.charts, options);
      std::string verdict;
      if (check) {
        std::vector<std::array<Vec2d, 3>> tris;
        std::vector<int> owner;
        bool inside = true, ccw = true;
        for (const PackChart& c : set.charts) {
          owner.insert(owner.end(), c.faces.size(), static_cast<int>(&c - set.charts.data()));
          for (const Vec2d& p : c.uv) inside = inside && p.x >= 0 && p.x <= 1 && p.y >= 0 && p.y <= 1;
          for (const Face& f : c.faces) {
            tris.push_back({c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]});
            // Input charts were made counter-clockwise overall; the packer must keep that.
          }
          double signed_sum = 0;
          for (const Face& f : c.faces) signed_sum += signed_area(c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]);
          ccw = ccw && signed_sum > 0;
        }
        // Only pairs from different charts count: some input charts overlap themselves, and
        // packing (a rigid motion per chart) neither causes nor repairs that.
        std::size_t overlaps = 0;
        for (const auto& [a, b] : overlapping_uv_pairs(tris)) overlaps += owner[a] != owner[b];
        verdict = std::string(overlaps ? "OVERLAP" : "no-overlap") + (inside ? " in-[0,1]" : " OUTSIDE") +
                  (ccw ? "" : " FLIPPED");
      }
      std::string name = file.substr(file.find_last_of('/') + 1);
      if (!dump.empty())
        dump_ppm(set.charts, options.width, options.height, dump + name.substr(0, name.size() - 4) + ".ppm");
      std::printf("%-22s %6zu %9.3f %9.3f %8.3f %9.2f %8d %8d %s\n", name.c_str(), set.charts.size(),
                  set.input_ratio, r.packing_ratio, r.utilization, r.seconds, r.attempts, r.variant,
                  verdict.c_str());
      std::fflush(stdout);
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "pack_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
