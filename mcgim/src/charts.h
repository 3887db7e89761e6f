#pragma once
// Internal: the charts of an atlas, their boundary loops, and the cut graph along which
// neighbouring charts are zippered (Sander et al. 2003 §3.2: cut-nodes and cut-paths).

#include <memory>
#include <mutex>
#include <vector>

#include "isochart/mesh.h"
#include "isochart/vec.h"
#include "mcgim/mcgim.h"

namespace mcgim::detail {

using isochart::Face;
using isochart::Mesh;
using isochart::Vec2d;
using isochart::Vec3d;

// One chart: an edge-connected set of faces with continuous texture coordinates, a disk.
struct Chart {
  std::vector<int> faces;         // parent face ids, ascending
  std::vector<Face> local_faces;  // chart vertex ids per face, in the parent's winding
  std::vector<int> mesh_vertex;   // chart vertex -> parent vertex
  std::vector<Vec2d> uv;          // input texture coordinates per chart vertex
  double area_3d = 0;
  double area_uv = 0;             // signed area of the input layout (< 0: mirrored)
  // The boundary loop as chart vertices, oriented like the faces (counter-clockwise in texture
  // space unless mirrored). Loop edge e joins loop[e] and loop[(e + 1) % L].
  std::vector<int> loop;
  std::vector<int> loop_side;     // side id per loop edge
  std::vector<int> sides;         // side ids in loop order, starting at loop edge 0's side
  // Cuts added to open a chart with holes into a disk, as chart vertex paths from a hole to
  // the rest of the boundary (vertex ids of one side; the other side has the same uvs).
  std::vector<std::vector<int>> slits;
  // The loops of those holes (chart vertex ids; each id keeps its uv after the slits split
  // vertices): a sample whose centre lies inside one would close the hole.
  std::vector<std::vector<int>> holes;
};

// A maximal run of a chart's loop between two consecutive nodes: one side of a cut path.
struct Side {
  int chart = -1;
  int first_edge = 0;   // loop edge where the side starts; loop[first_edge] is its start node
  int num_edges = 0;
  int path = -1;
  bool reversed = false;  // runs along its path from the path's end to its start
  bool has_nodes = true;  // false only for a whole loop on the mesh boundary without any node
};

// A cut path between two nodes, as a chain of mesh vertices with 3-D arc length. Two-sided
// paths separate two charts (or one chart from itself); one-sided paths run along the mesh
// boundary and stay open.
struct CutPath {
  std::vector<int> vertices;   // start node .. end node (for a node-less loop: first repeated)
  std::vector<double> arclen;  // cumulative 3-D length at each vertex
  int side_a = -1;             // runs forward
  int side_b = -1;             // runs backward; -1 for a mesh-boundary path
  double length() const { return arclen.empty() ? 0.0 : arclen.back(); }
};

class ClosestPoints;  // closest_point.h

// What the sample fit needs of the input surface: its closest-point search and face normals,
// built on first use (see original_surface in optimize_samples.cpp) and kept for every level and
// retry of the atlas (a coarse level's retries each rebuilt the search tree).
struct SurfaceCache {
  std::once_flag once;
  std::unique_ptr<ClosestPoints> closest;
  std::vector<Vec3d> face_normals;
  SurfaceCache();
  ~SurfaceCache();
};

struct AtlasCharts {
  const Mesh* mesh = nullptr;
  std::shared_ptr<SurfaceCache> surface = std::make_shared<SurfaceCache>();
  isochart::Topology topology;
  std::vector<Vec3d> vertex_normals;
  std::vector<Chart> charts;
  std::vector<Side> sides;
  std::vector<CutPath> paths;
  std::vector<char> is_node;  // per mesh vertex
  int num_nodes = 0;
  int num_artificial_nodes = 0;
  int input_euler = 0;
  int input_boundary_loops = 0;
  double surface_area = 0;
  // Width / height of the texture the atlas's UVs were laid out for (given, or read by
  // detect_texture_aspect): re-packing scales u by it, so charts from a 4:1 texture are not
  // packed 4 times flattened.
  double uv_aspect = 1;
};

// Splits the atlas into charts, checks that each is a disk, and builds the cut graph.
// `texture_aspect`: the width / height the UVs were laid out for; 0 reads it from them.
// \throw InputError for an invalid atlas (see build_level).
AtlasCharts prepare_atlas(const Mesh& atlas, double texture_aspect);

// The charts' layout in one image, in texel units (sample (x, y) has its centre at (x+.5, y+.5)).
struct Placement {
  int width = 0, height = 0;
  std::vector<std::vector<Vec2d>> texel;  // per chart, per chart vertex
  std::vector<char> mirrored;             // per chart
  double seconds = 0;
};

// Re-packs (options.repack) or keeps the atlas layout for a W×H image.
Placement place_charts(const AtlasCharts& atlas, const LevelOptions& options,
                       const std::vector<double>& area_scale,
                       const isochart::Progress& progress);

// Position, normal and a face/barycentric location of the point at arc length t on a path.
struct PathPoint {
  Vec3d position, normal;
  int face = -1;
  Vec3d barycentric;
};
PathPoint path_point(const AtlasCharts& atlas, const CutPath& path, double t);

// Position/normal at a barycentric location of a parent face.
Vec3d face_point(const Mesh& mesh, int face, const Vec3d& bary);

}  // namespace mcgim::detail
