// `isocharts psnr A B`: geometric PSNR and surface distances between two meshes (A is the
// reference whose bounding-box diagonal is the peak).

#include <cmath>
#include <sstream>

#include "cli.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "mcgim/psnr.h"

namespace cli {

namespace {

struct PsnrArgs {
  std::string a, b;
  long long samples = 1'000'000;
};

// JSON has no infinity: identical surfaces report a null PSNR.
nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

isochart::Mesh load_any(const Context& ctx, const std::string& path) {
  const std::string prefix = "builtin:";
  if (path.rfind(prefix, 0) == 0) return isochart::make_builtin(path.substr(prefix.size()));
  return ctx.load(path).mesh;
}

void run_psnr(const Context& ctx, const PsnrArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  ctx.check_paths({a.a, a.b}, {});
  const isochart::Mesh ma = load_any(ctx, a.a), mb = load_any(ctx, a.b);
  mcgim::DistanceOptions o;
  o.samples = a.samples;
  o.seed = ctx.opts.seed;
  mcgim::DistanceResult r;
  try {
    r = mcgim::measure_distance(ma, mb, o, ctx.progress());
  } catch (const isochart::InputError& e) {
    // The library names the mesh "A" or "B"; the user knows them by file name.
    if (!e.file().empty()) throw;
    const std::string what = e.what();
    throw isochart::InputError(what.find("mesh B") != std::string::npos ? a.b : a.a, what);
  }

  nlohmann::json j;
  j["a"] = a.a;
  j["b"] = a.b;
  j["psnr"] = finite_or_null(r.psnr);
  j["psnr_mean"] = finite_or_null(r.psnr_mean);
  j["rms_ab"] = r.rms_ab;
  j["rms_ba"] = r.rms_ba;
  j["max_ab"] = r.max_ab;
  j["max_ba"] = r.max_ba;
  j["hausdorff"] = r.hausdorff;
  j["diagonal"] = r.diagonal;
  j["samples_a"] = r.samples_a;
  j["samples_b"] = r.samples_b;
  j["seed"] = o.seed;
  j["seconds"] = seconds_since(t0);

  std::ostringstream t;
  t.precision(6);
  t << a.a << " vs " << a.b << "\n"
    << "  PSNR (max RMS)      " << r.psnr << " dB\n"
    << "  PSNR (mean RMS)     " << r.psnr_mean << " dB\n"
    << "  RMS A->B            " << r.rms_ab << "\n"
    << "  RMS B->A            " << r.rms_ba << "\n"
    << "  Hausdorff           " << r.hausdorff << "\n"
    << "  bbox diagonal of A  " << r.diagonal << "\n"
    << "  samples per mesh    " << a.samples << "\n";
  ctx.emit(j, t.str());
}

}  // namespace

void add_psnr(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<PsnrArgs>();
  CLI::App* sub = app.add_subcommand(
      "psnr", "Geometric PSNR, RMS and Hausdorff distances between two meshes (A is the reference)");
  sub->add_option("a", args->a, "Reference mesh (its bounding-box diagonal is the PSNR peak)")->required();
  sub->add_option("b", args->b, "Compared mesh, e.g. a remesh")->required();
  // About 63 bytes per sample: 20 M is 1.3 GB.
  sub->add_option("--samples", args->samples,
                  "Points sampled on each surface, by area (default 1000000, at most 20000000)")
      ->check(CLI::Range(1LL, 20'000'000LL));
  sub->footer(
      "PSNR = 20 log10(diagonal / d), d the larger of the two one-sided RMS distances (the mean "
      "of the two gives the second figure); distances are exact point-to-triangle. Identical surfaces "
      "(d below 1e-14 of the diagonal, which is rounding) give inf, null in JSON.\n"
      "Example: isocharts psnr ../shared/data/meshes/horse.ply horse_remesh.ply --json");
  sub->callback([&ctx, args, &action] { action = [&ctx, args] { run_psnr(ctx, *args); }; });
}

}  // namespace cli
