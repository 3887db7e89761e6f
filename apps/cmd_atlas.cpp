// `isocharts atlas IN -o OUT.obj`: the iso-chart texture atlas of a mesh.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <iomanip>
#include <sstream>

#include "cli.h"
#include "isochart/atlas.h"
#include "isochart/error.h"
#include "isochart/image.h"
#include "isochart/render.h"
#include "isochart/signal.h"
#include "isochart/stretch.h"

namespace cli {

namespace {

struct AtlasArgs {
  std::string input;
  std::vector<std::string> outputs;
  std::string png;
  int png_size = 1024;
  bool no_graph_cut = false;
  bool no_merge = false;
  bool keep_face_order = false;
  isochart::AtlasOptions options;
  // Signal-specialized atlas (§7).
  std::string signal;
  std::string signal_use = "full";
  std::string imt_out;
  std::string signal_texture_out;
  int sae_res = 0;  // 0: the packing size (--width x --height)
  isochart::SignalAtlasOptions signal_options;
  // The input's own texture carried over onto the atlas.
  std::string bake_texture;
  std::string texture;  // the image to carry over when not the one the input names
  GivenOptions given;
};

// Options that only a signal-specialized atlas reads.
constexpr std::initializer_list<const char*> kSignalOptions = {
    "--signal-use", "--beta", "--lambda", "--chart-lambda", "--split-efficiency", "--max-geometric-l2", "--sae-res"};

nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

// The baked texture's path as an OBJ's material names it: relative to the OBJ's directory,
// through symbolic links as they resolve (a name worked out from the spelling alone missed
// the file when the OBJ's directory was a link).
std::string material_texture_path(const std::string& obj, const std::string& texture) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(fs::absolute(obj).parent_path(), ec);
  const fs::path tex = fs::weakly_canonical(fs::absolute(texture), ec);
  return tex.lexically_relative(dir).string();
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// What --bake-texture cannot do with these outputs, refused before any work.
void check_bake_outputs(const AtlasArgs& a) {
  if (a.bake_texture.empty()) return;
  if (a.outputs.empty())
    bad_option("--bake-texture " + a.bake_texture +
               ": no -o output carries the texture coordinates the baked texture is laid out for");
  const std::string ext = lower_extension(a.bake_texture);
  for (const auto& out : a.outputs) {
    const isochart::MeshFormat f = isochart::format_from_path(out);
    if (f == isochart::MeshFormat::Glb && ext != ".png" && ext != ".jpg" && ext != ".jpeg")
      bad_option("--bake-texture " + a.bake_texture + ": " + out +
                 " can embed only a PNG or JPEG image (glTF); give a .png or .jpg texture");
    // `map_Kd` ends at the line's end, but most readers take its last word for the file.
    if (f == isochart::MeshFormat::Obj) {
      const std::string named = material_texture_path(out, a.bake_texture);
      if (named.find_first_of(" \t") != std::string::npos)
        bad_option("--bake-texture " + a.bake_texture + ": " + isochart::material_path(out) +
                   " would name it as '" + named +
                   "', and material readers split file names at spaces; give a path without spaces");
    }
  }
}

// What --bake-texture carries over: the images (or colours) faces read and the texture
// coordinates they read them at, as the input's materials read them.
struct Carry {
  std::vector<isochart::TextureSource> sources;
  std::vector<int> face_source;  // per face, into sources
  isochart::Mesh source;         // the input with the coordinates the materials read
  bool empty() const { return sources.empty(); }
};

// The input's materials, each face reading its own (an OBJ's `usemtl`, a glTF primitive's
// material): images read once each, coordinates moved per face by its material's map.
Carry carry_materials(const Context& ctx, const AtlasArgs& a, const isochart::Mesh& mesh) {
  MaterialImages m = read_material_images(a.input, mesh, a.bake_texture);
  // A material's texture belongs to the input model: baking over it would break the model.
  ctx.check_paths(m.files, {a.bake_texture});
  const long long untextured = m.untextured_faces;
  if (untextured == mesh.num_faces())
    throw isochart::InputError(
        a.input, "names no texture to carry over (--bake-texture); give one with --texture IMG");
  if (untextured > 0)
    ctx.warn(a.input, std::to_string(untextured) + (untextured == 1 ? " face reads" : " faces read") +
                          " no texture in its material; baked in the material's colour");
  Carry c;
  c.sources = std::move(m.sources);
  c.face_source = std::move(m.face_source);
  c.source = std::move(m.source);
  return c;
}

// The texture --bake-texture carries over (--texture, else `named`, the one the input names
// or embeds, or each face its own material's), read before any work so that a missing one
// fails at once. Without --bake-texture, a texture the input carries is not in the outputs,
// whose texture coordinates are new: said in a warning, with the remedy.
Carry texture_to_carry(const Context& ctx, const AtlasArgs& a, const isochart::LoadResult& in,
                       const isochart::MeshTexture& named) {
  if (a.bake_texture.empty()) {
    if (!in.mesh.has_uvs() || a.input.rfind("builtin:", 0) == 0) return {};
    const isochart::MeshTexture t = isochart::find_mesh_texture(a.input);
    if (!t.file.empty() || !t.bytes.empty())
      ctx.warn(a.input, "its texture " + (t.file.empty() ? std::string("(embedded)") : t.file) +
                            " is mapped through the texture coordinates the atlas replaces, so the outputs "
                            "do not carry it; --bake-texture FILE resamples it onto the atlas");
    return {};
  }
  const long long without = in.report.faces_without_uvs;
  if (!in.mesh.has_uvs())
    throw isochart::InputError(a.input,
                               "has no texture coordinates, so no texture to carry over (--bake-texture)");
  if (without > 0)
    throw isochart::InputError(a.input, std::to_string(without) +
                                            (without == 1 ? " face has" : " faces have") +
                                            " no texture coordinates to carry the texture over through "
                                            "(--bake-texture)");
  // Faces of several materials each read their own, unless --texture names one image for all.
  if (a.texture.empty() && named.several_materials && !in.mesh.face_materials.empty())
    return carry_materials(ctx, a, in.mesh);
  Carry c;
  c.sources.emplace_back();
  if (!a.texture.empty()) {
    c.sources[0].image = isochart::read_image(a.texture);
  } else {
    const isochart::MeshTexture& t = named;
    if (!t.problem.empty()) throw isochart::InputError(a.input, t.problem + " (--texture IMG names one)");
    c.sources[0].image = read_mesh_texture(t, a.bake_texture, a.input);
    if (c.sources[0].image.empty())
      throw isochart::InputError(
          a.input, "names no texture to carry over (--bake-texture); give one with --texture IMG");
  }
  // Read as the input's material reads its texture (its wrap and map transform), whichever
  // image --texture names.
  c.sources[0].wrap = named.wrap;
  c.face_source.assign(in.mesh.faces.size(), 0);
  c.source = as_material_reads(named, in.mesh);
  check_material_coordinates(a.input, c.source);
  return c;
}

void run_atlas(const Context& ctx, AtlasArgs a) {
  const auto t0 = std::chrono::steady_clock::now();
  // An option that would be silently ignored is more likely a mistake than a wish.
  if (a.given.has("--png-size") && a.png.empty()) bad_option("--png-size goes with --png");
  if (a.given.has("--alpha") && a.no_graph_cut)
    bad_option("--alpha weighs the graph cut; --no-graph-cut skips it");
  if (a.given.has("--merge-limit") && a.no_merge)
    bad_option("--merge-limit bounds the merging --no-merge skips");
  if (!a.texture.empty() && a.bake_texture.empty())
    bad_option("--texture names the image --bake-texture carries over; give --bake-texture FILE too");
  if (a.signal.empty())
    for (const char* name : kSignalOptions)
      if (a.given.has(name)) bad_option(std::string(name) + " goes with --signal");
  for (const auto& out : a.outputs)
    output_mesh_format(out, {isochart::MeshFormat::Obj, isochart::MeshFormat::Glb, isochart::MeshFormat::Ply},
                       ".obj, .glb or .ply");
  check_bake_outputs(a);
  isochart::MeshTexture named_texture;
  {
    std::vector<std::string> outs = a.outputs;
    for (const std::string* o : {&a.png, &a.imt_out, &a.signal_texture_out, &a.bake_texture})
      outs.push_back(*o);
    // An OBJ that carries the baked texture gets its material file beside it.
    if (!a.bake_texture.empty())
      for (const auto& out : a.outputs)
        if (isochart::format_from_path(out) == isochart::MeshFormat::Obj)
          outs.push_back(isochart::material_path(out));
    // The texture the input's material names is part of the input model, --texture or not:
    // baking over it would break the model.
    if (!a.bake_texture.empty() && a.input.rfind("builtin:", 0) != 0) {
      try {
        named_texture = isochart::find_mesh_texture(a.input);
      } catch (const isochart::InputError&) {
        // An input that cannot be read is refused below, by name.
      }
    }
    ctx.check_paths({a.input, signal_texture(a.signal), a.texture, named_texture.file}, outs);
    ctx.check_image_outputs({a.png, a.signal_texture_out, a.bake_texture});
  }
  a.options.seed = ctx.opts.seed;
  a.options.graph_cut = !a.no_graph_cut;
  a.options.merge = !a.no_merge;
  isochart::validate_options(a.options);
  if (!a.signal.empty()) {
    if (a.signal_use == "none") a.signal_options.use = isochart::SignalUse::None;
    else if (a.signal_use == "param") a.signal_options.use = isochart::SignalUse::Param;
    else if (a.signal_use == "full") a.signal_options.use = isochart::SignalUse::Full;
    else bad_option("--signal-use must be none, param or full");
    isochart::validate_signal_options(a.signal_options);
    // Chart building by the signal is what --signal-use full adds; elsewhere these change nothing.
    if (a.signal_options.use != isochart::SignalUse::Full)
      for (const char* name : {"--beta", "--chart-lambda", "--split-efficiency"})
        if (a.given.has(name))
          bad_option(std::string(name) + " goes with --signal-use full (it shapes the charts)");
    // A geometric atlas keeps --max-l2; the signal's parameterizations are what this bounds.
    if (a.signal_options.use == isochart::SignalUse::None && a.given.has("--max-geometric-l2"))
      bad_option(
          "--max-geometric-l2 goes with --signal-use param or full (--max-l2 bounds a geometric atlas)");
  }

  isochart::LoadResult in = ctx.load(a.input);
  Carry carry = texture_to_carry(ctx, a, in, named_texture);
  const double load_seconds = seconds_since(t0);
  isochart::Signal signal;
  isochart::SignalAtlasStats sig_stats;
  isochart::SaeResult sae;
  if (!a.signal.empty()) {
    signal = load_signal(ctx, a.signal, in, in.mesh, a.input);
    if (!a.imt_out.empty()) isochart::write_imt(a.imt_out, isochart::face_imt(in.mesh, signal));
  } else if (!a.imt_out.empty() || !a.signal_texture_out.empty()) {
    bad_option("--imt-out and --signal-texture-out need --signal");
  }
  // The library's input errors name no file: here they are about the input mesh.
  isochart::Atlas atlas = [&] {
    try {
      return a.signal.empty() ? isochart::build_atlas(in.mesh, a.options, ctx.progress())
                              : isochart::build_signal_atlas(in.mesh, signal, a.options, a.signal_options,
                                                             &sig_stats, ctx.progress());
    } catch (const isochart::InputError& e) {
      if (!e.file().empty()) throw;
      throw isochart::InputError(a.input, e.what());
    }
  }();
  const isochart::Mesh out_mesh = atlas.apply_to(in.mesh);
  // The SAE's texture has the atlas's shape and about --sae-res² texels: a 4:1 atlas baked into a
  // square texture measured twice the SAE of the same charts packed square. By default it is
  // the texture the atlas was packed for: measured at 256² a 1024² atlas's gutters and chart
  // borders weigh four times more, and the ranking of signal atlases against geometric ones
  // reversed (builtin:face, builtin:torus).
  // Past 4096² texels (about 400 MB to bake) the default keeps the shape at that size.
  const double aspect = static_cast<double>(a.options.pack.width) / a.options.pack.height;
  const double packed = std::sqrt(double(a.options.pack.width) * a.options.pack.height);
  const double res = a.sae_res > 0 ? a.sae_res : std::min(packed, 4096.0);
  const int sae_w = std::clamp(static_cast<int>(std::lround(res * std::sqrt(aspect))), 1, 8192);
  const int sae_h = std::clamp(static_cast<int>(std::lround(res / std::sqrt(aspect))), 1, 8192);
  if (!a.signal.empty()) {
    isochart::Image baked;
    sae = isochart::signal_approximation_error(out_mesh, signal, sae_w, sae_h,
                                               a.signal_texture_out.empty() ? nullptr : &baked);
    if (!a.signal_texture_out.empty()) {
      if (a.signal == "normals")
        for (auto& v : baked.pixels) v = 0.5f * v + 0.5f;
      isochart::write_image(a.signal_texture_out, baked);
    }
  }
  double bake_seconds = 0;
  bool bake_transparent = false;  // the outputs' materials then blend the texture's alpha
  const bool baking = !carry.empty();
  if (baking) {
    const auto t_bake = std::chrono::steady_clock::now();
    // At the packing size, 2×2 samples a texel up to 2048²; larger textures take one sample a
    // texel, as four would quadruple the time (the memory does not grow: the bake runs in bands).
    const int w = a.options.pack.width, h = a.options.pack.height;
    const int supersample = static_cast<long long>(w) * h <= 2048LL * 2048 ? 2 : 1;
    // The images are moved in (they are not needed after), so none is copied.
    const isochart::Image baked = isochart::transfer_textures(carry.source, std::move(carry.sources),
                                                              carry.face_source, out_mesh, w, h, supersample);
    const std::string ext = lower_extension(a.bake_texture);
    const int alpha = baked.alpha_channel();
    long long transparent = 0;
    if (alpha >= 0)
      for (std::size_t i = alpha; i < baked.pixels.size(); i += baked.channels)
        transparent += baked.pixels[i] < 0.999f ? 1 : 0;
    const bool jpeg = ext == ".jpg" || ext == ".jpeg";
    if (jpeg && transparent > 0)
      ctx.warn(a.bake_texture, "JPEG has no alpha: " + std::to_string(transparent) +
                                   " texels that are not opaque in the texture are written opaque");
    bake_transparent = transparent > 0 && !jpeg;
    isochart::write_image(a.bake_texture, baked);
    bake_seconds = seconds_since(t_bake);
  }
  const auto t_out = std::chrono::steady_clock::now();
  std::vector<std::string> materials;
  for (const auto& out : a.outputs) {
    isochart::SaveOptions so;
    so.texture_transparent = bake_transparent;
    if (a.keep_face_order) so.write_groups = isochart::ObjGroups::FaceOrder;
    if (baking) {
      const isochart::MeshFormat f = isochart::format_from_path(out);
      // An OBJ's material names the image relative to the OBJ; glb embeds it; PLY has no materials.
      if (f == isochart::MeshFormat::Obj) {
        so.texture = material_texture_path(out, a.bake_texture);
        materials.push_back(isochart::material_path(out));
      } else if (f == isochart::MeshFormat::Glb) {
        so.texture = a.bake_texture;
      }
    }
    isochart::save_mesh(out_mesh, out, so);
  }
  if (!a.png.empty()) {
    // The picture has the texture's proportions, its longer side --png-size pixels.
    const auto [pw, ph] = layout_size(a.png_size, aspect);
    isochart::write_image(a.png, isochart::render_uv_layout(out_mesh, pw, ph, aspect));
  }
  const auto& s = atlas.stats;
  // Every chart is accepted only within the bounds; the whole can still miss them where the
  // numbers cannot hold a triangle's shape (a sliver 1e-16 of its length high). Say so.
  // Signal atlases bound the signal-metric stretch; geometrically their charts keep
  // --max-geometric-l2 (full), or were built to --max-l2 and keep their geometric
  // parameterization where the signal one cannot meet --max-geometric-l2 (param).
  const isochart::SignalUse use = a.signal_options.use;
  const double max_gl2 = a.signal_options.max_geometric_l2;
  const double l2_bound = a.signal.empty() || use == isochart::SignalUse::None ? a.options.max_l2
                          : use == isochart::SignalUse::Param ? std::max(a.options.max_l2, max_gl2)
                                                              : max_gl2;
  if (!a.signal.empty() && use == isochart::SignalUse::Param && max_gl2 < a.options.max_l2 &&
      sig_stats.reverted_charts > 0)
    ctx.warn(a.input, std::to_string(sig_stats.reverted_charts) + " of " + std::to_string(s.charts) +
                          " charts keep their geometric parameterization: --signal-use param builds charts "
                          "to --max-l2 " +
                          plain_number(a.options.max_l2) + ", above --max-geometric-l2 " +
                          plain_number(max_gl2) +
                          ", and their signal parameterization could not meet the latter");
  // A signal atlas packs its charts at the densities the signal asks for, so measured as one
  // texture its charts read as shrunk against each other (bunny_lowres: Linf 5.64 with every
  // chart within 4.81 of bound 5). Its bounds are each chart's, measured at its own density.
  double chart_l2 = 0, chart_linf = 0;
  for (const auto& c : atlas.charts) {
    chart_l2 = std::max(chart_l2, c.l2);
    chart_linf = std::max(chart_linf, c.linf);
  }
  // --signal-use none packs geometrically: one texture, measured as such.
  const bool per_chart = !a.signal.empty() && use != isochart::SignalUse::None;
  const double l2_measured = per_chart ? chart_l2 : s.l2, linf_measured = per_chart ? chart_linf : s.linf;
  const bool bounds_met = l2_measured <= l2_bound * isochart::kStretchBoundSlack &&
                          linf_measured <= a.options.max_linf * isochart::kStretchBoundSlack &&
                          s.flipped == 0 && s.overlapping_pairs == 0;
  if (a.options.max_charts > 0 && s.charts > a.options.max_charts)
    // Not only the bounds: every chart must be a disk, so a closed surface is split (a sphere
    // into 6 whatever the bounds), and each separate piece is a chart of its own.
    ctx.warn(a.input,
             "the atlas needs " + std::to_string(s.charts) + " charts, more than --max-charts " +
                 std::to_string(a.options.max_charts) +
                 " (--max-charts only adds charts): its pieces must be cut into disks that meet the "
                 "stretch bounds, and only charts of at most " +
                 plain_number(100 * a.options.merge_max_fraction) +
                 " % of the faces are merged back (§6, --merge-limit); higher --max-l2, --max-linf or "
                 "--merge-limit may make fewer");
  if (!bounds_met) {
    std::ostringstream w;
    w << "the atlas misses its bounds (" << (per_chart ? "its charts' " : "") << "L2 " << l2_measured
      << ", Linf " << linf_measured << ", " << s.flipped << " flipped, " << s.overlapping_pairs
      << " overlapping pairs): some triangles are too thin for the coordinates' precision";
    ctx.warn(a.input, w.str());
  }
  // A long thin surface (a ribbon, a cable) is one chart as long as the texture is wide: in a
  // square texture it fills a sliver of it (a 1000:1 strip packed at 0.002). The texture's own
  // shape is the remedy, and the user may not think of it. A chart's length over its width is
  // about its extent squared over its area, whatever way it was turned in packing.
  // The packing ratio is of the charts' bounding box; in a texture much longer than that box
  // (a few charts in 8:1) most of the texture stays empty, which only the covered share says.
  double coverage = 0;
  for (const isochart::Face& t : atlas.face_uvs)
    coverage += std::abs(isochart::signed_area(atlas.uvs[t[0]], atlas.uvs[t[1]], atlas.uvs[t[2]]));
  bool warned_long_chart = false;
  if (s.packing_ratio < 0.25 && atlas.num_charts() > 0) {
    const int nc = atlas.num_charts();
    std::vector<isochart::Vec2d> lo(nc, {1e300, 1e300}), hi(nc, {-1e300, -1e300});
    std::vector<double> area(nc, 0);
    const double W = a.options.pack.width, H = a.options.pack.height;
    for (int f = 0; f < in.mesh.num_faces(); ++f) {
      const int c = atlas.face_chart[f];
      isochart::Vec2d p[3];
      for (int k = 0; k < 3; ++k) {
        const isochart::Vec2d& uv = atlas.uvs[atlas.face_uvs[f][k]];
        p[k] = {uv.x * W, uv.y * H};
        lo[c] = {std::min(lo[c].x, p[k].x), std::min(lo[c].y, p[k].y)};
        hi[c] = {std::max(hi[c].x, p[k].x), std::max(hi[c].y, p[k].y)};
      }
      area[c] += std::abs(isochart::signed_area(p[0], p[1], p[2]));
    }
    const int big = static_cast<int>(std::max_element(area.begin(), area.end()) - area.begin());
    const double dx = hi[big].x - lo[big].x, dy = hi[big].y - lo[big].y;
    const double elongation = area[big] > 0 ? (dx * dx + dy * dy) / area[big] : 0;
    if (elongation > 16) {
      std::ostringstream m;
      m << "the charts fill " << std::setprecision(2) << 100 * coverage
        << " % of the texture: the largest is about " << std::lround(elongation)
        << " times longer than wide; a texture of its shape (--width/--height) holds it at a higher "
           "resolution";
      ctx.warn(a.input, m.str());
      warned_long_chart = true;
    }
  }
  // The other way round: charts of no particular shape in a texture many times longer than
  // high line up along it and leave most of it empty (fandisk fills 1.9 % of 600×12).
  const double texture_aspect = static_cast<double>(a.options.pack.width) / a.options.pack.height;
  if (std::abs(std::log(texture_aspect)) >= std::log(4.0) && coverage < 0.5 && !warned_long_chart) {
    std::ostringstream m;
    m << "the charts fill " << std::setprecision(2) << 100 * coverage << " % of the " << a.options.pack.width
      << "x" << a.options.pack.height
      << " texture: in one this elongated they leave most of it empty; a squarer texture of as many "
         "texels holds them at a higher resolution";
    ctx.warn(a.input, m.str());
  }

  nlohmann::json j;
  j["file"] = a.input;
  // Every file written, the side outputs too (they also keep their own keys).
  std::vector<std::string> written = a.outputs;
  for (const std::string* side : {&a.png, &a.signal_texture_out, &a.imt_out, &a.bake_texture})
    if (!side->empty()) written.push_back(*side);
  written.insert(written.end(), materials.begin(), materials.end());
  j["outputs"] = written;
  if (!a.png.empty()) j["png"] = a.png;
  if (!a.bake_texture.empty()) j["baked_texture"] = a.bake_texture;
  j["faces"] = in.mesh.num_faces();
  j["charts"] = s.charts;
  j["charts_before_merge"] = s.charts_before_merge;
  j["l2_stretch"] = finite_or_null(s.l2);
  j["linf_stretch"] = finite_or_null(s.linf);
  j["packing_ratio"] = s.packing_ratio;
  j["texture_coverage"] = coverage;
  j["flipped"] = s.flipped;
  j["overlapping_pairs"] = s.overlapping_pairs;
  j["bounds_met"] = bounds_met;
  j["chart_l2_max"] = finite_or_null(chart_l2);
  j["chart_linf_max"] = finite_or_null(chart_linf);
  j["splits"] = s.splits;
  j["seed"] = s.seed;
  j["options"] = {{"max_l2", a.options.max_l2},
                  {"max_linf", a.options.max_linf},
                  {"max_charts", a.options.max_charts},
                  {"landmarks", a.options.landmarks},
                  {"alpha", a.options.alpha},
                  {"graph_cut", a.options.graph_cut},
                  {"merge", a.options.merge},
                  {"merge_limit", a.options.merge_max_fraction},
                  {"pack_grid", a.options.pack.search_size},
                  {"width", a.options.pack.width},
                  {"height", a.options.pack.height},
                  {"gutter", a.options.pack.gutter}};
  if (!a.signal.empty()) {
    j["signal"] = {{"signal", a.signal},
                   {"use", a.signal_use},
                   {"lambda", a.signal_options.lambda},
                   {"chart_lambda", a.signal_options.chart_lambda},
                   {"split_efficiency", a.signal_options.split_efficiency},
                   {"beta", a.signal_options.beta},
                   {"max_geometric_l2", a.signal_options.max_geometric_l2},
                   {"signal_stretch", finite_or_null(sig_stats.signal_stretch)},
                   {"metric_l2", finite_or_null(sig_stats.metric_l2)},
                   {"reverted_charts", sig_stats.reverted_charts},
                   {"sae_res", a.sae_res},
                   {"sae_width", sae_w},
                   {"sae_height", sae_h},
                   {"sae", sae.sae},
                   {"signal_rms", sae.signal_rms}};
    j["sae"] = sae.sae;
    if (!a.imt_out.empty()) j["imt"] = a.imt_out;
    if (!a.signal_texture_out.empty()) j["signal_texture"] = a.signal_texture_out;
  }
  nlohmann::json secs = s.seconds;
  if (!a.signal.empty()) secs["sae"] = sae.seconds;
  if (!a.bake_texture.empty()) secs["bake"] = bake_seconds;
  secs["load"] = load_seconds;
  secs["output"] = seconds_since(t_out);
  secs["total"] = seconds_since(t0);
  j["seconds"] = secs;
  nlohmann::json charts = nlohmann::json::array();
  for (const auto& c : atlas.charts)
    charts.push_back({{"faces", c.faces}, {"area", c.area_3d}, {"l2", finite_or_null(c.l2)}, {"linf", finite_or_null(c.linf)}});
  j["chart_list"] = charts;

  std::ostringstream t;
  t << a.input << ": " << s.charts << " charts (" << s.charts_before_merge << " before merging)\n"
    << "  L2 stretch        " << s.l2;
  if (per_chart)
    t << "  (charts up to " << chart_l2 << ", bound " << l2_bound << " geometric per chart)\n"
      << "  Linf stretch      " << s.linf << "  (charts up to " << chart_linf << ", bound "
      << a.options.max_linf << " per chart; the atlas's texel density follows the signal)\n";
  else
    t << "  (bound " << l2_bound << ")\n"
      << "  Linf stretch      " << s.linf << "  (bound " << a.options.max_linf << ")\n";
  t << "  packing ratio     " << s.packing_ratio;
  if (coverage < 0.9 * s.packing_ratio)
    t << "  (of the charts' bounding box; texture covered " << coverage << ")";
  t << "\n"
    << "  flipped / overlapping pairs  " << s.flipped << " / " << s.overlapping_pairs << "\n"
    << "  seconds           " << secs["total"].get<double>() << "\n";
  if (!a.signal.empty())
    t << "  signal " << a.signal << " (" << a.signal_use << "): signal stretch " << sig_stats.signal_stretch
      << ", SAE " << sae.sae << " at " << sae_w << "x" << sae_h << "\n";
  for (const auto& out : written) t << "  wrote " << out << "\n";
  ctx.emit(j, t.str());
}

}  // namespace

void add_atlas(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<AtlasArgs>();
  auto& o = args->options;
  CLI::App* sub = app.add_subcommand("atlas", "Build a stretch-bounded iso-chart texture atlas");
  sub->add_option("input", args->input, "Mesh file (OBJ/OFF/PLY/glTF) or builtin:NAME")->required();
  sub->add_option("-o,--output", args->outputs, "Output mesh with UVs (.obj, .glb, .ply); repeat for several");
  sub->add_option("--png", args->png,
                  "Also draw the chart layout into this image (PNG; JPG, TIFF, EXR, ... by extension)");
  // The layout is drawn at 2×2 samples per pixel, at most 2^25 samples in all.
  sub->add_option("--png-size", args->png_size, "Size of the layout PNG in pixels (at most 2896)")
      ->check(CLI::Range(16, 2896));
  sub->add_option("--max-l2", o.max_l2, "Bound on every chart's L2 stretch (at least 1; 1 = isometric)")
      ->capture_default_str();
  sub->add_option("--max-linf", o.max_linf,
                  "Bound on every chart's Linf stretch, shrink included (at least 1)")
      ->capture_default_str();
  sub->add_option(
         "--max-charts", o.max_charts,
         "0: as few charts as the bounds allow; N: split further until N charts (never fewer than the "
         "bounds and disk-shaped charts need)")
      ->capture_default_str();
  sub->add_option(
         "--width", o.pack.width,
         "Texture width in texels (packing; 8 to " + std::to_string(isochart::PackOptions::kMaxSize) + ")")
      ->capture_default_str();
  sub->add_option(
         "--height", o.pack.height,
         "Texture height in texels (packing; 8 to " + std::to_string(isochart::PackOptions::kMaxSize) + ")")
      ->capture_default_str();
  sub->add_option("--gutter", o.pack.gutter, "Empty texels between charts (0 to 64)")->capture_default_str();
  sub->add_option("--pack-grid", o.pack.search_size,
                  "Longest side of the grid the packing is searched on (64 to 8192; 0: the texture's "
                  "own): a larger texture is packed on one an integer times coarser, the gutter rounded up")
      ->check(CLI::Range(0, isochart::PackOptions::kMaxSize))
      ->capture_default_str();
  sub->add_option("--pack-cuts", o.pack_cuts,
                  "Extra charts cut off poorly shaped ones when that packs tighter (-1: automatic, under 12 "
                  "charts; 0: none)")
      ->capture_default_str();
  sub->add_option("--landmarks", o.landmarks,
                  "IsoMap landmarks of a whole component (at least 3); a sub-chart gets its share by "
                  "vertices, at least 25")
      ->capture_default_str();
  sub->add_option("--alpha", o.alpha, "Graph-cut weight of dihedral angle vs. embedding distortion")->capture_default_str();
  sub->add_flag("--no-graph-cut", args->no_graph_cut, "Skip graph-cut boundary optimization (ablation)");
  sub->add_flag("--no-merge", args->no_merge, "Skip merging small charts");
  sub->add_option("--merge-limit", o.merge_max_fraction,
                  "Charts of up to this fraction of the faces are merged into a neighbour when the union "
                  "meets the bounds (§6); larger values make fewer charts on simple shapes, for more "
                  "merging time")
      ->check(number_in(0.0, 1.0))
      ->capture_default_str();
  sub->add_option("--signal", args->signal,
                  "Specialize the atlas to a signal (§7): normals, colors, or texture:IMG (through the input's UVs)");
  sub->add_option("--signal-use", args->signal_use,
                  "none: geometric atlas, signal measured; param: geometric charts, signal parameterization; "
                  "full: signal charts and parameterization")
      ->capture_default_str();
  sub->add_option("--beta", args->signal_options.beta, "Eq. 6 weight of geodesic vs. signal distance")
      ->check(number_in(0.0, 1.0))
      ->capture_default_str();
  sub->add_option("--lambda", args->signal_options.lambda,
                  "Weight of the signal against the geometry in the metric")
      ->check(non_negative)
      ->capture_default_str();
  sub->add_option("--chart-lambda", args->signal_options.chart_lambda,
                  "Signal weight of the metric that splits and merges charts (0 = --lambda)")
      ->check(non_negative)
      ->capture_default_str();
  sub->add_option(
         "--split-efficiency", args->signal_options.split_efficiency,
         "Split large signal charts whose uniform texel density reaches less than this fraction of the "
         "ideal signal energy (0 = off)")
      ->check(number_in(0.0, 1.0))
      ->capture_default_str();
  sub->add_option("--max-geometric-l2", args->signal_options.max_geometric_l2,
                  "Geometric L2 stretch bound kept by signal charts")
      ->capture_default_str();
  // The same limit as sae's --res: 8192² takes 1.5 GB, 16384² took 6.3 GB.
  sub->add_option("--sae-res", args->sae_res,
                  "Texture size at which the SAE is reported (about this many texels squared, in the "
                  "--width:--height shape; default: the packing size, at most 4096 squared)")
      ->check(CLI::Range(1, 8192));
  sub->add_option("--imt-out", args->imt_out,
                  "Write the per-face IMT (g00 g01 g11 per line, in the input's face order)");
  sub->add_flag("--keep-face-order", args->keep_face_order,
                "Write the OBJ's faces in the input's order (a `g chartN` wherever the chart changes) "
                "instead of each chart's faces together");
  sub->add_option("--signal-texture-out", args->signal_texture_out,
                  "Write the signal baked into the atlas at the SAE's size (normals as 0.5n+0.5)");
  sub->add_option("--bake-texture", args->bake_texture,
                  "Carry the input's texture over: resample it through the input's UVs onto the atlas "
                  "(--width x --height) into this image, which the OBJ's material and the glb reference");
  sub->add_option("--texture", args->texture,
                  "With --bake-texture: the image to carry over, instead of the one the input's material "
                  "names or its glb embeds");
  sub->footer("Example: isocharts atlas builtin:creature -o creature_atlas.obj --png creature_atlas.png");
  sub->callback([&ctx, args, sub, &action] {
    args->given.record(sub, {"--png-size", "--alpha", "--merge-limit"});
    args->given.record(sub, kSignalOptions);
    action = [&ctx, args] { run_atlas(ctx, *args); };
  });
}

}  // namespace cli
