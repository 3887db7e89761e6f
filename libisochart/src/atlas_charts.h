#pragma once
// Internal: an atlas's charts as separate little meshes (chart-local vertex per atlas UV), for
// passes that re-parameterize or re-weight charts one by one and write the UVs back.

#include <vector>

#include "isochart/atlas.h"
#include "isochart/mesh.h"

namespace isochart::detail {

struct AtlasChart {
  std::vector<int> faces;   // chart face → mesh face
  std::vector<int> uv_ids;  // chart vertex → atlas uv id
  std::vector<Vec3d> positions;
  std::vector<Face> tris;   // chart-local corners
  std::vector<Vec2d> uv;
};

inline std::vector<AtlasChart> split_atlas_charts(const Mesh& mesh, const Atlas& atlas) {
  std::vector<AtlasChart> charts(atlas.num_charts());
  std::vector<int> local(atlas.uvs.size(), -1);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    AtlasChart& c = charts[atlas.face_chart[f]];
    Face t;
    for (int k = 0; k < 3; ++k) {
      const int u = atlas.face_uvs[f][k];
      if (local[u] < 0) {
        local[u] = static_cast<int>(c.uv_ids.size());
        c.uv_ids.push_back(u);
        c.positions.push_back(mesh.positions[mesh.faces[f][k]]);
        c.uv.push_back(atlas.uvs[u]);
      }
      t[k] = local[u];
    }
    c.faces.push_back(f);
    c.tris.push_back(t);
  }
  return charts;
}

}  // namespace isochart::detail
