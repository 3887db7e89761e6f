#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace fs = std::filesystem;

namespace {

struct CliRun {
  fs::path dir;
  explicit CliRun(const std::string& name)
      : dir(fs::temp_directory_path() / ("isocharts_" + name + "_" + std::to_string(::getpid()))) {
    fs::create_directories(dir);
  }
  ~CliRun() { fs::remove_all(dir); }
  int operator()(const std::string& args) const {
    const std::string cmd = std::string(ISOCHARTS_CLI) + " " + args + " > " + (dir / "stdout.txt").string() +
                            " 2> " + (dir / "stderr.txt").string();
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  nlohmann::json json() const {
    std::ifstream in(dir / "stdout.txt");
    return nlohmann::json::parse(in);
  }
};

}  // namespace

TEST_CASE("isocharts psnr reports distances and rejects bad input", "[mcgim][cli]") {
  const CliRun run("psnr_test");
  REQUIRE(run("psnr builtin:sphere builtin:sphere --samples 2000 --json") == 0);
  const nlohmann::json j = run.json();
  CHECK((j["psnr"].is_null() || j["psnr"].get<double>() >= 150.0));
  CHECK(j["hausdorff"].get<double>() < 1e-9);
  CHECK(j["samples_a"].get<long long>() == 2000);
  REQUIRE(run("psnr builtin:sphere builtin:torus --samples 2000 --json") == 0);
  const nlohmann::json k = run.json();
  CHECK(k["psnr"].get<double>() < 40.0);
  CHECK(k["rms_ab"].get<double>() > 0);
  CHECK(run("psnr builtin:sphere " + (run.dir / "missing.off").string()) == 2);
  CHECK(run("psnr builtin:sphere builtin:sphere --samples 0") == 2);
}

TEST_CASE("isocharts remesh writes watertight levels and reports them", "[mcgim][cli]") {
  const CliRun run("remesh_test");
  const std::string out = (run.dir / "sphere.ply").string(), pre = (run.dir / "gim").string();
  REQUIRE(run("remesh builtin:sphere -o " + out + " --levels 64,32 --psnr-samples 20000 --png " + pre + " --exr " + pre +
              " --json") == 0);
  const nlohmann::json j = run.json();
  REQUIRE(j["levels"].size() == 2);
  for (const auto& lv : j["levels"]) {
    CHECK(lv["closed"].get<bool>());
    CHECK(lv["manifold"].get<bool>());
    CHECK(lv["euler_preserved"].get<bool>());
    CHECK(lv["psnr"].get<double>() > 30.0);
    CHECK(lv["defined_samples"].get<long long>() >= lv["unique_vertices"].get<long long>());
  }
  CHECK(j["levels"][0]["resolution"][0] == 64);
  CHECK(j["levels"][1]["correspondence_samples"] == 0);
  CHECK(fs::exists(out));
  CHECK(fs::exists(run.dir / "sphere_32.ply"));
  CHECK(fs::exists(pre + "_64x64.exr"));
  CHECK(fs::exists(pre + "_32x32.png"));
  // Bad input exits with 2: exclusive sizes, a bad output extension, an atlas without UVs.
  CHECK(run("remesh builtin:sphere -o " + out + " --res 64 --samples 1000") == 2);
  CHECK(run("remesh builtin:sphere -o " + (run.dir / "x.xyz").string()) == 2);
  // Warnings printed on stderr are in the JSON too (also with -q, which silences stderr).
  REQUIRE(run("-q remesh builtin:torus -o " + (run.dir / "t.ply").string() + " --res 12 --no-psnr --json") ==
          0);
  {
    const nlohmann::json w = run.json()["warnings"];
    REQUIRE(w.size() == 1);
    CHECK(w[0].get<std::string>().find("12x12 level does not keep the input's topology") !=
          std::string::npos);
  }
  // A format remesh reads but does not write is refused before any work, saying what it writes.
  CHECK(run("remesh builtin:sphere -o " + (run.dir / "x.off").string()) == 2);
  {
    std::ifstream err(run.dir / "stderr.txt");
    std::string line;
    std::getline(err, line);
    CHECK(line.find("x.off: cannot write '.off' files (this command writes .ply, .obj or .glb)") !=
          std::string::npos);
  }
  CHECK(run("remesh builtin:sphere -o " + out + " --atlas builtin:torus") == 2);
  CHECK(run("remesh builtin:sphere -o " + out + " --res 1") == 2);
  // Too small for any 2x2 block of samples: an empty remesh is refused, not written (it was
  // written with exit 0 and reported closed and manifold), alone or as a pyramid level.
  const std::string tiny = (run.dir / "tiny.ply").string();
  for (const std::string sizes : {"--res 8", "--levels 32,8"}) {
    CHECK(run("remesh builtin:torus -o " + tiny + " --no-psnr " + sizes) == 2);
    std::ifstream err(run.dir / "stderr.txt");
    const std::string message((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
    CHECK(message.find("8x8 level: no 2x2 block of defined samples") != std::string::npos);
    CHECK_FALSE(fs::exists(tiny));
  }
  CHECK(run("remesh builtin:sphere -o " + out + " --signal normals --atlas " + out) == 2);
  CHECK(run("remesh builtin:sphere -o " + out + " --signal normals --signal-use all") == 2);
  CHECK(run("remesh builtin:sphere -o " + out + " --signal colors") == 2);  // no colours
  // An external atlas must be of the input's surface: the sphere's own atlas is, the torus's not.
  const std::string sphere_atlas = (run.dir / "sphere_atlas.obj").string(),
                    torus_atlas = (run.dir / "torus_atlas.obj").string();
  REQUIRE(run("atlas builtin:sphere -o " + sphere_atlas) == 0);
  REQUIRE(run("atlas builtin:torus -o " + torus_atlas) == 0);
  CHECK(run("remesh builtin:sphere -o " + out + " --res 32 --no-psnr --atlas " + sphere_atlas) == 0);
  CHECK(run("remesh builtin:sphere -o " + out + " --res 32 --no-psnr --atlas " + torus_atlas) == 2);
}

TEST_CASE("isocharts remesh --signal builds a signal-specialized atlas", "[mcgim][cli]") {
  const CliRun run("remesh_signal_test");
  const std::string out = (run.dir / "torus.ply").string();
  REQUIRE(run("remesh builtin:torus -o " + out + " --res 64 --psnr-samples 20000 --signal normals --json") == 0);
  const nlohmann::json j = run.json();
  CHECK(j["atlas"]["source"].get<std::string>().find("signal normals") != std::string::npos);
  CHECK(j["atlas"]["signal_stretch"].get<double>() > 0);
  const auto& lv = j["levels"][0];
  CHECK(lv["closed"].get<bool>());
  CHECK(lv["manifold"].get<bool>());
  CHECK(lv["euler_preserved"].get<bool>());
  CHECK(lv["psnr"].get<double>() > 30.0);
}

TEST_CASE("isocharts remesh keeps plane_holes' windows at 64² without a pinched vertex",
          "[mcgim][cli][slow]") {
  // plane_holes at 64²: 27 windows about two texels across. The level kept their loops and the
  // Euler characteristic but pinched one vertex where two windows are closer than a sample
  // (warned). Trying the best layout again with the sample grid at other phases on the charts
  // finds one without the pinch.
  const CliRun run("pinched_test");
  const std::string mesh = std::string(ISOCHARTS_SHARED_DATA) + "/meshes/plane_holes.obj";
  REQUIRE(run("remesh " + mesh + " -o " + (run.dir / "p.ply").string() + " --res 64 --no-psnr --json") == 0);
  const nlohmann::json j = run.json();
  const nlohmann::json& level = j["levels"][0];
  CHECK(level["boundary_loops"] == 27);
  CHECK(level["euler_preserved"] == true);
  CHECK(level["manifold"] == true);
  for (const auto& w : j["warnings"]) CHECK(w.get<std::string>().find("64x64 level") == std::string::npos);
}

TEST_CASE("isocharts remesh names the charts a level lost while keeping the topology", "[mcgim][cli][slow]") {
  // plane_holes at 67²: the topology is kept, but one engine chart got no sample and others few,
  // and the zipper contracted them onto their neighbours' seams: Hausdorff 2.7 (11 texels)
  // against 0.3 at 66², with no word said. The level's report and warnings now say it.
  const CliRun run("lost_charts_test");
  const std::string mesh = std::string(ISOCHARTS_SHARED_DATA) + "/meshes/plane_holes.obj";
  auto level = [&](int res, nlohmann::json& j) {
    REQUIRE(run("remesh " + mesh + " -o " + (run.dir / "p.ply").string() + " --res " + std::to_string(res) +
                " --json") == 0);
    j = run.json();
    return j["levels"][0];
  };
  nlohmann::json j;
  nlohmann::json lv = level(67, j);
  CHECK(lv["euler_preserved"] == true);
  CHECK(lv["lost_charts"].get<int>() >= 1);
  CHECK(lv["hausdorff"].get<double>() > 3 * lv["texel_size"].get<double>());
  bool warned = false;
  for (const auto& w : j["warnings"])
    warned |= w.get<std::string>().find("67x67 level lost part of the surface") != std::string::npos;
  CHECK(warned);
  lv = level(66, j);
  CHECK(lv["lost_charts"] == 0);
  CHECK(lv["hausdorff"].get<double>() < 3 * lv["texel_size"].get<double>());
  CHECK(j["warnings"].empty());
}
