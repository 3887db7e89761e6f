#pragma once
/// Baseline atlases that `isocharts bench` compares iso-charts against, each returned as an
/// isochart::Atlas so that every method is packed by our packer and measured the same way:
/// - LSCM charts (Lévy et al. 2002 parameterization over charts grown by Lloyd clustering with
///   Sander et al. 2003's distance × normal metric), optionally stretch-optimized afterwards;
/// - any atlas another tool wrote (a mesh with per-corner texture coordinates).

#include <cstdint>
#include <string>
#include <vector>

#include "isochart/atlas.h"
#include "isochart/mesh.h"
#include "isochart/optimize.h"
#include "isochart/pack.h"
#include "isochart/progress.h"

namespace isochart {

struct LscmOptions {
  /// A chart is split in two while its LSCM parameterization's normalized L2 stretch exceeds
  /// this: the same stopping rule as AtlasOptions::max_l2, so chart counts compare at equal
  /// stretch (Iso-charts §9, Fig. 19 uses the same thresholds for both methods).
  double max_l2 = 1.1;
  /// Same rule for the normalized Linf stretch, shrink included (AtlasOptions::max_linf).
  /// Infinity disables it.
  double max_linf = 5.0;
  /// Lloyd iterations of each two-way split (seed re-centring, Sander et al. 2003 §3.2).
  int lloyd_iterations = 3;
  /// λ of the region-growing cost (λ − n_seed·n_face)·|Δcentroid| (Sander et al. 2003):
  /// smaller values follow creases more eagerly. Must exceed 1 so every cost is positive.
  double normal_lambda = 2.0;
  /// Packing of the final charts (packed by pack_atlas, like the iso-chart atlas).
  PackOptions pack;
};

/// The `lscm` baseline: every mesh component starts as one chart; a chart is split in two by
/// Lloyd clustering (two seeds, feature-aware region growing) until it is a topological disk
/// whose LSCM parameterization (CGAL's LSCM_parameterizer_3, two pinned border vertices) has no
/// flipped triangle, no self-overlap, and stretch within `max_l2` / `max_linf`. Charts are
/// packed with pack_atlas. Deterministic, identical for any thread count.
/// `stats.splits` counts the two-way splits; seconds per stage are in `stats.seconds`:
/// "clustering", "parameterization", "packing", "total".
/// \throw InputError for invalid options or a mesh without faces or not edge-manifold.
/// \throw Cancelled when `progress` returns false.
Atlas build_lscm_atlas(const Mesh& mesh, const LscmOptions& options = {}, const Progress& progress = {});

/// The `lscm+stretch` baseline step: stretch-optimizes every chart of `atlas` in place with
/// optimize_stretch (Sander et al. 2001; Iso-charts §6), keeping the charts. A chart whose
/// optimized layout overlaps itself keeps its previous layout. Re-packs with `pack` and
/// refreshes the statistics; adds "optimization" and "packing" to `stats.seconds`.
/// `options.max_linf` should be the bound the charts were built for.
void optimize_atlas_stretch(const Mesh& mesh, Atlas& atlas, const OptimizeOptions& options = {},
                            const PackOptions& pack = {}, const Progress& progress = {});

/// Turns a mesh with per-corner texture coordinates (e.g. another tool's atlas read from an
/// OBJ with `vt`) into an Atlas of `mesh`'s faces: charts are the edge-connected pieces with
/// continuous texture coordinates (isochart::uv_charts). A chart laid out mirrored (negative
/// total signed UV area; UVAtlas writes v flipped) is mirrored back so that stretch counts no
/// flips; packers may mirror freely. UVs laid out for a texture `texture_aspect` times as wide
/// as high (0: detect_texture_aspect reads it from the UVs) are first scaled along u to square
/// texels. Not packed: call pack_atlas.
/// \throw InputError when the mesh has no texture coordinates or a chart has zero UV area.
Atlas atlas_from_uvs(const Mesh& mesh, double texture_aspect = 0);

/// A topological-disk check of one chart as MCGIM sampling needs it: one edge-connected,
/// edge- and vertex-manifold component with exactly one boundary loop and Euler
/// characteristic 1. `faces` are mesh face ids.
bool is_disk(const Mesh& mesh, const std::vector<int>& faces);

}  // namespace isochart
