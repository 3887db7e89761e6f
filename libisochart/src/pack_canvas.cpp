#include "pack_canvas.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>

namespace isochart::pack_detail {

namespace {

// Bit j (j < 8) set where byte j of `bytes` is at least `w`; bytes and w at most 127, so
// the per-byte subtraction never borrows across bytes.
inline unsigned bytes_at_least(const unsigned char* bytes, int w) {
  std::uint64_t v;
  std::memcpy(&v, bytes, sizeof v);
  const std::uint64_t high =
      ((v | 0x8080808080808080ULL) - 0x0101010101010101ULL * static_cast<unsigned>(w)) &
      0x8080808080808080ULL;
  return static_cast<unsigned>(((high >> 7) * 0x0102040810204080ULL) >> 56);
}

// Bits [shift, shift + 64) of a canvas row, for a raster word placed at bit offset `shift`.
inline Word canvas_word(const Word* row, int word, int bit) {
  return bit == 0 ? row[word] : (row[word] >> bit) | (row[word + 1] << (kWordBits - bit));
}

}  // namespace

Canvas::Canvas(int limit_w, int limit_h, int gutter, double growth_weight)
    : limit_w_(limit_w), limit_h_(limit_h), gutter_(gutter), growth_weight_(growth_weight) {
  // Room for any packing within the limits around a centred first chart, plus the gutter,
  // plus one spare word per row so that shifted reads never leave the row.
  width_ = ((2 * (limit_w + gutter) + 4 + kWordBits - 1) / kWordBits) * kWordBits;
  row_words_ = width_ / kWordBits + 1;
  height_ = 2 * (limit_h + gutter) + 4;
  bits_.assign(static_cast<std::size_t>(height_) * row_words_, 0);
  horizon_[static_cast<int>(Side::Top)].assign(width_, kNone);
  horizon_[static_cast<int>(Side::Bottom)].assign(width_, kNone);
  horizon_[static_cast<int>(Side::Right)].assign(height_, kNone);
  horizon_[static_cast<int>(Side::Left)].assign(height_, kNone);
  blocks_x_ = width_ / kBlock;
  blocks_y_ = (height_ + kBlock - 1) / kBlock;
  block_count_.assign(static_cast<std::size_t>(blocks_x_) * blocks_y_, 0);
  block_sat_.assign(static_cast<std::size_t>(blocks_x_ + 1) * (blocks_y_ + 1), 0);
  // On the empty canvas the largest free square at (x, y) reaches the canvas's far sides.
  // (16 spare bytes: rows are read 16 bytes at a time.)
  square_.resize(static_cast<std::size_t>(width_) * height_ + 16);
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x)
      square_[static_cast<std::size_t>(y) * width_ + x] =
          static_cast<unsigned char>(std::min({kSquareCap, width_ - x, height_ - y}));
  block_square_.assign(static_cast<std::size_t>(blocks_x_) * blocks_y_, 0);
  for (int by = 0; by < blocks_y_; ++by)
    for (int bx = 0; bx < blocks_x_; ++bx)
      block_square_[static_cast<std::size_t>(by) * blocks_x_ + bx] =
          static_cast<unsigned char>(std::min({kSquareCap, width_ - bx * kBlock, height_ - by * kBlock}));
  supers_x_ = (blocks_x_ + kSuper - 1) / kSuper;
  supers_y_ = (blocks_y_ + kSuper - 1) / kSuper;
  super_square_.assign(static_cast<std::size_t>(supers_x_) * supers_y_, kSquareCap);
}

void Canvas::update_free_squares(int x0, int y0, int x1, int y1) {
  // A square's lower-left corner sees only texels above and to the right of it, so only
  // corners below/left of the change, within the cap, can shrink.
  x0 = std::max(0, x0 - kSquareCap);
  y0 = std::max(0, y0 - kSquareCap);
  x1 = std::min(width_, x1);
  y1 = std::min(height_, y1);
  auto at = [this](int x, int y) -> int {
    return x < width_ && y < height_ ? square_[static_cast<std::size_t>(y) * width_ + x] : 0;
  };
  // square(x, y) = 0 on a set texel, else min(cap, 1 + min(square(x, y+1), square(x+1, y),
  // square(x+1, y+1))), outside the canvas 0. Rows run right to left carrying the two values
  // to the right; whole words of set texels are cleared at once (most of a busy canvas).
  for (int y = y1 - 1; y >= y0; --y) {
    unsigned char* row = &square_[static_cast<std::size_t>(y) * width_];
    const bool top = y + 1 >= height_;
    const unsigned char* up = top ? nullptr : row + width_;
    const Word* bits = &bits_[static_cast<std::size_t>(y) * row_words_];
    int right = at(x1, y), up_right = at(x1, y + 1);
    int x = x1 - 1;
    while (x >= x0) {
      if ((x & (kWordBits - 1)) == kWordBits - 1 && x - (kWordBits - 1) >= x0 &&
          bits[x / kWordBits] == ~Word{0}) {
        std::memset(row + x - (kWordBits - 1), 0, kWordBits);
        x -= kWordBits;
        right = 0;
        up_right = top ? 0 : up[x + 1];
        continue;
      }
      const int u = top ? 0 : up[x];
      const int v = (bits[x / kWordBits] >> (x % kWordBits)) & 1u
                        ? 0
                        : std::min(kSquareCap, 1 + std::min({u, right, up_right}));
      row[x] = static_cast<unsigned char>(v);
      right = v;
      up_right = u;
      --x;
    }
  }
  for (int by = y0 / kBlock; by <= (y1 - 1) / kBlock; ++by)
    for (int bx = x0 / kBlock; bx <= (x1 - 1) / kBlock; ++bx) {
      int m = 0;
      for (int y = by * kBlock; y < std::min(height_, (by + 1) * kBlock); ++y)
        for (int x = bx * kBlock; x < (bx + 1) * kBlock; ++x) m = std::max(m, at(x, y));
      block_square_[static_cast<std::size_t>(by) * blocks_x_ + bx] = static_cast<unsigned char>(m);
    }
  for (int sy = y0 / kBlock / kSuper; sy <= (y1 - 1) / kBlock / kSuper; ++sy)
    for (int sx = x0 / kBlock / kSuper; sx <= (x1 - 1) / kBlock / kSuper; ++sx) {
      int m = 0;
      for (int by = sy * kSuper; by < std::min(blocks_y_, (sy + 1) * kSuper); ++by)
        for (int bx = sx * kSuper; bx < std::min(blocks_x_, (sx + 1) * kSuper); ++bx)
          m = std::max<int>(m, block_square_[static_cast<std::size_t>(by) * blocks_x_ + bx]);
      super_square_[static_cast<std::size_t>(sy) * supers_x_ + sx] = static_cast<unsigned char>(m);
    }
}

int Canvas::max_free_square(int x0, int y0, int x1, int y1) const {
  int m = 0;
  for (int by = std::max(0, y0) / kBlock; by <= std::min(height_ - 1, y1) / kBlock; ++by)
    for (int bx = std::max(0, x0) / kBlock; bx <= std::min(width_ - 1, x1) / kBlock; ++bx)
      m = std::max<int>(m, block_square_[static_cast<std::size_t>(by) * blocks_x_ + bx]);
  return m;
}

Candidate Canvas::centre(const ChartRaster& r) const {
  if (!fits_limits(r)) return {};
  return {true, (width_ - r.w) / 2, (height_ - r.h) / 2, 0.0};
}

bool Canvas::collides(const ChartRaster& r, int x, int y) const {
  const int wx = x / kWordBits, bit = x % kWordBits;
  for (const int row : r.test_rows) {
    const Word* m = &r.bits[static_cast<std::size_t>(row) * r.words];
    const Word* c = &bits_[static_cast<std::size_t>(y + row) * row_words_];
    for (int k = r.row_first_word[row]; k <= r.row_last_word[row]; ++k)
      if (m[k] & canvas_word(c, wx + k, bit)) return true;
  }
  return false;
}

unsigned Canvas::right_steps(const std::vector<MaskWord>& right_edge, int x0, int y, int steps) const {
  // Edge texel at raster column c lands on canvas column x + c at position x: for x0 + 1 ..
  // x0 + steps that is the run of canvas bits starting at x0 + 1 + c.
  const Word window = (Word{1} << steps) - 1;
  unsigned hits = 0;
  for (const MaskWord& m : right_edge) {
    const Word* row = &bits_[static_cast<std::size_t>(y + m.row) * row_words_];
    for (Word b = m.bits; b; b &= b - 1) {
      const int a = x0 + 1 + m.word * kWordBits + __builtin_ctzll(b);
      const int w = a / kWordBits, bit = a % kWordBits;
      Word v = row[w] >> bit;
      if (bit + steps > kWordBits) v |= row[w + 1] << (kWordBits - bit);
      hits |= static_cast<unsigned>(v & window);
    }
  }
  return hits;
}

bool Canvas::collides(const std::vector<MaskWord>& mask, int x, int y) const {
  const int wx = x / kWordBits, bit = x % kWordBits;
  for (const MaskWord& m : mask)
    if (m.bits & canvas_word(&bits_[static_cast<std::size_t>(y + m.row) * row_words_], wx + m.word, bit))
      return true;
  return false;
}

int Canvas::contact(const ChartRaster& r, int x, int y) const {
  // The ring's origin is at (x − 1, y − 1). Outside the bounding box counts as touching:
  // a chart against the box side leaves no sliver there.
  const int ox = x - 1, wx = ox / kWordBits, bit = ox % kWordBits;
  const bool left_wall = x == box_.x, right_wall = x + r.w == box_.x + box_.w;
  int n = 0;
  for (int row = 0; row < r.h + 2; ++row) {
    const Word* m = &r.ring[static_cast<std::size_t>(row) * r.ring_words];
    const int cy = y - 1 + row;
    if (cy < box_.y || cy >= box_.y + box_.h) {
      for (int k = 0; k < r.ring_words; ++k) n += popcount(m[k]);
      continue;
    }
    const Word* c = &bits_[static_cast<std::size_t>(cy) * row_words_];
    Word first = 0, last = 0;
    for (int k = 0; k < r.ring_words; ++k) {
      const Word cw = canvas_word(c, wx + k, bit);
      n += popcount(m[k] & cw);
      if (k == 0) first = cw;
      if (k == (r.w + 1) / kWordBits) last = cw;
    }
    const int lb = (r.w + 1) % kWordBits;
    if (left_wall && (m[0] & 1u) && !(first & 1u)) ++n;
    if (right_wall && ((m[(r.w + 1) / kWordBits] >> lb) & 1u) && !((last >> lb) & 1u)) ++n;
  }
  return n;
}

long long Canvas::block_sum(int bx0, int by0, int bx1, int by1) const {
  const int stride = blocks_x_ + 1;
  return block_sat_[static_cast<std::size_t>(by1) * stride + bx1] -
         block_sat_[static_cast<std::size_t>(by0) * stride + bx1] -
         block_sat_[static_cast<std::size_t>(by1) * stride + bx0] +
         block_sat_[static_cast<std::size_t>(by0) * stride + bx0];
}

bool Canvas::surely_occupied(int x0, int y0, int x1, int y1) const {
  const int bx0 = (std::max(x0, 0) + kBlock - 1) / kBlock, by0 = (std::max(y0, 0) + kBlock - 1) / kBlock;
  const int bx1 = std::min(std::max(x1, 0) / kBlock, blocks_x_);
  const int by1 = std::min(std::max(y1, 0) / kBlock, blocks_y_);
  if (bx0 >= bx1 || by0 >= by1) return false;
  return block_sum(bx0, by0, bx1, by1) > 0;
}

bool Canvas::surely_empty(int x0, int y0, int x1, int y1) const {
  const int bx0 = std::max(x0, 0) / kBlock, by0 = std::max(y0, 0) / kBlock;
  const int bx1 = std::min((std::max(x1, 0) + kBlock - 1) / kBlock, blocks_x_);
  const int by1 = std::min((std::max(y1, 0) + kBlock - 1) / kBlock, blocks_y_);
  if (bx0 >= bx1 || by0 >= by1) return true;
  return block_sum(bx0, by0, bx1, by1) == 0;
}

void Canvas::update_blocks(int x0, int y0, int x1, int y1) {
  const int bx0 = std::max(x0, 0) / kBlock, by0 = std::max(y0, 0) / kBlock;
  const int bx1 = std::min((x1 + kBlock - 1) / kBlock, blocks_x_);
  const int by1 = std::min((y1 + kBlock - 1) / kBlock, blocks_y_);
  for (int by = by0; by < by1; ++by)
    for (int bx = bx0; bx < bx1; ++bx) {
      int count = 0;
      const int word = bx * kBlock / kWordBits, bit = bx * kBlock % kWordBits;
      for (int y = by * kBlock; y < std::min((by + 1) * kBlock, height_); ++y)
        count += popcount((bits_[static_cast<std::size_t>(y) * row_words_ + word] >> bit) & 0xFFu);
      block_count_[static_cast<std::size_t>(by) * blocks_x_ + bx] = count;
    }
  // Only sums over rectangles reaching past (bx0, by0) changed: the entries right of and above it.
  const int stride = blocks_x_ + 1;
  for (int by = by0; by < blocks_y_; ++by)
    for (int bx = bx0; bx < blocks_x_; ++bx)
      block_sat_[static_cast<std::size_t>(by + 1) * stride + bx + 1] =
          block_count_[static_cast<std::size_t>(by) * blocks_x_ + bx] +
          block_sat_[static_cast<std::size_t>(by) * stride + bx + 1] +
          block_sat_[static_cast<std::size_t>(by + 1) * stride + bx] -
          block_sat_[static_cast<std::size_t>(by) * stride + bx];
}

bool Canvas::surely_crowded(int x0, int y0, int x1, int y1, long long texels) const {
  // Occupied texels in the blocks fully inside the rectangle bound its occupancy from below.
  const int bx0 = (std::max(x0, 0) + kBlock - 1) / kBlock, by0 = (std::max(y0, 0) + kBlock - 1) / kBlock;
  const int bx1 = std::min(std::max(x1, 0) / kBlock, blocks_x_);
  const int by1 = std::min(std::max(y1, 0) / kBlock, blocks_y_);
  if (bx0 >= bx1 || by0 >= by1) return false;
  const long long area = static_cast<long long>(x1 - x0) * (y1 - y0);
  return area - block_sum(bx0, by0, bx1, by1) < texels;
}

void Canvas::search_block(const ChartRaster& r, int rotation, int bx, int by, int bxe, int bye,
                          Candidate& best) const {
  const int xmin = box_.x, xmax = box_.x + box_.w - r.w;
  const int ymin = box_.y, ymax = box_.y + box_.h - r.h;
  const Rect& core = r.core;
  // Each probe square must land on a free square as large: no block of corners offers one.
  for (const Rect& p : r.probes)
    if (max_free_square(bx + p.x, by + p.y, bxe + p.x, bye + p.y) < p.w) return;
  // Every position in this block covers the core's common part: one test rejects all.
  if (core.w > bxe - bx && core.h > bye - by &&
      surely_occupied(bxe + core.x, bye + core.y, bx + core.x + core.w, by + core.y + core.h))
    return;
  // Too few free texels where any of these positions could put the chart.
  if (surely_crowded(bx, by, bxe + r.w, bye + r.h, r.texels)) return;
  // Away from the box sides and with nothing near, no position touches anything.
  if (bx > xmin && bxe < xmax && by > ymin && bye < ymax &&
      surely_empty(bx - 1, by - 1, bxe + r.w + 1, bye + r.h + 1))
    return;
  // Feasibility of the positions of the block and of the ring of positions around it
  // (outside the allowed range counts as blocked, like a wall). `from_left`/`from_below`:
  // the neighbour position is free, so only the texels the move adds need testing.
  // Positions in range whose probes all land on large enough free squares, one bit per
  // position of a row of the block (bit j: x = bx − 1 + j).
  constexpr int kSpan = kBlock + 2;
  unsigned candidates[kSpan];
  for (int y = by - 1; y <= bye + 1; ++y) {
    unsigned mask = 0;
    if (y >= ymin && y <= ymax) {
      const int lo = std::max(bx - 1, xmin), hi = std::min(bxe + 1, xmax);
      for (int x = lo; x <= hi; ++x) mask |= 1u << (x - bx + 1);
      for (const Rect& p : r.probes) {
        if (!mask) break;
        const unsigned char* row = &square_[static_cast<std::size_t>(y + p.y) * width_ + bx - 1 + p.x];
        mask &= bytes_at_least(row, p.w) | (bytes_at_least(row + 8, p.w) << 8);
      }
    }
    candidates[y - by + 1] = mask;
  }
  // Moves to the right along a row of positions, tested for all the row's positions in one
  // pass over the right-edge texels (most positions searched are free, so each edge test read
  // the whole mask): bit s − 1 of `steps` says the edge collides at x0 + s, x0 = bx − 1.
  unsigned steps = 0;
  int steps_row = kNone;
  auto right_step_collides = [&](int x, int y) {
    if (steps_row != y) {
      steps_row = y;
      steps = right_steps(r.edge[static_cast<int>(Side::Right)], bx - 1, y, bxe + 1 - (bx - 1));
    }
    return (steps >> (x - bx)) & 1u;
  };
  auto fits = [&](int x, int y, bool from_left, bool from_below) {
    if (!((candidates[y - by + 1] >> (x - bx + 1)) & 1u)) return false;
    if (surely_empty(x, y, x + r.w, y + r.h)) return true;
    if (from_left) return !right_step_collides(x, y);
    if (from_below) return !collides(r.edge[static_cast<int>(Side::Top)], x, y);
    if (surely_crowded(x, y, x + r.w, y + r.h, r.texels)) return false;
    if (core.w > 0 && surely_occupied(x + core.x, y + core.y, x + core.x + core.w, y + core.y + core.h))
      return false;
    return !collides(r, x, y);
  };
  bool free[kSpan][kSpan];
  for (int y = by - 1; y <= bye + 1; ++y)
    for (int x = bx - 1; x <= bxe + 1; ++x) {
      const int i = y - by + 1, j = x - bx + 1;
      free[i][j] = fits(x, y, j > 0 && free[i][j - 1], i > 0 && free[i - 1][j]);
    }
  // Only a position that cannot move one texel in two directions is a candidate: the best
  // fit sits in a corner of the free space, like a piece pushed down and sideways.
  for (int y = by; y <= bye; ++y)
    for (int x = bx; x <= bxe; ++x) {
      const int i = y - by + 1, j = x - bx + 1;
      if (!free[i][j]) continue;
      if (!free[i - 1][j] + !free[i + 1][j] + !free[i][j - 1] + !free[i][j + 1] < 2) continue;
      const int c = contact(r, x, y);
      const double fraction = static_cast<double>(c) / r.ring_size;
      if (c > 0 && (!best.valid || -fraction < best.cost)) best = {true, x, y, -fraction, rotation};
    }
}

Candidate Canvas::best_inside(const ChartRaster* rasters, int count) const {
  if (empty()) return {};
  // Blocks of positions to search, per rotation. When the raster has a probe square, only
  // positions whose largest probe's corner falls in a block of the free-square map offering
  // a large enough square can fit; the blocks of positions are aligned with that map.
  struct Task {
    int rotation, x0, y0, x1, y1;
  };
  std::vector<Task> tasks;
  for (int k = 0; k < count; ++k) {
    const ChartRaster& r = rasters[k];
    if (!fits_limits(r) || box_.w < r.w || box_.h < r.h) continue;
    const int xmin = box_.x, xmax = box_.x + box_.w - r.w;
    const int ymin = box_.y, ymax = box_.y + box_.h - r.h;
    const int square = r.probes.empty() ? 0 : r.probes[0].w;
    if (square > 1) {
      const int cx = r.probes[0].x, cy = r.probes[0].y;
      const int bx0 = (xmin + cx) / kBlock, bx1 = (xmax + cx) / kBlock;
      const int by0 = (ymin + cy) / kBlock, by1 = (ymax + cy) / kBlock;
      for (int sy = by0 / kSuper; sy <= by1 / kSuper; ++sy)
        for (int sx = bx0 / kSuper; sx <= bx1 / kSuper; ++sx) {
          if (super_square_[static_cast<std::size_t>(sy) * supers_x_ + sx] < square) continue;
          for (int by = std::max(by0, sy * kSuper); by <= std::min(by1, sy * kSuper + kSuper - 1); ++by)
            for (int bx = std::max(bx0, sx * kSuper); bx <= std::min(bx1, sx * kSuper + kSuper - 1); ++bx) {
              if (block_square_[static_cast<std::size_t>(by) * blocks_x_ + bx] < square) continue;
              tasks.push_back({k, std::max(xmin, bx * kBlock - cx), std::max(ymin, by * kBlock - cy),
                               std::min(xmax, bx * kBlock + kBlock - 1 - cx),
                               std::min(ymax, by * kBlock + kBlock - 1 - cy)});
            }
        }
    } else {
      for (int y = ymin; y <= ymax; y += kBlock)
        for (int x = xmin; x <= xmax; x += kBlock)
          tasks.push_back({k, x, y, std::min(xmax, x + kBlock - 1), std::min(ymax, y + kBlock - 1)});
    }
  }
  // All rotations of one region of the canvas are searched together: the rotations' tasks
  // read the same rows of the occupancy and free-square maps, which then stay in cache (the
  // maps of a 1024² packing are megabytes; rotation by rotation, each pass re-read them).
  // A counting sort by tile keeps this linear; the order changes no result (see `better`).
  {
    constexpr int kTileShift = 5;  // 32-texel tiles
    const int tx0 = box_.x >> kTileShift, ty0 = box_.y >> kTileShift;
    const int tiles_x = ((box_.x + box_.w) >> kTileShift) - tx0 + 1;
    const int tiles_y = ((box_.y + box_.h) >> kTileShift) - ty0 + 1;
    std::vector<int> start(static_cast<std::size_t>(tiles_x) * tiles_y + 1, 0);
    auto tile = [&](const Task& t) {
      return static_cast<std::size_t>((t.y0 >> kTileShift) - ty0) * tiles_x + ((t.x0 >> kTileShift) - tx0);
    };
    for (const Task& t : tasks) ++start[tile(t) + 1];
    for (std::size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
    std::vector<Task> sorted(tasks.size());
    for (const Task& t : tasks) sorted[start[tile(t)]++] = t;
    tasks.swap(sorted);
  }
  // A total order on candidates: higher contact fraction, then lower y, x, rotation.
  auto better = [](const Candidate& a, const Candidate& b) {
    if (!b.valid) return a.valid;
    if (!a.valid) return false;
    if (a.cost != b.cost) return a.cost < b.cost;
    if (a.y != b.y) return a.y < b.y;
    if (a.x != b.x) return a.x < b.x;
    return a.rotation < b.rotation;
  };
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, tasks.size()), Candidate{},
      [&](const tbb::blocked_range<std::size_t>& range, Candidate best) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          const Task& task = tasks[t];
          Candidate c;
          search_block(rasters[task.rotation], task.rotation, task.x0, task.y0, task.x1, task.y1, c);
          if (better(c, best)) best = c;
        }
        return best;
      },
      [&](const Candidate& a, const Candidate& b) { return better(a, b) ? a : b; });
}

// The column loops are the packer's hottest: an AVX2 copy runs where the CPU has it (8 lanes of
// integer max and sum instead of SSE2's emulated max); integer arithmetic, the same result.
__attribute__((target_clones("avx2", "default"))) Candidate Canvas::best_from_side(const ChartRaster& r,
                                                                                   Side side) const {
  if (empty() || !fits_limits(r)) return {};
  const bool vertical = side == Side::Top || side == Side::Bottom;
  const bool positive = side == Side::Top || side == Side::Right;
  const int n = vertical ? r.w : r.h, m = vertical ? r.h : r.w;
  // The chart's horizon facing the packing, in the side's coordinate (larger = closer to
  // the side), and the packing's horizon facing the side, in the same coordinate. Empty
  // chart columns get values that drop out of the max and clamp to zero in the waste.
  constexpr int kFar = 1 << 26;
  std::vector<int> near_max(n), near_sum(n);
  for (int c = 0; c < n; ++c) {
    const int lo = vertical ? r.col_lo[c] : r.row_lo[c], hi = vertical ? r.col_hi[c] : r.row_hi[c];
    near_max[c] = lo <= hi ? (positive ? lo : -hi) : kFar;
    near_sum[c] = lo <= hi ? near_max[c] : -kFar;
  }
  const std::vector<int>& horizon = horizon_[static_cast<int>(side)];
  const int a0 = vertical ? box_.x : box_.y, a1 = a0 + (vertical ? box_.w : box_.h);
  const int b0 = vertical ? box_.y : box_.x, b1 = b0 + (vertical ? box_.h : box_.w);
  const int slide_limit = vertical ? limit_w_ : limit_h_;
  const int insert_limit = vertical ? limit_h_ : limit_w_;
  // Offsets where the chart overlaps the packing along the side and the packing stays within
  // the limit.
  const int i_lo = std::max(a0 - n + 1, a1 - slide_limit), i_hi = std::min(a1 - 1, a0 + slide_limit - n);
  if (i_lo > i_hi) return {};
  // Where the packing has no texel in a column, space down to the far side of the box is lost.
  const int ground = positive ? b0 - 1 : -b1;
  std::vector<int> floor(horizon.begin() + i_lo, horizon.begin() + i_hi + n);
  for (int& f : floor) f = f == kNone ? ground : f;
  const int* F = floor.data() - i_lo;
  const double aspect = static_cast<double>(limit_w_) / limit_h_;
  auto effective_area = [aspect](int w, int h) {
    const double width = std::max(static_cast<double>(w), h * aspect);
    return width * width / aspect;
  };
  const double area_before = effective_area(box_.w, box_.h);

  Candidate best;
  for (int i = i_lo; i <= i_hi; ++i) {
    // How far the chart comes in: its horizon one texel beyond the packing's, where nearest.
    int val = kNone;
    const int* p = horizon.data() + i;
    for (int c = 0; c < n; ++c) val = std::max(val, p[c] - near_max[c]);
    if (val < -kFar / 2) continue;  // no column over the packing
    ++val;
    const int pos = positive ? val : -val;  // raster origin on the insertion axis
    const int nb0 = std::min(b0, pos), nb1 = std::max(b1, pos + m);
    if (nb1 - nb0 > insert_limit) continue;
    const int na0 = std::min(a0, i), na1 = std::max(a1, i + n);
    const int nw = vertical ? na1 - na0 : nb1 - nb0, nh = vertical ? nb1 - nb0 : na1 - na0;
    const double growth = growth_weight_ * (effective_area(nw, nh) - area_before);
    if (best.valid && growth >= best.cost) continue;
    long long waste = 0;
    const int* f = F + i;
    for (int c = 0; c < n; ++c) waste += std::max(0, val - 1 + near_sum[c] - f[c]);
    const double cost = static_cast<double>(waste) + growth;
    if (!best.valid || cost < best.cost) best = {true, vertical ? i : pos, vertical ? pos : i, cost, 0};
  }
  return best;
}

void Canvas::place(const ChartRaster& r, int x, int y) {
  const int g = gutter_;
  int dwords = 0;
  const std::vector<Word> dilated = dilate(r, g, dwords);
  for (int row = 0; row < r.h + 2 * g; ++row)
    or_shifted(&bits_[static_cast<std::size_t>(y - g + row) * row_words_], row_words_,
               &dilated[static_cast<std::size_t>(row) * dwords], dwords, x - g);
  auto& top = horizon_[static_cast<int>(Side::Top)];
  auto& bottom = horizon_[static_cast<int>(Side::Bottom)];
  auto& right = horizon_[static_cast<int>(Side::Right)];
  auto& left = horizon_[static_cast<int>(Side::Left)];
  for (int c = 0; c < r.w; ++c) {
    if (r.col_lo[c] > r.col_hi[c]) continue;
    for (int X = x + c - g; X <= x + c + g; ++X) {
      top[X] = std::max(top[X], y + r.col_hi[c] + g);
      bottom[X] = std::max(bottom[X], -(y + r.col_lo[c] - g));
    }
  }
  for (int row = 0; row < r.h; ++row) {
    if (r.row_lo[row] > r.row_hi[row]) continue;
    for (int Y = y + row - g; Y <= y + row + g; ++Y) {
      right[Y] = std::max(right[Y], x + r.row_hi[row] + g);
      left[Y] = std::max(left[Y], -(x + r.row_lo[row] - g));
    }
  }
  if (empty()) {
    box_ = {x, y, r.w, r.h};
  } else {
    const int x0 = std::min(box_.x, x), y0 = std::min(box_.y, y);
    const int x1 = std::max(box_.x + box_.w, x + r.w), y1 = std::max(box_.y + box_.h, y + r.h);
    box_ = {x0, y0, x1 - x0, y1 - y0};
  }
  update_blocks(x - g, y - g, x + r.w + g, y + r.h + g);
  update_free_squares(x - g, y - g, x + r.w + g, y + r.h + g);
}

}  // namespace isochart::pack_detail
