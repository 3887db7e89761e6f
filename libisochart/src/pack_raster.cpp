#include "pack_raster.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <utility>

namespace isochart::pack_detail {

namespace {

// Texel coordinates are below ~2^15, so 1e-7 texel is far above double round-off and far
// below anything visible; widening every test by it keeps rasterization conservative when
// a vertex or edge falls exactly on a texel boundary.
constexpr double kEps = 1e-7;

void set_range(Word* row, int c0, int c1) {
  for (int c = c0; c <= c1;) {
    const int w = c / kWordBits, b = c % kWordBits;
    const int n = std::min(kWordBits - b, c1 - c + 1);
    const Word mask = n == kWordBits ? ~Word{0} : (((Word{1} << n) - 1) << b);
    row[w] |= mask;
    c += n;
  }
}

// Conservative coverage of one triangle: for each texel row, the x-extent of the triangle
// clipped to the row's slab is exact (the clipped polygon is convex and its vertices lie on
// the triangle's edges), so every texel that the triangle touches in that row is set.
void rasterize_triangle(const Vec2d& a, const Vec2d& b, const Vec2d& c, ChartRaster& r) {
  const Vec2d v[3] = {a, b, c};
  const double ylo = std::min({a.y, b.y, c.y}), yhi = std::max({a.y, b.y, c.y});
  const int r0 = std::max(0, static_cast<int>(std::floor(ylo - kEps)));
  const int r1 = std::min(r.h - 1, static_cast<int>(std::floor(yhi + kEps)));
  if (r0 == r1) {  // within one row: the slab holds the whole triangle
    const int c0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}) - kEps)));
    const int c1 = std::min(r.w - 1, static_cast<int>(std::floor(std::max({a.x, b.x, c.x}) + kEps)));
    if (c0 <= c1) set_range(&r.bits[static_cast<std::size_t>(r0) * r.words], c0, c1);
    return;
  }
  for (int row = r0; row <= r1; ++row) {
    const double s0 = row - kEps, s1 = row + 1 + kEps;
    double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin;
    for (int k = 0; k < 3; ++k) {
      const Vec2d& p = v[k];
      const Vec2d& q = v[(k + 1) % 3];
      const double lo = std::max(std::min(p.y, q.y), s0), hi = std::min(std::max(p.y, q.y), s1);
      if (lo > hi) continue;
      if (p.y == q.y) {
        xmin = std::min({xmin, p.x, q.x});
        xmax = std::max({xmax, p.x, q.x});
        continue;
      }
      const double t0 = (lo - p.y) / (q.y - p.y), t1 = (hi - p.y) / (q.y - p.y);
      const double x0 = p.x + (q.x - p.x) * t0, x1 = p.x + (q.x - p.x) * t1;
      xmin = std::min({xmin, x0, x1});
      xmax = std::max({xmax, x0, x1});
    }
    if (xmin > xmax) continue;
    const int c0 = std::max(0, static_cast<int>(std::floor(xmin - kEps)));
    const int c1 = std::min(r.w - 1, static_cast<int>(std::floor(xmax + kEps)));
    if (c0 <= c1) set_range(&r.bits[static_cast<std::size_t>(row) * r.words], c0, c1);
  }
}

// Largest rectangle of set texels, found on 4×4 cells that are entirely set (a cell grid is
// 16 times smaller and a rectangle is only a quick-rejection aid): histogram method.
Rect largest_rectangle(const ChartRaster& r) {
  constexpr int kCell = 4;
  const int cw = r.w / kCell, ch = r.h / kCell;
  if (cw == 0 || ch == 0) return {};
  std::vector<int> height(cw, 0);
  std::vector<int> stack;
  Rect best;
  for (int cy = 0; cy < ch; ++cy) {
    for (int k = 0; k < r.words; ++k) {
      Word all = ~Word{0};
      for (int d = 0; d < kCell; ++d) all &= r.bits[static_cast<std::size_t>(cy * kCell + d) * r.words + k];
      for (int b = 0; b < kWordBits / kCell; ++b) {
        const int cx = k * (kWordBits / kCell) + b;
        if (cx >= cw) break;
        height[cx] = ((all >> (b * kCell)) & 0xFu) == 0xFu ? height[cx] + 1 : 0;
      }
    }
    stack.clear();
    for (int c = 0; c <= cw; ++c) {
      const int hc = c < cw ? height[c] : 0;
      while (!stack.empty() && height[stack.back()] >= hc) {
        const int top = stack.back();
        stack.pop_back();
        const int left = stack.empty() ? 0 : stack.back() + 1;
        const Rect cand{left * kCell, (cy - height[top] + 1) * kCell, (c - left) * kCell,
                        height[top] * kCell};
        if (cand.area() > best.area()) best = cand;
      }
      stack.push_back(c);
    }
  }
  return best;
}

// Sizes the raster around the points; allocates it and returns the points in raster
// coordinates unless it exceeds max_w × max_h.
std::vector<Vec2d> start_raster(const std::vector<Vec2d>& points, ChartRaster& r, int max_w = 1 << 30,
                                int max_h = 1 << 30) {
  double minx = std::numeric_limits<double>::infinity(), miny = minx, maxx = -minx, maxy = -minx;
  for (const Vec2d& p : points) {
    minx = std::min(minx, p.x);
    miny = std::min(miny, p.y);
    maxx = std::max(maxx, p.x);
    maxy = std::max(maxy, p.y);
  }
  r.origin = {std::floor(minx - kEps), std::floor(miny - kEps)};
  const double w = std::floor(maxx + kEps) - r.origin.x + 1, h = std::floor(maxy + kEps) - r.origin.y + 1;
  r.w = static_cast<int>(std::min(w, static_cast<double>(max_w) + 1));
  r.h = static_cast<int>(std::min(h, static_cast<double>(max_h) + 1));
  if (r.w > max_w || r.h > max_h) return {};
  r.words = words_for(r.w);
  r.bits.assign(static_cast<std::size_t>(r.h) * r.words, 0);
  std::vector<Vec2d> local(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) local[i] = points[i] - r.origin;
  return local;
}

// Profiles, quick-rejection data, edge masks and the contact ring of a filled raster. Run 16
// times per chart and scale tried; an AVX2 copy where the CPU has it (integer work, same result).
__attribute__((target_clones("avx2", "default"))) void finish_raster(ChartRaster& r) {
  r.col_lo.assign(r.w, r.h);
  r.col_hi.assign(r.w, -1);
  r.row_lo.assign(r.h, r.w);
  r.row_hi.assign(r.h, -1);
  r.row_first_word.assign(r.h, r.words);
  r.row_last_word.assign(r.h, -1);
  for (int row = 0; row < r.h; ++row) {
    const Word* bits = &r.bits[static_cast<std::size_t>(row) * r.words];
    for (int k = 0; k < r.words; ++k) {
      Word v = bits[k];
      if (!v) continue;
      r.row_first_word[row] = std::min(r.row_first_word[row], k);
      r.row_last_word[row] = k;
      r.texels += popcount(v);
      r.row_lo[row] = std::min(r.row_lo[row], k * kWordBits + __builtin_ctzll(v));
      r.row_hi[row] = k * kWordBits + (kWordBits - 1 - __builtin_clzll(v));
      while (v) {
        const int c = k * kWordBits + __builtin_ctzll(v);
        v &= v - 1;
        r.col_lo[c] = std::min(r.col_lo[c], row);
        r.col_hi[c] = row;
      }
    }
  }
  r.core = largest_rectangle(r);

  // Largest set square with its lower-left corner at each cell, then the largest per region
  // of a 3×3 grid over the raster. Large rasters use cells of 2×2 or 4×4 texels (a cell is
  // set when all its texels are), which keeps this linear in words rather than texels.
  {
    constexpr int kCap = 63, kGrid = 3;
    const int cell = std::max(r.w, r.h) >= 256 ? 4 : std::max(r.w, r.h) >= 64 ? 2 : 1;
    const int cw = r.w / cell, ch = r.h / cell;
    const Word full = (Word{1} << cell) - 1;
    std::vector<unsigned char> square(static_cast<std::size_t>(cw + 1) * (ch + 1), 0);
    auto at = [&](int c, int row) -> unsigned char& {
      return square[static_cast<std::size_t>(row) * (cw + 1) + c];
    };
    std::array<Rect, kGrid * kGrid> best{};
    std::vector<Word> all(r.words);
    std::vector<int> grid_col(cw);  // grid column of each cell column, out of the inner loop
    for (int c = 0; c < cw; ++c) grid_col[c] = c * kGrid / cw;
    for (int row = ch - 1; row >= 0; --row) {
      Rect* best_row = &best[(row * kGrid / ch) * kGrid];
      std::fill(all.begin(), all.end(), ~Word{0});
      for (int d = 0; d < cell; ++d)
        for (int k = 0; k < r.words; ++k)
          all[k] &= r.bits[static_cast<std::size_t>(row * cell + d) * r.words + k];
      for (int c = cw - 1; c >= 0; --c) {
        const int bit = c * cell;
        const bool set = ((all[bit / kWordBits] >> (bit % kWordBits)) & full) == full;
        const int v =
            set ? std::min(kCap, 1 + std::min({at(c, row + 1), at(c + 1, row), at(c + 1, row + 1)})) : 0;
        at(c, row) = static_cast<unsigned char>(v);
        Rect& b = best_row[grid_col[c]];
        if (v >= b.w) b = {c, row, v, v};
      }
    }
    for (const Rect& b : best)
      if (b.w * cell >= 2)
        r.probes.push_back({b.x * cell, b.y * cell, std::min(kCap, b.w * cell), std::min(kCap, b.w * cell)});
    std::sort(r.probes.begin(), r.probes.end(), [](const Rect& a, const Rect& b) {
      return a.w != b.w ? a.w > b.w : (a.y != b.y ? a.y < b.y : a.x < b.x);
    });
  }

  // Edge masks: 0 = top edge (M(c,r) and not M(c,r+1)), 1 = bottom, 2 = right, 3 = left.
  for (int row = 0; row < r.h; ++row) {
    const Word* m = &r.bits[static_cast<std::size_t>(row) * r.words];
    const Word* above = row + 1 < r.h ? m + r.words : nullptr;
    const Word* below = row > 0 ? m - r.words : nullptr;
    for (int k = r.row_first_word[row]; k <= r.row_last_word[row]; ++k) {
      const Word v = m[k];
      if (!v) continue;
      const Word next_hi = k + 1 < r.words ? m[k + 1] << (kWordBits - 1) : 0;  // bit c+1 → c
      const Word prev_lo = k > 0 ? m[k - 1] >> (kWordBits - 1) : 0;            // bit c−1 → c
      const Word e[4] = {v & ~(above ? above[k] : 0), v & ~(below ? below[k] : 0), v & ~((v >> 1) | next_hi),
                         v & ~((v << 1) | prev_lo)};
      for (int d = 0; d < 4; ++d)
        if (e[d]) r.edge[d].push_back({row, k, e[d]});
    }
  }

  // Rows in breadth-first bisection order: a collision is usually found within a few rows.
  r.test_rows.reserve(r.h);
  std::deque<std::pair<int, int>> intervals{{0, r.h - 1}};
  while (!intervals.empty()) {
    const auto [lo, hi] = intervals.front();
    intervals.pop_front();
    if (lo > hi) continue;
    const int mid = lo + (hi - lo) / 2;
    if (r.row_first_word[mid] <= r.row_last_word[mid]) r.test_rows.push_back(mid);
    intervals.emplace_back(lo, mid - 1);
    intervals.emplace_back(mid + 1, hi);
  }

  std::vector<Word> ring = dilate(r, 1, r.ring_words);
  std::vector<Word> shifted(r.ring_words);
  for (int row = 0; row < r.h; ++row) {
    // Clear the chart itself (at offset (1, 1)) from its dilation, leaving the ring.
    std::fill(shifted.begin(), shifted.end(), 0);
    or_shifted(shifted.data(), r.ring_words, &r.bits[static_cast<std::size_t>(row) * r.words], r.words, 1);
    Word* o = &ring[static_cast<std::size_t>(row + 1) * r.ring_words];
    for (int k = 0; k < r.ring_words; ++k) o[k] &= ~shifted[k];
  }
  r.ring = std::move(ring);
  const int last = r.w + 1;
  for (int row = 0; row < r.h + 2; ++row) {
    const Word* o = &r.ring[static_cast<std::size_t>(row) * r.ring_words];
    int count = 0;
    for (int k = 0; k < r.ring_words; ++k) count += popcount(o[k]);
    r.ring_size += count;
    if (row == 0) r.ring_bottom = count;
    if (row == r.h + 1) r.ring_top = count;
    r.ring_left += o[0] & 1u;
    r.ring_right += (o[last / kWordBits] >> (last % kWordBits)) & 1u;
  }
}

}  // namespace

void or_shifted(Word* dst, int ndst, const Word* src, int nsrc, int shift) {
  const int woff = shift / kWordBits, bit = shift % kWordBits;
  for (int k = 0; k < nsrc; ++k) {
    const Word v = src[k];
    if (!v) continue;
    const int i = k + woff;
    if (i < ndst) dst[i] |= v << bit;
    if (bit && i + 1 < ndst) dst[i + 1] |= v >> (kWordBits - bit);
  }
}

std::vector<Word> dilate(const ChartRaster& r, int g, int& words_out) {
  const int wd = r.w + 2 * g, hd = r.h + 2 * g;
  words_out = words_for(wd);
  std::vector<Word> horizontal(static_cast<std::size_t>(r.h) * words_out, 0);
  for (int row = 0; row < r.h; ++row)
    for (int d = 0; d <= 2 * g; ++d)
      or_shifted(&horizontal[static_cast<std::size_t>(row) * words_out], words_out,
                 &r.bits[static_cast<std::size_t>(row) * r.words], r.words, d);
  std::vector<Word> out(static_cast<std::size_t>(hd) * words_out, 0);
  for (int row = 0; row < hd; ++row) {
    Word* o = &out[static_cast<std::size_t>(row) * words_out];
    for (int src = std::max(0, row - 2 * g); src <= std::min(r.h - 1, row); ++src) {
      const Word* s = &horizontal[static_cast<std::size_t>(src) * words_out];
      for (int k = 0; k < words_out; ++k) o[k] |= s[k];
    }
  }
  return out;
}

ChartOutline chart_outline(const std::vector<Vec2d>& uv, const std::vector<Face>& faces) {
  ChartOutline out;
  double total = 0;
  for (const Face& f : faces) total += std::abs(signed_area(uv[f[0]], uv[f[1]], uv[f[2]]));
  // Triangles this thin could change sign under rotation round-off: treat them as bad.
  const double tiny = 1e-12 * total;
  std::vector<std::pair<std::pair<int, int>, int>> halfedges;
  halfedges.reserve(3 * faces.size());
  std::vector<char> used(uv.size(), 0);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const Face& f = faces[i];
    if (signed_area(uv[f[0]], uv[f[1]], uv[f[2]]) <= tiny) out.bad_faces.push_back(static_cast<int>(i));
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      used[a] = 1;
      if (a < b)
        halfedges.push_back({{a, b}, 1});
      else if (b < a)
        halfedges.push_back({{b, a}, -1});
    }
  }
  std::sort(halfedges.begin(), halfedges.end());
  for (std::size_t i = 0; i < halfedges.size();) {
    std::size_t j = i;
    int net = 0;
    for (; j < halfedges.size() && halfedges[j].first == halfedges[i].first; ++j) net += halfedges[j].second;
    const auto [a, b] = halfedges[i].first;
    for (int m = 0; m < std::abs(net); ++m)
      out.boundary.push_back(net > 0 ? std::array<int, 2>{a, b} : std::array<int, 2>{b, a});
    i = j;
  }
  for (std::size_t v = 0; v < uv.size(); ++v)
    if (!used[v]) out.lone_vertices.push_back(static_cast<int>(v));
  return out;
}

ChartRaster rasterize_chart(const std::vector<Vec2d>& points, const std::vector<Face>& faces,
                            const ChartOutline& outline, int max_w, int max_h) {
  ChartRaster r;
  const std::vector<Vec2d> local = start_raster(points, r, max_w, max_h);
  if (r.w > max_w || r.h > max_h) return r;
  // Texels the chain touches.
  for (const auto& e : outline.boundary) rasterize_triangle(local[e[0]], local[e[1]], local[e[1]], r);
  for (const int f : outline.bad_faces)
    rasterize_triangle(local[faces[f][0]], local[faces[f][1]], local[faces[f][2]], r);
  for (const int v : outline.lone_vertices) rasterize_triangle(local[v], local[v], local[v], r);
  // Texel centres with a nonzero winding number: crossings of each row's centre line, with
  // the half-open rule on y so that a vertex on the line is counted once.
  std::vector<int> start(r.h + 1, 0);
  auto rows_of = [](const Vec2d& p, const Vec2d& q, int h, int& r0, int& r1) {
    const double ylo = std::min(p.y, q.y), yhi = std::max(p.y, q.y);
    r0 = std::max(0, static_cast<int>(std::ceil(ylo - 0.5)));
    r1 = std::min(h - 1, static_cast<int>(std::ceil(yhi - 0.5)) - 1);
  };
  for (const auto& e : outline.boundary) {
    int r0, r1;
    rows_of(local[e[0]], local[e[1]], r.h, r0, r1);
    for (int row = r0; row <= r1; ++row) ++start[row + 1];
  }
  for (int row = 0; row < r.h; ++row) start[row + 1] += start[row];
  std::vector<std::pair<double, int>> crossings(start[r.h]);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (const auto& e : outline.boundary) {
    const Vec2d& p = local[e[0]];
    const Vec2d& q = local[e[1]];
    int r0, r1;
    rows_of(p, q, r.h, r0, r1);
    const double slope = (q.x - p.x) / (q.y - p.y);
    const int dir = q.y > p.y ? 1 : -1;
    for (int row = r0; row <= r1; ++row) crossings[fill[row]++] = {p.x + (row + 0.5 - p.y) * slope, dir};
  }
  for (int row = 0; row < r.h; ++row) {
    auto first = crossings.begin() + start[row], last = crossings.begin() + start[row + 1];
    std::sort(first, last);
    int winding = 0;
    for (auto it = first; it != last; ++it) {
      winding += it->second;
      if (winding == 0 || it + 1 == last) continue;
      const int c0 = std::max(0, static_cast<int>(std::ceil(it->first - 0.5)));
      const int c1 = std::min(r.w - 1, static_cast<int>(std::ceil((it + 1)->first - 0.5)) - 1);
      if (c0 <= c1) set_range(&r.bits[static_cast<std::size_t>(row) * r.words], c0, c1);
    }
  }
  finish_raster(r);
  return r;
}

ChartRaster rasterize_triangles(const std::vector<Vec2d>& points, const std::vector<Face>& faces) {
  ChartRaster r;
  const std::vector<Vec2d> local = start_raster(points, r);
  for (const Face& f : faces) rasterize_triangle(local[f[0]], local[f[1]], local[f[2]], r);
  for (const Vec2d& p : local) rasterize_triangle(p, p, p, r);
  finish_raster(r);
  return r;
}

std::vector<Vec2d> convex_hull(std::vector<Vec2d> p) {
  std::sort(p.begin(), p.end(),
            [](const Vec2d& a, const Vec2d& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return p;
  std::vector<Vec2d> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 1] - h[k - 2], p[i] - h[k - 2]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 1] - h[k - 2], p[i] - h[k - 2]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

double min_area_rect_angle(const std::vector<Vec2d>& points) {
  const std::vector<Vec2d> hull = convex_hull(points);
  if (hull.size() < 2) return 0;
  if (hull.size() == 2) {
    const Vec2d d = hull[1] - hull[0];
    return -std::atan2(d.y, d.x);
  }
  return min_area_rect(hull).angle;
}

HullRect min_area_rect(const std::vector<Vec2d>& hull) {
  HullRect best;
  best.area = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Vec2d d = normalized(hull[(i + 1) % hull.size()] - hull[i]);
    // Coordinates along the edge and across it: the rectangle with one side on this edge.
    double u0 = std::numeric_limits<double>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
    for (const Vec2d& p : hull) {
      const double u = dot(p, d), v = cross(d, p);
      u0 = std::min(u0, u);
      u1 = std::max(u1, u);
      v0 = std::min(v0, v);
      v1 = std::max(v1, v);
    }
    const double area = (u1 - u0) * (v1 - v0);
    if (area < best.area * (1 - 1e-12)) {
      best.area = area;
      best.angle = -std::atan2(d.y, d.x);
    }
  }
  return best;
}

}  // namespace isochart::pack_detail
