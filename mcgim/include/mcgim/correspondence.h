#pragma once
/// Sample correspondence between two levels of an MCGIM pyramid by normal shooting
/// (Sander et al. 2002; Iso-charts §8): the levels are packed and zippered separately, so a
/// sample of one level is linked to the surface of the next coarser level explicitly.

#include <vector>

#include "isochart/progress.h"
#include "isochart/vec.h"
#include "mcgim/geometry_image.h"

namespace mcgim {

/// Where one sample lands on the coarser level's remesh.
struct Correspondence {
  int face = -1;              ///< face of the coarser remesh, −1 for an undefined sample
  isochart::Vec3d barycentric;///< of the landing point in `face` (corners in face order)
  isochart::Vec3d point;      ///< landing point (model units)
  /// Continuous coordinates of the landing point in the coarser geometry image, in samples:
  /// sample (x, y) has its centre at (x + 0.5, y + 0.5); divide by (width, height) for uv.
  isochart::Vec2d image_xy;
  int chart = -1;             ///< chart of `face` in the coarser image
  double distance = 0;        ///< from the sample to `point` (model units)
  bool hit = false;           ///< found by the normal ray (false: closest-point fallback)
};

struct ShootOptions {
  /// Longest accepted ray, in texels of the coarser level (texel size = sqrt(surface area /
  /// defined samples)); farther hits fall back to the closest point.
  double max_distance_texels = 3.0;
  /// A hit counts only if the face it lands on faces the same way as the ray's normal
  /// (cosine above this); otherwise the ray may have crossed to another sheet.
  double min_cosine = 0.0;
};

/// For every defined sample of `fine` (position and interpolated normal), casts the line along
/// the normal both ways and keeps the nearest hit on `coarse` (the remesh of `coarse_image`);
/// the closest point on `coarse` is the fallback. Undefined samples get face −1.
/// Deterministic and independent of the thread count.
/// \throw isochart::InputError when `coarse` has no face of positive area.
std::vector<Correspondence> shoot_normals(const GeometryImage& fine,
                                          const GeometryImage& coarse_image,
                                          const Remesh& coarse, const ShootOptions& options = {},
                                          const isochart::Progress& progress = {});

}  // namespace mcgim
