// `isocharts sae MESH_WITH_UV --signal normals --res 256`: the signal approximation error of an
// atlas (Iso-charts §9.3).

#include <cmath>
#include <sstream>

#include "cli.h"
#include "isochart/error.h"
#include "isochart/image.h"
#include "isochart/mesh.h"
#include "isochart/signal.h"
#include "isochart/stretch.h"

namespace cli {

namespace {

struct SaeArgs {
  std::string input;
  std::string signal = "normals";
  std::string source;
  int res = 256;
  int width = 0;
  int height = 0;
  std::string texture_out;
  std::string imt_out;
};

// Normals in [-1, 1] become displayable colours; colours and textures are written as they are.
isochart::Image displayable(const isochart::Image& img, bool signed_values) {
  isochart::Image out = img;
  if (signed_values)
    for (auto& v : out.pixels) v = 0.5f * v + 0.5f;
  return out;
}

void run_sae(const Context& ctx, const SaeArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const int width = a.width > 0 ? a.width : a.res;
  const int height = a.height > 0 ? a.height : a.res;
  ctx.check_paths({a.input, a.source, signal_texture(a.signal)}, {a.texture_out, a.imt_out});
  ctx.check_image_outputs({a.texture_out});
  const isochart::LoadResult loaded = ctx.load(a.input, true);
  const isochart::Mesh& mesh = loaded.mesh;
  if (!mesh.has_uvs())
    throw isochart::InputError(a.input, "mesh has no texture coordinates (vt); nothing to measure");
  {
    // The SAE bakes the signal into one texture through the UVs: where they leave it, overlap
    // or collapse, texels are shared or clamped and the figure says little about the atlas.
    const isochart::AtlasQuality q = isochart::measure_atlas(mesh);
    const double tol = 1e-9;
    if (q.uv_min.x < -tol || q.uv_min.y < -tol || q.uv_max.x > 1 + tol || q.uv_max.y > 1 + tol) {
      std::ostringstream w;
      w << "texture coordinates reach outside [0, 1] (" << q.uv_min.x << ".." << q.uv_max.x << " by "
        << q.uv_min.y << ".." << q.uv_max.y << "); they are clamped to the texture's edge";
      ctx.warn(a.input, w.str());
    }
    if (q.overlapping_pairs > 0)
      ctx.warn(a.input, std::to_string(q.overlapping_pairs) +
                            " pairs of triangles overlap in UV; they share texels, which raises the SAE");
    if (q.stretch.degenerate > 0)
      ctx.warn(a.input,
               std::to_string(q.stretch.degenerate) + " triangles have zero area in UV; they get no texels");
  }
  // The signal lives on the source mesh (same vertices and faces) when one is given: e.g. its
  // vertex colours, or a texture through its original texture coordinates.
  isochart::Signal signal;
  if (!a.source.empty()) {
    // Joined like the atlas, so that a source split at the same seams numbers alike.
    const isochart::LoadResult src_loaded = ctx.load(a.source, true);
    check_signal_uvs(a.signal, src_loaded, a.source);
    const isochart::Mesh& src = src_loaded.mesh;
    if (src.num_vertices() != mesh.num_vertices() || src.num_faces() != mesh.num_faces())
      throw isochart::InputError(a.source, "has " + std::to_string(src.num_vertices()) + " vertices and " +
                                               std::to_string(src.num_faces()) + " faces, the atlas " +
                                               std::to_string(mesh.num_vertices()) + " and " +
                                               std::to_string(mesh.num_faces()));
    // The signal goes to the atlas's vertex of the same number: a re-export that renumbered
    // the vertices gave a wrong SAE (9x on eight) without a word.
    const double tolerance = 1e-6 * isochart::bounding_box(mesh).diagonal();
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (!(isochart::norm(src.positions[v] - mesh.positions[v]) <= tolerance)) {
        std::ostringstream msg;
        msg << "vertex " << v << " is at (" << src.positions[v].x << ", " << src.positions[v].y << ", "
            << src.positions[v].z << "), the atlas's at (" << mesh.positions[v].x << ", "
            << mesh.positions[v].y << ", " << mesh.positions[v].z
            << "); the source must have the atlas's vertices in the same order";
        throw isochart::InputError(a.source, msg.str());
      }
    for (int f = 0; f < mesh.num_faces(); ++f)
      if (src.faces[f] != mesh.faces[f])
        throw isochart::InputError(a.source, "face " + std::to_string(f) +
                                                 " has other vertices than the atlas's; the source must "
                                                 "have the atlas's faces in the same order");
    signal = isochart::make_signal(src, a.signal, a.source);
  } else {
    check_signal_uvs(a.signal, loaded, a.input);
    signal = isochart::make_signal(mesh, a.signal, a.input);
  }
  isochart::Image baked;
  const isochart::SaeResult r = isochart::signal_approximation_error(mesh, signal, width, height, &baked);
  const std::vector<isochart::Imt> imt = isochart::face_imt(mesh, signal);
  // Measured in texels: a unit of u is width / height units of v.
  isochart::Mesh in_texels = mesh;
  for (isochart::Vec2d& uv : in_texels.uvs) uv.x *= static_cast<double>(width) / height;
  const double sst = isochart::signal_stretch(in_texels, imt);
  if (!a.texture_out.empty()) isochart::write_image(a.texture_out, displayable(baked, a.signal == "normals"));
  if (!a.imt_out.empty()) isochart::write_imt(a.imt_out, imt);

  nlohmann::json j;
  j["file"] = a.input;
  j["signal"] = a.signal;
  j["width"] = width;
  j["height"] = height;
  j["sae"] = r.sae;
  j["signal_rms"] = r.signal_rms;
  j["signal_stretch"] = std::isfinite(sst) ? nlohmann::json(sst) : nlohmann::json();
  j["samples"] = r.samples;
  if (!a.texture_out.empty()) j["texture"] = a.texture_out;
  if (!a.imt_out.empty()) j["imt"] = a.imt_out;
  j["seconds"] = {{"sae", r.seconds}, {"total", seconds_since(t0)}};
  std::ostringstream t;
  t << a.input << ": SAE " << r.sae << " at " << width << "x" << height << " (signal rms " << r.signal_rms
    << ", signal stretch " << sst << ")\n";
  if (!a.texture_out.empty()) t << "  wrote " << a.texture_out << "\n";
  if (!a.imt_out.empty()) t << "  wrote " << a.imt_out << "\n";
  ctx.emit(j, t.str());
}

}  // namespace

void add_sae(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<SaeArgs>();
  CLI::App* sub = app.add_subcommand("sae", "Signal approximation error of an atlas (a mesh with UVs)");
  sub->add_option("input", args->input, "Mesh with texture coordinates (OBJ/PLY/glTF)")->required();
  sub->add_option("--signal", args->signal, "normals, colors, or texture:IMG (mapped through --source's UVs)")
      ->capture_default_str();
  sub->add_option(
      "--source", args->source,
      "Mesh carrying the signal (same vertices and faces), e.g. the original with its colours or UVs");
  sub->add_option("--res", args->res, "Texture size in texels (square)")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  // 8192² takes 1.5 GB, 16384² 6 GB.
  sub->add_option("--width", args->width, "Texture width (overrides --res)")->check(CLI::Range(1, 8192));
  sub->add_option("--height", args->height, "Texture height (overrides --res)")->check(CLI::Range(1, 8192));
  sub->add_option("--texture-out", args->texture_out, "Write the baked signal texture (normals as 0.5n+0.5)");
  sub->add_option("--imt-out", args->imt_out, "Write the per-face IMT (g00 g01 g11 per line)");
  sub->footer("Example: isocharts sae bunny_atlas.obj --signal normals --res 256 --json");
  sub->callback([&ctx, args, &action] { action = [&ctx, args] { run_sae(ctx, *args); }; });
}

}  // namespace cli
