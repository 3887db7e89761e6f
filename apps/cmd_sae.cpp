// `isocharts sae MESH_WITH_UV --signal normals --res 256`: the signal approximation error of an
// atlas (Iso-charts §9.3).

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
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
  GivenOptions given;
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
  // A lone --width gave a texture of that width and --res's height: 2048x256 for a square atlas.
  if ((a.width > 0) != (a.height > 0)) bad_option("--width and --height go together");
  if (a.width > 0 && a.given.has("--res")) bad_option("--res and --width/--height are exclusive");
  const int width = a.width > 0 ? a.width : a.res;
  const int height = a.height > 0 ? a.height : a.res;
  ctx.check_paths({a.input, a.source, signal_texture(a.signal)}, {a.texture_out, a.imt_out});
  ctx.check_image_outputs({a.texture_out});
  const isochart::LoadResult loaded = ctx.load(a.input, true);
  const isochart::Mesh& mesh = loaded.mesh;
  if (!mesh.has_uvs())
    throw isochart::InputError(a.input, "mesh has no texture coordinates; nothing to measure");
  {
    // The SAE bakes the signal into one texture through the UVs: where they leave it, overlap
    // or collapse, texels are shared or clamped and the figure says little about the atlas.
    const isochart::AtlasQuality q = isochart::measure_atlas(mesh);
    // Texels exist only inside [0, 1]²: a triangle past the edge bakes nothing there, and its
    // samples read the edge's texels, which hold other triangles' signal or none.
    int off = 0, past = 0;
    for (const auto& f : mesh.face_uvs) {
      bool out = false, in_x = false, in_y = false;
      double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
      for (int c = 0; c < 3; ++c) {
        const isochart::Vec2d& t = mesh.uvs[f[c]];
        out = out || t.x < 0 || t.x > 1 || t.y < 0 || t.y > 1;
        lo_x = std::min(lo_x, t.x), hi_x = std::max(hi_x, t.x);
        lo_y = std::min(lo_y, t.y), hi_y = std::max(hi_y, t.y);
      }
      in_x = hi_x >= 0 && lo_x <= 1;
      in_y = hi_y >= 0 && lo_y <= 1;
      if (!(in_x && in_y))
        ++off;
      else if (out)
        ++past;
    }
    if (off == static_cast<int>(mesh.face_uvs.size()))
      throw isochart::InputError(a.input,
                                 "texture coordinates lie wholly outside [0, 1]; no texel of the texture "
                                 "would hold the signal");
    if (off + past > 0)
      warn_uvs_outside(ctx, a.input, q,
                       std::to_string(off + past) + " of " + std::to_string(mesh.face_uvs.size()) +
                           " triangles reach past the texture's edge, where they get no texels and read the "
                           "edge's instead, which raises the SAE");
    // An 8:1 atlas baked into a square texture reads as twice the signal stretch it has.
    read_texture_aspect(ctx, a.input, mesh, static_cast<double>(width) / height,
                        "the texture measured is " + std::to_string(width) + "x" + std::to_string(height));
    if (q.overlapping_pairs > 0)
      ctx.warn(a.input, std::to_string(q.overlapping_pairs) +
                            " pairs of triangles overlap in UV; they share texels, which raises the SAE");
    if (q.stretch.degenerate > 0)
      ctx.warn(a.input, std::to_string(q.stretch.degenerate) +
                            (q.stretch.degenerate == 1 ? " triangle has" : " triangles have") +
                            " zero area in UV; they get no texels");
    warn_sparse_chart(ctx, a.input, q.sparsest, "its signal is sampled by almost no texels");
  }
  // The signal lives on the source mesh (the atlas's mesh, perhaps numbered otherwise) when one is given:
  // e.g. its vertex colours, or a texture through its original texture coordinates.
  isochart::Signal signal;
  if (!a.source.empty()) {
    // Joined like the atlas, so that a source split at the same seams numbers alike.
    const isochart::LoadResult src_loaded = ctx.load(a.source, true);
    const isochart::Mesh& src = src_loaded.mesh;
    if (src.num_vertices() != mesh.num_vertices() || src.num_faces() != mesh.num_faces())
      throw isochart::InputError(a.source, "has " + std::to_string(src.num_vertices()) + " vertices and " +
                                               std::to_string(src.num_faces()) + " faces, the atlas " +
                                               std::to_string(mesh.num_vertices()) + " and " +
                                               std::to_string(mesh.num_faces()));
    // Each atlas vertex takes the source vertex at its position (a glb, split by chart and
    // joined again on loading, numbers them otherwise), and each atlas face the source face on
    // the same vertices, its corners turned alike (a glb also groups faces by chart). Matching
    // by number alone gave a wrong SAE without a word (9x on eight) or refused glb atlases.
    const double tolerance = 1e-6 * isochart::bounding_box(mesh).diagonal();
    std::vector<int> source_of(mesh.num_vertices(), -1);
    {
      const double cell = std::max(tolerance, 1e-300);
      auto cell_of = [&](const isochart::Vec3d& p) {
        return std::array<long long, 3>{static_cast<long long>(std::floor(p.x / cell)),
                                        static_cast<long long>(std::floor(p.y / cell)),
                                        static_cast<long long>(std::floor(p.z / cell))};
      };
      std::map<std::array<long long, 3>, std::vector<int>> grid;
      for (int v = 0; v < src.num_vertices(); ++v) grid[cell_of(src.positions[v])].push_back(v);
      std::vector<char> taken(src.num_vertices(), 0);
      for (int v = 0; v < mesh.num_vertices(); ++v) {
        const auto c = cell_of(mesh.positions[v]);
        int best = -1;
        double best_d = tolerance;
        for (long long dx = -1; dx <= 1; ++dx)
          for (long long dy = -1; dy <= 1; ++dy)
            for (long long dz = -1; dz <= 1; ++dz) {
              const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
              if (it == grid.end()) continue;
              for (int u : it->second) {
                const double d = isochart::norm(src.positions[u] - mesh.positions[v]);
                if (!taken[u] && (d < best_d || (d == best_d && best < 0))) {
                  best = u;
                  best_d = d;
                }
              }
            }
        if (best < 0) {
          std::ostringstream msg;
          msg << "has no vertex at the atlas's vertex " << v << " (" << mesh.positions[v].x << ", "
              << mesh.positions[v].y << ", " << mesh.positions[v].z
              << "); the source must be the atlas's mesh";
          throw isochart::InputError(a.source, msg.str());
        }
        taken[best] = 1;
        source_of[v] = best;
      }
    }
    std::vector<int> atlas_of(src.num_vertices(), -1);
    for (int v = 0; v < mesh.num_vertices(); ++v) atlas_of[source_of[v]] = v;
    isochart::Mesh ordered = src;
    ordered.positions = mesh.positions;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (src.has_normals()) ordered.normals[v] = src.normals[source_of[v]];
      if (src.has_colors()) ordered.colors[v] = src.colors[source_of[v]];
    }
    {
      auto key = [](const isochart::Face& t) {
        const int k = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
        return std::array<int, 3>{t[k], t[(k + 1) % 3], t[(k + 2) % 3]};
      };
      std::vector<isochart::Face> renumbered(src.faces.size());
      std::map<std::array<int, 3>, std::vector<int>> by_corners;
      for (int g = src.num_faces() - 1; g >= 0; --g) {
        for (int i = 0; i < 3; ++i) renumbered[g][i] = atlas_of[src.faces[g][i]];
        by_corners[key(renumbered[g])].push_back(g);
      }
      for (int f = 0; f < mesh.num_faces(); ++f) {
        auto it = by_corners.find(key(mesh.faces[f]));
        if (it == by_corners.end() || it->second.empty())
          throw isochart::InputError(a.source, "has no face on the vertices of the atlas's face " +
                                                   std::to_string(f) +
                                                   "; the source must be the atlas's mesh");
        const int g = it->second.back();
        it->second.pop_back();
        int turn = 0;
        while (renumbered[g][turn] != mesh.faces[f][0]) ++turn;
        ordered.faces[f] = mesh.faces[f];
        if (src.has_uvs())
          for (int i = 0; i < 3; ++i) ordered.face_uvs[f][i] = src.face_uvs[g][(turn + i) % 3];
      }
    }
    signal = load_signal(ctx, a.signal, src_loaded, ordered, a.source);
  } else {
    signal = load_signal(ctx, a.signal, loaded, mesh, a.input);
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
      "Mesh carrying the signal (the atlas's mesh: vertices matched by position, faces by their vertices), "
      "e.g. the original with its colours or UVs");
  sub->add_option("--res", args->res, "Texture size in texels (square)")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  // 8192² takes 1.5 GB, 16384² 6 GB.
  sub->add_option("--width", args->width, "Texture width (with --height, instead of --res)")
      ->check(CLI::Range(1, 8192));
  sub->add_option("--height", args->height, "Texture height (with --width, instead of --res)")
      ->check(CLI::Range(1, 8192));
  sub->add_option("--texture-out", args->texture_out, "Write the baked signal texture (normals as 0.5n+0.5)");
  sub->add_option("--imt-out", args->imt_out, "Write the per-face IMT (g00 g01 g11 per line)");
  sub->footer("Example: isocharts sae bunny_atlas.obj --signal normals --res 256 --json");
  sub->callback([&ctx, args, sub, &action] {
    args->given.record(sub, {"--res"});
    action = [&ctx, args] { run_sae(ctx, *args); };
  });
}

}  // namespace cli
