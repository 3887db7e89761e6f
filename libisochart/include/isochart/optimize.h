#pragma once
/// Stretch optimization of one chart's parameterization (Sander et al. 2001; Iso-charts §6).

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

#include "isochart/mesh.h"
#include "isochart/stretch.h"

namespace isochart {

struct OptimizeOptions {
  /// Sweeps over the vertices, worst first (Iso-charts §6: "a few iterations").
  int passes = 6;
  /// Random line-search directions tried per vertex and sweep (§6: up to 6).
  int tries = 6;
  /// A vertex stops trying new directions once a try improves its objective by less than this
  /// fraction (§6 uses 10%).
  double min_improvement = 0.1;
  /// Linf bound the optimizer works to keep every triangle under, with a margin (normalized
  /// stretch, shrink included). Triangles above `linf_margin * max_linf` are penalized.
  double max_linf = 5.0;
  double linf_margin = 0.9;
  /// Weight of the Linf penalty relative to the normalized L2² term.
  double linf_weight = 4.0;
  /// Only vertices whose 1-ring normalized L2 exceeds this, or whose ring violates the Linf margin,
  /// are moved in a sweep (§6: "greater than the user-specified limit"). 0 moves every vertex.
  double vertex_l2_threshold = 0.0;
  /// Fraction of the kernel segment used (keeps triangles away from degeneracy).
  double conservative = 0.8;
  /// Extra sweeps, after the main ones, over just the vertices of triangles still above the
  /// Linf bound, with a stronger Linf weight: the worst spots are few and local, and the L2
  /// sweeps weigh them little.
  int linf_repair_passes = 10;
  /// Stop early when the chart cannot reach this L2 stretch: after each sweep, the L2 reached
  /// if every remaining sweep gained as much as the last one is compared with it. 0 = never.
  double give_up_l2 = 0;
  std::uint64_t seed = 1;
  /// Signal-specialized metric (Sander et al. 2002; Iso-charts §7): #F symmetric tensors
  /// (g00, g01, g11) per unit surface area, in each face's own frame (x along corner 0 → 1,
  /// y towards corner 2). The L2 term becomes Σ A·tr(Jᵀ G J)/2 normalized by the metric area
  /// Σ A·sqrt(det G); the Linf term stays geometric so no triangle degenerates. Empty: G = I.
  std::vector<std::array<double, 3>> face_metric;
  /// Least UV distance kept between parts of a chart's boundary that are not neighbours, as a
  /// fraction of its mean boundary edge length: a move into that margin is refused unless it
  /// widens the gap. 0: the boundary only has to stay simple. A boundary closing in on itself
  /// keeps the chart one-to-one but bakes far-apart surface points into the same texels.
  double boundary_clearance = 0;
  /// When set and it turns true, the optimization stops at the next vertex (the caller no
  /// longer wants the result: a merge attempt computed ahead and then abandoned).
  const std::atomic<bool>* cancel = nullptr;
};

/// OptimizeOptions::boundary_clearance of signal-specialized charts (their parameterization
/// and re-optimization).
inline constexpr double kSignalBoundaryClearance = 0.5;

struct OptimizeResult {
  StretchStats before, after;
  long long moves = 0;   ///< accepted vertex moves
  int sweeps = 0;
  bool gave_up = false;  ///< stopped because give_up_l2 was out of reach
};

/// Removes flipped triangles from a chart's parameterization, as far as local moves can: each
/// vertex of a flipped triangle moves to the centroid of its 1-ring kernel (Iso-charts §6: "if a
/// vertex is not in the convex kernel of its neighborhood, we relocate it to the centroid of the
/// kernel"), or, when the kernel is empty, to the mean of its neighbours, for up to `max_passes`
/// sweeps. Returns the number of flipped or degenerate triangles left.
int untangle(const std::vector<Face>& faces, std::vector<Vec2d>& uv, int max_passes = 30);
/// Same, with the caller's Topology of (faces, #V = uv.size()) instead of building one.
int untangle(const std::vector<Face>& faces, std::vector<Vec2d>& uv, const Topology& topology, int max_passes = 30);

/// Optimizes per-vertex texture coordinates `uv` (#V) of a chart (positions #V, faces #F, CCW in
/// texture space) in place, reducing the normalized L2 stretch while pushing every triangle's
/// max(Γ, 1/γ) under the Linf margin. Each vertex moves by random line searches inside the kernel
/// of its 1-ring, so no triangle is ever flipped; boundary vertices move too (free boundary).
/// \pre no triangle of `uv` is flipped or degenerate (otherwise nothing moves and the result
///      reports the flips).
OptimizeResult optimize_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                                std::vector<Vec2d>& uv, const OptimizeOptions& options = {});
/// Same, with the caller's Topology of (faces, #V = uv.size()) instead of building one: a chart
/// tried from several starts is then analysed once. The result is the same.
OptimizeResult optimize_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                                std::vector<Vec2d>& uv, const OptimizeOptions& options, const Topology& topology);

}  // namespace isochart
