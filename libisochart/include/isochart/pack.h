#pragma once
/// Chart packing: lays out the charts of an atlas in [0,1]² for a W×H texture with a
/// guaranteed gutter (Iso-charts §6, the four-horizon extension of the "Tetris" packer of
/// Lévy et al. 2002).

#include <vector>

#include "isochart/mesh.h"
#include "isochart/progress.h"
#include "isochart/vec.h"

namespace isochart {

struct Atlas;

/// One chart to pack: a 2-D parameterization of a part of the surface.
struct PackChart {
  /// Per chart vertex; any position and scale. Faces should be counter-clockwise (the
  /// packer only rotates and translates, so the winding it is given is the winding it returns).
  std::vector<Vec2d> uv;
  std::vector<Face> faces;  ///< chart-local vertex indices into `uv`
  /// Surface area of the chart (units²). The packer scales the chart so that its UV area
  /// equals this (§6 step 1), so all charts share one texel density. 0 means "unknown":
  /// the chart's own UV area is used, i.e. the charts keep their relative UV scales.
  double area_3d = 0;
};

struct PackOptions {
  /// The largest texture side the packer takes.
  static constexpr int kMaxSize = 8192;
  /// Target texture size in texels (1..kMaxSize each). The packer works on a canvas of twice
  /// that size in each direction per order tried: about 4.5·W·H bytes each (5 MB at 1024²,
  /// 300 MB at 8192²).
  int width = 1024;
  int height = 1024;  ///< see width
  /// Minimum number of empty texels between two charts and between a chart and the texture
  /// border, measured on the W×H grid with conservative rasterization (every texel a
  /// triangle touches is the chart's) and a square neighbourhood (diagonals count).
  int gutter = 2;
  /// Orientations tried per chart, evenly spaced over 360° starting from the chart's
  /// minimal-area bounding rectangle (16 in the paper). Rotations only, never mirroring.
  /// 0 = automatic: 16, and 4 for more than 256 charts, where every chart's hole search in
  /// every rotation was most of the run (1,000 random triangles: 28 s → 11 s, packing ratio
  /// 0.612 → 0.606).
  int rotations = 0;
  /// Extension beyond §6: before introducing a chart from one of the four sides (which
  /// grows the packing), look for a place inside the current bounding box where it fits
  /// (a hole left by earlier charts, or the open space above a horizon), touching as much
  /// of its neighbourhood as possible.
  bool fill_holes = true;
  /// Extension beyond §6: when a chart is introduced from a side, its cost is the wasted
  /// texels plus this weight times the growth of the area of the smallest W:H rectangle
  /// around the packing. 0 is the paper's rule (least waste only); a positive weight keeps
  /// the packing near the target shape.
  double growth_weight = 0.5;
  /// Extension beyond §6: greedy variants. 1 = the paper's order (decreasing area) with
  /// `growth_weight`; 2 adds the order by decreasing length of the minimal rectangle; both
  /// pack at every scale of the search. More (up to 6) add both orders with the other
  /// growth weights of {0, 2}; these, with the first two, are then tried on a ladder of five
  /// scales 1% apart above the search's result, whose largest fitting scale is kept.
  /// 7 to 32 also try the area order perturbed (each chart's area times a fixed factor in
  /// [1, 2) drawn from a hash of chart and variant) on the ladder: the best of more greedy
  /// runs, for more time. 0 = automatic: 6 for up to 32 charts and textures up to 4096²,
  /// else 2. Variants run in parallel, each with its own canvas (see width).
  int variants = 0;
  /// Extension beyond §6: after packing, a chart that alone holds a side of the bounding
  /// box is moved into free room inside the other charts' box when there is any, shrinking
  /// the box (the packing ratio rises; the scale stays).
  bool compact = true;
  /// The scale search stops when the largest scale known to fit and the smallest known not
  /// to fit differ by less than this factor.
  double scale_tolerance = 0.005;
  /// The longest side of the grid the packing is searched on (0: the texture's own). A larger
  /// texture is packed on the grid k times coarser, for the smallest integer k that brings both
  /// sides within it and divides them (so the layout keeps the texture's shape exactly), with
  /// the gutter rounded up to whole coarse texels; when no such grid is at least half the size
  /// (1025², 4099²), on the texture's own grid. The time
  /// grows with the grid's area, the packing ratio hardly: the atlases of bunny, horse and
  /// fertility at 4096² packed in 4.4, 13.8 and 16.4 s on their own grid, 0.25, 0.81 and 0.78 s
  /// on a 1024² one, their ratios 0.651 → 0.645, 0.722 → 0.701, 0.633 → 0.641.
  int search_size = 0;
};

/// How one chart was moved: texel = scale · R(angle) · uv_in + offset, then uv = texel / (W, H).
struct ChartPlacement {
  double angle = 0;  ///< counter-clockwise rotation, radians
  double scale = 0;  ///< texels per input UV unit
  Vec2d offset;      ///< texels
};

struct PackResult {
  double packing_ratio = 0;                ///< Σ chart UV area / area of the UV bounding box of all charts
  double utilization = 0;                  ///< Σ chart UV area / area of [0,1]² (texture coverage)
  double texel_size = 0;                   ///< surface length per texel (units of √area_3d), all charts
  double seconds = 0;                      ///< wall time of pack_charts
  int used_width = 0;                      ///< texels spanned by the charts' conservative raster in x
  int used_height = 0;                     ///< same in y
  int attempts = 0;                        ///< scales tried (search and ladder)
  int variant = 0;                         ///< variant kept, in the order PackOptions::variants adds them
  std::vector<ChartPlacement> placements;  ///< per input chart
};

/// Packs the charts in place (Iso-charts §6): rewrites every chart's `uv` into [0,1]² so that
/// all charts share one texel density, no two charts come closer than `gutter` texels on the
/// W×H grid, no chart comes closer than `gutter` texels to the border, and the packing is as
/// large as it can be while fitting the texture (the scale is searched).
///
/// The paper's steps: (1) scale each chart so its UV area equals its 3-D area; (2) sort by
/// decreasing area; (3) for each chart, pick the direction pair by W_expect = H_curr·W/H
/// (left/right when W_expect > W_curr, else top/bottom) and introduce the chart from the
/// side of that pair, at the offset and in the rotation that waste the least space between
/// the chart's horizon and the packing's horizon (the four horizons: top, bottom, left and
/// right of the evolving packing). Charts are rasterized conservatively at the final texel
/// size and placed on that grid, so the gutter is exact; the texel size is searched
/// (bisection) for the largest packing that fits the W×H texture.
///
/// Additions, measured on the baseline atlases (see bench/pack_bench.cpp):
/// - rotations start from each chart's minimal-area bounding rectangle;
/// - before growing the packing from a side, a chart goes to the free position inside the
///   current bounding box (a hole between charts, or open space above a horizon) whose
///   outline touches the most placed charts, if any (`fill_holes`);
/// - side insertions also pay for growing the W:H rectangle around the packing
///   (`growth_weight`);
/// - greedy variants: a second order, by decreasing length of the minimal rectangle, and
///   other growth weights tried on a ladder of scales above the search's result (`variants`).
///
/// Deterministic, and identical for any number of TBB threads.
/// \throw InputError for invalid options or charts (empty, index out of range, NaN,
///        zero UV area, negative area), naming the chart, and when the charts cannot fit
///        the texture at any scale (too many charts for its size and gutter).
/// \throw Cancelled when `progress` returns false.
PackResult pack_charts(std::vector<PackChart>& charts, const PackOptions& options = {},
                       const Progress& progress = {});

/// Options of split_charts_for_packing.
struct PackSplitOptions {
  /// Every piece must still meet the chart bounds of the atlas (Iso-charts §3), measured on
  /// the piece alone normalized to its own 3-D area, as the packer scales it.
  double max_l2 = 1.1;
  double max_linf = 5.0;  ///< see max_l2 (shrink included)
  /// Charts that may be added. < 0 = automatic: up to `target_charts` charts in all, and at
  /// most as many as the atlas has (never more than doubling it).
  int max_added = -1;
  /// With max_added < 0: cutting stops at this many charts. Few large charts leave the
  /// packer nothing to fill the gaps between them with; with more than about a dozen, cuts
  /// measured on the shared meshes did not raise the packing ratio (horse: 14 → 19 charts,
  /// 0.683 → 0.681).
  int target_charts = 12;
  /// A cut is made only when it lowers the summed area of the charts' minimal bounding
  /// rectangles (each chart scaled to its 3-D area) by at least this fraction of the total
  /// chart area.
  double min_gain = 0.005;
};

struct PackSplitResult {
  int added = 0;                ///< charts added
  double seconds = 0;           ///< wall time
  double rect_fill_before = 0;  ///< Σ chart area / Σ minimal-rectangle area (3-D scale), before
  double rect_fill_after = 0;   ///< same, after
};

/// Extension beyond Iso-charts §6, run before packing: cuts charts of `atlas` in two along a
/// straight line of their own UV layout when the two pieces' minimal-area bounding
/// rectangles waste clearly less than the chart's (long arms, L shapes), which is what the
/// packer cannot interlock. UVs are kept, so no piece flips or overlaps; a cut is kept only
/// when both pieces are topological disks and meet the bounds. The largest gains go first;
/// pieces can be cut again. Charts are renumbered by their smallest face id; the new UVs
/// are the unpacked input layouts, so call pack_atlas next. Deterministic, identical for
/// any number of TBB threads.
PackSplitResult split_charts_for_packing(const Mesh& mesh, Atlas& atlas,
                                         const PackSplitOptions& options = {});

/// split_charts_for_packing, then pack_atlas, keeping the best packing ratio of three: the
/// uncut atlas, the cuts that gain at least 4·min_gain (the first cuts of the greedy
/// sequence) and all the cuts (the greedy packer is chaotic, and a better rectangle fit does
/// not always pack better). `split` receives what was kept (added = 0 when the uncut atlas
/// won); its seconds and the result's include all the packings.
PackResult split_and_pack_atlas(const Mesh& mesh, Atlas& atlas, const PackOptions& pack,
                                const PackSplitOptions& options, const Progress& progress = {},
                                PackSplitResult* split = nullptr);

}  // namespace isochart
