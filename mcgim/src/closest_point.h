#pragma once
// Internal: exact closest points on a triangle mesh, without CGAL in the header (the AABB tree
// lives in distance.cpp). Queries are const and safe from several threads.

#include <memory>

#include "isochart/mesh.h"

namespace mcgim::detail {

class ClosestPoints {
 public:
  /// Faces of zero area are left out. \pre the mesh has a face of positive area (see empty()).
  explicit ClosestPoints(const isochart::Mesh& mesh);
  ~ClosestPoints();
  ClosestPoints(const ClosestPoints&) = delete;
  ClosestPoints& operator=(const ClosestPoints&) = delete;

  bool empty() const;
  struct Hit {
    int face = -1;
    isochart::Vec3d point;
  };
  Hit closest(const isochart::Vec3d& p) const;
  /// The same closest point, found faster from a point of the surface near p (`near.point`
  /// on face `near.face`): it bounds the search from the start. A face of zero area or −1
  /// is no hint.
  Hit closest(const isochart::Vec3d& p, const Hit& near) const;
  /// The point of face f at barycentric coordinates b; face −1 when f has zero area.
  Hit point_at(int f, const isochart::Vec3d& b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Barycentric coordinates (clamped to the triangle) of the point of triangle abc nearest to p.
isochart::Vec3d barycentric_of(const isochart::Vec3d& p, const isochart::Vec3d& a, const isochart::Vec3d& b,
                               const isochart::Vec3d& c);

}  // namespace mcgim::detail
