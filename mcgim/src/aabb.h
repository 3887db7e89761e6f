#pragma once
// Internal: CGAL's AABB tree over the non-degenerate triangles of a mesh. Only distance.cpp
// and correspondence.cpp include it (CGAL is slow to compile).

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <vector>

#include "isochart/mesh.h"

namespace mcgim::detail {

using Kernel = CGAL::Simple_cartesian<double>;
using Point3 = Kernel::Point_3;
using Triangle3 = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle3>::const_iterator;
using AabbPrimitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using AabbTraits = CGAL::AABB_traits<Kernel, AabbPrimitive>;
using AabbTree = CGAL::AABB_tree<AabbTraits>;

inline Point3 to_point(const isochart::Vec3d& p) { return {p.x, p.y, p.z}; }
inline isochart::Vec3d to_vec(const Point3& p) { return {p.x(), p.y(), p.z()}; }

// The triangles of a mesh with positive area, and the face each one comes from. The tree is
// built completely (with its distance-query accelerator) before any concurrent query.
struct TriangleSet {
  std::vector<Triangle3> triangles;
  std::vector<int> face;
  std::vector<int> triangle_of;  ///< per mesh face, its index in `triangles` or −1 (zero area)
  AabbTree tree;

  /// Without `accelerate` (no kd-tree of start points), CGAL's own distance queries would scan
  /// for a start; the nearest-first searches of distance.cpp do not need one.
  explicit TriangleSet(const isochart::Mesh& m, bool accelerate = true) : triangle_of(m.num_faces(), -1) {
    for (int f = 0; f < m.num_faces(); ++f) {
      const auto& v = m.faces[f];
      const isochart::Vec3d& a = m.positions[v[0]];
      const isochart::Vec3d& b = m.positions[v[1]];
      const isochart::Vec3d& c = m.positions[v[2]];
      if (!(norm(cross(b - a, c - a)) > 0)) continue;
      triangle_of[f] = static_cast<int>(triangles.size());
      triangles.emplace_back(to_point(a), to_point(b), to_point(c));
      face.push_back(f);
    }
    if (triangles.empty()) return;
    tree.insert(triangles.begin(), triangles.end());
    tree.build();
    if (accelerate) tree.accelerate_distance_queries();
  }
  bool empty() const { return triangles.empty(); }
  /// Index in `triangles` of mesh face f; −1 for a face of zero area or no face.
  int triangle_index(int f) const {
    return f >= 0 && f < static_cast<int>(triangle_of.size()) ? triangle_of[f] : -1;
  }
  int face_of(TriangleIterator it) const { return face[static_cast<std::size_t>(it - triangles.begin())]; }
};

}  // namespace mcgim::detail
