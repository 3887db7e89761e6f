#include "mcgim/mcgim.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <string>

#include "charts.h"
#include "closest_point.h"
#include "isochart/error.h"
#include "optimize_samples.h"
#include "sampling.h"
#include "zipper.h"

namespace mcgim {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A face with two corners at one point: what reconstruct's join of coincident samples acts on.
bool has_collapsed_edge(const isochart::Mesh& m) {
  for (const isochart::Face& f : m.faces)
    for (int k = 0; k < 3; ++k) {
      const auto &p = m.positions[f[k]], &q = m.positions[f[(k + 1) % 3]];
      if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) return true;
    }
  return false;
}

void check_options(const LevelOptions& o) {
  auto bad = [](const std::string& msg) { throw isochart::InputError("", msg); };
  if (o.width < 2 || o.width > 16384 || o.height < 2 || o.height > 16384)
    bad("geometry image size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
        " is outside 2..16384");
  if (o.repack && (o.width > 8192 || o.height > 8192))
    bad("geometry image size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
        " is beyond 8192, the largest texture the packer handles");
  if (o.gutter < 1) bad("the gutter must be at least 1 texel");
  if (!(o.atlas_aspect >= 0) || !std::isfinite(o.atlas_aspect)) bad("the atlas aspect must be 0 or positive");
  if (o.optimize_iterations < 0) bad("optimize_iterations must be >= 0");
  if (o.geometric_iterations < 0) bad("geometric_iterations must be >= 0");
  if (!(o.optimize_regularization > 0)) bad("optimize_regularization must be > 0");
  if (!(o.fit_regularization > 0)) bad("fit_regularization must be > 0");
}

// Moves every chart by the same offset, within the image: where the sample grid falls on the
// charts changes, their gaps do not. Returns false when the layout leaves no room for it.
bool shift_layout(detail::Placement& pl, isochart::Vec2d shift) {
  double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
  for (const auto& chart : pl.texel)
    for (const auto& p : chart) {
      lo_x = std::min(lo_x, p.x);
      lo_y = std::min(lo_y, p.y);
      hi_x = std::max(hi_x, p.x);
      hi_y = std::max(hi_y, p.y);
    }
  // Each offset is taken forwards, or as the same phase backwards (one texel less).
  auto fit = [](double s, double lo, double hi, double size, double& out) {
    if (s == 0 || hi + s <= size) return out = s, true;
    if (lo + s - 1 >= 0) return out = s - 1, true;
    return false;
  };
  double sx = 0, sy = 0;
  if (!fit(shift.x, lo_x, hi_x, pl.width, sx) || !fit(shift.y, lo_y, hi_y, pl.height, sy)) return false;
  for (auto& chart : pl.texel)
    for (auto& p : chart) {
      p.x += sx;
      p.y += sy;
    }
  return true;
}

// Charts part of whose surface the remesh lost: a point of the chart (a face centroid; about
// 20,000 over the mesh, at least one per chart) more than this many texels from the remesh.
// Where the remesh keeps a chart, the farthest input point is within one or two texels
// (plane_holes at 64-69²: 1.2-1.6); a chart too thin or small for its samples is contracted by
// the zipper onto its neighbours' seams, and its surface is then 4-12 texels away (plane_holes
// at 67²: one chart emptied and three mostly, Hausdorff 2.7 against 0.3 at 66², 35.5 dB against
// 60.0, with the topology kept). Enlarging such charts in the retries below did not bring them
// back there (and at 60² kept a worse layout), so they are reported, not repaired.
constexpr double kLostTexels = 3.0;
constexpr long long kCoverageProbes = 20000;

// The number of charts whose surface the remesh no longer reaches.
int count_lost_charts(const detail::AtlasCharts& a, const isochart::Mesh& remesh, double texel) {
  const int nc = static_cast<int>(a.charts.size());
  if (remesh.num_faces() == 0 || !(texel > 0)) return 0;
  const detail::ClosestPoints near(remesh);
  if (near.empty()) return 0;
  const long long total = a.mesh->num_faces();
  const long long stride = std::max<long long>(1, total / kCoverageProbes);
  const double limit2 = (kLostTexels * texel) * (kLostTexels * texel);
  int count = 0;
  for (int c = 0; c < nc; ++c) {
    const std::vector<int>& faces = a.charts[c].faces;
    for (std::size_t i = 0; i < faces.size(); i += static_cast<std::size_t>(stride)) {
      const isochart::Face& f = a.mesh->faces[faces[i]];
      const isochart::Vec3d p =
          (a.mesh->positions[f[0]] + a.mesh->positions[f[1]] + a.mesh->positions[f[2]]) / 3.0;
      if (isochart::squared_norm(near.closest(p).point - p) > limit2) {
        ++count;
        break;
      }
    }
  }
  return count;
}

Level build_once(const detail::AtlasCharts& a, const LevelOptions& o, const std::vector<double>& area_scale,
                 std::vector<char>& strained, const isochart::Progress& progress,
                 isochart::Vec2d shift = {0, 0}, bool* shifted = nullptr) {
  Level lv;
  LevelStats& st = lv.stats;
  st.width = o.width;
  st.height = o.height;
  st.charts = static_cast<int>(a.charts.size());
  st.cut_nodes = a.num_nodes;
  st.input_euler_characteristic = a.input_euler;
  st.input_boundary_loops = a.input_boundary_loops;

  detail::Placement pl = detail::place_charts(a, o, area_scale, progress);
  st.seconds_packing = pl.seconds;
  if (shifted) {
    *shifted = shift_layout(pl, shift);
    if (!*shifted) return lv;
  }

  auto t0 = Clock::now();
  detail::Sampling sm = detail::sample_charts(a, pl, !o.repack, progress);
  st.seconds_sampling = since(t0);

  t0 = Clock::now();
  const detail::ZipperStats zs = detail::zipper(a, pl, sm, progress);
  st.seconds_zippering = since(t0);
  st.cut_paths = zs.cut_paths;
  st.empty_charts = zs.empty_charts;
  strained = zs.strained;
  st.removed_samples = sm.removed;
  st.forced_samples = sm.forced;

  lv.image = std::move(sm.image);
  t0 = Clock::now();
  const bool optimize = o.optimize && o.optimize_iterations + o.geometric_iterations > 0;
  lv.remesh = reconstruct(lv.image, !optimize);
  st.seconds_reconstruction = since(t0);

  if (optimize) {
    t0 = Clock::now();
    detail::optimize_samples(a, pl, sm.param, o, lv.image, lv.remesh, progress);
    // Samples the fit left on one point are joined now (none, mostly: the fit moves them
    // apart, which joining them first would have prevented). Only an edge between two
    // such samples calls for a join; without one the rebuild would give the same remesh.
    if (has_collapsed_edge(lv.remesh.mesh)) lv.remesh = reconstruct(lv.image);
    st.seconds_optimization = since(t0);
  }
  st.defined_samples = lv.image.defined_samples();
  st.unique_vertices = lv.remesh.mesh.num_vertices();
  st.triangles = lv.remesh.mesh.num_faces();
  st.degenerate_triangles = lv.remesh.degenerate_faces;
  st.collapsed_triangles = lv.remesh.collapsed_faces;
  st.topology = check_topology(lv.remesh.mesh);
  st.texel_size = st.defined_samples > 0 ? std::sqrt(a.surface_area / st.defined_samples) : 0.0;
  return lv;
}

// How far a remesh is from the input's topology; 0 when it is kept.
int topology_error(const LevelStats& st) {
  return topology_distance(st.topology, st.input_euler_characteristic, st.input_boundary_loops);
}

// At coarse resolutions a chart of a few texels may cover no triangle of samples and is
// contracted, which can pinch the remesh. Charts with fewer samples than a small disk needs, or
// on a cut path that collapsed, are then packed larger (their density no longer matches the
// others, which matters less than a remesh with the wrong topology) until the topology is kept
// or the attempts run out. Two ladders: a gentle one (×1.5 per attempt) first, then a steep one
// (×4) for starts the gentle one cannot rescue. Whether a level keeps its topology depends on
// where the sample grid falls on each chart, so more, smaller steps find more of the layouts
// that work, and they distort the sampling density less: with ×4 alone plane_holes' 64² level
// kept the wrong topology with charts enlarged up to 64× (37.4 dB), the gentle ladder finds the
// right one (51.6 dB), and feline's 64² level went from 38.2 to 51.1 dB. Among attempts with the
// same topology error the least enlarged is kept.
Level build_prepared(const detail::AtlasCharts& a, const LevelOptions& o, const isochart::Progress& progress) {
  constexpr int kMinSamples = 12;
  struct Ladder {
    double factor;
    int attempts;
  };
  constexpr Ladder kLadders[] = {{1.5, 13}, {4.0, 5}};
  const int nc = static_cast<int>(a.charts.size());
  auto work_seconds = [](const LevelStats& st) {
    return st.seconds_packing + st.seconds_sampling + st.seconds_zippering + st.seconds_reconstruction +
           st.seconds_optimization;
  };
  auto count_samples = [nc](const Level& lv) {
    std::vector<long long> count(nc, 0);
    for (int c : lv.image.chart)
      if (c >= 0) ++count[c];
    return count;
  };
  std::vector<char> first_strained;
  Level best = build_once(a, o, {}, first_strained, progress);
  int best_error = topology_error(best.stats);
  double best_enlargement = 1;
  std::vector<double> best_scale;
  std::vector<char> best_strained = first_strained;
  double spent = work_seconds(best.stats);
  const std::vector<long long> first_count = count_samples(best);
  for (const Ladder& ladder : kLadders) {
    if (!o.repack || best_error == 0) break;
    std::vector<double> scale(nc, 1.0);
    std::vector<char> strained = first_strained;
    std::vector<long long> count = first_count;
    for (int attempt = 0; attempt < ladder.attempts && best_error > 0; ++attempt) {
      int enlarged = 0;
      for (int c = 0; c < nc; ++c)
        if (count[c] < kMinSamples || strained[c]) {
          scale[c] *= ladder.factor;
          ++enlarged;
        }
      if (enlarged == 0) break;
      Level retry = build_once(a, o, scale, strained, progress);
      spent += work_seconds(retry.stats);
      retry.stats.enlarged_charts =
          static_cast<int>(std::count_if(scale.begin(), scale.end(), [](double x) { return x > 1.0; }));
      count = count_samples(retry);
      const int error = topology_error(retry.stats);
      // The packer normalizes the total area, so the spread of the scales is what distorts.
      const double enlargement = *std::max_element(scale.begin(), scale.end()) /
                                 *std::min_element(scale.begin(), scale.end());
      if (retry.remesh.mesh.num_faces() > 0 &&
          (error < best_error || (error == best_error && enlargement < best_enlargement))) {
        best_error = error;
        best_enlargement = enlargement;
        best_scale = scale;
        best_strained = strained;
        best = std::move(retry);
      }
    }
  }
  // Still short of the topology: the best layout again with the sample grid at other phases
  // on its charts (a hole a couple of texels across keeps its loop or not by where the sample
  // centres fall around it): the half-texel phases, the quarter diagonals, then the rest of the
  // quarter-texel grid (plane_holes at 64² first keeps its 27 windows at (¼, ½)).
  static constexpr double kPhases[][2] = {{0.5, 0.5},   {0.5, 0},     {0, 0.5},    {0.25, 0.25}, {0.75, 0.75},
                                          {0.25, 0.75}, {0.75, 0.25}, {0.25, 0.5}, {0.5, 0.25},  {0.75, 0.5},
                                          {0.5, 0.75},  {0.25, 0},    {0, 0.25},   {0.75, 0},    {0, 0.75}};
  if (o.repack && best_error > 0) {
    for (const auto& ph : kPhases) {
      std::vector<char> strained = best_strained;
      bool shifted = false;
      Level retry = build_once(a, o, best_scale, strained, progress, {ph[0], ph[1]}, &shifted);
      spent += work_seconds(retry.stats);  // a layout with no room to shift was still packed
      if (!shifted) continue;
      const int error = topology_error(retry.stats);
      // An empty remesh has no topology to lose (a torus's Euler characteristic is 0).
      if (error < best_error && retry.remesh.mesh.num_faces() > 0) {
        retry.stats.enlarged_charts = best.stats.enlarged_charts;
        best_error = error;
        best = std::move(retry);
        if (best_error == 0) break;
      }
    }
  }
  // Every attempt's time counts, as packing (the attempts differ in their packing).
  best.stats.seconds_packing += spent - work_seconds(best.stats);
  // A check of the reconstruction, so its time counts there.
  const auto tl = Clock::now();
  best.stats.lost_charts = count_lost_charts(a, best.remesh.mesh, best.stats.texel_size);
  best.stats.seconds_reconstruction += since(tl);
  return best;
}

}  // namespace

std::string topology_warning(const LevelStats& s) {
  const std::string level = std::to_string(s.width) + "x" + std::to_string(s.height) + " level";
  const TopologyCheck& t = s.topology;
  // Too few samples for the charts' cut paths (a coarse level of a many-chart atlas): the
  // remesh is written, but a pipeline reading only the exit code should hear about it.
  if (t.euler_characteristic != s.input_euler_characteristic || t.boundary_loops != s.input_boundary_loops ||
      !t.edge_manifold())
    return level + " does not keep the input's topology (euler " + std::to_string(t.euler_characteristic) +
           ", input " + std::to_string(s.input_euler_characteristic) + "; boundary loops " +
           std::to_string(t.boundary_loops) + ", input " + std::to_string(s.input_boundary_loops) +
           "): too few samples for its charts";
  // Same counts, but a vertex where two boundary loops or sheets touch: most mesh tools refuse
  // such a file or split the vertex (which changes the counts).
  if (!t.manifold())
    return level + " has " + std::to_string(t.nonmanifold_vertices) +
           (t.nonmanifold_vertices == 1 ? " non-manifold vertex" : " non-manifold vertices") +
           " (pinched where the surface is thinner than its samples)";
  // The topology is kept, but a chart's surface is gone: the remesh looks cut short there.
  if (s.lost_charts > 0)
    return level + " lost part of the surface of " + std::to_string(s.lost_charts) +
           (s.lost_charts == 1 ? " chart" : " charts") +
           " (over 3 texels from the remesh: too thin or small for their samples; try a larger resolution)";
  // Collinear samples across a part thinner than a texel, which no join removes: counted, but
  // a strict reader (ours with --no-repair) refuses the file and others drop the faces.
  if (s.degenerate_triangles > 0)
    return level + " has " + std::to_string(s.degenerate_triangles) +
           (s.degenerate_triangles == 1 ? " zero-area triangle" : " zero-area triangles") +
           " (where the surface is thinner than a texel); readers that drop them leave holes there";
  return {};
}

void check_not_empty(const Level& lv) {
  if (lv.remesh.mesh.num_faces() > 0) return;
  throw isochart::InputError("", std::to_string(lv.stats.width) + "x" + std::to_string(lv.stats.height) +
                                     " level: no 2x2 block of defined samples, so its remesh would be empty "
                                     "(the charts are too small at that resolution; use a larger one)");
}

Level build_level(const isochart::Mesh& atlas, const LevelOptions& options, const isochart::Progress& progress) {
  check_options(options);
  const auto t0 = Clock::now();
  const detail::AtlasCharts a = detail::prepare_atlas(atlas, options.atlas_aspect);
  const double seconds = since(t0);
  Level lv = build_prepared(a, options, progress);
  lv.stats.seconds_charts = seconds;
  return lv;
}

std::vector<Level> build_pyramid(const isochart::Mesh& atlas, const PyramidOptions& options,
                                 const isochart::Progress& progress) {
  if (options.sizes.empty()) throw isochart::InputError("", "a pyramid needs at least one level");
  std::vector<std::array<int, 2>> sizes = options.sizes;
  // Finest first: by sample count, descending (stable for equal counts).
  std::stable_sort(sizes.begin(), sizes.end(), [](const auto& x, const auto& y) {
    return static_cast<long long>(x[0]) * x[1] > static_cast<long long>(y[0]) * y[1];
  });
  LevelOptions o = options.level;
  for (const auto& s : sizes) {
    o.width = s[0];
    o.height = s[1];
    check_options(o);
  }
  const auto t0 = Clock::now();
  const detail::AtlasCharts a = detail::prepare_atlas(atlas, o.atlas_aspect);
  const double seconds = since(t0);
  // Built coarsest first: a level too small for the charts fails in a second, not after the
  // finer levels' minutes of work (--levels 1024,4 took 33 s to say 4x4 was too small). The
  // levels are independent, so the order changes nothing else.
  std::vector<Level> levels;
  for (auto s = sizes.rbegin(); s != sizes.rend(); ++s) {
    o.width = (*s)[0];
    o.height = (*s)[1];
    levels.push_back(build_prepared(a, o, progress));
    check_not_empty(levels.back());
  }
  std::reverse(levels.begin(), levels.end());
  levels.front().stats.seconds_charts = seconds;
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) {
    const auto tc = Clock::now();
    levels[l].coarser = shoot_normals(levels[l].image, levels[l + 1].image, levels[l + 1].remesh,
                                      options.shoot, progress);
    levels[l].stats.seconds_correspondence = since(tc);
  }
  return levels;
}

ResolutionChoice choose_resolution(const isochart::Mesh& atlas, long long target, const LevelOptions& options,
                                   const isochart::Progress& progress, int max_side) {
  if (target < 16) throw isochart::InputError("", "the sample budget must be at least 16");
  if (max_side < 4 || max_side > 16384)
    throw isochart::InputError("", "the largest side must be in 4..16384");
  const detail::AtlasCharts a = detail::prepare_atlas(atlas, options.atlas_aspect);
  LevelOptions o = options;
  ResolutionChoice best;
  auto trial = [&](int res) {
    o.width = o.height = res;
    check_options(o);
    const detail::Placement pl = detail::place_charts(a, o, {}, progress);
    const long long n = detail::count_covered(a, pl);
    ++best.trials;
    if (best.width == 0 || std::llabs(n - target) < std::llabs(best.defined_samples - target) ||
        (std::llabs(n - target) == std::llabs(best.defined_samples - target) && res < best.width)) {
      best.width = best.height = res;
      best.defined_samples = n;
    }
    return n;
  };
  // Coverage grows about with the square of the resolution (the packer fills a similar
  // fraction of any size): iterate on that model until within 1% of the budget. Each trial
  // packs the atlas, which can be slow for thousands of charts, so trials are few.
  int res = std::clamp(static_cast<int>(std::lround(std::sqrt(target / 0.6))), 4, max_side);
  std::vector<int> tried;
  for (int it = 0; it < 5; ++it) {
    if (std::find(tried.begin(), tried.end(), res) != tried.end()) break;
    tried.push_back(res);
    const long long n = trial(res);
    if (std::llabs(n - target) <= target / 100) break;
    const double scale = n > 0 ? std::sqrt(static_cast<double>(target) / n) : 2.0;
    const int wanted = static_cast<int>(std::clamp(std::lround(res * scale), 4L, 1L << 20));
    if (wanted > max_side && res == max_side) {
      best.capped = true;
      break;
    }
    res = std::min(wanted, max_side);
  }
  return best;
}

ResolutionChoice match_resolution(const isochart::Mesh& atlas, long long target, const LevelOptions& options,
                                  const isochart::Progress& progress, int max_side, bool square) {
  LevelOptions o = options;
  o.optimize = false;  // the sample count does not depend on it
  ResolutionChoice rc = choose_resolution(atlas, target, o, progress, max_side);
  if (rc.capped) return rc;
  std::map<std::array<int, 2>, long long> tried;
  std::array<int, 2> best{rc.width, rc.height};
  auto off = [&](long long d) { return std::llabs(d - target); };
  auto trial = [&](int w, int h) {
    w = std::clamp(w, 4, max_side);
    h = std::clamp(h, 4, max_side);
    if (tried.count({w, h})) return;
    o.width = w;
    o.height = h;
    const long long d = build_level(atlas, o, progress).stats.defined_samples;
    tried[{w, h}] = d;
    if (tried.size() == 1 || off(d) < off(tried[best])) best = {w, h};
  };
  auto good = [&] { return off(tried[best]) * 50 <= target; };
  trial(best[0], best[1]);
  for (int it = 0; it < 3 && !good(); ++it) {
    const long long d = tried[best];
    const double s = d > 0 ? std::sqrt(static_cast<double>(target) / d) : 2.0;
    const int w = static_cast<int>(std::lround(best[0] * s)), h = static_cast<int>(std::lround(best[1] * s));
    if (tried.count({std::clamp(w, 4, max_side), std::clamp(h, 4, max_side)})) break;
    trial(w, h);
  }
  // Cleanup makes the count jump by whole rows of a chart: the sizes around the best, by ring.
  // Square sizes step one side at a time around a fixed centre: following the best as it
  // moved skipped 21x21 (97 of 100 samples) on the way from 20x20 to 22x22.
  const std::array<int, 2> centre = best;
  for (int ring = 1; ring <= 3 && !good(); ++ring)
    for (int dw = -ring; dw <= ring && !good(); ++dw)
      for (int dh = -ring; dh <= ring && !good(); ++dh)
        if (!square && std::max(std::abs(dw), std::abs(dh)) == ring)
          trial(best[0] + dw, best[1] + dh);
        else if (square && dw == dh && std::abs(dw) == ring)
          trial(centre[0] + dw, centre[1] + dh);
  rc.width = best[0];
  rc.height = best[1];
  rc.defined_samples = tried[best];
  rc.trials += static_cast<int>(tried.size());
  return rc;
}

}  // namespace mcgim
