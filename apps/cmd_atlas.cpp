// `isocharts atlas IN -o OUT.obj`: the iso-chart texture atlas of a mesh.

#include <cmath>
#include <sstream>

#include "cli.h"
#include "isochart/atlas.h"
#include "isochart/error.h"
#include "isochart/image.h"
#include "isochart/render.h"

namespace cli {

namespace {

struct AtlasArgs {
  std::string input;
  std::vector<std::string> outputs;
  std::string png;
  int png_size = 1024;
  bool no_graph_cut = false;
  bool no_merge = false;
  isochart::AtlasOptions options;
};

nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

void run_atlas(const Context& ctx, AtlasArgs a) {
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& out : a.outputs) {
    const auto fmt = isochart::format_from_path(out);
    if (fmt != isochart::MeshFormat::Obj && fmt != isochart::MeshFormat::Glb && fmt != isochart::MeshFormat::Ply)
      throw isochart::InputError(out, "output must be .obj, .glb or .ply");
  }
  a.options.seed = ctx.opts.seed;
  a.options.graph_cut = !a.no_graph_cut;
  a.options.merge = !a.no_merge;
  isochart::validate_options(a.options);

  isochart::LoadResult in = ctx.load(a.input);
  const double load_seconds = seconds_since(t0);
  isochart::Atlas atlas = isochart::build_atlas(in.mesh, a.options, ctx.progress());
  const isochart::Mesh out_mesh = atlas.apply_to(in.mesh);
  const auto t_out = std::chrono::steady_clock::now();
  for (const auto& out : a.outputs) isochart::save_mesh(out_mesh, out);
  if (!a.png.empty())
    isochart::write_image(a.png, isochart::render_uv_layout(out_mesh, a.png_size, a.png_size));
  const auto& s = atlas.stats;

  nlohmann::json j;
  j["file"] = a.input;
  j["outputs"] = a.outputs;
  if (!a.png.empty()) j["png"] = a.png;
  j["faces"] = in.mesh.num_faces();
  j["charts"] = s.charts;
  j["charts_before_merge"] = s.charts_before_merge;
  j["l2_stretch"] = finite_or_null(s.l2);
  j["linf_stretch"] = finite_or_null(s.linf);
  j["packing_ratio"] = s.packing_ratio;
  j["flipped"] = s.flipped;
  j["overlapping_pairs"] = s.overlapping_pairs;
  j["splits"] = s.splits;
  j["seed"] = s.seed;
  j["options"] = {{"max_l2", a.options.max_l2},     {"max_linf", a.options.max_linf},
                  {"max_charts", a.options.max_charts}, {"landmarks", a.options.landmarks},
                  {"alpha", a.options.alpha},       {"graph_cut", a.options.graph_cut},
                  {"merge", a.options.merge},       {"width", a.options.pack.width},
                  {"height", a.options.pack.height}, {"gutter", a.options.pack.gutter}};
  nlohmann::json secs = s.seconds;
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
    << "  L2 stretch        " << s.l2 << "  (bound " << a.options.max_l2 << ")\n"
    << "  Linf stretch      " << s.linf << "  (bound " << a.options.max_linf << ")\n"
    << "  packing ratio     " << s.packing_ratio << "\n"
    << "  flipped / overlapping pairs  " << s.flipped << " / " << s.overlapping_pairs << "\n"
    << "  seconds           " << secs["total"].get<double>() << "\n";
  for (const auto& out : a.outputs) t << "  wrote " << out << "\n";
  if (!a.png.empty()) t << "  wrote " << a.png << "\n";
  ctx.emit(j, t.str());
}

}  // namespace

void add_atlas(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<AtlasArgs>();
  auto& o = args->options;
  CLI::App* sub = app.add_subcommand("atlas", "Build a stretch-bounded iso-chart texture atlas");
  sub->add_option("input", args->input, "Mesh file (OBJ/OFF/PLY/glTF) or builtin:NAME")->required();
  sub->add_option("-o,--output", args->outputs, "Output mesh with UVs (.obj, .glb, .ply); repeat for several");
  sub->add_option("--png", args->png, "Also draw the chart layout into this PNG");
  sub->add_option("--png-size", args->png_size, "Size of the layout PNG in pixels")->check(CLI::Range(16, 16384));
  sub->add_option("--max-l2", o.max_l2, "Bound on every chart's L2 stretch (1 = isometric)")->capture_default_str();
  sub->add_option("--max-linf", o.max_linf, "Bound on every chart's Linf stretch, shrink included")->capture_default_str();
  sub->add_option("--max-charts", o.max_charts, "0: as few charts as the bounds allow; N: split until N charts")
      ->capture_default_str();
  sub->add_option("--width", o.pack.width, "Texture width in texels (packing)")->capture_default_str();
  sub->add_option("--height", o.pack.height, "Texture height in texels (packing)")->capture_default_str();
  sub->add_option("--gutter", o.pack.gutter, "Empty texels between charts")->capture_default_str();
  sub->add_option("--landmarks", o.landmarks, "Landmarks per chart for the IsoMap embedding")->capture_default_str();
  sub->add_option("--alpha", o.alpha, "Graph-cut weight of dihedral angle vs. embedding distortion")->capture_default_str();
  sub->add_flag("--no-graph-cut", args->no_graph_cut, "Skip graph-cut boundary optimization (ablation)");
  sub->add_flag("--no-merge", args->no_merge, "Skip merging small charts");
  sub->footer("Example: isocharts atlas builtin:creature -o creature_atlas.obj --png creature_atlas.png");
  sub->callback([&ctx, args, &action] { action = [&ctx, args] { run_atlas(ctx, *args); }; });
}

}  // namespace cli
