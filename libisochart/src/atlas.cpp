// The iso-charts driver (Iso-charts §3): recursive stretch-driven splitting, merging, packing.

#include "atlas_charts.h"
#include "isochart/atlas.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <set>
#include <thread>
#include <unordered_map>

#include "chart.h"
#include "isochart/embedding.h"
#include "isochart/error.h"
#include "isochart/geodesic.h"
#include "isochart/stretch.h"
#include "partition.h"
#include "signal_distance.h"
#include "isochart/rng.h"

namespace isochart {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Fraction of the chart's triangles that `uv` maps clockwise (either orientation counts as
// unflipped: the chart may be mirrored as a whole).
double flipped_fraction(const detail::ChartGeometry& g, const std::vector<Vec2d>& uv) {
  int negative = 0;
  for (const Face& t : g.tris) negative += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) < 0 ? 1 : 0;
  const int n = g.num_faces();
  return n > 0 ? std::min(negative, n - negative) / static_cast<double>(n) : 0.0;
}

// A flat chart's own layout: its vertices projected onto its plane (an isometry, L2 = Linf = 1),
// with the faces' winding; empty unless every vertex lies within 1e-6 of the chart's size of
// that plane (coordinates written with six or seven digits, as CAD exports do) and every face
// faces the same way. CAD files fill flat polygons with fans of long slivers, on which
// geodesics and their embedding are poor: a flat 200-gon came out as 6 charts with Linf 3.6.
std::vector<Vec2d> planar_layout(const detail::ChartGeometry& g) {
  std::vector<Vec3d> face_n(g.tris.size());  // area-weighted
  Vec3d n;
  for (std::size_t f = 0; f < g.tris.size(); ++f) {
    const Face& t = g.tris[f];
    face_n[f] = cross(g.positions[t[1]] - g.positions[t[0]], g.positions[t[2]] - g.positions[t[0]]);
    n += face_n[f];
  }
  const double len = norm(n);
  if (!(len > 0)) return {};
  n = n / len;
  const BoundingBox box = bounding_box(g.positions);
  const double size = box.diagonal();
  const Vec3d& o = g.positions[0];
  for (const Vec3d& p : g.positions)
    if (std::abs(dot(p - o, n)) > 1e-6 * size) return {};
  for (const Vec3d& fn : face_n)
    if (!(dot(fn, n) > 0)) return {};
  // Any orthonormal basis (e1, e2) with e1 × e2 = n keeps the winding.
  const Vec3d a = std::abs(n.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  const Vec3d e1 = normalized(cross(a, n)), e2 = cross(n, e1);
  std::vector<Vec2d> uv(g.positions.size());
  for (std::size_t v = 0; v < uv.size(); ++v)
    uv[v] = {dot(g.positions[v] - o, e1), dot(g.positions[v] - o, e2)};
  return uv;
}

// Seconds per stage of one unit of work, summed into the atlas report in a fixed order.
struct StageTimes {
  double geodesics = 0, embedding = 0, optimization = 0, clustering = 0, graph_cut = 0;
  void add(const StageTimes& o) {
    geodesics += o.geodesics;
    embedding += o.embedding;
    optimization += o.optimization;
    clustering += o.clustering;
    graph_cut += o.graph_cut;
  }
};

// A finished chart.
struct DoneChart {
  detail::ChartGeometry geometry;
  detail::ChartParam param;
};

// A chart waiting to be processed: its faces and how many subdivisions produced it.
struct Work {
  std::vector<int> faces;
  int depth = 0;
  std::vector<int> path;     // part indices from the root of the recursion
  bool force_split = false;  // --max-charts: split even if the chart meets the bounds
  bool alone = false;        // the only chart of its recursion, nothing runs beside it
};

// What processing one chart produced: either an accepted parameterization or parts to recurse on.
struct Outcome {
  bool accepted = false;
  bool components_only = false;  // the parts are just the chart's disconnected pieces
  DoneChart chart;
  std::vector<std::vector<int>> parts;  // parent face ids per part
  StageTimes times;
};

// AtlasOptions::skip_packing: every chart scaled to its 3-D area, unrotated, its bounding box
// placed in rows about as wide as the layout is tall, a margin of 2% of the widest box
// between boxes; then the whole layout is scaled uniformly into [0,1]².
void lay_out_unpacked(const Mesh& mesh, Atlas& atlas) {
  const std::vector<detail::AtlasChart> charts = detail::split_atlas_charts(mesh, atlas);
  const int nc = static_cast<int>(charts.size());
  std::vector<double> scale(nc, 1.0);
  std::vector<Vec2d> lo(nc), size(nc);
  double box_area = 0, widest = 0;
  for (int c = 0; c < nc; ++c) {
    const detail::AtlasChart& ch = charts[c];
    double a3 = 0, a2 = 0;
    for (const Face& t : ch.tris) {
      a3 += triangle_area(ch.positions[t[0]], ch.positions[t[1]], ch.positions[t[2]]);
      a2 += std::abs(signed_area(ch.uv[t[0]], ch.uv[t[1]], ch.uv[t[2]]));
    }
    if (a2 > 0 && a3 > 0) scale[c] = std::sqrt(a3 / a2);
    Vec2d l{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    Vec2d h = -l;
    for (const Vec2d& p : ch.uv) {
      l = {std::min(l.x, p.x), std::min(l.y, p.y)};
      h = {std::max(h.x, p.x), std::max(h.y, p.y)};
    }
    lo[c] = l;
    size[c] = (h - l) * scale[c];
    box_area += size[c].x * size[c].y;
    widest = std::max({widest, size[c].x, size[c].y});
  }
  const double margin = 0.02 * widest;
  const double row_width = std::max(std::sqrt(box_area) * 1.2, widest);
  double x = 0, y = 0, row_height = 0, extent = 0;
  std::vector<Vec2d> corner(nc);
  for (int c = 0; c < nc; ++c) {
    if (x > 0 && x + size[c].x > row_width) {
      x = 0;
      y += row_height + margin;
      row_height = 0;
    }
    corner[c] = {x, y};
    x += size[c].x + margin;
    row_height = std::max(row_height, size[c].y);
    extent = std::max({extent, corner[c].x + size[c].x, corner[c].y + size[c].y});
  }
  const double to_unit = extent > 0 ? 1.0 / extent : 1.0;
  for (int c = 0; c < nc; ++c)
    for (size_t i = 0; i < charts[c].uv_ids.size(); ++i)
      atlas.uvs[charts[c].uv_ids[i]] = (corner[c] + (charts[c].uv[i] - lo[c]) * scale[c]) * to_unit;
  const StretchStats st = measure_stretch(atlas.apply_to(mesh));
  atlas.stats.charts = nc;
  atlas.stats.l2 = st.l2;
  atlas.stats.linf = st.linf;
  atlas.stats.flipped = st.flipped;
  atlas.stats.overlapping_pairs = -1;
  atlas.stats.packing_ratio = 0;
}

class Builder {
 public:
  Builder(const Mesh& mesh, const AtlasOptions& o, const Progress& progress)
      : mesh_(mesh), o_(o), progress_(progress), topo_(mesh) {
    split_.alpha = o.alpha;
    split_.medial_fraction = o.medial_fraction;
    split_.graph_cut = o.graph_cut;
    split_.min_rep_distance = 10 * mean_edge_length(mesh, topo_);
    param_.max_l2 = o.max_l2;
    param_.max_linf = o.max_linf;
    param_.optimize_passes = o.optimize_passes;
    if (!o.face_metric.empty()) param_.face_metric = &o.face_metric;
    param_.max_geometric_l2 = o.max_geometric_l2;
    component_vertices_.assign(topo_.num_components(), 0);
    std::vector<int> seen(mesh.num_vertices(), 0);
    for (int f = 0; f < mesh.num_faces(); ++f)
      for (int v : mesh.faces[f])
        if (!seen[v]) {
          seen[v] = 1;
          ++component_vertices_[topo_.face_components()[f]];
        }
  }

  Atlas run() {
    const auto t_start = Clock::now();
    // Every connected component starts as one chart.
    std::vector<Work> queue(topo_.num_components());
    for (int f = 0; f < mesh_.num_faces(); ++f) queue[topo_.face_components()[f]].faces.push_back(f);
    std::vector<DoneChart> done = recurse(std::move(queue), false);
    charts_before_merge_ = static_cast<int>(done.size());

    // --max-charts N: split the worst chart until there are N.
    while (o_.max_charts > 0 && static_cast<int>(done.size()) < o_.max_charts) {
      auto worst = std::max_element(done.begin(), done.end(), [](const DoneChart& a, const DoneChart& b) {
        if (a.geometry.num_faces() < 2) return b.geometry.num_faces() >= 2;
        if (b.geometry.num_faces() < 2) return false;
        return a.param.l2 < b.param.l2;
      });
      if (worst == done.end() || worst->geometry.num_faces() < 2) break;
      std::vector<Work> q{Work{worst->geometry.faces, 1, {}, false}};
      done.erase(worst);
      std::vector<DoneChart> more = recurse(std::move(q), true);
      for (auto& c : more) done.push_back(std::move(c));
    }
    charts_before_merge_ = std::max<int>(charts_before_merge_, static_cast<int>(done.size()));

    const auto t_merge = Clock::now();
    if (o_.merge) merge(done);
    const double merge_seconds = since(t_merge);

    // Stable output order: by smallest parent face id.
    std::sort(done.begin(), done.end(), [](const DoneChart& a, const DoneChart& b) {
      return *std::min_element(a.geometry.faces.begin(), a.geometry.faces.end()) <
             *std::min_element(b.geometry.faces.begin(), b.geometry.faces.end());
    });

    Atlas atlas = assemble(done);
    auto& s = atlas.stats.seconds;
    if (o_.skip_packing) {
      lay_out_unpacked(mesh_, atlas);
      atlas.stats.charts_before_merge = charts_before_merge_;
    } else {
      s["packing"] = pack(atlas);
    }
    atlas.stats.splits = splits_;
    atlas.stats.seed = o_.seed;
    s["geodesics"] = times_.geodesics;
    s["embedding"] = times_.embedding;
    s["optimization"] = times_.optimization;
    s["clustering"] = times_.clustering;
    s["graph_cut"] = times_.graph_cut;
    s["merging"] = merge_seconds;
    s["total"] = since(t_start);
    return atlas;
  }

 private:
  // Packs the atlas (§6), with the optional cuts for packing; returns the packing's seconds.
  double pack(Atlas& atlas) const {
    PackSplitOptions split;
    split.max_l2 = o_.max_l2;
    split.max_linf = o_.max_linf;
    split.max_added = o_.max_charts > 0 ? 0 : o_.pack_cuts;  // --max-charts N asks for exactly N
    PackSplitResult sr;
    const PackResult pr = split_and_pack_atlas(mesh_, atlas, o_.pack, split, progress_, &sr);
    atlas.stats.charts_before_merge = charts_before_merge_ + sr.added;
    return pr.seconds;
  }

  // Processes charts as a tree of tasks: a part is queued as soon as its parent is split, so a
  // core never waits for the slowest chart of a generation (the serial optimizer and clustering
  // of one large chart used to leave the other core idle). Every chart carries its path in the
  // tree, and the finished charts are ordered as a generation-by-generation traversal would
  // list them (by path length, then path); processing a chart depends only on its faces, depth
  // and the forced split, so the output never depends on the thread count.
  std::vector<DoneChart> recurse(std::vector<Work> queue, bool force_first_split) {
    for (size_t i = 0; i < queue.size(); ++i) {
      queue[i].path = {static_cast<int>(i)};
      queue[i].force_split = force_first_split;
      queue[i].alone = queue.size() == 1;
    }
    std::mutex mutex;
    std::vector<std::pair<std::vector<int>, DoneChart>> done;
    tbb::parallel_for_each(queue.begin(), queue.end(), [&](const Work& w, tbb::feeder<Work>& feeder) {
      Outcome r = process(w, w.force_split);
      long long accepted_faces;
      {
        const std::lock_guard<std::mutex> lock(mutex);
        times_.add(r.times);
        if (r.accepted) {
          accepted_faces_ += r.chart.geometry.num_faces();
          done.emplace_back(w.path, std::move(r.chart));
        } else {
          ++splits_;
        }
        accepted_faces = accepted_faces_;
      }
      if (r.accepted) {
        report(progress_, Stage::Clustering, static_cast<double>(accepted_faces) / std::max(1, mesh_.num_faces()));
        return;
      }
      // Separating disconnected pieces is not a subdivision: they keep their depth.
      const int depth = w.depth + (r.components_only ? 0 : 1);
      for (size_t j = 0; j < r.parts.size(); ++j) {
        Work child{std::move(r.parts[j]), depth, w.path, false};
        child.path.push_back(static_cast<int>(j));
        feeder.add(std::move(child));
      }
    });
    std::sort(done.begin(), done.end(), [](const auto& a, const auto& b) {
      return a.first.size() != b.first.size() ? a.first.size() < b.first.size() : a.first < b.first;
    });
    std::vector<DoneChart> charts;
    charts.reserve(done.size());
    for (auto& d : done) charts.push_back(std::move(d.second));
    return charts;
  }

  std::uint64_t chart_seed(const std::vector<int>& faces) const {
    return mix_seed(mix_seed(o_.seed, static_cast<std::uint64_t>(*std::min_element(faces.begin(), faces.end()))),
                    faces.size());
  }

  // Parameterizes the chart if it can meet the bounds, otherwise splits it (§3 steps 1–6).
  Outcome process(const Work& work, bool force_split) const {
    Outcome out;
    const std::vector<int>& faces = work.faces;
    detail::ChartGeometry g = detail::make_chart(mesh_, faces);
    // Faces meeting only at a vertex would make a pinched chart: each fan gets its own copy.
    const Topology topo = detail::chart_topology(g);
    if (topo.num_components() > 1) {
      out.components_only = true;
      out.parts.resize(topo.num_components());
      for (int f = 0; f < g.num_faces(); ++f) out.parts[topo.face_components()[f]].push_back(g.faces[f]);
      return out;
    }
    detail::ParamOptions po = param_;
    po.seed = chart_seed(faces);
    if (g.num_faces() == 1) {
      out.accepted = true;
      out.chart.param = detail::parameterize(g, {}, po);
      out.chart.geometry = std::move(g);
      return out;
    }
    // A disk may be accepted whole, from its own plane when it is flat, else from its embedding.
    const bool may_accept = topo.genus() == 0 && !topo.boundary_loops().empty() && !force_split;
    if (may_accept) {
      const std::vector<Vec2d> flat = planar_layout(g);
      if (!flat.empty() && try_accept(g, topo, flat, po, out)) return out;
    }
    Embedding emb = embed(g, out.times, landmarks_for(g, faces));
    if (may_accept) {
      if (!work.alone) {
        if (try_accept(g, topo, detail::isomap_uv(emb), po, out)) return out;
      } else {
        // The only chart in progress (the whole mesh, mostly): nothing else keeps the other
        // cores busy, so the split is computed while the acceptance is tried and dropped if
        // the chart is accepted. Both depend only on the chart: the result is the same.
        const std::vector<Vec2d> start = detail::isomap_uv(emb);
        Outcome split_out;
        bool accepted = false;
        tbb::parallel_invoke([&] { accepted = try_accept(g, topo, start, po, out); },
                             [&] { split(work, g, topo, po, emb, split_out); });
        if (accepted) return out;
        out.times.add(split_out.times);
        out.parts = std::move(split_out.parts);
        if (split_out.accepted) {
          out.accepted = true;
          out.chart = std::move(split_out.chart);
        }
        return out;
      }
    }
    split(work, g, topo, po, emb, out);
    return out;
  }

  // Splits a chart that was not accepted (§5) into `out.parts`; `emb` is its embedding.
  void split(const Work& work, const detail::ChartGeometry& g, const Topology& topo, const detail::ParamOptions& po,
             Embedding& emb, Outcome& out) const {
    auto t0 = Clock::now();
    if (!o_.vertex_signal.empty() && o_.signal_beta < 1)
      emb = detail::combined_embedding(g, emb, o_.vertex_signal, o_.signal_dimension, o_.signal_beta);
    detail::SplitKind kind;
    int m = 0;
    detail::SplitOptions so = split_;
    so.allow_general = work.depth == 0;
    std::vector<int> labels = detail::spectral_partition(g, emb, so, kind, m);
    if (m >= 2) m = detail::make_labels_connected(topo, g.positions, labels);
    out.times.clustering += since(t0);
    if (m >= 2 && split_.graph_cut) {
      t0 = Clock::now();
      detail::optimize_boundaries(g, topo, emb, labels, m, so);
      detail::smooth_labels(topo, labels);
      m = detail::make_labels_connected(topo, g.positions, labels);
      out.times.graph_cut += since(t0);
    }
    if (m < 2) {
      labels = detail::fallback_partition(g, topo, emb, m);
      m = detail::make_labels_connected(topo, g.positions, labels);
    }
    out.parts.assign(m, {});
    for (int f = 0; f < g.num_faces(); ++f) out.parts[labels[f]].push_back(g.faces[f]);
    if (m < 2) {
      // Cannot split (should not happen): accept the best parameterization we have so the run ends.
      out.parts.clear();
      out.accepted = true;
      out.chart.param = detail::parameterize(g, detail::isomap_uv(emb), po);
      out.chart.geometry = g;
    }
  }

  // Landmarks for chart g (with parent faces `faces`): the full count for a whole component,
  // in proportion to the chart's share of its component's vertices below that, at least 25.
  int landmarks_for(const detail::ChartGeometry& g, const std::vector<int>& faces) const {
    const int component = component_vertices_[topo_.face_components()[faces.front()]];
    const double share = component > 0 ? static_cast<double>(g.num_vertices()) / component : 1.0;
    return std::clamp(static_cast<int>(o_.landmarks * share), std::min(25, o_.landmarks), o_.landmarks);
  }

  Embedding embed(const detail::ChartGeometry& g, StageTimes& t, int landmarks) const {
    auto t0 = Clock::now();
    const GeodesicSolver solver(g.positions, g.tris);
    t.geodesics += since(t0);
    EmbeddingOptions eo;
    eo.landmarks = landmarks;
    t0 = Clock::now();
    Embedding e = landmark_isomap(solver, eo);
    t.embedding += since(t0);
    return e;
  }

  // Chart merging (§6): charts, smallest first, into the neighbour with the most similar average
  // normal, whenever the merged chart still meets the bounds.
  //
  // Each round tries one small chart's neighbours in order, and the first success wins. A
  // merge attempt depends only on the two charts, so its outcome is kept (keyed by each chart's
  // smallest face and size, which name one state of a chart: charts only grow) until one side
  // changes. With several threads, attempts the coming rounds will probably ask for (the next
  // small charts' first neighbours, this round's later candidates) run in the background while
  // the rounds go on, and a round takes an outcome from there when it is ready or being
  // computed. What is computed ahead changes only the time, never the result, so the atlas
  // does not depend on the thread count.
  void merge(std::vector<DoneChart>& done) const {
    const int total_faces = mesh_.num_faces();
    const int min_charts = std::max(1, o_.max_charts);
    // Shared with the background attempts, which must not see a chart move or change.
    std::vector<std::shared_ptr<const DoneChart>> charts;
    charts.reserve(done.size());
    for (DoneChart& c : done) charts.push_back(std::make_shared<const DoneChart>(std::move(c)));
    std::vector<int> chart_of(total_faces, -1);
    auto rebuild_index = [&] {
      for (int c = 0; c < static_cast<int>(charts.size()); ++c)
        for (int f : charts[c]->geometry.faces) chart_of[f] = c;
    };
    rebuild_index();
    const std::vector<Vec3d> fn = face_normals(mesh_);
    const std::vector<double> fa = face_areas(mesh_);
    std::vector<Vec3d> normals;
    auto refresh_normals = [&] {
      normals.assign(charts.size(), Vec3d{});
      for (size_t c = 0; c < charts.size(); ++c) {
        Vec3d n;
        for (int f : charts[c]->geometry.faces) n += fn[f] * fa[f];
        normals[c] = normalized(n);
      }
    };
    refresh_normals();
    using Key = std::pair<int, size_t>;
    using PairKey = std::pair<Key, Key>;  // (small, neighbour)
    auto key = [&](int c) {
      const auto& f = charts[c]->geometry.faces;
      return Key(*std::min_element(f.begin(), f.end()), f.size());
    };
    std::vector<char> tried(charts.size(), 0);
    std::set<PairKey> failed;
    std::map<PairKey, Outcome> known;  // outcomes in hand
    // Background attempts: queued (0), running (1), done (2) or abandoned before starting (3).
    struct Slot {
      std::atomic<int> state{0};
      std::atomic<bool> cancel{false};  // abandoned while running: stop early
      std::shared_ptr<const DoneChart> a, b;
      Outcome out;
      std::exception_ptr error;
    };
    // Whoever moves a slot from queued to running computes it.
    auto run_slot = [this](Slot& slot) {
      try {
        slot.out = merge_charts(*slot.a, *slot.b, &slot.cancel);
      } catch (...) {
        slot.error = std::current_exception();
      }
      slot.a.reset();
      slot.b.reset();
      slot.state.store(2, std::memory_order_release);
    };
    std::map<PairKey, std::shared_ptr<Slot>> ahead;
    std::vector<std::shared_ptr<Slot>> queue;  // in the order started
    tbb::task_group background;
    const int threads = static_cast<int>(
        std::min<size_t>(tbb::this_task_arena::max_concurrency(),
                         tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)));
    auto start_ahead = [&](int a, int b) {
      const PairKey k{key(a), key(b)};
      if (known.count(k) || ahead.count(k)) return;
      auto slot = std::make_shared<Slot>();
      slot->a = charts[a];
      slot->b = charts[b];
      ahead.emplace(k, slot);
      queue.push_back(slot);
      background.run([slot, &run_slot] {
        int queued = 0;
        if (slot->state.compare_exchange_strong(queued, 1)) run_slot(*slot);  // else taken or abandoned
      });
    };
    auto prune = [&] {
      queue.erase(std::remove_if(queue.begin(), queue.end(), [](const auto& q) { return q->state.load() >= 2; }),
                  queue.end());
    };
    // Counted over the queue (pruned every round), not over `ahead`, which keeps every
    // finished attempt nobody asked for yet: with thousands of charts that map grew to
    // thousands of entries, walked for every attempt started (most of a run whose bounds
    // split a sphere into its 5,120 triangles). Which attempts run ahead changes no result.
    auto in_flight = [&] {
      int n = 0;
      for (const auto& slot : queue) n += slot->state.load() < 2 ? 1 : 0;
      return n;
    };
    // The outcome of merging a into b: kept, computed ahead, or computed here.
    auto obtain = [&](int a, int b) -> Outcome& {
      const PairKey k{key(a), key(b)};
      auto it = known.find(k);
      if (it != known.end()) return it->second;
      Outcome out;
      const auto s = ahead.find(k);
      bool computed = false;
      if (s != ahead.end()) {
        const std::shared_ptr<Slot> slot = s->second;
        ahead.erase(s);
        int queued = 0;
        if (!slot->state.compare_exchange_strong(queued, 3)) {
          // Running elsewhere: meanwhile take on the oldest attempt nobody has started.
          while (slot->state.load(std::memory_order_acquire) != 2) {
            bool helped = false;
            for (const auto& other : queue) {
              int q = 0;
              if (other->state.load() == 0 && other->state.compare_exchange_strong(q, 1)) {
                run_slot(*other);
                helped = true;
                break;
              }
            }
            if (!helped) std::this_thread::yield();
          }
          if (slot->error) std::rethrow_exception(slot->error);
          out = std::move(slot->out);
          computed = true;
        }
      }
      if (!computed) out = merge_charts(*charts[a], *charts[b]);
      return known.emplace(k, std::move(out)).first->second;
    };
    auto forget = [&](const Key& gone) {
      for (auto k = known.begin(); k != known.end();)
        k = k->first.first == gone || k->first.second == gone ? known.erase(k) : std::next(k);
      for (auto k = ahead.begin(); k != ahead.end();) {
        if (k->first.first != gone && k->first.second != gone) {
          ++k;
          continue;
        }
        int queued = 0;
        // Already running: its outcome will never be asked for, so it may stop.
        if (!k->second->state.compare_exchange_strong(queued, 3)) k->second->cancel.store(true);
        k = ahead.erase(k);
      }
    };
    // Neighbours of chart c by decreasing normal similarity, without pairs known to fail.
    auto neighbours_of = [&](int c) {
      std::vector<int> nbs;
      for (int f : charts[c]->geometry.faces)
        for (int k = 0; k < 3; ++k) {
          const int nb = topo_.opposite_face(f, k);
          if (nb >= 0 && chart_of[nb] != c && std::find(nbs.begin(), nbs.end(), chart_of[nb]) == nbs.end())
            nbs.push_back(chart_of[nb]);
        }
      const Vec3d n0 = normals[c];
      std::sort(nbs.begin(), nbs.end(), [&](int a, int b) {
        const double da = dot(n0, normals[a]), db = dot(n0, normals[b]);
        return da != db ? da > db : a < b;
      });
      const Key kc = key(c);
      nbs.erase(std::remove_if(nbs.begin(), nbs.end(), [&](int nb) { return failed.count(std::minmax(kc, key(nb))) > 0; }),
                nbs.end());
      return nbs;
    };
    auto is_small = [&](int c) { return charts[c]->geometry.num_faces() <= o_.merge_max_fraction * total_faces; };
    // Attempts nobody will ask for: those not started are dropped, running ones told to stop.
    auto abandon_ahead = [&] {
      for (auto& [k, slot] : ahead) {
        int queued = 0;
        if (!slot->state.compare_exchange_strong(queued, 3)) slot->cancel.store(true);
      }
    };
    // Merging a million-face mesh takes half a minute: it reports its rounds (the share of
    // small charts looked at so far) and may be cancelled between them.
    int rounds = 0;
    double reported = 0;
    bool progress = true;
    while (progress && static_cast<int>(charts.size()) > min_charts) {
      progress = false;
      // Untried small charts, smallest first; the first is this round's.
      std::vector<int> smalls;
      for (int c = 0; c < static_cast<int>(charts.size()); ++c)
        if (!tried[c] && is_small(c)) smalls.push_back(c);
      if (smalls.empty()) break;
      reported =
          std::max(reported, static_cast<double>(rounds) / static_cast<double>(rounds + smalls.size()));
      ++rounds;
      try {
        report(progress_, Stage::Merging, reported);
      } catch (...) {
        abandon_ahead();
        throw;  // the task group waits for the running attempts, which stop early
      }
      std::stable_sort(smalls.begin(), smalls.end(), [&](int a, int b) {
        return charts[a]->geometry.num_faces() < charts[b]->geometry.num_faces();
      });
      const int small = smalls[0];
      tried[small] = 1;
      const std::vector<int> neighbours = neighbours_of(small);
      const Key ks = key(small);
      prune();
      if (threads > 1) {
        // While this thread works on the round's first candidate: the next four small charts'
        // first neighbours, the round's later candidates, then the other small charts' first
        // ones. The round's first candidate wins in most rounds, so its later ones are usually
        // wasted; a coming round's first is wasted only when this round changes one of its two
        // charts. With the later candidates second instead (the next small chart's first only
        // before them), bunny's merging took 0.85-0.87 s against 0.71-0.72 s, feline's
        // 1.96-2.03 s against 1.78-1.83 s, gargoyle's 2.51 s against 2.26-2.37 s (horse
        // alike); with every coming round first, bunny's 0.75-0.99 s. Up to six per extra
        // thread queued or running: with two, a round waiting for a running attempt mostly
        // finds another to compute meanwhile (gargoyle's merging 5.6-6.4 s with two, 4.4-4.6 s
        // with six).
        constexpr size_t kComingFirst = 4;
        const int budget = 6 * (threads - 1);
        std::vector<std::pair<int, int>> wanted;
        for (size_t j = 1; j < smalls.size(); ++j) {
          const int c = smalls[j];
          for (int nb : neighbours_of(c)) {
            if (nb == small) continue;  // about to change, either way
            const auto it = known.find({key(c), key(nb)});
            if (it != known.end() && !it->second.accepted) continue;
            if (it == known.end()) wanted.emplace_back(c, nb);
            break;
          }
        }
        const auto split = wanted.begin() + std::min(kComingFirst, wanted.size());
        std::vector<std::pair<int, int>> order(wanted.begin(), split);
        for (size_t i = 1; i < neighbours.size(); ++i) order.emplace_back(small, neighbours[i]);
        order.insert(order.end(), split, wanted.end());
        for (const auto& [a, b] : order) {
          if (in_flight() >= budget) break;
          start_ahead(a, b);
        }
      }
      size_t winner = neighbours.size();
      for (size_t i = 0; i < neighbours.size(); ++i)
        if (obtain(small, neighbours[i]).accepted) {
          winner = i;
          break;
        }
      // Candidates before the winner all failed: recorded so that neither side retries them
      // until one of them changes.
      for (size_t i = 0; i < winner; ++i) failed.insert(std::minmax(ks, key(neighbours[i])));
      if (winner < neighbours.size()) {
        const int nb = neighbours[winner];
        const Key kn = key(nb);
        auto it = known.find({ks, kn});
        // Replace the neighbour with the merged chart and drop the small one.
        charts[nb] = std::make_shared<const DoneChart>(std::move(it->second.chart));
        known.erase(it);
        // Outcomes involving either old chart are stale.
        forget(ks);
        forget(kn);
        tried[nb] = 0;
        charts.erase(charts.begin() + small);
        tried.erase(tried.begin() + small);
        rebuild_index();
        refresh_normals();
        progress = true;
      }
      if (!progress) {
        // Nothing merged for this chart; look at the next smallest.
        progress = std::find(tried.begin(), tried.end(), 0) != tried.end();
      }
    }
    abandon_ahead();
    background.wait();
    done.clear();
    for (auto& c : charts) done.push_back(*c);
  }

  // Tries to merge chart `a` into chart `b`. The start is the union of both parameterizations,
  // `a` moved onto `b` by the similarity that best matches their shared boundary vertices, so
  // no new embedding is needed; it is then untangled and optimized like any other start.
  Outcome merge_charts(const DoneChart& a, const DoneChart& b, const std::atomic<bool>* cancel = nullptr) const {
    Outcome out;
    std::vector<int> faces = a.geometry.faces;
    faces.insert(faces.end(), b.geometry.faces.begin(), b.geometry.faces.end());
    std::sort(faces.begin(), faces.end());
    detail::ChartGeometry g = detail::make_chart(mesh_, faces);
    const Topology topo = detail::chart_topology(g);
    if (topo.num_components() != 1 || topo.genus() != 0 || topo.boundary_loops().empty()) return out;

    // Texture coordinate of each parent vertex in either chart (first copy wins).
    std::unordered_map<int, Vec2d> uv_a, uv_b;
    for (int v = 0; v < a.geometry.num_vertices(); ++v) uv_a.emplace(a.geometry.vertex_parent[v], a.param.uv[v]);
    for (int v = 0; v < b.geometry.num_vertices(); ++v) uv_b.emplace(b.geometry.vertex_parent[v], b.param.uv[v]);
    std::vector<std::pair<Vec2d, Vec2d>> shared;  // (in a, in b)
    for (const auto& [pv, ua] : uv_a) {
      const auto it = uv_b.find(pv);
      if (it != uv_b.end()) shared.emplace_back(ua, it->second);
    }
    if (shared.size() < 2) return out;
    std::sort(shared.begin(), shared.end(), [](const auto& x, const auto& y) {
      return x.first.x != y.first.x ? x.first.x < y.first.x : x.first.y < y.first.y;
    });
    // Least-squares similarity (rotation, scale, translation; never a reflection) a → b.
    Vec2d ca, cb;
    for (const auto& [p, q] : shared) {
      ca += p;
      cb += q;
    }
    ca /= static_cast<double>(shared.size());
    cb /= static_cast<double>(shared.size());
    double sxx = 0, sxy = 0, norm_a = 0;
    for (const auto& [p, q] : shared) {
      const Vec2d x = p - ca, y = q - cb;
      sxx += dot(x, y);
      sxy += cross(x, y);
      norm_a += dot(x, x);
    }
    if (!(norm_a > 0)) return out;
    const double angle = std::atan2(sxy, sxx);
    const double scale = std::hypot(sxx, sxy) / norm_a;
    const double c = std::cos(angle) * scale, sn = std::sin(angle) * scale;
    auto to_b = [&](const Vec2d& p) {
      const Vec2d x = p - ca;
      return Vec2d{c * x.x - sn * x.y, sn * x.x + c * x.y} + cb;
    };
    std::vector<Vec2d> start_uncut(g.num_vertices());
    for (int v = 0; v < g.num_vertices(); ++v) {
      const int pv = g.vertex_parent[v];
      const auto it = uv_b.find(pv);
      start_uncut[v] = it != uv_b.end() ? it->second : to_b(uv_a.at(pv));
    }
    detail::ParamOptions po = param_;
    po.seed = chart_seed(faces);
    po.lscm_on_any_failure = true;
    // Over the 14 shared meshes no accepted union started above 0.07 % (of 204), and 150 of
    // 525 failed ones did, some of them spending a second in optimization.
    po.max_start_overlap = 0.002;
    po.cancel = cancel;
    try_accept(g, topo, start_uncut, po, out);
    return out;
  }

  // Parameterizes a genus-0 chart with boundary and accepts it into `out` if it meets the
  // bounds. Several boundary loops are slit into one first; the slit has zero width, so the
  // uncut chart's embedding is a valid start for the slit chart too.
  bool try_accept(const detail::ChartGeometry& g, const Topology& topo, const std::vector<Vec2d>& start_uv,
                  const detail::ParamOptions& po, Outcome& out) const {
    if (signal_too_uneven(g)) return false;
    detail::ChartGeometry cg = g;
    std::vector<int> origin;
    if (!detail::cut_to_disk(cg, &origin, &topo)) return false;
    std::vector<Vec2d> start;
    if (!start_uv.empty()) {
      for (int v : origin) start.push_back(start_uv[v]);
      detail::open_slits(cg, origin, start);
      // A tube (two boundary loops, slit lengthwise): the uncut embedding flattens it onto
      // itself. Geodesics on the slit chart go around the slit, so its own embedding unrolls it.
      const bool tube = topo.boundary_loops().size() == 2;
      if (tube && flipped_fraction(cg, start) > 0.25)
        start = detail::isomap_uv(embed(cg, out.times, landmarks_for(cg, g.faces)));
    }
    auto accept = [&out](detail::ChartGeometry& geometry, detail::ChartParam& param) {
      out.accepted = true;
      out.chart.geometry = std::move(geometry);
      out.chart.param = std::move(param);
      return true;
    };
    // A single boundary loop needs no slit: the chart is unchanged and so is its topology.
    detail::ParamOptions cut_po = po;
    if (topo.boundary_loops().size() == 1) cut_po.topology = &topo;
    detail::ChartParam p = detail::parameterize(cg, start, cut_po);
    out.times.optimization += p.optimize_seconds;
    if (p.accepted) return accept(cg, p);
    // A sock (a tube closed at one end, like a leg) folds onto itself in any flat start.
    // Slit lengthwise it unrolls: one chart instead of the two or three splitting would take.
    // Either its shape says so, or the start folded over a quarter of it.
    if (topo.boundary_loops().size() != 1) return false;
    const std::vector<double> dist = detail::boundary_distance(g, topo);
    const bool folded = !start.empty() && flipped_fraction(cg, start) > 0.25;
    if (!folded && !detail::is_sock(g, topo, dist)) return false;
    detail::ChartGeometry sg = g;
    if (!detail::cut_seam(sg, topo, &dist)) return false;
    if (detail::linf_bound_unreachable(sg, nullptr, po.max_linf)) return false;  // spares its embedding
    const Embedding se = embed(sg, out.times, landmarks_for(sg, g.faces));
    detail::ChartParam q = detail::parameterize(sg, detail::isomap_uv(se), po);
    out.times.optimization += q.optimize_seconds;
    return q.accepted && accept(sg, q);
  }

  // Signal-specialized charts (§7): a large chart whose signal density varies so much that a
  // single texel density wastes most of what an ideal allocation would gain is split.
  bool signal_too_uneven(const detail::ChartGeometry& g) const {
    if (o_.face_metric.empty() || !(o_.signal_split_efficiency > 0)) return false;
    if (g.num_faces() * 100 <= mesh_.num_faces()) return false;
    double area = 0, sqrt_sum = 0, m_sum = 0;
    for (size_t f = 0; f < g.tris.size(); ++f) {
      const Face& t = g.tris[f];
      const double a = triangle_area(g.positions[t[0]], g.positions[t[1]], g.positions[t[2]]);
      const auto& G = o_.face_metric[g.faces[f]];
      const double m = std::max(0.5 * (G[0] + G[2]) - 1.0, 0.0);
      area += a;
      sqrt_sum += a * std::sqrt(m);
      m_sum += a * m;
    }
    return m_sum > 0 && area > 0 && sqrt_sum * sqrt_sum / area < o_.signal_split_efficiency * m_sum;
  }

  Atlas assemble(const std::vector<DoneChart>& charts) const {
    Atlas a;
    a.face_chart.assign(mesh_.num_faces(), -1);
    a.face_uvs.assign(mesh_.num_faces(), Face{0, 0, 0});
    for (int c = 0; c < static_cast<int>(charts.size()); ++c) {
      const auto& g = charts[c].geometry;
      const auto& p = charts[c].param;
      const int offset = static_cast<int>(a.uvs.size());
      a.uvs.insert(a.uvs.end(), p.uv.begin(), p.uv.end());
      for (int f = 0; f < g.num_faces(); ++f) {
        const int pf = g.faces[f];
        a.face_chart[pf] = c;
        // Chart triangles keep the parent's corner order, so corner k matches.
        for (int k = 0; k < 3; ++k) a.face_uvs[pf][k] = offset + g.tris[f][k];
      }
      ChartInfo info;
      info.faces = g.num_faces();
      for (const Face& t : g.tris) info.area_3d += triangle_area(g.positions[t[0]], g.positions[t[1]], g.positions[t[2]]);
      info.l2 = p.l2;
      info.linf = p.linf;
      a.charts.push_back(info);
    }
    return a;
  }

  const Mesh& mesh_;
  const AtlasOptions& o_;
  const Progress& progress_;
  Topology topo_;
  std::vector<int> component_vertices_;  // referenced vertices per mesh component
  detail::SplitOptions split_;
  detail::ParamOptions param_;
  StageTimes times_;
  int splits_ = 0;
  int charts_before_merge_ = 0;
  long long accepted_faces_ = 0;
};

}  // namespace

void validate_options(const AtlasOptions& o) {
  auto bad = [](const std::string& m) { throw InputError("", m); };
  if (!(o.max_l2 >= 1.0) || !std::isfinite(o.max_l2)) bad("--max-l2 must be a number >= 1 (1 is an isometry)");
  if (!(o.max_linf >= 1.0) || !std::isfinite(o.max_linf)) bad("--max-linf must be a number >= 1");
  if (o.max_charts < 0) bad("--max-charts must be >= 0");
  if (o.pack_cuts < -1) bad("--pack-cuts must be -1 (automatic), 0 or more");
  if (o.landmarks < 3) bad("--landmarks must be >= 3");
  if (!(o.alpha >= 0 && o.alpha <= 1)) bad("--alpha must be in [0, 1]");
  if (!(o.medial_fraction > 0 && o.medial_fraction < 1)) bad("medial fraction must be in (0, 1)");
  if (!(o.merge_max_fraction >= 0 && o.merge_max_fraction <= 1)) bad("merge fraction must be in [0, 1]");
  if (o.optimize_passes < 0) bad("optimize passes must be >= 0");
  // The packer's own limit: a larger texture passed here and failed after the atlas was built.
  constexpr int kMax = PackOptions::kMaxSize;
  if (o.pack.width < 8 || o.pack.height < 8 || o.pack.width > kMax || o.pack.height > kMax)
    bad("--width and --height must be between 8 and " + std::to_string(kMax) + " texels");
  if (o.pack.gutter < 0 || o.pack.gutter > 64) bad("--gutter must be between 0 and 64 texels");
  if (o.pack.search_size != 0 && (o.pack.search_size < 64 || o.pack.search_size > kMax))
    bad("--pack-grid must be 0 (the texture's own grid) or between 64 and " + std::to_string(kMax));
  if (!(o.max_geometric_l2 >= 1.0) || !std::isfinite(o.max_geometric_l2))
    bad("the geometric L2 bound of a signal atlas must be a number >= 1");
}

Mesh Atlas::apply_to(const Mesh& mesh) const {
  Mesh m = mesh;
  m.uvs = uvs;
  m.face_uvs = face_uvs;
  m.face_groups = face_chart;
  return m;
}

PackResult pack_atlas(const Mesh& mesh, Atlas& atlas, const PackOptions& options, const Progress& progress) {
  // Each chart as its own small mesh for the packer.
  const int nc = atlas.num_charts();
  const std::vector<detail::AtlasChart> split = detail::split_atlas_charts(mesh, atlas);
  std::vector<PackChart> charts(nc);
  for (int c = 0; c < nc; ++c) {
    charts[c].uv = split[c].uv;
    charts[c].faces = split[c].tris;
    for (const Face& t : split[c].tris)
      charts[c].area_3d += triangle_area(split[c].positions[t[0]], split[c].positions[t[1]], split[c].positions[t[2]]);
  }
  PackResult r = pack_charts(charts, options, progress);
  for (int c = 0; c < nc; ++c)
    for (size_t i = 0; i < split[c].uv_ids.size(); ++i) atlas.uvs[split[c].uv_ids[i]] = charts[c].uv[i];

  // Whole-atlas figures, measured on the final texture coordinates in texels (1024×64 in
  // [0,1]²: L2 2.9 where it is 1.05).
  const Mesh m = atlas.apply_to(mesh);
  const StretchStats st = measure_texture_stretch(m, static_cast<double>(options.width) / options.height);
  atlas.stats.charts = nc;
  atlas.stats.l2 = st.l2;
  atlas.stats.linf = st.linf;
  atlas.stats.flipped = st.flipped;
  atlas.stats.overlapping_pairs = static_cast<long long>(overlapping_uv_pairs(m).size());
  atlas.stats.packing_ratio = r.packing_ratio;
  return r;
}

Atlas build_atlas(const Mesh& mesh, const AtlasOptions& options, const Progress& progress) {
  validate_options(options);
  if (mesh.faces.empty()) throw InputError("", "mesh has no faces");
  // A chart holds at least one face; asking for more charts than faces would split every
  // face off and then pack tens of thousands of single-triangle charts.
  if (options.max_charts > mesh.num_faces())
    throw InputError("", "--max-charts " + std::to_string(options.max_charts) + " exceeds the mesh's " +
                             std::to_string(mesh.num_faces()) + " faces");
  if (!options.vertex_signal.empty() &&
      (options.signal_dimension < 1 ||
       options.vertex_signal.size() != static_cast<size_t>(mesh.num_vertices()) * options.signal_dimension))
    throw InputError("", "vertex signal does not match the mesh's " + std::to_string(mesh.num_vertices()) + " vertices");
  if (!options.face_metric.empty() && static_cast<int>(options.face_metric.size()) != mesh.num_faces())
    throw InputError("", "signal metric has " + std::to_string(options.face_metric.size()) +
                             " faces, the mesh has " + std::to_string(mesh.num_faces()));
  Builder b(mesh, options, progress);
  return b.run();
}

}  // namespace isochart
