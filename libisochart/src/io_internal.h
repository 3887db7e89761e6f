#pragma once
// Internals of the mesh I/O module: per-format readers and writers, and the small text
// scanner the text formats share. Not part of the public API.

#include <sys/stat.h>

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "isochart/io.h"

namespace isochart::io_detail {

// ---- Readers: `data` is the whole file; they throw InputError(path, ...) ----
RawMesh read_obj(const std::string& path, std::string_view data, const LoadOptions& options);
RawMesh read_off(const std::string& path, std::string_view data, const LoadOptions& options);
RawMesh read_ply(const std::string& path, std::string_view data, const LoadOptions& options);
RawMesh read_gltf(const std::string& path, std::string_view data, bool binary, const LoadOptions& options);
/// find_mesh_texture for each format (`data` is the whole mesh file).
MeshTexture obj_texture(const std::string& path, std::string_view data);
MeshTexture gltf_texture(const std::string& path, std::string_view data, bool binary);
/// Every material's texture, in the numbering of Mesh::face_materials.
std::vector<MeshTexture> obj_textures(const std::string& path, std::string_view data,
                                      const std::vector<std::string>& materials);
std::vector<MeshTexture> gltf_textures(const std::string& path, std::string_view data, bool binary);
/// Joins vertices at bit-identical positions (glTF splits them at attribute seams).
void weld_equal_positions(RawMesh& raw);

// ---- Writers: return the file contents; save_mesh writes them atomically ----
std::string obj_text(const Mesh& mesh, const std::string& mtl_file, ObjGroups write_groups);
std::string mtl_text(const std::string& texture, bool transparent = false);
std::string ply_bytes(const Mesh& mesh, bool binary);
/// \throw InputError(texture, ...) when the texture cannot be read or is not PNG/JPEG.
std::string glb_bytes(const Mesh& mesh, const std::string& texture, bool transparent = false);

/// The largest input file read: a 20-million-face mesh (LoadOptions::max_faces) with normals
/// and UVs is about 3 GB as OBJ text.
constexpr unsigned long long kMaxInputFileBytes = 4ull << 30;

/// True when storing `positions − origin` as 32-bit floats moves no coordinate by more than
/// 1e-7 of `diagonal`, the positions' bounding-box diagonal (a mesh near the origin always
/// passes; one a thousand diagonals away does not).
bool float_positions_suffice(const std::vector<Vec3d>& positions, const Vec3d& origin, double diagonal);

/// note_input_file for a file already opened and fstat'ed.
void note_input_file(const struct stat& st);

/// Whole file contents. \throw InputError for a missing file, a directory, a device or pipe,
/// a file over kMaxInputFileBytes, a read error.
std::string read_file(const std::string& path);

/// A token made safe for a one-line message: control and non-ASCII bytes escaped as \xNN,
/// long tokens cut (a garbage "line" may be megabytes long).
std::string quoted(std::string_view token);

/// Throws InputError(path, "line N: message").
[[noreturn]] void fail_at_line(const std::string& path, long long line, const std::string& message);

/// Throws when a reader is about to hold more faces than options.max_faces allows.
void check_face_limit(const std::string& path, long long faces, const LoadOptions& options);

/// Lines of a text file, without the line end (LF or CRLF). Rejects NUL bytes, which no
/// text mesh format contains and which mark a binary file given the wrong extension.
class LineScanner {
 public:
  /// A UTF-8 byte-order mark at the start is skipped (editors on Windows write one).
  LineScanner(const std::string& path, std::string_view data);
  /// The next line, or false at the end of the data. Lines end at LF, CR LF or a lone CR
  /// (old Mac files, or a file pasted together from both).
  bool next(std::string_view& line);
  long long line_number() const { return line_; }
  /// Bytes not yet scanned.
  std::size_t remaining() const { return data_.size() - pos_; }
  /// Offset of the first byte not yet scanned.
  std::size_t offset() const { return pos_; }

 private:
  void find_next_lf();

  const std::string& path_;
  std::string_view data_;
  std::size_t pos_ = 0;
  std::size_t next_lf_ = 0;  // offset of the next '\n' (size when none); stale when below pos_
  long long line_ = 0;
};

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\v' || c == '\f' || c == '\r';
}

/// Splits off the next whitespace-separated token; false when none is left.
inline bool next_token(std::string_view& s, std::string_view& token) {
  std::size_t i = 0;
  while (i < s.size() && is_space(s[i])) ++i;
  if (i == s.size()) {
    s = {};
    return false;
  }
  std::size_t j = i;
  while (j < s.size() && !is_space(s[j])) ++j;
  token = s.substr(i, j - i);
  s.remove_prefix(j);
  return true;
}

/// Parses a whole token as a number (a leading '+' is allowed). nan/inf parse, so that the
/// caller can name them, and so do values beyond a double (as ±inf, or towards 0 when they
/// underflow); trailing junk does not.
bool parse_double(std::string_view token, double& value);
/// "'TOKEN' is not finite" for inf/nan text, "... is out of range" for a number beyond a double.
std::string not_finite(std::string_view token);
bool parse_int(std::string_view token, long long& value);
/// True for an optionally signed run of decimal digits, e.g. an index too large for parse_int,
/// so that readers can call it out of range rather than malformed.
bool is_integer_text(std::string_view token);

/// Parses the next token on a line as a finite number, or throws naming the line and `what`
/// (what was expected, when the line ends) or `name` (the value, when it is not finite).
double expect_number(std::string_view& rest, const std::string& path, long long line, const char* what,
                     const char* name);

/// Appends the shortest text that reads back as exactly `v` (std::to_chars).
void append_number(std::string& out, double v);
void append_number(std::string& out, float v);
void append_number(std::string& out, long long v);

}  // namespace isochart::io_detail
