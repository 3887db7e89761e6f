// `isocharts render MESH -o view.png`: shaded, chart-coloured or textured views of a mesh, or
// its UV layout.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "cli.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/image.h"
#include "isochart/render.h"

namespace cli {

namespace {

struct RenderArgs {
  std::string input;
  std::string output;
  std::string texture;
  bool charts = false;
  bool shaded = false;  // ignore the mesh's own texture
  bool wireframe = false;
  bool uv_layout = false;
  bool ortho = false;
  bool transparent = false;
  int views = 4;
  int width = 0;   // 0: 400 per view (1024 for --uv-layout)
  int height = 0;  // 0: 400 (1024 for --uv-layout)
  int supersample = 2;
  double aspect = 0;     // --uv-layout: texture width / height (0: square)
  std::string up = "y";  // the model's up axis: x, y, z, -x, -y or -z
  bool views_or_up_given = false;
  bool supersample_given = false;
};

isochart::Vec3d up_axis(const std::string& name) {
  const bool negative = !name.empty() && name[0] == '-';
  const std::string axis = negative ? name.substr(1) : name;
  const double sign = negative ? -1.0 : 1.0;
  if (axis == "x") return {sign, 0, 0};
  if (axis == "y") return {0, sign, 0};
  if (axis == "z") return {0, 0, sign};
  bad_option("--up must be x, y, z, -x, -y or -z, not '" + name + "'");
}

void run_render(const Context& ctx, const RenderArgs& a) {
  up_axis(a.up);  // reject a bad axis before loading anything
  const auto t0 = std::chrono::steady_clock::now();
  if (int(a.charts) + int(a.shaded) + int(!a.texture.empty()) > 1)
    bad_option("--charts, --shaded and --texture are exclusive");
  if (a.uv_layout && (a.shaded || a.charts))
    bad_option("--uv-layout draws the atlas itself, its charts coloured; it takes no --shaded or --charts");
  ctx.check_paths({a.input, a.texture}, {a.output});
  ctx.check_image_outputs({a.output});
  if (a.uv_layout && (!a.texture.empty() || a.wireframe || a.ortho || a.transparent))
    bad_option(
        "--uv-layout draws the atlas itself; it takes no --texture, --wireframe, --ortho or --transparent");
  if (a.uv_layout && a.views_or_up_given)
    bad_option("--uv-layout draws texture space; it takes no --views or --up");
  if (a.uv_layout && a.supersample_given)
    bad_option("--uv-layout always draws with " + std::to_string(isochart::kUvLayoutSupersample) + "x" +
               std::to_string(isochart::kUvLayoutSupersample) + " supersampling; it takes no --supersample");
  if (a.transparent) {
    std::string ext = a.output.substr(std::min(a.output.size(), a.output.find_last_of('.')));
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".jpg" || ext == ".jpeg")
      bad_option("--transparent needs an image with alpha (.png, .exr, .tif), not JPEG");
  }
  if (a.aspect > 0 && !a.uv_layout) bad_option("--aspect goes with --uv-layout");
  double aspect = a.aspect > 0 ? a.aspect : 1.0;
  // A layout picture defaults to the texture's proportions, its longer side 1024; one side
  // given, the other follows the proportions (--aspect 8 --width 100 drew a band in 100x128).
  const auto picture_size = [&](double texture_aspect) -> std::array<int, 2> {
    if (!a.uv_layout) return {a.width > 0 ? a.width : 400 * a.views, a.height > 0 ? a.height : 400};
    if (a.width > 0 && a.height > 0) return {a.width, a.height};
    if (a.width > 0) return {a.width, std::max(16, static_cast<int>(std::lround(a.width / texture_aspect)))};
    if (a.height > 0)
      return {std::max(16, static_cast<int>(std::lround(a.height * texture_aspect))), a.height};
    return layout_size(1024, texture_aspect);
  };
  const int ss = a.uv_layout ? isochart::kUvLayoutSupersample : a.supersample;
  const auto check_size = [&](int w, int h) {
    if (static_cast<long long>(w) * h * ss * ss > (1LL << 25))
      bad_option(
          "--width/--height/--supersample: " + std::to_string(w) + "x" + std::to_string(h) +
          " pixels at supersample " + std::to_string(ss) +
          " is too large to render (width x height x supersample² at most 33554432, e.g. 4096x2048 at 2)");
  };
  auto [width, height] = picture_size(aspect);
  check_size(width, height);
  if (!a.uv_layout && width < a.views)
    bad_option("--width " + std::to_string(width) + " is too small for " + std::to_string(a.views) +
               " views");

  // Built-in meshes are clean by construction and need no loading or repair.
  const std::string prefix = "builtin:";
  isochart::Mesh mesh = a.input.rfind(prefix, 0) == 0 ? isochart::make_builtin(a.input.substr(prefix.size()))
                                                      : ctx.load(a.input).mesh;
  // The options are checked above, so what the library still rejects is the mesh's content
  // (no charts, no UVs, bad indices): name the mesh file.
  auto for_input = [&](auto&& fn) {
    try {
      return fn();
    } catch (const isochart::InputError& e) {
      if (!e.file().empty()) throw;
      throw isochart::InputError(a.input, e.what());
    }
  };

  isochart::Image image;
  std::string mode;
  if (a.uv_layout) {
    // Without --aspect, a layout made for a non-square texture is drawn in that shape.
    if (a.aspect <= 0 && mesh.has_uvs()) {
      const double detected =
          read_texture_aspect(ctx, a.input, mesh, 1.0, "drawn in that shape (--aspect sets it)");
      if (detected != 1.0) {
        aspect = detected;
        const std::array<int, 2> size = picture_size(aspect);
        width = size[0];
        height = size[1];
        check_size(width, height);
      }
    }
    image = for_input([&] { return isochart::render_uv_layout(mesh, width, height, aspect); });
    mode = "uv-layout";
  }
  std::string own;           // the mesh's own texture drawn: its file, or "embedded"
  MaterialImages materials;  // or its materials' images, each face its own
  if (!a.uv_layout) {
    isochart::RenderOptions o;
    o.views = a.views;
    o.width = width;
    o.height = height;
    o.wireframe = a.wireframe;
    o.perspective = !a.ortho;
    o.transparent = a.transparent;
    o.supersample = a.supersample;
    o.up = up_axis(a.up);
    isochart::Image texture;
    if (a.texture.empty() && !a.charts && !a.shaded && mesh.has_uvs()) {
      // What synth and atlas outputs carry (an OBJ's MTL map_Kd, a glb's base colour) was
      // drawn untextured unless named again with --texture.
      const isochart::MeshTexture t = isochart::find_mesh_texture(a.input);
      if (!t.problem.empty() && !t.several_materials) ctx.warn(a.input, t.problem + "; drawn shaded");
      try {
        if (t.several_materials && !mesh.face_materials.empty()) {
          // Each face in its own material's image, or its colour where the material has none.
          materials = read_material_images(a.input, mesh, a.output, true);
          for (const std::string& why : materials.skipped)
            ctx.warn(a.input, why + "; its faces are drawn in the material's colour");
          if (materials.untextured_faces == mesh.num_faces()) {
            materials = {};
          } else {
            own = materials.files.empty() ? "embedded" : materials.files.front();
            mesh = std::move(materials.source);
            for (const isochart::TextureSource& m : materials.sources)
              o.materials.push_back({m.image.empty() ? nullptr : &m.image, m.wrap, m.colour});
            o.face_material = materials.face_source;
          }
        } else {
          texture = read_mesh_texture(t, a.output, a.input);
        }
        if (!texture.empty()) {
          own = t.file.empty() ? "embedded" : t.file;
          mesh = as_material_reads(t, mesh);
          check_material_coordinates(a.input, mesh);
          o.texture_wrap = t.wrap;
        }
      } catch (const isochart::InputError& e) {
        const std::string which = e.file().empty() || e.file() == a.input ? "" : " " + e.file();
        ctx.warn(a.input, "its texture" + which + " cannot be read (" + e.what() + "); drawn shaded");
        texture = isochart::Image{};
        materials = {};
        o.materials.clear();
        o.face_material.clear();
        own.clear();
      }
    }
    if (!a.texture.empty() || !own.empty()) {
      if (!mesh.has_uvs())
        throw isochart::InputError(a.input, "mesh has no texture coordinates; --texture needs them");
      if (own.empty()) texture = isochart::read_image(a.texture);
      o.texture = &texture;
      o.color = isochart::ColorMode::Textured;
      mode = "textured";
    } else if (a.charts) {
      o.color = isochart::ColorMode::Charts;
      mode = "charts";
    } else {
      mode = "shaded";
    }
    image = for_input([&] { return isochart::render_mesh(mesh, o); });
  }
  isochart::write_image(a.output, image);

  nlohmann::json j;
  j["file"] = a.input;
  j["output"] = a.output;
  j["mode"] = mode;
  if (mode == "textured") j["texture"] = own.empty() ? a.texture : own;
  if (mode == "textured" && !materials.sources.empty()) {
    nlohmann::json files = nlohmann::json::array();
    for (const std::string& f : materials.files) files.push_back(f);
    j["materials"] = materials.sources.size();
    j["texture_files"] = files;
  }
  j["views"] = a.uv_layout ? 0 : a.views;
  if (!a.uv_layout) j["up"] = a.up;
  j["width"] = image.width;
  j["height"] = image.height;
  j["faces"] = mesh.num_faces();
  j["seconds"] = seconds_since(t0);
  ctx.emit(j, a.output + "\n");
}

}  // namespace

void add_render(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub =
      app.add_subcommand("render", "Render views of a mesh (shaded, charts, textured) or its UV layout");
  sub->add_option("input", args->input, "Mesh file (OBJ/OFF/PLY/glTF) or builtin:NAME")->required();
  sub->add_option("-o,--output", args->output, "Output image (.png, .jpg, .exr, ...)")->required();
  sub->add_option("--texture", args->texture, "Texture image mapped through the mesh's UVs");
  sub->add_flag("--charts", args->charts, "Colour each chart (face groups, else UV charts)");
  sub->add_flag("--shaded", args->shaded,
                "Draw shaded without the mesh's own texture (by default an OBJ's MTL map_Kd or a glb's "
                "base-colour image is drawn)");
  sub->add_flag("--wireframe", args->wireframe, "Draw the triangle edges");
  sub->add_flag("--uv-layout", args->uv_layout, "Draw the atlas in texture space instead of 3D views");
  sub->add_option("--aspect", args->aspect,
                  "With --uv-layout: width / height of the texture the UVs address, so the layout is drawn "
                  "as the texture looks (default: read from the UVs)")
      ->check(number_in(1.0 / 16384, 16384.0));
  sub->add_option("--views", args->views,
                  "Number of views side by side: front, right, back, left, top, bottom, "
                  "front-right, back-left")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  sub->add_option("--width", args->width,
                  "Image width in pixels (default 400 per view; 1024 for --uv-layout)")
      ->check(CLI::Range(1, 16384));
  sub->add_option("--height", args->height, "Image height in pixels (default 400; 1024 for --uv-layout)")
      ->check(CLI::Range(1, 16384));
  sub->add_option("--up", args->up,
                  "The model's up axis, x, y, z, -x, -y or -z (default y; e.g. z for horse.ply)");
  sub->add_flag("--ortho", args->ortho, "Orthographic instead of perspective projection");
  sub->add_flag("--transparent", args->transparent, "Transparent background (RGBA) instead of white");
  sub->add_option("--supersample", args->supersample, "Samples per pixel along each axis (anti-aliasing)")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  sub->footer(
      "Examples:\n"
      "  isocharts render builtin:creature -o creature.png --views 4 --width 1600 --height 400\n"
      "  isocharts render atlas.obj --charts --wireframe -o charts.png\n"
      "  isocharts render atlas.obj --uv-layout -o layout.png");
  sub->callback([&ctx, args, sub, &action] {
    args->views_or_up_given = sub->count("--views") > 0 || sub->count("--up") > 0;
    args->supersample_given = sub->count("--supersample") > 0;
    action = [&ctx, args] { run_render(ctx, *args); };
  });
}

}  // namespace cli
