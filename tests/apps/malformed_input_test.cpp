// The CLI on a corpus of malformed and repairable inputs: every bad file is exit code 2 and
// exactly one clear line on stderr, naming the file and the problem, with no output left.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "isochart/image.h"
#include "isochart/io_test_util.h"

using namespace io_test;

namespace {

// Runs the CLI with stdout discarded and stderr saved; returns the exit code.
int run_cli(const std::string& args, const fs::path& err, const std::string& env = "") {
  const std::string cmd = (env.empty() ? "" : env + " ") + "'" + ISOCHARTS_CLI + "' " + args +
                          " > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Deterministic pseudo-random bytes (no global rand()).
std::string noise(std::size_t n, std::uint32_t seed) {
  std::string s(n, '\0');
  for (auto& c : s) {
    seed = seed * 1664525u + 1013904223u;
    c = static_cast<char>(seed >> 24);
  }
  return s;
}

template <typename T>
std::string le(T v) {
  return Bytes().put(v).data;
}

const std::string kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
const std::string kTetraObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

std::string binary_ply_header(int vertices, int faces) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(faces) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string binary_ply_triangle(float bad) {
  std::string s = binary_ply_header(3, 1);
  for (float x : {0.0f, 0.0f, 0.0f, 1.0f, bad, 0.0f, 0.0f, 1.0f, 0.0f}) s += le(x);
  s += le<std::uint8_t>(3) + le<std::int32_t>(0) + le<std::int32_t>(1) + le<std::int32_t>(2);
  return s;
}

std::string gltf_with_count(int count) {
  std::string bin;
  for (float x : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f}) bin += le(x);
  const nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
      {"buffers", {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}}},
      {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
      {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", count}, {"type", "VEC3"}}}}};
  return doc.dump();
}

struct Case {
  std::string file;     // input name inside its own directory
  std::string content;  // written as is
  std::string word;     // the problem, as stderr must name it
  enum Kind { File, Missing, Directory } kind = File;
};

std::vector<Case> malformed_corpus() {
  std::vector<Case> c;
  c.push_back({"missing.obj", "", "cannot open file", Case::Missing});
  c.push_back({"folder.obj", "", "is a directory", Case::Directory});
  c.push_back({"mesh.stl", "solid x\nendsolid x\n", "unknown mesh format"});
  c.push_back({"no_extension", kTetraObj, "no file extension"});
  c.push_back({"empty.obj", "", "file is empty"});
  c.push_back({"garbage.obj", "\x89PNG\r\n" + noise(4000, 1), "is not an OBJ statement"});
  c.push_back({"garbage_nul.obj", std::string("v 1 2 3\n\0\0\x01garbage", 19), "unexpected binary data"});
  c.push_back({"garbage.ply", noise(4000, 2), "not a PLY file"});
  c.push_back({"garbage.off", "OFX 12 garbage\n" + noise(100, 3), "expected an OFF header"});
  c.push_back({"truncated.obj", kTriangleObj + "v 0 0", "expected 3 coordinates after 'v'"});
  c.push_back({"truncated.off",
               "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 # a comment long enough to pass the size check\n",
               "(truncated)"});
  c.push_back(
      {"truncated_ascii.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n\n\n\n\n\n\n\n\n",
       "vertex 2: unexpected end of file (truncated)"});
  c.push_back({"truncated_binary.ply",
               binary_ply_triangle(0).substr(0, binary_ply_header(3, 1).size() + 36 + 5),
               "face 0: list of 3 values runs past the end of the file (truncated)"});
  c.push_back({"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "coordinate 'nan' is not finite"});
  c.push_back({"inf.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", "value 'inf' is not finite"});
  c.push_back({"nan_binary.ply", binary_ply_triangle(std::nanf("")), "vertex 1 has a non-finite coordinate"});
  c.push_back({"inf_binary.ply", binary_ply_triangle(-INFINITY),
               "vertex 1 has a non-finite coordinate (1, -inf, 0)"});
  c.push_back({"index_range.obj", kTriangleObj + "f 1 2 9\n", "vertex index 9 is out of range"});
  c.push_back({"index_zero.obj", kTriangleObj + "f 0 1 2\n", "vertex index 0 is invalid"});
  c.push_back(
      {"negative_index.obj", kTriangleObj + "f -1 -2 -9\n", "relative vertex index -9 reaches before"});
  c.push_back(
      {"index_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "vertex index 3 is out of range"});
  c.push_back(
      {"index_range.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
       "face 0 refers to vertex 7"});
  c.push_back({"two_corners.obj", kTriangleObj + "f 1 2\n", "face has 2 corners"});
  c.push_back({"two_corners.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "face has 2 corners"});
  c.push_back(
      {"huge_counts.off", "OFF\n2000000000 2000000000 0\n0 0 0\n", "header declares 2000000000 vertices"});
  c.push_back(
      {"huge_counts.ply", binary_ply_header(2000000000, 5), "header declares 2000000000 vertex elements"});
  c.push_back(
      {"huge_list.ply",
       binary_ply_header(3, 1) + std::string(36, '\0') + le<std::uint8_t>(255) + std::string(12, '\0'),
       "list of 255 values runs past"});
  c.push_back({"bad_format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown PLY format"});
  c.push_back({"no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", "no end_header line"});
  c.push_back({"bad_counts.off", "OFF\nthree 1 0\n", "expected the vertex, face and edge counts"});
  c.push_back({"truncated.glb", "glTF" + le<std::uint32_t>(2) + le<std::uint32_t>(4000) + noise(40, 4),
               "invalid glTF"});
  c.push_back({"bad_json.gltf", "{ \"asset\": { \"version\": \"2.0\" ", "invalid glTF"});
  c.push_back({"non_utf8.gltf", "{ \"asset\xff\xfe\": 1 }", "invalid glTF"});
  c.push_back({"accessor.gltf", gltf_with_count(30), "runs past the end of its bufferView"});
  c.push_back({"all_degenerate.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\nf 1 1 2\n", "no faces left"});
  c.push_back({"no_faces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "mesh has no faces"});
  c.push_back({"points_only.obj", kTriangleObj, "mesh has no faces"});
  c.push_back({"non_utf8.obj", kTriangleObj + "\xc3\x28\xff 1 2\nf 1 2 3\n",
               "'\\xc3(\\xff' is not an OBJ statement"});
  c.push_back({"long_line.obj", kTriangleObj + std::string(3'000'000, 'x') + "\nf 1 2 3\n",
               "is not an OBJ statement"});
  std::string many = "v";
  for (int i = 0; i < 500'000; ++i) many += " 1";
  c.push_back({"long_vertex.obj", many + "\n", "too many numbers after 'v'"});
  return c;
}

// The built-in sphere's atlas written to `atlas`, and its text with every line passed through
// `edit` (which may change the line, or return false to drop it).
std::string edited_sphere_atlas(const fs::path& atlas, const fs::path& err,
                                const std::function<bool(std::string&)>& edit) {
  REQUIRE(run_cli("-q atlas builtin:sphere -o '" + atlas.string() + "'", err) == 0);
  std::istringstream in(read_bytes(atlas));
  std::string text, line;
  while (std::getline(in, line))
    if (edit(line)) text += line + "\n";
  return text;
}

}  // namespace

TEST_CASE("malformed inputs: exit 2, one clear line, nothing left behind", "[cli]") {
  TempDir tmp("malformed");
  const std::vector<Case> corpus = malformed_corpus();
  REQUIRE(corpus.size() >= 25);
  int index = 0;
  for (const Case& c : corpus) {
    INFO(c.file);
    const fs::path dir = tmp.path / ("case" + std::to_string(index++));
    fs::create_directories(dir);
    const fs::path input = dir / c.file;
    if (c.kind == Case::File) write_bytes(input, c.content);
    if (c.kind == Case::Directory) fs::create_directory(input);
    const std::vector<std::string> before = entries(dir);
    const fs::path err = tmp.path / ("stderr" + std::to_string(index) + ".txt");
    const int code =
        run_cli("info '" + input.string() + "' --report '" + (dir / "OUT.json").string() + "'", err);
    const std::string text = read_bytes(err);
    CHECK(code == 2);
    CHECK(std::count(text.begin(), text.end(), '\n') == 1);
    CHECK(text.back() == '\n');
    CHECK_THAT(text, Catch::StartsWith("isocharts: error: "));
    CHECK_THAT(text, Catch::Contains(c.file));
    CHECK_THAT(text, Catch::Contains(c.word));
    CHECK(text.size() < 400);       // a message, not a dump of the input
    CHECK(entries(dir) == before);  // no OUT.json, no temporary file
  }
}

TEST_CASE("repairable inputs: warnings and exit 0, or exit 2 with --no-repair", "[cli]") {
  TempDir tmp("repairable");
  struct Repairable {
    std::string file, content;
    std::vector<std::string> warnings;
  };
  const std::vector<Repairable> cases = {
      {"quad.obj",
       "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
       {"triangulated 1 polygon into 2 triangles"}},
      {"degenerate.obj", kTetraObj + "f 1 1 2\n", {"removed 1 degenerate face"}},
      {"duplicate.off",
       "OFF\n4 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 3 2 1\n",
       {"removed 1 duplicate face"}},
      {"unreferenced.obj", kTetraObj + "v 5 5 5\n", {"dropped 1 unreferenced vertex"}},
      {"flipped.obj",
       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
       {"reoriented 1 face"}},
      {"touching.obj",
       kTetraObj + "v 0 -1 0\nv 0 0 -1\nf 1 5 2\nf 1 2 6\nf 1 6 5\nf 2 5 6\n",
       {"split 1 non-manifold edge"}},
      {"several.obj",
       "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\nf 1 2 3 4\nf 1 2 2\n",
       {"triangulated 1 polygon", "removed 1 degenerate face", "dropped 1 unreferenced vertex"}},
  };
  int index = 0;
  for (const auto& c : cases) {
    INFO(c.file);
    const fs::path dir = tmp.path / ("case" + std::to_string(index++));
    fs::create_directories(dir);
    const fs::path input = dir / c.file, out = dir / "OUT.json", err = dir / "stderr.txt";
    write_bytes(input, c.content);

    CHECK(run_cli("info '" + input.string() + "' --report '" + out.string() + "'", err) == 0);
    std::istringstream lines(read_bytes(err));
    std::vector<std::string> got;
    for (std::string line; std::getline(lines, line);) got.push_back(line);
    REQUIRE(got.size() == c.warnings.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      CHECK_THAT(got[i], Catch::StartsWith("isocharts: warning: " + input.string() + ": "));
      CHECK_THAT(got[i], Catch::Contains(c.warnings[i]));
    }
    REQUIRE(fs::exists(out));
    const nlohmann::json report = nlohmann::json::parse(read_bytes(out));
    CHECK(report["warnings"].size() == c.warnings.size());
    fs::remove(out);

    CHECK(run_cli("info --no-repair '" + input.string() + "' --report '" + out.string() + "'", err) == 2);
    const std::string text = read_bytes(err);
    CHECK(std::count(text.begin(), text.end(), '\n') == 1);
    CHECK_THAT(text, Catch::StartsWith("isocharts: error: " + input.string() + ": "));
    CHECK_THAT(text, Catch::Contains("it needs repair, which is turned off (--no-repair)"));
    CHECK_FALSE(fs::exists(out));
  }
}

TEST_CASE("info says a Moebius strip is not orientable", "[cli]") {
  // It is cut open to be oriented, so its counts read as a disk's, with only a repair warning.
  TempDir tmp("moebius");
  const fs::path mesh = tmp.path / "m.obj", out = tmp.path / "r.json", err = tmp.path / "err.txt";
  {
    const int n = 24;
    std::ofstream f(mesh);
    for (int i = 0; i < n; ++i) {
      const double t = 2 * M_PI * i / n;
      for (int w : {-1, 1})
        f << "v " << (2 + 0.5 * w * std::cos(t / 2)) * std::cos(t) << " "
          << (2 + 0.5 * w * std::cos(t / 2)) * std::sin(t) << " " << 0.5 * w * std::sin(t / 2) << "\n";
    }
    for (int i = 0; i < n; ++i) {
      const int a = 2 * i + 1, b = a + 1;
      // Round the strip once, its two edges trade places.
      const int c = i + 1 < n ? a + 2 : 2, d = i + 1 < n ? b + 2 : 1;
      f << "f " << a << " " << c << " " << d << "\nf " << a << " " << d << " " << b << "\n";
    }
  }
  REQUIRE(run_cli("info '" + mesh.string() + "' --report '" + out.string() + "'", err) == 0);
  nlohmann::json j = nlohmann::json::parse(read_bytes(out));
  CHECK(j["orientable"] == false);
  CHECK(j["cut_edges"].get<int>() >= 1);
  REQUIRE(run_cli("info builtin:torus --report '" + out.string() + "'", err) == 0);
  j = nlohmann::json::parse(read_bytes(out));
  CHECK(j["orientable"] == true);
  CHECK(j["cut_edges"] == 0);
}

TEST_CASE("a triangle soup is named, and --weld joins it", "[cli]") {
  // An OBJ written one triangle at a time read as one piece per triangle (a torus: 1024 charts)
  // without a word.
  TempDir tmp("soup");
  const fs::path soup = tmp.path / "soup.obj", out = tmp.path / "r.json", err = tmp.path / "err.txt";
  std::ofstream(soup) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 0 0\nv 1 1 0\nv -0 1 0\nf 1 2 3\nf 4 5 6\n";
  REQUIRE(run_cli("info '" + soup.string() + "' --report '" + out.string() + "'", err) == 0);
  nlohmann::json j = nlohmann::json::parse(read_bytes(out));
  CHECK(j["components"] == 2);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("2 vertices lie at the position of another vertex without being "
                             "joined to it, so the surface is cut there (--weld joins them)"));
  REQUIRE(run_cli("--weld info '" + soup.string() + "' --report '" + out.string() + "'", err) == 0);
  j = nlohmann::json::parse(read_bytes(out));
  CHECK(j["components"] == 1);
  CHECK(j["boundary_loops"] == 1);
  CHECK(read_bytes(err).empty());
}

TEST_CASE("stats reads our atlas of a repaired non-manifold input as the surface it is", "[cli]") {
  // A cube with a fin on one edge: the atlas splits that edge, leaving two vertices at each of
  // its ends. Joining them again for stats rebuilt the edge of three faces: repair warnings,
  // and --no-repair refused the file that info accepts.
  TempDir tmp("fin");
  const fs::path mesh = tmp.path / "fin.obj", atlas = tmp.path / "fin_atlas.obj", err = tmp.path / "err.txt";
  std::ofstream(mesh)
      << "v 0 0 0\nv 0 0 1\nv 0 1 0\nv 0 1 1\nv 1 0 0\nv 1 0 1\nv 1 1 0\nv 1 1 1\nv -1 0 0.5\n"
         "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\n"
         "f 1 7 3\nf 2 4 8\nf 2 8 6\nf 1 2 9\n";
  REQUIRE(run_cli("atlas '" + mesh.string() + "' -o '" + atlas.string() + "'", err) == 0);
  CHECK(run_cli("--no-repair info '" + atlas.string() + "'", err) == 0);
  CHECK(run_cli("--no-repair stats '" + atlas.string() + "'", err) == 0);
  CHECK(read_bytes(err).empty());
  CHECK(run_cli("stats '" + atlas.string() + "'", err) == 0);
  CHECK(read_bytes(err).empty());
}

TEST_CASE("a vertex used only by a face dropped as degenerate is not called a cut", "[cli]") {
  // Vertex 4 sits on vertex 3 and only the zero-area face 1 3 4 uses it: once that face is
  // dropped, nothing is cut there.
  TempDir tmp("coincident");
  const fs::path mesh = tmp.path / "c.obj", err = tmp.path / "err.txt";
  std::ofstream(mesh) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 1 1 0\nf 1 2 3\nf 1 3 4\n";
  REQUIRE(run_cli("info '" + mesh.string() + "'", err) == 0);
  const std::string e = read_bytes(err);
  CHECK_THAT(
      e, Catch::Contains("removed 1 degenerate face") && Catch::Contains("dropped 1 unreferenced vertex"));
  CHECK(e.find("without being joined") == std::string::npos);
}

TEST_CASE("a double-sided card keeps its back, and its atlas reads back without a soup warning", "[cli]") {
  TempDir tmp("card");
  const fs::path card = tmp.path / "card.obj", atlas = tmp.path / "atlas.obj", out = tmp.path / "r.json",
                 err = tmp.path / "err.txt";
  std::ofstream(card) << "v 0 0 0\nv 1 0 0\nv 1 1 0.2\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 3 2 1\nf 4 3 1\n";
  REQUIRE(run_cli("info '" + card.string() + "' --report '" + out.string() + "'", err) == 0);
  nlohmann::json j = nlohmann::json::parse(read_bytes(out));
  CHECK(j["double_sided_faces"] == 2);
  CHECK(j["duplicate_faces"] == 0);
  CHECK(j["components"] == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("card.obj: gave the back side of 2 faces repeated in reverse"));
  REQUIRE(run_cli("atlas '" + card.string() + "' -o '" + atlas.string() + "' --report '" + out.string() + "'",
                  err) == 0);
  // Written out, the two sides are coincident vertices by design, not a triangle soup.
  REQUIRE(run_cli("stats '" + atlas.string() + "' --report '" + out.string() + "'", err) == 0);
  CHECK(nlohmann::json::parse(read_bytes(out))["charts"] == 2);
  CHECK(read_bytes(err).find("without being joined") == std::string::npos);
}

TEST_CASE("the report is written atomically next to a good input", "[cli]") {
  TempDir tmp("report");
  const fs::path input = tmp.path / "tetra.obj", out = tmp.path / "report.json", err = tmp.path / "err.txt";
  write_bytes(input, kTetraObj);
  REQUIRE(run_cli("info '" + input.string() + "' --json --report '" + out.string() + "'", err) == 0);
  CHECK(read_bytes(err).empty());
  const nlohmann::json j = nlohmann::json::parse(read_bytes(out));
  CHECK(j["faces"] == 4);
  CHECK(j["used_triangles"] == 4);
  CHECK(j["closed"] == true);
  CHECK(entries(tmp.path) == std::vector<std::string>{"err.txt", "report.json", "tetra.obj"});
  // An unwritable report path is a clear error too.
  CHECK(run_cli("info '" + input.string() + "' --report '" + (tmp.path / "no/dir/r.json").string() + "'",
                err) == 2);
  CHECK_THAT(read_bytes(err), Catch::StartsWith("isocharts: error: ") && Catch::Contains("cannot write"));
}

TEST_CASE("a missing or broken image module is a clear error, and nothing is written", "[cli]") {
  TempDir tmp("image_module");
  const fs::path err = tmp.path / "err.txt", out = tmp.path / "view.png",
                 bogus = tmp.path / "not_a_module.so";
  write_bytes(bogus, "not a shared library\n");
  for (const fs::path& module : {bogus, tmp.path / "missing.so"}) {
    INFO(module.string());
    CHECK(run_cli("render builtin:sphere -o '" + out.string() + "'", err,
                  "ISOCHARTS_IMAGE_MODULE='" + module.string() + "'") == 1);
    const std::string text = read_bytes(err);
    CHECK_THAT(text, Catch::StartsWith("isocharts: error: image I/O is unavailable") &&
                         Catch::Contains(module.string()));
    CHECK(std::count(text.begin(), text.end(), '\n') == 1);
    CHECK_FALSE(fs::exists(out));
  }
  // Mesh work needs no image module at all.
  CHECK(run_cli("info builtin:sphere", err, "ISOCHARTS_IMAGE_MODULE='" + bogus.string() + "'") == 0);
}

TEST_CASE("a run that fails at its last output leaves none of its outputs", "[cli]") {
  TempDir tmp("partial");
  const fs::path err = tmp.path / "err.txt";
  // The atlas OBJ is fine, its layout PNG cannot be written (no such directory): no OBJ either.
  CHECK(run_cli("-q atlas builtin:sphere -o '" + (tmp.path / "a.obj").string() + "' --png '" +
                    (tmp.path / "no/dir/a.png").string() + "'",
                err) == 2);
  CHECK_THAT(read_bytes(err), Catch::StartsWith("isocharts: error: ") && Catch::Contains("a.png"));
  // The report's place is taken by a directory: the OBJ written before it is not left either.
  fs::create_directory(tmp.path / "r.json");
  CHECK(run_cli("-q atlas builtin:sphere -o '" + (tmp.path / "b.obj").string() + "' --report '" +
                    (tmp.path / "r.json").string() + "'",
                err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("r.json"));
  CHECK(entries(tmp.path) == std::vector<std::string>{"err.txt", "r.json"});
  CHECK(fs::is_empty(tmp.path / "r.json"));
}

TEST_CASE("an output over an input of the run, or two outputs on one path, are refused", "[cli]") {
  TempDir tmp("overwrite");
  const fs::path err = tmp.path / "err.txt", mesh = tmp.path / "s.obj";
  REQUIRE(run_cli("-q atlas builtin:sphere -o '" + mesh.string() + "'", err) == 0);
  const std::string before = read_bytes(mesh);
  for (const std::string& args : {"atlas '" + mesh.string() + "' -o '" + mesh.string() + "'",
                                  "--report '" + mesh.string() + "' info '" + mesh.string() + "'",
                                  "render '" + mesh.string() + "' --uv-layout -o '" +
                                      (tmp.path / "l.png").string() + "' --report '" + mesh.string() + "'"}) {
    CAPTURE(args);
    CHECK(run_cli("-q " + args, err) == 2);
    CHECK_THAT(read_bytes(err), Catch::Equals("isocharts: error: " + mesh.string() +
                                              ": cannot write: it is an input of this run and would be "
                                              "overwritten\n"));
    CHECK(read_bytes(mesh) == before);
  }
  // The input reached by another spelling or a hard link; found before the mesh is loaded.
  fs::create_hard_link(mesh, tmp.path / "hard.obj");
  for (const std::string& out : {(tmp.path / "." / "s.obj").string(), (tmp.path / "hard.obj").string()}) {
    CAPTURE(out);
    CHECK(run_cli("synth '" + mesh.string() + "' -o '" + out + "' --levels 64,32", err) == 2);
    CHECK_THAT(read_bytes(err), Catch::Equals("isocharts: error: " + out +
                                              ": cannot write: it is an input of this run and would be "
                                              "overwritten\n"));
  }
  fs::remove(tmp.path / "hard.obj");
  CHECK(read_bytes(mesh) == before);
  const fs::path twice = tmp.path / "t.obj";
  CHECK(run_cli("-q atlas builtin:sphere -o '" + twice.string() + "' -o '" + twice.string() + "'", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Equals("isocharts: error: " + twice.string() +
                                            ": cannot write: given as two outputs of this run\n"));
  const std::string other = (tmp.path / "sub" / ".." / "t.obj").string();
  fs::create_directory(tmp.path / "sub");
  CHECK(run_cli("atlas builtin:sphere -o '" + twice.string() + "' --report '" + other + "'", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Equals("isocharts: error: " + other +
                                            ": cannot write: given as two outputs of this run\n"));
  fs::remove(tmp.path / "sub");
  CHECK(entries(tmp.path) == std::vector<std::string>{"err.txt", "s.obj"});
}

TEST_CASE("render draws the texture a mesh file carries or names, unless --shaded", "[cli]") {
  // synth's outputs were drawn untextured unless their texture was named again.
  TempDir tmp("own_texture");
  const fs::path err = tmp.path / "err.txt", out = tmp.path / "r.json";
  REQUIRE(run_cli("-q synth builtin:sphere -o '" + (tmp.path / "s.glb").string() +
                      "' --levels 32 --atlas-size 64",
                  err) == 0);
  auto render = [&](const std::string& mesh, const std::string& extra, const std::string& png) {
    REQUIRE(run_cli("render '" + (tmp.path / mesh).string() + "' -o '" + (tmp.path / png).string() +
                        "' --views 1 --report '" + out.string() + "'" + extra,
                    err) == 0);
    return nlohmann::json::parse(read_bytes(out));
  };
  nlohmann::json j = render("s.obj", "", "obj.png");
  CHECK(j["mode"] == "textured");
  CHECK(j["texture"] == (tmp.path / "s.png").string());  // map_Kd, beside the MTL
  j = render("s.obj", " --texture '" + (tmp.path / "s.png").string() + "'", "given.png");
  CHECK(read_bytes(tmp.path / "obj.png") == read_bytes(tmp.path / "given.png"));
  j = render("s.glb", "", "glb.png");
  CHECK(j["mode"] == "textured");
  CHECK(j["texture"] == "embedded");
  j = render("s.obj", " --shaded", "plain.png");
  CHECK(j["mode"] == "shaded");
  CHECK(read_bytes(tmp.path / "plain.png") != read_bytes(tmp.path / "obj.png"));
  // The decoded copy of the embedded image is gone; a texture named but missing is a warning.
  for (const auto& e : fs::directory_iterator(tmp.path))
    CHECK(e.path().filename().string().find(".tmp-") == std::string::npos);
  fs::remove(tmp.path / "s.png");
  j = render("s.obj", "", "missing.png");
  CHECK(j["mode"] == "shaded");
  CHECK_THAT(read_bytes(err), Catch::Contains("s.obj: its texture " + (tmp.path / "s.png").string() +
                                              " cannot be read (image file not found)"));
  CHECK(run_cli("render builtin:sphere -o '" + (tmp.path / "x.png").string() + "' --shaded --charts", err) ==
        2);
  CHECK_THAT(read_bytes(err), Catch::Contains("--charts, --shaded and --texture are exclusive"));
}

TEST_CASE("a corrupt texture is one line: the image library's own message is not printed", "[cli]") {
  TempDir tmp("corrupt_png");
  const fs::path err = tmp.path / "err.txt", mesh = tmp.path / "s.obj", png = tmp.path / "t.png";
  REQUIRE(run_cli("-q atlas builtin:sphere -o '" + mesh.string() + "'", err) == 0);
  REQUIRE(run_cli("-q render builtin:creature -o '" + png.string() + "' --views 1", err) == 0);
  std::string bytes = read_bytes(png);
  for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 200; ++i) bytes[i] = 0x55;  // inside IDAT
  write_bytes(png, bytes);
  CHECK(run_cli("render '" + mesh.string() + "' --texture '" + png.string() + "' -o '" +
                    (tmp.path / "v.png").string() + "'",
                err) == 2);
  const std::string text = read_bytes(err);
  CHECK(std::count(text.begin(), text.end(), '\n') == 1);  // libpng used to print "libpng error: ..." first
  CHECK_THAT(text, Catch::StartsWith("isocharts: error: " + png.string() + ": cannot read image"));
}

TEST_CASE("bad commands and options get one line naming what is wrong", "[cli]") {
  TempDir tmp("badopts");
  const fs::path err = tmp.path / "err.txt";
  const fs::path out = tmp.path / "a.obj";
  auto line = [&] { return read_bytes(err); };
  CHECK(run_cli("--threads 2 bogus x", err) == 2);
  CHECK_THAT(line(),
             Catch::Equals("isocharts: error: unknown command 'bogus' (commands: info, stats, render, "
                           "atlas, remesh, psnr, synth, bench, sae)\n"));
  CHECK(run_cli("", err) == 2);
  CHECK_THAT(line(), Catch::StartsWith("isocharts: error: no command given"));
  // A seed that cannot be repeated from what was typed (wrapped or saturated) is refused.
  for (const std::string seed : {"-1", "18446744073709551616", "1e3", "0x10"}) {
    CHECK(run_cli("atlas builtin:sphere -o '" + out.string() + "' --seed " + seed, err) == 2);
    CHECK_THAT(line(), Catch::Equals("isocharts: error: --seed: expected an integer from 0 to "
                                     "18446744073709551615, got '" +
                                     seed + "'\n"));
  }
  CHECK(run_cli("synth builtin:sphere -o '" + (tmp.path / "s.glb").string() + "' --scale 0", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --scale: expected a positive number, got '0'\n"));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --levels 64,32,64", err) ==
        2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --levels: 64 is given twice\n"));
  // Values CLI11 cannot read, or outside a range, in our words (it said "Could not convert:
  // --width = abc" and, for a range, "Value 12x not in range").
  const std::string atlas = "atlas builtin:sphere -o '" + out.string() + "'";
  CHECK(run_cli(atlas + " --width abc", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --width: expected an integer, got 'abc'\n"));
  CHECK(run_cli(atlas + " --width 99999999999999", err) == 2);
  CHECK_THAT(line(),
             Catch::Equals("isocharts: error: --width: 99999999999999 is out of range for an integer\n"));
  CHECK(run_cli(atlas + " --max-l2 1.1x", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --max-l2: expected a number, got '1.1x'\n"));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --res 12x", err) == 2);
  CHECK_THAT(line(),
             Catch::Equals("isocharts: error: --res: expected an integer from 4 to 2048, got '12x'\n"));
  // 2 and 3 were allowed, and always failed once the atlas was built: one chart and its gutter need 4.
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --levels 64,3", err) == 2);
  CHECK_THAT(line(),
             Catch::Equals("isocharts: error: --levels: expected an integer from 4 to 2048, got '3'\n"));
  CHECK(run_cli(atlas + " --png-size 5", err) == 2);
  CHECK_THAT(line(),
             Catch::Equals("isocharts: error: --png-size: expected an integer from 16 to 2896, got '5'\n"));
  // Options that would do nothing, and empty values that would skip an output, are refused.
  CHECK(run_cli(atlas + " --png-size 64", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --png-size goes with --png\n"));
  CHECK(run_cli(atlas + " --beta 0.5", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --beta goes with --signal\n"));
  CHECK(run_cli(atlas + " --report ''", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --report: expected a value, got ''\n"));
  CHECK(run_cli(atlas + " --png=", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --png: expected a value, got ''\n"));
  // An option taken as the value before it: the run went on and wrote a file named after it.
  CHECK(run_cli(atlas + " --report --threads=2", err) == 2);
  CHECK_THAT(line(),
             Catch::Equals("isocharts: error: --report: got '--threads=2', which is an option, not a value "
                           "(write ./--threads=2 for a file of that name)\n"));
  CHECK_FALSE(fs::exists("--threads=2"));
  CHECK(run_cli("remesh builtin:sphere -o --png", err) == 2);
  CHECK_THAT(line(), Catch::StartsWith("isocharts: error: --output: got '--png', which is an option"));
  // An output in a directory that does not exist is refused before the work, not after it.
  const std::string nodir = (tmp.path / "no_such_dir").string();
  CHECK(run_cli("atlas builtin:sphere -o '" + nodir + "/a.obj'", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: " + nodir + "/a.obj: cannot write: directory " + nodir +
                                   " does not exist\n"));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --report '" + nodir +
                    "/r.json'",
                err) == 2);
  CHECK_THAT(line(), Catch::Contains("r.json: cannot write: directory"));
  // A directory no file can be made in, though access() lets root write there: found before
  // the work too (the image writers found it after, exit 1).
  CHECK(run_cli("render builtin:sphere -o /sys/isocharts_test_view.png", err) == 2);
  CHECK_THAT(line(), Catch::StartsWith("isocharts: error: /sys/isocharts_test_view.png: cannot write"));
  CHECK(run_cli("stats builtin:sphere --aspect 0", err) == 2);
  CHECK_THAT(
      line(),
      Catch::Equals("isocharts: error: --aspect: expected a number from 0.00006104 to 16384, got '0'\n"));
  // The bound quoted is inside the range (1/16384 printed as 0.000061 was refused when typed back).
  CHECK(run_cli("stats builtin:sphere --aspect 0.000061", err) == 2);
  {
    const fs::path atlas_file = tmp.path / "aspect_atlas.obj";
    REQUIRE(run_cli("atlas builtin:sphere -o '" + atlas_file.string() + "'", err) == 0);
    CHECK(run_cli("stats '" + atlas_file.string() + "' --aspect 0.00006104", err) == 0);
    CHECK(run_cli("stats '" + atlas_file.string() + "' --aspect 16384", err) == 0);
    fs::remove(atlas_file);
  }
  {
    // The help writes the range as the error does (it said 6.10352e-05).
    const fs::path help = tmp.path / "help.txt";
    CHECK(run_cli("stats --help | tee '" + help.string() + "'", err) == 0);
    CHECK_THAT(read_bytes(help), Catch::Contains("--aspect FLOAT:FLOAT in [0.00006104 - 16384]"));
    fs::remove(help);  // the checks below count what a failing command leaves behind
  }
  CHECK(run_cli("render builtin:sphere -o '" + (tmp.path / "v.png").string() + "' --width 4096 --height 4096",
                err) == 2);
  CHECK_THAT(line(), Catch::StartsWith("isocharts: error: --width/--height/--supersample: 4096x4096 pixels"));
  // Options that would be ignored are refused.
  CHECK(run_cli("render builtin:sphere -o '" + (tmp.path / "v.jpg").string() + "' --transparent", err) == 2);
  CHECK_THAT(line(), Catch::StartsWith("isocharts: error: --transparent needs an image with alpha"));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --no-psnr --psnr-samples 5",
                err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --psnr-samples does nothing with --no-psnr\n"));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --signal-use full", err) ==
        2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --signal-use goes with --signal\n"));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --res 32 --res 64", err) ==
        2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --res: given 2 times; give it once\n"));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() +
                    "' --no-optimize --shorter-diagonals",
                err) == 2);
  CHECK_THAT(line(),
             Catch::StartsWith("isocharts: error: --shorter-diagonals does nothing with --no-optimize"));
  CHECK(run_cli("remesh builtin:torus -o '" + (tmp.path / "r.ply").string() + "' --samples 16 --no-psnr",
                err) == 2);
  CHECK_THAT(line(),
             Catch::Contains("builtin:torus: --samples 16 is too few for this atlas's charts: pack: "));
  CHECK(run_cli("remesh builtin:sphere -o '" + (tmp.path / "r.ply").string() + "' --atlas-aspect 2", err) ==
        2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --atlas-aspect goes with --atlas\n"));
  // Accepted and doing nothing: the layout is always drawn with its charts coloured.
  CHECK(run_cli("render builtin:sphere --uv-layout --charts -o '" + (tmp.path / "v.png").string() + "'",
                err) == 2);
  CHECK_THAT(
      line(),
      Catch::Contains(
          "--uv-layout draws the atlas itself, its charts coloured; it takes no --shaded or --charts"));
  const std::string bench =
      "bench builtin:sphere --methods isochart --res 16 --sweep none --no-plots --out '" +
      (tmp.path / "b").string() + "'";
  CHECK(run_cli(bench + " --atlas-aspect 2", err) == 2);
  CHECK_THAT(line(), Catch::Contains("--atlas-aspect goes with an external atlas"));
  CHECK(run_cli("bench builtin:sphere --methods isochart --sweep 1.2 --sweep-max-faces 0 --out '" +
                    (tmp.path / "b").string() + "'",
                err) == 2);
  CHECK_THAT(line(), Catch::Contains("--sweep-max-faces 0 sweeps no mesh; give --sweep none for no sweep"));
  // --out makes its directory, not a tree of them under a mistyped parent.
  CHECK(run_cli("bench builtin:sphere --methods isochart --res 16 --sweep none --no-plots --out '" +
                    (tmp.path / "no_such" / "b").string() + "'",
                err) == 2);
  CHECK_THAT(line(), Catch::Contains("cannot write: directory " + (tmp.path / "no_such").string() +
                                     " does not exist"));
  CHECK_FALSE(fs::exists(tmp.path / "no_such"));
  CHECK(run_cli("render builtin:sphere -o '" + (tmp.path / "v.png").string() + "' --aspect 2", err) == 2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --aspect goes with --uv-layout\n"));
  // Quiet won silently over verbose.
  CHECK(run_cli("-q -v info builtin:sphere", err) == 2);
  CHECK_THAT(line(),
             Catch::Contains("--quiet excludes --verbose") || Catch::Contains("--verbose excludes --quiet"));
  // A UV layout is always drawn at 2x2: --supersample did nothing there, and the size check
  // used it (4096² at --supersample 1 passed, then the mesh was blamed).
  CHECK(
      run_cli("render builtin:sphere -o '" + (tmp.path / "v.png").string() + "' --uv-layout --supersample 1",
              err) == 2);
  CHECK_THAT(line(),
             Catch::Equals("isocharts: error: --uv-layout always draws with 2x2 supersampling; it takes no "
                           "--supersample\n"));
  CHECK(run_cli("render builtin:sphere -o '" + (tmp.path / "v.png").string() +
                    "' --uv-layout --width 4096 --height 4096",
                err) == 2);
  CHECK_THAT(line(),
             Catch::StartsWith("isocharts: error: --width/--height/--supersample: 4096x4096 pixels at "
                               "supersample 2 is too large"));
  // An even neighbourhood is refused before any work.
  CHECK(run_cli("-q synth builtin:sphere -o '" + (tmp.path / "s.glb").string() + "' --neighborhood 4", err) ==
        2);
  CHECK_THAT(line(), Catch::Equals("isocharts: error: --neighborhood must be odd (3, 5, 7, ...), not 4\n"));
  // A scale that would magnify the exemplar past the finest level's whole image used to run
  // out of memory (--scale 1: 15 GB); it is refused with the smallest scale that works.
  CHECK(run_cli("-q synth builtin:sphere -o '" + (tmp.path / "s.glb").string() +
                    "' --levels 64,32 --pixels-per-texel 0.001",
                err) == 2);
  const std::string scale_line = line();
  CHECK_THAT(scale_line,
             Catch::StartsWith("isocharts: error: --pixels-per-texel 0.001: exemplar scale too small") &&
                 Catch::Contains("the smallest scale is") && Catch::EndsWith("(1 per texel)\n"));
  CHECK(std::count(scale_line.begin(), scale_line.end(), '\n') == 1);
  CHECK(entries(tmp.path) == std::vector<std::string>{"err.txt"});
  // A tiny scale printed the magnified size with all its 300 digits and lost the advice at the
  // end of a fixed buffer.
  CHECK(run_cli("-q synth builtin:sphere -o '" + (tmp.path / "s.glb").string() +
                    "' --levels 64,32 --scale 1e-300",
                err) == 2);
  CHECK_THAT(line(), Catch::StartsWith("isocharts: error: --scale 1e-300: exemplar scale too small") &&
                         Catch::Contains("the smallest scale is") && Catch::EndsWith("(1 per texel)\n"));
  // The other end: a scale that would shrink the exemplar below 4 pixels across ran capped at
  // that and reported the scale asked for.
  CHECK(
      run_cli("-q synth builtin:sphere -o '" + (tmp.path / "s.glb").string() + "' --levels 64,32 --scale 1e9",
              err) == 2);
  const std::string large = line();
  CHECK_THAT(large, Catch::StartsWith("isocharts: error: --scale 1e+09: exemplar scale too large") &&
                        Catch::Contains("the largest scale is"));
  CHECK(entries(tmp.path) == std::vector<std::string>{"err.txt"});
  // The largest scale named (rounded down, not to the nearest) works.
  const auto at = large.find("the largest scale is ");
  REQUIRE(at != std::string::npos);
  const std::string largest = large.substr(at + 21, large.find(' ', at + 21) - at - 21);
  CHECK(run_cli("-q synth builtin:sphere -o '" + (tmp.path / "s.glb").string() + "' --levels 64,32 --scale " +
                    largest,
                err) == 0);
  // An exemplar too large to search at the scale asked for: the error names it and the option.
  const fs::path big = tmp.path / "big.png";
  isochart::Image noise_image(1100, 1100, 3);
  for (std::size_t i = 0; i < noise_image.pixels.size(); ++i)
    noise_image.pixels[i] = float((i * 7919) % 256) / 255;
  isochart::write_image(big.string(), noise_image);
  CHECK(run_cli("-q synth builtin:sphere -o '" + (tmp.path / "s.glb").string() +
                    "' --levels 64,32 --exemplar '" + big.string() + "' --pixels-per-texel 1",
                err) == 2);
  CHECK_THAT(line(), Catch::StartsWith("isocharts: error: " + big.string() +
                                       ": --pixels-per-texel 1: exemplar too large at this scale"));
  // The largest seed is a seed.
  CHECK(run_cli("-q info builtin:sphere --seed 18446744073709551615", err) == 0);
}

TEST_CASE("a write that fails midway (file size limit, as on a full disk) is one line, nothing left",
          "[cli]") {
  TempDir tmp("fsize");
  const fs::path err = tmp.path / "err.txt";
  const fs::path outdir = tmp.path / "out";
  fs::create_directory(outdir);
  // Writes past 16 KiB fail with EFBIG (SIGXFSZ ignored), the way they fail on a full disk.
  // libjpeg used to print its own line and exit the process; libpng to report success.
  for (const std::string ext : {"png", "jpg", "exr", "tif"}) {
    const fs::path out = outdir / ("view." + ext);
    CAPTURE(ext);
    const int status =
        std::system(("sh -c \"trap '' XFSZ; ulimit -f 16; exec '" + std::string(ISOCHARTS_CLI) +
                     "' render builtin:creature -o '" + out.string() +
                     "' --width 800 --height 800 -q\" > /dev/null 2> '" + err.string() + "'")
                        .c_str());
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 1);
    const std::string line = read_bytes(err);
    CHECK_THAT(line, Catch::StartsWith("isocharts: error: " + out.string() + ": cannot write: "));
    CHECK(std::count(line.begin(), line.end(), '\n') == 1);
    CHECK(line.find(".tmp") == std::string::npos);  // the temporary file is ours, not the user's
    CHECK(entries(outdir).empty());
  }
  // Meshes: the same failure is not the input's fault either (exit 1, not 2).
  for (const std::string ext : {"obj", "ply", "glb"}) {
    const fs::path out = outdir / ("sphere." + ext);
    CAPTURE(ext);
    const int status = std::system(("sh -c \"trap '' XFSZ; ulimit -f 16; exec '" +
                                    std::string(ISOCHARTS_CLI) + "' -q atlas builtin:sphere -o '" +
                                    out.string() + "'\" > /dev/null 2> '" + err.string() + "'")
                                       .c_str());
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 1);
    CHECK_THAT(read_bytes(err),
               Catch::Equals("isocharts: error: " + out.string() + ": cannot write: File too large\n"));
    CHECK(entries(outdir).empty());
  }
}

TEST_CASE("a PNG cut short gets our one-line error instead of libpng's", "[cli]") {
  TempDir tmp("cut_png");
  const fs::path err = tmp.path / "err.txt", png = tmp.path / "v.png", cut = tmp.path / "cut.png";
  REQUIRE(run_cli("render builtin:sphere -o '" + png.string() + "' --views 1", err) == 0);
  const std::string whole = read_bytes(png);
  REQUIRE(whole.size() > 200);
  write_bytes(cut, whole.substr(0, whole.size() / 2));
  const fs::path tri = tmp.path / "tri.obj";
  write_bytes(tri, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
  CHECK(run_cli("render '" + tri.string() + "' --texture '" + cut.string() + "' -o '" +
                    (tmp.path / "w.png").string() + "'",
                err) == 2);
  const std::string text = read_bytes(err);
  CHECK_THAT(text, Catch::StartsWith("isocharts: error: " + cut.string()) && Catch::Contains("cut short"));
  CHECK(std::count(text.begin(), text.end(), '\n') == 1);
  CHECK_FALSE(fs::exists(tmp.path / "w.png"));
  // Bytes after the end marker (some writers pad or append) are no reason to refuse it.
  const fs::path padded = tmp.path / "padded.png";
  write_bytes(padded, whole + std::string(100, '\0'));
  CHECK(run_cli("render '" + tri.string() + "' --texture '" + padded.string() + "' -o '" +
                    (tmp.path / "w.png").string() + "'",
                err) == 0);
}

TEST_CASE("remesh --atlas warns about an atlas whose charts overlap in UV", "[cli]") {
  TempDir tmp("overlap_atlas");
  const fs::path err = tmp.path / "err.txt", atlas = tmp.path / "a.obj", tiled = tmp.path / "tiled.obj";
  REQUIRE(run_cli("-q atlas builtin:sphere -o '" + atlas.string() + "'", err) == 0);
  // The same layout tiled three times over in each direction: charts land on themselves.
  std::istringstream in(read_bytes(atlas));
  std::ostringstream out;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("vt ", 0) == 0) {
      std::istringstream v(line.substr(3));
      double u = 0, w = 0;
      v >> u >> w;
      out << "vt " << std::fmod(3 * u, 1.0) << " " << std::fmod(3 * w, 1.0) << "\n";
    } else {
      out << line << "\n";
    }
  }
  write_bytes(tiled, out.str());
  const std::string remesh =
      "remesh builtin:sphere --res 32 -o '" + (tmp.path / "r.ply").string() + "' --no-psnr";
  REQUIRE(run_cli(remesh + " --atlas '" + atlas.string() + "'", err) == 0);
  CHECK(read_bytes(err).find("overlapping") == std::string::npos);
  REQUIRE(run_cli(remesh + " --atlas '" + tiled.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("isocharts: warning: " + tiled.string() + ": the atlas has ") &&
                                  Catch::Contains("overlapping triangle pairs in UV"));
}

TEST_CASE("a result that cannot be written to standard output fails the run", "[cli]") {
  // /dev/full takes no byte: the JSON (or the text) is lost, so the exit code must say so.
  if (!fs::exists("/dev/full")) return;
  TempDir tmp("stdout_full");
  const fs::path err = tmp.path / "err.txt";
  for (const std::string json : {" --json", ""}) {
    const std::string cmd = "'" + std::string(ISOCHARTS_CLI) + "' info builtin:sphere" + json +
                            " > /dev/full 2> '" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 1);
    std::ifstream in(err);
    std::string line;
    std::getline(in, line);
    CHECK(line == "isocharts: error: standard output: cannot write: No space left on device");
  }
}

TEST_CASE("info shows the triangle counts its topology is of when the file has polygons", "[cli]") {
  TempDir tmp("info_quads");
  const fs::path obj = tmp.path / "cube.obj", out = tmp.path / "out.txt";
  std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                        "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  const std::string cmd =
      "'" + std::string(ISOCHARTS_CLI) + "' -q info '" + obj.string() + "' > '" + out.string() + "'";
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // 8 - 18 + 12 = 2: the Euler characteristic is of the 12 triangles, not of the 6 quads.
  CHECK(text.find("faces                6\n") != std::string::npos);
  CHECK(text.find("used                 8 vertices, 12 triangles, 18 edges") != std::string::npos);
  CHECK(text.find("euler characteristic 2\n") != std::string::npos);
  const fs::path json = tmp.path / "out.json";
  const std::string jcmd =
      "'" + std::string(ISOCHARTS_CLI) + "' -q info '" + obj.string() + "' --json > '" + json.string() + "'";
  REQUIRE(std::system(jcmd.c_str()) == 0);
  std::ifstream jin(json);
  const nlohmann::json j = nlohmann::json::parse(jin);
  CHECK(j["faces"] == 6);
  CHECK(j["polygons_triangulated"] == 6);
  CHECK(j["used_vertices"] == 8);
  CHECK(j["used_triangles"] == 12);
}

TEST_CASE("outputs with names of up to 255 bytes are written", "[cli]") {
  // The temporary file beside the output is named after it: with a 245-byte name it went over
  // the 255-byte limit and the run failed ("File name too long") after all its work.
  TempDir tmp("long_names");
  const fs::path err = tmp.path / "err.txt";
  const std::string stem(251, 'L');
  const fs::path obj = tmp.path / (stem + ".obj"), png = tmp.path / (stem + ".png");
  CHECK(run_cli("-q atlas builtin:face -o '" + obj.string() + "' --png '" + png.string() + "'", err) == 0);
  CHECK(read_bytes(err).empty());
  CHECK(entries(tmp.path) == std::vector<std::string>{stem + ".obj", stem + ".png", "err.txt"});
  // A longer name is refused before any work (it failed at the very end, after printing
  // "wrote"), for derived names too (synth's OUT_mcgim.png).
  const std::string too_long(252, 'M');
  CHECK(run_cli("-q atlas builtin:face -o '" + (tmp.path / (too_long + ".obj")).string() + "'", err) == 2);
  CHECK_THAT(read_bytes(err),
             Catch::EndsWith("cannot write: the file name has 256 bytes, more than the 255 the "
                             "directory allows\n"));
  CHECK(run_cli("-q synth builtin:sphere -o '" + (tmp.path / (std::string(246, 'S') + ".glb")).string() + "'",
                err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("_mcgim.glb: cannot write: the file name has 256 bytes"));
  CHECK(entries(tmp.path) == std::vector<std::string>{stem + ".obj", stem + ".png", "err.txt"});
}

TEST_CASE("a long thin chart in a square texture gets a warning naming the remedy", "[cli]") {
  // A 100:1 flat strip is one chart that fills about 1 % of a square texture; a texture of its
  // shape holds it whole.
  TempDir tmp("strip");
  const fs::path strip = tmp.path / "strip.obj", err = tmp.path / "err.txt";
  std::string obj;
  const int n = 100;
  for (int i = 0; i <= n; ++i) obj += "v " + std::to_string(i) + " 0 0\nv " + std::to_string(i) + " 1 0\n";
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i + 1, b = a + 1, c = a + 2, d = a + 3;
    obj += "f " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + "\nf " +
           std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(b) + "\n";
  }
  write_bytes(strip, obj);
  CHECK(run_cli("atlas '" + strip.string() + "' -o '" + (tmp.path / "a.obj").string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("strip.obj: the charts fill") &&
                 Catch::Contains("the largest is about 10") &&  // 100-odd, with the gutter
                 Catch::Contains("times longer than wide; a texture of its shape (--width/--height)"));
  CHECK(run_cli("atlas '" + strip.string() + "' -o '" + (tmp.path / "b.obj").string() +
                    "' --width 4096 --height 40",
                err) == 0);
  CHECK(read_bytes(err).empty());
}

TEST_CASE("a texture many times longer than high, which the charts cannot fill, gets a warning", "[cli]") {
  // A square's one chart fills at most 1/16 of a 16:1 texture or geometry image.
  TempDir tmp("elongated");
  const fs::path square = tmp.path / "square.obj", err = tmp.path / "err.txt";
  write_bytes(square, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  CHECK(run_cli("atlas '" + square.string() + "' -o '" + (tmp.path / "a.obj").string() +
                    "' --width 1024 --height 64",
                err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("square.obj: the charts fill") &&
                                  Catch::Contains("% of the 1024x64 texture: in one this elongated"));
  CHECK(run_cli("remesh '" + square.string() + "' -o '" + (tmp.path / "r.ply").string() +
                    "' --width 256 --height 16 --no-psnr",
                err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("r.ply: 256x16 level defines") &&
                                  Catch::Contains("% of its samples: in an image this elongated"));
  // Square, no such warning (stderr may hold progress lines on a slow build, e.g. ASan).
  CHECK(run_cli("atlas '" + square.string() + "' -o '" + (tmp.path / "b.obj").string() + "'", err) == 0);
  CHECK(read_bytes(err).find("elongated") == std::string::npos);
}

TEST_CASE("synth says when the default scale is moved to one the pyramid can synthesize", "[cli]") {
  // A 1000 x 0.01 strip: a tenth of its diagonal holds the exemplar magnified past the finest
  // image, so the default scale is raised; that was silent while the same --scale is refused.
  TempDir tmp("strip_scale");
  const fs::path strip = tmp.path / "strip.obj", err = tmp.path / "err.txt";
  std::string obj;
  const int n = 200;
  for (int i = 0; i <= n; ++i)
    obj += "v " + std::to_string(5 * i) + " 0 0\nv " + std::to_string(5 * i) + " 0.01 0\n";
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i + 1, b = a + 1, c = a + 2, d = a + 3;
    obj += "f " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + "\nf " +
           std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(b) + "\n";
  }
  write_bytes(strip, obj);
  CHECK(run_cli("synth '" + strip.string() + "' -o '" + (tmp.path / "s.glb").string() + "' --levels 64,32",
                err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("builtin:bricks: the default scale (") &&
                                  Catch::Contains("the smallest that works"));
}

TEST_CASE("synth warns when --direction is along the surface normal", "[cli]") {
  // On a flat square seen face-on, (0,0,1) has no direction along the surface; the field then
  // follows another axis, which the user should hear about.
  TempDir tmp("direction");
  const fs::path square = tmp.path / "square.obj", err = tmp.path / "err.txt";
  write_bytes(square, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  const std::string run =
      "synth '" + square.string() + "' --levels 32,16 -o '" + (tmp.path / "s.glb").string() + "'";
  CHECK(run_cli(run + " --direction 0,0,1", err) == 0);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("square.obj: --direction 0,0,1 is within 17 degrees of the surface "
                             "normal on 100 % of the surface"));
  CHECK(run_cli(run + " --direction 1,0,0.2", err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("--direction"));
}

TEST_CASE("remesh --atlas warns when the atlas's surface is not the input's topology", "[cli]") {
  // The size check passes an atlas with one face left out; the remesh then has a hole that the
  // PSNR (measured against the atlas) does not show.
  TempDir tmp("atlas_topology");
  const fs::path atlas = tmp.path / "a.obj", holed = tmp.path / "holed.obj", err = tmp.path / "err.txt";
  bool dropped = false;
  write_bytes(holed, edited_sphere_atlas(atlas, err, [&](std::string& line) {
                if (dropped || line.rfind("f ", 0) != 0) return true;
                dropped = true;
                return false;
              }));
  const std::string run =
      "remesh builtin:sphere --res 32 --no-psnr -o '" + (tmp.path / "r.ply").string() + "' --atlas ";
  CHECK(run_cli(run + "'" + atlas.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("euler characteristic"));
  CHECK(run_cli(run + "'" + holed.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("holed.obj: the atlas's surface has euler characteristic 1 and 1 "
                             "boundary loops, the input's 2 and 0; the remesh follows the atlas"));
}

TEST_CASE("sae --source matches a renumbered source by position, and refuses another mesh", "[cli]") {
  // The signal went to the atlas vertex of the same number: a renumbered re-export of the
  // source gave a wrong SAE without a word (9x on eight).
  TempDir tmp("sae_source");
  const fs::path atlas = tmp.path / "a.obj", shuffled = tmp.path / "shuffled.obj", err = tmp.path / "err.txt";
  // The same mesh with its vertex list reversed and the faces renumbered to match.
  std::vector<std::string> vertices, faces;
  edited_sphere_atlas(atlas, err, [&](std::string& line) {
    if (line.rfind("v ", 0) == 0) vertices.push_back(line);
    if (line.rfind("f ", 0) == 0) faces.push_back(line);
    return true;
  });
  const int n = static_cast<int>(vertices.size());
  std::string text;
  for (int i = n - 1; i >= 0; --i) text += vertices[i] + "\n";
  for (const std::string& f : faces) {
    std::istringstream corners(f.substr(2));
    std::string c;
    text += "f";
    while (corners >> c) text += " " + std::to_string(n + 1 - std::stoi(c.substr(0, c.find('/'))));
    text += "\n";
  }
  write_bytes(shuffled, text);
  const std::string run = "-q --json sae '" + atlas.string() + "' --signal normals --res 64 --source ";
  auto sae = [&](const fs::path& source) {
    REQUIRE(run_cli(run + "'" + source.string() + "' --report '" + (tmp.path / "r.json").string() + "'",
                    err) == 0);
    const std::string json = read_bytes(tmp.path / "r.json");
    return std::stod(json.substr(json.find("\"sae\":") + 6));
  };
  CHECK(sae(shuffled) == Approx(sae(atlas)).epsilon(1e-12));
  // Another mesh (one vertex moved) is refused.
  std::string moved = text;
  moved.replace(0, moved.find('\n'), "v 9 9 9");
  write_bytes(tmp.path / "moved.obj", moved);
  CHECK(run_cli(run + "'" + (tmp.path / "moved.obj").string() + "'", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("moved.obj: has no vertex at the atlas's vertex") &&
                                  Catch::Contains("the source must be the atlas's mesh"));
}

TEST_CASE("sae --source takes the atlas's faces in any order, as a glb writes them", "[cli]") {
  // A glb groups faces by chart: the source's faces came back in another order, and sae
  // refused isocharts' own glb atlases of a textured mesh.
  TempDir tmp("sae_order");
  const fs::path src = tmp.path / "src.obj", glb = tmp.path / "re.glb", obj = tmp.path / "re.obj",
                 png = tmp.path / "t.png", err = tmp.path / "err.txt";
  REQUIRE(run_cli("-q atlas builtin:torus -o '" + src.string() + "'", err) == 0);
  REQUIRE(run_cli("-q atlas '" + src.string() + "' --max-l2 1.02 -o '" + glb.string() + "' -o '" +
                      obj.string() + "'",
                  err) == 0);
  isochart::Image img(16, 16, 3, 0.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) img.at(x, y, 0) = static_cast<float>((x * 7 + y * 3) % 16) / 15;
  isochart::write_image(png.string(), img);
  auto sae = [&](const fs::path& atlas) {
    REQUIRE(run_cli("-q --json sae '" + atlas.string() + "' --signal texture:'" + png.string() +
                        "' --source '" + src.string() + "' --report '" + (tmp.path / "r.json").string() + "'",
                    err) == 0);
    const std::string text = read_bytes(tmp.path / "r.json");
    return std::stod(text.substr(text.find("\"sae\":") + 6));
  };
  CHECK(sae(glb) == Approx(sae(obj)).epsilon(1e-6));  // the glb holds float positions
}

TEST_CASE("atlas writes one group per chart, or keeps the input's face order when asked", "[cli]") {
  TempDir tmp("face_order");
  const fs::path src = tmp.path / "src.obj", grouped = tmp.path / "g.obj", kept = tmp.path / "k.obj",
                 report = tmp.path / "r.json", err = tmp.path / "err.txt";
  // The source's faces come by chart; its atlas at a tighter bound has other charts, which
  // run through that order.
  REQUIRE(run_cli("-q atlas builtin:torus -o '" + src.string() + "'", err) == 0);
  const std::string run = "-q atlas '" + src.string() + "' --max-l2 1.02 --report '" + report.string() + "' ";
  REQUIRE(run_cli(run + "-o '" + grouped.string() + "'", err) == 0);
  const int charts = nlohmann::json::parse(read_bytes(report))["charts"];
  REQUIRE(run_cli(run + "--keep-face-order -o '" + kept.string() + "'", err) == 0);
  // Per file: the `g` lines, and each face's vertex indices (the part before each '/').
  const auto read = [](const fs::path& p) {
    std::vector<std::string> g, faces;
    std::istringstream in(read_bytes(p));
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("g ", 0) == 0) g.push_back(line);
      if (line.rfind("f ", 0) != 0) continue;
      std::istringstream words(line.substr(2));
      std::string face;
      for (std::string w; words >> w;) face += w.substr(0, w.find('/')) + ' ';
      faces.push_back(face);
    }
    return std::make_pair(g, faces);
  };
  const auto [src_g, src_faces] = read(src);
  const auto [g_g, g_faces] = read(grouped);
  const auto [k_g, k_faces] = read(kept);
  CHECK(static_cast<int>(g_g.size()) == charts);
  CHECK(std::set<std::string>(g_g.begin(), g_g.end()).size() == g_g.size());
  CHECK(k_faces == src_faces);
  CHECK(k_g.size() > g_g.size());  // the charts interleave in the source's order
  CHECK(g_faces != src_faces);
  auto sorted = [](std::vector<std::string> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  CHECK(sorted(g_faces) == sorted(src_faces));
}

TEST_CASE("bad image outputs and device outputs are refused before any work", "[cli]") {
  // They were found by the writers, after the atlas was built (minutes on a large mesh).
  TempDir tmp("image_outputs");
  const fs::path err = tmp.path / "err.txt";
  const std::string obj = (tmp.path / "a.obj").string();
  const std::string run = "atlas builtin:sphere -o '" + obj + "' ";
  const struct {
    std::string args, message;
  } cases[] = {
      {"--png '" + (tmp.path / "layout").string() + "'", "layout: output image needs an extension"},
      {"--png '" + (tmp.path / "layout.xyz").string() + "'", "layout.xyz: unsupported image format '.xyz'"},
      {"--png /dev/null", "/dev/null: cannot write: not a regular file"},
      {"--report /dev/null", "/dev/null: cannot write: not a regular file"},
  };
  for (const auto& c : cases) {
    INFO(c.args);
    CHECK(run_cli(run + c.args, err) == 2);
    CHECK_THAT(read_bytes(err), Catch::Contains(c.message) && !Catch::Contains("clustering"));
    CHECK(!fs::exists(obj));
  }
}

TEST_CASE("atlas says when the bounds need more charts than --max-charts, and checks option ranges",
          "[cli]") {
  TempDir tmp("max_charts");
  const fs::path err = tmp.path / "err.txt";
  const std::string out = " -o '" + (tmp.path / "a.obj").string() + "'";
  CHECK(run_cli("atlas builtin:sphere --max-charts 1" + out, err) == 0);
  const std::string warned = read_bytes(err);
  CHECK_THAT(warned, Catch::Contains("builtin:sphere: the atlas needs") &&
                         Catch::Contains("charts, more than --max-charts 1"));
  CHECK(run_cli("atlas builtin:sphere --max-charts 40" + out, err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("--max-charts"));
  CHECK(run_cli("atlas builtin:sphere --signal normals --split-efficiency 5" + out, err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("--split-efficiency: expected a number from 0 to 1"));
  // Refused when parsed, not after the signal was built, and not blamed on the mesh file.
  CHECK(run_cli("atlas builtin:sphere --signal normals --beta 2" + out, err) == 2);
  CHECK(read_bytes(err) == "isocharts: error: --beta: expected a number from 0 to 1, got '2'\n");
  // Options that shape the charts do nothing where the signal does not build them.
  for (const char* use : {"none", "param"}) {
    CHECK(run_cli(std::string("atlas builtin:sphere --signal normals --beta 0.3 --signal-use ") + use + out,
                  err) == 2);
    CHECK(read_bytes(err) == "isocharts: error: --beta goes with --signal-use full (it shapes the charts)\n");
  }
  // Named as the option, before the mesh is loaded; and refused where no signal
  // parameterization is built for it to bound.
  CHECK(run_cli("atlas builtin:sphere --signal normals --max-geometric-l2 nan" + out, err) == 2);
  CHECK(read_bytes(err) == "isocharts: error: --max-geometric-l2 must be a number >= 1 (1 is an isometry)\n");
  CHECK(run_cli("atlas builtin:sphere --signal normals --signal-use none --max-geometric-l2 3" + out, err) ==
        2);
  CHECK_THAT(read_bytes(err),
             Catch::StartsWith("isocharts: error: --max-geometric-l2 goes with --signal-use"));
  CHECK(run_cli("atlas builtin:sphere --no-graph-cut --alpha 0.3" + out, err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("--alpha weighs the graph cut"));
  CHECK(run_cli("atlas builtin:sphere --no-merge --merge-limit 0.5" + out, err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("--merge-limit bounds the merging --no-merge skips"));
  CHECK(run_cli("atlas builtin:sphere --merge-limit 1.5" + out, err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("--merge-limit"));
  CHECK(run_cli("atlas builtin:sphere --pack-grid 10" + out, err) == 2);
  CHECK(read_bytes(err) ==
        "isocharts: error: --pack-grid must be 0 (the texture's own grid) or between 64 and 8192\n");
  // A geometric atlas measured against a signal: one texture, packed geometrically; the report
  // lists every file written.
  const fs::path report = tmp.path / "r.json", png = tmp.path / "p.png", imt = tmp.path / "i.imt";
  REQUIRE(run_cli("--report '" + report.string() +
                      "' atlas builtin:sphere --signal normals --signal-use none" + out + " --png '" +
                      png.string() + "' --imt-out '" + imt.string() + "'",
                  err) == 0);
  const nlohmann::json r = nlohmann::json::parse(read_bytes(report));
  CHECK(r["outputs"] == nlohmann::json::array({(tmp.path / "a.obj").string(), png.string(), imt.string()}));
  CHECK(run_cli("sae builtin:sphere --res 256 --width 100 --height 100", err) == 2);
  CHECK(read_bytes(err) == "isocharts: error: --res and --width/--height are exclusive\n");
  CHECK(run_cli("atlas builtin:sphere --signal normals --lambda -1" + out, err) == 2);
  CHECK(read_bytes(err) == "isocharts: error: --lambda: expected a number >= 0, got '-1'\n");
  // sae's limit: 16384² took 6.3 GB after the whole atlas was built.
  CHECK(run_cli("atlas builtin:sphere --signal normals --sae-res 16384" + out, err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("--sae-res: expected an integer from 1 to 8192"));
  CHECK(run_cli("bench builtin:sphere --sweep 1.1,,1.2 --out '" + (tmp.path / "b").string() + "'", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("has an empty item"));
}

TEST_CASE("options taking a number in a range refuse nan", "[cli]") {
  // CLI::Range compares with < and >, which nan passes: stats --aspect nan measured every
  // triangle as zero-area with exit 0, and --split-efficiency nan ran as 0 (off).
  TempDir tmp("nan_options");
  const fs::path err = tmp.path / "err.txt";
  const std::string dir = " '" + tmp.path.string() + "/";
  const struct {
    std::string args, option;
  } cases[] = {
      {"stats builtin:sphere --aspect nan", "--aspect"},
      {"render builtin:sphere --uv-layout --aspect nan -o" + dir + "r.png'", "--aspect"},
      {"render builtin:sphere --aspect nan -o" + dir + "r.png'", "--aspect"},
      {"atlas builtin:sphere --signal normals --split-efficiency nan -o" + dir + "a.obj'",
       "--split-efficiency"},
      {"synth builtin:sphere --coherence nan -o" + dir + "s.glb'", "--coherence"},
  };
  for (const auto& c : cases) {
    INFO(c.args);
    CHECK(run_cli(c.args, err) == 2);
    CHECK_THAT(read_bytes(err),
               Catch::Contains(c.option + ": expected a number from") && Catch::Contains("got 'nan'"));
  }
  CHECK(std::distance(fs::directory_iterator(tmp.path), fs::directory_iterator()) == 1);
}

TEST_CASE("synth says when it cannot start at the --start-level asked for", "[cli]") {
  // The level was lowered to one with --start-samples samples without a word, and an index
  // past the pyramid ran like the default.
  TempDir tmp("start_level");
  const fs::path err = tmp.path / "err.txt";
  const std::string out = " -o '" + (tmp.path / "s.glb").string() + "' --levels 64,32,16 --atlas-size 64";
  CHECK(run_cli("synth builtin:sphere --start-level 3" + out, err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("--start-level 3: the pyramid has 3 levels, 0 (finest) to 2"));
  CHECK(!fs::exists(tmp.path / "s.glb"));
  CHECK(run_cli("synth builtin:sphere --start-level 2" + out, err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("--start-level 2: started at level 0 (64²)") &&
                                  Catch::Contains("fewer than --start-samples 1000 samples"));
  CHECK(run_cli("synth builtin:sphere --start-level 2 --start-samples 16" + out, err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("--start-level"));
}

TEST_CASE("comma lists refuse empty items and repeats alike", "[cli]") {
  // CLI11 dropped empty items of --levels silently, bench skipped them in --methods, and
  // --sweep ran a repeated bound twice.
  TempDir tmp("lists");
  const fs::path err = tmp.path / "err.txt";
  const std::string r = " -o '" + (tmp.path / "r.ply").string() + "'",
                    s = " -o '" + (tmp.path / "s.glb").string() + "'";
  const std::string b = " --out '" + (tmp.path / "b").string() + "'";
  const struct {
    std::string args, message;
  } cases[] = {
      {"remesh builtin:sphere --levels 64,,32" + r, "--levels: '64,,32' has an empty item"},
      {"remesh builtin:sphere --levels 64,32," + r, "--levels: '64,32,' has an empty item"},
      {"remesh builtin:sphere --levels 64,32 --levels 32" + r, "--levels: 32 is given twice"},
      {"synth builtin:sphere --levels 32,,16" + s, "--levels: '32,,16' has an empty item"},
      {"synth builtin:sphere --levels 32,4" + s, "--levels: expected an integer from 8 to 2048, got '4'"},
      {"bench builtin:sphere --methods isochart,,lscm" + b, "--methods: 'isochart,,lscm' has an empty item"},
      {"bench builtin:sphere --methods ," + b, "--methods: ',' has an empty item"},
      {"bench builtin:sphere --sweep 1.1,1.1" + b, "--sweep: 1.1 is given twice"},
      {"bench builtin:sphere --sweep 1.1,1.2," + b, "--sweep: '1.1,1.2,' has an empty item"},
  };
  for (const auto& c : cases) {
    INFO(c.args);
    CHECK(run_cli(c.args, err) == 2);
    CHECK(read_bytes(err) == "isocharts: error: " + c.message + "\n");
  }
  CHECK(std::distance(fs::directory_iterator(tmp.path), fs::directory_iterator()) == 1);  // err.txt
}

TEST_CASE("synth's textures are named without spaces, so MTL readers find them", "[cli]") {
  // map_Kd "my out.png" read as "out.png" in readers that end the name at a space.
  TempDir tmp("space names");
  const fs::path err = tmp.path / "err.txt";
  REQUIRE(run_cli("-q synth builtin:sphere --levels 32,16 --atlas-size 32 -o '" +
                      (tmp.path / "my out.obj").string() + "'",
                  err) == 0);
  for (const char* mtl : {"my_out.mtl", "my_out_mcgim.mtl"}) {
    INFO(mtl);
    const std::string text = read_bytes(tmp.path / mtl);
    const auto at = text.find("map_Kd ");
    REQUIRE(at != std::string::npos);
    const std::string png = text.substr(at + 7, text.find('\n', at) - at - 7);
    CHECK(png.find(' ') == std::string::npos);
    CHECK(fs::exists(tmp.path / png));
  }
  CHECK(fs::exists(tmp.path / "my out.glb"));
  CHECK(fs::exists(tmp.path / "my out_mcgim.obj"));
}

TEST_CASE("stats says when its packing ratio is not of the texture", "[cli]") {
  // UVs all outside [0, 1] read "packing ratio 1", two charts on one square "2", silently.
  TempDir tmp("stats_ratio");
  const fs::path err = tmp.path / "err.txt", outside = tmp.path / "outside.obj",
                 overlap = tmp.path / "overlap.obj";
  std::ofstream(outside) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 5 -3\nvt 6 -3\nvt 6 -2\nvt 5 -2\n"
                            "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
  std::ofstream(overlap) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
                            "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 0.9\n"
                            "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\nf 2/1 5/2 6/3\nf 2/1 6/3 3/4\n";
  CHECK(run_cli("stats '" + outside.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("texture coordinates reach outside [0, 1] (5, -3) to (6, -2)"));
  CHECK(run_cli("stats '" + overlap.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("overlapping triangle pairs: the packing ratio counts their UV area twice"));
  // "L2 stretch inf" alone did not say why.
  const fs::path line = tmp.path / "line.obj";
  std::ofstream(line) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 0.5 0\nvt 1 0\nvt 0.2 0\n"
                         "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
  CHECK(run_cli("stats '" + line.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("the stretch is infinite: 2 UV triangles have zero area"));
  CHECK(run_cli("stats '" + outside.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("infinite"));
}

TEST_CASE("stats, sae and remesh --keep-chart-sizes name a chart shrunk to a speck", "[cli]") {
  // A chart at a millionth of its texture share passed every check; kept at that size by
  // remesh --keep-chart-sizes it collapsed (30 dB) without a word.
  TempDir tmp("speck");
  const fs::path err = tmp.path / "err.txt", speck = tmp.path / "speck.obj", fine = tmp.path / "fine.obj";
  const std::string mesh =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
      "vt 0.1 0.1\nvt 0.45 0.1\nvt 0.45 0.9\nvt 0.1 0.9\nvt 0.6 0.1\n";
  const std::string faces = "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\nf 2/5 5/6 6/7\nf 2/5 6/7 3/8\n";
  std::ofstream(speck) << mesh << "vt 0.6001 0.1\nvt 0.6001 0.1001\nvt 0.6 0.1001\n" << faces;
  std::ofstream(fine) << mesh << "vt 0.95 0.1\nvt 0.95 0.9\nvt 0.6 0.9\n" << faces;
  const std::string warning =
      "the chart of face 2 (2 faces) gets 7.1e-08 of the texture its surface area would get";
  const std::string s = "'" + speck.string() + "'", f = "'" + fine.string() + "'";
  CHECK(run_cli("stats " + s, err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains(warning + "; its surface gets almost no texels"));
  CHECK(run_cli("sae " + s + " --res 32", err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains(warning + "; its signal is sampled by almost no texels"));
  const std::string out = " --res 32 --no-psnr -o '" + (tmp.path / "r.ply").string() + "'";
  CHECK(run_cli("remesh " + s + " --atlas " + s + " --keep-chart-sizes" + out, err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains(warning + "; --keep-chart-sizes keeps it that small"));
  // Re-packed at their surface areas, the charts sample evenly: nothing to say.
  CHECK(run_cli("remesh " + s + " --atlas " + s + out, err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("gets "));
  CHECK(run_cli("stats " + f, err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("gets "));
}

TEST_CASE("synth says when the default scale shrinks the exemplar to a thumbnail", "[cli]") {
  // A large photograph at the default scale was synthesized from a few pixels without a word.
  TempDir tmp("synth_thumb");
  const fs::path err = tmp.path / "err.txt";
  const std::string common =
      "synth builtin:sphere -o '" + (tmp.path / "s.glb").string() + "' --levels 32,16 --atlas-size 64";
  CHECK(run_cli(common, err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("builtin:bricks: at the default scale") &&
                                  Catch::Contains("the 128x128 exemplar is synthesized from 4x4 pixels"));
  const fs::path report = tmp.path / "r.json";
  CHECK(run_cli("--report '" + report.string() + "' " + common + " --pixels-per-texel 4", err) == 0);
  CHECK(read_bytes(err).find("at the default scale") == std::string::npos);
  // The 16² level is below the start level: not synthesized, so no exemplar level (it read 0x0).
  const nlohmann::json j = nlohmann::json::parse(read_bytes(report));
  REQUIRE(j.at("levels").size() == 2);
  CHECK(j["levels"][0]["synthesized"].get<bool>());
  CHECK_FALSE(j["levels"][1]["synthesized"].get<bool>());
  CHECK(j["levels"][1]["exemplar"].is_null());
  CHECK(j["levels"][1]["exemplar_pixels_per_texel"].is_null());
}

TEST_CASE("a file given twice in one run is warned about once", "[cli]") {
  // The input and its --atlas are the same file: it is loaded twice, and its warning was
  // printed twice.
  TempDir tmp("warn_once");
  const fs::path err = tmp.path / "err.txt", partial = tmp.path / "partial.obj";
  std::ofstream(partial)
      << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\nf 1 3 4\n";
  CHECK(run_cli("remesh '" + partial.string() + "' --atlas '" + partial.string() + "' -o '" +
                    (tmp.path / "r.ply").string() + "' --res 16",
                err) == 2);
  const std::string text = read_bytes(err);
  const std::string warning = "1 face has no texture coordinates";
  const std::size_t first = text.find(warning);
  REQUIRE(first != std::string::npos);
  CHECK(text.find(warning, first + 1) == std::string::npos);
  CHECK_THAT(text, Catch::Contains("atlas chart 1 (face 1) has zero texture area"));
}

TEST_CASE("stats says when the UVs were laid out for another texture shape", "[cli]") {
  // A unit square laid out 4 times narrower than high: a 4:1 texture's atlas, whose stretch
  // measured in a square texture reads as a chart flattened fourfold.
  TempDir tmp("stats_aspect");
  const fs::path err = tmp.path / "err.txt", wide = tmp.path / "wide.obj";
  std::ofstream(wide) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 0.25 0\nvt 0.25 1\nvt 0 1\n"
                         "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
  CHECK(run_cli("stats '" + wide.string() + "'", err) == 0);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("wide.obj: the texture coordinates look laid out for a texture 4 "
                             "times as wide as high; stretch is measured for --aspect 1"));
  CHECK(run_cli("stats '" + wide.string() + "' --aspect 4", err) == 0);
  CHECK(read_bytes(err).find("look laid out") == std::string::npos);
  CHECK(run_cli("stats '" + wide.string() + "' --aspect 0.25", err) == 0);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("4 times as wide as high; stretch is measured for --aspect 0.25"));
  // render --uv-layout draws it in that shape by default; one side given, the other follows.
  const fs::path out = tmp.path / "out.txt";
  CHECK(run_cli("--report '" + out.string() + "' render '" + wide.string() + "' --uv-layout -o '" +
                    (tmp.path / "l.png").string() + "'",
                err) == 0);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("4 times as wide as high; drawn in that shape (--aspect sets it)"));
  CHECK_THAT(read_bytes(out), Catch::Contains("\"height\": 256") && Catch::Contains("\"width\": 1024"));
  CHECK(run_cli("--report '" + out.string() + "' render '" + wide.string() +
                    "' --uv-layout --aspect 8 --width 400 -o '" + (tmp.path / "l.png").string() + "'",
                err) == 0);
  CHECK(read_bytes(err).find("look laid out") == std::string::npos);
  CHECK_THAT(read_bytes(out), Catch::Contains("\"height\": 50") && Catch::Contains("\"width\": 400"));
  // A square chart packed in an 8:1 texture: a packing ratio near 1 (its own box) but an eighth
  // of the texture covered, which the report now says.
  CHECK(run_cli("--report '" + out.string() + "' atlas '" + wide.string() + "' -o '" +
                    (tmp.path / "a.obj").string() + "' --width 1024 --height 128",
                err) == 0);
  const nlohmann::json report = nlohmann::json::parse(read_bytes(out));
  CHECK(report.at("packing_ratio").get<double>() > 0.8);
  CHECK(report.at("texture_coverage").get<double>() < 0.15);
}

TEST_CASE("a texture signal needs texture coordinates on every face", "[cli]") {
  // Faces without vt read the texel at (0, 0): half the surface got a made-up signal.
  TempDir tmp("signal_uvs");
  const fs::path err = tmp.path / "err.txt", mesh = tmp.path / "half.obj", png = tmp.path / "t.png";
  REQUIRE(run_cli("-q render builtin:creature -o '" + png.string() + "' --views 1 --width 64 --height 64",
                  err) == 0);
  write_bytes(mesh,
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n"
              "f 1/1 3/3 2/2\nf 1/1 2/2 4/3\nf 1 4 3\nf 2 3 4\n");
  const std::string signal = " --signal 'texture:" + png.string() + "'";
  CHECK(run_cli("atlas '" + mesh.string() + "' -o '" + (tmp.path / "a.obj").string() + "'" + signal, err) ==
        2);
  CHECK_THAT(read_bytes(err),
             Catch::Contains("half.obj: 2 faces have no texture coordinates to read --signal texture:"));
  CHECK(run_cli("sae '" + mesh.string() + "'" + signal, err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("2 faces have no texture coordinates"));
  // Normals need none.
  CHECK(
      run_cli("-q atlas '" + mesh.string() + "' -o '" + (tmp.path / "b.obj").string() + "' --signal normals",
              err) == 0);
}

TEST_CASE("a signal atlas's stretch bounds are its charts', each at its own density", "[cli][slow]") {
  // A signal atlas packs charts at the densities the signal asks for; measured as one texture
  // they read as shrunk against each other, and every signal atlas "missed its bounds" with
  // the reason "some triangles are too thin for the coordinates' precision".
  TempDir tmp("signal_bounds");
  const fs::path err = tmp.path / "err.txt", report = tmp.path / "r.json";
  REQUIRE(run_cli("--threads 2 --report '" + report.string() +
                      "' atlas builtin:creature --signal normals -o '" + (tmp.path / "a.obj").string() + "'",
                  err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("misses its bounds"));
  const nlohmann::json j = nlohmann::json::parse(read_bytes(report));
  CHECK(j["bounds_met"] == true);
  CHECK(j["chart_linf_max"].get<double>() <= 5.0);
  CHECK(j["chart_l2_max"].get<double>() <= 2.0);
  double worst = 0;
  for (const auto& c : j["chart_list"]) worst = std::max(worst, c["linf"].get<double>());
  CHECK(j["chart_linf_max"].get<double>() == worst);
  // The whole atlas's figure is over the bound by design: what the per-chart bound is for.
  CHECK(j["linf_stretch"].get<double>() > 5.0);
}

TEST_CASE("signal-use param under a geometric bound below --max-l2 says which charts kept theirs", "[cli]") {
  // Its charts are built to --max-l2; those whose signal parameterization cannot meet a lower
  // --max-geometric-l2 keep the geometric one. That read as "misses its bounds: some triangles
  // are too thin for the coordinates' precision".
  TempDir tmp("param_bounds");
  const fs::path err = tmp.path / "err.txt", report = tmp.path / "r.json";
  REQUIRE(
      run_cli(
          "--report '" + report.string() +
              "' atlas builtin:sphere --signal normals --signal-use param --max-geometric-l2 1.0001 -o '" +
              (tmp.path / "a.obj").string() + "'",
          err) == 0);
  const std::string text = read_bytes(err);
  CHECK_THAT(text, !Catch::Contains("misses its bounds"));
  CHECK_THAT(text, Catch::Contains("charts keep their geometric parameterization: --signal-use param builds "
                                   "charts to --max-l2 1.1, above --max-geometric-l2 1.0001"));
  const nlohmann::json j = nlohmann::json::parse(read_bytes(report));
  CHECK(j["bounds_met"] == true);
  CHECK(j["chart_l2_max"].get<double>() <= 1.1);
  CHECK(j["signal"]["reverted_charts"].get<int>() >= 1);
}

TEST_CASE("sae warns when the UVs leave the texture, overlap or collapse", "[cli]") {
  TempDir tmp("sae_warnings");
  const fs::path atlas = tmp.path / "a.obj", outside = tmp.path / "outside.obj", err = tmp.path / "err.txt";
  write_bytes(outside, edited_sphere_atlas(atlas, err, [](std::string& line) {
                if (line.rfind("vt ", 0) == 0) {
                  std::istringstream uv(line.substr(3));
                  double u = 0, v = 0;
                  uv >> u >> v;
                  line = "vt " + std::to_string(2 * u) + " " + std::to_string(v);
                }
                return true;
              }));
  CHECK(run_cli("sae '" + atlas.string() + "' --res 64", err) == 0);
  CHECK_THAT(read_bytes(err), !Catch::Contains("warning"));
  CHECK(run_cli("sae '" + outside.string() + "' --res 64", err) == 0);
  CHECK_THAT(read_bytes(err), Catch::Contains("outside.obj: texture coordinates reach outside [0, 1]"));
  // The warning said "clamped" while the triangles past the edge baked nothing.
  CHECK_THAT(read_bytes(err),
             Catch::Contains("triangles reach past the texture's edge, where they get no texels"));
  // Shifted off the texture altogether, nothing is baked: SAE equalled the signal's RMS.
  const fs::path shifted = tmp.path / "shifted.obj";
  write_bytes(shifted, edited_sphere_atlas(atlas, err, [](std::string& line) {
                if (line.rfind("vt ", 0) == 0) {
                  std::istringstream uv(line.substr(3));
                  double u = 0, v = 0;
                  uv >> u >> v;
                  line = "vt " + std::to_string(u + 1.5) + " " + std::to_string(v);
                }
                return true;
              }));
  CHECK(run_cli("sae '" + shifted.string() + "' --res 64", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("shifted.obj: texture coordinates lie wholly outside [0, 1]"));
}

TEST_CASE("directories, '-' and image prefixes with an extension are named for what they are", "[cli]") {
  TempDir tmp("names");
  const fs::path err = tmp.path / "err.txt";
  CHECK(run_cli("info '" + tmp.path.string() + "'", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("is a directory, not a mesh file"));
  CHECK(run_cli("info -", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("-: standard input and output are not supported"));
  CHECK(run_cli("atlas builtin:sphere -o -", err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("-: standard output is not supported"));
  // --png prev.png is the prefix prev: prev_32x32.png, not prev.png_32x32.png.
  CHECK(run_cli("-q remesh builtin:sphere --res 32 --no-psnr -o '" + (tmp.path / "r.ply").string() +
                    "' --png '" + (tmp.path / "prev.png").string() + "' --report '" +
                    (tmp.path / "r.json").string() + "'",
                err) == 0);
  CHECK(fs::exists(tmp.path / "prev_32x32.png"));
  // The report names the images it wrote (the summary named only the remesh).
  const nlohmann::json report = nlohmann::json::parse(read_bytes(tmp.path / "r.json"));
  CHECK(report["levels"][0]["images"] == nlohmann::json::array({(tmp.path / "prev_32x32.png").string()}));
  // A directory as the prefix wrote a file called _32x32.png into it.
  for (const std::string& dir : {tmp.path.string() + "/", tmp.path.string()}) {
    CHECK(run_cli("-q remesh builtin:sphere --res 32 --no-psnr -o '" + (tmp.path / "r2.ply").string() +
                      "' --exr '" + dir + "'",
                  err) == 2);
    CHECK_THAT(read_bytes(err), Catch::Contains("--exr takes a file name prefix") &&
                                    Catch::Contains("not the directory '" + dir + "'"));
  }
  CHECK(!fs::exists(tmp.path / "_32x32.exr"));
  // A prefix with another type's extension wrote e.png_32x32.exr.
  CHECK(run_cli("-q remesh builtin:sphere --res 32 --no-psnr -o '" + (tmp.path / "r2.ply").string() +
                    "' --exr '" + (tmp.path / "e.png").string() + "'",
                err) == 2);
  CHECK_THAT(read_bytes(err), Catch::Contains("the prefix ends in .png"));
  CHECK(!fs::exists(tmp.path / "r2.ply"));
}
