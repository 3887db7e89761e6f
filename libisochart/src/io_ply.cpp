// Stanford PLY: ascii, binary_little_endian and binary_big_endian readers (vertex position,
// normal, colour and texture coordinate; face index list and MeshLab's per-corner `texcoord`
// list; every other element and property skipped) and a writer.
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "io_internal.h"
#include "isochart/error.h"

namespace isochart::io_detail {

namespace {

enum class Type { I8, U8, I16, U16, I32, U32, F32, F64 };

int type_size(Type t) {
  switch (t) {
    case Type::I8:
    case Type::U8:
      return 1;
    case Type::I16:
    case Type::U16:
      return 2;
    case Type::I32:
    case Type::U32:
    case Type::F32:
      return 4;
    case Type::F64:
      return 8;
  }
  return 1;
}

bool parse_type(std::string_view s, Type& t) {
  static const struct {
    const char* name;
    Type type;
  } names[] = {{"char", Type::I8},   {"int8", Type::I8},     {"uchar", Type::U8},   {"uint8", Type::U8},
               {"short", Type::I16}, {"int16", Type::I16},   {"ushort", Type::U16}, {"uint16", Type::U16},
               {"int", Type::I32},   {"int32", Type::I32},   {"uint", Type::U32},   {"uint32", Type::U32},
               {"float", Type::F32}, {"float32", Type::F32}, {"double", Type::F64}, {"float64", Type::F64}};
  for (const auto& n : names)
    if (s == n.name) {
      t = n.type;
      return true;
    }
  return false;
}

bool is_float(Type t) {
  return t == Type::F32 || t == Type::F64;
}

// The values an integer type holds, as a binary file could store them.
bool fits(Type t, double v) {
  if (is_float(t)) return true;
  if (v != std::floor(v)) return false;
  const int bits = 8 * type_size(t);
  const bool is_signed = t == Type::I8 || t == Type::I16 || t == Type::I32;
  const double lo = is_signed ? -std::ldexp(1.0, bits - 1) : 0.0;
  const double hi = is_signed ? std::ldexp(1.0, bits - 1) - 1 : std::ldexp(1.0, bits) - 1;
  return v >= lo && v <= hi;
}

const char* type_name(Type t) {
  static const char* names[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"};
  return names[static_cast<int>(t)];
}

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// What a property means to us.
enum class Role { None, X, Y, Z, NX, NY, NZ, R, G, B, U, V, Indices, TexCoord };

struct Property {
  std::string name;
  Type type = Type::F32;
  bool is_list = false;
  Type count_type = Type::U8;
  Role role = Role::None;
};

struct Element {
  std::string name;
  long long count = 0;
  long long line = 0;  // header line, for messages
  std::vector<Property> props;
};

Role vertex_role(std::string_view n) {
  if (n == "x") return Role::X;
  if (n == "y") return Role::Y;
  if (n == "z") return Role::Z;
  if (n == "nx") return Role::NX;
  if (n == "ny") return Role::NY;
  if (n == "nz") return Role::NZ;
  if (n == "red" || n == "r" || n == "diffuse_red") return Role::R;
  if (n == "green" || n == "g" || n == "diffuse_green") return Role::G;
  if (n == "blue" || n == "b" || n == "diffuse_blue") return Role::B;
  if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") return Role::U;
  if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") return Role::V;
  return Role::None;
}

// Reads the values of one element record after another, from binary data or from ASCII
// lines (one record per line), and names the record in every error.
class RecordReader {
 public:
  RecordReader(const std::string& path, std::string_view body, bool ascii, bool swap, long long first_line)
      : path_(path),
        ascii_(ascii),
        swap_(swap),
        lines_(path, body),
        line_offset_(first_line),
        p_(reinterpret_cast<const unsigned char*>(body.data())),
        end_(p_ + body.size()) {}

  void begin(const std::string& element, long long index) {
    element_ = &element;
    index_ = index;
    if (ascii_) {
      std::string_view line;
      do {
        if (!lines_.next(line)) fail("unexpected end of file (truncated)");
        rest_ = line;
      } while (rest_.find_first_not_of(" \t\r\v\f") == std::string_view::npos);
    }
  }

  /// `check_type`: an ASCII value must fit the declared type (callers with a more telling
  /// check of their own pass false).
  double read(Type t, bool check_type = true) {
    if (ascii_) {
      std::string_view tok;
      if (!next_token(rest_, tok)) fail("expected more values on this line");
      double v = 0;
      if (!parse_double(tok, v)) fail(quoted(tok) + " is not a number");
      // A binary file could not hold it either: the header's type is wrong, or the value is.
      if (check_type && !fits(t, v))
        fail(quoted(tok) + " is not a " + type_name(t) + " value, as the header declares");
      return v;
    }
    const int n = type_size(t);
    if (end_ - p_ < n) fail("unexpected end of file (truncated)");
    unsigned char b[8];
    std::memcpy(b, p_, n);
    p_ += n;
    if (swap_) std::reverse(b, b + n);
    switch (t) {
      case Type::I8: {
        std::int8_t x;
        std::memcpy(&x, b, 1);
        return x;
      }
      case Type::U8:
        return b[0];
      case Type::I16: {
        std::int16_t x;
        std::memcpy(&x, b, 2);
        return x;
      }
      case Type::U16: {
        std::uint16_t x;
        std::memcpy(&x, b, 2);
        return x;
      }
      case Type::I32: {
        std::int32_t x;
        std::memcpy(&x, b, 4);
        return x;
      }
      case Type::U32: {
        std::uint32_t x;
        std::memcpy(&x, b, 4);
        return x;
      }
      case Type::F32: {
        float x;
        std::memcpy(&x, b, 4);
        return x;
      }
      case Type::F64: {
        double x;
        std::memcpy(&x, b, 8);
        return x;
      }
    }
    return 0;
  }

  /// A list length: non-negative and small enough for the rest of the file.
  long long read_count(Type t, int value_bytes) {
    const double c = read(t, false);
    if (!(c >= 0) || c != std::floor(c) || !fits(t, c)) {
      std::string text = "invalid list length ";
      append_number(text, c);
      fail(text);
    }
    const auto n = static_cast<long long>(c);
    const long long left = ascii_ ? static_cast<long long>(rest_.size()) / 2 + 1 : (end_ - p_) / value_bytes;
    if (n > left)
      fail("list of " + std::to_string(n) + " values runs past the end of the " +
           std::string(ascii_ ? "line" : "file (truncated)"));
    return n;
  }

  /// An ASCII record ends with its line: values beyond the header's properties mean the file
  /// does not match its header (OFF's reader refuses the like).
  void end() {
    if (!ascii_) return;
    std::string_view tok;
    if (next_token(rest_, tok))
      fail("more values on this line than the header declares (" + quoted(tok) + " is one too many)");
  }

  /// What follows the last record that is not blank (ASCII) or padding (binary zeros and
  /// white space): "" when nothing, else a description of it ending in "follow(s)".
  std::string trailing() {
    if (ascii_) {
      long long extra = 0;
      long long first = 0;
      std::string_view line;
      while (lines_.next(line))
        if (line.find_first_not_of(" \t\r\v\f") != std::string_view::npos && extra++ == 0)
          first = line_offset_ + lines_.line_number();
      if (extra == 0) return "";
      return extra > 1 ? std::to_string(extra) + " more lines of data from line " + std::to_string(first) +
                             " follow"
                       : "a line of data (line " + std::to_string(first) + ") follows";
    }
    const auto padding = [](unsigned char c) {
      return c == 0 || c == ' ' || c == '\n' || c == '\r' || c == '\t';
    };
    if (std::all_of(p_, end_, padding)) return "";
    return std::to_string(end_ - p_) + " more bytes of data follow";
  }

  [[noreturn]] void fail(const std::string& message) const {
    const std::string what = *element_ + " " + std::to_string(index_) + ": " + message;
    if (ascii_) fail_at_line(path_, line_offset_ + lines_.line_number(), what);
    throw InputError(path_, what);
  }

 private:
  const std::string& path_;
  bool ascii_, swap_;
  LineScanner lines_;
  long long line_offset_;
  std::string_view rest_;
  const unsigned char* p_;
  const unsigned char* end_;
  const std::string* element_ = nullptr;
  long long index_ = 0;
};

}  // namespace

RawMesh read_ply(const std::string& path, std::string_view data, const LoadOptions& options) {
  RawMesh raw;
  raw.source = path;
  std::string_view line, rest, tok;
  if (data.substr(0, 3) == "\xEF\xBB\xBF") data.remove_prefix(3);  // a UTF-8 byte-order mark
  if (data.substr(0, 3) != "ply" || (data.size() > 3 && data[3] != '\n' && data[3] != '\r'))
    throw InputError(path, "not a PLY file (it does not start with 'ply')");
  // The header is text up to the end_header line; a binary body follows it directly, so the
  // end of that line is read in the style of the first line (LF, CR LF or CR): a body starting
  // with byte 10 after a CR-only header is not taken for a line end.
  const std::string_view eol = data.substr(3, 2) == "\r\n" ? "\r\n" : data.substr(3, 1) == "\r" ? "\r" : "\n";
  std::size_t end_header = std::string_view::npos;
  for (std::size_t at = data.find("end_header"); at != std::string_view::npos;
       at = data.find("end_header", at + 1))
    if (data[at - 1] == '\n' || data[at - 1] == '\r') {
      end_header = at;
      break;
    }
  if (end_header == std::string_view::npos)
    throw InputError(path, "PLY header has no end_header line (truncated file or not a PLY file)");
  std::size_t body_start = end_header + 10;
  if (data.substr(body_start, eol.size()) == eol) {
    body_start += eol.size();
  } else if (data.substr(body_start, 1) == "\n" || data.substr(body_start, 2) == "\r\n") {
    body_start += data[body_start] == '\n' ? 1 : 2;  // a header mixing line ends
  } else if (body_start < data.size()) {
    throw InputError(path, "PLY header has no end_header line (truncated file or not a PLY file)");
  }
  const std::string_view body = data.substr(body_start);

  enum class Format { Ascii, LittleEndian, BigEndian } format = Format::Ascii;
  bool saw_format = false;
  std::vector<Element> elements;
  LineScanner lines(path, data.substr(0, end_header));
  lines.next(line);  // "ply"
  while (lines.next(line)) {
    const long long ln = lines.line_number();
    rest = line;
    if (!next_token(rest, tok)) continue;
    if (tok == "comment" || tok == "obj_info") continue;
    if (tok == "format") {
      std::string_view f;
      next_token(rest, f);
      if (f == "ascii")
        format = Format::Ascii;
      else if (f == "binary_little_endian")
        format = Format::LittleEndian;
      else if (f == "binary_big_endian")
        format = Format::BigEndian;
      else
        fail_at_line(path, ln,
                     "unknown PLY format " + quoted(f) +
                         " (expected ascii, binary_little_endian or binary_big_endian)");
      std::string_view version;
      if (!next_token(rest, version)) fail_at_line(path, ln, "format line has no version (expected 1.0)");
      if (version != "1.0")
        fail_at_line(path, ln, "PLY version " + quoted(version) + " is not supported (only 1.0)");
      if (saw_format) fail_at_line(path, ln, "a second format line");
      saw_format = true;
    } else if (tok == "element") {
      Element e;
      std::string_view name, count;
      if (!next_token(rest, name) || !next_token(rest, count) || !parse_int(count, e.count) || e.count < 0 ||
          e.count > INT_MAX)
        fail_at_line(path, ln, "expected 'element NAME COUNT' with 0 <= COUNT < 2^31");
      e.name = std::string(name);
      e.line = ln;
      for (const Element& other : elements)
        if (other.name == e.name)
          fail_at_line(path, ln,
                       "element " + quoted(name) + " is declared twice (first on line " +
                           std::to_string(other.line) + ")");
      elements.push_back(std::move(e));
    } else if (tok == "property") {
      if (elements.empty()) fail_at_line(path, ln, "property before any element");
      Property p;
      std::string_view t1;
      next_token(rest, t1);
      if (t1 == "list") {
        std::string_view ct, it;
        p.is_list = true;
        if (!next_token(rest, ct) || !parse_type(ct, p.count_type) || !next_token(rest, it) ||
            !parse_type(it, p.type))
          fail_at_line(path, ln, "expected 'property list COUNT_TYPE VALUE_TYPE NAME'");
        if (is_float(p.count_type)) fail_at_line(path, ln, "list length type must be an integer type");
      } else if (!parse_type(t1, p.type)) {
        fail_at_line(path, ln, "unknown property type " + quoted(t1));
      }
      std::string_view name;
      if (!next_token(rest, name)) fail_at_line(path, ln, "property has no name");
      p.name = std::string(name);
      for (const Property& other : elements.back().props)
        if (other.name == p.name)
          fail_at_line(path, ln,
                       "property " + quoted(name) + " of element " + quoted(elements.back().name) +
                           " is declared twice");
      elements.back().props.push_back(std::move(p));
    } else {
      fail_at_line(path, ln, "unknown PLY header keyword " + quoted(tok));
    }
  }
  if (!saw_format) throw InputError(path, "PLY header has no format line");
  const long long header_lines = lines.line_number() + 1;  // + the end_header line

  // Roles, and a check of every declared count against the bytes that follow.
  const Element* vertex_el = nullptr;
  const Element* face_el = nullptr;
  long long min_bytes = 0;
  for (auto& e : elements) {
    long long record = 0;
    for (auto& p : e.props) {
      record += format == Format::Ascii ? 2 : type_size(p.is_list ? p.count_type : p.type);
      if (e.name == "vertex" && !p.is_list) p.role = vertex_role(p.name);
      if (e.name == "face" && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        if (is_float(p.type)) fail_at_line(path, e.line, "face index list must have an integer type");
        p.role = Role::Indices;
      }
      if (e.name == "face" && p.is_list && p.name == "texcoord") p.role = Role::TexCoord;
    }
    if (e.name == "vertex") vertex_el = &e;
    if (e.name == "face") face_el = &e;
    if (e.count > 0 && record > 0 && e.count > (static_cast<long long>(body.size()) - min_bytes) / record + 1)
      fail_at_line(path, e.line,
                   "header declares " + std::to_string(e.count) + " " + e.name + " elements, but only " +
                       std::to_string(body.size()) +
                       " bytes of data follow (truncated file or corrupt header)");
    min_bytes += e.count * record;
  }
  if (!vertex_el) throw InputError(path, "PLY file has no vertex element");
  bool has[16] = {};
  for (const auto& p : vertex_el->props) has[static_cast<int>(p.role)] = true;
  if (!has[int(Role::X)] || !has[int(Role::Y)] || !has[int(Role::Z)])
    fail_at_line(path, vertex_el->line, "vertex element has no x, y and z properties");
  const bool normals = has[int(Role::NX)] && has[int(Role::NY)] && has[int(Role::NZ)];
  const bool colors = has[int(Role::R)] && has[int(Role::G)] && has[int(Role::B)];
  const bool vertex_uv = has[int(Role::U)] && has[int(Role::V)];
  bool face_indices = false, corner_uv = false;
  if (face_el)
    for (const auto& p : face_el->props) {
      face_indices |= p.role == Role::Indices;
      corner_uv |= p.role == Role::TexCoord;
    }
  if (face_el && !face_indices) fail_at_line(path, face_el->line, "face element has no vertex_indices list");
  if (face_el) check_face_limit(path, face_el->count, options);

  raw.positions.resize(static_cast<std::size_t>(vertex_el->count));
  if (normals) raw.normals.resize(raw.positions.size());
  if (colors) raw.colors.resize(raw.positions.size());
  if (vertex_uv && !corner_uv) raw.uvs.resize(raw.positions.size());
  if (face_el) {
    raw.polygons.resize(static_cast<std::size_t>(face_el->count));
    if (corner_uv) raw.polygon_uvs.resize(raw.polygons.size());
  }

  const bool swap = format != Format::Ascii && (format == Format::LittleEndian) != host_is_little_endian();
  RecordReader in(path, body, format == Format::Ascii, swap, header_lines);
  for (const auto& e : elements) {
    const bool is_vertex = &e == vertex_el, is_face = &e == face_el;
    for (long long i = 0; i < e.count; ++i) {
      in.begin(e.name, i);
      for (const auto& p : e.props) {
        if (p.is_list) {
          const long long n = in.read_count(p.count_type, type_size(p.type));
          if (is_face && p.role == Role::Indices) {
            if (n < 3) in.fail("face has " + std::to_string(n) + " corners; a face needs at least 3");
            auto& poly = raw.polygons[static_cast<std::size_t>(i)];
            poly.resize(static_cast<std::size_t>(n));
            for (auto& v : poly) {
              const double x = in.read(p.type, false);
              if (!(x >= 0 && x <= INT_MAX) || x != std::floor(x)) {
                // As a double, not cast: 1e20 cast to long long printed as -9223372036854775808.
                std::string text = "vertex index ";
                append_number(text, x);
                in.fail(text + (x == std::floor(x) ? " is out of range" : " is not a whole number"));
              }
              if (!fits(p.type, x))
                in.fail("vertex index " + std::to_string(static_cast<long long>(x)) + " is not a " +
                        type_name(p.type) + " value, as the header declares");
              v = static_cast<int>(x);
            }
          } else if (is_face && p.role == Role::TexCoord) {
            // MeshLab's convention: u0 v0 u1 v1 ... per corner; checked against the corner
            // count once the whole record is read.
            if (n % 2 != 0) in.fail("texcoord list has an odd number of values");
            auto& puv = raw.polygon_uvs[static_cast<std::size_t>(i)];
            puv.resize(static_cast<std::size_t>(n / 2));
            for (auto& t : puv) {
              const double u = in.read(p.type);
              const double w = in.read(p.type);
              t = static_cast<int>(raw.uvs.size());
              raw.uvs.push_back({u, w});
            }
          } else {
            for (long long q = 0; q < n; ++q) in.read(p.type);
          }
          continue;
        }
        const double x = in.read(p.type);
        if (!is_vertex || p.role == Role::None) continue;
        auto& v = raw.positions[static_cast<std::size_t>(i)];
        // Integer colours span their type's range; float colours are in [0, 1] already.
        const double cscale = p.type == Type::U8 ? 1.0 / 255 : p.type == Type::U16 ? 1.0 / 65535 : 1.0;
        switch (p.role) {
          case Role::X:
            v.x = x;
            break;
          case Role::Y:
            v.y = x;
            break;
          case Role::Z:
            v.z = x;
            break;
          case Role::NX:
            if (normals) raw.normals[i].x = x;
            break;
          case Role::NY:
            if (normals) raw.normals[i].y = x;
            break;
          case Role::NZ:
            if (normals) raw.normals[i].z = x;
            break;
          case Role::R:
            if (colors) raw.colors[i].x = x * cscale;
            break;
          case Role::G:
            if (colors) raw.colors[i].y = x * cscale;
            break;
          case Role::B:
            if (colors) raw.colors[i].z = x * cscale;
            break;
          case Role::U:
            if (!raw.uvs.empty() && !corner_uv) raw.uvs[i].x = x;
            break;
          case Role::V:
            if (!raw.uvs.empty() && !corner_uv) raw.uvs[i].y = x;
            break;
          default:
            break;
        }
      }
      in.end();
      if (is_face && corner_uv) {
        const auto& poly = raw.polygons[static_cast<std::size_t>(i)];
        const auto& puv = raw.polygon_uvs[static_cast<std::size_t>(i)];
        if (puv.size() != poly.size())
          in.fail("texcoord list has " + std::to_string(2 * puv.size()) + " values for " +
                  std::to_string(poly.size()) + " corners");
      }
    }
  }
  // Data past the declared records means the counts are wrong: they were read as far as the
  // header said and the rest was dropped without a word.
  const std::string extra = in.trailing();
  if (!extra.empty())
    throw InputError(path, extra + " the last element the header declares (" + elements.back().name + " " +
                               std::to_string(elements.back().count) +
                               "); the header's counts do not match the file");
  if (vertex_uv && !corner_uv) raw.polygon_uvs = raw.polygons;
  // Float colours are meant to be in [0, 1], but some writers store 8-bit values as floats.
  // Taken as they are, the signal was 255 times too strong and a written PLY saturated.
  bool float_colors = false;
  for (const auto& p : vertex_el->props)
    float_colors |= (p.role == Role::R || p.role == Role::G || p.role == Role::B) && p.type != Type::U8 &&
                    p.type != Type::U16;
  if (colors && float_colors) {
    double top = 0;
    for (const Vec3d& c : raw.colors) top = std::max({top, c.x, c.y, c.z});
    std::ostringstream reach;
    reach << "float vertex colours reach " << top;
    if (top > 255) throw InputError(path, reach.str() + ", beyond both [0, 1] and the 8-bit range");
    if (top > 1) {
      for (Vec3d& c : raw.colors) c = c / 255.0;
      raw.warnings.push_back(reach.str() + ": read as 8-bit values (0..255) and scaled to [0, 1]");
    }
  }
  // Colours per face (some scanners and CAD exports) have nowhere to go: signals, the atlas
  // texture and the written mesh are per vertex.
  if (face_el) {
    bool face_colors = false;
    for (const auto& p : face_el->props) {
      const Role r = vertex_role(p.name);
      face_colors |= !p.is_list && (r == Role::R || r == Role::G || r == Role::B);
    }
    if (face_colors) raw.warnings.push_back("face colours are not read (only vertex colours are)");
  }
  return raw;
}

std::string ply_bytes(const Mesh& m, bool binary) {
  const bool uv = m.has_uvs();
  std::string out = "ply\nformat ";
  out += binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  out += "comment isocharts\nelement vertex " + std::to_string(m.num_vertices()) + "\n";
  // Doubles when floats would move the mesh (far from the origin: at 1e9 every vertex of a
  // unit-sized mesh fell on one point).
  const bool wide = !float_positions_suffice(m.positions, Vec3d{}, bounding_box(m).diagonal());
  out += wide ? "property double x\nproperty double y\nproperty double z\n"
              : "property float x\nproperty float y\nproperty float z\n";
  if (m.has_normals()) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (m.has_colors()) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "element face " + std::to_string(m.num_faces()) + "\n";
  out += "property list uchar int vertex_indices\n";
  if (uv) out += "property list uchar float texcoord\n";
  out += "end_header\n";

  auto put_int = [&](long long v, int bytes) {
    if (binary) {
      // Little-endian whatever the host.
      for (int i = 0; i < bytes; ++i)
        out += static_cast<char>((static_cast<unsigned long long>(v) >> (8 * i)) & 0xff);
    } else {
      append_number(out, v);
    }
  };
  auto put_float = [&](double v) {
    const auto f = static_cast<float>(v);
    if (binary) {
      std::uint32_t bits;
      std::memcpy(&bits, &f, 4);
      put_int(bits, 4);
    } else {
      append_number(out, f);
    }
  };
  auto put_position = [&](double v) {
    if (!wide) return put_float(v);
    if (binary) {
      std::uint64_t bits;
      std::memcpy(&bits, &v, 8);
      for (int i = 0; i < 8; ++i) out += static_cast<char>((bits >> (8 * i)) & 0xff);
    } else {
      append_number(out, v);
    }
  };
  auto sep = [&](char c) {
    if (!binary) out += c;
  };
  for (int v = 0; v < m.num_vertices(); ++v) {
    for (int i = 0; i < 3; ++i) {
      if (i) sep(' ');
      put_position(m.positions[v][i]);
    }
    if (m.has_normals())
      for (int i = 0; i < 3; ++i) {
        sep(' ');
        put_float(m.normals[v][i]);
      }
    if (m.has_colors())
      for (int i = 0; i < 3; ++i) {
        sep(' ');
        put_int(std::lround(std::clamp(m.colors[v][i], 0.0, 1.0) * 255), 1);
      }
    sep('\n');
  }
  for (int f = 0; f < m.num_faces(); ++f) {
    put_int(3, 1);
    for (int k = 0; k < 3; ++k) {
      sep(' ');
      put_int(m.faces[f][k], 4);
    }
    if (uv) {
      sep(' ');
      put_int(6, 1);
      for (int k = 0; k < 3; ++k) {
        const Vec2d& t = m.uvs[m.face_uvs[f][k]];
        sep(' ');
        put_float(t.x);
        sep(' ');
        put_float(t.y);
      }
    }
    sep('\n');
  }
  return out;
}

}  // namespace isochart::io_detail
