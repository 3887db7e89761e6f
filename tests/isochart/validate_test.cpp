#include "isochart/validate.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <set>

#include "isochart/error.h"
#include "isochart/io_test_util.h"

using namespace isochart;
using io_test::signed_volume;

namespace {

RawMesh raw_of(std::vector<Vec3d> positions, std::vector<std::vector<int>> polygons) {
  RawMesh r;
  r.source = "test.obj";
  r.positions = std::move(positions);
  r.polygons = std::move(polygons);
  return r;
}

// Unit tetrahedron, outward.
RawMesh tetrahedron() {
  return raw_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

// Unit cube as six outward quads; vertex i = (i & 1, (i >> 1) & 1, (i >> 2) & 1).
RawMesh cube_quads() {
  std::vector<Vec3d> p;
  for (int i = 0; i < 8; ++i) p.push_back({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
  return raw_of(p, {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}});
}

RawMesh cube_triangles() {
  RawMesh r = cube_quads();
  std::vector<std::vector<int>> tris;
  for (const auto& q : r.polygons) {
    tris.push_back({q[0], q[1], q[2]});
    tris.push_back({q[0], q[2], q[3]});
  }
  r.polygons = tris;
  return r;
}

bool has_degenerate_or_duplicate(const Mesh& m) {
  std::set<std::array<int, 3>> seen;
  for (const auto& f : m.faces) {
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) return true;
    if (triangle_area(m.positions[f[0]], m.positions[f[1]], m.positions[f[2]]) == 0) return true;
    std::array<int, 3> s = f;
    std::sort(s.begin(), s.end());
    if (!seen.insert(s).second) return true;
  }
  return false;
}

// What every repaired mesh must be.
void check_clean(const Mesh& m) {
  const Topology t(m);
  CHECK(t.nonmanifold_edges().empty());
  CHECK(t.nonmanifold_vertices().empty());
  CHECK(io_test::consistently_oriented(m, t));
  CHECK_FALSE(has_degenerate_or_duplicate(m));
  CHECK(t.num_referenced_vertices() == m.num_vertices());
}

Mesh validate(const RawMesh& r, ValidationReport& rep, bool repair = true) {
  return validate_mesh(r, repair, rep);
}

std::string error_of(const RawMesh& r, bool repair) {
  ValidationReport rep;
  try {
    validate_mesh(r, repair, rep);
  } catch (const InputError& e) {
    CHECK(e.file() == r.source);
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("a clean mesh passes unchanged", "[validate]") {
  ValidationReport rep;
  const RawMesh r = tetrahedron();
  const Mesh m = validate(r, rep, false);
  CHECK(m.positions == r.positions);
  REQUIRE(m.num_faces() == 4);
  for (int f = 0; f < 4; ++f) CHECK(m.faces[f] == Face{r.polygons[f][0], r.polygons[f][1], r.polygons[f][2]});
  CHECK(rep.warnings.empty());
  CHECK(rep.input_vertices == 4);
  CHECK(rep.input_faces == 4);
  CHECK(rep.components == 1);
  CHECK(rep.reoriented_faces == 0);
}

TEST_CASE("unrecoverable input is an InputError naming the element", "[validate]") {
  CHECK_THAT(error_of(raw_of({}, {}), true), Catch::Contains("no vertices"));
  CHECK_THAT(error_of(raw_of({{0, 0, 0}}, {}), true), Catch::Contains("no faces"));
  RawMesh nan = tetrahedron();
  nan.positions[2].y = std::nan("");
  CHECK_THAT(error_of(nan, true), Catch::Contains("vertex 2") && Catch::Contains("non-finite"));
  RawMesh inf = tetrahedron();
  inf.normals.assign(4, {0, 0, 1});
  inf.normals[3].z = INFINITY;
  CHECK_THAT(error_of(inf, true), Catch::Contains("vertex 3") && Catch::Contains("normal"));
  // Finite but beyond what areas and squared distances can hold, or too small to have any.
  RawMesh huge = tetrahedron();
  huge.positions[1].x = 1e200;
  CHECK_THAT(error_of(huge, true), Catch::Contains("vertex 1") && Catch::Contains("beyond"));
  RawMesh tiny = tetrahedron();
  for (auto& p : tiny.positions) p = p * 1e-300;
  CHECK_THAT(error_of(tiny, true), Catch::Contains("too small"));
  // A mesh whose coordinates cannot resolve its shape: 1e-14 across, 1 from the origin (its
  // vertices on a grid of about 50 steps). 1e-6 across at 1 is fine.
  RawMesh coarse = tetrahedron();
  for (auto& p : coarse.positions) p = p * 1e-14 + Vec3d{1, 0, 0};
  CHECK_THAT(error_of(coarse, true), Catch::Contains("from the origin") && Catch::Contains("too coarse"));
  RawMesh offset = tetrahedron();
  for (auto& p : offset.positions) p = p * 1e-6 + Vec3d{1, 0, 0};
  ValidationReport offset_report;
  CHECK(validate(offset, offset_report).num_faces() == 4);
  RawMesh small = tetrahedron();  // a micrometre-sized part in metres is fine
  for (auto& p : small.positions) p = p * 1e-6;
  ValidationReport rep;
  CHECK(validate(small, rep).num_faces() == 4);
  RawMesh range = tetrahedron();
  range.polygons[1][2] = 4;
  CHECK_THAT(error_of(range, true), Catch::Contains("face 1 refers to vertex 4"));
  RawMesh negative = tetrahedron();
  negative.polygons[3][0] = -1;
  CHECK_THAT(error_of(negative, true), Catch::Contains("face 3 refers to vertex -1"));
  RawMesh two = tetrahedron();
  two.polygons[2] = {0, 1};
  CHECK_THAT(error_of(two, true), Catch::Contains("face 2 has 2 corners"));
  RawMesh uv = tetrahedron();
  uv.uvs = {{0, 0}, {1, 0}};
  uv.polygon_uvs.assign(4, {0, 1, 2});
  CHECK_THAT(error_of(uv, true), Catch::Contains("texture coordinate 2"));
  RawMesh far_uv = tetrahedron();  // stretch of such UVs overflowed to NaN in `stats`
  far_uv.uvs = {{0, 0}, {1e300, 0}, {0, 1}};
  far_uv.polygon_uvs.assign(4, {0, 1, 2});
  CHECK_THAT(error_of(far_uv, true), Catch::Contains("texture coordinate 1 is beyond"));
  RawMesh all_degenerate = raw_of({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}, {{0, 1, 2}, {0, 1, 1}});
  CHECK_THAT(error_of(all_degenerate, true), Catch::Contains("no faces left"));
}

TEST_CASE("polygons are triangulated without flips or lost area", "[validate]") {
  // A non-convex L-shaped hexagon in a tilted plane, and a square with a vertex in the
  // middle of one side (a collinear corner must still be used, not create a T-junction).
  const double s = std::sqrt(0.5);
  auto tilt = [&](double x, double y) { return Vec3d{x, y * s, y * s}; };
  RawMesh r = raw_of({tilt(0, 0),
                      tilt(2, 0),
                      tilt(2, 1),
                      tilt(1, 1),
                      tilt(1, 2),
                      tilt(0, 2),
                      {5, 0, 0},
                      {6, 0, 0},
                      {7, 0, 0},
                      {7, 1, 0},
                      {5, 1, 0}},
                     {{0, 1, 2, 3, 4, 5}, {6, 7, 8, 9, 10}});
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  CHECK(rep.polygons == 2);
  REQUIRE(m.num_faces() == 4 + 3);
  CHECK(rep.degenerate_faces == 0);
  const Vec3d n_l = normalized(cross(tilt(1, 0) - tilt(0, 0), tilt(0, 1) - tilt(0, 0)));
  double area_l = 0, area_sq = 0;
  std::set<int> used;
  for (const auto& f : m.faces) {
    const Vec3d n = cross(m.positions[f[1]] - m.positions[f[0]], m.positions[f[2]] - m.positions[f[0]]);
    const bool in_l = m.positions[f[0]].x < 4;
    CHECK(dot(n, in_l ? n_l : Vec3d{0, 0, 1}) > 0);  // same side as the polygon: no flipped triangle
    (in_l ? area_l : area_sq) += norm(n) / 2;
    for (int v : f) used.insert(v);
  }
  CHECK(area_l == Approx(3.0));
  CHECK(area_sq == Approx(2.0));
  CHECK(used.size() == 11);  // the collinear corner (6, 0, 0) is a vertex of some triangle
  check_clean(m);
  REQUIRE(rep.warnings.size() == 1);
  CHECK_THAT(rep.warnings[0], Catch::Contains("triangulated 2 polygons into 7 triangles"));
  CHECK_THAT(error_of(r, false), Catch::Contains("face 0 has 6 corners") &&
                                     Catch::Contains("it needs repair, which is turned off (--no-repair)"));
}

TEST_CASE("a large concave polygon is triangulated without flips", "[validate]") {
  // Beyond ear clipping's size (2,000 corners) a constrained Delaunay triangulation takes
  // over: a fan of this star turned half its triangles over, on top of the others.
  const int n = 4000;
  std::vector<Vec3d> pos;
  std::vector<int> poly;
  double area = 0;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n, r = i % 2 == 0 ? 1.0 : 0.5;
    pos.push_back({r * std::cos(a), r * std::sin(a), 0});
    poly.push_back(i);
  }
  for (int i = 0; i < n; ++i) area += 0.5 * (pos[i].x * pos[(i + 1) % n].y - pos[(i + 1) % n].x * pos[i].y);
  ValidationReport rep;
  const Mesh m = validate(raw_of(pos, {poly}), rep);
  REQUIRE(m.num_faces() == n - 2);
  double sum = 0;
  int flipped = 0;
  for (const auto& f : m.faces) {
    const double z = cross(m.positions[f[1]] - m.positions[f[0]], m.positions[f[2]] - m.positions[f[0]]).z;
    flipped += z <= 0 ? 1 : 0;
    sum += z / 2;
  }
  CHECK(flipped == 0);
  CHECK(sum == Approx(area).epsilon(1e-12));
  check_clean(m);
  // A large polygon whose edges cross cannot be triangulated inside: it is fanned, as before.
  std::swap(poly[10], poly[2000]);
  ValidationReport rep2;
  CHECK(validate(raw_of(pos, {poly}), rep2).num_faces() > 0);
}

TEST_CASE("a quad mesh triangulates into the closed cube", "[validate]") {
  ValidationReport rep;
  const Mesh m = validate(cube_quads(), rep);
  CHECK(m.num_faces() == 12);
  CHECK(signed_volume(m) == Approx(1.0));
  check_clean(m);
  const Topology t(m);
  CHECK(t.boundary_loops().empty());
  CHECK(t.genus() == 0);
}

TEST_CASE("degenerate faces are found exactly and removed", "[validate]") {
  ValidationReport rep;
  // Exactly collinear in floating point: the third point is three times the second.
  RawMesh line = raw_of({{0, 0, 0}, {0.25, 0.5, 0.75}, {0.75, 1.5, 2.25}, {0, 0, 1}}, {{0, 1, 2}, {1, 0, 3}});
  Mesh m = validate(line, rep);
  CHECK(rep.degenerate_faces == 1);
  CHECK(m.num_faces() == 1);
  CHECK_THAT(error_of(line, false), Catch::Contains("face 0 is degenerate (zero area)"));
  // Flat to double precision (height below 1e-15 of the longest side; no packed layout can
  // keep its shape): degenerate too. A sliver 1e-10 high is a triangle.
  RawMesh flat = raw_of({{0, 0, 0}, {1, 0, 0}, {2, 1e-300, 0}, {0, 0, 1}}, {{0, 1, 2}, {1, 0, 3}});
  m = validate(flat, rep);
  CHECK(rep.degenerate_faces == 1);
  CHECK(m.num_faces() == 1);
  CHECK_THAT(error_of(flat, false), Catch::Contains("face 0 is degenerate (zero area)"));
  RawMesh thin = raw_of({{0, 0, 0}, {1, 0, 0}, {0.5, 1e-10, 0}}, {{0, 1, 2}});
  m = validate(thin, rep);
  CHECK(rep.degenerate_faces == 0);
  CHECK(m.num_faces() == 1);
  RawMesh rep_vertex = raw_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 1, 1}});
  CHECK_THAT(error_of(rep_vertex, false), Catch::Contains("face 1 is degenerate (it repeats a vertex)"));
  m = validate(rep_vertex, rep);
  CHECK(rep.degenerate_faces == 1);
  CHECK(m.num_faces() == 1);
  // A polygon of one vertex repeated is degenerate, not also "triangulated into 0 triangles".
  RawMesh one_corner = raw_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {1, 1, 1, 1, 1}});
  m = validate(one_corner, rep);
  CHECK(rep.degenerate_faces == 1);
  CHECK(rep.polygons == 0);
  CHECK(m.num_faces() == 1);
}

TEST_CASE("duplicate faces are removed whatever their corner order", "[validate]") {
  RawMesh r = tetrahedron();
  r.polygons.push_back({2, 1, 0});  // reversed copy of face 0 (0, 2, 1)
  r.polygons.push_back({3, 0, 1});  // rotated copy of face 1
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  CHECK(rep.duplicate_faces == 2);
  CHECK(m.num_faces() == 4);
  check_clean(m);
  CHECK_THAT(error_of(r, false), Catch::Contains("face 4 has the same vertices as face 0"));
}

TEST_CASE("a double-sided sheet keeps both sides, each a sheet of its own", "[validate]") {
  // Every face again, reversed, on the same vertices: the duplicate test removed the back.
  const std::vector<Vec3d> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.2}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0.1}};
  for (const bool quads : {false, true}) {
    INFO((quads ? "quads" : "triangles"));
    std::vector<std::vector<int>> front =
        quads ? std::vector<std::vector<int>>{{0, 1, 2, 3}, {1, 4, 5, 2}}
              : std::vector<std::vector<int>>{{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2}};
    std::vector<std::vector<int>> polys = front;
    for (auto f : front) {
      std::reverse(f.begin(), f.end());
      polys.push_back(f);
    }
    RawMesh r = raw_of(p, polys);
    r.normals = p;
    ValidationReport rep;
    const Mesh m = validate(r, rep);
    CHECK(rep.double_sided_faces == static_cast<int>(front.size()));
    CHECK(rep.duplicate_faces == 0);
    CHECK(rep.input_vertices == 6);
    CHECK(m.num_faces() == 8);
    CHECK(m.num_vertices() == 12);  // the back's own copies, at the same places
    CHECK(rep.components == 2);
    check_clean(m);
    const Topology t(m);
    int boundary = 0;
    for (int e = 0; e < t.num_edges(); ++e) boundary += t.is_boundary_edge(e);
    CHECK(boundary == 12);  // each side keeps its rim of 6 edges
    // The two sides face away from each other.
    auto normal = [&](int f) {
      const Face& x = m.faces[f];
      return cross(m.positions[x[1]] - m.positions[x[0]], m.positions[x[2]] - m.positions[x[0]]);
    };
    int up = 0, down = 0;
    for (int f = 0; f < m.num_faces(); ++f) (normal(f).z > 0 ? up : down)++;
    CHECK(up == 4);
    CHECK(down == 4);
    bool warned = false;
    for (const auto& w : rep.warnings) warned |= w.find("double-sided sheet") != std::string::npos;
    CHECK(warned);
  }
  // A reversed copy of one face of a closed surface is junk, not a second side.
  RawMesh t = tetrahedron();
  t.polygons.push_back({2, 1, 0});
  ValidationReport rep;
  CHECK(validate(t, rep).num_faces() == 4);
  CHECK(rep.double_sided_faces == 0);
  CHECK(rep.duplicate_faces == 1);
}

TEST_CASE("unreferenced vertices are dropped and attributes remapped", "[validate]") {
  RawMesh r = raw_of({{9, 9, 9}, {0, 0, 0}, {8, 8, 8}, {1, 0, 0}, {0, 1, 0}}, {{1, 3, 4}});
  r.normals = {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 0, 1}, {0, 0, 1}};
  r.colors = {{1, 1, 1}, {0.1, 0, 0}, {1, 1, 1}, {0.3, 0, 0}, {0.4, 0, 0}};
  r.uvs = {{0, 0}, {0.5, 0.5}, {1, 0}, {0, 1}};
  r.polygon_uvs = {{0, 2, 3}};
  r.polygon_groups = {7};
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  CHECK(rep.unreferenced_vertices == 2);
  REQUIRE(m.num_vertices() == 3);
  CHECK(m.positions[m.faces[0][0]] == Vec3d{0, 0, 0});
  CHECK(m.positions[m.faces[0][1]] == Vec3d{1, 0, 0});
  CHECK(m.colors[m.faces[0][1]].x == 0.3);
  CHECK(m.normals[m.faces[0][2]] == Vec3d{0, 0, 1});
  REQUIRE(m.uvs.size() == 3);  // the unused (0.5, 0.5) is dropped too
  CHECK(m.uvs[m.face_uvs[0][1]] == Vec2d{1, 0});
  CHECK(m.face_groups == std::vector<int>{7});
  CHECK_THAT(error_of(r, false), Catch::Contains("vertex 0 is used by no face") &&
                                     Catch::Contains("it needs repair, which is turned off (--no-repair)"));
}

TEST_CASE("two closed surfaces touching along an edge are split apart, both closed", "[validate]") {
  // Tetrahedron A and its copy rotated 180 degrees about the x axis share edge (0, 1).
  RawMesh r = tetrahedron();
  r.positions.push_back({0, -1, 0});
  r.positions.push_back({0, 0, -1});
  for (const auto& f : std::vector<std::vector<int>>{{0, 4, 1}, {0, 1, 5}, {0, 5, 4}, {1, 4, 5}})
    r.polygons.push_back(f);
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  CHECK(rep.nonmanifold_edges == 1);
  CHECK(m.num_faces() == 8);
  CHECK(m.num_vertices() == 8);
  CHECK(rep.components == 2);
  check_clean(m);
  const Topology t(m);
  CHECK(t.num_components() == 2);
  CHECK(t.boundary_loops().empty());  // both stay closed
  CHECK(t.genus() == 0);
  CHECK(signed_volume(m) == Approx(2.0 / 6));
  CHECK_THAT(error_of(r, false), Catch::Contains("edge (0,1) has 4 faces") &&
                                     Catch::Contains("it needs repair, which is turned off (--no-repair)"));
}

TEST_CASE("a fin on an edge is separated into a manifold", "[validate]") {
  RawMesh r =
      raw_of({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}}, {{0, 1, 2}, {0, 2, 3}, {0, 2, 4}});
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  CHECK(rep.nonmanifold_edges == 1);
  CHECK(m.num_faces() == 3);
  check_clean(m);
}

TEST_CASE("two solids sharing one vertex are split at it", "[validate]") {
  RawMesh r = tetrahedron();
  // The point reflection of A (mirror: windings reversed to stay outward).
  r.positions.push_back({-1, 0, 0});
  r.positions.push_back({0, -1, 0});
  r.positions.push_back({0, 0, -1});
  for (const auto& f : std::vector<std::vector<int>>{{0, 4, 5}, {0, 6, 4}, {0, 5, 6}, {4, 6, 5}})
    r.polygons.push_back(f);
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  CHECK(rep.nonmanifold_vertices == 1);
  CHECK(rep.nonmanifold_edges == 0);
  CHECK(m.num_vertices() == 8);
  CHECK(rep.components == 2);
  CHECK(signed_volume(m) == Approx(2.0 / 6));
  check_clean(m);
  CHECK_THAT(error_of(r, false), Catch::Contains("vertex 0 joins several separate fans"));
}

TEST_CASE("orientation is made consistent and outward", "[validate]") {
  RawMesh r = cube_triangles();
  for (int f : {1, 4, 9}) std::swap(r.polygons[f][1], r.polygons[f][2]);
  ValidationReport rep;
  Mesh m = validate(r, rep);
  CHECK(rep.reoriented_faces == 3);
  CHECK(signed_volume(m) == Approx(1.0));
  check_clean(m);
  CHECK_THAT(error_of(r, false), Catch::Contains("oriented inconsistently") &&
                                     Catch::Contains("it needs repair, which is turned off (--no-repair)"));

  // Inside out as a whole: every face flips, and the normals with them.
  RawMesh inside = cube_triangles();
  for (auto& p : inside.polygons) std::swap(p[1], p[2]);
  for (const auto& p : inside.positions) inside.normals.push_back(normalized(Vec3d{0.5, 0.5, 0.5} - p));
  inside.uvs = {{0, 0}, {1, 0}, {0, 1}};
  inside.polygon_uvs.assign(inside.polygons.size(), {0, 1, 2});
  m = validate(inside, rep);
  CHECK(rep.reoriented_faces == 12);
  CHECK(signed_volume(m) == Approx(1.0));
  for (int v = 0; v < m.num_vertices(); ++v)
    CHECK(dot(m.normals[v], m.positions[v] - Vec3d{0.5, 0.5, 0.5}) > 0);
  // UVs follow their corners through the flip.
  for (int f = 0; f < m.num_faces(); ++f) CHECK(m.uvs[m.face_uvs[f][1]] == Vec2d{0, 1});
  CHECK_THAT(error_of(inside, false), Catch::Contains("oriented inward"));
}

TEST_CASE("an open surface keeps the orientation of most of its faces", "[validate]") {
  // A 3 x 3 grid of quads, 18 triangles, two of them flipped.
  std::vector<Vec3d> p;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) p.push_back({double(x), double(y), 0.1 * x * y});
  std::vector<std::vector<int>> tris;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const int a = 4 * y + x;
      tris.push_back({a, a + 1, a + 5});
      tris.push_back({a, a + 5, a + 4});
    }
  std::swap(tris[3][0], tris[3][1]);
  std::swap(tris[12][0], tris[12][1]);
  ValidationReport rep;
  const Mesh m = validate(raw_of(p, tris), rep);
  CHECK(rep.reoriented_faces == 2);
  for (const auto& f : m.faces)
    CHECK(cross(m.positions[f[1]] - m.positions[f[0]], m.positions[f[2]] - m.positions[f[0]]).z > 0);
  check_clean(m);
}

TEST_CASE("a Moebius strip is cut open into an orientable surface", "[validate]") {
  const int n = 24;
  const double pi = std::acos(-1.0);
  std::vector<Vec3d> p;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * pi * i / n;
    const Vec3d c{std::cos(t), std::sin(t), 0};
    const Vec3d w =
        Vec3d{std::cos(t) * std::cos(t / 2), std::sin(t) * std::cos(t / 2), std::sin(t / 2)} * 0.3;
    p.push_back(c + w);
    p.push_back(c - w);
  }
  std::vector<std::vector<int>> tris;
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i, b = 2 * i + 1;
    // After a full turn the half twist swaps the two sides.
    const int a2 = i + 1 < n ? 2 * (i + 1) : 1, b2 = i + 1 < n ? 2 * (i + 1) + 1 : 0;
    tris.push_back({a, b, a2});
    tris.push_back({b, b2, a2});
  }
  const RawMesh r = raw_of(p, tris);
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  CHECK(rep.cut_edges >= 1);
  CHECK(m.num_faces() == 2 * n);
  check_clean(m);
  CHECK_THAT(error_of(r, false), Catch::Contains("not orientable"));
}

TEST_CASE("random soups always come out manifold and consistently oriented", "[validate]") {
  // Many triangles over few vertices: non-manifold edges and vertices, inconsistent
  // orientation and duplicates everywhere. The repair must terminate with a clean mesh.
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> coord(-1, 1);
    std::uniform_int_distribution<int> pick(0, 29);
    std::vector<Vec3d> p(30);
    for (auto& x : p) x = {coord(rng), coord(rng), coord(rng)};
    std::vector<std::vector<int>> tris(300);
    for (auto& t : tris) t = {pick(rng), pick(rng), pick(rng)};
    RawMesh r = raw_of(p, tris);
    r.normals = p;
    ValidationReport rep;
    const Mesh m = validate(r, rep);
    INFO("seed " << seed);
    CHECK(m.num_faces() == 300 - rep.degenerate_faces - rep.duplicate_faces);
    CHECK(m.normals.size() == m.positions.size());
    check_clean(m);
    for (const auto& w : rep.warnings) CHECK(w.find('\n') == std::string::npos);
  }
}

TEST_CASE("groups and per-corner UVs survive triangulation", "[validate]") {
  RawMesh r = cube_quads();
  r.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  r.polygon_uvs.assign(6, {0, 1, 2, 3});
  r.polygon_groups = {5, 5, 6, 6, 7, 8};
  ValidationReport rep;
  const Mesh m = validate(r, rep);
  REQUIRE(m.num_faces() == 12);
  REQUIRE(m.face_uvs.size() == 12);
  for (int f = 0; f < 12; ++f) {
    const int g = m.face_groups[f];
    CHECK((g == 5 || g == 6 || g == 7 || g == 8));
    // The UV triangle keeps the orientation of the 3D one (both counter-clockwise).
    CHECK(signed_area(m.uvs[m.face_uvs[f][0]], m.uvs[m.face_uvs[f][1]], m.uvs[m.face_uvs[f][2]]) > 0);
  }
  CHECK(std::count(m.face_groups.begin(), m.face_groups.end(), 5) == 4);
}

TEST_CASE("to_raw_mesh round-trips through validation", "[validate]") {
  ValidationReport rep;
  const Mesh a = validate(cube_triangles(), rep);
  const Mesh b = validate_mesh(to_raw_mesh(a, "again"), false, rep);
  CHECK(b.positions == a.positions);
  CHECK(b.faces == a.faces);
}

TEST_CASE("topology of large degenerate fans: one walk per edge", "[validate]") {
  // 20,000 faces on one vertex (a UV layout whose corners all sit at one point, as faces
  // without texture coordinates get): the fan walk used to re-read the shared edge's faces
  // from every face and took minutes for a few thousand.
  std::vector<Face> faces(20000, Face{0, 0, 0});
  const Topology all(faces, 1);
  CHECK(all.num_edges() == 1);
  CHECK(all.edge_faces(0).size() == 60000);
  CHECK(all.nonmanifold_vertices() == std::vector<int>{0});  // each face holds the vertex thrice
  // A proper fan of the same size around one vertex is one fan: manifold there.
  const int n = 20000;
  std::vector<Face> fan;
  for (int i = 0; i < n; ++i) fan.push_back({0, 1 + i, 1 + (i + 1) % n});
  const Topology wheel(fan, n + 1);
  CHECK(wheel.nonmanifold_vertices().empty());
  CHECK(wheel.nonmanifold_edges().empty());
  CHECK(wheel.boundary_loops().size() == 1);  // the rim
}
