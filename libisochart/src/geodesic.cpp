#include "isochart/geodesic.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "isochart/error.h"

namespace isochart {

namespace {

using Wedge = detail::GeodesicWedge;

// Unfoldings tried per obtuse corner before giving up; a well-shaped strip finds its vertex
// within two or three.
constexpr int kMaxUnfoldings = 12;

// Corners more obtuse than this (cosine; about 95.7°) are split by unfolding. Nearly right
// corners, common in scanned meshes, gained nothing measurable against CGAL's exact distances
// (torus 0.35% vs 0.38% mean error, bumpy patch 0.066% vs 0.069%) but cost a fifth of the run
// time on the bunny (9514 corners split instead of 2027).
constexpr double kSplitCosine = -0.1;

// A triangle whose unfolded height is below this fraction of its base gives no direction
// information and only amplifies rounding, so it takes part in edge updates only.
constexpr double kMinRelativeHeight = 1e-9;

// Relative tolerance of the "update comes from inside the triangle" test.
constexpr double kInsideSlack = 1e-9;

// Vertex states during a run.
constexpr std::uint8_t kFar = 0, kFront = 1, kFrozen = 2;

// Per-thread scratch for one fast-marching run.
//
// The front is a radix heap (Ahuja et al. 1990) over the bit patterns of the non-negative
// double keys, which order like the numbers: an entry lives in the bucket of the highest bit
// in which its key differs from the last popped key, so a push is an append and a pop rescans
// one bucket. Popped keys never decrease, which a Dijkstra-ordered front guarantees except for
// the rare triangle update landing below its own inputs; those are queued at the current key
// (their distance is kept). There is no decrease-key: a lowered vertex is pushed again and its
// later entries are dropped because it is frozen by then. On the bunny it was about 10% faster
// than an indexed 4-ary heap (whose sift-downs dominated the profile), and 15% more once the
// first non-empty bucket came from a bit mask instead of a scan.
struct Scratch {
  struct Entry {
    std::uint64_t key;
    int v;
  };
  std::vector<std::uint8_t> state;  // kFar, kFront or kFrozen per vertex
  std::vector<int> label;           // source index per reached vertex, for runs from several sources
  // Bucket i ≥ 1 holds keys whose highest bit differing from `last` is bit i − 1; bucket 0
  // holds keys equal to it. Keys are non-negative doubles, so bit 63 never differs: 64 buckets.
  std::vector<Entry> buckets[64];
  std::uint64_t occupied = 0;  // bit i set when bucket i is not empty
  std::uint64_t last = 0;
  std::size_t size = 0;

  static std::uint64_t bits(double key) {
    std::uint64_t b;
    std::memcpy(&b, &key, sizeof b);
    return b;
  }
  // Written without branches: which bucket a key falls in is what the hardware cannot predict.
  int bucket_of(std::uint64_t key) const { return 63 - __builtin_clzll(((key ^ last) << 1) | 1); }
  void put(const Entry& e) {
    const int b = bucket_of(e.key);
    buckets[b].push_back(e);
    occupied |= std::uint64_t{1} << b;
  }

  void reset(int n) {
    state.assign(static_cast<std::size_t>(n), kFar);
    for (auto& b : buckets) b.clear();
    occupied = 0;
    last = 0;
    size = 0;
  }
  bool empty() const { return size == 0; }
  void push(int v, double distance) {
    put({std::max(bits(distance), last), v});
    ++size;
  }
  int pop() {
    if (buckets[0].empty()) {
      const int i = __builtin_ctzll(occupied & ~std::uint64_t{1});
      occupied &= ~(std::uint64_t{1} << i);
      std::vector<Entry>& b = buckets[i];
      std::uint64_t least = b.front().key;
      for (const Entry& e : b) least -= (least - e.key) & (std::uint64_t{0} - (e.key < least));
      last = least;
      for (const Entry& e : b) put(e);  // each lands in a lower bucket
      b.clear();
    }
    const int v = buckets[0].back().v;
    buckets[0].pop_back();
    if (buckets[0].empty()) occupied &= ~std::uint64_t{1};
    --size;
    return v;
  }
};

Scratch& thread_scratch() {
  thread_local Scratch s;
  return s;
}

struct P2 {
  double x, y;
};
inline P2 sub(P2 a, P2 b) {
  return {a.x - b.x, a.y - b.y};
}
inline double dot2(P2 a, P2 b) {
  return a.x * b.x + a.y * b.y;
}
inline double cross2(P2 a, P2 b) {
  return a.x * b.y - a.y * b.x;
}

// The point at distances l1 from p1 and l2 from p2, on the other side of line p1p2 than `away`.
// Returns false when the edge is degenerate or the side cannot be told.
bool unfold_point(P2 p1, P2 p2, double l1, double l2, P2 away, P2& out) {
  const P2 e = sub(p2, p1);
  const double len = std::sqrt(dot2(e, e));
  if (!(len > 0)) return false;
  const P2 u{e.x / len, e.y / len};
  const P2 n{-u.y, u.x};
  const double a = (l1 * l1 - l2 * l2 + len * len) / (2 * len);
  const double h = std::sqrt(std::max(0.0, l1 * l1 - a * a));
  const double side = dot2(sub(away, p1), n);
  if (side == 0) return false;
  const double s = side > 0 ? -h : h;
  out = {p1.x + a * u.x + s * n.x, p1.y + a * u.y + s * n.y};
  return true;
}

// `target` in the frame of a triangle update seen from x: x at the origin, `other` on the +x
// axis, target below it. cy = 0 (disabled) when the triangle is too flat to give a direction.
struct Frame {
  float cx = 0, cy = 0;
};
Frame make_frame(P2 x, P2 other, P2 target) {
  const P2 e = sub(other, x);
  const double len = std::sqrt(dot2(e, e));
  if (!(len > 0)) return Frame{};
  const P2 u{e.x / len, e.y / len};
  const P2 n{-u.y, u.x};
  const P2 r = sub(target, x);
  const double cy = -std::abs(dot2(r, n));
  if (-cy <= kMinRelativeHeight * len) return Frame{};
  return Frame{static_cast<float>(dot2(r, u)), static_cast<float>(cy)};
}

// Distance at C (frame: X = (0,0), Y = (c,0), C = (cx,cy), cy < 0) from the virtual point source
// at distance dx from X and dy from Y on the far side of XY. +inf when the circles do not meet
// or the source's ray to C misses the segment XY (the update would come from outside).
inline double triangle_update(double dx, double dy, double c, double cx, double cy) {
  if (!(cy < 0)) return GeodesicSolver::inf;  // a disabled frame
  const double sx = ((dx - dy) * (dx + dy) + c * c) / (2 * c);
  const double sy2 = (dx - sx) * (dx + sx);
  if (sy2 < 0) return GeodesicSolver::inf;
  const double sy = std::sqrt(sy2);
  // The ray S→C meets the x axis at x = (cx·sy − sx·cy) / (sy − cy); sy − cy > 0. The slack
  // keeps rays through X or Y themselves (a grid diagonal, or a split triangle whose virtual
  // vertex is the source) from being lost to rounding.
  const double num = cx * sy - sx * cy;
  const double span = c * (sy - cy);
  if (num < -kInsideSlack * span || num > (1 + kInsideSlack) * span) return GeodesicSolver::inf;
  const double ex = cx - sx, ey = cy - sy;
  return std::sqrt(ex * ex + ey * ey);
}

// Edge update along a wedge length (disabled when negative).
inline double edge_update(double dx, float len) {
  return std::signbit(len) ? GeodesicSolver::inf : dx + len;
}

}  // namespace

GeodesicSolver::GeodesicSolver(const std::vector<Vec3d>& positions, const std::vector<Face>& faces)
    : positions_(positions) {
  const int nv = static_cast<int>(positions.size());
  const int nf = static_cast<int>(faces.size());
  for (int v = 0; v < nv; ++v)
    if (!is_finite(positions[v]))
      throw InputError("", "geodesics: vertex " + std::to_string(v) + " has a non-finite position");
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      if (faces[f][k] < 0 || faces[f][k] >= nv)
        throw InputError("", "geodesics: face " + std::to_string(f) + " references vertex " +
                                 std::to_string(faces[f][k]) + ", but there are " + std::to_string(nv) +
                                 " vertices");

  auto valid_face = [&](int f) {
    const Face& t = faces[f];
    return t[0] != t[1] && t[1] != t[2] && t[2] != t[0];
  };

  // Vertex → faces (CSR), for the neighbour lookups of unfolding.
  std::vector<int> vf_off(nv + 1, 0), vf;
  for (int f = 0; f < nf; ++f)
    if (valid_face(f))
      for (int k = 0; k < 3; ++k) ++vf_off[faces[f][k] + 1];
  for (int v = 0; v < nv; ++v) vf_off[v + 1] += vf_off[v];
  vf.resize(vf_off[nv]);
  {
    std::vector<int> fill(vf_off.begin(), vf_off.end() - 1);
    for (int f = 0; f < nf; ++f)
      if (valid_face(f))
        for (int k = 0; k < 3; ++k) vf[fill[faces[f][k]]++] = f;
  }

  auto length = [&](int a, int b) { return norm(positions[a] - positions[b]); };

  // The face across edge (a, b) from face f, or -1 on a boundary or non-manifold edge.
  auto across = [&](int f, int a, int b) {
    int found = -1;
    for (int i = vf_off[a]; i < vf_off[a + 1]; ++i) {
      const int g = vf[i];
      if (g == f) continue;
      const Face& t = faces[g];
      if (t[0] == b || t[1] == b || t[2] == b) {
        if (found >= 0) return -1;
        found = g;
      }
    }
    return found;
  };

  // Wedges gathered as (owner, wedge), then bucketed by owner.
  std::vector<std::pair<int, Wedge>> recs;
  recs.reserve(static_cast<std::size_t>(nf) * 3);
  // A virtual triangle (C, P, Q) only updates C: one wedge at P and one at Q.
  auto add_virtual = [&](int c, int p, int q, P2 pc, P2 pp, P2 pq) {
    const float len = -static_cast<float>(std::sqrt(dot2(sub(pq, pp), sub(pq, pp))));
    const Frame at_p = make_frame(pp, pq, pc), at_q = make_frame(pq, pp, pc);
    recs.push_back({p, Wedge{c, q, -0.0f, len, at_p.cx, at_p.cy, 0, 0}});
    recs.push_back({q, Wedge{c, p, -0.0f, len, at_q.cx, at_q.cy, 0, 0}});
  };

  for (int f = 0; f < nf; ++f) {
    if (!valid_face(f)) continue;
    // The triangle laid out in its plane, corner k at p[k].
    const Face& t = faces[f];
    const double l01 = length(t[0], t[1]), l02 = length(t[0], t[2]), l12 = length(t[1], t[2]);
    P2 p[3] = {{0, 0}, {l01, 0}, {0, 0}};
    if (l01 > 0) {
      const double x = (l01 * l01 + l02 * l02 - l12 * l12) / (2 * l01);
      p[2] = {x, std::sqrt(std::max(0.0, l02 * l02 - x * x))};
    }
    for (int k = 0; k < 3; ++k) {
      const int y = (k + 1) % 3, z = (k + 2) % 3;
      const Frame fy = make_frame(p[k], p[z], p[y]), fz = make_frame(p[k], p[y], p[z]);
      recs.push_back({t[k], Wedge{t[y], t[z], static_cast<float>(length(t[k], t[y])),
                                  static_cast<float>(length(t[k], t[z])), fy.cx, fy.cy, fz.cx, fz.cy}});
    }
    for (int k = 0; k < 3; ++k) {
      const int c = t[k], a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      const P2 pc = p[k], pa = sub(p[(k + 1) % 3], pc), pb = sub(p[(k + 2) % 3], pc);
      if (!(dot2(pa, pa) > 0 && dot2(pb, pb) > 0) ||
          dot2(pa, pb) >= kSplitCosine * std::sqrt(dot2(pa, pa) * dot2(pb, pb)))
        continue;
      // Obtuse at C: walk the strip of triangles that the acute section of the angle (the
      // directions within 90° of both CA and CB) crosses, until a vertex falls inside it.
      // Coordinates are relative to C from here on.
      const P2 origin{0, 0};
      int p1 = a, p2 = b, g = f;
      P2 q1 = pa, q2 = pb, prev = origin;
      bool split = false;
      for (int step = 0; step < kMaxUnfoldings; ++step) {
        const int h = across(g, p1, p2);
        if (h < 0) break;
        const Face& th = faces[h];
        const int v = th[0] != p1 && th[0] != p2 ? th[0] : (th[1] != p1 && th[1] != p2 ? th[1] : th[2]);
        if (v == c) break;
        P2 pv;
        if (!unfold_point(q1, q2, length(v, p1), length(v, p2), prev, pv)) break;
        const bool within_a = dot2(pv, pa) > 0;  // angle(CA, CV) < 90°
        const bool within_b = dot2(pv, pb) > 0;  // angle(CV, CB) < 90°
        if (within_a && within_b) {
          add_virtual(c, a, v, origin, pa, pv);
          add_virtual(c, v, b, origin, pv, pb);
          split = true;
          break;
        }
        if (!within_b) {  // V lies on A's side of the section: continue across (V, p2)
          if (cross2(pv, q2) <= 0) break;
          prev = q1;
          p1 = v;
          q1 = pv;
        } else {  // V lies on B's side: continue across (p1, V)
          if (cross2(q1, pv) <= 0) break;
          prev = q2;
          p2 = v;
          q2 = pv;
        }
        g = h;
      }
      // The obtuse triangle's own update stays: it is exact on a plane whenever it applies, and
      // on a curved torus the virtual triangles alone measured twice its error.
      ++(split ? split_obtuse_ : unsplit_obtuse_);
    }
  }

  wedge_offsets_.assign(nv + 1, 0);
  for (const auto& r : recs) ++wedge_offsets_[r.first + 1];
  for (int v = 0; v < nv; ++v) wedge_offsets_[v + 1] += wedge_offsets_[v];
  wedges_.resize(recs.size());
  {
    std::vector<int> fill(wedge_offsets_.begin(), wedge_offsets_.end() - 1);
    for (const auto& r : recs) wedges_[fill[r.first]++] = r.second;
  }
  // An interior edge belongs to two triangles; its edge update is kept in the first only.
  std::vector<int> seen;
  for (int v = 0; v < nv; ++v) {
    seen.clear();
    for (int i = wedge_offsets_[v]; i < wedge_offsets_[v + 1]; ++i) {
      Wedge& w = wedges_[i];
      for (auto [target, len] : {std::pair<int, float*>{w.y, &w.xy}, std::pair<int, float*>{w.z, &w.xz}}) {
        if (std::signbit(*len)) continue;
        if (std::find(seen.begin(), seen.end(), target) != seen.end())
          *len = -*len;
        else
          seen.push_back(target);
      }
    }
  }
}

template <bool kSeveralSources>
void GeodesicSolver::march(const int* sources, int num_sources, double* d, double max_distance,
                           int* accepted) const {
  Scratch& s = thread_scratch();
  const int nv = num_vertices();
  s.reset(nv);
  // With several sources each vertex remembers the source whose front reached it, and a
  // triangle update only combines two vertices of one front: the virtual source of a
  // triangle whose corners were reached from different sources lies nowhere, and its value
  // undercuts the true distance along the bisector.
  int* label = nullptr;
  if (kSeveralSources) {
    s.label.resize(static_cast<std::size_t>(nv));
    label = s.label.data();
  }
  for (int i = 0; i < num_sources; ++i) {
    const int v = sources[i];
    if (v < 0 || v >= nv)
      throw Error("geodesics: source " + std::to_string(v) + " is not a vertex (there are " +
                  std::to_string(nv) + ")");
    d[v] = 0;
    if (kSeveralSources) label[v] = i;
    s.push(v, 0);
  }
  int count = 0;
  std::uint8_t* state = s.state.data();
  const Wedge* wedges = wedges_.data();
  const int* offsets = wedge_offsets_.data();
  auto relax = [&](int c, double cand, int from) {
    if (cand < d[c] && cand <= max_distance) {
      // A run is bound by the scattered reads of wedges, not by arithmetic: fetch those of a
      // vertex when it joins the front, so they are in cache by the time it is accepted.
      if (state[c] == kFar) {
        state[c] = kFront;
        const char* p0 = reinterpret_cast<const char*>(wedges + offsets[c]);
        const char* p1 = reinterpret_cast<const char*>(wedges + offsets[c + 1]);
        for (const char* p = p0; p < p1; p += 64) __builtin_prefetch(p, 0, 2);
      }
      d[c] = cand;
      if (kSeveralSources) label[c] = label[from];
      s.push(c, cand);
    }
  };
  while (!s.empty()) {
    const int x = s.pop();
    if (state[x] == kFrozen) continue;  // a later entry of a vertex lowered after it was queued
    state[x] = kFrozen;
    ++count;
    const double dx = d[x];
    for (int i = offsets[x], e = offsets[x + 1]; i < e; ++i) {
      const Wedge& w = wedges[i];
      const bool fy = state[w.y] == kFrozen, fz = state[w.z] == kFrozen;
      if (fy && fz) continue;
      if (!fy) {
        double cand = edge_update(dx, w.xy);
        if (fz && (!kSeveralSources || label[w.z] == label[x]))
          cand = std::min(cand, triangle_update(dx, d[w.z], std::abs(w.xz), w.fy_cx, w.fy_cy));
        relax(w.y, cand, x);
      }
      if (!fz) {
        double cand = edge_update(dx, w.xz);
        if (fy && (!kSeveralSources || label[w.y] == label[x]))
          cand = std::min(cand, triangle_update(dx, d[w.y], std::abs(w.xy), w.fz_cx, w.fz_cy));
        relax(w.z, cand, x);
      }
    }
  }
  if (accepted) *accepted = count;
}

void GeodesicSolver::distances(const std::vector<int>& sources, std::vector<double>& out,
                               double max_distance) const {
  out.resize(positions_.size());
  distances(sources.data(), static_cast<int>(sources.size()), out.data(), max_distance);
}

void GeodesicSolver::distances(const int* sources, int num_sources, double* out, double max_distance) const {
  std::fill(out, out + num_vertices(), inf);
  if (num_sources > 1)
    march<true>(sources, num_sources, out, max_distance, nullptr);
  else
    march<false>(sources, num_sources, out, max_distance, nullptr);
}

std::vector<double> GeodesicSolver::distance_rows(const std::vector<int>& sources) const {
  const std::size_t nv = positions_.size();
  std::vector<double> rows(sources.size() * nv);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sources.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        distances(&sources[i], 1, rows.data() + i * nv);
                    });
  return rows;
}

int GeodesicSolver::lower_distances(int source, std::vector<double>& field) const {
  if (field.size() != positions_.size())
    throw Error("geodesics: lower_distances needs a field of " + std::to_string(positions_.size()) +
                " values, got " + std::to_string(field.size()));
  int count = 0;
  march<false>(&source, 1, field.data(), inf, &count);
  return count;
}

}  // namespace isochart
