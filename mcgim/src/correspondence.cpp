// GCC (with -fsanitize) reports a false -Wmaybe-uninitialized inside CGAL's ray query, where a
// boost::optional<double> is returned empty; the warning comes from inlined header code.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include "mcgim/correspondence.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "aabb.h"
#include "closest_point.h"
#include "isochart/error.h"

namespace mcgim {

namespace {

using isochart::Vec2d;
using isochart::Vec3d;

}  // namespace

std::vector<Correspondence> shoot_normals(const GeometryImage& fine, const GeometryImage& coarse_image,
                                          const Remesh& coarse, const ShootOptions& o,
                                          const isochart::Progress& progress) {
  const detail::TriangleSet ts(coarse.mesh);
  if (ts.empty()) throw isochart::InputError("", "the coarser remesh has no face of positive area");
  const int defined = coarse_image.defined_samples();
  const double texel = std::sqrt(isochart::surface_area(coarse.mesh) / std::max(defined, 1));
  const double reach = o.max_distance_texels * texel;
  const std::vector<Vec3d> fn = isochart::face_normals(coarse.mesh);
  const int W = coarse_image.width;
  const std::size_t N = fine.chart.size();
  std::vector<Correspondence> out(N);
  const std::size_t chunk = 4096;
  const std::size_t chunks = (N + chunk - 1) / chunk;
  std::atomic<std::size_t> done{0};
  isochart::report(progress, isochart::Stage::Correspondence, 0.0);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t ci) {
    const std::size_t end = std::min(N, (ci + 1) * chunk);
    for (std::size_t i = ci * chunk; i < end; ++i) {
      if (!fine.defined(static_cast<int>(i))) continue;
      const Vec3d p = fine.positions[i];
      const Vec3d n = fine.normals[i];
      Correspondence& c = out[i];
      double best = std::numeric_limits<double>::infinity();
      if (squared_norm(n) > 0) {
        for (double sign : {1.0, -1.0}) {
          const detail::Kernel::Ray_3 ray(detail::to_point(p),
                                          detail::Kernel::Vector_3(sign * n.x, sign * n.y, sign * n.z));
          const auto hit = ts.tree.first_intersection(ray);
          if (!hit) continue;
          Vec3d q;
          if (const auto* pt = boost::get<detail::Point3>(&hit->first)) {
            q = detail::to_vec(*pt);
          } else if (const auto* sg = boost::get<detail::Kernel::Segment_3>(&hit->first)) {
            const Vec3d s0 = detail::to_vec(sg->source()), s1 = detail::to_vec(sg->target());
            q = squared_norm(s0 - p) <= squared_norm(s1 - p) ? s0 : s1;
          } else {
            continue;
          }
          const int f = ts.face_of(hit->second);
          const double d = norm(q - p);
          if (d > reach || d >= best || dot(fn[f], n) <= o.min_cosine) continue;
          best = d;
          c.face = f;
          c.point = q;
          c.hit = true;
        }
      }
      if (!c.hit) {
        const auto cp = ts.tree.closest_point_and_primitive(detail::to_point(p));
        c.point = detail::to_vec(cp.first);
        c.face = ts.face_of(cp.second);
      }
      c.distance = norm(c.point - p);
      const auto& fv = coarse.mesh.faces[c.face];
      c.barycentric = detail::barycentric_of(c.point, coarse.mesh.positions[fv[0]], coarse.mesh.positions[fv[1]],
                                     coarse.mesh.positions[fv[2]]);
      const auto& s = coarse.face_samples[c.face];
      const double b[3] = {c.barycentric.x, c.barycentric.y, c.barycentric.z};
      c.image_xy = {};
      for (int k = 0; k < 3; ++k) c.image_xy += Vec2d{s[k] % W + 0.5, s[k] / W + 0.5} * b[k];
      c.chart = coarse_image.chart[s[0]];
    }
    const std::size_t k = ++done;
    isochart::report(progress, isochart::Stage::Correspondence, static_cast<double>(k) / chunks);
  });
  return out;
}

}  // namespace mcgim
