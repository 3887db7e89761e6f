// `isocharts stats FILE`: quality figures of an existing atlas (a mesh with UVs).

#include <cmath>
#include <sstream>

#include "cli.h"
#include "isochart/error.h"
#include "isochart/stretch.h"

namespace cli {

namespace {

struct StatsArgs {
  std::string input;
  double aspect = 1;
};

// JSON has no infinity: a flipped atlas reports null stretch.
nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

void run_stats(const Context& ctx, const StatsArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  ctx.check_paths({a.input}, {});
  isochart::LoadResult r = ctx.load(a.input, true);
  if (!r.mesh.has_uvs())
    throw isochart::InputError(a.input, "mesh has no texture coordinates; nothing to measure");
  const isochart::AtlasQuality q = isochart::measure_atlas(r.mesh, a.aspect);
  const int turned = q.stretch.flipped - q.stretch.degenerate;
  // The packing ratio is measured against the UVs' own bounding box: it says nothing of a
  // texture the UVs leave (an atlas at u in [5, 6] read 1), and overlaps count twice (2).
  warn_uvs_outside(ctx, a.input, q, "the packing ratio is of their own bounding box, not of the texture");
  // Stretch in [0,1]² of a 4:1 texture's atlas reads as charts flattened fourfold.
  std::ostringstream measured;
  measured << "stretch is measured for --aspect " << a.aspect;
  const double detected = read_texture_aspect(ctx, a.input, r.mesh, a.aspect, measured.str());
  if (q.overlapping_pairs > 0)
    ctx.warn(a.input, std::to_string(q.overlapping_pairs) +
                          " overlapping triangle pairs: the packing ratio counts their UV area twice");
  warn_sparse_chart(ctx, a.input, q.sparsest, "its surface gets almost no texels");
  // "L2 stretch inf" alone left the reader to find the one flipped triangle among thousands.
  if (q.stretch.flipped > 0) {
    const int zero = q.stretch.degenerate;
    std::ostringstream w;
    w << "the stretch is infinite: ";
    if (turned > 0)
      w << turned
        << (turned == 1 ? " UV triangle is flipped against its chart"
                        : " UV triangles are flipped against their charts");
    if (turned > 0 && zero > 0) w << " and ";
    if (zero > 0) w << zero << (zero == 1 ? " UV triangle has" : " UV triangles have") << " zero area";
    ctx.warn(a.input, w.str());
  }

  nlohmann::json j;
  j["file"] = a.input;
  j["faces"] = r.mesh.num_faces();
  j["charts"] = q.charts;
  j["aspect"] = a.aspect;
  j["aspect_detected"] = detected;
  j["l2_stretch"] = finite_or_null(q.stretch.l2);
  j["linf_stretch"] = finite_or_null(q.stretch.linf);
  j["flipped"] = turned;
  j["zero_area_uv"] = q.stretch.degenerate;
  j["mirrored_charts"] = q.mirrored_charts;
  j["overlapping_pairs"] = q.overlapping_pairs;
  j["packing_ratio"] = q.packing_ratio;
  j["seam_length"] = q.seam_length;
  j["seam_length_relative"] = q.seam_length_relative;
  j["surface_area"] = q.stretch.area_3d;
  j["uv_area"] = q.uv_area;
  j["uv_bbox"] = {q.uv_min.x, q.uv_min.y, q.uv_max.x, q.uv_max.y};
  j["min_chart_density"] = q.sparsest.density;
  j["seconds"] = seconds_since(t0);

  std::ostringstream t;
  t << a.input << "\n"
    << "  charts              " << q.charts << "\n"
    << "  L2 stretch          " << q.stretch.l2 << "\n"
    << "  Linf stretch        " << q.stretch.linf << "\n"
    << "  flipped triangles   " << turned << " (against their chart)\n"
    << "  zero-area in UV     " << q.stretch.degenerate << "\n"
    << "  mirrored charts     " << q.mirrored_charts << "\n"
    << "  overlapping pairs   " << q.overlapping_pairs << "\n"
    << "  packing ratio       " << q.packing_ratio
    << (q.uv_area < 0.9 * q.packing_ratio
            ? "  (of the charts' bounding box; texture covered " + std::to_string(q.uv_area) + ")"
            : std::string())
    << "\n"
    << "  seam length         " << q.seam_length << " (" << q.seam_length_relative << " x sqrt(area))\n";
  ctx.emit(j, t.str());
}

}  // namespace

void add_stats(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<StatsArgs>();
  CLI::App* sub = app.add_subcommand("stats", "Stretch, flips, overlaps, packing and seams of an atlas");
  sub->add_option("input", args->input, "Mesh with texture coordinates (OBJ vt, PLY/glTF UVs)")->required();
  sub->add_option("--aspect", args->aspect,
                  "Width / height of the texture the UVs address (stretch is measured in texels; "
                  "default 1, a square texture)")
      ->check(number_in(1.0 / 16384, 16384.0));
  sub->footer("Example: isocharts stats ../shared/data/baseline_atlases/bunny_uvatlas.obj");
  sub->callback([&ctx, args, &action] { action = [&ctx, args] { run_stats(ctx, *args); }; });
}

}  // namespace cli
