// Wavefront OBJ: reader (v with optional colours, vt, vn, f in all four corner forms with
// relative indices, polygons, g/o groups) and writer (+ MTL).
#include <sys/stat.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <unordered_map>

#include "io_internal.h"
#include "isochart/error.h"

namespace isochart::io_detail {

namespace {

bool is_identifier(std::string_view s) {
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return !s.empty();
}

// Statements of the OBJ spec that carry nothing a triangle mesh needs (materials, smoothing,
// free-form geometry, display attributes).
bool is_ignored_statement(std::string_view key) {
  static const char* const names[] = {
      "s",        "mtllib",     "usemtl",    "usemap", "maplib", "vp",   "cstype", "deg",
      "bmat",     "step",       "curv",      "curv2",  "surf",   "parm", "trim",   "hole",
      "scrv",     "sp",         "end",       "con",    "mg",     "lod",  "bevel",  "c_interp",
      "d_interp", "shadow_obj", "trace_obj", "ctech",  "stech",  "call", "csh"};
  for (const char* n : names)
    if (key == n) return true;
  return false;
}

// The largest 1-based index seen for one kind of element, with its line, so that forward
// references (legal in OBJ) are checked once all elements are known.
struct MaxRef {
  long long index = 0;
  long long line = 0;
};

}  // namespace

RawMesh read_obj(const std::string& path, std::string_view data, const LoadOptions& options) {
  RawMesh raw;
  raw.source = path;
  std::vector<Vec3d> normals_in;   // the vn list
  std::vector<int> corner_normal;  // per corner of raw.polygons in order, -1 when none
  std::vector<Vec3d> colors;
  long long colored = 0, corners_with_normal = 0;
  std::vector<std::vector<int>> polygon_uvs;
  long long faces_with_uv = 0;
  // Group ids in order of first use by a face, so that a name with no faces takes none.
  std::unordered_map<std::string, int> group_ids;
  std::vector<int> groups;
  // Materials likewise by `usemtl` name in order of first use (obj_textures numbers them so).
  std::unordered_map<std::string, int> material_ids;
  std::vector<int> materials;
  int current_material = -1;
  std::string group_name;
  int current_group = -1;  // id of group_name, -1 until a face uses it
  bool saw_group = false;
  MaxRef max_v, max_vt, max_vn;
  long long ignored_elements = 0, unknown_statements = 0, first_unknown_line = 0;
  std::string first_unknown;

  LineScanner lines(path, data);
  std::string_view line;
  std::vector<int> poly, poly_uv;
  std::string joined;
  // Drops trailing blanks and a continuation backslash from `l`; true when there was one.
  auto cut_continuation = [](std::string_view& l) {
    while (!l.empty() && is_space(l.back())) l.remove_suffix(1);
    if (l.empty() || l.back() != '\\') return false;
    l.remove_suffix(1);
    return true;
  };
  while (lines.next(line)) {
    std::string_view rest = line, key;
    if (!next_token(rest, key) || key[0] == '#') continue;
    // A statement may be split over lines ending in a backslash (the format allows it for long
    // face lists); errors name its last line.
    std::string_view part = line;
    if (cut_continuation(part)) {
      joined.assign(part);
      while (lines.next(line)) {
        part = line;
        const bool more = cut_continuation(part);
        joined.append(" ").append(part);
        if (!more) break;
      }
      line = joined;
      rest = line;
      next_token(rest, key);
    }
    const long long ln = lines.line_number();

    if (key == "v") {
      double c[7];
      int n = 0;
      std::string_view tok;
      while (next_token(rest, tok) && tok[0] != '#') {
        if (n == 7 || !parse_double(tok, c[n])) {
          if (n < 7) fail_at_line(path, ln, quoted(tok) + " is not a number");
          fail_at_line(path, ln, "too many numbers after 'v' (expected x y z, x y z w or x y z r g b)");
        }
        if (!std::isfinite(c[n])) fail_at_line(path, ln, "coordinate " + not_finite(tok));
        ++n;
      }
      if (n < 3) fail_at_line(path, ln, "expected 3 coordinates after 'v'");
      if (n != 3 && n != 4 && n != 6)
        fail_at_line(
            path, ln,
            "expected x y z, x y z w or x y z r g b after 'v', found " + std::to_string(n) + " numbers");
      raw.positions.push_back({c[0], c[1], c[2]});
      if (n == 6) {
        colors.resize(raw.positions.size());
        colors.back() = {c[3], c[4], c[5]};
        ++colored;
      }
    } else if (key == "vt") {
      Vec2d uv;
      uv.x = expect_number(rest, path, ln, "texture coordinate after 'vt'", "texture coordinate");
      std::string_view tok;
      if (next_token(rest, tok) && tok[0] != '#') {
        if (!parse_double(tok, uv.y)) fail_at_line(path, ln, quoted(tok) + " is not a number");
        if (!std::isfinite(uv.y)) fail_at_line(path, ln, "texture coordinate " + not_finite(tok));
      }
      raw.uvs.push_back(uv);
    } else if (key == "vn") {
      Vec3d nrm;
      for (int i = 0; i < 3; ++i)
        nrm[i] = expect_number(rest, path, ln, "3 coordinates after 'vn'", "normal coordinate");
      normals_in.push_back(nrm);
    } else if (key == "f" || key == "fo") {
      poly.clear();
      poly_uv.clear();
      int with_uv = 0;
      std::string_view tok;
      while (next_token(rest, tok) && tok[0] != '#') {
        // v, v/vt, v//vn or v/vt/vn; a third slash leaves "vn/x" in parts[2], which then
        // fails to parse.
        std::string_view parts[3], t = tok;
        int np = 0;
        for (;;) {
          const std::size_t slash = t.find('/');
          if (np == 2 || slash == std::string_view::npos) {
            parts[np++] = t;
            break;
          }
          parts[np++] = t.substr(0, slash);
          t.remove_prefix(slash + 1);
        }
        auto resolve = [&](std::string_view s, std::size_t count, const char* what, MaxRef& max) {
          long long i = 0;
          if (!parse_int(s, i)) {
            if (is_integer_text(s))
              fail_at_line(path, ln,
                           std::string(what) + " index " + std::string(s) +
                               " is out of range (too large for any mesh)");
            fail_at_line(path, ln,
                         quoted(tok) + " is not a face corner (expected v, v/vt, v//vn or v/vt/vn)");
          }
          if (i == 0)
            fail_at_line(path, ln, std::string(what) + " index 0 is invalid (OBJ indices start at 1)");
          if (i < 0) {
            if (-i > static_cast<long long>(count))
              fail_at_line(path, ln,
                           "relative " + std::string(what) + " index " + std::to_string(i) +
                               " reaches before the first " + what + " (only " + std::to_string(count) +
                               " so far)");
            return static_cast<int>(static_cast<long long>(count) + i);
          }
          if (i > INT_MAX)
            fail_at_line(path, ln, std::string(what) + " index " + std::to_string(i) + " is out of range");
          if (i > max.index) max = {i, ln};
          return static_cast<int>(i - 1);
        };
        if (parts[0].empty())
          fail_at_line(path, ln, quoted(tok) + " is not a face corner (expected v, v/vt, v//vn or v/vt/vn)");
        poly.push_back(resolve(parts[0], raw.positions.size(), "vertex", max_v));
        if (np > 1 && !parts[1].empty()) {
          poly_uv.push_back(resolve(parts[1], raw.uvs.size(), "texture coordinate", max_vt));
          ++with_uv;
        }
        const bool has_n = np > 2 && !parts[2].empty();
        corner_normal.push_back(has_n ? resolve(parts[2], normals_in.size(), "normal", max_vn) : -1);
        corners_with_normal += has_n ? 1 : 0;
      }
      if (poly.size() < 3)
        fail_at_line(path, ln,
                     "face has " + std::to_string(poly.size()) + " corners; a face needs at least 3");
      if (with_uv != 0 && with_uv != static_cast<int>(poly.size()))
        fail_at_line(path, ln, "face mixes corners with and without texture coordinates");
      if (static_cast<long long>(raw.polygons.size()) >= options.max_faces)
        check_face_limit(path, static_cast<long long>(raw.polygons.size()) + 1, options);
      if (current_group < 0)  // faces before any g/o form the unnamed group
        current_group = group_ids.emplace(group_name, static_cast<int>(group_ids.size())).first->second;
      groups.push_back(current_group);
      materials.push_back(current_material);
      raw.polygons.push_back(poly);
      polygon_uvs.push_back(poly_uv);
      faces_with_uv += with_uv ? 1 : 0;
    } else if (key == "g" || key == "o") {
      // The rest of the line is the name; "g" alone is the default group.
      std::size_t i = 0;
      while (i < rest.size() && is_space(rest[i])) ++i;
      std::string name(rest.substr(i));
      while (!name.empty() && is_space(name.back())) name.pop_back();
      saw_group = true;
      group_name = std::move(name);
      current_group = -1;
    } else if (key == "usemtl") {
      std::size_t i = 0;
      while (i < rest.size() && is_space(rest[i])) ++i;
      std::string name(rest.substr(i));
      while (!name.empty() && is_space(name.back())) name.pop_back();
      current_material = material_ids.emplace(name, static_cast<int>(material_ids.size())).first->second;
    } else if (key == "l" || key == "p") {
      ++ignored_elements;
    } else if (is_ignored_statement(key)) {
      // Nothing a triangle mesh needs.
    } else if (is_identifier(key) && key.size() <= 32) {
      if (unknown_statements++ == 0) {
        first_unknown = std::string(key);
        first_unknown_line = ln;
      }
    } else {
      fail_at_line(path, ln, quoted(key) + " is not an OBJ statement");
    }
  }

  auto check_max = [&](const MaxRef& max, std::size_t count, const char* what, const char* plural) {
    if (max.index > static_cast<long long>(count))
      fail_at_line(path, max.line,
                   std::string(what) + " index " + std::to_string(max.index) +
                       " is out of range (the file has " + std::to_string(count) + " " + plural + ")");
  };
  check_max(max_v, raw.positions.size(), "vertex", "vertices");
  check_max(max_vt, raw.uvs.size(), "texture coordinate", "texture coordinates");
  check_max(max_vn, normals_in.size(), "normal", "normals");

  if (colored > 0 && colored == static_cast<long long>(raw.positions.size())) {
    // Exporters write colours either in [0, 1] or in [0, 255].
    double max_c = 0;
    for (const auto& c : colors) max_c = std::max({max_c, c.x, c.y, c.z});
    if (max_c > 1)
      for (auto& c : colors) c /= 255.0;
    raw.colors = std::move(colors);
  } else if (colored > 0) {
    raw.warnings.push_back("only " + std::to_string(colored) + " of " + std::to_string(raw.positions.size()) +
                           " vertices have colours; colours ignored");
  }

  if (faces_with_uv > 0) {
    const long long missing = static_cast<long long>(raw.polygons.size()) - faces_with_uv;
    if (missing > 0) {
      const int zero = static_cast<int>(raw.uvs.size());
      raw.uvs.push_back({0, 0});
      for (std::size_t f = 0; f < polygon_uvs.size(); ++f)
        if (polygon_uvs[f].empty()) polygon_uvs[f].assign(raw.polygons[f].size(), zero);
      raw.warnings.push_back(std::to_string(missing) + (missing == 1 ? " face has" : " faces have") +
                             " no texture coordinates; they get (0, 0)");
      raw.faces_without_uvs = missing;
    }
    raw.polygon_uvs = std::move(polygon_uvs);
  } else {
    raw.uvs.clear();
  }

  const long long corners = static_cast<long long>(corner_normal.size());
  if (corners_with_normal > 0 && corners_with_normal == corners) {
    // OBJ normals are per corner; the mesh keeps one per vertex, the normalized average of
    // the normals its corners name (hard edges are smoothed).
    raw.normals.assign(raw.positions.size(), Vec3d{});
    std::size_t c = 0;
    for (const auto& p : raw.polygons)
      for (int v : p) raw.normals[v] += normalized(normals_in[corner_normal[c++]]);
    for (auto& n : raw.normals) n = normalized(n);
  } else if (corners_with_normal > 0) {
    raw.warnings.push_back("only " + std::to_string(corners_with_normal) + " of " + std::to_string(corners) +
                           " face corners have normals; normals ignored");
  }

  if (saw_group) raw.polygon_groups = std::move(groups);
  if (!material_ids.empty()) {
    raw.polygon_materials = std::move(materials);
    raw.material_names.resize(material_ids.size());
    for (auto& [name, id] : material_ids) raw.material_names[id] = name;
  }
  if (ignored_elements > 0)
    raw.warnings.push_back("ignored " + std::to_string(ignored_elements) +
                           " line and point elements ('l', 'p')");
  if (unknown_statements > 0)
    raw.warnings.push_back("ignored " + std::to_string(unknown_statements) +
                           " unsupported statements (first: " + quoted(first_unknown) + " on line " +
                           std::to_string(first_unknown_line) + ")");
  return raw;
}

std::string mtl_text(const std::string& texture, bool transparent) {
  return "# isocharts\nnewmtl material0\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\nmap_Kd " + texture +
         "\n" + (transparent ? "map_d " + texture + "\n" : "");
}

std::string obj_text(const Mesh& m, const std::string& mtl_file, ObjGroups write_groups) {
  std::string out;
  out.reserve(m.positions.size() * 48 + m.uvs.size() * 32 + m.faces.size() * 40);
  out += "# isocharts\n";
  if (!mtl_file.empty()) out += "mtllib " + mtl_file + "\n";
  for (int v = 0; v < m.num_vertices(); ++v) {
    out += "v";
    for (int i = 0; i < 3; ++i) {
      out += ' ';
      append_number(out, m.positions[v][i]);
    }
    if (m.has_colors())
      for (int i = 0; i < 3; ++i) {
        out += ' ';
        append_number(out, m.colors[v][i]);
      }
    out += '\n';
  }
  if (m.has_uvs())
    for (const auto& uv : m.uvs) {
      out += "vt ";
      append_number(out, uv.x);
      out += ' ';
      append_number(out, uv.y);
      out += '\n';
    }
  if (m.has_normals())
    for (const auto& n : m.normals) {
      out += "vn";
      for (int i = 0; i < 3; ++i) {
        out += ' ';
        append_number(out, n[i]);
      }
      out += '\n';
    }
  if (!mtl_file.empty()) out += "usemtl material0\n";
  const bool groups = write_groups != ObjGroups::None && m.face_groups.size() == m.faces.size();
  // Importers make one object or selection set per `g` statement, so a chart whose faces are
  // scattered through the file would come in as thousands of pieces: each group's faces are
  // written together (stable, groups in ascending order) unless the face order must stay.
  std::vector<int> order(m.faces.size());
  std::iota(order.begin(), order.end(), 0);
  if (groups && write_groups == ObjGroups::Contiguous)
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return m.face_groups[a] < m.face_groups[b]; });
  bool first = true;
  int last_group = 0;
  for (const int f : order) {
    if (groups && (first || m.face_groups[f] != last_group)) {
      last_group = m.face_groups[f];
      out += "g chart";
      append_number(out, static_cast<long long>(last_group));
      out += '\n';
    }
    first = false;
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      append_number(out, static_cast<long long>(m.faces[f][k]) + 1);
      if (m.has_uvs() || m.has_normals()) {
        out += '/';
        if (m.has_uvs()) append_number(out, static_cast<long long>(m.face_uvs[f][k]) + 1);
        if (m.has_normals()) {
          out += '/';
          append_number(out, static_cast<long long>(m.faces[f][k]) + 1);
        }
      }
    }
    out += '\n';
  }
  return out;
}

namespace {

std::string_view trim(std::string_view v) {
  while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
  while (!v.empty() && (v.back() == ' ' || v.back() == '\t' || v.back() == '\r')) v.remove_suffix(1);
  return v;
}

// The rest of `line` after `keyword` and white space, or nullopt when it is another line.
bool after_keyword(std::string_view line, std::string_view keyword, std::string_view& rest) {
  line = trim(line);
  if (line.size() <= keyword.size() || line.substr(0, keyword.size()) != keyword) return false;
  if (line[keyword.size()] != ' ' && line[keyword.size()] != '\t') return false;
  rest = trim(line.substr(keyword.size()));
  return !rest.empty();
}

std::string directory_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

// A texture map statement: the file it names after its options (`-s 1 1 1`, `-clamp on`, ...),
// the rest of the line, which may hold spaces (Blender writes such names as they are), without
// surrounding quotes; and the options that change where the image is read.
struct MapStatement {
  std::string file;
  bool clamp = false;  // -clamp on
  Vec2d scale{1, 1};   // -s u v
  Vec2d offset{0, 0};  // -o u v
  std::string problem;  // an option value no number can hold, or empty
};

MapStatement map_statement(std::string_view rest) {
  // Options and how many values follow them (-o, -s and -t take one to three numbers).
  static const std::pair<std::string_view, int> kOptions[] = {
      {"-blendu", 1}, {"-blendv", 1},  {"-bm", 1},  {"-boost", 1}, {"-cc", 1},
      {"-clamp", 1},  {"-imfchan", 1}, {"-mm", 2},  {"-o", 3},     {"-s", 3},
      {"-t", 3},      {"-texres", 1},  {"-type", 1}};
  // The first word of `r` (after blanks), and `r` moved past it.
  auto take_word = [](std::string_view& r) {
    r = trim(r);
    const std::size_t end = r.find_first_of(" \t");
    const std::string_view w = r.substr(0, end);
    r = end == std::string_view::npos ? std::string_view() : r.substr(end);
    return w;
  };
  auto is_number = [](std::string_view w) {
    return !w.empty() && w.find_first_not_of("+-.0123456789eE") == std::string_view::npos &&
           w.find_first_of("0123456789") != std::string_view::npos;
  };
  MapStatement m;
  for (;;) {
    std::string_view after = rest;
    const std::string_view word = take_word(after);
    int values = -1;
    for (const auto& [name, count] : kOptions)
      if (word == name) values = count;
    if (values < 0) break;  // the file name starts here
    rest = after;
    const bool numeric = word == "-o" || word == "-s" || word == "-t";
    for (int i = 0; i < values; ++i) {
      std::string_view ahead = rest;
      const std::string_view value = take_word(ahead);
      if (value.empty() || (numeric && !is_number(value))) break;  // `-s tex.png`: no value
      rest = ahead;
      if (word == "-clamp") m.clamp = value == "on";
      if ((word == "-s" || word == "-o") && i < 2 && is_number(value)) {
        // strtod of a word the number test passed; a malformed one ("1e") reads as its prefix.
        const double x = std::strtod(std::string(value).c_str(), nullptr);
        Vec2d& target = word == "-s" ? m.scale : m.offset;
        if (std::isfinite(x))
          (i == 0 ? target.x : target.y) = x;
        else if (m.problem.empty())
          m.problem = std::string(word) + " value " + std::string(value) + " is beyond any number";
      }
    }
  }
  m.file = std::string(trim(rest));
  if (m.file.size() >= 2 && m.file.front() == '"' && m.file.back() == '"')
    m.file = m.file.substr(1, m.file.size() - 2);
  return m;
}

// A path as written in a material file, relative to `dir` unless absolute; written on Windows
// (backslashes) it is read with slashes when that is what exists.
std::string material_file(const std::string& dir, const std::string& name) {
  std::string p = !name.empty() && name.front() == '/' ? name : dir + name;
  struct stat st {};
  if (p.find('\\') != std::string::npos && ::stat(p.c_str(), &st) != 0) {
    std::string q = name;
    std::replace(q.begin(), q.end(), '\\', '/');
    const std::string alt = !q.empty() && q.front() == '/' ? q : dir + q;
    if (::stat(alt.c_str(), &st) == 0) return alt;
  }
  return p;
}

// The material libraries a `mtllib` statement names: the whole rest of the line when that is
// a file (a name with spaces), else its words (the statement takes a list).
std::vector<std::string> material_libraries(const std::string& dir, std::string_view rest) {
  const std::string whole = material_file(dir, std::string(rest));
  struct stat st {};
  if (::stat(whole.c_str(), &st) == 0) return {whole};
  std::vector<std::string> libs;
  for (std::string_view r = rest; !trim(r).empty();) {
    r = trim(r);
    const std::size_t end = r.find_first_of(" \t");
    libs.push_back(material_file(dir, std::string(r.substr(0, end))));
    r = end == std::string_view::npos ? std::string_view() : r.substr(end);
  }
  return libs;
}

}  // namespace

namespace {

// The `mtllib` libraries an OBJ names and its `usemtl` names in order of first use.
struct ObjMaterials {
  std::vector<std::string> libraries;
  std::vector<std::string> used;
};

ObjMaterials obj_materials(const std::string& path, std::string_view data) {
  ObjMaterials m;
  for (std::size_t at = 0; at < data.size();) {
    std::size_t end = data.find('\n', at);
    if (end == std::string_view::npos) end = data.size();
    const std::string_view line = data.substr(at, end - at);
    at = end + 1;
    std::string_view rest;
    if (after_keyword(line, "mtllib", rest)) {
      for (std::string& lib : material_libraries(directory_of(path), rest))
        m.libraries.push_back(std::move(lib));
    } else if (after_keyword(line, "usemtl", rest)) {
      if (std::find(m.used.begin(), m.used.end(), rest) == m.used.end()) m.used.emplace_back(rest);
    }
  }
  return m;
}

// Material `material`'s texture and colour from the first library defining it (the first
// material of the first readable library when `material` is empty).
MeshTexture material_texture(const std::vector<std::string>& libraries, const std::string& material) {
  std::string unreadable;
  bool defined = false;  // the material is defined in a library read
  for (const std::string& mtl_path : libraries) {
    std::string mtl;
    try {
      mtl = read_file(mtl_path);
    } catch (const InputError& e) {
      // A missing MTL only loses the material, as in every viewer, but is said.
      if (unreadable.empty())
        unreadable = "its material library " + mtl_path + " cannot be read (" + e.what() + ")";
      continue;
    }
    bool in_material = false, seen_material = false;
    MeshTexture t;
    for (std::size_t at = 0; at < mtl.size();) {
      std::size_t end = mtl.find('\n', at);
      if (end == std::string::npos) end = mtl.size();
      const std::string_view line = std::string_view(mtl).substr(at, end - at);
      at = end + 1;
      std::string_view rest;
      if (after_keyword(line, "newmtl", rest)) {
        if (seen_material && in_material) break;
        in_material = material.empty() ? !seen_material : rest == material;
        seen_material = true;
        defined = defined || in_material;
      } else if (in_material && after_keyword(line, "Kd", rest)) {
        double c[3];
        int n = 0;
        for (std::string_view r = rest; n < 3 && !trim(r).empty(); ++n) {
          r = trim(r);
          const std::size_t stop = r.find_first_of(" \t");
          const std::string word(r.substr(0, stop));
          char* after = nullptr;
          c[n] = std::strtod(word.c_str(), &after);
          if (after == word.c_str() || *after != '\0' || !std::isfinite(c[n])) break;
          r = stop == std::string_view::npos ? std::string_view() : r.substr(stop);
        }
        if (n == 3) t.colour = {c[0], c[1], c[2]};
      } else if (in_material && t.file.empty() &&
                 (after_keyword(line, "map_Kd", rest) || after_keyword(line, "map_kd", rest))) {
        // map_kd: as some exporters write it, and other readers take it.
        const MapStatement map = map_statement(rest);
        if (map.file.empty()) continue;
        t.file = material_file(directory_of(mtl_path), map.file);
        if (!map.problem.empty()) {
          t.problem = "its material's map_Kd " + map.problem;
          t.file.clear();  // not read at all rather than read elsewhere than the map says
        }
        if (map.clamp) t.wrap = {Wrap::Clamp, Wrap::Clamp};
        // As Blender and three.js read them: uv · scale + offset.
        t.uv_transform.a = map.scale.x;
        t.uv_transform.e = map.scale.y;
        t.uv_transform.c = map.offset.x;
        t.uv_transform.f = map.offset.y;
      }
    }
    if (defined || (material.empty() && seen_material)) return t;
  }
  MeshTexture none;
  none.problem = unreadable;
  // A material used but defined nowhere is lost as a missing library is, and said alike.
  if (none.problem.empty() && !material.empty() && !libraries.empty() && !defined)
    none.problem = "its material " + material + " is defined in no material library it names";
  return none;
}

}  // namespace

MeshTexture obj_texture(const std::string& path, std::string_view data) {
  const ObjMaterials m = obj_materials(path, data);
  MeshTexture t = material_texture(m.libraries, m.used.empty() ? std::string() : m.used.front());
  t.several_materials = m.used.size() > 1;
  return t;
}

std::vector<MeshTexture> obj_textures(const std::string& path, std::string_view data,
                                      const std::vector<std::string>& materials) {
  const ObjMaterials m = obj_materials(path, data);
  std::vector<MeshTexture> out;
  for (const std::string& name : materials) {
    out.push_back(material_texture(m.libraries, name));
    out.back().several_materials = materials.size() > 1;
  }
  return out;
}

}  // namespace isochart::io_detail
