// `isocharts remesh IN -o OUT.ply`: multi-chart geometry images of a mesh (one level or a
// pyramid), the remesh of each level, its watertightness checks and its geometric PSNR.

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <utility>

#include "cli.h"
#include "isochart/atlas.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/mesh.h"
#include "isochart/signal.h"
#include "isochart/stretch.h"
#include "mcgim/image_io.h"
#include "mcgim/mcgim.h"
#include "mcgim/psnr.h"

namespace cli {

namespace {

// The largest side, --samples included.
constexpr int kMaxSide = kMaxImageSide;
// One chart and its one-texel gutter need 4 samples a side; more charts need more, which
// packing says.
constexpr int kMinSide = 4;

struct RemeshArgs {
  std::string input;
  std::string output;
  std::string atlas;
  int res = 0;
  long long samples = 0;
  int width = 0, height = 0;
  std::vector<std::string> levels_given;  // --levels as typed
  std::vector<int> levels;
  std::string exr, png;
  bool no_optimize = false;
  int fit_passes = mcgim::LevelOptions{}.geometric_iterations;
  bool shorter_diagonals = false;
  long long psnr_samples = 1'000'000;
  bool no_psnr = false;
  std::string signal;
  std::string signal_use = "param";
  bool keep_chart_sizes = false;
  double atlas_aspect = 0;  // 0: read from the atlas's UVs
  GivenOptions given;
};

nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

// "out.ply" + 128 -> "out_128.ply" (the finest level keeps the name as given).
std::string level_path(const std::string& path, int w, int h, bool suffix) {
  if (!suffix) return path;
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  const std::string tag = "_" + std::to_string(w) + (w == h ? "" : "x" + std::to_string(h));
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + tag;
  return path.substr(0, dot) + tag + path.substr(dot);
}

std::string image_path(std::string prefix, int w, int h, const char* ext) {
  // `--png prev.png` means the prefix prev, not prev.png_64x64.png.
  const std::size_t n = std::char_traits<char>::length(ext);
  if (prefix.size() > n && std::equal(ext, ext + n, prefix.end() - n, [](char a, char b) {
        return a == std::tolower(static_cast<unsigned char>(b));
      }))
    prefix.resize(prefix.size() - n);
  return prefix + "_" + std::to_string(w) + "x" + std::to_string(h) + ext;
}

isochart::LoadResult load_any(const Context& ctx, const std::string& path, bool atlas = false) {
  const std::string prefix = "builtin:";
  if (path.rfind(prefix, 0) == 0) return {isochart::make_builtin(path.substr(prefix.size())), {}};
  return ctx.load(path, atlas);
}

void run_remesh(const Context& ctx, const RemeshArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const int modes = (a.res > 0) + (a.samples > 0) + (a.width > 0 || a.height > 0) + !a.levels.empty();
  if (modes > 1) bad_option("--res, --samples, --width/--height and --levels are exclusive");
  if ((a.width > 0) != (a.height > 0)) bad_option("--width and --height go together");
  if (!a.signal.empty() && !a.atlas.empty()) bad_option("--signal builds the atlas; it does not go with --atlas");
  if (a.signal_use != "param" && a.signal_use != "full") bad_option("--signal-use must be param or full");
  // An option that would be silently ignored is more likely a mistake than a wish.
  if (a.given.has("--signal-use") && a.signal.empty()) bad_option("--signal-use goes with --signal");
  if (a.given.has("--fit-passes") && a.no_optimize) bad_option("--fit-passes does nothing with --no-optimize");
  // Diagonals are chosen by the closest-point fit; without it they are the shorter ones anyway.
  if (a.shorter_diagonals && (a.no_optimize || a.fit_passes == 0))
    bad_option(std::string("--shorter-diagonals does nothing with ") +
               (a.no_optimize ? "--no-optimize" : "--fit-passes 0") +
               " (the diagonals are the shorter ones)");
  if (a.given.has("--psnr-samples") && a.no_psnr) bad_option("--psnr-samples does nothing with --no-psnr");
  if (a.atlas_aspect > 0 && a.atlas.empty()) bad_option("--atlas-aspect goes with --atlas");
  if (a.keep_chart_sizes && a.atlas.empty())
    bad_option("--keep-chart-sizes goes with --atlas (a signal atlas given as a file)");
  // A prefix that names a directory would write files called _64x64.png into it.
  for (const auto& [option, prefix] :
       {std::pair<std::string, std::string>{"--png", a.png}, {"--exr", a.exr}}) {
    std::error_code ec;
    if (!prefix.empty() && (prefix.back() == '/' || std::filesystem::is_directory(prefix, ec)))
      bad_option(option + " takes a file name prefix (e.g. " +
                 (std::filesystem::path(prefix) / "gim").string() + " for gim_256x256" +
                 (option == "--png" ? ".png" : ".exr") + "), not the directory '" + prefix + "'");
    // A prefix ending in another file type's extension (--exr e.png) is more likely a
    // mistake than a wish for e.png_64x64.exr.
    const std::string own = option == "--png" ? "png" : "exr";
    const std::string name = std::filesystem::path(prefix).filename().string();
    const auto dot = name.find_last_of('.');
    if (dot != std::string::npos && dot > 0) {
      std::string ext = name.substr(dot + 1);
      for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      // Another type is one of the formats the tool itself reads or writes (a mesh, an image,
      // its JSON report); anything else after a dot (gim.v2) is just part of the name.
      const auto is_format = [&](auto check) {
        try {
          check(prefix);
          return true;
        } catch (const isochart::InputError&) {
          return false;
        }
      };
      const bool other_type =
          ext != own &&
          (ext == "json" || is_format([](const std::string& p) { isochart::format_from_path(p); }) ||
           is_format([](const std::string& p) { isochart::check_image_output(p); }));
      if (other_type)
        bad_option(option + " " + prefix + ": the prefix ends in ." + ext + ", so the files would be " +
                   prefix + "_WxH." + own + "; give a prefix such as " +
                   prefix.substr(0, prefix.size() - ext.size() - 1) + " (or one ending in ." + own + ")");
    }
  }
  {
    // Outputs whose sizes are known now (not those of --samples, checked when written).
    const std::vector<std::string> inputs{a.input, a.atlas, signal_texture(a.signal)};
    ctx.check_paths(inputs, {a.output});
    std::vector<std::array<int, 2>> sizes;
    for (int r : a.levels) sizes.push_back({r, r});
    if (a.res > 0) sizes.push_back({a.res, a.res});
    if (a.width > 0) sizes.push_back({a.width, a.height});
    for (const auto& [w, h] : sizes) {
      std::vector<std::string> derived{level_path(a.output, w, h, true)};
      if (!a.exr.empty()) derived.push_back(image_path(a.exr, w, h, ".exr"));
      if (!a.png.empty()) derived.push_back(image_path(a.png, w, h, ".png"));
      for (const std::string& d : derived) ctx.check_paths(inputs, {d});
    }
  }
  output_mesh_format(a.output,
                     {isochart::MeshFormat::Ply, isochart::MeshFormat::Obj, isochart::MeshFormat::Glb},
                     ".ply, .obj or .glb");

  const isochart::LoadResult loaded = load_any(ctx, a.input);
  const isochart::Mesh& input = loaded.mesh;
  // The atlas: an external one, or the iso-chart atlas of the input.
  nlohmann::json atlas_json;
  isochart::Mesh atlas;
  // An atlas built here is packed square; only a given one has a shape to read.
  double atlas_aspect = a.atlas_aspect > 0 ? a.atlas_aspect : 1.0;
  const auto ta = std::chrono::steady_clock::now();
  if (!a.atlas.empty()) {
    atlas = load_any(ctx, a.atlas, true).mesh;
    if (!atlas.has_uvs()) throw isochart::InputError(a.atlas, "the atlas has no texture coordinates");
    check_atlas_matches(input, atlas, a.atlas);
    // Read here once, said, and handed to the remesh (which would otherwise read it again).
    if (a.atlas_aspect == 0)
      atlas_aspect = read_texture_aspect(ctx, a.atlas, atlas, 1.0,
                                         "its charts are packed at that shape (--atlas-aspect sets it)");
    {
      // The remesh is of the atlas's surface; one with a face missing or a seam left open
      // (a hole in a closed input) passes the size check above, so say so.
      const isochart::Topology topo_in(input), topo_atlas(atlas);
      if (topo_in.euler_characteristic() != topo_atlas.euler_characteristic() ||
          topo_in.boundary_loops().size() != topo_atlas.boundary_loops().size())
        ctx.warn(a.atlas,
                 "the atlas's surface has euler characteristic " +
                     std::to_string(topo_atlas.euler_characteristic()) + " and " +
                     std::to_string(topo_atlas.boundary_loops().size()) + " boundary loops, the input's " +
                     std::to_string(topo_in.euler_characteristic()) + " and " +
                     std::to_string(topo_in.boundary_loops().size()) + "; the remesh follows the atlas");
    }
    atlas_json["source"] = a.atlas;
    // Folded or overlapping charts sample one place of the surface for two: the remesh folds
    // there (an atlas tiled three times over gave 22.8 dB where its own layout gives 76.7).
    const isochart::AtlasQuality q = isochart::measure_atlas(atlas);
    atlas_json["flipped"] = q.stretch.flipped;
    atlas_json["overlapping_pairs"] = q.overlapping_pairs;
    // Mirrored charts (other tools' "flipped" triangles) sample as well as any: not warned.
    if (q.overlapping_pairs > 0)
      ctx.warn(a.atlas, "the atlas has " + std::to_string(q.overlapping_pairs) +
                            " overlapping triangle pairs in UV; where a chart overlaps itself the remesh folds");
    // Re-packed at its surface area a speck of a chart samples as well as any; kept at its size
    // it collapses to a few samples (30 dB where the same atlas re-packed gave 77).
    if (a.keep_chart_sizes)
      warn_sparse_chart(ctx, a.atlas, q.sparsest,
                        "--keep-chart-sizes keeps it that small, so its surface gets almost no samples");
  } else {
    isochart::AtlasOptions ao;
    ao.seed = ctx.opts.seed;
    isochart::Atlas built;
    if (!a.signal.empty()) {
      // A signal-specialized atlas of the geometry's own signal (normals): more samples where
      // the surface bends, where linear reconstruction errs most.
      isochart::SignalAtlasOptions so;
      so.use = a.signal_use == "full" ? isochart::SignalUse::Full : isochart::SignalUse::Param;
      const isochart::Signal signal = load_signal(ctx, a.signal, loaded, input, a.input);
      isochart::SignalAtlasStats ss;
      built = isochart::build_signal_atlas(input, signal, ao, so, &ss, ctx.progress());
      atlas_json["source"] = "iso-charts, signal " + a.signal + " (" + a.signal_use + ")";
      atlas_json["signal_stretch"] = ss.signal_stretch;
    } else {
      built = isochart::build_atlas(input, ao, ctx.progress());
      atlas_json["source"] = "iso-charts";
    }
    atlas = built.apply_to(input);
    atlas_json["charts"] = built.num_charts();
    atlas_json["l2"] = built.stats.l2;
    atlas_json["linf"] = built.stats.linf;
  }
  atlas_json["seconds"] = seconds_since(ta);
  // The library reports atlas problems without a file name: they belong to the atlas's source.
  const std::string atlas_file = a.atlas.empty() ? a.input : a.atlas;
  auto for_atlas = [&](auto&& fn) {
    try {
      return fn();
    } catch (const isochart::InputError& e) {
      if (!e.file().empty()) throw;
      throw isochart::InputError(atlas_file, e.what());
    }
  };

  mcgim::LevelOptions lo;
  lo.optimize = !a.no_optimize;
  lo.geometric_iterations = a.fit_passes;
  lo.fit_diagonals = !a.shorter_diagonals;
  lo.keep_chart_sizes = a.keep_chart_sizes || !a.signal.empty();
  lo.atlas_aspect = atlas_aspect;
  std::vector<std::array<int, 2>> sizes;
  nlohmann::json search;
  if (!a.levels.empty()) {
    for (int r : a.levels) sizes.push_back({r, r});
  } else if (a.samples > 0) {
    const mcgim::ResolutionChoice rc = for_atlas([&] {
      try {
        // Square sizes by the samples left after cleanup: the covered count alone gave 64
        // of --samples 100 where 21x21 gives 97.
        return mcgim::match_resolution(atlas, a.samples, lo, ctx.progress(), kMaxSide, true);
      } catch (const isochart::InputError& e) {
        // "do not fit a 9x9 texture" named a size the user never gave.
        if (!e.file().empty()) throw;
        throw isochart::InputError("", "--samples " + std::to_string(a.samples) +
                                           " is too few for this atlas's charts: " + e.what());
      }
    });
    if (rc.capped)
      ctx.warn(a.input, "--samples " + std::to_string(a.samples) + " needs an image larger than " +
                            std::to_string(kMaxSide) + "x" + std::to_string(kMaxSide) +
                            ", the largest remesh; it holds " + std::to_string(rc.defined_samples) +
                            " defined samples of this atlas");
    sizes.push_back({rc.width, rc.height});
    search["target_samples"] = a.samples;
    search["resolution"] = {rc.width, rc.height};
    search["defined_samples"] = rc.defined_samples;
    search["trials"] = rc.trials;
  } else if (a.width > 0) {
    sizes.push_back({a.width, a.height});
  } else {
    const int r = a.res > 0 ? a.res : 256;
    sizes.push_back({r, r});
  }

  std::vector<mcgim::Level> levels;
  if (sizes.size() == 1) {
    lo.width = sizes[0][0];
    lo.height = sizes[0][1];
    levels.push_back(for_atlas([&] {
      mcgim::Level lv = mcgim::build_level(atlas, lo, ctx.progress());
      mcgim::check_not_empty(lv);
      return lv;
    }));
  } else {
    mcgim::PyramidOptions po;
    po.sizes = sizes;
    po.level = lo;
    levels = for_atlas([&] { return mcgim::build_pyramid(atlas, po, ctx.progress()); });
  }

  nlohmann::json jl = nlohmann::json::array();
  std::ostringstream t;
  t << a.input << (a.atlas.empty() ? "" : " (atlas " + a.atlas + ")") << "\n";
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const mcgim::Level& lv = levels[l];
    const mcgim::LevelStats& s = lv.stats;
    const std::string out = level_path(a.output, s.width, s.height, l > 0);
    const auto tw = std::chrono::steady_clock::now();
    isochart::save_mesh(lv.remesh.mesh, out);
    std::vector<std::string> images;
    if (!a.exr.empty()) {
      images.push_back(image_path(a.exr, s.width, s.height, ".exr"));
      mcgim::write_exr(lv.image, images.back());
    }
    if (!a.png.empty()) {
      images.push_back(image_path(a.png, s.width, s.height, ".png"));
      mcgim::write_normal_preview(lv.image, images.back());
    }
    const double seconds_output = seconds_since(tw);
    mcgim::DistanceResult d;
    if (!a.no_psnr) {
      mcgim::DistanceOptions dopt;
      dopt.samples = a.psnr_samples;
      dopt.seed = ctx.opts.seed;
      d = mcgim::measure_distance(atlas, lv.remesh.mesh, dopt, ctx.progress());
    }
    nlohmann::json j;
    j["output"] = out;
    j["resolution"] = {s.width, s.height};
    j["charts"] = s.charts;
    j["empty_charts"] = s.empty_charts;
    j["lost_charts"] = s.lost_charts;
    j["enlarged_charts"] = s.enlarged_charts;
    j["defined_samples"] = s.defined_samples;
    j["removed_samples"] = s.removed_samples;
    j["forced_samples"] = s.forced_samples;
    j["unique_vertices"] = s.unique_vertices;
    j["triangles"] = s.triangles;
    j["degenerate_triangles"] = s.degenerate_triangles;
    j["collapsed_triangles"] = s.collapsed_triangles;
    j["pocket_triangles"] = lv.remesh.pocket_faces;
    j["cut_nodes"] = s.cut_nodes;
    j["cut_paths"] = s.cut_paths;
    j["closed"] = s.topology.closed();
    j["edge_manifold"] = s.topology.edge_manifold();
    j["manifold"] = s.topology.manifold();
    j["boundary_loops"] = s.topology.boundary_loops;
    j["input_boundary_loops"] = s.input_boundary_loops;
    j["euler_characteristic"] = s.topology.euler_characteristic;
    j["input_euler_characteristic"] = s.input_euler_characteristic;
    j["euler_preserved"] = s.topology.euler_characteristic == s.input_euler_characteristic;
    j["components"] = s.topology.components;
    j["texel_size"] = s.texel_size;
    if (!a.no_psnr) {
      j["psnr"] = finite_or_null(d.psnr);
      j["psnr_mean"] = finite_or_null(d.psnr_mean);
      j["rms_ab"] = d.rms_ab;
      j["rms_ba"] = d.rms_ba;
      j["hausdorff"] = d.hausdorff;
      j["distance_samples"] = a.psnr_samples;
    }
    j["correspondence_samples"] = lv.coarser.empty() ? 0 : s.defined_samples;
    j["images"] = images;
    j["seconds"] = {{"charts", s.seconds_charts},
                    {"packing", s.seconds_packing},
                    {"sampling", s.seconds_sampling},
                    {"zippering", s.seconds_zippering},
                    {"reconstruction", s.seconds_reconstruction},
                    {"optimization", s.seconds_optimization},
                    {"correspondence", s.seconds_correspondence},
                    {"distance", a.no_psnr ? 0.0 : d.seconds},
                    {"output", seconds_output}};
    jl.push_back(j);

    t << "  " << s.width << "x" << s.height << ": " << s.defined_samples << " defined, " << s.unique_vertices
      << " unique, " << s.triangles << " triangles (" << s.degenerate_triangles << " zero-area), "
      << (s.topology.closed() ? "closed" : std::to_string(s.topology.boundary_loops) + " boundary loops") << ", "
      << (s.topology.manifold() ? "manifold" : "NOT manifold") << ", euler " << s.topology.euler_characteristic
      << (s.topology.euler_characteristic == s.input_euler_characteristic ? "" : " (input " + std::to_string(s.input_euler_characteristic) + ")");
    if (!a.no_psnr) t << ", PSNR " << std::fixed << std::setprecision(2) << d.psnr << " dB" << std::defaultfloat;
    // Not a warning: small charts contracted at coarse levels are how a MCGIM coarsens (their
    // surface stays within 3 texels, else lost_charts warns), but features go with them.
    if (s.empty_charts > 0)
      t << ", " << s.empty_charts << (s.empty_charts == 1 ? " chart" : " charts") << " without samples";
    t << " -> " << out;
    for (const std::string& image : images) t << ", " << image;
    t << "\n";
    const std::string warning = mcgim::topology_warning(s);
    if (!warning.empty()) ctx.warn(out, warning);
    // Charts cannot fill a strip of an image: the samples went unused, which the PSNR alone
    // does not say (fandisk at 600×12 defines 3 % of its texels).
    const double texels = static_cast<double>(s.width) * s.height;
    if (std::abs(std::log(static_cast<double>(s.width) / s.height)) >= std::log(4.0) &&
        s.defined_samples < 0.25 * texels) {
      std::ostringstream m;
      m << s.width << "x" << s.height << " level defines " << std::setprecision(2)
        << 100 * s.defined_samples / texels
        << " % of its samples: in an image this elongated the charts leave most of it empty; a squarer "
           "one of as many samples defines more";
      ctx.warn(out, m.str());
    }
  }
  nlohmann::json j;
  j["input"] = a.input;
  j["atlas"] = atlas_json;
  if (!search.empty()) j["search"] = search;
  j["levels"] = jl;
  j["seed"] = ctx.opts.seed;
  j["seconds"] = seconds_since(t0);
  ctx.emit(j, t.str());
}

}  // namespace

void add_remesh(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<RemeshArgs>();
  CLI::App* sub = app.add_subcommand(
      "remesh", "Multi-chart geometry images and their watertight remeshes (one level or a pyramid)");
  sub->add_option("input", args->input, "Mesh file (OBJ/OFF/PLY/glTF) or builtin:NAME")->required();
  sub->add_option("-o,--output", args->output,
                  "Remesh of the finest level (.ply, .obj or .glb); "
                  "coarser levels get _RES before the extension")
      ->required();
  sub->add_option("--res", args->res,
                  "Square image resolution (default 256; at most 2048, ~600 bytes a sample)")
      ->check(CLI::Range(kMinSide, kMaxSide));
  sub->add_option("--samples", args->samples,
                  "Choose the square resolution giving about N defined samples (at most 2048x2048)")
      ->check(CLI::Range(16LL, 4'194'304LL));
  sub->add_option("--width", args->width, "Image width (with --height)")
      ->check(CLI::Range(kMinSide, kMaxSide));
  sub->add_option("--height", args->height, "Image height (with --width)")
      ->check(CLI::Range(kMinSide, kMaxSide));
  sub->add_option("--levels", args->levels_given, "Pyramid of square resolutions, e.g. 256,128,64,32");
  sub->add_option("--atlas", args->atlas, "Use this atlas (a mesh with texture coordinates) instead of "
                                          "building the iso-chart atlas of the input");
  sub->add_option("--exr", args->exr, "Write each level as PREFIX_WxH.exr (float positions, normals, "
                                      "defined mask, chart and group ids, block diagonals)");
  sub->add_option(
      "--png", args->png,
      "Write a normal-map preview of each level as PREFIX_WxH.png (a .png ending PREFIX is dropped)");
  sub->add_flag("--no-optimize", args->no_optimize, "Keep the zippered sample positions (no fitting)");
  sub->add_flag("--shorter-diagonals", args->shorter_diagonals,
                "Split every 2x2 block along its shorter diagonal (default: the one closer to the input "
                "surface, chosen by the fit)");
  sub->add_option("--fit-passes", args->fit_passes,
                  "Closest-point fitting passes of the samples to the surface (more: higher PSNR, slower)")
      ->check(CLI::Range(0, 20))
      ->capture_default_str();
  sub->add_option("--psnr-samples", args->psnr_samples, "Points per surface for the PSNR (default 1000000)")
      ->check(CLI::Range(1LL, 20'000'000LL));
  sub->add_flag("--no-psnr", args->no_psnr, "Skip the distance measurement");
  sub->add_option("--signal", args->signal,
                  "Build a signal-specialized atlas for this signal (normals: samples follow the "
                  "curvature; colors; texture:IMG) and keep its chart sizes");
  sub->add_option("--signal-use", args->signal_use,
                  "With --signal: param (geometric charts, signal parameterization; default) or full "
                  "(signal charts too)");
  sub->add_option("--atlas-aspect", args->atlas_aspect,
                  "Width / height of the texture the --atlas was laid out for, so its charts are "
                  "packed unsquashed (default: read from its UVs, which a stretched chart can mislead)")
      ->check(number_in(1.0 / 16384, 16384.0));
  sub->add_flag("--keep-chart-sizes", args->keep_chart_sizes,
                "Re-pack with the atlas's relative chart sizes instead of one texel density (for "
                "signal-specialized atlases given with --atlas)");
  sub->footer(
      "Each level is packed for its own resolution (gutter 1 texel), sampled, zippered and "
      "reconstructed; in a pyramid every sample is linked to the next coarser level by normal "
      "shooting. The PSNR compares the remesh with the atlas's surface.\n"
      "Examples:\n"
      "  isocharts remesh ../shared/data/meshes/horse.ply -o horse_gim.ply --samples 47000 --json\n"
      "  isocharts remesh ../shared/data/meshes/horse.ply -o horse_sig.ply --samples 47000 --signal normals\n"
      "  isocharts remesh ../shared/data/meshes/bunny.obj -o bunny.ply --levels 256,128,64,32 --png bunny\n"
      "  isocharts remesh ../shared/data/meshes/bunny.obj -o bunny_xatlas.ply --res 256 \\\n"
      "      --atlas ../shared/data/baseline_atlases/bunny_xatlas.obj");
  sub->callback([&ctx, args, sub, &action] {
    args->given.record(sub, {"--signal-use", "--fit-passes", "--psnr-samples"});
    action = [&ctx, args] {
      args->levels = parse_levels(args->levels_given, kMinSide, kMaxSide);
      run_remesh(ctx, *args);
    };
  });
}

}  // namespace cli
