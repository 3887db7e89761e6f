#include "sampling.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <string>

#include "isochart/error.h"
#include "isochart/union_find.h"

namespace mcgim::detail {

namespace {

using isochart::Error;
using isochart::InputError;

// Texel coordinates are snapped to 1/4096 texel so that inside tests are exact integer
// arithmetic: with images up to 16384 texels, coordinates stay below 2^26 and orientation
// products below 2^55.
constexpr double kFixed = 4096.0;
constexpr std::int64_t kHalf = 2048;

// A bridge sample or touched texel spans a crack when a grid neighbour lies farther on the
// surface than this many times the length the offset has under the chart's map at either
// sample (see the neck retry in sample_charts). Measured on bridges: 0.9-1.9 across shallow notches
// (armadillo, skull, gargoyle, plane_holes), 2.1-23 across cracks; 3 gave the highest PSNR on gargoyle.
constexpr double kTornBridge = 3.0;

struct FixedPoint {
  std::int64_t x, y;
};

FixedPoint to_fixed(const Vec2d& p) {
  return {static_cast<std::int64_t>(std::llround(p.x * kFixed)),
          static_cast<std::int64_t>(std::llround(p.y * kFixed))};
}

std::int64_t orient(const FixedPoint& a, const FixedPoint& b, const FixedPoint& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// A covered sample of one chart.
struct Hit {
  int sample;
  int local_face;
  Vec3d bary;  // in the face's corner order
};

// Rasterizes one chart: a sample belongs to a triangle when its centre is strictly inside, or
// on its boundary and inside after the symbolic shift (ε, ε²), ε → 0+. The shift puts every
// point in the interior of exactly one triangle of a partition, so centres on shared edges
// and vertices are counted once. Triangles flipped relative to the chart (folds) are skipped;
// where triangles of one chart overlap, the first face wins.
std::vector<Hit> rasterize_chart(const Chart& ch, const std::vector<Vec2d>& texel, bool mirrored,
                                 int width, int height, bool want_bary) {
  const std::int64_t s = mirrored ? -1 : 1;
  Vec2d lo{1e300, 1e300}, hi{-1e300, -1e300};
  for (const Vec2d& p : texel) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y)};
  }
  const int x0 = std::max(0, static_cast<int>(std::floor(lo.x - 0.5)));
  const int y0 = std::max(0, static_cast<int>(std::floor(lo.y - 0.5)));
  const int x1 = std::min(width - 1, static_cast<int>(std::ceil(hi.x - 0.5)));
  const int y1 = std::min(height - 1, static_cast<int>(std::ceil(hi.y - 0.5)));
  std::vector<Hit> hits;
  if (x1 < x0 || y1 < y0) return hits;
  const int gw = x1 - x0 + 1;
  std::vector<int> owner(static_cast<std::size_t>(gw) * (y1 - y0 + 1), -1);
  for (int lf = 0; lf < static_cast<int>(ch.local_faces.size()); ++lf) {
    const Face& f = ch.local_faces[lf];
    const FixedPoint P[3] = {to_fixed(texel[f[0]]), to_fixed(texel[f[1]]), to_fixed(texel[f[2]])};
    if (s * orient(P[0], P[1], P[2]) <= 0) continue;
    // Per edge: the sign the symbolic shift gives a centre lying exactly on it.
    int tie[3];
    for (int k = 0; k < 3; ++k) {
      const std::int64_t dx = P[(k + 1) % 3].x - P[k].x, dy = P[(k + 1) % 3].y - P[k].y;
      const std::int64_t t = dy != 0 ? (dy > 0 ? -1 : 1) : (dx > 0 ? 1 : -1);
      tie[k] = static_cast<int>(t * s);
    }
    double fx0 = 1e300, fy0 = 1e300, fx1 = -1e300, fy1 = -1e300;
    for (int k = 0; k < 3; ++k) {
      fx0 = std::min(fx0, texel[f[k]].x);
      fy0 = std::min(fy0, texel[f[k]].y);
      fx1 = std::max(fx1, texel[f[k]].x);
      fy1 = std::max(fy1, texel[f[k]].y);
    }
    const int sx0 = std::max(x0, static_cast<int>(std::floor(fx0 - 0.5)));
    const int sy0 = std::max(y0, static_cast<int>(std::floor(fy0 - 0.5)));
    const int sx1 = std::min(x1, static_cast<int>(std::ceil(fx1 - 0.5)));
    const int sy1 = std::min(y1, static_cast<int>(std::ceil(fy1 - 0.5)));
    for (int y = sy0; y <= sy1; ++y)
      for (int x = sx0; x <= sx1; ++x) {
        const FixedPoint C{(2 * static_cast<std::int64_t>(x) + 1) * kHalf,
                           (2 * static_cast<std::int64_t>(y) + 1) * kHalf};
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const std::int64_t w = s * orient(P[k], P[(k + 1) % 3], C);
          inside = w > 0 || (w == 0 && tie[k] > 0);
        }
        if (!inside) continue;
        int& o = owner[static_cast<std::size_t>(y - y0) * gw + (x - x0)];
        if (o < 0) o = lf;
      }
  }
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const int lf = owner[static_cast<std::size_t>(y - y0) * gw + (x - x0)];
      if (lf < 0) continue;
      Hit h{y * width + x, lf, {}};
      if (want_bary) {
        const Face& f = ch.local_faces[lf];
        const Vec2d c{x + 0.5, y + 0.5};
        const Vec2d& q0 = texel[f[0]];
        const Vec2d& q1 = texel[f[1]];
        const Vec2d& q2 = texel[f[2]];
        const double area = cross(q1 - q0, q2 - q0);
        double b0 = cross(q1 - c, q2 - c) / area, b1 = cross(q2 - c, q0 - c) / area;
        double b2 = 1 - b0 - b1;
        b0 = std::max(b0, 0.0);
        b1 = std::max(b1, 0.0);
        b2 = std::max(b2, 0.0);
        const double sum = b0 + b1 + b2;
        h.bary = sum > 0 ? Vec3d{b0 / sum, b1 / sum, b2 / sum} : Vec3d{1.0 / 3, 1.0 / 3, 1.0 / 3};
      }
      hits.push_back(h);
    }
  return hits;
}

// --- Cleanup: the samples of one chart, reconstructed by the 2×2 rule, must form a disk. ---

constexpr int kDx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
constexpr int kDy[8] = {0, 1, 1, 1, 0, -1, -1, -1};

int direction(int dx, int dy) {
  for (int d = 0; d < 8; ++d)
    if (kDx[d] == dx && kDy[d] == dy) return d;
  return -1;
}

struct LocalGrid {
  int x0 = 0, y0 = 0, w = 0, h = 0;
  std::vector<char> in;
  int at(int x, int y) const { return y * w + x; }
  /// Image index (row width W) of a grid cell.
  int to_image(int v, int W) const { return (v / w + y0) * W + (v % w + x0); }
};

// The bounding box of some image samples (row width W) with a margin of one empty cell, the
// samples marked in it.
LocalGrid grid_around(const std::vector<int>& samples, int W) {
  int x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = -1, y1 = -1;
  for (int i : samples) {
    x0 = std::min(x0, i % W);
    x1 = std::max(x1, i % W);
    y0 = std::min(y0, i / W);
    y1 = std::max(y1, i / W);
  }
  LocalGrid g;
  g.x0 = x0 - 1;
  g.y0 = y0 - 1;
  g.w = x1 - x0 + 3;
  g.h = y1 - y0 + 3;
  g.in.assign(static_cast<std::size_t>(g.w) * g.h, 0);
  for (int i : samples) g.in[g.at(i % W - g.x0, i / W - g.y0)] = 1;
  return g;
}

// Triangles of the block with lower-left corner (bx, by), counter-clockwise in grid space (the
// diagonal of a full block is arbitrary: it changes neither the boundary nor the topology).
int block_triangles(const LocalGrid& g, int bx, int by, std::array<std::array<int, 3>, 2>& tris) {
  const int c[4] = {g.at(bx, by), g.at(bx + 1, by), g.at(bx + 1, by + 1), g.at(bx, by + 1)};
  int n = 0, missing = -1;
  for (int k = 0; k < 4; ++k) {
    if (g.in[c[k]]) ++n;
    else missing = k;
  }
  if (n == 4) {
    tris[0] = {c[0], c[1], c[2]};
    tris[1] = {c[0], c[2], c[3]};
    return 2;
  }
  if (n == 3) {
    int t = 0;
    for (int k = 1; k <= 3; ++k) tris[0][t++] = c[(missing + k) % 4];
    return 1;
  }
  return 0;
}

// Removes covered samples until the chart's reconstruction is one disk: samples in no
// triangle, pinch samples (two boundary wedges), all components but the largest, and a
// path of samples cutting each hole open to the outer boundary. Returns the ring
// (counter-clockwise in grid space) or an empty ring when nothing is left.
std::vector<int> make_disk(LocalGrid& g, long long& removed, long long* cut_off = nullptr) {
  const int n = g.w * g.h;
  std::vector<unsigned char> out(n);
  std::vector<int> ring;
  auto remove = [&](int v) {
    if (g.in[v]) {
      g.in[v] = 0;
      ++removed;
    }
  };
  for (;;) {
    std::fill(out.begin(), out.end(), 0);
    std::vector<char> used(n, 0);
    isochart::UnionFind uf(n);
    std::vector<int> tri_count(n, 0);
    std::array<std::array<int, 3>, 2> tris;
    bool any = false;
    for (int by = 0; by + 1 < g.h; ++by)
      for (int bx = 0; bx + 1 < g.w; ++bx) {
        const int nt = block_triangles(g, bx, by, tris);
        for (int t = 0; t < nt; ++t) {
          any = true;
          for (int k = 0; k < 3; ++k) {
            const int a = tris[t][k], b = tris[t][(k + 1) % 3];
            out[a] |= static_cast<unsigned char>(1u << direction(b % g.w - a % g.w, b / g.w - a / g.w));
            used[a] = 1;
            uf.unite(a, b);
          }
          ++tri_count[tris[t][0]];
        }
      }
    bool changed = false;
    for (int v = 0; v < n; ++v)
      if (g.in[v] && !used[v]) {
        remove(v);
        changed = true;
      }
    if (changed) continue;
    if (!any) return {};
    // Boundary edges: directed edges whose reverse is absent.
    std::vector<int> next(n, -1);
    for (int v = 0; v < n; ++v) {
      if (!out[v]) continue;
      const int x = v % g.w, y = v / g.w;
      int count = 0;
      for (int d = 0; d < 8; ++d) {
        if (!(out[v] & (1u << d))) continue;
        const int u = g.at(x + kDx[d], y + kDy[d]);
        if (out[u] & (1u << ((d + 4) % 8))) continue;
        next[v] = u;
        ++count;
      }
      if (count > 1) {
        remove(v);
        changed = true;
      }
    }
    if (changed) continue;
    // Keep the component with the most triangles (the lowest root on ties).
    std::vector<int> comp_tris(n, 0);
    for (int v = 0; v < n; ++v)
      if (tri_count[v]) comp_tris[uf.find(v)] += tri_count[v];
    int best = -1;
    for (int v = 0; v < n; ++v)
      if (comp_tris[v] > 0 && (best < 0 || comp_tris[v] > comp_tris[best])) best = v;
    for (int v = 0; v < n; ++v)
      if (g.in[v] && uf.find(v) != best) {
        remove(v);
        changed = true;
        if (cut_off) ++*cut_off;
      }
    if (changed) continue;
    // Boundary loops; the outer one has the largest signed area.
    std::vector<std::vector<int>> loops;
    std::vector<double> areas;
    std::vector<char> seen(n, 0);
    for (int v = 0; v < n; ++v) {
      if (next[v] < 0 || seen[v]) continue;
      std::vector<int> loop;
      double area = 0;
      for (int u = v; !seen[u]; u = next[u]) {
        if (next[u] < 0) throw Error("geometry image: open boundary chain in a chart");
        seen[u] = 1;
        loop.push_back(u);
        const int w = next[u];
        area += static_cast<double>(u % g.w) * (w / g.w) - static_cast<double>(w % g.w) * (u / g.w);
      }
      loops.push_back(std::move(loop));
      areas.push_back(area);
    }
    if (loops.size() == 1) {
      ring = std::move(loops[0]);
      break;
    }
    const int outer = static_cast<int>(std::max_element(areas.begin(), areas.end()) - areas.begin());
    const int hole = outer == 0 ? 1 : 0;
    std::vector<char> is_outer(n, 0);
    for (int v : loops[outer]) is_outer[v] = 1;
    // Breadth-first search from the hole through the chart's samples to the outer boundary.
    std::vector<int> from(n, -2);
    std::deque<int> queue;
    for (int v : loops[hole]) {
      from[v] = -1;
      queue.push_back(v);
    }
    int reached = -1;
    while (!queue.empty() && reached < 0) {
      const int v = queue.front();
      queue.pop_front();
      if (is_outer[v]) {
        reached = v;
        break;
      }
      const int x = v % g.w, y = v / g.w;
      for (int d = 0; d < 8; d += 2) {
        const int xx = x + kDx[d], yy = y + kDy[d];
        if (xx < 0 || yy < 0 || xx >= g.w || yy >= g.h) continue;
        const int u = g.at(xx, yy);
        if (!g.in[u] || from[u] != -2) continue;
        from[u] = v;
        queue.push_back(u);
      }
    }
    if (reached < 0) throw Error("geometry image: a hole in a chart is not connected to its outside");
    for (int v = reached; v >= 0; v = from[v]) remove(v);
  }
  return ring;
}

// Squared distance from p to the triangle abc (2-D) and the barycentric coordinates of the
// closest point.
double closest_on_triangle(const Vec2d& p, const Vec2d& a, const Vec2d& b, const Vec2d& c, Vec3d& bary) {
  const double area = cross(b - a, c - a);
  if (area != 0) {
    const double u = cross(b - p, c - p) / area, v = cross(c - p, a - p) / area, w = 1 - u - v;
    if (u >= 0 && v >= 0 && w >= 0) {
      bary = {u, v, w};
      return 0;
    }
  }
  double best = 1e300;
  const Vec2d q[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const Vec2d d = q[(k + 1) % 3] - q[k];
    const double len2 = dot(d, d);
    const double t = len2 > 0 ? std::clamp(dot(p - q[k], d) / len2, 0.0, 1.0) : 0.0;
    const double dist = squared_norm(p - (q[k] + d * t));
    if (dist < best) {
      best = dist;
      double bb[3] = {0, 0, 0};
      bb[k] = 1 - t;
      bb[(k + 1) % 3] = t;
      bary = {bb[0], bb[1], bb[2]};
    }
  }
  return best;
}

// Whether the triangle p0 p1 p2 meets the closed texel square [x, x+1] × [y, y+1]
// (separating axes: the square's two axes and the triangle's three edge normals).
bool triangle_touches_square(const Vec2d& p0, const Vec2d& p1, const Vec2d& p2, int x, int y) {
  const Vec2d t[3] = {p0, p1, p2};
  const Vec2d q[4] = {{static_cast<double>(x), static_cast<double>(y)},
                      {x + 1.0, static_cast<double>(y)},
                      {x + 1.0, y + 1.0},
                      {static_cast<double>(x), y + 1.0}};
  auto separated = [&](const Vec2d& axis) {
    double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
    for (const Vec2d& p : t) {
      a0 = std::min(a0, dot(p, axis));
      a1 = std::max(a1, dot(p, axis));
    }
    for (const Vec2d& p : q) {
      b0 = std::min(b0, dot(p, axis));
      b1 = std::max(b1, dot(p, axis));
    }
    return a1 < b0 || b1 < a0;
  };
  if (separated({1, 0}) || separated({0, 1})) return false;
  for (int k = 0; k < 3; ++k) {
    const Vec2d e = t[(k + 1) % 3] - t[k];
    if (separated({-e.y, e.x})) return false;
  }
  return true;
}

// Removes the samples whose centres lie within `radius` texels of the segment ab.
void remove_near_segment(LocalGrid& g, const Vec2d& a, const Vec2d& b, double radius, long long& removed) {
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x, b.x) - radius - 0.5)) - g.x0);
  const int x1 = std::min(g.w - 1, static_cast<int>(std::ceil(std::max(a.x, b.x) + radius - 0.5)) - g.x0);
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y, b.y) - radius - 0.5)) - g.y0);
  const int y1 = std::min(g.h - 1, static_cast<int>(std::ceil(std::max(a.y, b.y) + radius - 0.5)) - g.y0);
  const Vec2d d = b - a;
  const double len2 = dot(d, d);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const int v = g.at(x, y);
      if (!g.in[v]) continue;
      const Vec2d p{x + g.x0 + 0.5, y + g.y0 + 0.5};
      const double t = len2 > 0 ? std::clamp(dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
      if (squared_norm(p - (a + d * t)) <= radius * radius) {
        g.in[v] = 0;
        ++removed;
      }
    }
}

// Where a concave notch of the chart is narrower than the sample spacing, samples on its two
// sides are neighbours and block triangles would bridge it, covering the neighbouring chart's
// surface a second time. Removes both ends of every sample edge (4- or 8-neighbours) that runs
// outside the chart for more than a quarter texel, or that crosses the notch anywhere when the
// notch is deeper than a texel: the slits the atlas cut to open a chart around a hole have zero
// width, and unless the ring of samples enters them, zippering contracts the slit and joins
// the hole to the slit's mouth.
void remove_bridges(LocalGrid& g, const Chart& ch, const std::vector<Vec2d>& texel, long long& removed) {
  const int L = static_cast<int>(ch.loop.size());
  // Texel length along the loop to the start of each edge.
  std::vector<double> along(L + 1, 0.0);
  for (int e = 0; e < L; ++e) along[e + 1] = along[e] + norm(texel[ch.loop[(e + 1) % L]] - texel[ch.loop[e]]);
  const double perimeter = along[L];
  // Loop edges by local cell: cell (i, j) spans the samples (i, j) .. (i + 1, j + 1).
  std::vector<std::vector<int>> cells(static_cast<std::size_t>(g.w) * g.h);
  auto local = [&](const Vec2d& p) { return Vec2d(p.x - 0.5 - g.x0, p.y - 0.5 - g.y0); };
  for (int e = 0; e < L; ++e) {
    const Vec2d a = local(texel[ch.loop[e]]), b = local(texel[ch.loop[(e + 1) % L]]);
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x, b.x))));
    const int x1 = std::min(g.w - 1, static_cast<int>(std::floor(std::max(a.x, b.x))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y, b.y))));
    const int y1 = std::min(g.h - 1, static_cast<int>(std::floor(std::max(a.y, b.y))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) cells[g.at(x, y)].push_back(e);
  }
  std::vector<char> drop(g.in.size(), 0);
  std::vector<int> cand;
  std::vector<std::pair<double, double>> ts;  // crossing: parameter on the sample edge, loop position
  static constexpr int kNx[4] = {1, 1, 0, -1}, kNy[4] = {0, 1, 1, 1};
  for (int y = 0; y < g.h; ++y)
    for (int x = 0; x < g.w; ++x) {
      if (!g.in[g.at(x, y)]) continue;
      for (int d = 0; d < 4; ++d) {
        const int xx = x + kNx[d], yy = y + kNy[d];
        if (xx < 0 || xx >= g.w || yy >= g.h || !g.in[g.at(xx, yy)]) continue;
        cand.clear();
        for (int cy = std::max(0, std::min(y, yy) - 1); cy <= std::min(g.h - 1, std::max(y, yy)); ++cy)
          for (int cx = std::max(0, std::min(x, xx) - 1); cx <= std::min(g.w - 1, std::max(x, xx)); ++cx)
            for (int e : cells[g.at(cx, cy)]) cand.push_back(e);
        if (cand.empty()) continue;
        std::sort(cand.begin(), cand.end());
        cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
        const Vec2d p{static_cast<double>(x), static_cast<double>(y)};
        const Vec2d q{static_cast<double>(xx), static_cast<double>(yy)};
        const Vec2d dq = q - p;
        ts.clear();
        for (int e : cand) {
          const Vec2d a = local(texel[ch.loop[e]]), b = local(texel[ch.loop[(e + 1) % L]]);
          const Vec2d db = b - a;
          const double den = cross(dq, db);
          if (den == 0) continue;
          const double t = cross(a - p, db) / den, u = cross(a - p, dq) / den;
          if (t >= 0 && t <= 1 && u >= 0 && u <= 1) ts.emplace_back(t, along[e] + u * (along[e + 1] - along[e]));
        }
        if (ts.size() < 2) continue;
        std::sort(ts.begin(), ts.end());
        double outside = 0;
        bool deep = false;
        for (std::size_t k = 0; k + 1 < ts.size(); k += 2) {
          outside += ts[k + 1].first - ts[k].first;
          const double gap = std::abs(ts[k + 1].second - ts[k].second);
          deep = deep || std::min(gap, perimeter - gap) > 2.0;
        }
        if (outside * norm(dq) > 0.25 || deep) drop[g.at(x, y)] = drop[g.at(xx, yy)] = 1;
      }
    }
  for (std::size_t v = 0; v < g.in.size(); ++v)
    if (drop[v] && g.in[v]) {
      g.in[v] = 0;
      ++removed;
    }
}

}  // namespace

Sampling sample_charts(const AtlasCharts& a, const Placement& pl, bool check_gap,
                       const isochart::Progress& progress) {
  const Mesh& m = *a.mesh;
  const int W = pl.width, H = pl.height;
  const int nc = static_cast<int>(a.charts.size());
  isochart::report(progress, isochart::Stage::Sampling, 0.0);
  std::vector<std::vector<Hit>> hits(nc);
  tbb::parallel_for(0, nc, [&](int c) {
    hits[c] = rasterize_chart(a.charts[c], pl.texel[c], pl.mirrored[c], W, H, true);
  });
  isochart::report(progress, isochart::Stage::Sampling, 0.3);

  Sampling s;
  GeometryImage& im = s.image;
  im.width = W;
  im.height = H;
  const std::size_t N = static_cast<std::size_t>(W) * H;
  im.positions.assign(N, {});
  im.normals.assign(N, {});
  im.chart.assign(N, -1);
  im.group.assign(N, -1);
  im.face.assign(N, -1);
  im.barycentric.assign(N, {});
  im.num_charts = nc;
  im.chart_mirrored = pl.mirrored;
  s.param.resize(N);
  for (std::size_t i = 0; i < N; ++i) s.param[i] = {static_cast<double>(i % W) + 0.5, static_cast<double>(i / W) + 0.5};
  auto fail = [&](const std::string& msg) {
    if (check_gap) throw InputError("", msg + " at " + std::to_string(W) + "x" + std::to_string(H) +
                                            "; re-pack the atlas");
    throw Error("packing left " + msg + " at " + std::to_string(W) + "x" + std::to_string(H));
  };
  for (int c = 0; c < nc; ++c)
    for (const Hit& h : hits[c]) {
      if (im.chart[h.sample] >= 0)
        fail("charts " + std::to_string(im.chart[h.sample]) + " and " + std::to_string(c) +
             " overlapping (sample " + std::to_string(h.sample % W) + "," +
             std::to_string(h.sample / W) + ")");
      im.chart[h.sample] = c;
      const Chart& ch = a.charts[c];
      im.face[h.sample] = ch.faces[h.local_face];
      im.barycentric[h.sample] = h.bary;
      ++s.covered;
    }
  // Every 2×2 block must hold samples of one chart only.
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const int c = im.chart[im.index(x, y)];
      if (c < 0) continue;
      for (int d = 0; d < 4; ++d) {
        static constexpr int ox[4] = {1, -1, 0, 1}, oy[4] = {0, 1, 1, 1};
        const int xx = x + ox[d], yy = y + oy[d];
        if (xx < 0 || xx >= W || yy >= H) continue;
        const int o = im.chart[im.index(xx, yy)];
        if (o >= 0 && o != c)
          fail("charts " + std::to_string(std::min(c, o)) + " and " + std::to_string(std::max(c, o)) +
               " closer than one texel (samples " + std::to_string(x) + "," + std::to_string(y) +
               " and " + std::to_string(xx) + "," + std::to_string(yy) + ")");
      }
    }
  isochart::report(progress, isochart::Stage::Sampling, 0.5);

  // Opens the slits of a chart with holes: no block triangle may cross a slit, so every
  // sample within √2/2 of it goes (each crossing triangle edge has an end that close).
  auto remove_slit_samples = [&](LocalGrid& g, int c, long long* removed = nullptr) {
    long long count = 0;
    for (const auto& slit : a.charts[c].slits)
      for (std::size_t i = 0; i + 1 < slit.size(); ++i)
        remove_near_segment(g, pl.texel[c][slit[i]], pl.texel[c][slit[i + 1]], 0.75, count);
    if (removed) *removed += count;
  };
  // Cleanup per chart, in parallel: the charts' samples are disjoint.
  s.regions.resize(nc);
  tbb::parallel_for(0, nc, [&](int c) {
    ChartRegion& r = s.regions[c];
    if (hits[c].empty()) return;
    std::vector<int> hit_samples;
    hit_samples.reserve(hits[c].size());
    for (const Hit& h : hits[c]) hit_samples.push_back(h.sample);
    LocalGrid g = grid_around(hit_samples, W);
    auto to_image = [&](int v) { return g.to_image(v, W); };
    remove_slit_samples(g, c, &r.removed);
    // Bridges across notches come out, unless that cuts off a part of the chart (a notch
    // almost through it): losing the part costs more than a bridge, which zippering survives.
    const LocalGrid whole = g;
    long long bridged = 0, cleaned = 0, cut_off = 0;
    remove_bridges(g, a.charts[c], pl.texel[c], bridged);
    for (int v = 0; v < g.w * g.h; ++v)
      if (whole.in[v] && !g.in[v]) r.bridges.push_back(to_image(v));
    std::sort(r.bridges.begin(), r.bridges.end());
    std::vector<int> ring = make_disk(g, cleaned, &cut_off);
    const long long total = std::count(whole.in.begin(), whole.in.end(), 1);
    if (cleaned > std::max(16LL, total / 50)) {
      LocalGrid alt = whole;
      long long alt_cleaned = 0, alt_cut_off = 0;
      std::vector<int> alt_ring = make_disk(alt, alt_cleaned, &alt_cut_off);
      if (!alt_ring.empty() && alt_cleaned + 16 < cleaned + bridged) {
        g = std::move(alt);
        ring = std::move(alt_ring);
        bridged = 0;
        r.bridges.clear();
        cleaned = alt_cleaned;
        cut_off = alt_cut_off;
      }
    }
    r.removed += bridged + cleaned;
    r.cut_off = cut_off;
    for (int v = 0; v < g.w * g.h; ++v)
      if (g.in[v]) r.samples.push_back(to_image(v));
    std::sort(r.samples.begin(), r.samples.end());
    if (!ring.empty()) {
      // Start at the lowest image index, for determinism.
      std::vector<int> img(ring.size());
      for (std::size_t i = 0; i < ring.size(); ++i) img[i] = to_image(ring[i]);
      std::rotate(img.begin(), std::min_element(img.begin(), img.end()), img.end());
      // The grid triangles are counter-clockwise; a mirrored chart's loop is clockwise.
      if (pl.mirrored[c]) std::reverse(img.begin() + 1, img.end());
      r.ring = std::move(img);
    }
  });
  isochart::report(progress, isochart::Stage::Sampling, 0.8);

  std::vector<char> keep(N, 0);
  for (const ChartRegion& r : s.regions) {
    for (int i : r.samples) keep[i] = 1;
    s.removed += r.removed;
  }
  for (std::size_t i = 0; i < N; ++i) {
    if (im.chart[i] < 0) continue;
    if (!keep[i]) {
      im.chart[i] = -1;
      im.face[i] = -1;
      im.barycentric[i] = {};
      continue;
    }
    const Face& f = m.faces[im.face[i]];
    const Vec3d& b = im.barycentric[i];
    im.positions[i] = face_point(m, im.face[i], b);
    im.normals[i] = normalized(a.vertex_normals[f[0]] * b.x + a.vertex_normals[f[1]] * b.y +
                               a.vertex_normals[f[2]] * b.z);
  }
  // A chart too small or too thin for a triangle of sample centres would have to be
  // contracted to a point, which stretches its neighbours towards that point and pinches them
  // where it touches one of them twice. Such a chart gets the samples of the texels it touches
  // and their 4-neighbours instead (made a disk as above), or failing that the free 2×2 block
  // nearest to it; never a sample 8-adjacent to another chart's. Each sits at the chart's
  // closest point.
  auto free_for = [&](int c, int x, int y) {
    if (x < 0 || y < 0 || x >= W || y >= H || im.chart[im.index(x, y)] >= 0) return false;
    for (int yy = y - 1; yy <= y + 1; ++yy)
      for (int xx = x - 1; xx <= x + 1; ++xx)
        if (xx >= 0 && yy >= 0 && xx < W && yy < H) {
          const int o = im.chart[im.index(xx, yy)];
          if (o >= 0 && o != c) return false;
        }
    return true;
  };
  // The point of chart c closest to sample i's centre in texel space.
  auto closest_hit = [&](int c, int i) {
    const Chart& ch = a.charts[c];
    const Vec2d p{i % W + 0.5, i / W + 0.5};
    Hit h{i, 0, {}};
    double best = 1e300;
    for (std::size_t lf = 0; lf < ch.local_faces.size(); ++lf) {
      Vec3d b;
      const Face& f = ch.local_faces[lf];
      const double d = closest_on_triangle(p, pl.texel[c][f[0]], pl.texel[c][f[1]], pl.texel[c][f[2]], b);
      if (d < best) {
        best = d;
        h.local_face = static_cast<int>(lf);
        h.bary = b;
      }
    }
    return h;
  };
  auto define_closest = [&](int c, int i) {
    const Chart& ch = a.charts[c];
    const Hit h = closest_hit(c, i);
    const Vec3d& best_bary = h.bary;
    const int pf = ch.faces[h.local_face];
    const Face& f = m.faces[pf];
    const Face& lf = ch.local_faces[h.local_face];
    s.param[i] = pl.texel[c][lf[0]] * best_bary.x + pl.texel[c][lf[1]] * best_bary.y + pl.texel[c][lf[2]] * best_bary.z;
    im.chart[i] = c;
    im.face[i] = pf;
    im.barycentric[i] = best_bary;
    im.positions[i] = face_point(m, pf, best_bary);
    im.normals[i] = normalized(a.vertex_normals[f[0]] * best_bary.x + a.vertex_normals[f[1]] * best_bary.y +
                               a.vertex_normals[f[2]] * best_bary.z);
    ++s.forced;
  };
  // Texels whose square the chart's triangles meet (conservative rasterization).
  auto touched_texels = [&](int c) {
    const Chart& ch = a.charts[c];
    std::vector<int> cand;
    for (const Face& f : ch.local_faces) {
      const Vec2d& p0 = pl.texel[c][f[0]];
      const Vec2d& p1 = pl.texel[c][f[1]];
      const Vec2d& p2 = pl.texel[c][f[2]];
      const int x0 = std::max(0, static_cast<int>(std::floor(std::min({p0.x, p1.x, p2.x}))));
      const int x1 = std::min(W - 1, static_cast<int>(std::floor(std::max({p0.x, p1.x, p2.x}))));
      const int y0 = std::max(0, static_cast<int>(std::floor(std::min({p0.y, p1.y, p2.y}))));
      const int y1 = std::min(H - 1, static_cast<int>(std::floor(std::max({p0.y, p1.y, p2.y}))));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          Vec3d unused;
          // Within half a texel of the centre the square is surely touched; otherwise test
          // exactly (closest_on_triangle returns a squared distance).
          if (closest_on_triangle(Vec2d(x + 0.5, y + 0.5), p0, p1, p2, unused) > 0.25 &&
              !triangle_touches_square(p0, p1, p2, x, y))
            continue;
          cand.push_back(im.index(x, y));
        }
    }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    // A hole narrower than two texels has texels the triangles around it touch; a sample
    // there would close the hole.
    auto in_hole = [&](int i) {
      const Vec2d p{i % W + 0.5, i / W + 0.5};
      for (const auto& hole : ch.holes) {
        bool inside = false;
        for (std::size_t k = 0, j = hole.size() - 1; k < hole.size(); j = k++) {
          const Vec2d& q0 = pl.texel[c][hole[k]];
          const Vec2d& q1 = pl.texel[c][hole[j]];
          if ((q0.y > p.y) != (q1.y > p.y) && p.x < q0.x + (p.y - q0.y) * (q1.x - q0.x) / (q1.y - q0.y))
            inside = !inside;
        }
        if (inside) return true;
      }
      return false;
    };
    cand.erase(std::remove_if(cand.begin(), cand.end(), in_hole), cand.end());
    return cand;
  };
  // A part of a chart joined to the rest by a neck thinner than a sample was cut off above and
  // would be contracted with all its surface. Such charts are tried again with the free texels
  // they touch added, which carries the neck across; the result is kept when it holds more.
  // A sample taken off as a bridge across a notch, or a touched texel (whose closest point
  // stands for it), comes back only when no grid neighbour lies far from it on the surface:
  // across a crack deeper than a texel the block triangles would join surface points far apart
  // (gargoyle, a 13-chart atlas at 256²: a tear of 13-36-unit edges, 54.5 dB instead of 78;
  // skull's atlas at --max-l2 1.05, 256²: touched texels in a crack, 74.1 dB instead of 85.0),
  // while across a shallow notch they follow the surface and keep its samples (armadillo at
  // 64²: 0.65 dB).
  for (int c = 0; c < nc; ++c) {
    ChartRegion& r = s.regions[c];
    if (r.ring.empty() || r.cut_off < 16) continue;
    const Chart& chart = a.charts[c];
    auto hit_at = [&](int i) -> const Hit* {
      const auto h = std::lower_bound(hits[c].begin(), hits[c].end(), i,
                                      [](const Hit& x, int v) { return x.sample < v; });
      return h != hits[c].end() && h->sample == i ? &*h : nullptr;
    };
    auto hit_point = [&](const Hit& h) { return face_point(m, chart.faces[h.local_face], h.bary); };
    // Surface length of a texel offset d in the hit's triangle (its affine map from texels).
    auto surface_length = [&](const Hit& h, const Vec2d& d) {
      const Face& f = m.faces[chart.faces[h.local_face]];
      const Face& l = chart.local_faces[h.local_face];
      const Vec2d u1 = pl.texel[c][l[1]] - pl.texel[c][l[0]], u2 = pl.texel[c][l[2]] - pl.texel[c][l[0]];
      const double det = cross(u1, u2);
      if (det == 0) return std::numeric_limits<double>::infinity();
      // d = a u1 + b u2
      const double wa = cross(d, u2) / det, wb = cross(u1, d) / det;
      return norm((m.positions[f[1]] - m.positions[f[0]]) * wa +
                  (m.positions[f[2]] - m.positions[f[0]]) * wb);
    };
    // Free texels the chart touches without covering their centres: each stands for its
    // closest point of the chart, which across a crack is on one side only.
    const std::vector<int> touched = touched_texels(c);
    std::vector<Hit> fringe;
    for (int t : touched)
      if (!hit_at(t) && free_for(c, t % W, t / W)) fringe.push_back(closest_hit(c, t));
    auto point_at = [&](int i) -> const Hit* {
      if (const Hit* h = hit_at(i)) return h;
      const auto h =
          std::lower_bound(fringe.begin(), fringe.end(), i, [](const Hit& x, int v) { return x.sample < v; });
      return h != fringe.end() && h->sample == i ? &*h : nullptr;
    };
    std::vector<int> tested = r.bridges;
    for (const Hit& h : fringe) tested.push_back(h.sample);
    std::vector<int> torn;
    for (int b : tested) {
      const Hit* hb = point_at(b);
      if (!hb) continue;
      const Vec3d pb = hit_point(*hb);
      const int bx = b % W, by = b / W;
      double worst = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = bx + dx, y = by + dy;
          if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= W || y >= H) continue;
          const Hit* hn = point_at(im.index(x, y));
          if (!hn) continue;
          const Vec2d d(dx, dy);
          const double expect = std::max(surface_length(*hb, d), surface_length(*hn, d));
          worst = std::max(worst, norm(hit_point(*hn) - pb) / expect);
        }
      if (worst > kTornBridge) torn.push_back(b);
    }
    std::sort(torn.begin(), torn.end());
    auto torn_bridge = [&](int i) { return std::binary_search(torn.begin(), torn.end(), i); };
    std::vector<int> set = r.samples;
    for (const Hit& h : hits[c])
      if (!torn_bridge(h.sample) && free_for(c, h.sample % W, h.sample / W)) set.push_back(h.sample);
    for (int t : touched)
      if (!torn_bridge(t) && free_for(c, t % W, t / W)) set.push_back(t);
    std::sort(set.begin(), set.end());
    set.erase(std::unique(set.begin(), set.end()), set.end());
    LocalGrid g = grid_around(set, W);
    long long dropped = 0;
    // The texels added back include those taken off the slits above; they go again.
    remove_slit_samples(g, c);
    std::vector<int> ring = make_disk(g, dropped);
    auto to_image = [&](int v) { return g.to_image(v, W); };
    std::vector<int> samples;
    for (int v = 0; v < g.w * g.h; ++v)
      if (g.in[v]) samples.push_back(to_image(v));
    if (ring.empty() || samples.size() < r.samples.size() + 16) continue;
    for (int i : r.samples)
      if (!std::binary_search(samples.begin(), samples.end(), i)) {
        im.chart[i] = -1;
        im.face[i] = -1;
        im.barycentric[i] = {};
        im.positions[i] = {};
        im.normals[i] = {};
      }
    const Chart& ch = a.charts[c];
    for (int i : samples) {
      if (std::binary_search(r.samples.begin(), r.samples.end(), i)) continue;
      // A covered sample keeps its exact location; a touched one goes to the closest point.
      const auto hit = std::lower_bound(hits[c].begin(), hits[c].end(), i,
                                        [](const Hit& h, int v) { return h.sample < v; });
      if (hit != hits[c].end() && hit->sample == i) {
        const Face& f = m.faces[ch.faces[hit->local_face]];
        im.chart[i] = c;
        im.face[i] = ch.faces[hit->local_face];
        im.barycentric[i] = hit->bary;
        im.positions[i] = face_point(m, im.face[i], hit->bary);
        im.normals[i] = normalized(a.vertex_normals[f[0]] * hit->bary.x + a.vertex_normals[f[1]] * hit->bary.y +
                                   a.vertex_normals[f[2]] * hit->bary.z);
        --r.removed;
        --s.removed;
      } else {
        define_closest(c, i);
      }
    }
    for (int& v : ring) v = to_image(v);
    std::rotate(ring.begin(), std::min_element(ring.begin(), ring.end()), ring.end());
    if (pl.mirrored[c]) std::reverse(ring.begin() + 1, ring.end());
    r.samples = std::move(samples);
    r.ring = std::move(ring);
  }
  for (int c = 0; c < nc; ++c) {
    if (!s.regions[c].ring.empty()) continue;
    const Chart& ch = a.charts[c];
    ChartRegion& r = s.regions[c];
    // Touched texels and their 4-neighbours.
    std::vector<int> cand = touched_texels(c);
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    const std::size_t touched = cand.size();
    for (std::size_t k = 0; k < touched; ++k) {
      const int x = cand[k] % W, y = cand[k] / W;
      const int nx[4] = {x + 1, x - 1, x, x}, ny[4] = {y, y, y + 1, y - 1};
      for (int d = 0; d < 4; ++d)
        if (nx[d] >= 0 && ny[d] >= 0 && nx[d] < W && ny[d] < H) cand.push_back(im.index(nx[d], ny[d]));
    }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    cand.erase(std::remove_if(cand.begin(), cand.end(), [&](int i) { return !free_for(c, i % W, i / W); }),
               cand.end());
    std::vector<int> ring;
    if (!cand.empty()) {
      LocalGrid g = grid_around(cand, W);
      long long dropped = 0;
      ring = make_disk(g, dropped);
      auto to_image = [&](int v) { return g.to_image(v, W); };
      if (!ring.empty()) {
        for (int v = 0; v < g.w * g.h; ++v)
          if (g.in[v]) r.samples.push_back(to_image(v));
        for (int& v : ring) v = to_image(v);
        std::rotate(ring.begin(), std::min_element(ring.begin(), ring.end()), ring.end());
      }
    }
    if (ring.empty()) {
      // The free 2×2 block nearest to the chart's centroid.
      Vec2d centroid;
      double area = 0;
      for (const Face& f : ch.local_faces) {
        const double ar = std::abs(isochart::signed_area(pl.texel[c][f[0]], pl.texel[c][f[1]], pl.texel[c][f[2]]));
        centroid += (pl.texel[c][f[0]] + pl.texel[c][f[1]] + pl.texel[c][f[2]]) * (ar / 3);
        area += ar;
      }
      if (!(area > 0)) continue;
      centroid = centroid / area;
      const int bx0 = static_cast<int>(std::floor(centroid.x - 1.0)), by0 = static_cast<int>(std::floor(centroid.y - 1.0));
      std::vector<std::pair<double, std::array<int, 2>>> blocks;
      for (int by = by0 - 1; by <= by0 + 1; ++by)
        for (int bx = bx0 - 1; bx <= bx0 + 1; ++bx)
          blocks.push_back({squared_norm(Vec2d(bx + 1.0, by + 1.0) - centroid), {bx, by}});
      std::sort(blocks.begin(), blocks.end());
      for (const auto& blk : blocks) {
        const int bx = blk.second[0], by = blk.second[1];
        if (!free_for(c, bx, by) || !free_for(c, bx + 1, by) || !free_for(c, bx + 1, by + 1) || !free_for(c, bx, by + 1))
          continue;
        ring = {im.index(bx, by), im.index(bx + 1, by), im.index(bx + 1, by + 1), im.index(bx, by + 1)};
        r.samples = ring;
        break;
      }
    }
    if (ring.empty()) continue;
    std::sort(r.samples.begin(), r.samples.end());
    for (int i : r.samples) define_closest(c, i);
    if (pl.mirrored[c]) std::reverse(ring.begin() + 1, ring.end());
    r.ring = std::move(ring);
  }
  isochart::report(progress, isochart::Stage::Sampling, 1.0);
  return s;
}

long long count_covered(const AtlasCharts& a, const Placement& pl) {
  const int nc = static_cast<int>(a.charts.size());
  std::vector<long long> counts(nc, 0);
  tbb::parallel_for(0, nc, [&](int c) {
    counts[c] = static_cast<long long>(
        rasterize_chart(a.charts[c], pl.texel[c], pl.mirrored[c], pl.width, pl.height, false).size());
  });
  long long total = 0;
  for (long long n : counts) total += n;
  return total;
}

}  // namespace mcgim::detail
