#pragma once
/// Mesh input and output: OBJ, OFF, PLY (ASCII and binary) and glTF 2.0 (.gltf/.glb) in;
/// OBJ (+vt, +MTL), PLY and glb out. Built-in meshes ("builtin:NAME") load like files.
///
/// Conventions worth knowing:
/// - Texture coordinates have their origin at the bottom left (OBJ's convention); glTF's
///   top-left v is flipped (v' = 1 - v) on reading and writing.
/// - OBJ normals are per corner; a mesh keeps the normalized mean per vertex.
/// - glTF: every triangle, strip and fan primitive reached from the default scene (every
///   mesh when there is no scene), node transforms applied (a mirroring transform reverses
///   the winding); each primitive is one face group. Vertices are shared only within a
///   primitive, or between primitives of one node that use the same attribute accessors.
/// - An attribute only some faces or vertices have is dropped (normals, colours) or filled
///   with (0, 0) (texture coordinates), with a warning in the validation report.

#include <string>
#include <utility>
#include <vector>

#include "isochart/image.h"
#include "isochart/mesh.h"
#include "isochart/validate.h"

namespace isochart {

enum class MeshFormat { Obj, Off, Ply, Gltf, Glb, Builtin };

/// The format implied by the path ("builtin:" prefix or extension, case-insensitive).
/// \throw InputError when the extension is not one we read or write.
MeshFormat format_from_path(const std::string& path);

struct LoadOptions {
  /// Repair what can be repaired (see validate.h) and warn; when false, any problem that
  /// needs repair is an InputError instead.
  bool repair = true;
  /// Refuse meshes with more faces than this (after triangulation), to fail early and
  /// clearly instead of exhausting memory.
  long long max_faces = 20'000'000;
  /// Join corners at bit-identical positions, texture coordinates staying per corner. glTF
  /// files are always joined (a vertex per combination of attributes); atlases from other
  /// tools arrive split at their UV seams in any format (one vertex per position and UV).
  bool weld = false;
  /// With `weld`, for a file of our own atlas: when joining would leave a surface that needs
  /// a cut or split repaired (non-manifold, or non-orientable) and the file as written does
  /// not, the file is read as written. Its corners at one position are then what keeps it a
  /// surface (the copies an earlier repair made), and are not reported as a cut.
  bool weld_only_if_surface = false;
};

struct LoadResult {
  Mesh mesh;                ///< validated (and repaired) mesh
  ValidationReport report;  ///< what was found in the input and what was repaired
};

/// Reads, validates and (by default) repairs a mesh. The whole file is read at once; header
/// counts are checked against the file size before anything is allocated.
/// \throw InputError naming the file and the problem (missing, unreadable, unknown format,
///        parse error with line number for text formats or the element ("vertex 17",
///        "face 3") for binary ones, empty, NaN/Inf, index out of range, too large, ...).
LoadResult load_mesh(const std::string& path, const LoadOptions& options = {});

/// The colour texture a mesh file names or carries, for drawing it: an OBJ's material's
/// `map_Kd` (the material of its first `usemtl`, else the MTL's first; the path relative to
/// the MTL), or a glTF/glb's first material's base-colour image (its encoded bytes, or the
/// file it refers to). All empty when there is none.
struct MeshTexture {
  std::string file;       ///< an image file, or empty
  std::string bytes;      ///< an embedded image's encoded bytes, or empty
  std::string extension;  ///< ".png" or ".jpg" for `bytes`
  std::string problem;    ///< why a texture the file names cannot be used, or empty
  /// The faces use more than one material (OBJ `usemtl` names, glTF primitives' materials), so
  /// this first material's texture is not every face's.
  bool several_materials = false;
  /// How the material reads the image outside [0, 1] (glTF sampler wrapS / wrapT, OBJ
  /// `-clamp on`).
  TextureWrap wrap;
  /// Where the material reads its image for the file's texture coordinates (OBJ `map_Kd -s`
  /// and `-o`, glTF KHR_texture_transform), in the mesh's convention (v up).
  struct UvTransform {
    // (u, v) ↦ (a·u + b·v + c, d·u + e·v + f)
    double a = 1, b = 0, c = 0, d = 0, e = 1, f = 0;
    bool identity() const { return a == 1 && b == 0 && c == 0 && d == 0 && e == 1 && f == 0; }
    Vec2d apply(const Vec2d& uv) const { return {a * uv.x + b * uv.y + c, d * uv.x + e * uv.y + f}; }
  };
  UvTransform uv_transform;
  /// The material's diffuse colour (OBJ `Kd`, glTF baseColorFactor's RGB): what its faces
  /// show where it has no texture.
  Vec3d colour{1, 1, 1};
};
/// \throw InputError when the mesh file itself cannot be read; a texture named but missing is
///        returned by name (reading it then fails).
MeshTexture find_mesh_texture(const std::string& path);
/// Every material's texture, entry i for material id i of mesh.face_materials (the mesh as
/// loaded from `path`): by `usemtl` name for an OBJ, by material index for a glTF/glb. Empty
/// when the mesh has no per-face materials.
/// \throw InputError when the mesh file itself cannot be read.
std::vector<MeshTexture> find_material_textures(const std::string& path, const Mesh& mesh);

/// Reads a file into a raw polygon soup without validation (what the file says: glTF
/// vertices split at UV and normal seams stay split; load_mesh joins those at equal positions).
/// \throw InputError as load_mesh for file-level problems.
RawMesh read_raw_mesh(const std::string& path, const LoadOptions& options = {});

/// How an OBJ writes a mesh's face groups.
enum class ObjGroups {
  None,        ///< no `g` statements
  Contiguous,  ///< each group's faces together, groups in ascending order, one `g` each
  FaceOrder,   ///< faces in the mesh's order, a `g` wherever the group changes
};

struct SaveOptions {
  /// For OBJ: write an MTL next to the OBJ that references this image (path written as
  /// given, relative to the OBJ). For glb: embed this image as the base colour texture.
  std::string texture;
  /// The texture's alpha is transparency (a cut-out or see-through texture): the glb's material
  /// blends it (alphaMode BLEND) and the MTL names the image as `map_d` too. Otherwise viewers
  /// draw the texture opaque.
  bool texture_transparent = false;
  /// PLY only: binary little-endian (default) or ASCII.
  bool binary_ply = true;
  /// OBJ only: how face_groups become `g chartN` statements.
  ObjGroups write_groups = ObjGroups::Contiguous;
};

/// The material file save_mesh writes beside an OBJ with a texture: the OBJ's path with its
/// extension replaced by .mtl, spaces and tabs in the file name turned into underscores
/// (`mtllib` names are separated by spaces).
std::string material_path(const std::string& obj_path);

/// Writes `mesh` to `path` (format from the extension: .obj, .ply, .glb), via a temporary
/// file in the same directory that is renamed over `path` only when complete.
/// - OBJ: every number as the shortest decimal that reads back exactly; `vt`, `vn`,
///   `g chartN` per face group (by default each group's faces written together, so the
///   file's face order can differ from the mesh's); with a texture, `NAME.mtl` beside it (written first,
///   removed again if the OBJ fails).
/// - PLY: float positions and normals, uchar colours, per-corner UVs as a face `texcoord`
///   list (MeshLab's convention); no groups.
/// - glb: float POSITION/NORMAL/COLOR_0/TEXCOORD_0 with vertices split at UV seams, one
///   primitive per face group (uint32 indices), the texture embedded as baseColorTexture.
///   The bytes depend only on the mesh and the texture.
/// \throw InputError for an unsupported extension, a path that cannot be written, or a
///        texture that cannot be read or is not PNG/JPEG (glb); nothing is left behind.
void save_mesh(const Mesh& mesh, const std::string& path, const SaveOptions& options = {});

/// Writes `data` to `path` atomically: a temporary file beside it (named from the pid and a
/// counter) renamed over `path`, or removed on failure. Used for every output.
/// \throw InputError(path, "cannot write: REASON").
void write_file_atomic(const std::string& path, const std::string& data);

/// A fresh temporary file name beside `target` (same directory, so the rename is atomic), unique
/// per process and call, at most 255 bytes long. With an `extension` (".png") it is hidden and
/// ends in it, for writers that pick the format by the name.
std::string temporary_path(const std::string& target, const std::string& extension = "");

/// Temporary output files (written beside their target, not yet renamed into place) are tracked
/// from before they are created until they are renamed or removed, so that an interrupted run
/// leaves none behind. The writers call these; at most 256 files are tracked at once (more are
/// written, just not tracked).
void track_temporary_file(const std::string& path);
void untrack_temporary_file(const std::string& path);
/// Removes a tracked temporary file (a failed write) and stops tracking it.
void remove_temporary_file(const std::string& path);

/// For programs: on SIGINT, SIGTERM or SIGHUP (unless ignored when this is called), removes every
/// tracked temporary file, then lets the signal end the process as it would have. The library
/// itself never installs signal handlers.
void remove_temporary_files_on_interrupt();

/// Whether two paths name one file: the same device and inode when both exist, else the same
/// path once `.`, `..` and symbolic links are resolved (an output not written yet).
bool same_file(const std::string& a, const std::string& b);

/// Records that the run read `path`: while an OutputBatch is open, an output over that file
/// (the same file, through any name or link) is refused. The readers call it.
void note_input_file(const std::string& path);

/// Where an output written to `path` lands: `path`, or the file its symbolic links lead to
/// (outputs are written through links, which stay links).
/// \throw InputError(path, "cannot write: ...") when that is a directory, a device or another
///        file that is not a regular one (an atomic rename would replace it), or, while an
///        OutputBatch is open, a file this run read (note_input_file).
std::string output_target(const std::string& path);

/// All of a run's outputs, or none. While a batch is open, write_file_atomic, save_mesh and
/// write_image leave each output in its temporary file; commit() renames them all into place,
/// and a batch closed without commit() (a later step failed) removes them, so a failed run
/// never leaves a partial set of outputs (an OBJ without its PNG, one level of four, ...).
/// One batch at a time per process; writes from any thread join it.
class OutputBatch {
 public:
  OutputBatch();
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  /// Renames every staged file over its target, in the order written.
  /// \throw InputError(target, "cannot write: Is a directory") before any rename when a target
  ///        is a directory; Error("TARGET: cannot write: REASON") if a rename fails midway: the
  ///        outputs renamed so far get their previous files back (or are removed), the rest
  ///        are dropped.
  void commit();
  /// Called by the writers: keeps `tmp` for `target` when a batch is open (true), else false.
  static bool stage(const std::string& tmp, const std::string& target);
  static bool open();
  /// Where `target`'s content is now: its staged temporary file if this batch wrote it, else
  /// `target` (for a later step that reads an output back, e.g. a glb embedding its PNG).
  static std::string current_path(const std::string& target);

 private:
  std::vector<std::pair<std::string, std::string>> staged_;
};

}  // namespace isochart
