#pragma once
/// Mesh validation and repair: what the file says (RawMesh) → a clean triangle mesh.

#include <string>
#include <vector>

#include "isochart/mesh.h"

namespace isochart {

/// A mesh as read from a file, before validation: polygons of any size.
struct RawMesh {
  std::string source;  ///< file name, for messages
  std::vector<Vec3d> positions;
  std::vector<std::vector<int>> polygons;  ///< vertex indices per face (0-based, unchecked)
  std::vector<Vec3d> normals;              ///< per-vertex, or empty
  std::vector<Vec3d> colors;               ///< per-vertex RGB in [0,1], or empty
  std::vector<Vec2d> uvs;
  std::vector<std::vector<int>> polygon_uvs;  ///< per polygon, same size as polygons[i], or empty
  std::vector<int> polygon_groups;            ///< per polygon group id, or empty
  std::vector<int> polygon_materials;         ///< per polygon material (Mesh::face_materials), or empty
  std::vector<std::string> material_names;    ///< Mesh::material_names
  std::vector<std::string> warnings;          ///< reader notes (ignored elements, dropped attributes)
  long long faces_without_uvs = 0;            ///< faces an OBJ gave no vt, given (0, 0) by the reader
};

/// The raw form of an existing mesh, so that meshes made in code (built-ins, tests) go
/// through the same validation as files.
RawMesh to_raw_mesh(const Mesh& mesh, const std::string& source);

/// Splits each edge-connected piece made wholly of polygons and their reversed copies (a
/// double-sided sheet) into its two sides, the back one on vertices of its own, into `out`.
/// Returns the polygons moved (0: none, `out` untouched). validate_mesh does this when repairing.
int split_double_sided(const RawMesh& raw, RawMesh& out);

/// What validation found in the input and what it changed.
struct ValidationReport {
  int input_vertices = 0;             ///< vertices in the file
  int input_faces = 0;                ///< faces in the file (polygons count once)
  int polygons = 0;                   ///< faces with more than 3 corners (triangulated)
  int degenerate_faces = 0;           ///< zero-area faces or faces repeating a vertex (removed)
  int duplicate_faces = 0;            ///< faces with the same vertex set as an earlier one (removed)
  /// Input faces given vertices of their own as the back of a double-sided sheet (a piece
  /// made wholly of faces and their reversed copies): both sides kept, as separate sheets.
  int double_sided_faces = 0;
  int unreferenced_vertices = 0;      ///< vertices used by no face (dropped)
  int nonmanifold_edges = 0;          ///< edges with more than two faces (split)
  int nonmanifold_vertices = 0;       ///< vertices joining several fans (split)
  int reoriented_faces = 0;           ///< faces flipped to make orientation consistent
  int cut_edges = 0;                  ///< edges cut open because no consistent orientation exists
  int components = 0;                 ///< edge-connected components after repair
  long long faces_without_uvs = 0;    ///< faces the file gave no texture coordinates (they read (0, 0))
  /// Used vertices at the bit-identical position of another, not joined to it (LoadOptions::weld
  /// joins them): a triangle soup reads as one piece per triangle.
  long long coincident_vertices = 0;
  std::vector<std::string> warnings;  ///< one line per repair, for the CLI to print
};

/// Validates and repairs a raw mesh into a clean, consistently oriented, edge- and
/// vertex-manifold triangle mesh. With `repair` false, any problem that would need a
/// repair throws instead. Attributes (normals, colours, UVs, groups) are carried along.
///
/// Repairs, in order, each reported as one line in `report.warnings`:
/// - polygons are triangulated by ear clipping in their best-fit plane (exact predicates),
/// - faces repeating a vertex or with exactly zero area (exact collinearity) are removed,
/// - faces with the vertex set of an earlier face are removed,
/// - at an edge with more than two faces, faces are paired with their angular neighbour of
///   opposite orientation on their back side (so two closed surfaces that touch along an
///   edge both stay closed) and the pairs are split apart; every vertex whose faces form
///   several fans is split into one vertex per fan,
/// - orientation is made consistent per component (closed components outward by signed
///   volume, open ones with the fewest flips); a non-orientable component is cut open,
/// - vertices used by no face are dropped.
/// Vertex ids in messages are the input's (0-based).
/// \throw InputError (file = raw.source) for unrecoverable problems: empty mesh, NaN/Inf
///        values, indices out of range, faces with fewer than 3 corners, or any problem
///        that needs a repair when `repair` is false (the message says "needs repair").
Mesh validate_mesh(const RawMesh& raw, bool repair, ValidationReport& report);

}  // namespace isochart
