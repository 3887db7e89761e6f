// Cutting charts whose layout packs poorly (an extension beyond Iso-charts §6).
//
// The packer can only place whole charts; a chart with a long arm or an L shape leaves the
// space between its arms to smaller charts, and with a handful of large charts there are
// none to fill it. Cutting such a chart along a straight line of its own layout keeps its
// UVs (no flip, no overlap, and the stretch changes only by the per-piece renormalization),
// and two near-rectangular pieces pack far better than one L. The proxy for "packs better"
// is the area of the minimal bounding rectangles, which is what the packer's box grows by
// when it cannot interlock charts.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "atlas_charts.h"
#include "isochart/atlas.h"
#include "isochart/baselines.h"
#include "isochart/pack.h"
#include "isochart/stretch.h"
#include "pack_raster.h"

namespace isochart {

using detail::AtlasChart;
using detail::split_atlas_charts;

namespace {

constexpr double kPi = 3.14159265358979323846;
// Cut lines: this many directions over 180°, at these area quantiles along each.
constexpr int kDirections = 16;
constexpr int kQuantiles = 9;
// A piece must hold at least this fraction of its parent's area (smaller ones gain little
// and add a chart).
constexpr double kMinPieceFraction = 0.05;
// Candidate cuts validated (disk, stretch) per piece, best proxy gain first.
constexpr int kCandidates = 4;
// split_and_pack_atlas also packs the cuts whose gain exceeds this many times min_gain.
constexpr double kCoarseGain = 4;

struct ChartData {
  AtlasChart chart;
  Topology topo;
  std::vector<int> sorted_vertices;  // by (u, v): monotone-chain hulls of subsets need no sort
  std::vector<double> area_3d, area_uv;
  std::vector<Vec2d> centroid;
};

// A piece of a chart: chart-local face ids, and its best cut once evaluated.
struct Piece {
  int chart = 0;
  std::vector<int> faces;
  bool evaluated = false;
  double gain = 0;  // rectangle area saved by the best valid cut (3-D area units)
  std::vector<int> part_a, part_b;
  double l2_a = 0, linf_a = 0, l2_b = 0, linf_b = 0;
  double l2 = -1, linf = -1;  // of the piece itself; < 0 while it is an original chart
};

// Scratch per evaluating thread.
struct Scratch {
  std::vector<int> face_mark, rest_mark, vertex_mark, queue, label;
  int stamp = 0;
  std::vector<Vec2d> hull;
  void reset(int faces, int vertices) {
    if (static_cast<int>(face_mark.size()) < faces) {
      face_mark.assign(faces, 0);
      rest_mark.assign(faces, 0);
      label.assign(faces, 0);
    }
    if (static_cast<int>(vertex_mark.size()) < vertices) vertex_mark.assign(vertices, 0);
  }
  int next() { return ++stamp; }
};

// Area of the minimal-area bounding rectangle of the vertices of `faces` (chart UV units). The
// hull is built here from the chart's presorted vertices rather than by convex_hull, which
// would sort again for each of the hundreds of candidate pieces.
double rect_area(const ChartData& d, const std::vector<int>& faces, Scratch& s) {
  const int st = s.next();
  for (const int f : faces)
    for (const int v : d.chart.tris[f]) s.vertex_mark[v] = st;
  std::vector<Vec2d>& h = s.hull;
  h.clear();
  // Andrew's monotone chain over the presorted vertices.
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t start = h.size();
    const int n = static_cast<int>(d.sorted_vertices.size());
    for (int i = 0; i < n; ++i) {
      const int v = d.sorted_vertices[pass == 0 ? i : n - 1 - i];
      if (s.vertex_mark[v] != st) continue;
      const Vec2d& p = d.chart.uv[v];
      while (h.size() >= start + 2 && cross(h.back() - h[h.size() - 2], p - h[h.size() - 2]) <= 0) h.pop_back();
      h.push_back(p);
    }
    h.pop_back();  // the last point of each chain starts the other
  }
  if (h.size() < 3) return 0;
  return pack_detail::min_area_rect(h).area;
}

struct Sums {
  double a3 = 0, auv = 0;
};
Sums sums(const ChartData& d, const std::vector<int>& faces) {
  Sums s;
  for (const int f : faces) {
    s.a3 += d.area_3d[f];
    s.auv += d.area_uv[f];
  }
  return s;
}

// Rectangle area in the packer's units (the piece scaled so its UV area is its 3-D area).
double packed_rect(const ChartData& d, const std::vector<int>& faces, Scratch& s) {
  const Sums a = sums(d, faces);
  return a.auv > 0 ? rect_area(d, faces, s) * a.a3 / a.auv : std::numeric_limits<double>::infinity();
}

// Faces of `faces` reachable from `seed` through edges, staying among faces with label
// `want` in s.label. Marks them in `marks` with `mark`.
void grow(const ChartData& d, int seed, int want, std::vector<int>& marks, int mark, Scratch& s,
          std::vector<int>& out) {
  out.clear();
  s.queue.clear();
  s.queue.push_back(seed);
  marks[seed] = mark;
  for (std::size_t i = 0; i < s.queue.size(); ++i) {
    const int f = s.queue[i];
    out.push_back(f);
    for (int k = 0; k < 3; ++k) {
      const int g = d.topo.opposite_face(f, k);
      if (g >= 0 && s.label[g] == want && marks[g] != mark) {
        marks[g] = mark;
        s.queue.push_back(g);
      }
    }
  }
}

bool disk(const ChartData& d, const std::vector<int>& faces) {
  Mesh m;
  m.positions = d.chart.positions;
  m.faces.reserve(faces.size());
  for (const int f : faces) m.faces.push_back(d.chart.tris[f]);
  std::vector<int> all(faces.size());
  std::iota(all.begin(), all.end(), 0);
  return is_disk(m, all);
}

StretchStats piece_stretch(const ChartData& d, const std::vector<int>& faces) {
  std::vector<Face> tris;
  tris.reserve(faces.size());
  for (const int f : faces) tris.push_back(d.chart.tris[f]);
  return measure_stretch(d.chart.positions, tris, d.chart.uv);
}

struct Cut {
  double gain = 0;
  std::vector<int> a, b;
};

// A straight cut through triangles leaves a saw-tooth boundary: triangles with two of their
// three neighbours across it. They change sides (all at once per pass, so the result does
// not depend on an order), which shortens the seam; the pieces are re-checked afterwards.
void smooth_cut(const ChartData& d, Cut& c, Scratch& s) {
  for (const int f : c.a) s.label[f] = 1;
  for (const int f : c.b) s.label[f] = 2;
  std::vector<int> all = c.a;
  all.insert(all.end(), c.b.begin(), c.b.end());
  std::sort(all.begin(), all.end());
  std::vector<int> flip;
  for (int pass = 0; pass < 3; ++pass) {
    flip.clear();
    for (const int f : all) {
      int across = 0;
      for (int k = 0; k < 3; ++k) {
        const int g = d.topo.opposite_face(f, k);
        across += g >= 0 && s.label[g] != 0 && s.label[g] != s.label[f];
      }
      if (across >= 2) flip.push_back(f);
    }
    if (flip.empty()) break;
    for (const int f : flip) s.label[f] = 3 - s.label[f];
  }
  c.a.clear();
  c.b.clear();
  for (const int f : all) (s.label[f] == 1 ? c.a : c.b).push_back(f);
  for (const int f : all) s.label[f] = 0;
}

// Finds the best valid straight cut of a piece (sets gain 0 when there is none).
void evaluate(const ChartData& d, Piece& p, const PackSplitOptions& o, Scratch& s) {
  p.evaluated = true;
  p.gain = 0;
  const int m = static_cast<int>(p.faces.size());
  if (m < 8) return;
  s.reset(static_cast<int>(d.chart.tris.size()), static_cast<int>(d.chart.uv.size()));
  const Sums total = sums(d, p.faces);
  if (!(total.a3 > 0) || !(total.auv > 0)) return;
  const double r0 = packed_rect(d, p.faces, s);

  std::vector<Cut> best;  // the kCandidates largest gains, descending
  auto offer = [&](double gain, const std::vector<int>& a, const std::vector<int>& b) {
    if (!(gain > 0)) return;
    if (static_cast<int>(best.size()) == kCandidates && gain <= best.back().gain) return;
    Cut c{gain, a, b};
    auto at = std::find_if(best.begin(), best.end(), [&](const Cut& x) { return gain > x.gain; });
    best.insert(at, std::move(c));
    if (static_cast<int>(best.size()) > kCandidates) best.pop_back();
  };

  std::vector<int> order(m);
  std::vector<double> proj(m);
  std::vector<int> comp, rest;
  for (int k = 0; k < kDirections; ++k) {
    const double a = kPi * k / kDirections;
    const Vec2d n{std::cos(a), std::sin(a)};
    for (int i = 0; i < m; ++i) {
      const Vec2d& c = d.centroid[p.faces[i]];
      proj[i] = c.x * n.x + c.y * n.y;
    }
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](int x, int y) { return proj[x] < proj[y] || (proj[x] == proj[y] && x < y); });
    int pos = 0;
    double cum = 0;
    for (int q = 1; q <= kQuantiles; ++q) {
      const double target = total.a3 * q / (kQuantiles + 1);
      while (pos < m && cum < target) cum += d.area_3d[p.faces[order[pos++]]];
      if (pos <= 0 || pos >= m) continue;
      // Label: 1 below the line, 2 above; faces outside the piece keep 0.
      for (int i = 0; i < m; ++i) s.label[p.faces[order[i]]] = i < pos ? 1 : 2;
      const int seen = s.next();
      for (int i = 0; i < m; ++i) {
        const int f = p.faces[i];
        if (s.face_mark[f] == seen) continue;
        const int side = s.label[f];
        grow(d, f, side, s.face_mark, seen, s, comp);
        const Sums cs = sums(d, comp);
        if (cs.a3 < kMinPieceFraction * total.a3 || cs.a3 > (1 - kMinPieceFraction) * total.a3) continue;
        // The rest must be one piece: label the component 3, the rest 4, and grow the rest.
        for (const int g : comp) s.label[g] = 3;
        int seed = -1;
        for (int j = 0; j < m && seed < 0; ++j)
          if (s.label[p.faces[j]] != 3) seed = p.faces[j];
        for (int j = 0; j < m; ++j)
          if (s.label[p.faces[j]] != 3) s.label[p.faces[j]] = 4;
        const int rs = s.next();
        grow(d, seed, 4, s.rest_mark, rs, s, rest);
        if (static_cast<int>(rest.size()) + static_cast<int>(comp.size()) == m) {
          const double r = packed_rect(d, comp, s) + packed_rect(d, rest, s);
          offer(r0 - r, comp, rest);
        }
        // Restore the labels for the remaining components of this cut.
        for (int j = 0; j < m; ++j) s.label[p.faces[order[j]]] = j < pos ? 1 : 2;
      }
    }
  }
  for (int j = 0; j < m; ++j) s.label[p.faces[j]] = 0;

  for (Cut& c : best) {
    Cut smooth = c;
    smooth_cut(d, smooth, s);
    if (!smooth.a.empty() && !smooth.b.empty() && disk(d, smooth.a) && disk(d, smooth.b)) {
      smooth.gain = c.gain;
      c = std::move(smooth);
    } else if (!disk(d, c.a) || !disk(d, c.b)) {
      continue;
    }
    const StretchStats sa = piece_stretch(d, c.a), sb = piece_stretch(d, c.b);
    if (sa.flipped || sb.flipped || !(sa.l2 <= o.max_l2) || !(sb.l2 <= o.max_l2) ||
        !(sa.linf <= o.max_linf) || !(sb.linf <= o.max_linf))
      continue;
    p.gain = c.gain;
    p.part_a = std::move(c.a);
    p.part_b = std::move(c.b);
    p.l2_a = sa.l2;
    p.linf_a = sa.linf;
    p.l2_b = sb.l2;
    p.linf_b = sb.linf;
    return;
  }
}

}  // namespace

PackSplitResult split_charts_for_packing(const Mesh& mesh, Atlas& atlas, const PackSplitOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  PackSplitResult result;
  const int nc = atlas.num_charts();
  const int budget =
      options.max_added >= 0 ? options.max_added : std::min(nc, std::max(0, options.target_charts - nc));
  if (nc == 0 || budget == 0) return result;
  std::vector<ChartData> data(nc);
  {
    std::vector<AtlasChart> split = split_atlas_charts(mesh, atlas);
    tbb::parallel_for(0, nc, [&](int c) {
      ChartData& d = data[c];
      d.chart = std::move(split[c]);
      const AtlasChart& ch = d.chart;
      d.topo = Topology(ch.tris, static_cast<int>(ch.uv.size()));
      d.sorted_vertices.resize(ch.uv.size());
      std::iota(d.sorted_vertices.begin(), d.sorted_vertices.end(), 0);
      std::sort(d.sorted_vertices.begin(), d.sorted_vertices.end(), [&](int a, int b) {
        const Vec2d &p = ch.uv[a], &q = ch.uv[b];
        return p.x < q.x || (p.x == q.x && (p.y < q.y || (p.y == q.y && a < b)));
      });
      const int nf = static_cast<int>(ch.tris.size());
      d.area_3d.resize(nf);
      d.area_uv.resize(nf);
      d.centroid.resize(nf);
      for (int f = 0; f < nf; ++f) {
        const Face& t = ch.tris[f];
        d.area_3d[f] = triangle_area(ch.positions[t[0]], ch.positions[t[1]], ch.positions[t[2]]);
        d.area_uv[f] = std::abs(signed_area(ch.uv[t[0]], ch.uv[t[1]], ch.uv[t[2]]));
        d.centroid[f] = (ch.uv[t[0]] + ch.uv[t[1]] + ch.uv[t[2]]) * (1.0 / 3);
      }
    });
  }
  std::vector<Piece> pieces(nc);
  double total_area = 0;
  for (int c = 0; c < nc; ++c) {
    pieces[c].chart = c;
    pieces[c].faces.resize(data[c].chart.tris.size());
    std::iota(pieces[c].faces.begin(), pieces[c].faces.end(), 0);
    total_area += sums(data[c], pieces[c].faces).a3;
  }
  auto evaluate_pending = [&]() {
    std::vector<int> todo;
    for (int i = 0; i < static_cast<int>(pieces.size()); ++i)
      if (!pieces[i].evaluated) todo.push_back(i);
    tbb::parallel_for(0, static_cast<int>(todo.size()), [&](int j) {
      Scratch s;
      Piece& p = pieces[todo[j]];
      evaluate(data[p.chart], p, options, s);
    });
  };
  auto rect_fill = [&]() {
    double rect = 0;
    Scratch s;
    for (const Piece& p : pieces) {
      s.reset(static_cast<int>(data[p.chart].chart.tris.size()),
              static_cast<int>(data[p.chart].chart.uv.size()));
      rect += packed_rect(data[p.chart], p.faces, s);
    }
    return rect > 0 ? total_area / rect : 0;
  };
  result.rect_fill_before = rect_fill();

  while (result.added < budget) {
    evaluate_pending();
    int pick = -1;
    for (int i = 0; i < static_cast<int>(pieces.size()); ++i)
      if (pieces[i].gain > 0 && (pick < 0 || pieces[i].gain > pieces[pick].gain)) pick = i;
    if (pick < 0 || pieces[pick].gain < options.min_gain * total_area) break;
    Piece& p = pieces[pick];
    Piece b;
    b.chart = p.chart;
    b.faces = std::move(p.part_b);
    b.l2 = p.l2_b;
    b.linf = p.linf_b;
    p.faces = std::move(p.part_a);
    p.l2 = p.l2_a;
    p.linf = p.linf_a;
    p.evaluated = false;
    p.gain = 0;
    p.part_a.clear();
    pieces.push_back(std::move(b));
    ++result.added;
  }
  result.rect_fill_after = rect_fill();

  if (result.added > 0) {
    // Stable order, as the atlas driver's: by smallest mesh face id.
    std::vector<int> first(pieces.size());
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      int lo = std::numeric_limits<int>::max();
      for (const int f : pieces[i].faces) lo = std::min(lo, data[pieces[i].chart].chart.faces[f]);
      first[i] = lo;
    }
    std::vector<int> order(pieces.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return first[a] < first[b]; });

    std::vector<Vec2d> uvs;
    std::vector<ChartInfo> infos;
    std::vector<int> local_id;
    for (int id = 0; id < static_cast<int>(order.size()); ++id) {
      const Piece& p = pieces[order[id]];
      const ChartData& d = data[p.chart];
      local_id.assign(d.chart.uv.size(), -1);
      ChartInfo info = atlas.charts[p.chart];
      info.faces = static_cast<int>(p.faces.size());
      info.area_3d = 0;
      for (const int f : p.faces) {
        const int mf = d.chart.faces[f];
        atlas.face_chart[mf] = id;
        info.area_3d += d.area_3d[f];
        for (int k = 0; k < 3; ++k) {
          const int v = d.chart.tris[f][k];
          if (local_id[v] < 0) {
            local_id[v] = static_cast<int>(uvs.size());
            uvs.push_back(d.chart.uv[v]);
          }
          atlas.face_uvs[mf][k] = local_id[v];
        }
      }
      if (p.l2 >= 0) {
        info.l2 = p.l2;
        info.linf = p.linf;
      }
      infos.push_back(info);
    }
    atlas.uvs = std::move(uvs);
    atlas.charts = std::move(infos);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

PackResult split_and_pack_atlas(const Mesh& mesh, Atlas& atlas, const PackOptions& pack,
                                const PackSplitOptions& options, const Progress& progress,
                                PackSplitResult* split) {
  const auto t0 = std::chrono::steady_clock::now();
  // Two cut levels, the coarse one a prefix of the fine one (the same greedy sequence,
  // stopped at a higher gain): which packs best is not predictable, so both are packed.
  const int nc = atlas.num_charts();
  const int budget =
      options.max_added >= 0 ? options.max_added : std::min(nc, std::max(0, options.target_charts - nc));
  PackSplitOptions coarse = options;
  coarse.max_added = budget;
  coarse.min_gain = options.min_gain * kCoarseGain;
  if (budget == 0) {
    PackResult r = pack_atlas(mesh, atlas, pack, progress);
    if (split) *split = PackSplitResult{0, r.seconds, 0, 0};
    return r;
  }
  Atlas cut1 = atlas;
  PackSplitResult s1 = split_charts_for_packing(mesh, cut1, coarse);
  PackSplitOptions fine = options;
  fine.max_added = budget - s1.added;
  Atlas cut2 = cut1;
  const PackSplitResult s2 = split_charts_for_packing(mesh, cut2, fine);
  PackSplitResult sr = s1;
  sr.added = s1.added + s2.added;
  sr.rect_fill_after = s2.added > 0 ? s2.rect_fill_after : s1.rect_fill_after;

  PackResult result = pack_atlas(mesh, atlas, pack, progress);
  int kept = 0;
  if (s1.added > 0) {
    PackResult r = pack_atlas(mesh, cut1, pack, progress);
    if (r.packing_ratio > result.packing_ratio) {
      atlas = cut1;
      result = std::move(r);
      kept = s1.added;
    }
  }
  if (s2.added > 0) {
    PackResult r = pack_atlas(mesh, cut2, pack, progress);
    if (r.packing_ratio > result.packing_ratio) {
      atlas = std::move(cut2);
      result = std::move(r);
      kept = s1.added + s2.added;
    }
  }
  sr.added = kept;
  sr.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result.seconds = sr.seconds;
  if (split) *split = sr;
  return result;
}

}  // namespace isochart
