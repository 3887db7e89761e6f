// Geomview OFF reader: OFF, COFF, NOFF, STOFF and their combinations, '#' comments, counts
// on the header line or the next one, polygons, vertex colours in [0, 1] or [0, 255].
#include <algorithm>
#include <climits>
#include <cmath>

#include "io_internal.h"
#include "isochart/error.h"

namespace isochart::io_detail {

RawMesh read_off(const std::string& path, std::string_view data, const LoadOptions& options) {
  RawMesh raw;
  raw.source = path;
  LineScanner lines(path, data);
  // The next line with content, its comment stripped.
  auto next_content = [&](std::string_view& line) {
    while (lines.next(line)) {
      const std::size_t hash = line.find('#');
      if (hash != std::string_view::npos) line = line.substr(0, hash);
      std::string_view probe = line, tok;
      if (next_token(probe, tok)) return true;
    }
    return false;
  };

  std::string_view line, rest, tok;
  if (!next_content(line)) throw InputError(path, "has no OFF header (only comments or blank lines)");
  rest = line;
  next_token(rest, tok);
  // [ST][C][N][4][n]OFF, in this order.
  std::string_view h = tok;
  const bool st = h.substr(0, 2) == "ST";
  if (st) h.remove_prefix(2);
  const bool colored = !h.empty() && h[0] == 'C';
  if (colored) h.remove_prefix(1);
  const bool with_normals = !h.empty() && h[0] == 'N';
  if (with_normals) h.remove_prefix(1);
  if (!h.empty() && h[0] == '4' && h.substr(1).find("OFF") != std::string_view::npos)
    fail_at_line(path, lines.line_number(), "only 3D OFF files are supported (header " + quoted(tok) + ")");
  // nOFF gives the space dimension before the counts; a 3-D one is a plain OFF.
  if (h == "nOFF") {
    const std::string header(tok);
    std::string_view dim;
    if (!next_token(rest, dim)) {
      if (!next_content(line)) throw InputError(path, "file ends after the nOFF header (no dimension)");
      rest = line;
      next_token(rest, dim);
    }
    long long n = 0;
    if (!parse_int(dim, n) || n != 3)
      fail_at_line(path, lines.line_number(),
                   "only 3D OFF files are supported (header " + quoted(header) + " with dimension " +
                       quoted(dim) + ")");
    h = "OFF";
  }
  if (h != "OFF")
    fail_at_line(path, lines.line_number(),
                 "expected an OFF header ('OFF', 'COFF', 'NOFF', ...), found " + quoted(tok));

  // Counts: vertices, faces and (ignored) edges, on the header line or the next one.
  long long counts[3] = {0, 0, 0};
  int nc = 0;
  std::string_view count_line = rest;
  if (!next_token(count_line, tok)) {
    if (!next_content(line)) throw InputError(path, "file ends after the OFF header (no counts)");
    count_line = line;
  } else if (tok == "BINARY") {
    fail_at_line(path, lines.line_number(), "binary OFF is not supported");
  } else {
    count_line = rest;
  }
  const long long count_ln = lines.line_number();
  while (next_token(count_line, tok)) {
    if (nc == 3 || !parse_int(tok, counts[nc]))
      fail_at_line(path, count_ln, "expected the vertex, face and edge counts, found " + quoted(tok));
    ++nc;
  }
  if (nc < 2) fail_at_line(path, count_ln, "expected the vertex, face and edge counts");
  const long long nv = counts[0], nf = counts[1];
  if (nv < 0 || nf < 0 || nv > INT_MAX || nf > INT_MAX)
    fail_at_line(
        path, count_ln,
        "vertex and face counts " + std::to_string(nv) + " " + std::to_string(nf) + " are out of range");
  // A vertex line takes at least 6 bytes ("0 0 0\n") and a face line 2 (a corner count, which
  // may be wrong; that is said with its line): a header claiming more than the file can hold
  // is refused before anything is allocated.
  if (nv * 6 + nf * 2 > static_cast<long long>(lines.remaining()) + 2)
    fail_at_line(path, count_ln,
                 "header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                     " faces, but only " + std::to_string(lines.remaining()) +
                     " bytes follow (truncated file or corrupt header)");
  check_face_limit(path, nf, options);

  raw.positions.reserve(nv);
  if (with_normals) raw.normals.reserve(nv);
  if (colored) raw.colors.reserve(nv);
  if (st) raw.uvs.reserve(nv);
  const int fixed = 3 + (with_normals ? 3 : 0) + (st ? 2 : 0);
  double c[16];
  double max_color = 0;
  for (long long i = 0; i < nv; ++i) {
    if (!next_content(line))
      throw InputError(path, "unexpected end of file after " + std::to_string(i) + " of " +
                                 std::to_string(nv) + " vertices (truncated)");
    const long long ln = lines.line_number();
    int n = 0;
    rest = line;
    while (n < 16 && next_token(rest, tok)) {
      if (!parse_double(tok, c[n])) fail_at_line(path, ln, quoted(tok) + " is not a number");
      if (!std::isfinite(c[n])) fail_at_line(path, ln, "value " + not_finite(tok));
      ++n;
    }
    if (n < fixed)
      fail_at_line(path, ln,
                   "vertex " + std::to_string(i) + ": expected " + std::to_string(fixed) +
                       " numbers, found " + std::to_string(n));
    raw.positions.push_back({c[0], c[1], c[2]});
    int at = 3;
    if (with_normals) {
      raw.normals.push_back({c[3], c[4], c[5]});
      at = 6;
    }
    // Colours sit between the normal and the texture coordinate (geomview order).
    const int ncolor = n - fixed;
    if (colored) {
      if (ncolor != 3 && ncolor != 4)
        fail_at_line(path, ln,
                     "vertex " + std::to_string(i) + ": expected an r g b [a] colour after the " +
                         (with_normals ? "normal" : "coordinates"));
      raw.colors.push_back({c[at], c[at + 1], c[at + 2]});
      max_color = std::max({max_color, c[at], c[at + 1], c[at + 2]});
    }
    if (st) raw.uvs.push_back({c[n - 2], c[n - 1]});
  }
  if (max_color > 1)
    for (auto& col : raw.colors) col /= 255.0;

  raw.polygons.resize(static_cast<std::size_t>(nf));
  for (long long j = 0; j < nf; ++j) {
    if (!next_content(line))
      throw InputError(path, "unexpected end of file after " + std::to_string(j) + " of " +
                                 std::to_string(nf) + " faces (truncated)");
    const long long ln = lines.line_number();
    rest = line;
    long long k = 0;
    next_token(rest, tok);
    // The first face line holding what a vertex line holds: the header counts too few vertices.
    const auto vertex_like = [&]() -> std::string {
      if (j > 0) return std::string();
      std::string_view r = line, t;
      int n = 0;
      double x;
      bool whole = true;
      while (next_token(r, t)) {
        if (!parse_double(t, x) || ++n > fixed) return std::string();
        whole &= x == std::floor(x);
      }
      // "2 0 1" is a face of two corners as it stands; "0 0 1" or "0.5 0 0" is not a face.
      if (n != fixed || (whole && n - 1 == k)) return std::string();
      return " (it looks like a vertex: does the header count too few vertices?)";
    };
    if (!parse_int(tok, k)) fail_at_line(path, ln, quoted(tok) + " is not a corner count" + vertex_like());
    if (k < 3)
      fail_at_line(path, ln,
                   "face has " + std::to_string(k) + " corners; a face needs at least 3" + vertex_like());
    if (k > static_cast<long long>(rest.size()))
      fail_at_line(path, ln, "face declares " + std::to_string(k) + " corners but lists fewer indices");
    auto& poly = raw.polygons[static_cast<std::size_t>(j)];
    poly.resize(static_cast<std::size_t>(k));
    for (long long q = 0; q < k; ++q) {
      long long idx = 0;
      if (!next_token(rest, tok))
        fail_at_line(
            path, ln,
            "face declares " + std::to_string(k) + " corners but lists " + std::to_string(q) + " indices");
      if (!parse_int(tok, idx))
        fail_at_line(path, ln,
                     is_integer_text(tok)
                         ? "vertex index " + std::string(tok) + " is out of range (the file has " +
                               std::to_string(nv) + " vertices)"
                         : quoted(tok) + " is not a vertex index");
      if (idx < 0 || idx >= nv)
        fail_at_line(path, ln,
                     "vertex index " + std::to_string(idx) + " is out of range (the file has " +
                         std::to_string(nv) + " vertices)");
      poly[static_cast<std::size_t>(q)] = static_cast<int>(idx);
    }
    // Anything left is a face colour, which a mesh does not keep.
  }
  // More lines than the header declares: the counts are wrong, and the rest of the mesh would
  // be dropped without a word.
  if (next_content(line))
    fail_at_line(path, lines.line_number(),
                 "more data after the " + std::to_string(nf) + " faces the header declares (" + quoted(line) +
                     "); the header's counts do not match the file");
  if (st) raw.polygon_uvs = raw.polygons;
  return raw;
}

}  // namespace isochart::io_detail
