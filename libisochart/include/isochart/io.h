#pragma once
/// Mesh input and output: OBJ, OFF, PLY (ASCII and binary) and glTF 2.0 (.gltf/.glb) in;
/// OBJ (+vt, +MTL), PLY and glb out. Built-in meshes ("builtin:NAME") load like files.

#include <string>

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
};

struct LoadResult {
  Mesh mesh;                  ///< validated (and repaired) mesh
  ValidationReport report;    ///< what was found in the input and what was repaired
};

/// Reads, validates and (by default) repairs a mesh.
/// \throw InputError naming the file and the problem (missing, unreadable, unknown format,
///        parse error with line number, empty, NaN/Inf, index out of range, too large, ...).
LoadResult load_mesh(const std::string& path, const LoadOptions& options = {});

/// Reads a file into a raw polygon soup without validation (what the file says).
/// \throw InputError as load_mesh for file-level problems.
RawMesh read_raw_mesh(const std::string& path, const LoadOptions& options = {});

struct SaveOptions {
  /// For OBJ: write an MTL next to the OBJ that references this image (path written as
  /// given, relative to the OBJ). For glb: embed this image as the base colour texture.
  std::string texture;
  /// PLY only: binary little-endian (default) or ASCII.
  bool binary_ply = true;
  /// OBJ only: write one `g chartN` group per value of face_groups.
  bool write_groups = true;
};

/// Writes `mesh` to `path` (format from the extension: .obj, .ply, .glb), via a temporary
/// file in the same directory that is renamed over `path` only when complete.
/// \throw InputError for an unsupported extension, Error when writing fails.
void save_mesh(const Mesh& mesh, const std::string& path, const SaveOptions& options = {});

/// Writes `data` to `path` atomically (temporary file + rename). Used for every output.
void write_file_atomic(const std::string& path, const std::string& data);

}  // namespace isochart
