#pragma once
/// Geometric distance between two surfaces and the geometric PSNR of a remesh
/// (Sander et al. 2003; Iso-charts §9.2, Table II).

#include <cstdint>

#include "isochart/mesh.h"
#include "isochart/progress.h"

namespace mcgim {

struct DistanceOptions {
  /// Points sampled on each surface, spread over the faces in proportion to their area.
  long long samples = 1'000'000;
  /// The sample points depend only on this seed and the meshes (not on the thread count).
  std::uint64_t seed = 1;
};

/// One-sided distances are taken from points sampled on one surface to the exact closest point
/// of the other (point-to-triangle, over all triangles).
struct DistanceResult {
  double rms_ab = 0;     ///< RMS distance from points of A to B (model units)
  double rms_ba = 0;     ///< RMS distance from points of B to A
  double max_ab = 0;     ///< largest sampled distance from A to B
  double max_ba = 0;     ///< largest sampled distance from B to A
  double hausdorff = 0;  ///< max(max_ab, max_ba): sampled symmetric Hausdorff distance
  double diagonal = 0;   ///< bounding-box diagonal of A, the PSNR peak
  /// 20·log10(diagonal / max(rms_ab, rms_ba)) in dB: the headline figure; +inf when the
  /// distance is zero.
  double psnr = 0;
  /// 20·log10(diagonal / mean(rms_ab, rms_ba)) in dB, the other convention in use.
  double psnr_mean = 0;
  long long samples_a = 0;
  long long samples_b = 0;
  double seconds = 0;
};

/// Symmetric RMS surface distance and PSNR between A (the original) and B (e.g. a remesh).
/// Zero-area faces get no samples and are ignored as targets.
/// \throw isochart::InputError when a mesh has no face of positive area or samples < 1.
/// \throw isochart::Cancelled when `progress` returns false.
DistanceResult measure_distance(const isochart::Mesh& a, const isochart::Mesh& b,
                                const DistanceOptions& options = {},
                                const isochart::Progress& progress = {});

/// 20·log10(peak / d); +inf for d ≤ 1e-14·peak (rounding: the surfaces are the same).
double psnr_db(double peak, double d);

}  // namespace mcgim
