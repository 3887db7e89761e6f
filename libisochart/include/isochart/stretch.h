#pragma once
/// Geometric stretch of a parameterization (Sander et al. 2001; Iso-charts §3) and the
/// other quality figures of an atlas: flips, exact UV overlaps, packing ratio, seams.

#include <vector>

#include "isochart/mesh.h"

namespace isochart {

/// A stretch bound b is met by values up to b · kStretchBoundSlack: a plane laid out exactly
/// measures Linf 1 + 4e-15, and --max-linf 1 without the slack gave every triangle a chart.
constexpr double kStretchBoundSlack = 1 + 1e-9;

/// Stretch of one triangle's map from texture space to the surface. Γ and γ are the
/// largest and smallest singular values of its Jacobian. Not normalized.
struct TriangleStretch {
  double gamma_max = 0;  ///< Γ
  double gamma_min = 0;  ///< γ
  double l2 = 0;         ///< sqrt((Γ² + γ²) / 2); +inf when flipped or degenerate
  double linf = 0;       ///< max(Γ, 1/γ); +inf when flipped or degenerate
  bool flipped = false;  ///< UV area ≤ 0 (clockwise or degenerate in texture space)
};

/// \param q 3D corners, \param p texture corners (counter-clockwise for a valid map).
TriangleStretch triangle_stretch(const Vec3d q[3], const Vec2d p[3]);

/// Whole-parameterization stretch, normalized so that 1.0 is ideal: texture coordinates are
/// scaled so the total texture area equals the total surface area before Γ, γ are taken.
/// L2 = sqrt(Σ A3D·(Γ²+γ²)/2 / Σ A3D); Linf = max over triangles of max(Γ, 1/γ).
/// Zero-area 3D triangles are skipped. Any flipped triangle makes both infinite.
struct StretchStats {
  double l2 = 0;
  double linf = 0;
  int flipped = 0;        ///< triangles with UV area ≤ 0
  int degenerate = 0;     ///< of those, triangles with zero UV area (not turned over, but no stretch either)
  double area_3d = 0;     ///< total surface area
  double area_uv = 0;     ///< total |UV area|
  int worst_face = -1;    ///< face reaching linf
};

/// Per-corner UVs: uv(f, k) is the texture coordinate of corner k of face f.
/// `faces` selects the faces to measure (all when empty).
StretchStats measure_stretch(const Mesh& mesh, const std::vector<int>& faces = {});

/// The whole mesh's stretch on a texture `texture_aspect` (width / height) times as wide as
/// high, i.e. in texels: a unit of u is that many times as long as a unit of v. A chart packed
/// without distortion in texels is anisotropic in [0,1]² when the texture is not square.
StretchStats measure_texture_stretch(const Mesh& mesh, double texture_aspect);

/// The width / height of the texture a mesh's UVs were laid out for, read from the UVs
/// themselves (a file's [0,1]² coordinates do not say): the area-weighted geometric mean over
/// the faces of |∂p/∂u| / |∂p/∂v|, which is W/H for charts laid out without stretch in texels.
/// Uneven stretch in charts of every orientation scatters it by a few percent, so an estimate
/// within 10 % of a power of two (1 included) returns that power exactly. Returns 1 when the
/// charts disagree (their per-chart estimates spread by more than a factor 1.4: a stretched
/// chart, not the texture), for a mesh without UVs and without a face of positive area.
double detect_texture_aspect(const Mesh& mesh);

/// Same with per-vertex UVs (one UV per mesh vertex, as for a single chart).
StretchStats measure_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                             const std::vector<Vec2d>& uv);

/// Per-face normalized stretch values (l2, linf) with the same normalization as
/// measure_stretch over the whole mesh.
std::vector<TriangleStretch> per_face_stretch(const Mesh& mesh);

/// Pairs of UV triangles whose interiors overlap, found with exact orientation predicates
/// (triangles that only touch along an edge or at a point do not count). Flipped or
/// degenerate UV triangles are reported by measure_stretch, not here, unless they overlap
/// another triangle's interior. Returns at most `max_pairs` pairs (all when 0).
std::vector<std::pair<int, int>> overlapping_uv_pairs(const std::vector<std::array<Vec2d, 3>>& tris,
                                                      std::size_t max_pairs = 0);
std::vector<std::pair<int, int>> overlapping_uv_pairs(const Mesh& mesh, std::size_t max_pairs = 0);

/// True when the UV layout of a chart (triangles indexing `uv`) is proven one-to-one: the
/// triangles form a topological disk, every triangle has the same strict orientation (exact
/// predicates) and the boundary polygon is simple. Then every point off the boundary's image
/// has as many preimages as the boundary winds around it, at most one, so no two interiors
/// overlap (overlapping_uv_pairs would find none). False means "not proven", not "overlaps":
/// the caller falls back to overlapping_uv_pairs. Costs a pass over the triangles and a
/// segment intersection test of the boundary only, against the all-pairs test of every
/// triangle. `topo` is the triangles' connectivity when the caller has it.
bool uv_layout_is_embedding(const std::vector<Face>& tris, const std::vector<Vec2d>& uv, const Topology& topo);
bool uv_layout_is_embedding(const std::vector<Face>& tris, const std::vector<Vec2d>& uv);

/// Charts of a mesh with per-corner UVs: faces connected through edges whose two sides
/// share texture coordinates. Returns the chart id per face; `num_charts` receives the count.
std::vector<int> uv_charts(const Mesh& mesh, int& num_charts);

/// The chart with the fewest texels for its surface: its share of the UV area over its share of
/// the surface area, 1 for every chart when texels are spread evenly. A chart shrunk to a speck
/// by a broken atlas reads 1e-9; real atlases, signal-specialized ones included, keep above 0.5.
struct ChartDensity {
  double density = 1;
  int first_face = -1;  ///< -1 without a chart of positive surface and UV area
  int faces = 0;
};
ChartDensity sparsest_chart(const Mesh& mesh);

/// All the figures `isocharts stats` prints.
struct AtlasQuality {
  int charts = 0;
  /// Charts laid out mirrored as a whole (UVAtlas writes v downwards: all of them). Stretch and
  /// flips are measured with them unmirrored, so `stretch.flipped` counts triangles turned
  /// against their own chart; a mirrored chart still breaks tangent-space normal maps.
  int mirrored_charts = 0;
  StretchStats stretch;
  long long overlapping_pairs = 0;
  double packing_ratio = 0;   ///< total UV area / area of the UV bounding box
  double uv_area = 0;
  double seam_length = 0;     ///< 3D length of interior mesh edges cut by the atlas
  double seam_length_relative = 0;  ///< seam_length / sqrt(surface area)
  Vec2d uv_min, uv_max;       ///< UV bounding box
  ChartDensity sparsest;
};
/// `texture_aspect`: as for measure_texture_stretch.
AtlasQuality measure_atlas(const Mesh& mesh, double texture_aspect = 1);

}  // namespace isochart
