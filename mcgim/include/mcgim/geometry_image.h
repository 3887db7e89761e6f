#pragma once
/// Multi-chart geometry images (Sander et al. 2003; Iso-charts §8, §9.2): a W×H grid of surface
/// samples, each chart of an atlas rasterized into its own region, with chart boundaries
/// "zippered" so that the mesh rebuilt from the grid is watertight.

#include <array>
#include <vector>

#include "isochart/mesh.h"
#include "isochart/vec.h"

namespace mcgim {

/// A geometry image. Sample (x, y) is stored at index y·width + x and sits at texture
/// coordinate ((x + 0.5) / width, (y + 0.5) / height): row 0 is v ≈ 0, the bottom row of an image
/// file in the OBJ convention (image writers flip rows accordingly).
///
/// A sample is *defined* when its chart id is ≥ 0. Defined samples of different charts are
/// never 8-adjacent, so every 2×2 block holds samples of at most one chart. Samples welded by
/// zippering share a group id and hold exactly the same position and normal; a sample inside a
/// chart is a group of its own. Group ids are 0 .. num_groups − 1.
struct GeometryImage {
  int width = 0;
  int height = 0;
  std::vector<isochart::Vec3d> positions;  ///< W·H positions (model units); zero when undefined
  std::vector<isochart::Vec3d> normals;    ///< W·H unit normals; zero when undefined
  std::vector<int> chart;                  ///< W·H chart id, −1 = undefined
  std::vector<int> group;                  ///< W·H zipper group id, −1 = undefined
  /// W·H face of the original mesh the sample was taken from and its barycentric coordinates
  /// there (before zippering and optimization moved it); −1 / zero when undefined.
  std::vector<int> face;
  std::vector<isochart::Vec3d> barycentric;
  int num_charts = 0;  ///< chart ids are 0 .. num_charts − 1 (a chart may have no sample)
  int num_groups = 0;
  /// Per chart: its texture layout is mirrored (faces clockwise in texture space). Only an
  /// atlas used with its own layout can have mirrored charts; re-packed charts never are.
  std::vector<char> chart_mirrored;
  /// Per 2×2 block (indexed by its lower-left sample), the diagonal chosen by the sample fit:
  /// 1 splits along (x+1, y)–(x, y+1), 0 along (x, y)–(x+1, y+1). Empty: the shorter one.
  using Diagonals = std::vector<char>;
  Diagonals block_diagonal;

  int index(int x, int y) const { return y * width + x; }
  bool defined(int i) const { return chart[i] >= 0; }
  /// Whether reconstruct splits the full block at lower-left sample i along (x+1, y)–(x, y+1):
  /// block_diagonal's choice unless a diagonal's ends were welded, else the shorter one.
  bool splits_13(int i) const;
  int defined_samples() const;
};

/// A mesh rebuilt from a geometry image.
struct Remesh {
  /// One vertex per zipper group used by a face (or per set of joined groups, see reconstruct);
  /// faces oriented like the original surface;
  /// per-corner uvs are the corner samples' texture coordinates, face_groups the chart ids,
  /// normals the samples' normals.
  isochart::Mesh mesh;
  std::vector<int> sample_vertex;                 ///< W·H → mesh vertex, −1 when not used
  std::vector<std::array<int, 3>> face_samples;   ///< per face, its corner sample indices
  int degenerate_faces = 0;  ///< faces kept although their area is zero (collinear corners)
  /// Block triangles dropped because two corners share a group, or lie on exactly one point
  /// and their groups were joined.
  int collapsed_faces = 0;
  /// Faces dropped as pockets: pairs of triangles on the same three groups with opposite
  /// orientations (a seam corner cut on both sides), and small pieces that touch the rest of
  /// the mesh only at vertices (a contracted seam closed them up).
  int pocket_faces = 0;
};

/// Rebuilds the mesh (Sander et al. 2003 §3): each 2×2 block with 4 defined samples gives two
/// triangles split along the shorter 3-D diagonal (or the one `block_diagonal` names, unless
/// that diagonal's ends were welded), a block with 3 gives one, then samples are
/// welded by group and triangles whose corners fall into fewer than 3 groups are dropped, as
/// are pockets (see Remesh::pocket_faces). Groups at exactly the same position that share an
/// edge are then joined where the link condition allows (the surface stays manifold, its
/// topology unchanged), which drops the faces on that edge. Other zero-area triangles are
/// kept (they are what makes zippered seams watertight) and counted: a triangle counts as
/// zero-area when its height is below 1e-9 of its longest edge.
/// `join_coincident` false keeps such groups apart (the sample fit, which may still move them
/// apart, rebuilds with false and joins only at the end).
/// \throw isochart::InputError when a block mixes two charts or the arrays have the wrong size.
Remesh reconstruct(const GeometryImage& image, bool join_coincident = true);

/// Topology figures of a mesh, used to check reconstructions.
struct TopologyCheck {
  int vertices = 0;            ///< referenced vertices
  int faces = 0;
  int edges = 0;
  int boundary_edges = 0;      ///< edges with one face
  int nonmanifold_edges = 0;   ///< edges with more than two faces
  int nonmanifold_vertices = 0;///< vertices whose faces form several fans
  int boundary_loops = 0;
  int components = 0;
  int euler_characteristic = 0;
  int degenerate_faces = 0;    ///< faces with zero area (as in reconstruct)
  bool closed() const { return boundary_edges == 0; }
  bool edge_manifold() const { return nonmanifold_edges == 0; }
  bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0; }
};
TopologyCheck check_topology(const isochart::Mesh& mesh);

/// How far a mesh is from the topology of a surface with that Euler characteristic and number
/// of boundary loops: non-manifold edges and vertices plus the differences; 0 when it has it.
int topology_distance(const TopologyCheck& t, int euler_characteristic, int boundary_loops);

}  // namespace mcgim
