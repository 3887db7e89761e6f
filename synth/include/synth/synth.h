#pragma once
/// Surface texture synthesis over an MCGIM pyramid (Iso-charts §8; Wei & Levoy 2001):
/// neighbourhoods are gathered in each chart's 2-D image domain, rotated and scaled by a smooth
/// tangent direction field (by default an N-direction field, N = 2 or 4 from the exemplar),
/// and cross chart seams by walking over the surface into the neighbour chart. The first
/// synthesized level (chosen from the exemplar's correlation length and smoothness, see
/// SynthOptions::start_level) starts from an exemplar copy grown over the surface along the
/// field, continued across seams, then gets non-causal passes; each finer level starts from its
/// coarser level's exemplar coordinates carried through the normal-shooting correspondence
/// (coordinate upsampling), then gets non-causal passes in a random order over neighbourhoods
/// of the current and the coarser level. Candidates are Ashikhmin coherent candidates with
/// their k-coherence sets (Tong et al. 2002) plus a few from FLANN kd-trees on PCA-reduced
/// neighbourhoods, re-ranked exactly with a coherence bias.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "isochart/error.h"
#include "isochart/image.h"
#include "isochart/mesh.h"
#include "isochart/progress.h"
#include "isochart/vec.h"
#include "mcgim/mcgim.h"

namespace synth {

struct SynthOptions {
  /// Exemplar pixels per unit of surface length. 0: the exemplar's width spans a tenth of the
  /// mesh's bounding-box diagonal.
  double scale = 0;
  /// When > 0, overrides `scale`: exemplar pixels per texel of the finest level, i.e. the
  /// scale that shows the exemplar at this many of its pixels per finest sample.
  double pixels_per_texel = 0;
  /// Direction of the exemplar's x axis on the surface. Zero: a smooth tangent field computed
  /// on the mesh (the x axis projected into each tangent plane, then relaxed).
  isochart::Vec3d direction{0, 0, 0};
  int neighborhood = 5;         ///< odd side of the current-level square neighbourhood (≥ 3)
  int coarse_neighborhood = 3;  ///< odd side of the coarser-level square (≥ 1)
  /// Every level after the coarsest starts from coordinate upsampling (each sample continues
  /// the exemplar patch of its coarser sample), then gets `full_passes` non-causal passes over
  /// all samples in a random order. Samples are matched in batches of this many consecutive
  /// ones, in parallel, a batch seeing the batches before it: 1 is a sequential pass; small
  /// batches (≪ samples) give the same quality, and the result is the same for any thread count.
  int first_pass_batch = 256;
  int full_passes = 2;      ///< non-causal passes per level after the coarsest
  int coarsest_passes = 2;  ///< non-causal passes on the first synthesized level after its exemplar copy
  /// The first synthesized level's exemplar copy is grown breadth-first along the direction
  /// field; true: its exemplar coordinates are then replaced by the least-squares fit of the
  /// field's offsets over all neighbour pairs, which spreads the field's curl evenly instead of
  /// leaving it as shears where the growth fronts meet.
  bool relax_copy = true;
  /// The fit (a sparse factorization) is made up to this many samples (zipper groups) of the
  /// first level; larger levels keep the breadth-first copy.
  int relax_copy_max = 1'100'000;
  /// Rounds of the as-rigid-as-possible fit of the copy (each sample's field offsets turned to
  /// match its neighbours', which keeps the exemplar's scale where the field does not close).
  /// −1: automatic, 20 when the direction field has 4-fold symmetry (the exemplar looks alike
  /// turned, so the drift from the field does not show), else 0.
  int rigid_copy_rounds = -1;
  /// Coherence bias (Hertzmann et al. 2001's κ): a kd-tree candidate must be this much better
  /// (relative distance) than the best coherent one to be chosen. 0: no preference.
  double coherence = 0.1;
  /// Size of the k-coherence sets (Tong et al. 2002): per exemplar pixel, its most similar
  /// neighbourhoods elsewhere, tried shifted like the coherent candidates. 0: coherent only.
  int k_coherence = 2;
  /// Levels with fewer samples (zipper groups) than this are never synthesized (the finest
  /// level always is): on levels of a few hundred samples most neighbourhood taps cross seams
  /// or leave the mesh and only add noise (bunny's 32² level: 366 samples).
  int min_level_samples = 1000;
  /// Where synthesis starts. −1 (automatic): at the coarsest level allowed by
  /// `min_level_samples` when (a) its neighbourhood footprint (`neighborhood` texels, in
  /// original exemplar pixels) covers the exemplar's correlation length (see
  /// correlation_length), so that its neighbourhoods see the exemplar's structure, and (b) the
  /// exemplar is smooth at the finest texel (exemplar_smoothness at one finest texel ≥
  /// `smoothness_threshold`), so that a coarse level keeps what makes it up; otherwise at the
  /// finest level, from the exemplar copy grown along the field, which keeps structure that
  /// coarse neighbourhoods cannot see or that coarse levels blur away. Measured on bunny and
  /// horse at 256² with one exemplar pixel per finest texel (bench/README.md): the cells
  /// exemplar (smoothness 0.92, correlation 5.7 pixels) starts at 64², where cells stay round
  /// and even (from 256² they come out streaked and merged); the bricks (mortar lines across
  /// the image: correlation 45 pixels), gravel and wicker photographs (smoothness ≤ 0.68)
  /// start at 256², where rows, stones and strands stay crisp (from 64² gravel comes out as
  /// flat olive patches and brick rows as fragments).
  /// ≥ 0: start at that pyramid index (clamped to the levels allowed by `min_level_samples`).
  int start_level = -1;
  /// Correlation threshold of the automatic start (see correlation_length).
  double correlation_threshold = 0.1;
  /// Smoothness the automatic start needs to begin at a coarse level (see start_level).
  double smoothness_threshold = 0.85;
  int candidates = 8;       ///< FLANN candidates re-ranked exactly
  int pca_dims = 12;        ///< PCA dimensions of the kd-trees (more: better candidates, slower)
  int relax_iterations = 200;///< smoothing sweeps of the computed direction field
  /// Rotational symmetry N of the computed direction field. 1: a vector field (the x axis
  /// projected and relaxed, see direction_field). N > 1: the globally smoothest N-direction
  /// field (directions equal up to multiples of 360°/N), whose singularities have index k/N
  /// instead of whole turns, with one representative per sample chosen to vary continuously
  /// within and across charts and levels. 0: automatic, see SynthResult::direction_symmetry.
  int direction_symmetry = 0;
  /// Automatic symmetry: 4 when the exemplar's correlation lengths along x and y (see
  /// correlation_lengths) differ by at most this factor, otherwise 2.
  double symmetry_ratio = 1.5;
  std::uint64_t seed = 1;   ///< every random choice; output independent of the thread count
};

/// Per-level figures. Seconds are wall time. Levels coarser than the first synthesized one
/// (see SynthOptions::start_level) have only their size and texel size set.
struct SynthLevelStats {
  int width = 0, height = 0;
  int exemplar_width = 0, exemplar_height = 0;  ///< exemplar pyramid level
  double texel_size = 0;         ///< model units
  double exemplar_factor = 0;    ///< original exemplar pixels per texel of this level
  long long groups = 0;          ///< synthesized surface samples (zipper groups)
  long long missing_taps = 0;    ///< taps dropped (off the mesh boundary)
  long long seam_taps = 0;       ///< taps that crossed into another chart
  double seconds = 0;
};

struct SynthResult {
  /// The finest level's texture in the MCGIM layout, RGB, row 0 = top (the image file's
  /// orientation), gutter filled with the nearest sample's colour.
  isochart::Image texture;
  /// Per level (finest first): colour of every zipper group, RGB in [0, 1].
  std::vector<std::vector<std::array<float, 3>>> group_colors;
  std::vector<SynthLevelStats> levels;
  /// Per finest-level zipper group: the pixel (y·w + x, w = levels[0].exemplar_width) of the
  /// finest exemplar level its colour was copied from, −1 when none (a sample without data).
  std::vector<int> exemplar_pixels;
  /// Per finest-level sample (y·width + x): how the exemplar continues around it, the 2×2 map
  /// from an image offset (dx, dy) in samples to finest-exemplar-level pixels (row-major:
  /// ∂x/∂dx, ∂x/∂dy, ∂y/∂dx, ∂y/∂dy) in the direction field's frame at the sample; zero
  /// where the sample has no neighbour in its chart.
  std::vector<std::array<float, 4>> exemplar_jacobians;
  double scale = 0;  ///< exemplar pixels per unit of surface length actually used
  /// The scale before the limits on it: the default (the exemplar spanning a tenth of the
  /// bounding-box diagonal) or the one asked for. Differs from `scale` only for the default,
  /// moved into the range the pyramid can synthesize (a scale asked for outside it is refused).
  double requested_scale = 0;
  int start_level = 0;  ///< pyramid index synthesis started at (see SynthOptions::start_level)
  /// Symmetry N of the direction field used (see SynthOptions::direction_symmetry).
  int direction_symmetry = 1;
  /// What the automatic start compared (see SynthOptions::start_level): the exemplar's
  /// correlation length and the neighbourhood footprint of the coarsest level allowed by
  /// SynthOptions::min_level_samples, both in original exemplar pixels.
  double correlation_length = 0;
  double coarse_footprint = 0;
  /// exemplar_smoothness at one finest texel, which the automatic start compared too.
  double smoothness = 0;
  /// Fraction of the first synthesized level's neighbour pairs whose offset in the fitted
  /// exemplar copy is more than 1.3× longer or shorter than the direction field's offset (the
  /// copy magnifies or shrinks the exemplar there). 0 when the copy is not fitted.
  double copy_scale_off = 0;
  /// Mean over finest-level samples of the squared distance between the final neighbourhood
  /// and its best exemplar match, per valid component, divided by the exemplar's variance
  /// (0 = every neighbourhood occurs in the exemplar; about 2 for unrelated noise).
  double match_error = 0;
  /// Mean colour difference between samples two texels apart across a zippered seam, divided
  /// by the same figure for pairs inside charts (1 = seams invisible). 0 when both are 0
  /// (a constant texture); +inf when only the interior one is 0; NaN when no pair crosses a
  /// seam (one chart without seams).
  double seam_error = 0;
  long long seam_pairs = 0;
  /// Standard deviation over finest-level samples of log(local texel size on the surface).
  double texel_scale_spread = 0;
  double seconds = 0;
};

/// A scale asked for (SynthOptions::scale or pixels_per_texel) that the built pyramid cannot
/// synthesize. Its limits depend on the pyramid's texel size, so the caller learns of them only
/// here; `exemplar_size()` says the exemplar is too large to search at that scale (a smaller
/// exemplar would do), otherwise the scale magnifies or shrinks the exemplar too far.
class ScaleError : public isochart::InputError {
 public:
  ScaleError(const std::string& message, bool exemplar_size)
      : isochart::InputError("", message), exemplar_size_(exemplar_size) {}
  bool exemplar_size() const { return exemplar_size_; }

 private:
  bool exemplar_size_;
};

/// Synthesizes a texture over `pyramid` (from mcgim::build_pyramid of `atlas`, finest first;
/// one level is fine) from `exemplar` (RGB, see load_exemplar).
/// \throw ScaleError for a scale out of the pyramid's range, isochart::InputError for other bad
///        options or an empty pyramid; Cancelled via `progress`.
SynthResult synthesize(const isochart::Mesh& atlas, const std::vector<mcgim::Level>& pyramid,
                       const isochart::Image& exemplar, const SynthOptions& options = {},
                       const isochart::Progress& progress = {});

/// Transfers a level's texture (RGB, in that level's layout, row 0 = top) onto the atlas's own
/// texture coordinates: a `size`×`size` RGB image (row 0 = top) for `atlas`'s uvs. Each chart's
/// MCGIM layout is an affine image of its atlas layout, fitted from the samples; texels outside
/// every chart take the nearest covered texel's colour so that mipmaps do not bleed.
///
/// With `synthesis` (the result of synthesize on `level`'s pyramid) and its `exemplar` (the
/// original RGB image), each texel reads the exemplar instead of interpolating the samples'
/// colours: it continues the exemplar position of each of its (up to four) nearest samples by
/// its offset from them (SynthResult::exemplar_jacobians), looks the exemplar up there
/// (bilinear, mirrored at its edges, prefiltered to the atlas's texel size) and blends the
/// four by their bilinear weights. Where neighbouring samples continue one patch this draws the
/// exemplar itself at the atlas's resolution, without the samples' rounding to whole exemplar
/// pixels; samples without an exemplar position keep their colour.
isochart::Image transfer_to_atlas(const isochart::Mesh& atlas, const mcgim::Level& level,
                                  const isochart::Image& texture, int size,
                                  const SynthResult* synthesis = nullptr,
                                  const isochart::Image* exemplar = nullptr);

/// Per-vertex unit tangent directions of `mesh`: `direction` (or the x axis when zero, the
/// y axis where x is nearly normal) projected into each tangent plane. When `direction` is
/// zero: with `symmetry` 1, then relaxed by `iterations` sweeps of neighbour averaging; with
/// N = `symmetry` > 1, one representative per vertex of the globally smoothest N-direction
/// field (Knöppel et al. 2013: the smallest eigenvector of the N-fold connection Laplacian,
/// by inverse iteration from the projected axis, min(40, max(5, iterations/10)) steps).
/// \throw isochart::InputError when symmetry < 1.
std::vector<isochart::Vec3d> direction_field(const isochart::Mesh& mesh,
                                             const isochart::Vec3d& direction, int iterations,
                                             int symmetry = 1);

/// The share of `mesh`'s surface area where direction_field does not follow `direction`
/// because it lies too near the normal (within about 17°) and another axis takes over: 1 on a
/// flat mesh given its normal. 0 for a zero direction or a mesh without area.
double direction_along_normal_share(const isochart::Mesh& mesh, const isochart::Vec3d& direction);

/// A neighbourhood tap: a weighted mix of up to four samples of one level (weights sum to 1),
/// or missing (all weights 0) when it falls off the mesh boundary.
struct Tap {
  std::array<int, 4> sample{{-1, -1, -1, -1}};
  std::array<float, 4> weight{{0, 0, 0, 0}};
  bool crossed = false;  ///< found through the surface in another chart than the start
  bool valid() const { return sample[0] >= 0; }
};

/// Local geometry of one level: per sample the tangent frame and the image-to-surface
/// Jacobian, and a spatial hash for taps that leave their chart.
class LevelGeometry {
 public:
  /// `directions`: W·H tangent directions (any length; projected and normalized per sample).
  LevelGeometry(const mcgim::Level& level, const std::vector<isochart::Vec3d>& directions);
  ~LevelGeometry();
  LevelGeometry(LevelGeometry&&) noexcept;
  LevelGeometry& operator=(LevelGeometry&&) noexcept;

  /// The tap at surface offset a·t1 + b·t2 (model units; t1 the direction, t2 = n × t1) from
  /// the point at continuous image position `xy` of chart `chart` (frame of sample `frame`):
  /// inside the chart a bilinear lookup; otherwise the offset point is located on the
  /// surface (nearest sample facing the same way) and looked up in that sample's chart.
  Tap locate(isochart::Vec2d xy, int chart, int frame, double a, double b) const;
  /// Same from the centre of sample `s`.
  Tap locate(int s, double a, double b) const;
  /// Unit tangent t1, t2 and normal of sample s.
  isochart::Vec3d t1(int s) const;
  isochart::Vec3d t2(int s) const;
  /// ∂position/∂x and ∂position/∂y at sample s (model units per texel).
  isochart::Vec3d dpdx(int s) const;
  isochart::Vec3d dpdy(int s) const;
  /// Local texel size at s: sqrt(|∂p/∂x × ∂p/∂y|) (model units).
  double texel_size(int s) const;
  /// Position where a tap lands (its weights applied to sample positions).
  isochart::Vec3d position(const Tap& t) const;

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace synth
