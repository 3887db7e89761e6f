#pragma once
// Internal to the packer: the evolving packing on a texel grid, its four horizons
// (Iso-charts §6) and the search for placements.

#include <array>
#include <vector>

#include "pack_raster.h"

namespace isochart::pack_detail {

/// The side a chart is introduced from: it comes from that side and moves toward the
/// packing until it touches its horizon (Top: comes from +y and moves down).
enum class Side { Top = 0, Bottom = 1, Right = 2, Left = 3 };

/// A position for a chart raster: texel (c, r) of the raster lands on canvas texel
/// (x + c, y + r). Lower cost is better.
struct Candidate {
  bool valid = false;
  int x = 0, y = 0;
  double cost = 0;
  int rotation = 0;  ///< which raster of a set, when a search covers several
};

/// The packing on a canvas of texels. The canvas holds the placed charts dilated by the
/// gutter, so a chart raster fits where none of its texels meets a canvas texel, and then
/// keeps at least `gutter` empty texels to every placed chart.
class Canvas {
 public:
  static constexpr int kNone = -(1 << 28);

  /// The packing's bounding box (of undilated chart texels) may not exceed
  /// `limit_w` × `limit_h`; the canvas is large enough for any packing within that limit
  /// that contains the first chart, which is placed at its centre. `growth_weight` weighs
  /// the growth of the aspect-corrected bounding area against wasted texels.
  Canvas(int limit_w, int limit_h, int gutter, double growth_weight);

  bool empty() const { return box_.w == 0; }
  /// Bounding box of the placed (undilated) chart texels.
  const Rect& bounds() const { return box_; }

  /// Whether the raster fits the limits at all (in this rotation).
  bool fits_limits(const ChartRaster& r) const { return r.w <= limit_w_ && r.h <= limit_h_; }
  /// The first chart goes to the centre of the canvas.
  Candidate centre(const ChartRaster& r) const;

  /// The best position inside the current bounding box, if any (extension of §6: holes
  /// left between charts and the open space above the horizons): the free position whose
  /// 1-texel ring touches the most placed charts or box sides (cost = −touching fraction).
  /// Searches the `count` rasters (rotations of one chart) at once; ties go to the lowest
  /// (y, x, rotation), whatever the number of threads.
  Candidate best_inside(const ChartRaster* rasters, int count) const;
  /// Introducing the raster from `side` (Iso-charts §6): for each offset along the side the
  /// chart moves in until it touches the horizon; the cost of an offset is the number of
  /// texels wasted between the chart's horizon and the packing's horizon, plus the growth
  /// penalty. Only offsets keeping the packing within the limits count.
  Candidate best_from_side(const ChartRaster& r, Side side) const;

  bool collides(const ChartRaster& r, int x, int y) const;
  /// Whether the sparse mask at (x, y) meets a canvas texel.
  bool collides(const std::vector<MaskWord>& mask, int x, int y) const;
  /// collides(right_edge, x0 + s, y) for s = 1 .. `steps` (≤ 32) as bit s − 1, in one pass.
  unsigned right_steps(const std::vector<MaskWord>& right_edge, int x0, int y, int steps) const;
  /// Touching ring texels of a raster at (x, y) (placed charts and bounding-box sides).
  int contact(const ChartRaster& r, int x, int y) const;
  /// Adds the raster, dilated by the gutter, at (x, y).
  void place(const ChartRaster& r, int x, int y);

  /// Canvas size in texels, whether texel (x, y) is taken (a dilated chart texel), and the side
  /// of the largest free square with its lower-left texel at (x, y), capped at kSquareCap
  /// (the map the searches prune with; exposed for tests).
  int width() const { return width_; }
  int height() const { return height_; }
  bool occupied(int x, int y) const { return is_set(x, y); }
  int free_square(int x, int y) const { return square_[static_cast<std::size_t>(y) * width_ + x]; }
  static constexpr int kSquareCap = 63;

 private:
  static constexpr int kBlock = 8;  // coarse occupancy blocks for early rejection

  /// The best inside position of one raster among positions [x0, x1] × [y0, y1] (at most
  /// a block), into `best`.
  void search_block(const ChartRaster& r, int rotation, int x0, int y0, int x1, int y1,
                    Candidate& best) const;
  /// Whether any canvas texel is set in a block fully inside [x0, x1) × [y0, y1): a true
  /// answer is certain, a false one says nothing.
  bool surely_occupied(int x0, int y0, int x1, int y1) const;
  /// Whether no canvas texel can be set in [x0, x1) × [y0, y1): a true answer is certain.
  bool surely_empty(int x0, int y0, int x1, int y1) const;
  /// Whether [x0, x1) × [y0, y1) surely has fewer than `texels` free canvas texels.
  bool surely_crowded(int x0, int y0, int x1, int y1, long long texels) const;
  long long block_sum(int bx0, int by0, int bx1, int by1) const;
  void update_blocks(int x0, int y0, int x1, int y1);
  /// Recomputes the free-square map where placing texels in [x0, x1) × [y0, y1) changed it.
  void update_free_squares(int x0, int y0, int x1, int y1);
  /// Largest free square (capped) with its lower-left corner anywhere in [x0, x1] × [y0, y1],
  /// bounded from above through the per-block maxima.
  int max_free_square(int x0, int y0, int x1, int y1) const;
  bool is_set(int x, int y) const {
    return (bits_[static_cast<std::size_t>(y) * row_words_ + x / kWordBits] >> (x % kWordBits)) & 1u;
  }

  int limit_w_, limit_h_, gutter_;
  double growth_weight_;
  int width_, height_, row_words_;
  std::vector<Word> bits_;
  // The four horizons of the dilated packing, each stored so that larger is closer to its
  // side: [Top][x] = highest set y in column x, [Bottom][x] = −lowest, [Right][y] = highest
  // set x in row y, [Left][y] = −lowest; kNone when the column/row is empty.
  std::array<std::vector<int>, 4> horizon_;
  Rect box_;
  int blocks_x_, blocks_y_;
  std::vector<int> block_count_;
  std::vector<long long> block_sat_;  // (blocks_y_+1) × (blocks_x_+1) summed-area table
  // Side of the largest free square whose lower-left texel is (x, y), capped, and its
  // maximum per block: a chart fits only where its core's square does.
  std::vector<unsigned char> square_;
  std::vector<unsigned char> block_square_;
  // The same over super-blocks of kSuper × kSuper blocks, to skip crowded areas wholesale.
  static constexpr int kSuper = 8;
  int supers_x_ = 0, supers_y_ = 0;
  std::vector<unsigned char> super_square_;
};

}  // namespace isochart::pack_detail
