#pragma once
// Internal to the packer: bit rasters of charts and the geometry that prepares them.

#include <array>
#include <cstdint>
#include <vector>

#include "isochart/mesh.h"
#include "isochart/vec.h"

namespace isochart::pack_detail {

using Word = std::uint64_t;
constexpr int kWordBits = 64;

/// Portable bit count; without -mpopcnt the builtin calls a slow library routine.
inline int popcount(Word v) {
  v = v - ((v >> 1) & 0x5555555555555555ULL);
  v = (v & 0x3333333333333333ULL) + ((v >> 2) & 0x3333333333333333ULL);
  v = (v + (v >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
  return static_cast<int>((v * 0x0101010101010101ULL) >> 56);
}

inline int words_for(int bits) {
  return (bits + kWordBits - 1) / kWordBits;
}

/// An axis-aligned rectangle of texels [x, x+w) × [y, y+h).
struct Rect {
  int x = 0, y = 0, w = 0, h = 0;
  long long area() const { return static_cast<long long>(w) * h; }
};

/// One nonzero word of a sparse row mask.
struct MaskWord {
  int row = 0, word = 0;
  Word bits = 0;
};

/// A rotated, scaled chart rasterized conservatively: texel (c, r) is set when any triangle
/// touches the closed square [c, c+1] × [r, r+1]. Texel coordinates are the chart's
/// scaled, rotated coordinates minus `origin` (an integer vector), so moving the raster by
/// whole texels moves the chart exactly.
struct ChartRaster {
  int w = 0, h = 0;        ///< size in texels
  int words = 0;           ///< words per row of `bits`
  Vec2d origin;            ///< chart point (scaled, rotated) that maps to texel corner (0, 0)
  std::vector<Word> bits;  ///< h rows × `words`
  std::vector<int> row_first_word, row_last_word;  ///< nonzero word range per row
  /// Per column: lowest and highest set row (col_lo > col_hi when the column is empty).
  std::vector<int> col_lo, col_hi;
  /// Per row: leftmost and rightmost set column (row_lo > row_hi when empty).
  std::vector<int> row_lo, row_hi;
  long long texels = 0;  ///< set texels
  Rect core;             ///< a large rectangle of set texels, for early rejection
  /// Squares of set texels spread over the raster (largest first, at most 9, side ≥ 2,
  /// capped at 63): wherever the chart fits, free squares at least as large sit there.
  std::vector<Rect> probes;
  std::vector<int> test_rows;  ///< row order for collision tests: spread-out rows first
  /// The texels a one-texel move in each direction adds (indexed by Side: moving up (+y),
  /// down, right (+x), left), in the raster's own coordinates at its new position: when a
  /// position is free, its neighbour is free iff these texels are.
  std::vector<MaskWord> edge[4];

  // The 1-texel ring around the chart (3×3 dilation minus the chart), origin at (-1, -1),
  // used to measure how much of the chart's outline touches its surroundings.
  int ring_words = 0;
  std::vector<Word> ring;  ///< (h + 2) rows × ring_words
  int ring_size = 0;
  int ring_left = 0, ring_right = 0, ring_bottom = 0, ring_top = 0;  ///< ring texels on each outer side

  bool test(int c, int r) const { return (bits[r * words + c / kWordBits] >> (c % kWordBits)) & 1u; }
};

/// What rasterizing a chart needs of its mesh, independent of rotation and scale.
///
/// The conservative raster of the union of the triangles is the set of texels that either
/// meet the boundary chain ∂(Σ triangles) or whose centre has a nonzero winding number
/// with respect to it, plus the rasters of the triangles with non-positive area. (A texel
/// that meets the union without lying inside it meets the union's boundary, which is part
/// of the chain or of a non-positive triangle; a point covered only by cancelling layers
/// lies in a non-positive triangle.) The chain has O(√F) edges, so this is much cheaper
/// than rasterizing every triangle.
struct ChartOutline {
  std::vector<std::array<int, 2>> boundary;  ///< directed chain edges, repeated by multiplicity
  std::vector<int> bad_faces;                ///< faces with (nearly) zero or negative area
  std::vector<int> lone_vertices;            ///< vertices no face uses
};

/// \param uv the chart's vertices in any frame related to the packer's by a rotation and a
///        positive scale (signs of areas are what matter).
ChartOutline chart_outline(const std::vector<Vec2d>& uv, const std::vector<Face>& faces);

/// Rasterizes `points` (already rotated and scaled to texels) using the outline. A raster
/// wider than `max_w` or taller than `max_h` could never be placed: only its size is set.
ChartRaster rasterize_chart(const std::vector<Vec2d>& points, const std::vector<Face>& faces,
                            const ChartOutline& outline, int max_w = 1 << 30, int max_h = 1 << 30);

/// Reference rasterization, triangle by triangle (slow; for tests).
ChartRaster rasterize_triangles(const std::vector<Vec2d>& points, const std::vector<Face>& faces);

/// The chart raster dilated by `g` texels with a square neighbourhood: (w + 2g) × (h + 2g)
/// texels, origin at (-g, -g), `words_out` words per row.
std::vector<Word> dilate(const ChartRaster& r, int g, int& words_out);

/// Convex hull (counter-clockwise, no collinear points) of a point set.
std::vector<Vec2d> convex_hull(std::vector<Vec2d> points);

/// The rotation (radians) that turns the points' minimal-area enclosing rectangle axis-aligned.
double min_area_rect_angle(const std::vector<Vec2d>& points);

/// Minimal-area enclosing rectangle of a convex polygon of ≥ 3 vertices (counter-clockwise,
/// as convex_hull returns): its area and the rotation (radians) that turns it axis-aligned.
struct HullRect {
  double area = 0;
  double angle = 0;
};
HullRect min_area_rect(const std::vector<Vec2d>& hull);

/// ORs `src` (`nsrc` words) shifted left by `shift` bits into `dst` (`ndst` words); bits
/// shifted past `ndst` words are dropped.
void or_shifted(Word* dst, int ndst, const Word* src, int nsrc, int shift);

}  // namespace isochart::pack_detail
