#pragma once
/// Iso-charts atlas construction (Zhou, Snyder, Guo, Shum; §3–6): stretch-driven chartification
/// by spectral analysis of geodesic distances, graph-cut chart boundaries, stretch-optimized
/// parameterization, merging of small charts, and packing.

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "isochart/mesh.h"
#include "isochart/pack.h"
#include "isochart/progress.h"

namespace isochart {

struct AtlasOptions {
  /// Every chart's normalized L2 stretch must not exceed this (§3; paper default 1.1).
  double max_l2 = 1.1;
  /// Every chart's normalized Linf stretch, shrink included (max(Γ, 1/γ)), must not exceed this
  /// (§3; paper default 5.0).
  double max_linf = 5.0;
  /// 0: as few charts as the bounds need. N > 0: keep splitting the worst chart until there are
  /// N charts (never fewer than the bounds need).
  int max_charts = 0;
  /// Landmarks for the landmark IsoMap of a whole mesh component (§6; all vertices when it has
  /// fewer). A sub-chart uses this many times its share of the component's vertices, but at
  /// least 25 (UVAtlas's minimum): it measured 3-4x less fast marching for the same chart
  /// counts on bunny and gargoyle.
  int landmarks = 100;
  /// Weight of the angular term against the embedding-distortion term in the graph-cut
  /// capacity (§5.2 eq. 2).
  double alpha = 0.5;
  /// Fraction of the split chart's area forming the medial region the graph cut may move (§5.2).
  double medial_fraction = 0.3;
  /// Optimize chart boundaries by graph cut (§5.2). Off gives the "isomap-nocut" ablation.
  bool graph_cut = true;
  /// Merge charts when the merged chart still meets the bounds (§6).
  bool merge = true;
  /// Charts up to this fraction of the mesh's faces are merge candidates, smallest first. The
  /// paper uses 0.1 ("small" charts); larger values trade time for fewer charts.
  double merge_max_fraction = 0.1;
  /// Stretch-optimization sweeps per chart parameterization (§6).
  int optimize_passes = 6;
  /// Seed of every random choice; with the same seed the atlas is identical for any thread count.
  std::uint64_t seed = 1;
  /// Packing (§6): texture size, gutter, rotations; searched on a grid of at most 1024 on its
  /// longer side (PackOptions::search_size), so a 4096² atlas packs about as fast as a 1024² one.
  PackOptions pack = [] {
    PackOptions p;
    p.search_size = 1024;
    return p;
  }();
  /// Skip the packing (§6) for callers that re-pack the charts themselves (pack_atlas, e.g.
  /// once per texture size): each chart keeps its own parameterization, scaled so its UV area
  /// equals its 3-D area (one texel density, as the packer would scale it) and unrotated; the
  /// charts' bounding boxes are then laid out in rows, apart from one another, and the whole
  /// layout is scaled uniformly into [0,1]². No gutter at any texture size, and a low packing
  /// ratio. Stats: packing_ratio is 0, overlapping_pairs is -1 (not measured: the boxes are
  /// disjoint and every chart was accepted without self-overlap); l2, linf and flipped are
  /// measured as usual. pack_cuts is ignored.
  bool skip_packing = false;
  /// Extension beyond §6: before packing, cut up to this many extra charts off poorly shaped
  /// ones (straight cuts in UV, each piece within the bounds) when that packs tighter; -1 lets
  /// the packer decide (atlases under 12 charts, at most doubling them). 0 (default) keeps the
  /// fewest charts: measured on the shared meshes, -1 raised packing by 0.03–0.14 on the seven
  /// meshes under 12 charts, doubled their charts and lengthened their seams by 35–165 %, and
  /// took about 4× the packing time (bench/README.md). Ignored with max_charts.
  int pack_cuts = 0;
  /// Signal-specialized charts (§7; see signal.h, which fills this): #F metric tensors
  /// (g00, g01, g11) per unit surface area in each face's frame (x along corner 0 → 1). When
  /// given, charts are split, merged and parameterized by their L2 stretch in this metric
  /// (bound max_l2), and must also meet max_geometric_l2 and max_linf geometrically. Empty:
  /// the geometric method.
  std::vector<std::array<double, 3>> face_metric;
  /// Geometric L2 bound kept with face_metric (normalized, 1 = isometric).
  double max_geometric_l2 = 2.0;
  /// With face_metric: a chart of more than 1% of the mesh's faces is split when the signal
  /// energy of its best texel allocation, (Σ A·√m)²/A, is below this fraction of the energy of
  /// a uniform one, Σ A·m (m = tr(G)/2 − 1, the signal part of the metric): its signal is too
  /// uneven for one texel density (signal stretch as splitting criterion, §7). 0 = off.
  double signal_split_efficiency = 0;
  /// Signal per vertex (#V × signal_dimension) for the combined distance of §7 eq. 6 in the
  /// spectral analysis and graph cut of chart splitting, with weight `signal_beta` on the
  /// geodesic part (1 = geodesic only). Empty: geodesic distances.
  std::vector<double> vertex_signal;
  int signal_dimension = 0;
  double signal_beta = 1.0;
};

/// One chart of the atlas.
struct ChartInfo {
  int faces = 0;
  double area_3d = 0;
  double l2 = 0;    ///< normalized L2 stretch of the chart
  double linf = 0;  ///< normalized Linf stretch (shrink included)
};

/// Figures describing the whole atlas (what `isocharts atlas --json` reports).
struct AtlasStats {
  int charts = 0;
  int charts_before_merge = 0;
  double l2 = 0;            ///< whole-atlas normalized L2 stretch
  double linf = 0;          ///< whole-atlas normalized Linf stretch
  int flipped = 0;          ///< flipped UV triangles
  long long overlapping_pairs = 0;  ///< UV triangle pairs whose interiors overlap (exact); -1 = not measured
  double packing_ratio = 0; ///< Σ chart UV area / UV bounding box area
  int splits = 0;           ///< chart subdivisions performed
  std::uint64_t seed = 0;
  /// Seconds per stage summed over worker threads (geodesics, embedding, optimization,
  /// clustering, graph_cut, merging, packing), and "total" wall-clock seconds.
  std::map<std::string, double> seconds;
};

/// A texture atlas of a mesh: a chart per face and a texture coordinate per face corner.
struct Atlas {
  std::vector<int> face_chart;  ///< #F chart id per face
  std::vector<Vec2d> uvs;       ///< texture coordinates, referenced by face_uvs
  std::vector<Face> face_uvs;   ///< #F indices into uvs
  std::vector<ChartInfo> charts;
  AtlasStats stats;

  int num_charts() const { return static_cast<int>(charts.size()); }
  /// The mesh with this atlas's UVs and one face group per chart.
  Mesh apply_to(const Mesh& mesh) const;
};

/// Builds, optimizes, merges and packs the iso-chart atlas of `mesh` (a validated, manifold,
/// consistently oriented mesh; several components are fine).
/// \throw InputError for invalid options, Cancelled when `progress` returns false.
Atlas build_atlas(const Mesh& mesh, const AtlasOptions& options = {}, const Progress& progress = {});

/// Re-packs an atlas's charts (e.g. for another texture size) and refreshes its statistics.
PackResult pack_atlas(const Mesh& mesh, Atlas& atlas, const PackOptions& options, const Progress& progress = {});

/// Checks AtlasOptions and throws InputError naming the first bad option.
void validate_options(const AtlasOptions& options);

}  // namespace isochart
