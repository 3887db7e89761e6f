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
