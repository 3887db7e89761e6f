// `isocharts bench` end to end on small inputs: matched defined samples, outputs written
// completely (and nothing else left in the directory), per-row failures, bad inputs.
#include <sys/wait.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("isocharts_bench_test_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

int run_cli(const std::string& args, const fs::path& err) {
  const std::string cmd =
      std::string("'") + ISOCHARTS_CLI + "' " + args + " > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (char c : s) {
    if (c == '"') {
      quoted = !quoted;  // CSV quoting: the quotes are not part of the value
      continue;
    }
    if (c == sep && !quoted) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

// CSV rows as column-name → value maps.
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p) {
  std::istringstream in(slurp(p));
  std::string line;
  std::getline(in, line);
  const auto header = split(line, ',');
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const auto cells = split(line, ',');
    REQUIRE(cells.size() == header.size());
    std::map<std::string, std::string> r;
    for (std::size_t i = 0; i < header.size(); ++i) r[header[i]] = cells[i];
    rows.push_back(r);
  }
  return rows;
}

// bench MESH --methods isochart,external:ATLAS at 16², its two rows.
std::vector<std::map<std::string, std::string>> bench_against(const fs::path& mesh, const fs::path& atlas,
                                                              const fs::path& dir) {
  const fs::path out = dir / "out", err = dir / "stderr.txt";
  const int rc =
      run_cli("bench '" + mesh.string() + "' --methods isochart,external:'" + atlas.string() +
                  "' --res 16 --psnr-samples 2000 --sweep none --no-plots --out '" + out.string() + "'",
              err);
  REQUIRE(rc == 0);
  auto rows = read_csv(out / "bench.csv");
  REQUIRE(rows.size() == 2);
  return rows;
}

int count_lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace

TEST_CASE("bench: every method lands within 2% of the reference's defined samples", "[bench]") {
  const fs::path dir = fresh_dir("torus");
  const fs::path err = dir / "stderr.txt";
  const fs::path out = dir / "out";
  REQUIRE(run_cli("bench builtin:torus --methods isochart,lscm,lscm+stretch,isomap-nocut --res 64 "
                  "--psnr-samples 20000 --sweep 1.1,1.4 --pack-res 256 --out '" +
                      out.string() + "' --report '" + (dir / "r.json").string() + "'",
                  err) == 0);
  const auto rows = read_csv(out / "bench.csv");
  REQUIRE(rows.size() == 4);
  const nlohmann::json report = nlohmann::json::parse(slurp(dir / "r.json"));
  const long long target = std::stoll(rows[0].at("defined_samples"));
  CHECK(rows[0].at("width") == "64");
  for (const auto& r : rows) {
    INFO(r.at("method") << " " << r.at("note"));
    CHECK(r.at("mesh") == "torus");
    REQUIRE(r.at("note").empty());
    CHECK(std::stoi(r.at("charts")) >= 1);
    CHECK(std::stoll(r.at("target_samples")) == target);
    const long long d = std::stoll(r.at("defined_samples"));
    CHECK(std::llabs(d - target) * 50 <= target);
    CHECK(std::stoll(r.at("unique_samples")) <= d);
    const double psnr = std::stod(r.at("psnr_db"));
    CHECK(psnr > 30);
    CHECK(psnr < 200);
  }
  // The sweep: two bounds per method. lscm splits along one fixed tree whatever the bound, so
  // its looser bound can never need more charts.
  const auto sweep = read_csv(out / "sweep.csv");
  REQUIRE(sweep.size() == 8);
  for (std::size_t i = 0; i + 1 < sweep.size(); i += 2) {
    CHECK(sweep[i].at("method") == sweep[i + 1].at("method"));
    CHECK(sweep[i].at("max_l2") == "1.1");
    CHECK(sweep[i + 1].at("max_l2") == "1.4");
    CHECK(std::isfinite(std::stod(sweep[i].at("l2"))));
    // The report carries the sweep too (it was only in sweep.csv and bench.md).
    for (std::size_t k : {i, i + 1}) {
      CHECK(report["sweep"][k]["method"] == sweep[k].at("method"));
      CHECK(report["sweep"][k]["charts"] == std::stoi(sweep[k].at("charts")));
    }
    if (sweep[i].at("method") == "lscm") {
      CHECK(std::stod(sweep[i].at("l2")) <= 1.1);
      CHECK(std::stoi(sweep[i + 1].at("charts")) <= std::stoi(sweep[i].at("charts")));
    }
  }
  const std::string md = slurp(out / "bench.md");
  CHECK(md.find("| torus | 5184 | lscm+stretch |") != std::string::npos);
  CHECK(md.find("![psnr.png](psnr.png)") != std::string::npos);
  CHECK(report["plots"] == nlohmann::json::array({"psnr.png", "stretch_torus.png"}));
  // The outputs and nothing else: atomic writes leave no temporary files behind.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(out)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  CHECK(names ==
        std::vector<std::string>{"bench.csv", "bench.md", "psnr.png", "stretch_torus.png", "sweep.csv"});
  for (const char* png : {"psnr.png", "stretch_torus.png"}) {
    const auto size = fs::file_size(out / png);
    CHECK(size > 1000);
    CHECK(size < 100'000);
  }
}

TEST_CASE("bench: an external atlas the sampler rejects is an n/a row, not an abort", "[bench]") {
  const fs::path dir = fresh_dir("holed_torus");
  // A torus with one face removed, texture coordinates its projection on the equatorial plane:
  // one continuous chart with one boundary loop and genus 1, which no MCGIM can sample.
  std::ostringstream obj;
  const int nu = 16, nv = 8;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double a = 2 * M_PI * i / nu, b = 2 * M_PI * j / nv, rad = 2 + 0.7 * std::cos(b);
      const double x = rad * std::cos(a), y = rad * std::sin(a), z = 0.7 * std::sin(b);
      obj << "v " << x << " " << y << " " << z << "\n";
      obj << "vt " << 0.5 + 0.15 * x << " " << 0.5 + 0.15 * y << "\n";
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      if (i == 0 && j == 0) continue;  // the hole
      const int a = i * nv + j + 1, b = ((i + 1) % nu) * nv + j + 1, c = i * nv + (j + 1) % nv + 1,
                d = ((i + 1) % nu) * nv + (j + 1) % nv + 1;
      obj << "f " << a << "/" << a << " " << b << "/" << b << " " << d << "/" << d << "\n";
      obj << "f " << a << "/" << a << " " << d << "/" << d << " " << c << "/" << c << "\n";
    }
  const fs::path mesh = dir / "holed_torus.obj";
  std::ofstream(mesh) << obj.str();
  const fs::path out = dir / "out";
  const fs::path err = dir / "stderr.txt";
  REQUIRE(run_cli("bench '" + mesh.string() + "' --methods isochart,external:'" + mesh.string() +
                      "' --res 48 --psnr-samples 5000 --sweep none --no-plots --out '" + out.string() + "'",
                  err) == 0);
  const auto rows = read_csv(out / "bench.csv");
  REQUIRE(rows.size() == 2);
  CHECK(rows[0].at("note").empty());
  CHECK(rows[1].at("method") == "external:holed_torus");
  CHECK(rows[1].at("note").rfind("n/a: ", 0) == 0);
  CHECK(rows[1].at("psnr_db").empty());
}

TEST_CASE("bench: a row whose samples miss the first method's by more than 2% says so", "[bench]") {
  // A 10×10 grid without its centre 2×2 cells: lscm's best size holds 4.3 % more samples than
  // isochart's 24², and the row had no note.
  const fs::path dir = fresh_dir("ring");
  const fs::path mesh = dir / "ring.obj", out = dir / "out", err = dir / "stderr.txt";
  {
    std::ofstream f(mesh);
    const int n = 10;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) f << "v " << double(i) / n << " " << double(j) / n << " 0\n";
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (i >= 3 && i <= 6 && j >= 3 && j <= 6) continue;
        const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 2, d = a + n + 1;
        f << "f " << a << " " << b << " " << c << "\nf " << a << " " << c << " " << d << "\n";
      }
  }
  REQUIRE(run_cli("bench '" + mesh.string() +
                      "' --methods isochart,lscm --res 24 --psnr-samples 2000 --sweep none "
                      "--no-plots --out '" +
                      out.string() + "'",
                  err) == 0);
  const auto rows = read_csv(out / "bench.csv");
  REQUIRE(rows.size() == 2);
  for (const auto& r : rows) {
    INFO(r.at("method") << " " << r.at("defined_diff_percent") << " " << r.at("note"));
    const bool off = std::abs(std::stod(r.at("defined_diff_percent"))) > 2;
    CHECK(off == (r.at("note").find("% off the first method's") != std::string::npos));
  }
}

TEST_CASE("bench: an external atlas of another surface is an n/a row", "[bench]") {
  // Moved by half its size: the same face count, so it was benched, and its remesh measured
  // against its own geometry scored like an atlas of this mesh.
  const fs::path dir = fresh_dir("moved_atlas");
  const fs::path mesh = dir / "quad.obj", moved = dir / "moved.obj";
  std::ofstream(mesh) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
  std::ofstream(moved)
      << "v 0.5 0 0\nv 1.5 0 0\nv 1.5 1 0\nv 0.5 1 0\nvt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 "
         "0.9\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
  const auto rows = bench_against(mesh, moved, dir);
  CHECK(rows[1].at("method") == "external:moved");
  CHECK(rows[1].at("note").rfind("n/a: the atlas is not of the input mesh", 0) == 0);
  CHECK(rows[1].at("psnr_db").empty());
}

TEST_CASE("bench: an atlas with a flipped triangle says why its stretch is inf", "[bench]") {
  const fs::path dir = fresh_dir("flipped_atlas");
  const fs::path mesh = dir / "quad.obj", flip = dir / "flip.obj";
  const std::string geometry = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 0\n";
  std::ofstream(mesh) << geometry << "f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n";
  // The centre's vt below the bottom edge's: the bottom triangle turns over.
  std::ofstream(flip) << geometry
                      << "vt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 0.9\nvt 0.5 0.08\n"
                         "f 1/1 2/2 5/5\nf 2/2 3/3 5/5\nf 3/3 4/4 5/5\nf 4/4 1/1 5/5\n";
  const auto rows = bench_against(mesh, flip, dir);
  CHECK(rows[1].at("l2") == "inf");
  CHECK_THAT(rows[1].at("note"), Catch::Contains("1 UV triangle flipped or collapsed: stretch infinite"));
  CHECK(rows[0].at("note").find("stretch infinite") == std::string::npos);
}

TEST_CASE("bench: only external methods and no baseline atlas for the mesh: an n/a row saying so",
          "[bench]") {
  const fs::path dir = fresh_dir("no_baseline");
  const fs::path out = dir / "out", err = dir / "stderr.txt";
  fs::create_directories(dir / "data" / "baseline_atlases");
  // Nothing to compare at all is a failed run (it exited 0 with one n/a row), saying why.
  REQUIRE(run_cli("bench builtin:sphere --methods external --data '" + (dir / "data").string() +
                      "' --sweep none --no-plots --out '" + out.string() + "'",
                  err) == 2);
  {
    std::ifstream e(err);
    const std::string text((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
    CHECK_THAT(text, Catch::Contains("no method gave a result on any mesh (no baseline atlas "));
    CHECK_THAT(text, Catch::Contains("sphere_*.obj)"));
  }
  CHECK(!fs::exists(out / "bench.csv"));
  // With a mesh that has one, the other's row is n/a and says why.
  REQUIRE(
      run_cli("atlas builtin:torus -o '" + (dir / "data" / "baseline_atlases" / "torus_x.obj").string() + "'",
              err) == 0);
  REQUIRE(run_cli("bench builtin:sphere builtin:torus --methods external --data '" + (dir / "data").string() +
                      "' --res 16 --sweep none --no-plots --out '" + out.string() + "'",
                  err) == 0);
  const auto rows = read_csv(out / "bench.csv");
  REQUIRE(rows.size() == 2);
  CHECK(rows[0].at("method") == "external");
  CHECK(rows[0].at("note").rfind("n/a: no baseline atlas ", 0) == 0);
  CHECK(rows[0].at("note").find("sphere_*.obj") != std::string::npos);
  // Among other methods the row is left out, but bench.md says so (it did not). Without a
  // sweep no sweep.csv is written, and an earlier run's is not left to be taken for this one's.
  std::ofstream(out / "sweep.csv") << "mesh,method,bound,charts,l2\n";
  REQUIRE(run_cli("bench builtin:sphere --methods isochart,external --data '" + (dir / "data").string() +
                      "' --res 16 --sweep none --no-plots --out '" + out.string() + "'",
                  err) == 0);
  CHECK(read_csv(out / "bench.csv").size() == 1);
  std::ifstream md(out / "bench.md");
  const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  CHECK_THAT(text, Catch::Contains("No `external` rows for sphere: no baseline atlases in"));
  CHECK(!fs::exists(out / "sweep.csv"));
}

TEST_CASE("bench: plots of an earlier run into the same directory are removed", "[bench]") {
  const fs::path dir = fresh_dir("stale_plots");
  const fs::path out = dir / "out", err = dir / "stderr.txt";
  fs::create_directories(out);
  for (const char* f : {"psnr.png", "stretch_bunny.png", "notes.png"}) std::ofstream(out / f) << "old";
  REQUIRE(
      run_cli("bench builtin:sphere --methods isochart --res 16 --psnr-samples 2000 --sweep none --no-plots "
              "--out '" +
                  out.string() + "'",
              err) == 0);
  CHECK_FALSE(fs::exists(out / "psnr.png"));
  CHECK_FALSE(fs::exists(out / "stretch_bunny.png"));
  // Files the bench does not write are the user's.
  CHECK(fs::exists(out / "notes.png"));
  CHECK(fs::exists(out / "bench.md"));
}

TEST_CASE("bench: bad inputs are one line and exit code 2", "[bench]") {
  const fs::path dir = fresh_dir("bad");
  const fs::path err = dir / "stderr.txt";
  const std::string out = " --out '" + (dir / "out").string() + "'";
  const fs::path bad = dir / "bad.obj";
  std::ofstream(bad) << "v 0 0 0\nv 1 0 0\nf 1 2 9\n";
  std::ofstream(dir / "sphere.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  struct Case {
    std::string args, expect;
  };
  for (const Case& c : std::vector<Case>{
           {"bench builtin:sphere --methods isochart,foo", "unknown method 'foo'"},
           {"bench builtin:sphere --methods isochart,isochart", "given twice"},
           {"bench builtin:sphere --methods external:/nonexistent/x.obj", "/nonexistent/x.obj: no such file"},
           {"bench /nonexistent/mesh.obj --methods isochart", "/nonexistent/mesh.obj: no such file"},
           {"bench builtin:sphere --res 3", "--res must be between 8 and 2048"},
           {"bench builtin:sphere --max-l2 inf", "--max-l2 must be a finite number of at least 1"},
           {"bench builtin:sphere --max-linf inf", "--max-linf must be a finite number of at least 1"},
           {"bench builtin:sphere --res 4096", "--res must be between 8 and 2048"},
           {"bench builtin:sphere --sweep 1.1,abc", "--sweep: 'abc'"},
           // Found before any work, and before the output directory is made: an unreadable
           // mesh found after the others threw their rows away, a mistyped --data benched the
           // built-in meshes, and two meshes of one name were merged in the tables.
           {"bench builtin:sphere '" + bad.string() + "' --methods lscm --sweep none",
            "line 3: vertex index 9 is out of range"},
           // An external atlas given by name that cannot be read: not an n/a row per mesh.
           {"bench builtin:sphere --methods external:'" + bad.string() + "' --sweep none",
            "line 3: vertex index 9 is out of range"},
           {"bench --methods lscm --data /nonexistent/data --sweep none",
            "/nonexistent/data: --data: no such directory"},
           {"bench builtin:sphere '" + (dir / "sphere.obj").string() + "' --methods lscm",
            "are both named 'sphere'"},
       }) {
    INFO(c.args);
    CHECK(run_cli(c.args + out, err) == 2);
    const std::string e = slurp(err);
    CHECK(count_lines(e) == 1);
    CHECK(e.rfind("isocharts: error: ", 0) == 0);
    CHECK(e.find(c.expect) != std::string::npos);
  }
  CHECK(!fs::exists(dir / "out"));
  // --out naming a file said only that the directory could not be created.
  CHECK(run_cli("bench builtin:sphere --methods lscm --sweep none --out '" + bad.string() + "'", err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains("--out takes a directory") && Catch::Contains("this is a file"));
}

TEST_CASE("bench: equal PSNR is a tie, not a win for lscm", "[bench]") {
  // One triangle: both methods make the same one-chart atlas and the same remesh.
  const fs::path dir = fresh_dir("tie");
  const fs::path mesh = dir / "tri.obj", out = dir / "out", err = dir / "stderr.txt";
  std::ofstream(mesh) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  REQUIRE(run_cli("-q bench '" + mesh.string() +
                      "' --methods isochart,lscm --res 64 --sweep none --no-plots --out '" + out.string() +
                      "'",
                  err) == 0);
  const std::string md = slurp(out / "bench.md");
  CHECK_THAT(md, Catch::Contains("PSNR isochart − lscm = 0.00 dB") && Catch::Contains("a tie on PSNR"));
  CHECK(md.find("lscm wins") == std::string::npos);
}

TEST_CASE("bench: an exact remesh reads PSNR inf, not a failure", "[bench]") {
  // A flat strip 4e4 times as long as wide: both remeshes reproduce it exactly. The table
  // showed "–", the CSV nothing and the summary "no comparison ()".
  const fs::path dir = fresh_dir("exact");
  const fs::path mesh = dir / "strip.obj", out = dir / "out", err = dir / "stderr.txt";
  {
    std::ofstream f(mesh);
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i <= 40; ++i) f << "v " << 0.025 * i << " " << 5e-5 * j << " 0\n";
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 40; ++i) {
        const int a = j * 41 + i + 1;
        f << "f " << a << " " << a + 1 << " " << a + 42 << "\nf " << a << " " << a + 42 << " " << a + 41
          << "\n";
      }
  }
  REQUIRE(run_cli("-q bench '" + mesh.string() +
                      "' --methods isochart,lscm --res 32 --sweep none --no-plots --out '" + out.string() +
                      "'",
                  err) == 0);
  const auto rows = read_csv(out / "bench.csv");
  REQUIRE(rows.size() == 2);
  for (const auto& r : rows) CHECK(r.at("psnr_db") == "inf");
  const std::string md = slurp(out / "bench.md");
  CHECK_THAT(md, Catch::Contains("| inf |") && Catch::Contains("both remeshes are exact (PSNR inf)"));
}
