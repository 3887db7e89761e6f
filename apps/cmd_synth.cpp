// `isocharts synth IN --exemplar IMG -o OUT.glb`: grows a texture from an exemplar over the
// surface (iso-chart atlas → MCGIM pyramid → multiresolution synthesis) and writes the textured
// MCGIM remesh and the original mesh with its atlas and the transferred texture.
// `isocharts exemplar NAME -o FILE.png` (hidden): writes one of the procedural exemplars.

#include <cctype>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "cli.h"
#include "isochart/atlas.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/image.h"
#include "mcgim/mcgim.h"
#include "synth/exemplar.h"
#include "synth/synth.h"

namespace cli {

namespace {

struct SynthArgs {
  std::string input;
  std::string output;
  std::string exemplar = "builtin:bricks";
  double scale = 0;
  double pixels_per_texel = 0;
  std::vector<double> direction;
  std::vector<std::string> levels_given{"256,128,64,32"};  // --levels as typed
  std::vector<int> levels;
  int neighborhood = 5;
  int coarse_neighborhood = 3;
  int full_passes = -1;     // -1: the library's default
  int start_passes = -1;    // -1: the library's default
  int rigid_copy = -1;      // -1: automatic
  bool colour_transfer = false;
  double coherence = -1;    // < 0: the library's default
  int start_samples = -1;   // -1: the library's default
  int start_level = -1;     // -1: automatic
  int symmetry = -1;        // -1: the library's default
  int atlas_size = 1024;
};

nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

std::string stem_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path;
  return path.substr(0, dot);
}

// The stem of the PNG textures: the MTL names them in `map_Kd`, which many OBJ readers end at
// a space (tinyobjloader took "out.png" from "map_Kd my out.png"), so spaces in the file name
// become underscores, as in the MTL's own name (isochart::save_mesh).
std::string texture_stem(const std::string& stem) {
  std::string t = stem;
  const auto slash = t.find_last_of('/');
  for (std::size_t i = slash == std::string::npos ? 0 : slash + 1; i < t.size(); ++i)
    if (t[i] == ' ' || t[i] == '\t') t[i] = '_';
  return t;
}

// The extensions of the two meshes written: the one typed keeps its case (`-o a.GLB` wrote
// a.glb, and the file asked for was not there).
std::pair<std::string, std::string> mesh_extensions(const std::string& output) {
  const std::string typed = output.substr(stem_of(output).size());
  std::string lower = typed;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return {lower == ".glb" ? typed : ".glb", lower == ".obj" ? typed : ".obj"};
}

std::string base_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

void run_synth(const Context& ctx, const SynthArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  output_mesh_format(a.output, {isochart::MeshFormat::Glb, isochart::MeshFormat::Obj},
                     ".glb or .obj; both are written, with PNG textures");
  {
    const std::string stem = stem_of(a.output), tex = texture_stem(stem);
    const auto [glb, obj] = mesh_extensions(a.output);
    std::vector<std::string> outs;
    for (const std::string& tail : {glb, obj, "_mcgim" + glb, "_mcgim" + obj}) outs.push_back(stem + tail);
    for (const char* tail : {".mtl", ".png", "_mcgim.mtl", "_mcgim.png"}) outs.push_back(tex + tail);
    ctx.check_paths({a.input, a.exemplar}, outs);
  }
  if (!a.direction.empty() && a.direction.size() != 3) bad_option("--direction takes three numbers x,y,z");
  std::vector<double> direction = a.direction;
  if (!direction.empty()) {
    // (0,0,0) would silently mean "computed field", NaN nothing at all. Only the direction
    // counts: scaled to a largest component of 1, since squaring 1e-300 or 1e308 leaves 0 or inf.
    double largest = 0;
    for (double x : direction) largest = std::isfinite(x) ? std::max(largest, std::abs(x)) : NAN;
    if (!(largest > 0)) bad_option("--direction must be a finite, non-zero vector x,y,z");
    for (double& x : direction) x /= largest;
  }
  // Checked here, not only in the library, so that a typo fails before the atlas is built.
  if (a.neighborhood % 2 == 0) bad_option("--neighborhood must be odd (3, 5, 7, ...), not " + std::to_string(a.neighborhood));
  if (a.coarse_neighborhood % 2 == 0)
    bad_option("--coarse-neighborhood must be odd (1, 3, 5, ...), not " + std::to_string(a.coarse_neighborhood));
  if (a.scale > 0 && a.pixels_per_texel > 0) bad_option("--scale and --pixels-per-texel are exclusive");
  if (a.start_level >= static_cast<int>(a.levels.size()))
    bad_option("--start-level " + std::to_string(a.start_level) + ": the pyramid has " +
               std::to_string(a.levels.size()) + " levels, 0 (finest) to " +
               std::to_string(a.levels.size() - 1));
  long long clipped = 0;
  const isochart::Image exemplar = synth::exemplar_from(a.exemplar, &clipped);
  // An HDR exemplar comes out mostly white or black; the user should hear why.
  if (clipped > 0) {
    const double share = 100.0 * clipped / (3.0 * exemplar.width * exemplar.height);
    std::ostringstream w;
    w << clipped << " colour values (" << std::setprecision(3) << share
      << " %) lie outside [0, 1] and are clipped; scale the image into [0, 1] to keep them";
    ctx.warn(a.exemplar, w.str());
  }

  const std::string prefix = "builtin:";
  const isochart::Mesh input = a.input.rfind(prefix, 0) == 0 ? isochart::make_builtin(a.input.substr(prefix.size()))
                                                             : ctx.load(a.input).mesh;
  if (!direction.empty()) {
    // There the field follows another axis, so on a flat mesh seen face-on it is ignored outright.
    const double share =
        synth::direction_along_normal_share(input, {direction[0], direction[1], direction[2]});
    if (share >= 0.25) {
      std::ostringstream w;
      w << "--direction " << a.direction[0] << "," << a.direction[1] << "," << a.direction[2]
        << " is within 17 degrees of the surface normal on " << std::setprecision(3) << 100 * share
        << " % of the surface, where the pattern follows another axis; give a direction along the surface";
      ctx.warn(a.input, w.str());
    }
  }
  const auto ta = std::chrono::steady_clock::now();
  isochart::AtlasOptions ao;
  ao.seed = ctx.opts.seed;
  const isochart::Atlas built = isochart::build_atlas(input, ao, ctx.progress());
  const isochart::Mesh atlas = built.apply_to(input);
  const double seconds_atlas = seconds_since(ta);

  const auto tp = std::chrono::steady_clock::now();
  mcgim::PyramidOptions po;
  po.sizes.clear();
  for (int r : a.levels) po.sizes.push_back({r, r});
  po.level.atlas_aspect = 1;  // its own square atlas: nothing to read from the UVs
  std::vector<mcgim::Level> pyramid;
  try {
    pyramid = mcgim::build_pyramid(atlas, po, ctx.progress());
  } catch (const isochart::InputError& e) {
    if (!e.file().empty()) throw;
    throw isochart::InputError(a.input, e.what());
  }
  const double seconds_pyramid = seconds_since(tp);

  synth::SynthOptions so;
  so.scale = a.scale;
  so.pixels_per_texel = a.pixels_per_texel;
  if (!direction.empty()) so.direction = {direction[0], direction[1], direction[2]};
  so.neighborhood = a.neighborhood;
  so.coarse_neighborhood = a.coarse_neighborhood;
  if (a.full_passes >= 0) so.full_passes = a.full_passes;
  if (a.start_passes >= 0) so.coarsest_passes = a.start_passes;
  so.rigid_copy_rounds = a.rigid_copy;
  if (a.coherence >= 0) so.coherence = a.coherence;
  if (a.start_samples >= 0) so.min_level_samples = a.start_samples;
  if (a.start_level < -1) bad_option("--start-level takes a pyramid index (0 = finest) or -1 (automatic)");
  so.start_level = a.start_level;
  if (a.symmetry >= 1) so.direction_symmetry = a.symmetry;
  so.seed = ctx.opts.seed;
  synth::SynthResult r;
  try {
    r = synth::synthesize(atlas, pyramid, exemplar, so, ctx.progress());
  } catch (const synth::ScaleError& e) {
    // The library's scale limits depend on the built pyramid; name the option that set the
    // scale, and for the exemplar's size, the exemplar.
    std::ostringstream opt;
    if (a.pixels_per_texel > 0) opt << "--pixels-per-texel " << a.pixels_per_texel << ": ";
    else if (a.scale > 0) opt << "--scale " << a.scale << ": ";
    if (e.exemplar_size()) throw isochart::InputError(a.exemplar, opt.str() + e.what());
    bad_option(opt.str() + e.what());
  }
  if (a.start_level >= 0 && r.start_level != a.start_level)
    ctx.warn(a.input, "--start-level " + std::to_string(a.start_level) + ": started at level " +
                          std::to_string(r.start_level) + " (" +
                          std::to_string(pyramid[r.start_level].stats.width) +
                          "²); the coarser levels hold fewer than --start-samples " +
                          std::to_string(so.min_level_samples) + " samples");

  // The default scale moved to a limit (an exemplar magnified past the finest image, or shrunk
  // below 4 pixels a texel): the pattern is not the size the README promises, so say so.
  if (a.scale <= 0 && a.pixels_per_texel <= 0) {
    const double asked = r.requested_scale;
    if (std::abs(std::log(r.scale / asked)) > 1e-6) {
      std::ostringstream w;
      w << "the default scale (" << asked << " exemplar pixels per unit length, the exemplar spanning a "
        << "tenth of the bounding-box diagonal) is out of the range this pyramid can synthesize; used "
        << r.scale << (r.scale > asked ? ", the smallest" : ", the largest") << " that works";
      ctx.warn(a.exemplar, w.str());
    }
  }

  // The default scale ties the exemplar to the model's size, not its own: a 4096² photograph
  // was synthesized from a 20² thumbnail without a word.
  if (a.scale <= 0 && a.pixels_per_texel <= 0 && !r.levels.empty() && r.levels.front().exemplar_factor > 8) {
    const auto& finest = r.levels.front();
    std::ostringstream w;
    w << "at the default scale (the exemplar spans about a tenth of the bounding-box diagonal) the "
      << exemplar.width << "x" << exemplar.height << " exemplar is synthesized from " << finest.exemplar_width
      << "x" << finest.exemplar_height
      << " pixels at the finest level; --pixels-per-texel or --scale keeps more of it";
    ctx.warn(a.exemplar, w.str());
  }

  const auto tt = std::chrono::steady_clock::now();
  const isochart::Image atlas_tex = synth::transfer_to_atlas(atlas, pyramid[0], r.texture, a.atlas_size,
                                                               a.colour_transfer ? nullptr : &r, &exemplar);
  const double seconds_transfer = seconds_since(tt);

  // Outputs: STEM.{glb,obj,png} (the input mesh on its atlas) and STEM_mcgim.{glb,obj,png}.
  const auto tw = std::chrono::steady_clock::now();
  const std::string stem = stem_of(a.output);
  const auto [glb, obj] = mesh_extensions(a.output);
  const std::string atlas_png = texture_stem(stem) + ".png", gim_png = texture_stem(stem) + "_mcgim.png";
  isochart::write_image(atlas_png, atlas_tex);
  isochart::write_image(gim_png, r.texture);
  isochart::SaveOptions so_glb, so_obj;
  so_glb.texture = atlas_png;
  so_obj.texture = base_name(atlas_png);
  isochart::save_mesh(atlas, stem + glb, so_glb);
  isochart::save_mesh(atlas, stem + obj, so_obj);
  so_glb.texture = gim_png;
  so_obj.texture = base_name(gim_png);
  isochart::save_mesh(pyramid[0].remesh.mesh, stem + "_mcgim" + glb, so_glb);
  isochart::save_mesh(pyramid[0].remesh.mesh, stem + "_mcgim" + obj, so_obj);
  const double seconds_output = seconds_since(tw);
  ctx.end_progress();

  nlohmann::json j;
  j["input"] = a.input;
  j["exemplar"] = a.exemplar;
  const std::string atlas_mtl = isochart::material_path(stem + obj),
                    gim_mtl = isochart::material_path(stem + "_mcgim" + obj);
  j["outputs"] = {stem + glb, stem + obj, atlas_mtl, atlas_png, stem + "_mcgim" + glb, stem + "_mcgim" + obj,
                  gim_mtl,    gim_png};
  j["scale"] = r.scale;
  j["charts"] = built.num_charts();
  j["seam_error"] = finite_or_null(r.seam_error);
  j["seam_pairs"] = r.seam_pairs;
  j["match_error"] = r.match_error;
  j["texel_scale_spread"] = r.texel_scale_spread;
  j["start_level"] = r.start_level;
  j["direction_symmetry"] = r.direction_symmetry;
  j["correlation_length"] = r.correlation_length;
  j["coarse_footprint"] = r.coarse_footprint;
  j["smoothness"] = r.smoothness;
  j["copy_scale_off"] = r.copy_scale_off;
  nlohmann::json jl = nlohmann::json::array();
  for (const auto& l : r.levels) {
    // Levels below the start level are not synthesized: no exemplar level, not a zero one.
    const bool synthesized = l.exemplar_width > 0;
    jl.push_back(
        {{"resolution", {l.width, l.height}},
         {"synthesized", synthesized},
         {"exemplar", synthesized ? nlohmann::json{l.exemplar_width, l.exemplar_height} : nlohmann::json()},
         {"texel_size", l.texel_size},
         {"exemplar_pixels_per_texel", synthesized ? nlohmann::json(l.exemplar_factor) : nlohmann::json()},
         {"samples", l.groups},
         {"seam_taps", l.seam_taps},
         {"missing_taps", l.missing_taps},
         {"seconds", l.seconds}});
  }
  j["levels"] = jl;
  j["seconds_breakdown"] = {{"atlas", seconds_atlas},   {"pyramid", seconds_pyramid},
                            {"synthesis", r.seconds},   {"transfer", seconds_transfer},
                            {"output", seconds_output}};
  j["seconds"] = seconds_since(t0);
  std::ostringstream t;
  t << a.input << " with " << a.exemplar << ": " << built.num_charts()
    << (built.num_charts() == 1 ? " chart" : " charts") << ", levels";
  for (int lv : a.levels) t << " " << lv;
  t << "\n  seam error ";
  if (std::isnan(r.seam_error))
    t << "none (no seam)";
  else
    t << r.seam_error;
  t << ", match error " << r.match_error << ", texel-scale spread " << r.texel_scale_spread << "\n  wrote "
    << stem << glb << "/" << obj << " with " << atlas_png << " and " << stem << "_mcgim" << glb << "/" << obj
    << " with " << gim_png << " in " << j["seconds"].get<double>() << " s\n";
  ctx.emit(j, t.str());
}

}  // namespace

void add_synth(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* sub = app.add_subcommand("synth", "Grow a texture from an exemplar image over the surface");
  sub->add_option("input", args->input, "Mesh file (OBJ/OFF/PLY/glTF) or builtin:NAME")->required();
  sub->add_option(
         "-o,--output", args->output,
         "OUT.glb or OUT.obj: writes OUT.glb, OUT.obj+mtl, OUT.png (the mesh on its iso-chart atlas) "
         "and OUT_mcgim.glb/.obj/.png (the textured geometry-image remesh); spaces in OUT become '_' in "
         "the .png and .mtl names, which an OBJ's material line cannot quote")
      ->required();
  sub->add_option("--exemplar", args->exemplar,
                  "Exemplar image (PNG/JPG/EXR: RGB, opaque RGBA or grey) or builtin:bricks|cells|weave|noise "
                  "(default builtin:bricks)");
  sub->add_option("--scale", args->scale,
                  "Exemplar pixels per unit of surface length (default: the exemplar spans a tenth of the "
                  "bounding-box diagonal)")
      ->check(cli::positive);
  sub->add_option("--pixels-per-texel", args->pixels_per_texel,
                  "Instead of --scale: exemplar pixels per texel of the finest level (1 = the exemplar at "
                  "full resolution)")
      ->check(cli::positive);
  sub->add_option("--direction", args->direction, "Exemplar x axis on the surface, x,y,z (default: smooth field)")
      ->delimiter(',');
  sub->add_option("--levels", args->levels_given,
                  "MCGIM pyramid resolutions, any order (default 256,128,64,32; 8 to 2048)");
  sub->add_option("--neighborhood", args->neighborhood, "Side of the current-level neighbourhood (odd, default 5)")
      ->check(CLI::Range(3, 15));
  sub->add_option("--coarse-neighborhood", args->coarse_neighborhood,
                  "Side of the coarser-level neighbourhood (odd, default 3)")
      ->check(CLI::Range(1, 15));
  sub->add_option("--passes", args->full_passes, "Non-causal passes per level after the first synthesized (default 2)")
      ->check(CLI::Range(0, 10));
  sub->add_option("--start-passes", args->start_passes,
                  "Non-causal passes on the first synthesized level after its exemplar copy (default 2)")
      ->check(CLI::Range(0, 10));
  sub->add_flag("--colour-transfer", args->colour_transfer,
                "Atlas texture from the finest samples' colours, interpolated (default: each texel reads the "
                "exemplar where its nearest samples' exemplar positions continue)");
  sub->add_option("--rigid-copy", args->rigid_copy,
                  "Rounds of the as-rigid-as-possible fit of the first level's exemplar copy (keeps the "
                  "exemplar's scale, lets directions drift; default -1: 20 with a 4-direction field, else 0)")
      ->check(CLI::Range(-1, 100));
  sub->add_option(
         "--coherence", args->coherence,
         "How much better (relative neighbourhood distance) a match elsewhere in the exemplar must be "
         "than continuing a neighbour's patch (default 0.1)")
      ->check(number_in(0.0, 10.0));
  sub->add_option(
         "--start-samples", args->start_samples,
         "Start at no level with fewer samples than N, the finest excepted, which is always synthesized "
         "(default 1000)")
      ->check(CLI::Range(1, 1 << 28));
  sub->add_option(
         "--start-level", args->start_level,
         "Pyramid level synthesis starts at, 0 = finest, never one with fewer than --start-samples "
         "samples (default -1: automatic, from the "
         "exemplar's correlation length against the coarsest level's neighbourhood footprint and its "
         "smoothness at the finest texel)")
      ->check(CLI::Range(-1, 64));
  sub->add_option("--symmetry", args->symmetry,
                  "Rotational symmetry N of the computed direction field: directions equal up to "
                  "360/N degrees (1: a vector field; default: 4 when the exemplar decorrelates alike "
                  "along x and y, else 2)")
      ->check(CLI::Range(1, 8));
  sub->add_option("--atlas-size", args->atlas_size, "Texture size of the atlas output (default 1024)")
      ->check(CLI::Range(16, 8192));
  sub->footer("Example:\n  isocharts synth builtin:creature -o creature.glb && "
              "isocharts render creature.glb --texture creature.png --views 4 -o creature_views.png");
  sub->callback([&ctx, args, &action] {
    action = [&ctx, args] {
      args->levels = parse_levels(args->levels_given, 8, kMaxImageSide);
      run_synth(ctx, *args);
    };
  });

  auto ex = std::make_shared<std::pair<std::string, std::string>>();
  auto size = std::make_shared<int>(128);
  CLI::App* gen = app.add_subcommand("exemplar", "Write a procedural exemplar texture");
  gen->group("");  // hidden: a tool for exemplars/
  gen->add_option("name", ex->first, "bricks, cells, weave or noise")->required();
  gen->add_option("-o,--output", ex->second, "Image file (.png)")->required();
  gen->add_option("--size", *size, "Side in pixels (default 128)")->check(CLI::Range(8, 4096));
  gen->callback([&ctx, ex, size, &action] {
    action = [&ctx, ex, size] {
      isochart::write_image(ex->second, synth::make_exemplar(ex->first, *size, ctx.opts.seed));
      ctx.emit({{"exemplar", ex->first}, {"output", ex->second}, {"size", *size}}, "wrote " + ex->second + "\n");
    };
  });
}

}  // namespace cli
