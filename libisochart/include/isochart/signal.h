#pragma once
/// Signal-specialized atlases (Iso-charts §7, §9.3; Sander et al. 2002): a surface signal
/// (per-vertex normals or colours, or a texture mapped through existing UVs), its integrated
/// metric tensor (IMT) per face, signal stretch of a parameterization, and the signal
/// approximation error (SAE) of an atlas at a given texture size.

#include <array>
#include <string>
#include <vector>

#include "isochart/atlas.h"
#include "isochart/image.h"
#include "isochart/mesh.h"
#include "isochart/progress.h"

namespace isochart {

/// A signal over the surface of one mesh (same vertex and face order).
/// Linear: per-vertex values interpolated linearly over each face. Mapped: `texture` looked
/// up bilinearly (clamped) through the per-corner texture coordinates `uvs`/`face_uvs`.
struct Signal {
  int dimension = 0;                  ///< values per sample (3 for normals and colours)
  std::vector<double> vertex_values;  ///< #V × dimension, linear signals only
  Image texture;                      ///< mapped signals only
  std::vector<Vec2d> uvs;             ///< mapped: texture coordinates referenced by face_uvs
  std::vector<Face> face_uvs;         ///< mapped: #F indices into uvs
  /// mapped: some texture coordinates leave [0, 1]², so the texture is read as `wrap` says
  /// there (repeated unless the material says otherwise); otherwise it is clamped at its
  /// borders, as an atlas must be (set_texture_coordinates).
  bool tiling = false;
  /// mapped: how the lookups wrap along u and v, the material's wrap on an axis whose
  /// coordinates leave [0, 1], Clamp on the others (set_texture_coordinates).
  TextureWrap wrap{Wrap::Clamp, Wrap::Clamp};
  /// mapped: texels of the image that were not opaque (alpha < 0.999). Alpha is not part of
  /// the signal (it is dropped from `texture`), so their colour counts as it is stored.
  long long transparent_texels = 0;
  /// mapped, optional: box-filtered reductions of `texture`, each half the size of the one
  /// before (mips[0] the first of them), and a level of detail per face (0: `texture`, 1:
  /// mips[0], ...; fractions blend two levels), so that a face that reads many texels for each
  /// value taken averages them instead of aliasing (transfer_texture).
  std::vector<Image> mips;
  std::vector<float> face_lod;

  bool is_mapped() const { return !texture.empty(); }
  /// Sets uvs and face_uvs, and `tiling` and `wrap` from them: `material` (how the file's
  /// material reads its texture) on an axis some coordinate leaves [0, 1] along.
  void set_texture_coordinates(const std::vector<Vec2d>& uvs, const std::vector<Face>& face_uvs,
                               const TextureWrap& material = {});
  /// The signal at barycentric point (1 − b1 − b2, b1, b2) of face f, `dimension` values.
  void evaluate(const Mesh& mesh, int f, double b1, double b2, double* out) const;
};

/// The signal named by `spec` on `mesh`:
/// - "normals": the mesh's per-vertex normals, normalized to unit length (area-weighted face
///   normals when it has none);
/// - "colors": the mesh's per-vertex colours (RGB in [0, 1]);
/// - "texture:IMG": the image IMG mapped through the mesh's texture coordinates.
/// \throw InputError(file, ...) for an unknown spec or a signal the mesh does not carry
///        (no colours, no UVs), naming `file`; InputError(IMG, ...) when the image is unreadable.
Signal make_signal(const Mesh& mesh, const std::string& spec, const std::string& file = "");

/// Integrated metric tensor of one face (Sander et al. 2002, §3): ∫_T ∇fᵀ∇f dA over the
/// face's surface, with ∇f the signal's 2-D gradient in the face's own orthonormal frame
/// (x along corner 0 → 1, y towards corner 2). Symmetric 2×2 stored as (g00, g01, g11);
/// units: signal² (the face area cancels the 1/length² of the gradient).
using Imt = std::array<double, 3>;

/// IMT of every face (#F). Linear signals: exact (constant gradient per face). Mapped signals:
/// numerical integration by subdivision of each face into n² sub-triangles, n adapted to the
/// face's extent in texels of the source texture (≥ 1 sub-triangle edge per texel, n ≤ 32),
/// each integrated exactly for the linear interpolant of its sampled corners.
std::vector<Imt> face_imt(const Mesh& mesh, const Signal& signal);

/// Combined metric per face (#F, per unit surface area, same frame as Imt) used by the
/// signal-specialized parameterization and splitting: G = I + λ·IMT / (A·ν), with ν the
/// surface-average of tr(IMT)/(2A), so λ weighs the signal against the geometry (λ = 0 is
/// purely geometric). Faces of zero area get G = I.
std::vector<Imt> signal_metric(const Mesh& mesh, const std::vector<Imt>& imt, double lambda);

/// Normalized L2 stretch of per-vertex `uv` in the metric `face_metric` (#F, as from
/// signal_metric): sqrt(k²·Σ A·tr(JᵀGJ)/2 / Σ A·sqrt(det G)) with k² = UV area / metric area,
/// J the texture → surface Jacobian. Equals the geometric L2 stretch when G = I. +inf when a
/// triangle is flipped or degenerate in UV.
double metric_l2_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                         const std::vector<Vec2d>& uv, const std::vector<Imt>& face_metric);

/// Signal stretch of an atlas (Sander et al. 2002; Iso-charts §7): with texture coordinates
/// scaled so the total UV area equals the surface area, sqrt(Σ tr(Jᵀ IMT J)/2 / Σ tr(IMT)/2).
/// An isometric map gives 1; spending more texture on high-signal faces gives less.
/// `mesh` needs per-corner UVs; `imt` is #F. A triangle facing the other way in UV (a
/// mirrored chart) is measured like its mirror image; +inf when one has zero UV area.
double signal_stretch(const Mesh& mesh, const std::vector<Imt>& imt);

/// The signal sampled into a W×H texture through the atlas `mesh` (per-corner UVs in [0,1]²,
/// v = 0 at the bottom row): every texel whose centre lies in a UV triangle gets the signal
/// there; texels within 1.5 texels of a chart get the signal at the nearest point of the
/// nearest triangle (so bilinear lookups near chart edges see the chart's own signal); the
/// remaining gutter is filled by repeated dilation. `dimension` channels of float.
/// \throw InputError when the mesh has no UVs or the size is not in 1..16384.
Image bake_signal(const Mesh& mesh, const Signal& signal, int width, int height);

/// A texture carried from one layout of a mesh to another: `texture`, mapped through the
/// texture coordinates of `source`, resampled into a `width`×`height` image for the texture
/// coordinates of `target` (the same faces, in the same order, laid out anew, e.g. by
/// build_atlas). Every channel is kept, alpha included; colours are filtered premultiplied
/// by alpha, so transparent texels lend no colour. Each texel is the mean of
/// `supersample`² samples in it (point samples at texel centres alias where the new
/// layout has fewer texels for a part than the old one); texels outside the charts are filled
/// from the nearest chart, as bake_signal does, so that bilinear lookups and mipmaps do not
/// bleed. A source coordinate outside [0, 1] reads the texture as `wrap` says (repeated by
/// default) along that axis.
/// \throw InputError when either mesh lacks texture coordinates on some face, the faces
///        differ in number, the size is not in 1..16384 or supersample is not in 1..4.
Image transfer_texture(const Mesh& source, const Image& texture, const Mesh& target, int width, int height,
                       int supersample = 2, const TextureWrap& wrap = {});

/// One material's part in transfer_textures: its image, or, when that is empty, its colour.
struct TextureSource {
  Image image;
  TextureWrap wrap;
  Vec3d colour{1, 1, 1};
};

/// transfer_texture for faces reading different images (several materials): face f reads
/// sources[face_source[f]] through the source mesh's texture coordinates. One image keeps its
/// own channels; several meet in grey or RGB (colour when any is), with alpha when any has it
/// (opaque where a source has none), and the deepest bits.
/// \throw InputError as transfer_texture, and when a face names no source or an image has
///        other channels than grey or RGB with or without alpha among several.
/// The sources are taken by value: moved in, their images are resampled without a copy.
Image transfer_textures(const Mesh& source, std::vector<TextureSource> sources,
                        const std::vector<int>& face_source, const Mesh& target, int width, int height,
                        int supersample = 2);

struct SaeResult {
  /// Signal approximation error: sqrt(∫_S |f − f̃|² dA / ∫_S dA), f the signal, f̃ its
  /// bilinear reconstruction from the baked texture, |·| the Euclidean norm over channels.
  double sae = 0;
  /// sqrt(∫_S |f − f̄|² dA / ∫_S dA), the signal's own spread, for scale.
  double signal_rms = 0;
  long long samples = 0;  ///< surface points integrated
  double seconds = 0;
};

/// SAE of an atlas at W×H (Sander et al. 2002 §5; Iso-charts §9.3): bakes the signal with
/// bake_signal and integrates the difference at area-weighted surface points (each face
/// subdivided into n² sub-triangles, n from its UV extent so a sub-triangle spans at most half
/// a texel, midpoint rule per sub-triangle). `mesh` carries the atlas's UVs; the signal must
/// be defined on the same vertices and faces. `baked` (optional) receives the texture.
SaeResult signal_approximation_error(const Mesh& mesh, const Signal& signal, int width, int height,
                                     Image* baked = nullptr);

/// How build_signal_atlas uses the signal.
enum class SignalUse {
  None,   ///< geometric atlas (the signal is only measured)
  Param,  ///< geometric charts, each re-optimized in the signal metric; signal-weighted packing
  Full,   ///< signal metric and eq. 6 distances for splitting and merging, then as Param
};

struct SignalAtlasOptions {
  SignalUse use = SignalUse::Full;
  /// λ of signal_metric: weight of the signal against the geometry in the metric.
  double lambda = 2.0;
  /// λ of the metric that decides chart splitting and merging (Full); 0 = `lambda`. A larger
  /// value separates high-signal regions into their own charts, which packing then enlarges.
  double chart_lambda = 0;
  /// Full: AtlasOptions::signal_split_efficiency for the signal charts (0 = off).
  double split_efficiency = 0.7;
  /// Geometric L2 stretch each chart must still meet (normalized, 1 = isometric); a
  /// signal-optimized chart over it falls back to a weaker signal weight, then to its
  /// geometric parameterization. The geometric Linf bound of AtlasOptions always holds.
  double max_geometric_l2 = 2.0;
  /// β of eq. 6 (Iso-charts §7): weight of the geodesic distance against the signal distance
  /// (summed along the geodesic paths) in the distances the spectral analysis and the graph
  /// cut see (Full only; 1 = geometric). The paper's 0.5 (bench/README.md, Signal section).
  double beta = 0.5;
};

/// Per-atlas signal figures, alongside AtlasStats.
struct SignalAtlasStats {
  double signal_stretch = 0;  ///< signal_stretch() of the final atlas
  double metric_l2 = 0;       ///< L2 stretch in the combined metric, whole atlas
  int reverted_charts = 0;    ///< charts whose signal re-optimization broke a bound (kept as they were)
  double seconds = 0;         ///< time spent on the signal (IMT, re-optimization, re-packing)
};

/// \throw InputError (no file) naming the option (as the CLI spells it) out of its range.
void validate_signal_options(const SignalAtlasOptions& options);

/// Builds an atlas whose charts (Full) and parameterizations (Param, Full) adapt to `signal`
/// (Iso-charts §7), then packs charts with texture area in proportion to their signal-weighted
/// size: each chart's UV area ∝ sqrt(E·A_uv), E its energy Σ A·tr(JᵀGJ), which minimizes the
/// total energy for a fixed texture. No flips and no overlaps, geometric Linf ≤ max_linf.
/// \throw InputError for invalid options, as build_atlas.
Atlas build_signal_atlas(const Mesh& mesh, const Signal& signal, const AtlasOptions& options,
                         const SignalAtlasOptions& signal_options, SignalAtlasStats* stats = nullptr,
                         const Progress& progress = {});

/// Writes one line per face "g00 g01 g11" (IMT, face frame as Imt) to `path`, atomically.
void write_imt(const std::string& path, const std::vector<Imt>& imt);

}  // namespace isochart
