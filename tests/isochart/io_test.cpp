#include "isochart/io.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "isochart/error.h"
#include "isochart/image.h"
#include "isochart/io_test_util.h"

using namespace isochart;
using namespace io_test;

namespace {

std::string load_error(const std::string& path, const LoadOptions& o = {}) {
  try {
    load_mesh(path, o);
  } catch (const InputError& e) {
    CHECK(e.file() == path);
    return e.what();
  }
  return "";
}

// A GLB container around a JSON document and a binary chunk.
std::string glb_container(const std::string& json_text, std::string bin) {
  std::string j = json_text;
  while (j.size() % 4) j += ' ';
  while (bin.size() % 4) bin += '\0';
  Bytes b;
  b.put<std::uint32_t>(0x46546C67)
      .put<std::uint32_t>(2)
      .put<std::uint32_t>(static_cast<std::uint32_t>(12 + 8 + j.size() + 8 + bin.size()));
  b.put<std::uint32_t>(static_cast<std::uint32_t>(j.size())).put<std::uint32_t>(0x4E4F534A);
  b.data += j;
  b.put<std::uint32_t>(static_cast<std::uint32_t>(bin.size())).put<std::uint32_t>(0x004E4942);
  b.data += bin;
  return b.data;
}

// The closed cube with every attribute: per-vertex normals and colours, one UV chart per
// side (seams on every cube edge) and one group per side.
Mesh attributed_cube() {
  std::vector<Vec3d> p;
  for (int i = 0; i < 8; ++i) p.push_back({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  Mesh m;
  m.positions = p;
  for (int q = 0; q < 6; ++q) {
    const int base = static_cast<int>(m.uvs.size());
    const double u0 = 0.1 + 0.15 * q;
    m.uvs.push_back({u0, 0.1});
    m.uvs.push_back({u0 + 0.1, 0.1});
    m.uvs.push_back({u0 + 0.1, 0.3});
    m.uvs.push_back({u0, 0.3});
    m.faces.push_back({quads[q][0], quads[q][1], quads[q][2]});
    m.faces.push_back({quads[q][0], quads[q][2], quads[q][3]});
    m.face_uvs.push_back({base, base + 1, base + 2});
    m.face_uvs.push_back({base, base + 2, base + 3});
    m.face_groups.push_back(q);
    m.face_groups.push_back(q);
  }
  for (const auto& x : p) {
    m.normals.push_back(normalized(x - Vec3d{0.5, 0.5, 0.5}));
    m.colors.push_back({x.x * 0.8 + 0.1, x.y * 0.6, 0.3 + 0.2 * x.z});
  }
  return m;
}

// Per corner, the two meshes have the same position, UV, normal and colour (within `tol`),
// and the same face groups.
void check_same_corners(const Mesh& a, const Mesh& b, double tol, bool groups, bool colors_uchar = false) {
  REQUIRE(a.num_faces() == b.num_faces());
  REQUIRE(b.has_uvs() == a.has_uvs());
  REQUIRE(b.has_normals() == a.has_normals());
  REQUIRE(b.has_colors() == a.has_colors());
  const double ctol = colors_uchar ? 0.5 / 255 + 1e-9 : tol;
  for (int f = 0; f < a.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int va = a.faces[f][k], vb = b.faces[f][k];
      CHECK(norm(a.positions[va] - b.positions[vb]) <= tol);
      if (a.has_uvs()) CHECK(norm(a.uvs[a.face_uvs[f][k]] - b.uvs[b.face_uvs[f][k]]) <= tol);
      if (a.has_normals()) CHECK(norm(a.normals[va] - b.normals[vb]) <= tol);
      if (a.has_colors()) CHECK(norm(a.colors[va] - b.colors[vb]) <= std::sqrt(3.0) * ctol);
    }
  if (groups) CHECK(a.face_groups == b.face_groups);
}

}  // namespace

// ---- Formats and dispatch ------------------------------------------------------------------

TEST_CASE("format comes from the extension", "[io]") {
  CHECK(format_from_path("a/b.OBJ") == MeshFormat::Obj);
  CHECK(format_from_path("x.off") == MeshFormat::Off);
  CHECK(format_from_path("x.Ply") == MeshFormat::Ply);
  CHECK(format_from_path("x.gltf") == MeshFormat::Gltf);
  CHECK(format_from_path("x.glb") == MeshFormat::Glb);
  CHECK(format_from_path("builtin:sphere") == MeshFormat::Builtin);
  CHECK_THROWS_WITH(format_from_path("mesh.stl"), Catch::Contains("unknown mesh format '.stl'"));
  CHECK_THROWS_WITH(format_from_path("dir.v2/mesh"), Catch::Contains("no file extension"));
}

TEST_CASE("built-in meshes go through make_builtin", "[io]") {
  // An unknown name is make_builtin's InputError, whatever the built-ins are.
  CHECK_THROWS_AS(load_mesh("builtin:no_such_mesh"), InputError);
}

TEST_CASE("file-level problems are InputErrors", "[io]") {
  TempDir d;
  CHECK_THAT(load_error(d.file("missing.obj")), Catch::Contains("cannot open file"));
  fs::create_directory(d.file("dir.obj"));
  CHECK_THAT(load_error(d.file("dir.obj")), Catch::Contains("is a directory"));
  CHECK_THAT(load_error(d.write("empty.off", "")), Catch::Contains("file is empty"));
  // A device or a pipe is refused at once: /dev/zero was read until memory ran out, and
  // opening a FIFO waited for a writer.
  fs::create_symlink("/dev/zero", d.file("zero.obj"));
  CHECK_THAT(load_error(d.file("zero.obj")), Catch::Contains("is not a regular file"));
  REQUIRE(::mkfifo(d.file("pipe.ply").c_str(), 0600) == 0);
  CHECK_THAT(load_error(d.file("pipe.ply")), Catch::Contains("is not a regular file"));
  // Larger than any mesh the loader takes (a sparse file: no disk is used).
  const std::string huge = d.write("huge.obj", "v 0 0 0\n");
  fs::resize_file(huge, 5ull << 30);
  CHECK_THAT(load_error(huge), Catch::Contains("is 5120 MiB, larger than the 4096 MiB an input may be"));
}

// ---- OBJ -----------------------------------------------------------------------------------

TEST_CASE("OBJ: corner forms, relative indices, polygons", "[io]") {
  TempDir d;
  const std::string path = d.write("a.obj",
                                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n"
                                   "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                   "vn 0 0 -1\n"
                                   "f 1/1/1 4/4/1 3/3/1 2/2/1\n"  // quad, v/vt/vn
                                   "f 1/1 2/2 5/3\n"              // v/vt
                                   "f -4/-3 -3/-2 -1/-1\n"        // relative
                                   "f 3/3 4/4 5/1\n"
                                   "f 4/4 1/1 5/2\n");
  const RawMesh raw = read_raw_mesh(path);
  REQUIRE(raw.polygons.size() == 5);
  CHECK(raw.polygons[0] == std::vector<int>{0, 3, 2, 1});
  CHECK(raw.polygons[2] == std::vector<int>{1, 2, 4});
  CHECK(raw.polygon_uvs[2] == std::vector<int>{1, 2, 3});
  CHECK(raw.normals.empty());  // only the quad's corners name normals
  REQUIRE(raw.warnings.size() == 1);
  CHECK_THAT(raw.warnings[0], Catch::Contains("normals ignored"));

  const LoadResult r = load_mesh(path);
  CHECK(r.report.polygons == 1);
  CHECK(r.mesh.num_faces() == 6);
  CHECK(Topology(r.mesh).boundary_loops().empty());
  CHECK(Topology(r.mesh).genus() == 0);
}

TEST_CASE("OBJ: a statement may continue on the next line after a backslash", "[io]") {
  TempDir d;
  const RawMesh raw =
      read_raw_mesh(d.write("c.obj",
                            "# a comment ending in \\\nv 0 0 0\nv 1 0 \\\n 0\nv 1 1 0\nv 0 1 0\r\n"
                            "f 1 2 \\ \r\n3 \\\n4\n"));
  REQUIRE(raw.positions.size() == 4);
  CHECK(raw.positions[1].x == 1);
  CHECK(raw.positions[1].z == 0);
  REQUIRE(raw.polygons.size() == 1);
  CHECK(raw.polygons[0] == std::vector<int>{0, 1, 2, 3});
  // Errors name the statement's last line.
  CHECK(load_error(d.write("e.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n9\n")) ==
        "line 5: vertex index 9 is out of range (the file has 3 vertices)");
}

TEST_CASE("atlases split at their UV seams are joined again when asked", "[io]") {
  // A tetrahedron written as other tools write atlases: one vertex per (position, UV), so every
  // face is its own piece. Loaded as an atlas it is one closed surface, UVs kept per corner.
  TempDir d;
  std::string obj;
  const char* corners[4] = {"0 0 0", "1 0 0", "0 1 0", "0 0 1"};
  const int tris[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) obj += std::string("v ") + corners[t[k]] + "\n";
  for (int f = 0; f < 4; ++f)
    obj += "vt " + std::to_string(0.25 * f) + " 0\nvt " + std::to_string(0.25 * f + 0.2) + " 0\nvt " +
           std::to_string(0.25 * f) + " 0.2\n";
  for (int f = 0; f < 4; ++f) {
    obj += "f";
    for (int k = 1; k <= 3; ++k) obj += " " + std::to_string(3 * f + k) + "/" + std::to_string(3 * f + k);
    obj += "\n";
  }
  const std::string path = d.write("split.obj", obj);
  CHECK(load_mesh(path).mesh.num_vertices() == 12);  // a mesh file keeps its pieces
  LoadOptions lo;
  lo.weld = true;
  const Mesh m = load_mesh(path, lo).mesh;
  CHECK(m.num_vertices() == 4);
  CHECK(Topology(m).boundary_loops().empty());
  CHECK(Topology(m).euler_characteristic() == 2);
  REQUIRE(m.uvs.size() == 12);
  CHECK(m.uvs[m.face_uvs[3][0]].x == Approx(0.75));
}

TEST_CASE("weld_only_if_surface keeps the split that keeps an atlas a surface", "[io]") {
  // Our atlas of a cube with a fin on its edge 1-2: the repair gave corner 2 a copy (10), and
  // joined again, the edge has three faces.
  TempDir d;
  const std::string path =
      d.write("fin.obj",
              "v 0 0 0\nv 0 0 1\nv 0 1 0\nv 0 1 1\nv 1 0 0\nv 1 0 1\nv 1 1 0\nv 1 1 1\nv -1 0 0.5\nv 0 0 1\n"
              "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 10 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\n"
              "f 1 7 3\nf 2 4 8\nf 10 8 6\nf 1 2 9\n");
  LoadOptions lo;
  lo.weld = true;
  CHECK(load_mesh(path, lo).report.nonmanifold_edges == 1);
  lo.weld_only_if_surface = true;
  for (bool repair : {true, false}) {
    lo.repair = repair;
    const LoadResult r = load_mesh(path, lo);
    CHECK(r.mesh.num_vertices() == 10);
    CHECK(r.report.nonmanifold_edges == 0);
    CHECK(r.report.cut_edges == 0);
    CHECK(r.report.warnings.empty());
  }
  // Where joining needs no repair, it joins.
  const std::string closed = d.write("closed.obj",
                                     "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 0 0\n"
                                     "f 1 3 2\nf 5 2 4\nf 1 4 3\nf 2 3 4\n");
  lo.repair = true;
  const LoadResult r = load_mesh(closed, lo);
  CHECK(r.mesh.num_vertices() == 4);
  CHECK(r.report.warnings.empty());
}

TEST_CASE("OBJ: colours, normals, UVs and groups", "[io]") {
  TempDir d;
  const std::string path =
      d.write("b.obj",
              "# comment\r\nmtllib b.mtl\r\no body\r\n"
              "v 0 0 0 255 0 0\r\nv 1 0 0 0 255 0\r\nv 0 1 0 0 0 255\r\nv 0 0 1 51 51 51\r\n"
              "vn 0 0 -2\r\nvn 0 0 1\r\n"
              "usemtl red\r\ns 1\r\ng first\r\n"
              "f 1//1 3//1 2//1 # trailing comment\r\n"
              "g second\r\nf 1//2 2//2 4//2\r\n"
              "g first\r\nf 1//1 4//1 3//1\r\nf 2//2 3//2 4//2\r\n"
              "l 1 2\r\n"
              "vendorthing 1 2 3\r\n");
  const RawMesh raw = read_raw_mesh(path);
  REQUIRE(raw.colors.size() == 4);
  CHECK(raw.colors[1].y == Approx(1.0));  // 0-255 colours are scaled
  CHECK(raw.colors[3].x == Approx(0.2));
  REQUIRE(raw.normals.size() == 4);
  // Each vertex gets the normalized mean of its corners' normals: vertex 0 is named with
  // (0, 0, -2) twice and (0, 0, 1) once.
  CHECK(raw.normals[0] == Vec3d{0, 0, -1});
  CHECK(raw.normals[1] == Vec3d{0, 0, 1});
  // Ids by first use: "body" names no face, "first" and "second" do.
  CHECK(raw.polygon_groups == std::vector<int>{0, 1, 0, 0});
  REQUIRE(raw.warnings.size() == 2);
  CHECK_THAT(raw.warnings[0], Catch::Contains("ignored 1 line and point elements"));
  CHECK_THAT(raw.warnings[1], Catch::Contains("'vendorthing' on line 20"));
}

TEST_CASE("text formats: a byte-order mark and lone CR line ends are read like plain LF", "[io]") {
  TempDir d;
  // Lone CRs (old Mac files), CR LF and LF mixed; the line numbers count each kind once.
  const RawMesh obj = read_raw_mesh(d.write("m.obj", "\xEF\xBB\xBFv 0 0 0\rv 1 0 0\r\nv 0 1 0\nf 1 2 3\r"));
  CHECK(obj.positions.size() == 3);
  CHECK(obj.positions[1] == Vec3d{1, 0, 0});
  REQUIRE(obj.polygons.size() == 1);
  CHECK(obj.polygons[0] == std::vector<int>{0, 1, 2});
  CHECK_THAT(load_error(d.write("bad.obj", "v 0 0 0\rv 1 0 0\r\nv 0 x 0\n")), Catch::Contains("line 3"));
  const RawMesh off =
      read_raw_mesh(d.write("m.off", "\xEF\xBB\xBFOFF\r3 1 0\r0 0 0\r1 0 0\r0 1 0\r3 0 1 2\r"));
  CHECK(off.positions.size() == 3);
  CHECK(off.polygons.size() == 1);
  // PLY: a BOM, and a CR-only header before a binary body whose first byte is 10 (LF).
  const std::string header =
      "ply\rformat binary_little_endian 1.0\relement vertex 3\rproperty float x\r"
      "property float y\rproperty float z\relement face 1\r"
      "property list uchar int vertex_indices\rend_header\r";
  std::string body;
  auto put = [&](const void* p, std::size_t n) { body.append(static_cast<const char*>(p), n); };
  const float xyz[9] = {1.4e-44f /* bytes 0a 00 00 00 */, 0, 0, 1, 0, 0, 0, 1, 0};
  put(xyz, sizeof xyz);
  const unsigned char three = 3;
  const int idx[3] = {0, 1, 2};
  put(&three, 1);
  put(idx, sizeof idx);
  const RawMesh ply = read_raw_mesh(d.write("m.ply", "\xEF\xBB\xBF" + header + body));
  REQUIRE(ply.positions.size() == 3);
  CHECK(ply.positions[1] == Vec3d{1, 0, 0});
  REQUIRE(ply.polygons.size() == 1);
  CHECK(ply.polygons[0] == std::vector<int>{0, 1, 2});
}

TEST_CASE("OBJ: faces without texture coordinates next to faces with them get (0, 0)", "[io]") {
  TempDir d;
  const RawMesh raw = read_raw_mesh(
      d.write("c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0.5 0.5\nf 1/1 3/1 2/1\nf 1 2 4\n"));
  REQUIRE(raw.polygon_uvs.size() == 2);
  CHECK(raw.uvs[raw.polygon_uvs[1][0]] == Vec2d{0, 0});
  CHECK_THAT(raw.warnings.at(0), Catch::Contains("1 face has no texture coordinates"));
}

TEST_CASE("OBJ: parse errors name the line", "[io]") {
  TempDir d;
  const std::string head = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  auto err = [&](const std::string& body) { return load_error(d.write("bad.obj", head + body)); };
  CHECK(err("v 1 2\n") == "line 4: expected 3 coordinates after 'v'");
  CHECK(err("v 1 nan 2\n") == "line 4: coordinate 'nan' is not finite");
  // A number beyond a double is out of range, not "not a number"; one that underflows reads as 0.
  CHECK(err("v 1 2 1e999\n") == "line 4: coordinate '1e999' is out of range (beyond 1.8e308)");
  CHECK(err("v 1 2 -1e999\n") == "line 4: coordinate '-1e999' is out of range (beyond 1.8e308)");
  CHECK(err("v 1 2 inf\n") == "line 4: coordinate 'inf' is not finite");
  CHECK(err("vn 0 nan 1\n") == "line 4: normal coordinate 'nan' is not finite");
  CHECK(err("vt 0.5 1e400\n") == "line 4: texture coordinate '1e400' is out of range (beyond 1.8e308)");
  CHECK(err("f 1 2\n") == "line 4: face has 2 corners; a face needs at least 3");
  CHECK(err("f 0 1 2\n") == "line 4: vertex index 0 is invalid (OBJ indices start at 1)");
  CHECK_THAT(err("f -1 -2 -4\n"),
             Catch::StartsWith("line 4: relative vertex index -4 reaches before the first vertex"));
  CHECK(err("f 1 2 3\nf 1 2 9\nf 1 2 4\n") ==
        "line 5: vertex index 9 is out of range (the file has 3 vertices)");
  CHECK(err("f 1/1 2/1 3/1\n") ==
        "line 4: texture coordinate index 1 is out of range (the file has 0 texture coordinates)");
  // An index too large for a long long is out of range, not malformed.
  CHECK(err("f 1 2 99999999999999999999\n") ==
        "line 4: vertex index 99999999999999999999 is out of range (too large for any mesh)");
  CHECK(err("f 1/1 2/-99999999999999999999 3/1\n") ==
        "line 4: texture coordinate index -99999999999999999999 is out of range (too large for any mesh)");
  CHECK_THAT(err("f 1/x 2 3\n"), Catch::Contains("line 4: '1/x' is not a face corner"));
  CHECK_THAT(err("f 1/1/1/1 2 3\n"), Catch::Contains("is not a face corner"));
  CHECK(err("vt 0 0\nf 1/1 2 3\n") == "line 5: face mixes corners with and without texture coordinates");
  CHECK(err("\xff\xfe garbage\n") == "line 4: '\\xff\\xfe' is not an OBJ statement");
  CHECK(err("v 1 2 3 4 5\n") == "line 4: expected x y z, x y z w or x y z r g b after 'v', found 5 numbers");
  CHECK_THAT(err(std::string("v 1 2 3\0\n", 9)), Catch::Contains("line 4: unexpected binary data"));
  CHECK(err("") == "mesh has no faces");
}

TEST_CASE("face limits are enforced", "[io]") {
  TempDir d;
  LoadOptions o;
  o.max_faces = 3;
  CHECK_THAT(
      load_error(d.write("many.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3\nf 1 2 3\nf 1 2 3\n"), o),
      Catch::Contains("has 4 faces, more than the limit of 3"));
  CHECK_THAT(
      load_error(d.write("many.off", "OFF\n3 4 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n3 0 1 2\n3 0 1 2\n"),
                 o),
      Catch::Contains("has 4 faces, more than the limit of 3"));
  // A hexagon is one face in the file but four triangles.
  CHECK_THAT(
      load_error(d.write("hex.obj", "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 2 0\nv -1 1 0\nf 1 2 3 4 5 6\n"),
                 o),
      Catch::Contains("has 4 faces, more than the limit of 3"));
}

// ---- OFF -----------------------------------------------------------------------------------

TEST_CASE("OFF: header variants, comments, polygons and colours", "[io]") {
  TempDir d;
  SECTION("counts on the header line, comments, a quad") {
    const RawMesh raw = read_raw_mesh(d.write("a.off",
                                              "# made by hand\nOFF 5 2 0 # counts\n\n0 0 0\n1 0 0\n1 1 0\n"
                                              "# a comment between vertices\n0 1 0\n0.5 0.5 1\n"
                                              "4 0 1 2 3\n3 0 1 4 255 0 0\n"));
    REQUIRE(raw.polygons.size() == 2);
    CHECK(raw.polygons[0] == std::vector<int>{0, 1, 2, 3});
    CHECK(raw.polygons[1] == std::vector<int>{0, 1, 4});
    CHECK(raw.colors.empty());
  }
  SECTION("COFF with 0-255 colours") {
    const RawMesh raw = read_raw_mesh(
        d.write("c.off", "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 51 255\n3 0 1 2\n"));
    REQUIRE(raw.colors.size() == 3);
    CHECK(raw.colors[0].x == Approx(1.0));
    CHECK(raw.colors[2].z == Approx(0.2));
  }
  SECTION("CNOFF with normals and [0, 1] colours") {
    const RawMesh raw = read_raw_mesh(d.write(
        "n.off", "CNOFF\n3 1 0\n0 0 0 0 0 1 0.5 0.25 1\n1 0 0 0 0 1 0 0 0\n0 1 0 0 0 1 1 1 1\n3 0 1 2\n"));
    REQUIRE(raw.normals.size() == 3);
    CHECK(raw.normals[1] == Vec3d{0, 0, 1});
    CHECK(raw.colors[0] == Vec3d{0.5, 0.25, 1});
  }
  SECTION("STOFF texture coordinates") {
    const RawMesh raw =
        read_raw_mesh(d.write("t.off", "STOFF\n3 1 0\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n"));
    REQUIRE(raw.polygon_uvs.size() == 1);
    CHECK(raw.uvs[raw.polygon_uvs[0][2]] == Vec2d{0, 1});
  }
}

TEST_CASE("OFF: nOFF of dimension 3 is a plain OFF; other dimensions are refused", "[io]") {
  TempDir d;
  const std::string body = "4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n";
  CHECK(read_raw_mesh(d.write("a.off", "nOFF\n3\n" + body)).polygons.size() == 2);
  CHECK(read_raw_mesh(d.write("b.off", "nOFF 3 " + body)).positions.size() == 4);
  CHECK(load_error(d.write("c.off", "nOFF\n4\n" + body)) ==
        "line 2: only 3D OFF files are supported (header 'nOFF' with dimension '4')");
  CHECK_THAT(load_error(d.write("d.off", "4OFF\n" + body)),
             Catch::Contains("only 3D OFF files are supported"));
}

TEST_CASE("OFF: errors name the line", "[io]") {
  TempDir d;
  auto err = [&](const std::string& text) { return load_error(d.write("bad.off", text)); };
  CHECK_THAT(err("PLY\n3 1 0\n"), Catch::Contains("line 1: expected an OFF header"));
  CHECK(err("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n") == "line 4: vertex 1: expected 3 numbers, found 2");
  CHECK(err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n") ==
        "line 6: vertex index 5 is out of range (the file has 3 vertices)");
  CHECK(err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n") ==
        "line 6: face has 2 corners; a face needs at least 3");
  // A vertex more than the header counts is read as the first face, and said to look like one.
  CHECK(err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n") ==
        "line 6: face has 0 corners; a face needs at least 3 (it looks like a vertex: does the header count "
        "too few vertices?)");
  // A face of no corners is said as such, not taken for a truncated file.
  CHECK(err("OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n0\n") ==
        "line 8: face has 0 corners; a face needs at least 3");
  CHECK(err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n") ==
        "line 6: face declares 4 corners but lists 3 indices");
  CHECK(err("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 # padding, so the size check passes\n") ==
        "unexpected end of file after 1 of 2 faces (truncated)");
  CHECK_THAT(err("OFF\n2000000000 2000000000 0\n0 0 0\n"),
             Catch::Contains("line 2: header declares 2000000000 vertices"));
  CHECK_THAT(err("OFF\n-3 1 0\n"), Catch::Contains("out of range"));
  CHECK(err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99999999999999999999\n") ==
        "line 6: vertex index 99999999999999999999 is out of range (the file has 3 vertices)");
  CHECK(err("OFF\n3 1 0\n0 0 inf\n1 0 0\n0 1 0\n3 0 1 2\n") == "line 3: value 'inf' is not finite");
  CHECK(err("OFF BINARY\n") == "line 1: binary OFF is not supported");
  // Faces past the declared count were dropped without a word; comments after the end are fine.
  CHECK(err("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n") ==
        "line 7: more data after the 1 faces the header declares ('3 0 2 1'); the header's counts do not "
        "match the file");
  CHECK(read_raw_mesh(d.write("ok.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n# end\n"))
            .polygons.size() == 1);
}

// ---- PLY -----------------------------------------------------------------------------------

namespace {

// A tetrahedron with an unknown vertex property, an unknown element between vertices and
// faces, a list-then-scalar face record and a trailing edge element, in the given format.
std::string ply_tetra(const std::string& format) {
  const bool ascii = format == "ascii";
  std::string h = "ply\nformat " + format +
                  " 1.0\ncomment test\n"
                  "element vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
                  "property float confidence\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                  "property float nx\nproperty float ny\nproperty float nz\n"
                  "element material 1\nproperty list uchar float weights\nproperty int id\n"
                  "element face 4\nproperty list ushort uint vertex_indices\nproperty int flags\n"
                  "property list uchar float texcoord\n"
                  "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  const double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  if (ascii) {
    std::ostringstream s;
    for (int v = 0; v < 4; ++v)
      s << p[v][0] << " " << p[v][1] << " " << p[v][2] << " 0.5 " << 50 * v << " 255 0 0 0 1\n";
    s << "2 0.25 0.75 7\n";
    for (int i = 0; i < 4; ++i)
      s << "3 " << f[i][0] << " " << f[i][1] << " " << f[i][2] << " -1 6 0 0 1 0 0." << i + 1 << " 1\n";
    s << "0 1\n";
    return h + s.str();
  }
  Bytes b;
  b.big_endian = format == "binary_big_endian";
  for (int v = 0; v < 4; ++v) {
    b.put(p[v][0]).put(p[v][1]).put(p[v][2]).put(0.5f);
    b.put<std::uint8_t>(static_cast<std::uint8_t>(50 * v)).put<std::uint8_t>(255).put<std::uint8_t>(0);
    b.put(0.0f).put(0.0f).put(1.0f);
  }
  b.put<std::uint8_t>(2).put(0.25f).put(0.75f).put<std::int32_t>(7);
  for (int i = 0; i < 4; ++i) {
    b.put<std::uint16_t>(3);
    for (int k = 0; k < 3; ++k) b.put<std::uint32_t>(static_cast<std::uint32_t>(f[i][k]));
    b.put<std::int32_t>(-1).put<std::uint8_t>(6);
    b.put(0.0f).put(0.0f).put(1.0f).put(0.0f).put(static_cast<float>(0.1 * (i + 1))).put(1.0f);
  }
  b.put<std::int32_t>(0).put<std::int32_t>(1);
  return h + b.data;
}

}  // namespace

TEST_CASE("PLY: ascii, little and big endian read the same", "[io]") {
  TempDir d;
  for (const std::string format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    INFO(format);
    const RawMesh raw = read_raw_mesh(d.write(format + ".ply", ply_tetra(format)));
    REQUIRE(raw.positions.size() == 4);
    CHECK(raw.positions[3] == Vec3d{0, 0, 1});
    REQUIRE(raw.polygons.size() == 4);
    CHECK(raw.polygons[3] == std::vector<int>{1, 2, 3});
    REQUIRE(raw.colors.size() == 4);
    CHECK(raw.colors[2].x == Approx(100.0 / 255));
    CHECK(raw.colors[2].y == Approx(1.0));
    REQUIRE(raw.normals.size() == 4);
    CHECK(raw.normals[1] == Vec3d{0, 0, 1});
    REQUIRE(raw.polygon_uvs.size() == 4);
    CHECK(raw.uvs[raw.polygon_uvs[2][2]].x == Approx(0.3).epsilon(1e-6));
    CHECK(raw.uvs[raw.polygon_uvs[2][2]].y == 1.0);
    const LoadResult r = load_mesh(d.file(format + ".ply"));
    CHECK(r.report.warnings.empty());
    CHECK(r.mesh.num_faces() == 4);
  }
}

TEST_CASE("PLY: per-vertex texture coordinates and the vertex_index name", "[io]") {
  TempDir d;
  const RawMesh raw =
      read_raw_mesh(d.write("uv.ply",
                            "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\n"
                            "property float y\r\nproperty float z\r\nproperty float s\r\n"
                            "property float t\r\nelement face 1\r\n"
                            "property list uchar int vertex_index\r\nend_header\r\n"
                            "0 0 0 0 0\r\n1 0 0 1 0\r\n0 1 0 0 1\r\n3 0 1 2\r\n"));
  REQUIRE(raw.polygon_uvs.size() == 1);
  CHECK(raw.uvs[raw.polygon_uvs[0][1]] == Vec2d{1, 0});
}

TEST_CASE("PLY: float colours stored as 0..255 are scaled, with a warning", "[io]") {
  // Read as they were, the colour signal was 255 times too strong and a written PLY saturated.
  TempDir d;
  auto ply = [](const std::string& body) {
    return "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "property float red\nproperty float green\nproperty float blue\nelement face 1\n"
           "property list uchar int vertex_indices\nend_header\n" +
           body + "3 0 1 2\n";
  };
  const RawMesh byte = read_raw_mesh(d.write("b.ply", ply("0 0 0 255 0 0\n1 0 0 0 51 0\n0 1 0 0 0 0\n")));
  REQUIRE(byte.colors.size() == 3);
  CHECK(byte.colors[0].x == Approx(1.0));
  CHECK(byte.colors[1].y == Approx(0.2));
  REQUIRE(byte.warnings.size() == 1);
  CHECK_THAT(byte.warnings[0], Catch::Contains("float vertex colours reach 255: read as 8-bit values"));
  const RawMesh unit = read_raw_mesh(d.write("u.ply", ply("0 0 0 1 0 0\n1 0 0 0 0.2 0\n0 1 0 0 0 0\n")));
  CHECK(unit.colors[1].y == Approx(0.2));
  CHECK(unit.warnings.empty());
  CHECK_THAT(load_error(d.write("h.ply", ply("0 0 0 300 0 0\n1 0 0 0 0 0\n0 1 0 0 0 0\n"))),
             Catch::Contains("float vertex colours reach 300, beyond both [0, 1] and the 8-bit range"));
}

TEST_CASE("PLY: an ASCII line with more values than the header declares is refused", "[io]") {
  // OFF refuses data past its header's counts; these were read as far as the header said.
  TempDir d;
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  CHECK(read_raw_mesh(d.write("ok.ply", head + "0 0 0\n1 0 0 \t\n0 1 0\n3 0 1 2\n")).polygons.size() == 1);
  CHECK_THAT(
      load_error(d.write("v.ply", head + "0 0 0 7\n1 0 0\n0 1 0\n3 0 1 2\n")),
      Catch::Contains(
          "line 10: vertex 0: more values on this line than the header declares ('7' is one too many)"));
  CHECK_THAT(load_error(d.write("f.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 3\n")),
             Catch::Contains(
                 "line 13: face 0: more values on this line than the header declares ('3' is one too many)"));
}

TEST_CASE("PLY: face colours are named as not read", "[io]") {
  TempDir d;
  const RawMesh raw = read_raw_mesh(d.write(
      "fc.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nproperty uchar red\n"
      "property uchar green\nproperty uchar blue\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 255 0 0\n"));
  REQUIRE(raw.polygons.size() == 1);
  CHECK(raw.colors.empty());
  REQUIRE(raw.warnings.size() == 1);
  CHECK(raw.warnings[0] == "face colours are not read (only vertex colours are)");
}

TEST_CASE("PLY: errors name the line or the element", "[io]") {
  TempDir d;
  const std::string full = ply_tetra("binary_little_endian");
  CHECK(load_error(d.write("t1.ply", full.substr(0, full.size() - 20))) ==
        "face 3: list of 6 values runs past the end of the file (truncated)");
  CHECK(load_error(d.write("t0.ply", full.substr(0, full.size() - 3))) ==
        "edge 0: unexpected end of file (truncated)");
  const std::string header_end = "end_header\n";
  const std::size_t body = full.find(header_end) + header_end.size();
  CHECK_THAT(
      load_error(d.write("t2.ply", full.substr(0, body + 40))),
      Catch::Contains("header declares 4 vertex elements, but only 40 bytes of data follow (truncated"));
  CHECK_THAT(load_error(d.write("t3.ply", full.substr(0, body - 5))), Catch::Contains("no end_header line"));
  CHECK_THAT(load_error(d.write("huge.ply",
                                "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n"
                                "property float x\nproperty float y\nproperty float z\nend_header\n0000")),
             Catch::Contains("line 3: header declares 2000000000 vertex elements"));
  CHECK_THAT(load_error(d.write("fmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n")),
             Catch::Contains("line 2: unknown PLY format 'binary_middle_endian'"));
  const std::string ascii_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  CHECK(load_error(d.write("a1.ply", ascii_head + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n")) ==
        "line 11: vertex 1: expected more values on this line");
  CHECK(load_error(d.write("a2.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n")) ==
        "line 13: face 0: vertex index -2 is out of range");
  // Indices are read as doubles; one beyond a long long used to print as -9223372036854775808.
  CHECK(load_error(d.write("a3.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 99999999999999999999\n")) ==
        "line 13: face 0: vertex index 1e+20 is out of range");
  CHECK(load_error(d.write("a4.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 1.5\n")) ==
        "line 13: face 0: vertex index 1.5 is not a whole number");
  // The header with one declaration changed, and the same body.
  const auto edited = [&](const std::string& from, const std::string& to) {
    std::string h = ascii_head;
    h.replace(h.find(from), from.size(), to);
    return h;
  };
  const std::string triangle = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  // What a binary file of the same header could not hold, an ASCII one may not either.
  CHECK(load_error(d.write("u300.ply", edited("float x", "uchar x") + "0 0 0\n300 0 0\n0 1 0\n3 0 1 2\n")) ==
        "line 11: vertex 1: '300' is not a uchar value, as the header declares");
  CHECK(load_error(
            d.write("i300.ply", edited("uchar int", "uchar uchar") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 300\n")) ==
        "line 13: face 0: vertex index 300 is not a uchar value, as the header declares");
  // Declarations made twice, and a PLY version other than 1.0.
  CHECK(load_error(d.write("dupx.ply", edited("property float y", "property float x") + triangle)) ==
        "line 5: property 'x' of element 'vertex' is declared twice");
  CHECK(load_error(d.write("dupface.ply", edited("end_header", "element face 0\nend_header") + triangle)) ==
        "line 9: element 'face' is declared twice (first on line 7)");
  CHECK(load_error(d.write("v2.ply", edited("1.0", "2.0") + triangle)) ==
        "line 2: PLY version '2.0' is not supported (only 1.0)");
  CHECK(load_error(d.write("a3.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")) ==
        "face 0 refers to vertex 3, but there are only 3 vertices");
  CHECK(load_error(d.write("a4.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n")) ==
        "line 13: face 0: face has 2 corners; a face needs at least 3");
  CHECK(load_error(d.write("a5.ply", ascii_head + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n")) ==
        "vertex 1 has a non-finite coordinate (1, nan, 0)");
  CHECK_THAT(load_error(d.write("noply.ply", "solid stl\n")), Catch::Contains("not a PLY file"));
  // Counts smaller than the data: the rest was dropped without a word. Zero padding is not data.
  CHECK(load_error(d.write("more.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n\n")) ==
        "a line of data (line 14) follows the last element the header declares (face 1); the header's counts "
        "do not match the file");
  CHECK_THAT(
      load_error(d.write("more2.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n3 1 2 0\n")),
      Catch::StartsWith("2 more lines of data from line 14 follow"));
  CHECK_THAT(load_error(d.write("more.bin.ply", full + std::string(7, '\x01'))),
             Catch::StartsWith("7 more bytes of data follow the last element"));
  CHECK(read_raw_mesh(d.write("pad.bin.ply", full + std::string(20, '\0'))).polygons.size() == 4);
  CHECK(load_error(d.write("neg.ply", ascii_head + "0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n")) ==
        "line 13: face 0: invalid list length -3");
}

// ---- glTF ----------------------------------------------------------------------------------

namespace {

// One square (4 vertices with NORMAL and TEXCOORD_0) drawn three ways: mesh 0 holds a
// TRIANGLES primitive (ushort indices) and a TRIANGLE_FAN one (uint indices) on the same
// accessors; mesh 1 a TRIANGLE_STRIP (ubyte indices). Node 0 (mesh 0) is moved by +10 in x;
// its child node 1 (mesh 1) mirrors x. Node 2 is not in the scene.
struct GltfSample {
  std::string bin;
  nlohmann::json doc;
};

GltfSample gltf_sample() {
  Bytes b;
  const float pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (const auto& p : pos) b.put(p[0]).put(p[1]).put(p[2]);                             // 0..48
  for (int i = 0; i < 4; ++i) b.put(0.0f).put(0.0f).put(1.0f);                           // 48..96
  for (const auto& p : pos) b.put(p[0] * 0.5f).put(p[1] * 0.25f);                        // 96..128
  for (int i : {0, 1, 2, 0, 2, 3}) b.put<std::uint16_t>(static_cast<std::uint16_t>(i));  // 128..140
  for (int i : {0, 1, 3, 2}) b.put<std::uint8_t>(static_cast<std::uint8_t>(i));          // 140..144
  for (int i : {0, 1, 2, 3}) b.put<std::uint32_t>(static_cast<std::uint32_t>(i));        // 144..160
  using nlohmann::json;
  json doc = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes",
       {{{"mesh", 0}, {"translation", {10, 0, 0}}, {"children", {1}}},
        {{"mesh", 1}, {"scale", {-1, 1, 1}}},
        {{"mesh", 0}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
        {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 48}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 32}},
        {{"buffer", 0}, {"byteOffset", 128}, {"byteLength", 12}},
        {{"buffer", 0}, {"byteOffset", 140}, {"byteLength", 4}},
        {{"buffer", 0}, {"byteOffset", 144}, {"byteLength", 16}}}},
      {"accessors",
       {{{"bufferView", 0},
         {"componentType", 5126},
         {"count", 4},
         {"type", "VEC3"},
         {"min", {0, 0, 0}},
         {"max", {1, 1, 0}}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
        {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}},
        {{"bufferView", 4}, {"componentType", 5121}, {"count", 4}, {"type", "SCALAR"}},
        {{"bufferView", 5}, {"componentType", 5125}, {"count", 4}, {"type", "SCALAR"}}}},
  };
  const json attrs = {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}};
  doc["meshes"] = {
      {{"primitives",
        {{{"attributes", attrs}, {"indices", 3}}, {{"attributes", attrs}, {"indices", 5}, {"mode", 6}}}}},
      {{"primitives", {{{"attributes", attrs}, {"indices", 4}, {"mode", 5}}}}}};
  return {b.data, doc};
}

std::string gltf_text(const GltfSample& s) {
  nlohmann::json doc = s.doc;
  doc["buffers"] = {
      {{"byteLength", s.bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(s.bin)}}};
  return doc.dump();
}

std::string glb_of(const GltfSample& s) {
  nlohmann::json doc = s.doc;
  doc["buffers"] = {{{"byteLength", s.bin.size()}}};
  return glb_container(doc.dump(), s.bin);
}

}  // namespace

TEST_CASE("glTF: triangles from a count that is not a multiple of 3, and a short data: URI, are said",
          "[io]") {
  TempDir d;
  const GltfSample s = gltf_sample();
  // Mesh 0's first primitive: 6 indices; 5 of them, or its 4 vertices without indices.
  nlohmann::json doc = s.doc;
  doc["accessors"][3]["count"] = 5;
  GltfSample cut{s.bin, doc};
  CHECK_THAT(load_error(d.write("i.gltf", gltf_text(cut))),
             Catch::Contains("triangles from 5 indices, not a multiple of 3"));
  doc = s.doc;
  doc["meshes"][0]["primitives"][0].erase("indices");
  GltfSample noidx{s.bin, doc};
  CHECK_THAT(load_error(d.write("n.gltf", gltf_text(noidx))),
             Catch::Contains("triangles from 4 vertices, not a multiple of 3"));
  // byteLength beyond the data: tinygltf's message quoted the whole base64 text.
  nlohmann::json big = nlohmann::json::parse(gltf_text(s));
  big["buffers"][0]["byteLength"] = s.bin.size() + 1000;
  const std::string e = load_error(d.write("b.gltf", big.dump()));
  CHECK_THAT(e, Catch::Contains("invalid glTF: a buffer's data: URI does not decode to its byteLength"));
  CHECK_THAT(e, !Catch::Contains(";base64,"));
}

TEST_CASE("glTF: primitives, modes, index types and transforms", "[io]") {
  TempDir d;
  const GltfSample s = gltf_sample();
  const RawMesh a = read_raw_mesh(d.write("s.gltf", gltf_text(s)));
  const RawMesh b = read_raw_mesh(d.write("s.glb", glb_of(s)));
  for (const RawMesh* r : {&a, &b}) {
    // Mesh 0's two primitives share vertices (same accessors); mesh 1 has its own.
    REQUIRE(r->positions.size() == 8);
    CHECK(r->positions[2] == Vec3d{11, 1, 0});
    CHECK(r->positions[6] == Vec3d{9, 1, 0});  // mirrored child: 10 - 1
    REQUIRE(r->polygons.size() == 6);
    CHECK(r->polygons[0] == std::vector<int>{0, 1, 2});
    CHECK(r->polygons[3] == std::vector<int>{0, 2, 3});  // fan
    CHECK(r->polygons[4] == std::vector<int>{4, 7, 5});  // strip (0,1,3) mirrored
    CHECK(r->polygon_groups == std::vector<int>{0, 0, 1, 1, 2, 2});
    REQUIRE(r->uvs.size() == 8);
    CHECK(r->uvs[2] == Vec2d{0.5, 0.75});  // glTF v is flipped to OBJ's convention
    REQUIRE(r->normals.size() == 8);
    // Every face's winding agrees with its vertex normals, the mirrored ones included.
    for (const auto& p : r->polygons) {
      const Vec3d n = cross(r->positions[p[1]] - r->positions[p[0]], r->positions[p[2]] - r->positions[p[0]]);
      CHECK(dot(n, r->normals[p[0]]) > 0);
    }
  }
  CHECK(a.positions == b.positions);
  CHECK(a.polygons == b.polygons);

  // The same with the buffer in a file beside the .gltf.
  nlohmann::json doc = s.doc;
  doc["buffers"] = {{{"byteLength", s.bin.size()}, {"uri", "s.bin"}}};
  d.write("s.bin", s.bin);
  const RawMesh c = read_raw_mesh(d.write("external.gltf", doc.dump()));
  CHECK(c.positions == a.positions);
  CHECK(c.polygons == a.polygons);
  fs::remove(d.file("s.bin"));
  CHECK_THAT(load_error(d.file("external.gltf")), Catch::StartsWith("invalid glTF"));
  fs::create_directory(d.file("s.bin"));  // tinygltf's own reader threw bad_alloc on this
  CHECK_THAT(load_error(d.file("external.gltf")),
             Catch::StartsWith("invalid glTF") && Catch::Contains("is a directory"));
  // tinygltf's check that the file exists opened it, and waited forever on a FIFO.
  fs::remove(d.file("s.bin"));
  REQUIRE(::mkfifo(d.file("s.bin").c_str(), 0600) == 0);
  CHECK_THAT(load_error(d.file("external.gltf")),
             Catch::StartsWith("invalid glTF") && Catch::Contains("is not a regular file"));
}

TEST_CASE("glTF and OBJ: a texture named but unusable is said, by file or by reason", "[io]") {
  TempDir d;
  const GltfSample s = gltf_sample();
  nlohmann::json doc = s.doc;
  doc["buffers"] = {{{"byteLength", s.bin.size()}, {"uri", "s.bin"}}};
  doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  doc["textures"] = {{{"source", 0}}};
  d.write("s.bin", s.bin);
  // An image file is handed over by name (reading it then says what is wrong), also when it
  // is missing or a FIFO, which the mesh reader must not wait on.
  doc["images"] = {{{"uri", "my%20tex.png"}}};
  MeshTexture t = find_mesh_texture(d.write("file.gltf", doc.dump()));
  CHECK(t.file == d.file("my tex.png"));
  CHECK(t.problem.empty());
  REQUIRE(::mkfifo(d.file("my tex.png").c_str(), 0600) == 0);
  CHECK(read_raw_mesh(d.file("file.gltf")).polygons.size() == 6);
  CHECK(find_mesh_texture(d.file("file.gltf")).file == d.file("my tex.png"));
  // Embedded bytes that are no PNG or JPEG, and a texture without an image.
  doc["images"] = {{{"uri", "data:image/png;base64,AAAA"}}};
  t = find_mesh_texture(d.write("bad.gltf", doc.dump()));
  CHECK(t.bytes.empty());
  CHECK(t.problem == "its base-colour image is not a PNG or JPEG image");
  doc["textures"] = {{{"sampler", 0}}};
  doc["samplers"] = {nlohmann::json::object()};
  CHECK(find_mesh_texture(d.write("none.gltf", doc.dump())).problem ==
        "its base-colour texture names no image");
  // The sampler's wraps are kept per axis; without a sampler glTF repeats.
  doc["images"] = {{{"uri", "tex.png"}}};
  doc["textures"] = {{{"source", 0}}};
  t = find_mesh_texture(d.write("nosampler.gltf", doc.dump()));
  CHECK((t.wrap.u == Wrap::Repeat && t.wrap.v == Wrap::Repeat));
  doc["textures"] = {{{"source", 0}, {"sampler", 0}}};
  doc["samplers"] = {{{"wrapS", 33071}, {"wrapT", 33648}}};
  t = find_mesh_texture(d.write("sampler.gltf", doc.dump()));
  CHECK(t.problem.empty());
  CHECK((t.wrap.u == Wrap::Clamp && t.wrap.v == Wrap::Mirror));
  // A wrap glTF does not define, or a sampler that is not there, was read as repeating.
  doc["samplers"] = {{{"wrapS", 12345}}};
  CHECK(find_mesh_texture(d.write("badwrap.gltf", doc.dump())).problem ==
        "its base-colour texture's sampler has wrapS 12345, not a glTF wrap mode (33071, 33648 or 10497)");
  doc["samplers"] = {{{"wrapS", 10497}}};
  doc["textures"] = {{{"source", 0}, {"sampler", 3}}};
  CHECK(find_mesh_texture(d.write("nosuchsampler.gltf", doc.dump())).problem ==
        "its base-colour texture's sampler 3 is out of range (1 samplers)");
  doc["textures"] = {{{"source", 0}, {"sampler", 0}}};
  // A URI decoding to a control character (%00) names no file; it reached error messages raw.
  doc["images"] = {{{"uri", "a%00b.png"}}};
  t = find_mesh_texture(d.write("nul.gltf", doc.dump()));
  CHECK(t.file.empty());
  CHECK(t.problem == "its base-colour image URI holds a control character, so it names no file");
  doc["images"] = {{{"uri", "tex.png"}}};
  // A primitive naming a material the file does not have is refused, not drawn without one.
  nlohmann::json missing = doc;
  missing["meshes"][0]["primitives"][0]["material"] = 4;
  CHECK(load_error(d.write("nomaterial.gltf", missing.dump())) ==
        "mesh 0 primitive 0 names material 4, and the file has 1 material");
  // An OBJ whose material library is missing.
  t = find_mesh_texture(d.write("m.obj", "mtllib gone.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  CHECK(t.file.empty());
  CHECK_THAT(t.problem, Catch::StartsWith("its material library " + d.file("gone.mtl") + " cannot be read"));
  // The texture is what a glTF maps through TEXCOORD_0, untransformed; anything else is said.
  doc["textures"] = {{{"source", 0}}};
  doc["images"] = {{{"uri", "tex.png"}}};
  doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}, {"texCoord", 1}}}}}}};
  CHECK(find_mesh_texture(d.write("tc1.gltf", doc.dump())).problem ==
        "its base-colour texture is mapped through TEXCOORD_1, and only TEXCOORD_0 is read");
  // Values tinygltf would read as 0 (or truncate to 0) are refused at load.
  for (const auto& [value, shown] : std::vector<std::pair<nlohmann::json, std::string>>{
           {4294967296LL, "'4294967296'"}, {1.5, "'1.5'"}, {"1", "'\"1\"'"}, {-1, "'-1'"}}) {
    nlohmann::json bad = doc;
    bad["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = value;
    CHECK(load_error(d.write("tcbad.gltf", bad.dump())) ==
          "a texture's texCoord " + shown + " is not a texture coordinate set (a whole number from 0)");
  }
  // KHR_texture_transform is read, in the mesh's coordinates (v up; glTF's v runs down). The
  // extension's own example picks the lower left quadrant of the image, turned: the mesh's
  // corner (0, 0) (glTF (0, 1)) reads the image at glTF (0.5, 1), ours (0.5, 0).
  auto transform_of = [&](const std::string& ext) {
    doc["materials"] = nlohmann::json::parse(
        R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": )" +
        ext + "}}}}]");
    return find_mesh_texture(d.write("tt.gltf", doc.dump()));
  };
  t = transform_of(R"({"offset": [0, 1], "rotation": 1.57079632679, "scale": [0.5, 0.5]})");
  REQUIRE(t.problem.empty());
  for (const auto& [from, to] : {std::pair<Vec2d, Vec2d>{{0, 0}, {0.5, 0}},
                                 {{1, 1}, {0, 0.5}},
                                 {{0, 1}, {0, 0}},
                                 {{1, 0}, {0.5, 0.5}}}) {
    CHECK(t.uv_transform.apply(from).x == Approx(to.x).margin(1e-9));
    CHECK(t.uv_transform.apply(from).y == Approx(to.y).margin(1e-9));
  }
  // Its second example flips glTF's v, which in the mesh's coordinates is a flip as well.
  t = transform_of(R"({"offset": [0, 1], "scale": [1, -1]})");
  CHECK(t.uv_transform.apply({0.25, 0.125}).x == Approx(0.25));
  CHECK(t.uv_transform.apply({0.25, 0.125}).y == Approx(0.875));
  CHECK(transform_of(R"({"scale": [2, 2]})").uv_transform.apply({0.5, 0.5}).y ==
        Approx(0));  // grows from glTF's top
  // Its texCoord overrides the texture's; malformed values are said.
  CHECK(transform_of(R"({"texCoord": 1})").problem ==
        "its base-colour texture is mapped through TEXCOORD_1, and only TEXCOORD_0 is read");
  CHECK(transform_of(R"({"scale": [2]})").problem ==
        "its base-colour texture's KHR_texture_transform is malformed");
  CHECK(transform_of(R"({"rotation": "a"})").problem ==
        "its base-colour texture's KHR_texture_transform is malformed");
}

TEST_CASE("OBJ: map_Kd names with spaces, options, quotes and backslashes; several mtllib libraries",
          "[io]") {
  TempDir d;
  fs::create_directories(d.file("tex dir"));
  d.write("tex dir/my tex.png", "");
  const std::string geometry = "usemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  auto texture_of = [&](const std::string& mtl_line, const std::string& mtllib = "m.mtl") {
    d.write("m.mtl", "newmtl a\n" + mtl_line + "\n");
    return find_mesh_texture(d.write("m.obj", "mtllib " + mtllib + "\n" + geometry)).file;
  };
  const std::string want = d.file("tex dir/my tex.png");
  CHECK(texture_of("map_Kd tex dir/my tex.png") == want);  // as Blender writes it
  CHECK(texture_of("map_Kd -s 1 1 1 -clamp on tex dir/my tex.png") == want);
  CHECK(texture_of("map_Kd -bm 0.5 -s 2 2 \"tex dir/my tex.png\"") == want);
  d.write("tex dir/2.png", "");
  CHECK(texture_of("map_Kd -s tex dir/2.png").find("tex dir/2.png") !=
        std::string::npos);                                 // -s without values
  CHECK(texture_of("map_Kd tex dir\\my tex.png") == want);  // written on Windows
  // The options that move the image or stop its tiling are kept, the file name still found.
  d.write("m.mtl", "newmtl a\nmap_Kd -clamp on -s 2 3 1 -o 0.5 -0.25 0 -bm 1 tex dir/my tex.png\n");
  MeshTexture t = find_mesh_texture(d.write("m.obj", "mtllib m.mtl\n" + geometry));
  CHECK(t.file == want);
  CHECK((t.wrap.u == Wrap::Clamp && t.wrap.v == Wrap::Clamp));
  CHECK(t.uv_transform.apply({1, 1}).x == 2.5);
  CHECK(t.uv_transform.apply({1, 1}).y == 2.75);
  CHECK((t.uv_transform.b == 0 && t.uv_transform.d == 0));
  d.write("m.mtl", "newmtl a\nmap_Kd -clamp off tex dir/my tex.png\n");
  t = find_mesh_texture(d.file("m.obj"));
  CHECK((t.wrap.u == Wrap::Repeat && t.wrap.v == Wrap::Repeat));
  CHECK(t.uv_transform.identity());
  // map_kd as some exporters write it; a map too large for any number is said, not ignored.
  CHECK(texture_of("map_kd tex dir/my tex.png") == want);
  d.write("m.mtl", "newmtl a\nmap_Kd -s 1e400 1 1 tex dir/my tex.png\n");
  t = find_mesh_texture(d.file("m.obj"));
  CHECK(t.file.empty());
  CHECK(t.problem == "its material's map_Kd -s value 1e400 is beyond any number");
  // `mtllib` takes a list: the first library without the material is passed over.
  d.write("other.mtl", "newmtl b\nmap_Kd nothing.png\n");
  d.write("m.mtl", "newmtl a\nmap_Kd tex dir/my tex.png\n");
  CHECK(find_mesh_texture(d.write("two.obj", "mtllib other.mtl m.mtl\n" + geometry)).file == want);
  // A material used but defined in no library is said, as a missing library is.
  CHECK(find_mesh_texture(d.write("undef.obj", "mtllib other.mtl\n" + geometry)).problem ==
        "its material a is defined in no material library it names");
}

TEST_CASE("glTF: a chain of nodes deeper than the call stack loads", "[io]") {
  // The scene was walked by one recursive call per level: 20,000 levels crashed the program.
  TempDir d;
  GltfSample s = gltf_sample();
  const int depth = 50000;
  nlohmann::json nodes = nlohmann::json::array();
  for (int i = 0; i < depth; ++i) nodes.push_back({{"children", {i + 1}}, {"translation", {1e-3, 0, 0}}});
  nodes.push_back({{"mesh", 0}});
  s.doc["nodes"] = nodes;
  const RawMesh r = read_raw_mesh(d.write("deep.glb", glb_of(s)));
  REQUIRE(r.positions.size() == 4);
  CHECK(r.positions[2].x == Approx(1 + depth * 1e-3).epsilon(1e-9));
}

TEST_CASE("glTF: texture coordinates only in TEXCOORD_1 are named, not dropped silently", "[io]") {
  TempDir d;
  GltfSample s = gltf_sample();
  for (auto& mesh : s.doc["meshes"])
    for (auto& prim : mesh["primitives"]) {
      prim["attributes"]["TEXCOORD_1"] = prim["attributes"]["TEXCOORD_0"];
      prim["attributes"].erase("TEXCOORD_0");
    }
  const RawMesh r = read_raw_mesh(d.write("lightmap.glb", glb_of(s)));
  CHECK(r.uvs.empty());
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0] == "3 primitives have TEXCOORD_1 but no TEXCOORD_0; only TEXCOORD_0 is read");
  // Both sets: TEXCOORD_0 is read, nothing to say.
  GltfSample both = gltf_sample();
  for (auto& mesh : both.doc["meshes"])
    for (auto& prim : mesh["primitives"]) prim["attributes"]["TEXCOORD_1"] = prim["attributes"]["TEXCOORD_0"];
  const RawMesh b = read_raw_mesh(d.write("both.glb", glb_of(both)));
  CHECK(b.uvs.size() == 8);
  CHECK(b.warnings.empty());
}

TEST_CASE("glTF: malformed files are clear errors", "[io]") {
  TempDir d;
  GltfSample s = gltf_sample();
  CHECK_THAT(load_error(d.write("bad.gltf", "{ \"asset\": ")), Catch::StartsWith("invalid glTF"));
  const std::string glb = glb_of(s);
  CHECK_THAT(load_error(d.write("cut.glb", glb.substr(0, glb.size() / 2))),
             Catch::StartsWith("invalid glTF"));
  CHECK_THAT(load_error(d.write("junk.glb", "this is not a glb file at all")),
             Catch::StartsWith("invalid glTF"));
  s.doc["accessors"][0]["count"] = 400;
  CHECK_THAT(load_error(d.write("count.glb", glb_of(s))),
             Catch::Contains("mesh 0 primitive 0 POSITION (accessor 0) runs past the end of its bufferView"));
  // Float indices over a bufferView sized for ushorts: the type is the problem, not the size.
  s = gltf_sample();
  s.doc["accessors"][3]["componentType"] = 5126;
  CHECK_THAT(load_error(d.write("floatidx.glb", glb_of(s))),
             Catch::Contains("mesh 0 primitive 0 indices (accessor 3) has a non-integer component type"));
  s = gltf_sample();
  s.bin[128] = 9;  // first ushort index
  CHECK_THAT(load_error(d.write("index.glb", glb_of(s))),
             Catch::Contains("mesh 0 primitive 0: index 9 is out of range (4 vertices)"));
  s = gltf_sample();
  s.doc["nodes"][1]["children"] = {0};
  CHECK_THAT(load_error(d.write("cycle.glb", glb_of(s))), Catch::Contains("node 0 is reached twice"));
  s = gltf_sample();
  s.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  s.doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  CHECK_THAT(load_error(d.write("draco.glb", glb_of(s))), Catch::Contains("unsupported extension"));
  // A transform of the wrong length, a glTF 1.0 asset, a glb container of version 1.
  s = gltf_sample();
  s.doc["nodes"][0].erase("translation");
  s.doc["nodes"][0]["matrix"] = std::vector<double>(15, 0.0);
  CHECK(load_error(d.write("matrix15.glb", glb_of(s))) == "node 0 has a matrix of 15 numbers, not 16");
  s = gltf_sample();
  s.doc["asset"]["version"] = "1.0";
  CHECK(load_error(d.write("v1.glb", glb_of(s))) == "glTF version '1.0' is not supported (only 2.x)");
  std::string v1 = glb_of(gltf_sample());
  v1[4] = 1;
  CHECK(load_error(d.write("container1.glb", v1)) == "glb container version 1 is not supported (only 2)");
  // Only points and lines: said so, not "no vertices".
  s = gltf_sample();
  for (auto& mesh : s.doc["meshes"])
    for (auto& prim : mesh["primitives"]) prim["mode"] = 1;
  CHECK(load_error(d.write("lines.glb", glb_of(s))) ==
        "has only point and line primitives (3), no triangles");
  LoadOptions o;
  o.max_faces = 3;  // the fan would be faces 3 and 4
  CHECK_THAT(load_error(d.write("limit.glb", glb_of(gltf_sample())), o),
             Catch::Contains("has 4 faces, more than the limit of 3"));
}

// ---- Writers -------------------------------------------------------------------------------

TEST_CASE("OBJ round trip keeps everything exactly", "[io]") {
  TempDir d;
  const Mesh m = attributed_cube();
  save_mesh(m, d.file("cube.obj"));
  const LoadResult r = load_mesh(d.file("cube.obj"));
  CHECK(r.report.warnings.empty());
  check_same_corners(m, r.mesh, 1e-12, true);
  CHECK(r.mesh.positions == m.positions);
  CHECK(d.entries() == std::vector<std::string>{"cube.obj"});
}

TEST_CASE("OBJ writes each group's faces together unless the face order must stay", "[io]") {
  TempDir d;
  // Groups interleaved face by face, the way an atlas's charts run through the input's order.
  Mesh m = attributed_cube();
  for (int f = 0; f < m.num_faces(); ++f) m.face_groups[f] = (f % 3 == 1) ? 0 : (f % 3 == 0 ? 2 : 1);
  const auto g_lines = [](const std::string& text) {
    std::vector<std::string> g;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
      if (line.rfind("g ", 0) == 0) g.push_back(line);
    return g;
  };

  save_mesh(m, d.file("grouped.obj"));
  CHECK(g_lines(io_test::read_bytes(d.file("grouped.obj"))) ==
        std::vector<std::string>{"g chart0", "g chart1", "g chart2"});
  const Mesh grouped = load_mesh(d.file("grouped.obj")).mesh;
  REQUIRE(grouped.num_faces() == m.num_faces());
  // The same faces, group by group in the mesh's order within each group.
  std::vector<int> expect_order;
  for (int g = 0; g < 3; ++g)
    for (int f = 0; f < m.num_faces(); ++f)
      if (m.face_groups[f] == g) expect_order.push_back(f);
  for (int i = 0; i < grouped.num_faces(); ++i) {
    const int f = expect_order[i];
    CHECK(grouped.face_groups[i] == m.face_groups[f]);
    for (int k = 0; k < 3; ++k) {
      CHECK(grouped.positions[grouped.faces[i][k]] == m.positions[m.faces[f][k]]);
      CHECK(grouped.uvs[grouped.face_uvs[i][k]] == m.uvs[m.face_uvs[f][k]]);
    }
  }

  SaveOptions keep;
  keep.write_groups = ObjGroups::FaceOrder;
  save_mesh(m, d.file("ordered.obj"), keep);
  CHECK(g_lines(io_test::read_bytes(d.file("ordered.obj"))).size() ==
        static_cast<std::size_t>(m.num_faces()));
  const Mesh ordered = load_mesh(d.file("ordered.obj")).mesh;
  check_same_corners(m, ordered, 1e-12, false);
  // Group ids are numbered by first appearance when read, so compare the partition.
  for (int f = 0; f < m.num_faces(); ++f)
    for (int h = 0; h < m.num_faces(); ++h)
      CHECK((ordered.face_groups[f] == ordered.face_groups[h]) == (m.face_groups[f] == m.face_groups[h]));

  SaveOptions none;
  none.write_groups = ObjGroups::None;
  save_mesh(m, d.file("plain.obj"), none);
  CHECK(g_lines(io_test::read_bytes(d.file("plain.obj"))).empty());
}

TEST_CASE("PLY round trips, binary and ASCII", "[io]") {
  TempDir d;
  const Mesh m = attributed_cube();
  for (bool binary : {true, false}) {
    SaveOptions o;
    o.binary_ply = binary;
    const std::string path = d.file(binary ? "b.ply" : "a.ply");
    save_mesh(m, path, o);
    CHECK(read_bytes(path).find(binary ? "format binary_little_endian" : "format ascii") !=
          std::string::npos);
    const LoadResult r = load_mesh(path);
    CHECK(r.report.warnings.empty());
    Mesh expect = m;
    expect.face_groups.clear();  // PLY has no groups
    check_same_corners(expect, r.mesh, 1e-7, false, true);
  }
}

TEST_CASE("PLY and glb keep a mesh far from the origin in shape", "[io]") {
  // Float positions a billion units out are 64 units apart: every vertex of the cube fell on
  // one point. PLY switches to doubles, glb stores positions around a translated node.
  TempDir d;
  Mesh far = attributed_cube();
  const Vec3d offset{1e9, -3e9, 2e9};
  for (auto& p : far.positions) p += offset;
  SaveOptions ascii;
  ascii.binary_ply = false;
  save_mesh(far, d.file("far.ply"));
  save_mesh(far, d.file("far_ascii.ply"), ascii);
  save_mesh(far, d.file("far.glb"));
  CHECK(read_bytes(d.file("far.ply")).find("property double x") != std::string::npos);
  for (const char* name : {"far.ply", "far_ascii.ply", "far.glb"}) {
    INFO(name);
    const LoadResult r = load_mesh(d.file(name));
    REQUIRE(r.mesh.num_faces() == far.num_faces());
    std::vector<Vec3d> got = r.mesh.positions, want = far.positions;
    auto less = [](const Vec3d& a, const Vec3d& b) {
      return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
    };
    std::sort(got.begin(), got.end(), less);
    std::sort(want.begin(), want.end(), less);
    REQUIRE(got.size() == want.size());
    for (std::size_t i = 0; i < got.size(); ++i) CHECK(norm(got[i] - want[i]) < 1e-6);
  }
  // Near the origin positions stay floats (and the glb has no translation).
  save_mesh(attributed_cube(), d.file("near.ply"));
  save_mesh(attributed_cube(), d.file("near.glb"));
  CHECK(read_bytes(d.file("near.ply")).find("property float x") != std::string::npos);
  CHECK(read_bytes(d.file("near.glb")).find("translation") == std::string::npos);
}

TEST_CASE("glb round trip, deterministic bytes", "[io]") {
  TempDir d;
  const Mesh m = attributed_cube();
  save_mesh(m, d.file("a.glb"));
  save_mesh(m, d.file("b.glb"));
  CHECK(read_bytes(d.file("a.glb")) == read_bytes(d.file("b.glb")));
  const LoadResult r = load_mesh(d.file("a.glb"));
  CHECK(r.report.warnings.empty());
  // The file splits vertices at UV seams (every side of the cube its own piece); reading
  // joins them again, so the cube comes back closed and in one piece, UVs per corner.
  CHECK(read_raw_mesh(d.file("a.glb")).positions.size() == 24);
  CHECK(r.mesh.num_vertices() == 8);
  CHECK(r.report.components == 1);
  CHECK(r.report.input_vertices == 8);
  check_same_corners(m, r.mesh, 1e-7, true);
}

TEST_CASE("glb: separate pieces touching at a face, an edge or a corner are not joined", "[io]") {
  TempDir d;
  // With UV seams on every edge (24 vertices a cube in the glb) for pieces meeting along an
  // edge or at a corner; without UVs (8 a cube) for a shared face: a seam-split cube touching
  // another at a face comes back cut open along that face (the join is undone there, as the
  // two cubes' faces on it cannot be told apart without their geometry).
  for (const Vec3d& offset : {Vec3d{1, 0, 0}, Vec3d{1, 1, 0}, Vec3d{1, 1, 1}}) {
    CAPTURE(offset.x, offset.y, offset.z);
    Mesh cube = attributed_cube();
    if (offset.y == 0) {
      cube.uvs.clear();
      cube.face_uvs.clear();
    }
    Mesh two = cube;
    const int nv = static_cast<int>(cube.positions.size()), nt = static_cast<int>(cube.uvs.size());
    for (const Vec3d& p : cube.positions) two.positions.push_back(p + offset);
    two.normals.insert(two.normals.end(), cube.normals.begin(), cube.normals.end());
    two.colors.insert(two.colors.end(), cube.colors.begin(), cube.colors.end());
    two.uvs.insert(two.uvs.end(), cube.uvs.begin(), cube.uvs.end());
    for (int f = 0; f < cube.num_faces(); ++f) {
      two.faces.push_back({cube.faces[f][0] + nv, cube.faces[f][1] + nv, cube.faces[f][2] + nv});
      if (cube.has_uvs())
        two.face_uvs.push_back(
            {cube.face_uvs[f][0] + nt, cube.face_uvs[f][1] + nt, cube.face_uvs[f][2] + nt});
      two.face_groups.push_back(cube.face_groups[f] + 6);
    }
    save_mesh(two, d.file("two.glb"));
    const LoadResult r = load_mesh(d.file("two.glb"));
    // As from an OBJ: two closed cubes, no repair needed.
    CHECK(r.report.warnings.empty());
    CHECK(r.mesh.num_vertices() == 16);
    CHECK(r.mesh.num_faces() == 24);
    CHECK(r.report.components == 2);
    CHECK(Topology(r.mesh).boundary_loops().empty());
  }
}

TEST_CASE("textures: OBJ gets an MTL, glb embeds the image", "[io]") {
  TempDir d;
  const Mesh m = attributed_cube();
  SaveOptions o;
  o.texture = "atlas.png";
  save_mesh(m, d.file("t.obj"), o);
  CHECK(d.entries() == std::vector<std::string>{"t.mtl", "t.obj"});
  const std::string obj = read_bytes(d.file("t.obj"));
  CHECK(obj.find("mtllib t.mtl\n") != std::string::npos);
  CHECK(obj.find("usemtl material0\n") != std::string::npos);
  CHECK(read_bytes(d.file("t.mtl")).find("map_Kd atlas.png\n") != std::string::npos);
  CHECK(load_mesh(d.file("t.obj")).mesh.num_faces() == 12);
  // mtllib lists names separated by spaces: the MTL of "my cube.obj" is "my_cube.mtl".
  save_mesh(m, d.file("my cube.obj"), o);
  CHECK(read_bytes(d.file("my cube.obj")).find("mtllib my_cube.mtl\n") != std::string::npos);
  CHECK(d.entries() == std::vector<std::string>{"my cube.obj", "my_cube.mtl", "t.mtl", "t.obj"});

  const std::string png = std::string(ISOCHARTS_SHARED_DATA) + "/exemplars/bricks.png";
  o.texture = png;
  save_mesh(m, d.file("t.glb"), o);
  const std::string glb = read_bytes(d.file("t.glb"));
  CHECK(glb.find(read_bytes(png)) != std::string::npos);
  CHECK(glb.find("\"image/png\"") != std::string::npos);
  CHECK(glb.find("baseColorTexture") != std::string::npos);
  check_same_corners(m, load_mesh(d.file("t.glb")).mesh, 1e-7, true);

  o.texture = d.write("not_an_image.png", "hello");
  CHECK_THROWS_WITH(save_mesh(m, d.file("u.glb"), o), Catch::Contains("not a PNG or JPEG"));
  o.texture = d.file("missing.png");
  CHECK_THROWS_AS(save_mesh(m, d.file("u.glb"), o), InputError);
  CHECK_FALSE(fs::exists(d.file("u.glb")));
}

TEST_CASE("writes are atomic and leave nothing behind on failure", "[io]") {
  TempDir d;
  const Mesh m = attributed_cube();
  CHECK_THROWS_WITH(save_mesh(m, d.file("mesh.off")), Catch::Contains("cannot write this format"));
  CHECK_THROWS_AS(save_mesh(m, d.file("no/such/dir/mesh.obj")), InputError);
  // The target is a directory: writing the temp file works, the rename fails.
  fs::create_directory(d.file("taken.ply"));
  CHECK_THROWS_WITH(save_mesh(m, d.file("taken.ply")), Catch::Contains("cannot write"));
  CHECK(d.entries() == std::vector<std::string>{"taken.ply"});
  // Overwriting replaces the old content.
  write_file_atomic(d.file("x.txt"), "old content that is longer");
  write_file_atomic(d.file("x.txt"), "new");
  CHECK(read_bytes(d.file("x.txt")) == "new");
  CHECK(d.entries() == std::vector<std::string>{"taken.ply", "x.txt"});
  // The replacement keeps the replaced file's permissions (it became 0644), alone or in a batch.
  fs::permissions(d.file("x.txt"), fs::perms::owner_read | fs::perms::owner_write);
  write_file_atomic(d.file("x.txt"), "newer");
  CHECK(fs::status(d.file("x.txt")).permissions() == (fs::perms::owner_read | fs::perms::owner_write));
  fs::permissions(d.file("x.txt"), fs::perms::owner_read | fs::perms::group_read);
  {
    OutputBatch batch;
    write_file_atomic(d.file("x.txt"), "newest");
    batch.commit();
  }
  CHECK(read_bytes(d.file("x.txt")) == "newest");
  CHECK(fs::status(d.file("x.txt")).permissions() == (fs::perms::owner_read | fs::perms::group_read));
  fs::permissions(d.file("x.txt"), fs::perms::owner_read | fs::perms::owner_write);
}

TEST_CASE("an output batch lands all its files together or none", "[io]") {
  TempDir d;
  const Mesh m = attributed_cube();
  {
    OutputBatch batch;
    save_mesh(m, d.file("a.ply"));
    write_file_atomic(d.file("b.txt"), "second");
    // Two outputs on one path: the first would be lost, so the second is refused.
    CHECK_THROWS_WITH(write_file_atomic(d.file("b.txt"), "again"), Catch::Contains("given as two outputs"));
    // Nothing is in place before the commit; a reader in the same run finds the staged file.
    CHECK_FALSE(fs::exists(d.file("a.ply")));
    CHECK(OutputBatch::open());
    CHECK(read_bytes(OutputBatch::current_path(d.file("b.txt"))) == "second");
    batch.commit();
  }
  {
    // A file the run read is never an output of it, whatever name or link leads to it.
    fs::create_symlink("a.ply", d.file("link.ply"));
    OutputBatch batch;
    load_mesh(d.file("a.ply"));
    CHECK_THROWS_WITH(save_mesh(m, d.file("a.ply")), Catch::Contains("is an input of this run"));
    CHECK_THROWS_WITH(write_file_atomic(d.file("link.ply"), "x"), Catch::Contains("is an input of this run"));
    batch.commit();
    fs::remove(d.file("link.ply"));
  }
  CHECK(load_mesh(d.file("a.ply")).mesh.num_faces() == m.num_faces());
  {
    // Outside a batch (library use) reads are not remembered.
    load_mesh(d.file("a.ply"));
    OutputBatch batch;
    save_mesh(m, d.file("a.ply"));
    batch.commit();
  }
  CHECK_FALSE(OutputBatch::open());
  CHECK(read_bytes(d.file("b.txt")) == "second");
  CHECK(d.entries() == std::vector<std::string>{"a.ply", "b.txt"});
  {
    // A failed run (no commit): its new outputs vanish, the old ones stay as they were.
    OutputBatch batch;
    write_file_atomic(d.file("b.txt"), "third");
    save_mesh(m, d.file("c.obj"));
  }
  CHECK(read_bytes(d.file("b.txt")) == "second");
  CHECK(d.entries() == std::vector<std::string>{"a.ply", "b.txt"});
  {
    // A directory in the way of an output: refused at once, or, when it appears after the
    // write, by the commit before it renames any.
    fs::create_directory(d.file("taken.txt"));
    OutputBatch batch;
    write_file_atomic(d.file("new.txt"), "x");
    CHECK_THROWS_WITH(write_file_atomic(d.file("taken.txt"), "y"), Catch::Contains("cannot write"));
    write_file_atomic(d.file("later.txt"), "z");
    fs::create_directory(d.file("later.txt"));
    CHECK_THROWS_WITH(batch.commit(), Catch::Contains("cannot write"));
  }
  CHECK(d.entries() == std::vector<std::string>{"a.ply", "b.txt", "later.txt", "taken.txt"});
  CHECK(fs::is_empty(d.file("later.txt")));
  {
    // A rename failing midway (here: the second output's directory is gone) puts back what
    // the first ones replaced, and removes what they added; it was left half-done.
    fs::create_directory(d.file("sub"));
    OutputBatch batch;
    write_file_atomic(d.file("b.txt"), "fourth");
    write_file_atomic(d.file("fresh.txt"), "new");
    write_file_atomic(d.file("sub/c.txt"), "x");
    fs::remove_all(d.file("sub"));
    CHECK_THROWS_WITH(batch.commit(), Catch::Contains("sub/c.txt: cannot write"));
  }
  CHECK(read_bytes(d.file("b.txt")) == "second");
  CHECK(d.entries() == std::vector<std::string>{"a.ply", "b.txt", "later.txt", "taken.txt"});
}

TEST_CASE("an interrupted run leaves no temporary files", "[io]") {
  TempDir d;
  const Mesh m = attributed_cube();
  write_file_atomic(d.file("old.txt"), "kept");
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      // As the program does: handlers first, then a batch whose outputs are staged when the
      // signal comes (Ctrl-C during a long run).
      remove_temporary_files_on_interrupt();
      OutputBatch batch;
      save_mesh(m, d.file("a.obj"));
      write_file_atomic(d.file("old.txt"), "replaced");
      write_image(d.file("t.png"), Image(4, 4, 3, 0.5f));
      ::raise(sig);
      ::_exit(0);  // not reached
    }
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    // The process still ends as killed by the signal, and only the old file is there.
    CHECK(WIFSIGNALED(status));
    CHECK(WTERMSIG(status) == sig);
    CHECK(d.entries() == std::vector<std::string>{"old.txt"});
    CHECK(read_bytes(d.file("old.txt")) == "kept");
  }
  // A file renamed into place is no longer tracked: nothing removes it afterwards.
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    remove_temporary_files_on_interrupt();
    write_file_atomic(d.file("done.txt"), "x");
    ::raise(SIGTERM);
    ::_exit(0);
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  CHECK(d.entries() == std::vector<std::string>{"done.txt", "old.txt"});
}

TEST_CASE("outputs are written through symbolic links, never over special files", "[io]") {
  TempDir d;
  fs::create_directory(d.file("real"));
  fs::create_symlink("real/a.txt", d.file("a.txt"));
  write_file_atomic(d.file("a.txt"), "through");
  CHECK(fs::is_symlink(d.file("a.txt")));
  CHECK(read_bytes(d.file("real/a.txt")) == "through");
  CHECK(output_target(d.file("a.txt")) == d.file("real/a.txt"));
  // A FIFO (like a device) would be replaced by the rename: refused, and left as it was.
  REQUIRE(::mkfifo(d.file("pipe").c_str(), 0600) == 0);
  fs::create_symlink("pipe", d.file("via_link.txt"));
  CHECK_THROWS_WITH(write_file_atomic(d.file("pipe"), "x"), Catch::Contains("not a regular file"));
  CHECK_THROWS_WITH(write_file_atomic(d.file("via_link.txt"), "x"), Catch::Contains("not a regular file"));
  CHECK(fs::is_fifo(d.file("pipe")));
  CHECK(d.entries() == std::vector<std::string>{"a.txt", "pipe", "real", "via_link.txt"});
}
