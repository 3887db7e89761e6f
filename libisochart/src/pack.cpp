// Chart packing (Iso-charts §6). The driver: validate and normalize the charts, then search
// the texel scale; at each scale every chart is rasterized in every rotation and the charts
// are packed greedily, one order per task (pack_once). The canvas (pack_canvas.h) holds the
// packing, its four horizons and the searches; the rasters come from pack_raster.h.
//
// Determinism: each packing is sequential over charts; the parallel parts (rasterizing,
// evaluating rotations and blocks of positions, the orders) write to their own slots or
// reduce with a total order, so the result is the same for any number of threads.

#include "isochart/pack.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>

#include "isochart/error.h"
#include "pack_canvas.h"

namespace isochart {

using pack_detail::Candidate;
using pack_detail::Canvas;
using pack_detail::ChartRaster;
using pack_detail::Rect;
using pack_detail::Side;

namespace {

constexpr double kPi = 3.14159265358979323846;
// The scale search gives up (the charts cannot fit at any scale) after this many attempts.
constexpr int kMaxAttempts = 60;
// The ladder of scales tried above the base search's result with all variants: rungs of 1%.
constexpr int kLadderRungs = 5;
constexpr double kLadderStep = 0.01;
// Greedy variants at most (PackOptions::variants).
constexpr int kMaxVariants = 32;
// Above this many charts, this many rotations per chart (16 below; PackOptions::rotations = 0).
constexpr int kManyCharts = 256;
constexpr int kManyChartsRotations = 4;

// A chart in the packer's own frame: centred, scaled so its UV area equals its 3-D area.
struct Prepared {
  std::vector<Vec2d> points;
  const std::vector<Face>* faces = nullptr;
  double area = 0;        // UV area after normalization
  double base_angle = 0;  // turns the minimal-area rectangle axis-aligned
  double length = 0;      // longer side of that rectangle
  Vec2d centre;           // input UV centre
  double scale_in = 1;    // normalized = (uv − centre) · scale_in
  pack_detail::ChartOutline outline;
};

struct Placed {
  int rotation = -1;
  int x = 0, y = 0;
  Vec2d origin;  // the raster origin of the chosen rotation
};

struct Attempt {
  bool ok = false;
  std::vector<Placed> placed;  // per chart
  Rect box;
  double ratio = 0;            // chart area / raster bounding box, to compare orders
  double placed_fraction = 0;  // of the charts' texels, when the packing failed
};

std::string chart_name(std::size_t i) {
  return "chart " + std::to_string(i);
}

Prepared prepare(const PackChart& c, std::size_t index) {
  if (c.faces.empty()) throw InputError("", chart_name(index) + " has no faces");
  const int nv = static_cast<int>(c.uv.size());
  for (std::size_t v = 0; v < c.uv.size(); ++v)
    if (!is_finite(c.uv[v]))
      throw InputError("", chart_name(index) + ": vertex " + std::to_string(v) + " has a non-finite UV");
  double area = 0;
  for (std::size_t f = 0; f < c.faces.size(); ++f) {
    const Face& t = c.faces[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv)
        throw InputError("", chart_name(index) + ": face " + std::to_string(f) + " references vertex " +
                                 std::to_string(t[k]) + " but the chart has " + std::to_string(nv));
    area += std::abs(signed_area(c.uv[t[0]], c.uv[t[1]], c.uv[t[2]]));
  }
  if (!(area > 0) || !std::isfinite(area)) throw InputError("", chart_name(index) + " has zero UV area");
  if (!std::isfinite(c.area_3d) || c.area_3d < 0)
    throw InputError("", chart_name(index) + ": area_3d is " + std::to_string(c.area_3d) +
                             " (must be a finite value >= 0)");
  Prepared p;
  p.faces = &c.faces;
  p.area = c.area_3d > 0 ? c.area_3d : area;
  p.scale_in = std::sqrt(p.area / area);
  Vec2d lo = c.uv[0], hi = c.uv[0];
  for (const Vec2d& q : c.uv) {
    lo = {std::min(lo.x, q.x), std::min(lo.y, q.y)};
    hi = {std::max(hi.x, q.x), std::max(hi.y, q.y)};
  }
  p.centre = (lo + hi) * 0.5;
  p.points.reserve(c.uv.size());
  for (const Vec2d& q : c.uv) p.points.push_back((q - p.centre) * p.scale_in);
  p.base_angle = pack_detail::min_area_rect_angle(p.points);
  p.outline = pack_detail::chart_outline(p.points, c.faces);
  const double cs = std::cos(p.base_angle), sn = std::sin(p.base_angle);
  Vec2d rlo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2d rhi = -rlo;
  for (const Vec2d& q : p.points) {
    const Vec2d r{cs * q.x - sn * q.y, sn * q.x + cs * q.y};
    rlo = {std::min(rlo.x, r.x), std::min(rlo.y, r.y)};
    rhi = {std::max(rhi.x, r.x), std::max(rhi.y, r.y)};
  }
  p.length = std::max(rhi.x - rlo.x, rhi.y - rlo.y);
  return p;
}

double rotation_angle(const Prepared& c, int k, int rotations) {
  return c.base_angle + 2 * kPi * k / rotations;
}

// The chart's points rotated by rotation k and scaled to texels. Rasterization and the final
// UVs both come from this one function, so they agree to the last bit.
std::vector<Vec2d> texel_points(const Prepared& c, int k, int rotations, double scale) {
  const double a = rotation_angle(c, k, rotations);
  const double cs = std::cos(a) * scale, sn = std::sin(a) * scale;
  std::vector<Vec2d> out(c.points.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = {cs * c.points[i].x - sn * c.points[i].y, sn * c.points[i].x + cs * c.points[i].y};
  return out;
}

std::vector<ChartRaster> rasterize_all(const std::vector<Prepared>& charts, int rotations, double scale,
                                       int limit_w, int limit_h) {
  std::vector<ChartRaster> out(charts.size() * rotations);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size()),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t j = range.begin(); j != range.end(); ++j) {
                        const Prepared& c = charts[j / rotations];
                        const int k = static_cast<int>(j % rotations);
                        out[j] = pack_detail::rasterize_chart(texel_points(c, k, rotations, scale), *c.faces,
                                                              c.outline, limit_w, limit_h);
                      }
                    });
  return out;
}

// One packing of all charts at the rasters' scale, in the given order (§6 step 3).
// `tick(k)` is called every few charts with the number placed so far.
template <class Tick>
Attempt pack_once(const std::vector<ChartRaster>& rasters, int rotations, const std::vector<int>& order,
                  int limit_w, int limit_h, int gutter, double growth_weight, bool fill_holes,
                  double area_texels, const Tick& tick) {
  Canvas canvas(limit_w, limit_h, gutter, growth_weight);
  Attempt attempt;
  attempt.placed.resize(rasters.size() / rotations);
  const double aspect = static_cast<double>(limit_w) / limit_h;
  std::vector<Candidate> candidates(2 * rotations);
  for (std::size_t step = 0; step < order.size(); ++step) {
    if (step % 32 == 31) tick(step);
    const int chart = order[step];
    const ChartRaster* r = &rasters[static_cast<std::size_t>(chart) * rotations];
    Candidate chosen;
    if (canvas.empty()) {
      // The first chart: the rotation whose box is closest to the target's aspect.
      double best_area = std::numeric_limits<double>::infinity();
      for (int k = 0; k < rotations; ++k) {
        if (!canvas.fits_limits(r[k])) continue;
        const double width = std::max<double>(r[k].w, r[k].h * aspect);
        if (width * width < best_area) {
          best_area = width * width;
          chosen = canvas.centre(r[k]);
          chosen.rotation = k;
        }
      }
    } else {
      if (fill_holes) chosen = canvas.best_inside(r, rotations);
      if (!chosen.valid) {
        // §6: W_expect = H_curr·W/H; grow sideways when the packing is narrower than that.
        // Lowest cost wins; ties go to the lowest rotation, then the first side of the pair.
        const Rect& box = canvas.bounds();
        bool sideways = box.h * aspect > box.w;
        for (int pass = 0; pass < 2 && !chosen.valid; ++pass, sideways = !sideways) {
          const Side sides[2] = {sideways ? Side::Left : Side::Top, sideways ? Side::Right : Side::Bottom};
          tbb::parallel_for(0, 2 * rotations,
                            [&](int j) { candidates[j] = canvas.best_from_side(r[j / 2], sides[j % 2]); });
          for (int j = 0; j < 2 * rotations; ++j) {
            const Candidate& c = candidates[j];
            if (c.valid && (!chosen.valid || c.cost < chosen.cost)) {
              chosen = c;
              chosen.rotation = j / 2;
            }
          }
        }
      }
    }
    if (!chosen.valid) {  // does not fit at this scale
      long long done = 0, all = 0;
      for (const int c : order) {
        const long long t = rasters[static_cast<std::size_t>(c) * rotations].texels;
        all += t;
        if (attempt.placed[c].rotation >= 0) done += t;
      }
      attempt.placed = {};
      attempt.placed_fraction = static_cast<double>(done) / std::max<long long>(all, 1);
      return attempt;
    }
    canvas.place(r[chosen.rotation], chosen.x, chosen.y);
    attempt.placed[chart] = {chosen.rotation, chosen.x, chosen.y, r[chosen.rotation].origin};
  }
  attempt.ok = true;
  attempt.box = canvas.bounds();
  attempt.ratio = area_texels / static_cast<double>(attempt.box.area());
  return attempt;
}

// Extension beyond §6, after the greedy packing: a chart that alone holds a side of the
// bounding box moves into free room inside the box of the others when there is any (any
// rotation, most contact first), which shrinks the box; repeated while that helps. The
// greedy packing places large charts first and cannot move them when later ones leave room.
void compact(Attempt& a, const std::vector<ChartRaster>& rasters, int rotations, int limit_w, int limit_h,
             int gutter, double growth_weight, double area_texels) {
  const int n = static_cast<int>(a.placed.size());
  auto rect_of = [&](int i) {
    const Placed& p = a.placed[i];
    const ChartRaster& r = rasters[static_cast<std::size_t>(i) * rotations + p.rotation];
    return Rect{p.x, p.y, r.w, r.h};
  };
  auto unite = [](const Rect& a0, const Rect& b) {
    if (a0.w == 0) return b;
    const int x0 = std::min(a0.x, b.x), y0 = std::min(a0.y, b.y);
    const int x1 = std::max(a0.x + a0.w, b.x + b.w), y1 = std::max(a0.y + a0.h, b.y + b.h);
    return Rect{x0, y0, x1 - x0, y1 - y0};
  };
  for (int round = 0; round < 4 && n > 1; ++round) {
    bool moved = false;
    for (int i = 0; i < n; ++i) {
      Rect others;
      for (int j = 0; j < n; ++j)
        if (j != i) others = unite(others, rect_of(j));
      if (others.area() >= a.box.area()) continue;  // not alone on any side
      Canvas canvas(limit_w, limit_h, gutter, growth_weight);
      for (int j = 0; j < n; ++j)
        if (j != i) {
          const Placed& p = a.placed[j];
          canvas.place(rasters[static_cast<std::size_t>(j) * rotations + p.rotation], p.x, p.y);
        }
      const ChartRaster* r = &rasters[static_cast<std::size_t>(i) * rotations];
      const Candidate c = canvas.best_inside(r, rotations);
      if (!c.valid) continue;
      const Rect box = canvas.bounds();
      if (box.area() >= a.box.area()) continue;
      a.placed[i] = {c.rotation, c.x, c.y, r[c.rotation].origin};
      a.box = box;
      moved = true;
    }
    if (!moved) break;
  }
  a.ratio = area_texels / static_cast<double>(a.box.area());
}

// A way to run the greedy packing: the order of the charts and the weight of growth.
struct Variant {
  int order = 0;
  double growth = 0;
};

// The outcome of one scale search: the largest scale found to fit and its packing.
struct Search {
  double fits = 0;
  Attempt best;
  int variant = 0;  // index into the variants searched
  int attempts = 0;
  std::vector<ChartRaster> rasters;  // at `fits`
};

// Scale search (texels per surface unit): at each scale tried, every variant packs (in
// parallel) and the scale fits when one of them does. Grow while packings fit, then bisect
// between the largest scale that fits and the smallest that does not. `tick(f)` reports progress within an
// attempt; `attempts_done` counts attempts overall.
template <class Tick>
Search search_scale(const std::vector<Prepared>& prepared, int rotations,
                    const std::vector<std::vector<int>>& orders, const std::vector<Variant>& variants,
                    const PackOptions& options, double total_area, double start, const Tick& tick,
                    std::atomic<int>& attempts_done) {
  const int g = options.gutter;
  const int limit_w = options.width - 2 * g, limit_h = options.height - 2 * g;
  const double n = static_cast<double>(prepared.size());
  Search search;
  double scale = start, fails = std::numeric_limits<double>::infinity();
  while (search.attempts < kMaxAttempts) {
    tick(0);
    ++search.attempts;
    std::vector<ChartRaster> rasters = rasterize_all(prepared, rotations, scale, limit_w, limit_h);
    std::vector<Attempt> tries(variants.size());
    tbb::parallel_for(0, static_cast<int>(variants.size()), [&](int v) {
      tries[v] = pack_once(rasters, rotations, orders[variants[v].order], limit_w, limit_h, g,
                           variants[v].growth, options.fill_holes, total_area * scale * scale,
                           [&](std::size_t done) { tick(done / n); });
    });
    ++attempts_done;
    int ok = -1;
    double placed = 0;
    for (int v = 0; v < static_cast<int>(tries.size()); ++v) {
      if (tries[v].ok && (ok < 0 || tries[v].ratio > tries[ok].ratio)) ok = v;
      placed = std::max(placed, tries[v].placed_fraction);
    }
    if (ok >= 0) {
      search.fits = scale;
      search.best = std::move(tries[ok]);
      search.variant = ok;
      search.rasters = std::move(rasters);
    } else {
      fails = scale;
    }
    if (search.fits > 0 && fails < std::numeric_limits<double>::infinity()) {
      if (fails / search.fits <= 1 + options.scale_tolerance) break;
      scale = std::sqrt(search.fits * fails);
    } else if (search.fits > 0) {
      const double room = std::min(static_cast<double>(limit_w) / search.best.box.w,
                                   static_cast<double>(limit_h) / search.best.box.h);
      scale *= std::max(room, 1 + 4 * options.scale_tolerance);
    } else {
      // Nothing fitted yet: shrink by what did not fit (area goes with the square of scale).
      scale *= std::sqrt(std::clamp(placed, 0.5, 0.98));
    }
  }
  return search;
}

std::string texels(int n) {
  return std::to_string(n) + (n == 1 ? " texel" : " texels");
}

void validate(const PackOptions& o) {
  auto bad = [](const std::string& m) { throw InputError("", m); };
  constexpr int kMax = PackOptions::kMaxSize;
  if (o.width < 1 || o.width > kMax || o.height < 1 || o.height > kMax)
    bad("pack: texture size " + std::to_string(o.width) + "x" + std::to_string(o.height) + " is outside 1.." +
        std::to_string(kMax));
  if (o.gutter < 0) bad("pack: gutter " + std::to_string(o.gutter) + " is negative");
  if (o.width - 2 * o.gutter < 1 || o.height - 2 * o.gutter < 1)
    bad("pack: a gutter of " + texels(o.gutter) + " leaves no room in a " + std::to_string(o.width) + "x" +
        std::to_string(o.height) + " texture");
  if (o.rotations < 0 || o.rotations > 360)
    bad("pack: rotations " + std::to_string(o.rotations) + " is outside 0..360");
  if (!(o.growth_weight >= 0) || !std::isfinite(o.growth_weight))
    bad("pack: growth_weight " + std::to_string(o.growth_weight) + " must be finite and >= 0");
  if (o.variants < 0) bad("pack: variants " + std::to_string(o.variants) + " is negative");
  if (!(o.scale_tolerance > 0 && o.scale_tolerance < 1))
    bad("pack: scale_tolerance " + std::to_string(o.scale_tolerance) + " is outside (0, 1)");
  if (o.search_size != 0 && (o.search_size < 64 || o.search_size > kMax))
    bad("pack: search grid " + std::to_string(o.search_size) + " is outside 64.." + std::to_string(kMax) +
        " (0: the texture's own)");
}

// How many texels of the texture a texel of the search grid spans (see search_size): 1 when
// the texture is within it, or no grid between half the search size and the search size
// divides both sides (1025² would be packed on 205², far coarser than asked).
int coarse_factor(const PackOptions& o) {
  const int longest = std::max(o.width, o.height);
  if (o.search_size <= 0 || longest <= o.search_size) return 1;
  for (int k = (longest + o.search_size - 1) / o.search_size; 2 * (longest / k) >= o.search_size; ++k) {
    if (o.width % k != 0 || o.height % k != 0) continue;
    const int g = (o.gutter + k - 1) / k;
    return o.width / k > 2 * g && o.height / k > 2 * g ? k : 1;
  }
  return 1;
}

}  // namespace

PackResult pack_charts(std::vector<PackChart>& charts, const PackOptions& options, const Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  validate(options);
  // A large texture is packed on a coarser grid; the charts' UVs in [0,1]² then fit it as they
  // are, their gaps k times as many texels.
  if (const int k = coarse_factor(options); k > 1) {
    PackOptions coarse = options;
    coarse.width /= k;
    coarse.height /= k;
    coarse.gutter = (options.gutter + k - 1) / k;
    coarse.search_size = 0;
    PackResult r = pack_charts(charts, coarse, progress);
    for (ChartPlacement& p : r.placements) {
      p.scale *= k;
      p.offset = p.offset * static_cast<double>(k);
    }
    r.texel_size /= k;
    r.used_width *= k;
    r.used_height *= k;
    return r;
  }
  PackResult result;
  if (charts.empty()) return result;
  report(progress, Stage::Packing, 0);

  const int n = static_cast<int>(charts.size());
  // Every chart's hole search walks the whole packing, once per rotation: with many charts
  // (many components, or tight bounds) that is most of a run, and small charts lose little
  // with four orientations of their minimal rectangle.
  const int rotations = options.rotations > 0 ? options.rotations : n > kManyCharts ? kManyChartsRotations : 16;
  const int g = options.gutter;
  const int limit_w = options.width - 2 * g, limit_h = options.height - 2 * g;
  std::vector<Prepared> prepared(n);
  for (int i = 0; i < n; ++i) prepared[i] = prepare(charts[i], i);
  double total_area = 0;
  for (const Prepared& p : prepared) total_area += p.area;

  // §6 step 2: decreasing area; the second order sorts by the longer rectangle side.
  std::vector<std::vector<int>> orders(2, std::vector<int>(n));
  for (auto& o : orders) std::iota(o.begin(), o.end(), 0);
  std::stable_sort(orders[0].begin(), orders[0].end(),
                   [&](int a, int b) { return prepared[a].area > prepared[b].area; });
  std::stable_sort(orders[1].begin(), orders[1].end(),
                   [&](int a, int b) { return prepared[a].length > prepared[b].length; });
  // The base search packs both orders with the growth weight at every scale. The greedy
  // packing is chaotic: a small change of order, weight or scale moves whole charts, and
  // whether it fits is not monotone in the scale. So, on few charts, where it is cheap, a
  // ladder of scales above the base's best fit is tried with all variants (both orders with
  // growth weights `growth_weight`, 0 and 2), and the largest scale that fits is kept.
  const bool small = n <= 32 && static_cast<long long>(options.width) * options.height <= 4096LL * 4096;
  const int count = options.variants > 0 ? std::min(options.variants, kMaxVariants) : (small ? 6 : 2);
  // Variants beyond 6: the area order perturbed, each chart's key multiplied by a factor in
  // [1, 2) from a hash of (chart, variant), so every run draws the same orders.
  for (int extra = 0; extra + 6 < count; ++extra) {
    std::vector<double> key(n);
    for (int i = 0; i < n; ++i) {
      std::uint64_t h = (static_cast<std::uint64_t>(i) << 32) ^ static_cast<std::uint64_t>(extra + 1);
      h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ULL;
      h = (h ^ (h >> 27)) * 0x94D049BB133111EBULL;
      h ^= h >> 31;
      key[i] = prepared[i].area * (1 + static_cast<double>(h >> 11) / 9007199254740992.0);
    }
    std::vector<int> o(n);
    std::iota(o.begin(), o.end(), 0);
    std::stable_sort(o.begin(), o.end(), [&](int a, int b) { return key[a] > key[b]; });
    orders.push_back(std::move(o));
  }
  std::vector<Variant> variants{{0, options.growth_weight}};
  if (count >= 2) variants.push_back({1, options.growth_weight});
  const std::vector<Variant> base = variants;
  for (const double w : {0.0, 2.0})
    for (int o = 0; o < 2; ++o)
      if (w != options.growth_weight && static_cast<int>(variants.size()) < count) variants.push_back({o, w});
  for (int o = 2; o < static_cast<int>(orders.size()); ++o)
    variants.push_back({o, o % 2 ? 0.0 : options.growth_weight});
  const int rungs = variants.size() > base.size() ? kLadderRungs : 0;

  std::atomic<int> attempts_done{0};
  const double expected = 10.0 + rungs;  // attempts, roughly
  const auto tick = [&](double within) {
    report(progress, Stage::Packing, std::min(0.95, (attempts_done.load() + within) / expected));
  };
  Search best_search = search_scale(prepared, rotations, orders, base, options, total_area,
                                    std::sqrt(0.75 * limit_w * limit_h / total_area), tick, attempts_done);
  if (best_search.fits <= 0)
    throw InputError("", std::string("pack: ") +
                             (n == 1 ? "the chart does" : "the " + std::to_string(n) + " charts do") +
                             " not fit a " + std::to_string(options.width) + "x" +
                             std::to_string(options.height) + " texture with a gutter of " + texels(g));
  int attempts = best_search.attempts;
  const double base_fits = best_search.fits;
  // The largest rung where some variant fits wins (its densest packing there), so the rungs
  // are tried from the top and the search stops at the first that fits: the rungs below could
  // not change the result. Rung 0 is the base scale, where only the new variants can improve
  // (a tighter box). The rasters of the winning scale are kept for the compaction.
  std::vector<ChartRaster> best_rasters;
  for (int k = rungs; k >= 0 && rungs > 0; --k) {
    const double scale = base_fits * (1 + k * kLadderStep);
    const std::vector<Variant> tried(variants.begin() + (k == 0 ? base.size() : 0), variants.end());
    tick(0);
    ++attempts;
    std::vector<ChartRaster> rasters =
        k == 0 ? std::move(best_search.rasters) : rasterize_all(prepared, rotations, scale, limit_w, limit_h);
    std::vector<Attempt> tries(tried.size());
    tbb::parallel_for(0, static_cast<int>(tried.size()), [&](int v) {
      tries[v] = pack_once(rasters, rotations, orders[tried[v].order], limit_w, limit_h, g, tried[v].growth,
                           options.fill_holes, total_area * scale * scale, [](std::size_t) {});
    });
    ++attempts_done;
    bool found = false;
    for (int v = 0; v < static_cast<int>(tries.size()); ++v)
      if (tries[v].ok && (scale > best_search.fits || tries[v].ratio > best_search.best.ratio)) {
        best_search.fits = scale;
        best_search.best = std::move(tries[v]);
        best_search.variant = v + (k == 0 ? static_cast<int>(base.size()) : 0);
        found = true;
      }
    if (found || k == 0) best_rasters = std::move(rasters);
    if (best_search.fits > base_fits) break;
  }
  const int best_variant = best_search.variant;
  Attempt& best = best_search.best;
  const double fits = best_search.fits;
  if (options.compact) {
    if (best_rasters.empty()) best_rasters = std::move(best_search.rasters);
    if (best_rasters.empty()) best_rasters = rasterize_all(prepared, rotations, fits, limit_w, limit_h);
    compact(best, best_rasters, rotations, limit_w, limit_h, g, options.growth_weight, total_area * fits * fits);
  }

  // Centre the packing in the texture; the gutter to the border is then at least g.
  const Rect& box = best.box;
  const int shift_x = g + (limit_w - box.w) / 2 - box.x, shift_y = g + (limit_h - box.h) / 2 - box.y;
  result.placements.resize(n);
  double uv_area = 0;
  Vec2d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2d hi = -lo;
  for (int i = 0; i < n; ++i) {
    const Placed& pl = best.placed[i];
    const Prepared& p = prepared[i];
    const std::vector<Vec2d> pts = texel_points(p, pl.rotation, rotations, fits);
    const Vec2d shift{static_cast<double>(pl.x + shift_x), static_cast<double>(pl.y + shift_y)};
    PackChart& c = charts[i];
    for (std::size_t v = 0; v < pts.size(); ++v) {
      const Vec2d t = (pts[v] - pl.origin) + shift;
      c.uv[v] = {t.x / options.width, t.y / options.height};
      lo = {std::min(lo.x, c.uv[v].x), std::min(lo.y, c.uv[v].y)};
      hi = {std::max(hi.x, c.uv[v].x), std::max(hi.y, c.uv[v].y)};
    }
    for (const Face& f : c.faces) uv_area += std::abs(signed_area(c.uv[f[0]], c.uv[f[1]], c.uv[f[2]]));
    ChartPlacement& out = result.placements[i];
    out.angle = rotation_angle(p, pl.rotation, rotations);
    out.scale = fits * p.scale_in;
    const Vec2d rc{std::cos(out.angle) * p.centre.x - std::sin(out.angle) * p.centre.y,
                   std::sin(out.angle) * p.centre.x + std::cos(out.angle) * p.centre.y};
    out.offset = shift - pl.origin - rc * out.scale;
  }
  const double box_area = (hi.x - lo.x) * (hi.y - lo.y);
  result.packing_ratio = box_area > 0 ? uv_area / box_area : 0;
  result.utilization = uv_area;
  result.texel_size = 1 / fits;
  result.used_width = box.w;
  result.used_height = box.h;
  result.attempts = attempts;
  result.variant = best_variant;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report(progress, Stage::Packing, 1);
  return result;
}

}  // namespace isochart
