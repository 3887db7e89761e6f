// CGAL's exact geodesics, kept in their own translation unit because the headers take long to
// compile and are needed only as a reference.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_shortest_path.h>

#include <limits>
#include <string>

#include "isochart/error.h"
#include "isochart/geodesic.h"

namespace isochart {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Traits = CGAL::Surface_mesh_shortest_path_traits<Kernel, SurfaceMesh>;
using ShortestPath = CGAL::Surface_mesh_shortest_path<Traits>;
}  // namespace

std::vector<double> exact_geodesic_distances(const std::vector<Vec3d>& positions,
                                             const std::vector<Face>& faces, int source) {
  const int nv = static_cast<int>(positions.size());
  if (source < 0 || source >= nv)
    throw Error("exact geodesics: source " + std::to_string(source) + " is not a vertex");
  std::vector<double> out(positions.size(), std::numeric_limits<double>::infinity());
  out[source] = 0;

  // Only referenced vertices go into the CGAL mesh: isolated vertices have no face location.
  std::vector<SurfaceMesh::Vertex_index> handle(positions.size());
  std::vector<char> used(positions.size(), 0);
  for (const Face& f : faces)
    for (int v : f) {
      if (v < 0 || v >= nv)
        throw InputError("", "exact geodesics: a face references vertex " + std::to_string(v) +
                                 ", but there are " + std::to_string(nv) + " vertices");
      used[v] = 1;
    }
  if (!used[source]) return out;

  SurfaceMesh mesh;
  for (int v = 0; v < nv; ++v)
    if (used[v]) handle[v] = mesh.add_vertex(Kernel::Point_3(positions[v].x, positions[v].y, positions[v].z));
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const auto fh = mesh.add_face(handle[faces[f][0]], handle[faces[f][1]], handle[faces[f][2]]);
    if (fh == SurfaceMesh::null_face())
      throw InputError(
          "", "exact geodesics: face " + std::to_string(f) + " breaks the oriented 2-manifold CGAL needs");
  }

  ShortestPath paths(mesh);
  paths.add_source_point(handle[source]);
  for (int v = 0; v < nv; ++v) {
    if (!used[v] || v == source) continue;
    const double d = CGAL::to_double(paths.shortest_distance_to_source_points(handle[v]).first);
    if (d >= 0) out[v] = d;
  }
  return out;
}

}  // namespace isochart
