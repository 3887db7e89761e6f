#pragma once
/// Building multi-chart geometry images from an atlas (Sander et al. 2003; Iso-charts §8, §9.2):
/// packing at the image's resolution, sampling, zippering, reconstruction, sample optimization,
/// and pyramids of several resolutions linked by normal shooting.
///
/// The atlas is an isochart::Mesh with per-corner texture coordinates (`uvs`, `face_uvs`); its
/// charts are the edge-connected pieces of `face_groups` (or of isochart::uv_charts when there
/// are no groups), each piece with continuous texture coordinates. Every chart must be a
/// topological disk with a non-degenerate layout.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "isochart/mesh.h"
#include "isochart/progress.h"
#include "mcgim/correspondence.h"
#include "mcgim/geometry_image.h"

namespace mcgim {

struct LevelOptions {
  int width = 256;   ///< samples per row (2 .. 16384; 8192 when re-packing)
  int height = 256;  ///< rows (2 .. 16384; 8192 when re-packing)
  /// Re-pack the atlas's charts for this resolution with isochart::pack_charts (every chart
  /// at the same texel density, at least `gutter` empty texels between charts). When false,
  /// the atlas's own layout in [0,1]² is used as is and must keep charts ≥ 1 texel apart.
  bool repack = true;
  int gutter = 1;  ///< texels between charts when re-packing (≥ 1)
  /// When re-packing, size each chart by its texture area in the input atlas (the atlas's
  /// relative chart sizes kept) instead of its surface area (one texel density everywhere).
  /// For signal-specialized atlases, whose packing gives charts with more signal variation
  /// more texels (Iso-charts §7): the samples follow the signal, not just the area.
  bool keep_chart_sizes = false;
  /// Width / height of the texture the atlas's UVs were laid out for, so that re-packing
  /// scales u by it; 0 reads it from the UVs (isochart::detect_texture_aspect).
  double atlas_aspect = 0;
  /// Move the samples (welded groups together) towards the original surface after
  /// zippering (Sander et al. 2003's final optimization): least-squares fits of the
  /// reconstructed surface to points of the original surface, with a pull towards the sampled
  /// positions; no sample moves by more than a texel.
  bool optimize = true;
  /// Parametric passes: original points matched through their texture coordinates (cheap).
  int optimize_iterations = 1;
  /// Geometric passes after those: original points matched to their closest remesh points and
  /// remesh face centroids to their closest original points (exact, about 0.3 s per pass per
  /// 50k samples on 2 cores). Each pass re-picks the diagonals.
  int geometric_iterations = 2;
  /// With the geometric passes: split each 2×2 block along the diagonal whose triangles lie
  /// closer to the original surface instead of the shorter one (kept in the image's
  /// block_diagonal, so the image still defines the remesh). A block keeps its diagonal when
  /// the other one is already an edge of the remesh; the choice is dropped if it would take the
  /// remesh further from the input's topology.
  bool fit_diagonals = true;
  /// Weight of the pull towards the sampled positions in the parametric (point-to-point)
  /// passes, relative to the fit, per unit of texel area. Small values fit harder; it keeps
  /// samples without data in place. Measured when the closest-point passes were point-to-point
  /// too (until 2026-11-26, evening): 0.05 rather
  /// than harder fits: the closest-point matches are re-made only once per pass, and a
  /// tighter fit to them overshoots (a horse signal atlas at 47k samples, two fit points per
  /// texel: 0.02 → 86.16 dB, 0.1 → 86.26; four points: 0.05 → 86.33, 0.1 → 86.36). Not 0.1:
  /// on armadillo's 64² level that fit re-picked diagonals that lost the topology, and the
  /// rebuilt level measured 33.5 dB instead of 49.5.
  double optimize_regularization = 0.05;
  /// The same pull in the closest-point passes, which fit point-to-plane (the distance along
  /// the original surface's normal only, with no triangle allowed to turn over). Nothing else
  /// holds samples in place along the surface, so it is smaller than the point-to-point fit's:
  /// horse's signal atlas at 47k samples 89.60 / 90.29 dB at 0.005 / 0.002 (89.09 at 0.01,
  /// measured without the turn-over guard) against 87.48 point-to-point; at 0.002 its remesh had
  /// 205 triangles with an angle under 5° against 133 at 0.005 and 99 point-to-point.
  double fit_regularization = 0.005;
};

/// What one level measured. Seconds are wall time per stage.
struct LevelStats {
  int width = 0, height = 0;
  int charts = 0;
  int empty_charts = 0;       ///< charts left without a sample at this resolution (contracted)
  /// Charts part of whose surface is over 3 texels from the remesh (contracted by the zipper:
  /// too thin or small for their samples at this resolution); topology_warning names them.
  int lost_charts = 0;
  /// Charts packed larger than their surface area asks for: when a coarse level's remesh
  /// loses the input's topology (charts too small for a triangle of samples collapse), the
  /// level is rebuilt with its sparsest charts enlarged (×1.5 per attempt, up to 13 times,
  /// then ×4 up to 5 times) until it keeps the topology; the least enlarged of the best is kept.
  /// Still short of it, that layout is tried at the other phases of a quarter-texel grid.
  int enlarged_charts = 0;
  long long defined_samples = 0;
  long long removed_samples = 0;  ///< covered samples dropped to make each chart a disk
  /// Samples added to charts too small to cover a triangle of sample centres: one 2×2 block at
  /// the free place nearest to the chart, each sample at the chart's closest point.
  long long forced_samples = 0;
  long long unique_vertices = 0;  ///< vertices of the remesh (after welding)
  long long triangles = 0;
  long long degenerate_triangles = 0;
  long long collapsed_triangles = 0;
  int cut_nodes = 0;          ///< nodes of the cut graph (artificial ones included)
  int cut_paths = 0;          ///< cut paths zippered (two-sided)
  TopologyCheck topology;     ///< of the remesh
  int input_euler_characteristic = 0;
  int input_boundary_loops = 0;
  double texel_size = 0;      ///< sqrt(surface area / defined samples), model units
  /// Splitting the atlas into charts and building the cut graph (done once per atlas: in a
  /// pyramid it is counted on the finest level only).
  double seconds_charts = 0;
  double seconds_packing = 0, seconds_sampling = 0, seconds_zippering = 0,
         seconds_reconstruction = 0, seconds_optimization = 0, seconds_correspondence = 0;
};

/// One level: the image, its remesh, and (in a pyramid, for all but the coarsest level) the
/// normal-shooting correspondence of each of its samples on the next coarser level.
struct Level {
  GeometryImage image;
  Remesh remesh;
  LevelStats stats;
  std::vector<Correspondence> coarser;  ///< W·H, empty for the coarsest level
};

/// Builds one MCGIM from an atlas: pack (or keep) the layout at W×H, rasterize each chart (a
/// sample is defined iff its centre lies in one of the chart's triangles, a centre on a shared
/// edge or vertex belonging to exactly one of them), drop samples so that each chart's samples
/// form a disk, zipper, reconstruct, optimize.
/// \throw isochart::InputError for an atlas without texture coordinates, a chart that is not a
///        disk or is degenerate, a non-manifold mesh, or (with repack off) charts closer than a
///        texel or outside [0,1]²; isochart::Error when the packer cannot fit the charts.
/// \throw isochart::Cancelled when `progress` returns false.
Level build_level(const isochart::Mesh& atlas, const LevelOptions& options = {},
                  const isochart::Progress& progress = {});

/// What is wrong with a level's remesh for a user, in one line ("WxH level does not keep the
/// input's topology (...)", "WxH level has N non-manifold vertices (...)", "WxH level lost
/// part of the surface of N charts (...)" or "WxH level has N zero-area triangles (...)"),
/// the first that applies; empty when it keeps the input's Euler characteristic and boundary
/// loops, is manifold, lost no chart and has no zero-area triangle.
std::string topology_warning(const LevelStats& stats);

/// \throw isochart::InputError("", "WxH level: no 2x2 block of defined samples, ...") when the
///        level's remesh has no triangle: its charts are too small for its resolution. An
///        empty remesh is no result; build_pyramid checks every level with it.
void check_not_empty(const Level& level);

struct PyramidOptions {
  /// Resolutions, any order; the levels are returned finest first. Each is packed,
  /// sampled and zippered on its own.
  std::vector<std::array<int, 2>> sizes = {{256, 256}, {128, 128}, {64, 64}, {32, 32}};
  LevelOptions level;  ///< width and height are taken from `sizes`
  ShootOptions shoot;
};

/// Builds every level and links each level's samples to the next coarser level by normal
/// shooting (Iso-charts §8).
std::vector<Level> build_pyramid(const isochart::Mesh& atlas, const PyramidOptions& options = {},
                                 const isochart::Progress& progress = {});

/// Result of the resolution search for a sample budget.
struct ResolutionChoice {
  int width = 0, height = 0;
  long long defined_samples =
      0;  ///< choose_resolution: covered before disk cleanup; match_resolution: the built level's
  int trials = 0;
  bool capped = false;  ///< the budget needs a side beyond max_side; this is max_side
};

/// Searches the square resolution whose packed atlas covers about `target_samples` samples,
/// with sides of at most `max_side` (a level takes about 600 bytes a sample: 2.4 GB at 2048²).
/// `capped` in the result says that the budget needed more.
ResolutionChoice choose_resolution(const isochart::Mesh& atlas, long long target_samples,
                                   const LevelOptions& options = {}, const isochart::Progress& progress = {},
                                   int max_side = 16384);

/// choose_resolution, then refined by building levels (without optimization) at nearby sizes,
/// width and height apart (or square sizes only, with `square`), until the defined samples
/// after cleanup are within 2 % of `target_samples` or a few dozen sizes are tried; the closest
/// wins. `defined_samples` is then the built level's. A capped choice is returned as is: every
/// other size holds fewer.
ResolutionChoice match_resolution(const isochart::Mesh& atlas, long long target_samples,
                                  const LevelOptions& options = {}, const isochart::Progress& progress = {},
                                  int max_side = 16384, bool square = false);

}  // namespace mcgim
