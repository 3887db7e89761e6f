// Validation and repair of a raw polygon soup into a clean, oriented, manifold triangle mesh.
//
// Connectivity is kept as a "mate" per half-edge (half-edge h = 3 f + k is edge k of face f,
// from corner k to corner k+1): the half-edge it is glued to, or -1. Manifold edges glue
// their two faces; non-manifold edges glue chosen pairs; orientation conflicts unglue. Each
// vertex is then split into one vertex per fan of corners connected through glued edges,
// which turns the gluing into the output's vertex sharing.
#include "isochart/validate.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_face_base_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <tuple>

#include "isochart/error.h"
#include "isochart/union_find.h"

namespace isochart {

namespace {

// A triangle whose height is below 1e-15 of its longest side is flat to double precision: no
// layout can keep its shape once packed (its UVs a few ulps apart near 0.5), and the atlas
// flipped such slivers. Treated like an exactly collinear triangle.
bool too_thin(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double longest = std::max({squared_norm(b - a), squared_norm(c - b), squared_norm(a - c)});
  return norm(cross(b - a, c - a)) < 1e-15 * longest;
}

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

std::string text(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}
std::string text(const Vec3d& v) {
  return "(" + text(v.x) + ", " + text(v.y) + ", " + text(v.z) + ")";
}
std::string text(const Vec2d& v) {
  return "(" + text(v.x) + ", " + text(v.y) + ")";
}

K::Point_3 point(const Vec3d& p) {
  return {p.x, p.y, p.z};
}

// ---- Polygon triangulation -------------------------------------------------------------

// Polygons beyond this size get a constrained Delaunay triangulation instead: ear clipping is
// quadratic per ear.
constexpr std::size_t kMaxEarClipping = 2000;

// A simple polygon (projected, counter-clockwise) triangulated by a constrained Delaunay
// triangulation of its edges, keeping the faces inside; false (nothing appended) when the
// polygon is not simple (edges crossing, repeated points), which the caller fans instead.
bool triangulate_cdt(const std::vector<K::Point_2>& p, const std::vector<int>& corners,
                     std::vector<std::array<int, 3>>& out) {
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
  using Fbi = CGAL::Triangulation_face_base_with_info_2<int, K>;  // nesting level, -1 unvisited
  using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbi>;
  using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
  using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_tag>;
  const int n = static_cast<int>(p.size());
  Cdt cdt;
  std::vector<Cdt::Vertex_handle> v(n);
  try {
    for (int i = 0; i < n; ++i) {
      v[i] = cdt.insert(p[i]);
      v[i]->info() = i;
    }
    if (cdt.number_of_vertices() != static_cast<std::size_t>(n)) return false;  // a repeated point
    for (int i = 0; i < n; ++i) cdt.insert_constraint(v[i], v[(i + 1) % n]);
  } catch (const std::exception&) {
    return false;  // crossing edges
  }
  // Inside: reached from the infinite faces across an odd number of constrained edges.
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  std::vector<Cdt::Face_handle> stack{cdt.infinite_face()}, next;
  cdt.infinite_face()->info() = 0;
  for (int level = 0; !stack.empty(); ++level) {
    while (!stack.empty()) {
      const Cdt::Face_handle f = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const Cdt::Face_handle g = f->neighbor(k);
        if (g->info() != -1) continue;
        if (cdt.is_constrained({f, k})) {
          g->info() = level + 1;
          next.push_back(g);
        } else {
          g->info() = level;
          stack.push_back(g);
        }
      }
    }
    std::swap(stack, next);
  }
  std::vector<std::array<int, 3>> tris;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    if (f->info() % 2 == 1)
      tris.push_back(
          {corners[f->vertex(0)->info()], corners[f->vertex(1)->info()], corners[f->vertex(2)->info()]});
  if (static_cast<int>(tris.size()) != n - 2) return false;  // not a simple polygon after all
  out.insert(out.end(), tris.begin(), tris.end());
  return true;
}

// Ear clipping in the plane across the dominant axis of the polygon's Newell normal; that
// projection only drops a coordinate, so the 2D predicates are exact on the input values.
// `corners` are positions in `poly`; triangles are appended as corner triples.
void triangulate(const std::vector<Vec3d>& pos, const std::vector<int>& poly, const std::vector<int>& corners,
                 std::vector<std::array<int, 3>>& out) {
  const int n = static_cast<int>(corners.size());
  if (n == 3) {
    out.push_back({corners[0], corners[1], corners[2]});
    return;
  }
  Vec3d c;
  for (int i : corners) c += pos[poly[i]];
  c /= n;
  Vec3d normal;
  for (int i = 0; i < n; ++i) normal += cross(pos[poly[corners[i]]] - c, pos[poly[corners[(i + 1) % n]]] - c);
  const double ax = std::abs(normal.x), ay = std::abs(normal.y), az = std::abs(normal.z);
  const int axis = ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
  auto fan = [&](int from) {
    for (int i = 1; i + 1 < n; ++i)
      out.push_back({corners[from], corners[(from + i) % n], corners[(from + i + 1) % n]});
  };
  if (normal[axis] == 0) {
    fan(0);
    return;
  }
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const bool flip = normal[axis] < 0;  // make the projected polygon counter-clockwise
  std::vector<K::Point_2> p(n);
  for (int i = 0; i < n; ++i) {
    const Vec3d& q = pos[poly[corners[i]]];
    p[i] = flip ? K::Point_2(q[v], q[u]) : K::Point_2(q[u], q[v]);
  }
  if (static_cast<std::size_t>(n) > kMaxEarClipping) {
    // A fan of a concave polygon overlaps itself: a 4,000-gon star came out with half its
    // triangles turned over.
    if (!triangulate_cdt(p, corners, out)) fan(0);
    return;
  }
  std::vector<int> prev(n), next(n);
  for (int i = 0; i < n; ++i) {
    prev[i] = (i + n - 1) % n;
    next[i] = (i + 1) % n;
  }
  auto is_ear = [&](int b) {
    const int a = prev[b], c2 = next[b];
    if (CGAL::orientation(p[a], p[b], p[c2]) != CGAL::LEFT_TURN) return false;
    for (int r = next[c2]; r != a; r = next[r]) {
      if (p[r] == p[a] || p[r] == p[b] || p[r] == p[c2]) continue;
      if (CGAL::orientation(p[a], p[b], p[r]) != CGAL::RIGHT_TURN &&
          CGAL::orientation(p[b], p[c2], p[r]) != CGAL::RIGHT_TURN &&
          CGAL::orientation(p[c2], p[a], p[r]) != CGAL::RIGHT_TURN)
        return false;
    }
    return true;
  };
  int remaining = n, i = 0;
  while (remaining > 3) {
    bool clipped = false;
    for (int step = 0; step < remaining; ++step, i = next[i]) {
      if (!is_ear(i)) continue;
      out.push_back({corners[prev[i]], corners[i], corners[next[i]]});
      next[prev[i]] = next[i];
      prev[next[i]] = prev[i];
      i = next[i];
      --remaining;
      clipped = true;
      break;
    }
    if (!clipped) {
      // Self-intersecting or numerically flat: no ear exists. Fan what is left.
      for (int j = next[i]; next[j] != i; j = next[j])
        out.push_back({corners[i], corners[j], corners[next[j]]});
      return;
    }
  }
  out.push_back({corners[prev[i]], corners[i], corners[next[i]]});
}

// ---- Non-manifold edges ----------------------------------------------------------------

// Pairs the faces around a non-manifold edge. Seen along the edge, a face whose normal turns
// counter-clockwise has its back side (the solid, for an outward surface) clockwise, so it
// is paired with its clockwise neighbour of opposite orientation: each pair then encloses
// one solid wedge, and two closed surfaces touching along the edge both stay closed.
// Left-over faces (odd counts, or no opposite neighbour) stay unglued along this edge.
void pair_around_edge(const int* half_edges, int count, const std::vector<Face>& faces,
                      const std::vector<Vec3d>& pos, std::vector<int>& mate) {
  const int h0 = half_edges[0];
  const int a = std::min(faces[h0 / 3][h0 % 3], faces[h0 / 3][(h0 % 3 + 1) % 3]);
  const int b = std::max(faces[h0 / 3][h0 % 3], faces[h0 / 3][(h0 % 3 + 1) % 3]);
  const Vec3d d = normalized(pos[b] - pos[a]);
  const Vec3d helper = std::abs(d.x) <= std::abs(d.y) && std::abs(d.x) <= std::abs(d.z) ? Vec3d{1, 0, 0}
                       : std::abs(d.y) <= std::abs(d.z)                                 ? Vec3d{0, 1, 0}
                                                                                        : Vec3d{0, 0, 1};
  const Vec3d e1 = normalized(cross(d, helper)), e2 = cross(d, e1);
  struct Item {
    double angle;
    int face, half_edge, sign;  // sign +1 when the face runs a → b
  };
  std::vector<Item> items;
  for (int i = 0; i < count; ++i) {
    const int h = half_edges[i], f = h / 3, k = h % 3;
    const Vec3d w = pos[faces[f][(k + 2) % 3]] - pos[a];
    items.push_back({std::atan2(dot(w, e2), dot(w, e1)), f, h, faces[f][k] == a ? 1 : -1});
  }
  std::sort(items.begin(), items.end(), [](const Item& x, const Item& y) {
    return x.angle != y.angle ? x.angle < y.angle : x.face < y.face;
  });
  while (items.size() >= 2) {
    const std::size_t m = items.size();
    std::size_t i = 0, j = 1;
    for (std::size_t q = 0; q < m; ++q)
      if (items[q].sign < 0 && items[(q + 1) % m].sign > 0) {
        i = q;
        j = (q + 1) % m;
        break;
      }
    // Without an opposite pair the orientation is inconsistent here; pairing angular
    // neighbours still gives a manifold that the orientation pass can then fix.
    mate[items[i].half_edge] = items[j].half_edge;
    mate[items[j].half_edge] = items[i].half_edge;
    items.erase(items.begin() + static_cast<long>(std::max(i, j)));
    items.erase(items.begin() + static_cast<long>(std::min(i, j)));
  }
}

// The corner of face g at (input) vertex v, given that half-edge j of g touches v.
int corner_at(const std::vector<Face>& faces, int g, int j, int v) {
  return faces[g][j] == v ? 3 * g + j : 3 * g + (j + 1) % 3;
}

// Fans: corners joined across glued edges, one union-find class per output vertex.
UnionFind corner_classes(const std::vector<Face>& faces, const std::vector<int>& mate) {
  UnionFind uf(3 * faces.size());
  for (std::size_t h = 0; h < mate.size(); ++h) {
    const int h2 = mate[h];
    if (h2 < static_cast<int>(h)) continue;  // each glued pair once (and -1 skipped)
    const int f = static_cast<int>(h / 3), k = static_cast<int>(h % 3), g = h2 / 3, j = h2 % 3;
    const int va = faces[f][k], vb = faces[f][(k + 1) % 3];
    uf.unite(3 * f + k, corner_at(faces, g, j, va));
    uf.unite(3 * f + (k + 1) % 3, corner_at(faces, g, j, vb));
  }
  return uf;
}

// Half-edges grouped by undirected edge: `order` lists half-edges so that those on one
// edge are contiguous (groups in order of their smaller, then larger vertex; half-edges by
// id inside), `start` holds each group's first position plus a final end. `vertex_of(c)`
// is the vertex at corner c. Bucketing by the smaller vertex keeps this linear but for
// tiny per-vertex sorts.
struct EdgeGroups {
  std::vector<int> order, start;
};
template <typename VertexOf>
EdgeGroups group_edges(int num_half_edges, int num_vertices, VertexOf vertex_of) {
  auto ends = [&](int h) {
    const int a = vertex_of(h), b = vertex_of(h - h % 3 + (h % 3 + 1) % 3);
    return std::make_pair(std::min(a, b), std::max(a, b));
  };
  std::vector<int> offset(num_vertices + 1, 0);
  for (int h = 0; h < num_half_edges; ++h) ++offset[ends(h).first + 1];
  for (int v = 0; v < num_vertices; ++v) offset[v + 1] += offset[v];
  EdgeGroups g;
  g.order.resize(num_half_edges);
  {
    std::vector<int> cursor(offset.begin(), offset.end() - 1);
    for (int h = 0; h < num_half_edges; ++h) g.order[cursor[ends(h).first]++] = h;
  }
  for (int v = 0; v < num_vertices; ++v) {
    const auto first = g.order.begin() + offset[v], last = g.order.begin() + offset[v + 1];
    std::sort(first, last, [&](int x, int y) {
      const int bx = ends(x).second, by = ends(y).second;
      return bx != by ? bx < by : x < y;
    });
    for (auto it = first; it != last; ++it)
      if (it == first || ends(*it).second != ends(*(it - 1)).second)
        g.start.push_back(static_cast<int>(it - g.order.begin()));
  }
  g.start.push_back(num_half_edges);
  return g;
}

}  // namespace

// ---- Double-sided sheets -----------------------------------------------------------------

// A double-sided sheet (a card of foliage, a flag) gives every face twice, once reversed, on
// the same vertices. Read as it is, its inner edges have four faces, and the duplicate test
// removed one side. Here each edge-connected piece made wholly of such pairs is split into
// its two sides, the back one on vertices of its own: two coincident open sheets, each
// unfolded and textured on its own. A piece where only some faces are repeated reversed (a
// stray copy on a closed surface) is left to the duplicate test. Returns the polygons moved
// to new vertices (0: `out` untouched).
int split_double_sided(const RawMesh& raw, RawMesh& out) {
  const int np = static_cast<int>(raw.polygons.size());
  const int nv = static_cast<int>(raw.positions.size());
  // Reversed twins: the same vertices, each polygon the other read backwards, and no third copy.
  std::vector<std::pair<std::vector<int>, int>> keys;
  keys.reserve(np);
  for (int f = 0; f < np; ++f) {
    std::vector<int> k = raw.polygons[f];
    std::sort(k.begin(), k.end());
    if (std::adjacent_find(k.begin(), k.end()) != k.end()) continue;  // repeats a vertex
    keys.emplace_back(std::move(k), f);
  }
  std::sort(keys.begin(), keys.end());
  auto reversed = [&](int f, int g) {
    const auto& a = raw.polygons[f];
    const auto& b = raw.polygons[g];
    const int n = static_cast<int>(a.size());
    const int at = static_cast<int>(std::find(b.begin(), b.end(), a[0]) - b.begin());
    for (int i = 0; i < n; ++i)
      if (b[((at - i) % n + n) % n] != a[i]) return false;
    return true;
  };
  std::vector<int> twin(np, -1);
  bool any = false;
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    if (keys[i].first != keys[i + 1].first) continue;
    if (i > 0 && keys[i - 1].first == keys[i].first) continue;
    if (i + 2 < keys.size() && keys[i + 2].first == keys[i].first) continue;
    const int f = keys[i].second, g = keys[i + 1].second;
    if (!reversed(f, g)) continue;
    twin[f] = g;
    twin[g] = f;
    any = true;
  }
  if (!any) return 0;

  // Polygon edges grouped by their two vertices; `forward` when the polygon runs low → high.
  struct Side {
    int low, high, face;
    bool forward;
    bool operator<(const Side& o) const {
      return std::tie(low, high, face, forward) < std::tie(o.low, o.high, o.face, o.forward);
    }
  };
  std::vector<Side> sides;
  for (int f = 0; f < np; ++f) {
    const auto& p = raw.polygons[f];
    for (std::size_t i = 0; i < p.size(); ++i) {
      const int u = p[i], w = p[(i + 1) % p.size()];
      sides.push_back({std::min(u, w), std::max(u, w), f, u < w});
    }
  }
  std::sort(sides.begin(), sides.end());
  std::vector<std::size_t> start = {0};
  for (std::size_t i = 1; i <= sides.size(); ++i)
    if (i == sides.size() || sides[i].low != sides[i - 1].low || sides[i].high != sides[i - 1].high)
      start.push_back(i);
  std::vector<std::vector<int>> edges_of(np);  // per polygon: its edge groups
  UnionFind pieces(np);
  for (std::size_t e = 0; e + 1 < start.size(); ++e)
    for (std::size_t i = start[e]; i < start[e + 1]; ++i) {
      edges_of[sides[i].face].push_back(static_cast<int>(e));
      pieces.unite(sides[i].face, sides[start[e]].face);
    }
  std::vector<char> mixed(np, 0);
  for (int f = 0; f < np; ++f)
    if (twin[f] < 0) mixed[pieces.find(f)] = 1;

  // Per whole piece, its front: the side reached from its first polygon across edges run the
  // other way by a polygon that is not the twin (at the rim only the twin shares the edge).
  std::vector<signed char> sheet(np, 0);  // +1 front, -1 back
  std::vector<int> queue;
  for (int s = 0; s < np; ++s) {
    if (mixed[pieces.find(s)] || sheet[s] != 0) continue;
    bool ok = true;
    std::vector<int> seen;
    sheet[s] = 1;
    sheet[twin[s]] = -1;
    queue.assign(1, s);
    seen = {s, twin[s]};
    for (std::size_t qi = 0; qi < queue.size() && ok; ++qi) {
      const int f = queue[qi];
      for (int e : edges_of[f]) {
        bool dir = false;
        for (std::size_t i = start[e]; i < start[e + 1]; ++i)
          if (sides[i].face == f) dir = sides[i].forward;
        for (std::size_t i = start[e]; i < start[e + 1]; ++i) {
          const int g = sides[i].face;
          if (g == f || g == twin[f] || sides[i].forward == dir) continue;
          if (sheet[g] == 0) {
            sheet[g] = sheet[f];
            sheet[twin[g]] = static_cast<signed char>(-sheet[f]);
            seen.push_back(g);
            seen.push_back(twin[g]);
            queue.push_back(g);
          } else if (sheet[g] != sheet[f]) {
            ok = false;  // the sides meet: no two sheets to separate
          }
        }
      }
    }
    if (!ok)
      for (int f : seen) sheet[f] = 0, mixed[pieces.find(f)] = 1;
  }
  // Pieces where the walk did not reach every polygon are not two plain sheets either.
  std::vector<int> reached(np, 0), size(np, 0);
  for (int f = 0; f < np; ++f) {
    ++size[pieces.find(f)];
    reached[pieces.find(f)] += sheet[f] != 0;
  }
  int moved = 0;
  out = raw;
  std::vector<int> copy_of(nv, -1);
  std::vector<int> touched;
  int last_piece = -1;
  std::vector<int> order(np);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return pieces.find(a) < pieces.find(b); });
  for (int f : order) {
    const int r = pieces.find(f);
    if (sheet[f] >= 0 || mixed[r] || reached[r] != size[r]) continue;
    if (r != last_piece) {  // each piece's back gets vertices of its own
      for (int v : touched) copy_of[v] = -1;
      touched.clear();
      last_piece = r;
    }
    for (int& v : out.polygons[f]) {
      if (copy_of[v] < 0) {
        copy_of[v] = static_cast<int>(out.positions.size());
        touched.push_back(v);
        out.positions.push_back(raw.positions[v]);
        if (!raw.normals.empty()) out.normals.push_back(raw.normals[v]);
        if (!raw.colors.empty()) out.colors.push_back(raw.colors[v]);
      }
      v = copy_of[v];
    }
    ++moved;
  }
  return moved;
}

RawMesh to_raw_mesh(const Mesh& mesh, const std::string& source) {
  RawMesh raw;
  raw.source = source;
  raw.positions = mesh.positions;
  raw.normals = mesh.normals;
  raw.colors = mesh.colors;
  raw.polygons.reserve(mesh.faces.size());
  for (const Face& f : mesh.faces) raw.polygons.push_back({f[0], f[1], f[2]});
  if (mesh.has_uvs()) {
    raw.uvs = mesh.uvs;
    raw.polygon_uvs.reserve(mesh.face_uvs.size());
    for (const Face& f : mesh.face_uvs) raw.polygon_uvs.push_back({f[0], f[1], f[2]});
  }
  raw.polygon_groups = mesh.face_groups;
  raw.polygon_materials = mesh.face_materials;
  raw.material_names = mesh.material_names;
  return raw;
}

Mesh validate_mesh(const RawMesh& raw, bool repair, ValidationReport& report) {
  const std::string& src = raw.source;
  auto fail = [&](const std::string& message) { throw InputError(src, message); };
  auto need_repair = [&](const std::string& message) {
    throw InputError(src, message + "; it needs repair, which is turned off (--no-repair)");
  };
  report = ValidationReport{};
  report.warnings = raw.warnings;
  report.faces_without_uvs = raw.faces_without_uvs;

  // ---- Errors nothing can repair ----
  if (raw.positions.size() > static_cast<std::size_t>(INT_MAX) / 2 ||
      raw.polygons.size() > static_cast<std::size_t>(INT_MAX) / 3)
    fail("mesh is too large");
  const int nv = static_cast<int>(raw.positions.size());
  const int np = static_cast<int>(raw.polygons.size());
  report.input_vertices = nv;
  report.input_faces = np;
  if (nv == 0) fail("mesh has no vertices");
  if (np == 0) fail("mesh has no faces");
  const bool has_normals = !raw.normals.empty(), has_colors = !raw.colors.empty();
  const bool has_uvs = !raw.polygon_uvs.empty(), has_groups = !raw.polygon_groups.empty();
  if (has_normals && raw.normals.size() != raw.positions.size())
    fail(std::to_string(raw.normals.size()) + " normals for " + std::to_string(nv) + " vertices");
  if (has_colors && raw.colors.size() != raw.positions.size())
    fail(std::to_string(raw.colors.size()) + " colours for " + std::to_string(nv) + " vertices");
  if (has_uvs && raw.polygon_uvs.size() != raw.polygons.size())
    fail("texture coordinates for " + std::to_string(raw.polygon_uvs.size()) + " of " + std::to_string(np) +
         " faces");
  if (has_groups && raw.polygon_groups.size() != raw.polygons.size())
    fail("groups for " + std::to_string(raw.polygon_groups.size()) + " of " + std::to_string(np) + " faces");
  const bool has_materials = !raw.polygon_materials.empty();
  if (has_materials && raw.polygon_materials.size() != raw.polygons.size())
    fail("materials for " + std::to_string(raw.polygon_materials.size()) + " of " + std::to_string(np) +
         " faces");
  for (int v = 0; v < nv; ++v) {
    if (!is_finite(raw.positions[v]))
      fail("vertex " + std::to_string(v) + " has a non-finite coordinate " + text(raw.positions[v]));
    if (has_normals && !is_finite(raw.normals[v]))
      fail("vertex " + std::to_string(v) + " has a non-finite normal " + text(raw.normals[v]));
    if (has_colors && !is_finite(raw.colors[v]))
      fail("vertex " + std::to_string(v) + " has a non-finite colour " + text(raw.colors[v]));
  }
  // Beyond these, products of coordinates (areas, squared distances) overflow or underflow
  // double precision somewhere in the pipeline; say so here rather than fail deep inside.
  constexpr double kMaxCoordinate = 1e30, kMinExtent = 1e-30;
  {
    Vec3d lo{0, 0, 0}, hi{0, 0, 0};
    for (int v = 0; v < nv; ++v) {
      const Vec3d& p = raw.positions[v];
      if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > kMaxCoordinate)
        fail("vertex " + std::to_string(v) + " has a coordinate beyond ±1e30 " + text(p));
      lo = v == 0 ? p : Vec3d{std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = v == 0 ? p : Vec3d{std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    if (nv > 0 && extent > 0 && extent < kMinExtent)
    {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.3g", extent);
      fail(std::string("the mesh is too small to process (largest extent ") + buf + "); scale it up");
    }
    // Doubles carry 52 bits: a mesh 1e-14 across at 1 from the origin (or 1e-6 at 1e9) has its
    // vertices on a grid of a few dozen steps, its triangles cannot keep their shapes, and
    // the atlas missed its bounds. Below 2^20 steps across, refuse rather than mislead.
    const double far = std::max({std::abs(lo.x), std::abs(lo.y), std::abs(lo.z), std::abs(hi.x), std::abs(hi.y),
                                 std::abs(hi.z)});
    if (nv > 0 && extent > 0 && extent < std::ldexp(far, -32)) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "the mesh is %.3g across but %.3g from the origin", extent, far);
      fail(std::string(buf) + ": its coordinates are too coarse for its size; move it nearer the origin");
    }
  }
  for (std::size_t t = 0; t < raw.uvs.size(); ++t)
    if (!is_finite(raw.uvs[t]))
      fail("texture coordinate " + std::to_string(t) + " is not finite " + text(raw.uvs[t]));
    else if (std::max(std::abs(raw.uvs[t].x), std::abs(raw.uvs[t].y)) > kMaxCoordinate)
      fail("texture coordinate " + std::to_string(t) + " is beyond ±1e30 " + text(raw.uvs[t]));
  for (int f = 0; f < np; ++f) {
    const auto& poly = raw.polygons[f];
    if (poly.size() < 3)
      fail("face " + std::to_string(f) + " has " + std::to_string(poly.size()) +
           " corners; a face needs at least 3");
    for (int v : poly)
      if (v < 0 || v >= nv)
        fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
             ", but there are only " + std::to_string(nv) + " vertices");
    if (has_uvs) {
      if (raw.polygon_uvs[f].size() != poly.size())
        fail("face " + std::to_string(f) + " has " + std::to_string(raw.polygon_uvs[f].size()) +
             " texture coordinates for " + std::to_string(poly.size()) + " corners");
      for (int t : raw.polygon_uvs[f])
        if (t < 0 || t >= static_cast<int>(raw.uvs.size()))
          fail("face " + std::to_string(f) + " refers to texture coordinate " + std::to_string(t) +
               ", but there are only " + std::to_string(raw.uvs.size()));
    }
  }
  if (repair) {
    RawMesh split;
    if (const int moved = split_double_sided(raw, split)) {
      Mesh m = validate_mesh(split, repair, report);
      report.input_vertices = nv;
      report.double_sided_faces = moved;
      report.warnings.push_back("gave the back side of " + std::to_string(moved) +
                                (moved == 1 ? " face" : " faces") +
                                " repeated in reverse (a double-sided sheet) vertices of its own, so both "
                                "sides are kept as separate sheets");
      return m;
    }
  }

  // ---- Triangulation and degenerate faces ----
  std::vector<Face> faces, face_uv;
  std::vector<int> face_source;  // input face of each triangle
  faces.reserve(raw.polygons.size());
  std::vector<int> corners;
  std::vector<std::array<int, 3>> tris;
  int triangles_from_polygons = 0;
  for (int f = 0; f < np; ++f) {
    const auto& poly = raw.polygons[f];
    tris.clear();
    if (poly.size() == 3) {
      tris.push_back({0, 1, 2});
    } else {
      if (!repair)
        need_repair("face " + std::to_string(f) + " has " + std::to_string(poly.size()) + " corners, not 3");
      // Repeated consecutive corners carry no area; dropping them first keeps ear clipping
      // on a proper polygon.
      corners.clear();
      for (int i = 0; i < static_cast<int>(poly.size()); ++i)
        if (corners.empty() || poly[corners.back()] != poly[i]) corners.push_back(i);
      while (corners.size() > 1 && poly[corners.back()] == poly[corners.front()]) corners.pop_back();
      if (corners.size() < 3) {
        ++report.degenerate_faces;  // a polygon of one or two distinct corners: not triangulated
        continue;
      }
      ++report.polygons;
      triangulate(raw.positions, poly, corners, tris);
      triangles_from_polygons += static_cast<int>(tris.size());
    }
    for (const auto& t : tris) {
      const Face v = {poly[t[0]], poly[t[1]], poly[t[2]]};
      const bool repeated = v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
      if (repeated || CGAL::collinear(point(raw.positions[v[0]]), point(raw.positions[v[1]]),
                                      point(raw.positions[v[2]])) ||
          too_thin(raw.positions[v[0]], raw.positions[v[1]], raw.positions[v[2]])) {
        ++report.degenerate_faces;
        if (!repair)
          need_repair("face " + std::to_string(f) + " is degenerate (" +
                      (repeated ? "it repeats a vertex" : "zero area") + ")");
        continue;
      }
      faces.push_back(v);
      if (has_uvs) {
        const auto& puv = raw.polygon_uvs[f];
        face_uv.push_back({puv[t[0]], puv[t[1]], puv[t[2]]});
      }
      face_source.push_back(f);
    }
  }

  // ---- Duplicate faces: the same vertex set, whatever the order ----
  {
    std::vector<std::pair<Face, int>> keys(faces.size());
    for (std::size_t f = 0; f < faces.size(); ++f) {
      Face s = faces[f];
      std::sort(s.begin(), s.end());
      keys[f] = {s, static_cast<int>(f)};
    }
    std::sort(keys.begin(), keys.end());
    std::vector<char> drop(faces.size(), 0);
    for (std::size_t i = 1; i < keys.size(); ++i)
      if (keys[i].first == keys[i - 1].first) {
        drop[keys[i].second] = 1;
        ++report.duplicate_faces;
        if (!repair) {
          std::size_t first = i - 1;
          while (first > 0 && keys[first - 1].first == keys[i].first) --first;
          need_repair("face " + std::to_string(face_source[keys[i].second]) +
                      " has the same vertices as face " + std::to_string(face_source[keys[first].second]));
        }
      }
    if (report.duplicate_faces > 0) {
      std::size_t w = 0;
      for (std::size_t f = 0; f < faces.size(); ++f)
        if (!drop[f]) {
          faces[w] = faces[f];
          if (has_uvs) face_uv[w] = face_uv[f];
          face_source[w] = face_source[f];
          ++w;
        }
      faces.resize(w);
      if (has_uvs) face_uv.resize(w);
      face_source.resize(w);
    }
  }
  if (faces.empty()) fail("mesh has no faces left after removing degenerate and duplicate faces");
  const int nf = static_cast<int>(faces.size());

  // ---- Gluing: manifold edges directly, non-manifold edges by pairing ----
  std::vector<int> mate(3 * static_cast<std::size_t>(nf), -1);
  {
    const EdgeGroups edges = group_edges(3 * nf, nv, [&](int c) { return faces[c / 3][c % 3]; });
    // Non-manifold vertices as Topology defines them: faces around v joined through any edge
    // at v, however many faces that edge has, form more than one fan.
    UnionFind fans(3 * static_cast<std::size_t>(nf));
    for (std::size_t e = 0; e + 1 < edges.start.size(); ++e) {
      const int* he = edges.order.data() + edges.start[e];
      const int count = edges.start[e + 1] - edges.start[e];
      for (int i = 1; i < count; ++i) {
        const int x = he[0], y = he[i];
        const int va = faces[x / 3][x % 3], vb = faces[x / 3][(x % 3 + 1) % 3];
        fans.unite(x, corner_at(faces, y / 3, y % 3, va));
        fans.unite(x - x % 3 + (x % 3 + 1) % 3, corner_at(faces, y / 3, y % 3, vb));
      }
      if (count == 2) {
        mate[he[0]] = he[1];
        mate[he[1]] = he[0];
      } else if (count > 2) {
        ++report.nonmanifold_edges;
        if (!repair) {
          const int h = he[0];
          const int a = faces[h / 3][h % 3], b = faces[h / 3][(h % 3 + 1) % 3];
          need_repair("edge (" + std::to_string(std::min(a, b)) + "," + std::to_string(std::max(a, b)) +
                      ") has " + std::to_string(count) + " faces");
        }
        pair_around_edge(he, count, faces, raw.positions, mate);
      }
    }
    std::vector<int> first_fan(nv, -1);
    std::vector<char> counted(nv, 0);
    for (int c = 0; c < 3 * nf; ++c) {
      const int v = faces[c / 3][c % 3], r = fans.find(c);
      if (first_fan[v] < 0) {
        first_fan[v] = r;
      } else if (first_fan[v] != r && !counted[v]) {
        counted[v] = 1;
        ++report.nonmanifold_vertices;
        if (!repair) need_repair("vertex " + std::to_string(v) + " joins several separate fans of faces");
      }
    }
  }

  // ---- Orientation: BFS over glued edges; a conflict means non-orientable, cut there ----
  // A glued pair is consistent when the two faces run the shared edge in opposite directions.
  auto direction = [&](int h) { return faces[h / 3][h % 3] < faces[h / 3][(h % 3 + 1) % 3] ? 1 : -1; };
  std::vector<signed char> orient(nf, 0);
  std::vector<int> component(nf, -1);
  int num_components = 0;
  int first_conflict = -1;
  {
    std::vector<int> queue;
    queue.reserve(nf);
    for (int seed = 0; seed < nf; ++seed) {
      if (orient[seed] != 0) continue;
      orient[seed] = 1;
      component[seed] = num_components;
      queue.assign(1, seed);
      for (std::size_t qi = 0; qi < queue.size(); ++qi) {
        const int f = queue[qi];
        for (int k = 0; k < 3; ++k) {
          const int h = 3 * f + k, h2 = mate[h];
          if (h2 < 0) continue;
          const int g = h2 / 3;
          const signed char want = static_cast<signed char>(-orient[f] * direction(h) * direction(h2));
          if (orient[g] == 0) {
            orient[g] = want;
            component[g] = num_components;
            queue.push_back(g);
          } else if (orient[g] != want) {
            if (first_conflict < 0) first_conflict = f;
            mate[h] = mate[h2] = -1;
            ++report.cut_edges;
          }
        }
      }
      ++num_components;
    }
  }
  if (!repair && report.cut_edges > 0)
    need_repair("the surface through face " + std::to_string(face_source[first_conflict]) +
                " is not orientable (it would have to be cut open)");

  // Per component: closed ones face outward (positive signed volume), open ones keep the
  // orientation most of their faces already have. `turn` is -1 for a component flipped as a
  // whole: its file had "outward" backwards, normals included.
  std::vector<signed char> turn;
  {
    std::vector<double> volume(num_components, 0.0);
    std::vector<int> flipped(num_components, 0), size(num_components, 0), origin(num_components, -1);
    std::vector<char> open(num_components, 0);
    for (int f = 0; f < nf; ++f) {
      const int c = component[f];
      if (origin[c] < 0) origin[c] = faces[f][0];
      // Relative to a point of the component, for accuracy far from the origin.
      const Vec3d o = raw.positions[origin[c]];
      const Vec3d a = raw.positions[faces[f][0]] - o, b = raw.positions[faces[f][1]] - o,
                  d = raw.positions[faces[f][2]] - o;
      volume[c] += orient[f] * dot(a, cross(b, d));
      flipped[c] += orient[f] < 0 ? 1 : 0;
      ++size[c];
      for (int k = 0; k < 3; ++k) open[c] |= mate[3 * f + k] < 0 ? 1 : 0;
    }
    turn.assign(num_components, 1);
    for (int c = 0; c < num_components; ++c)
      if (open[c] ? 2 * flipped[c] > size[c] : volume[c] < 0) turn[c] = -1;
    for (int f = 0; f < nf; ++f) {
      orient[f] = static_cast<signed char>(orient[f] * turn[component[f]]);
      if (orient[f] < 0) {
        ++report.reoriented_faces;
        if (!repair)
          need_repair(open[component[f]] || flipped[component[f]] > 0
                          ? "face " + std::to_string(face_source[f]) +
                                " is oriented inconsistently with its neighbours"
                          : "the closed surface through face " + std::to_string(face_source[f]) +
                                " is oriented inward (negative volume)");
      }
    }
  }

  // ---- Vertex splitting: one output vertex per fan ----
  // Fans are unions of corners across glued edges. Where two faces share both ends of an
  // edge without being glued (possible after pairing or cutting around a vertex whose link
  // passes that edge twice), the vertex's fan is cut further until no such edge remains.
  std::vector<int> corner_vertex(3 * static_cast<std::size_t>(nf));
  std::vector<int> origin_of_new;  // input vertex of each vertex past nv
  std::vector<int> parent_edge;    // fan walk: half-edge that reached a corner; -2 unvisited
  for (;;) {
    UnionFind uf = corner_classes(faces, mate);
    std::vector<int> class_vertex(3 * static_cast<std::size_t>(nf), -1);
    std::vector<char> taken(nv, 0);
    origin_of_new.clear();
    for (int c = 0; c < 3 * nf; ++c) {
      const int r = uf.find(c);
      if (class_vertex[r] < 0) {
        const int v = faces[c / 3][c % 3];
        if (!taken[v]) {
          taken[v] = 1;
          class_vertex[r] = v;
        } else {
          class_vertex[r] = nv + static_cast<int>(origin_of_new.size());
          origin_of_new.push_back(v);
        }
      }
      corner_vertex[c] = class_vertex[r];
    }
    if (report.nonmanifold_edges == 0 && report.nonmanifold_vertices == 0 && report.cut_edges == 0) break;

    const int num_out = nv + static_cast<int>(origin_of_new.size());
    const EdgeGroups edges = group_edges(3 * nf, num_out, [&](int c) { return corner_vertex[c]; });
    std::vector<std::pair<int, int>> clashes;  // half-edges on one output edge, not glued
    for (std::size_t e = 0; e + 1 < edges.start.size(); ++e) {
      const int* he = edges.order.data() + edges.start[e];
      const int count = edges.start[e + 1] - edges.start[e];
      for (int q = 1; q < count; ++q)
        if (mate[he[0]] != he[q]) {
          clashes.emplace_back(he[0], he[q]);
          break;
        }
    }
    if (clashes.empty()) break;
    if (parent_edge.empty()) parent_edge.assign(3 * static_cast<std::size_t>(nf), -2);
    int cuts = 0;
    for (const auto& [h1, h2] : clashes) {
      // Both faces have a corner at the output vertex x where h1 starts: walk x's fan from
      // h1's corner to the other face's corner and cut the middle edge of that walk.
      const int x = corner_vertex[h1];
      const int v = faces[h1 / 3][h1 % 3];
      const int goal_face = h2 / 3;
      std::vector<int> bfs = {h1};
      parent_edge[h1] = -1;
      int goal = -1;
      for (std::size_t qi = 0; qi < bfs.size(); ++qi) {
        const int c = bfs[qi];
        if (c / 3 == goal_face) {
          goal = c;
          break;
        }
        const int f = c / 3, k = c % 3;
        for (const int h : {3 * f + k, 3 * f + (k + 2) % 3}) {
          const int m2 = mate[h];
          if (m2 < 0) continue;
          const int nc = corner_at(faces, m2 / 3, m2 % 3, v);
          if (corner_vertex[nc] != x || parent_edge[nc] != -2) continue;
          parent_edge[nc] = h;
          bfs.push_back(nc);
        }
      }
      std::vector<int> path;
      for (int c = goal; c >= 0 && parent_edge[c] >= 0;) {
        const int h = parent_edge[c];
        path.push_back(h);
        c = corner_at(faces, h / 3, h % 3, v);
      }
      for (int c : bfs) parent_edge[c] = -2;
      // No path: a cut made earlier in this round already separated the two faces.
      if (path.empty()) continue;
      const int cut = path[path.size() / 2];
      mate[mate[cut]] = -1;
      mate[cut] = -1;
      ++report.cut_edges;
      ++cuts;
    }
    // A fresh round always reaches its first clash, so every round cuts; this only guards
    // against looping forever should that reasoning ever break.
    if (cuts == 0) throw Error("internal: vertex splitting made no progress");
  }

  // ---- Output: flip, drop unreferenced vertices, carry attributes ----
  const int total = nv + static_cast<int>(origin_of_new.size());
  std::vector<int> remap(total, -1);
  for (int c = 0; c < 3 * nf; ++c) remap[corner_vertex[c]] = 0;
  for (int v = 0; v < nv; ++v)
    if (remap[v] < 0) ++report.unreferenced_vertices;
  if (!repair && report.unreferenced_vertices > 0) {
    int v = 0;
    while (remap[v] >= 0) ++v;
    need_repair("vertex " + std::to_string(v) + " is used by no face");
  }
  Mesh m;
  auto source_vertex = [&](int v) { return v < nv ? v : origin_of_new[v - nv]; };
  for (int v = 0; v < total; ++v) {
    if (remap[v] < 0) continue;
    remap[v] = m.num_vertices();
    const int s = source_vertex(v);
    m.positions.push_back(raw.positions[s]);
    if (has_normals) m.normals.push_back(raw.normals[s]);
    if (has_colors) m.colors.push_back(raw.colors[s]);
  }
  m.faces.resize(nf);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) m.faces[f][k] = remap[corner_vertex[3 * f + k]];
    if (orient[f] < 0) std::swap(m.faces[f][1], m.faces[f][2]);
  }
  if (has_normals) {
    // An output vertex lies in one component, so its normal flips with that component.
    std::vector<char> negate(m.positions.size(), 0);
    for (int f = 0; f < nf; ++f)
      if (turn[component[f]] < 0)
        for (int k = 0; k < 3; ++k) negate[m.faces[f][k]] = 1;
    for (std::size_t v = 0; v < negate.size(); ++v)
      if (negate[v]) m.normals[v] = -m.normals[v];
  }
  if (has_uvs) {
    std::vector<int> uv_remap(raw.uvs.size(), -1);
    for (const Face& t : face_uv)
      for (int i : t) uv_remap[i] = 0;
    for (std::size_t t = 0; t < raw.uvs.size(); ++t)
      if (uv_remap[t] == 0) {
        uv_remap[t] = static_cast<int>(m.uvs.size());
        m.uvs.push_back(raw.uvs[t]);
      }
    m.face_uvs.resize(nf);
    for (int f = 0; f < nf; ++f) {
      for (int k = 0; k < 3; ++k) m.face_uvs[f][k] = uv_remap[face_uv[f][k]];
      if (orient[f] < 0) std::swap(m.face_uvs[f][1], m.face_uvs[f][2]);
    }
  }
  if (has_groups) {
    m.face_groups.resize(nf);
    for (int f = 0; f < nf; ++f) m.face_groups[f] = raw.polygon_groups[face_source[f]];
  }
  if (has_materials) {
    m.face_materials.resize(nf);
    for (int f = 0; f < nf; ++f) m.face_materials[f] = raw.polygon_materials[face_source[f]];
    m.material_names = raw.material_names;
  }
  {
    UnionFind uf(nf);
    for (int h = 0; h < 3 * nf; ++h)
      if (mate[h] >= 0) uf.unite(h / 3, mate[h] / 3);
    for (int f = 0; f < nf; ++f) report.components += uf.find(f) == f ? 1 : 0;
  }

  auto& w = report.warnings;
  auto count = [](int n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
  };
  if (report.polygons > 0)
    w.push_back("triangulated " + count(report.polygons, "polygon", "polygons") + " into " +
                count(triangles_from_polygons, "triangle", "triangles"));
  if (report.degenerate_faces > 0)
    w.push_back("removed " + count(report.degenerate_faces, "degenerate face", "degenerate faces") +
                " (repeated vertex or zero area)");
  if (report.duplicate_faces > 0)
    w.push_back("removed " + count(report.duplicate_faces, "duplicate face", "duplicate faces"));
  if (report.nonmanifold_edges > 0)
    w.push_back("split " + count(report.nonmanifold_edges, "non-manifold edge", "non-manifold edges") +
                " (more than two faces)");
  if (report.nonmanifold_vertices > 0)
    w.push_back("split " +
                count(report.nonmanifold_vertices, "non-manifold vertex", "non-manifold vertices") +
                " (several fans of faces)");
  if (report.cut_edges > 0)
    w.push_back("cut " + count(report.cut_edges, "edge", "edges") +
                " open where no consistent orientation exists");
  if (report.reoriented_faces > 0)
    w.push_back("reoriented " + count(report.reoriented_faces, "face", "faces") +
                " for a consistent, outward orientation");
  if (report.unreferenced_vertices > 0)
    w.push_back("dropped " +
                count(report.unreferenced_vertices, "unreferenced vertex", "unreferenced vertices"));
  return m;
}

}  // namespace isochart
