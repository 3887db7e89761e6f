#include "isochart/builtin.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "isochart/error.h"
#include "isochart/mesh.h"

using namespace isochart;

namespace {

// The creature takes a noticeable fraction of a second; build each mesh once.
const Mesh& builtin(const std::string& name) {
  static std::map<std::string, Mesh> cache;
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, make_builtin(name)).first;
  return it->second;
}

double signed_volume(const Mesh& m) {
  double v = 0;
  for (const Face& f : m.faces) v += dot(m.positions[f[0]], cross(m.positions[f[1]], m.positions[f[2]])) / 6;
  return v;
}

double min_angle_degrees(const Mesh& m) {
  double best = 180;
  for (const Face& f : m.faces)
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = m.positions[f[k]];
      const Vec3d a = m.positions[f[(k + 1) % 3]] - p, b = m.positions[f[(k + 2) % 3]] - p;
      best = std::min(best, std::atan2(norm(cross(a, b)), dot(a, b)) * 180 / 3.14159265358979323846);
    }
  return best;
}

// Consistent orientation: every directed edge is used by at most one face.
bool consistently_oriented(const Mesh& m) {
  std::vector<std::pair<int, int>> directed;
  for (const Face& f : m.faces)
    for (int k = 0; k < 3; ++k) directed.push_back({f[k], f[(k + 1) % 3]});
  std::sort(directed.begin(), directed.end());
  return std::adjacent_find(directed.begin(), directed.end()) == directed.end();
}

int duplicate_vertices(const Mesh& m) {
  std::vector<Vec3d> p = m.positions;
  std::sort(p.begin(), p.end(), [](const Vec3d& a, const Vec3d& b) {
    return a.x != b.x ? a.x < b.x : (a.y != b.y ? a.y < b.y : a.z < b.z);
  });
  int duplicates = 0;
  for (std::size_t i = 1; i < p.size(); ++i) duplicates += p[i] == p[i - 1];
  return duplicates;
}

void check_clean(const Mesh& m) {
  const Topology t(m);
  CHECK(t.num_components() == 1);
  CHECK(t.is_manifold());
  CHECK(t.num_referenced_vertices() == m.num_vertices());
  CHECK(consistently_oriented(m));
  CHECK(duplicate_vertices(m) == 0);
  // No slivers: measured minima are 54° (sphere), 30° (torus), 19° (face), 17° (creature).
  CHECK(min_angle_degrees(m) > 15.0);
}

}  // namespace

TEST_CASE("builtin names are all buildable", "[builtin]") {
  const auto names = builtin_names();
  REQUIRE(names.size() == 4);
  for (const auto& n : names) CHECK(builtin(n).num_faces() > 0);
}

TEST_CASE("builtin sphere is a clean closed genus-0 surface", "[builtin]") {
  const Mesh& m = builtin("sphere");
  CHECK(m.num_faces() >= 4000);
  CHECK(m.num_faces() <= 6000);
  const Topology t(m);
  CHECK(t.boundary_loops().empty());
  CHECK(t.genus() == 0);
  check_clean(m);
  CHECK(signed_volume(m) > 0);
  for (const Vec3d& p : m.positions) CHECK(std::abs(norm(p) - 1) < 1e-12);
}

TEST_CASE("builtin torus is a clean closed genus-1 surface", "[builtin]") {
  const Mesh& m = builtin("torus");
  CHECK(m.num_faces() >= 4000);
  CHECK(m.num_faces() <= 6000);
  const Topology t(m);
  CHECK(t.boundary_loops().empty());
  CHECK(t.genus() == 1);
  CHECK(t.euler_characteristic() == 0);
  check_clean(m);
  CHECK(signed_volume(m) > 0);
}

TEST_CASE("builtin creature is a clean closed genus-0 surface", "[builtin]") {
  const Mesh& m = builtin("creature");
  CHECK(m.num_faces() >= 20000);
  CHECK(m.num_faces() <= 40000);
  const Topology t(m);
  CHECK(t.boundary_loops().empty());
  CHECK(t.genus() == 0);
  CHECK(t.euler_characteristic() == 2);
  check_clean(m);
  CHECK(signed_volume(m) > 0);
}

TEST_CASE("builtin creature has protruding head, ears, legs and tail", "[builtin]") {
  // +x forward, +y up: look for surface points at the tips of each appendage.
  const Mesh& m = builtin("creature");
  int feet[4] = {0, 0, 0, 0}, ears[2] = {0, 0}, tail = 0, snout = 0;
  for (const Vec3d& p : m.positions) {
    if (p.y < -0.95) ++feet[(p.x > 0 ? 2 : 0) + (p.z > 0 ? 1 : 0)];
    if (p.y > 1.2 && p.x > 0.7) ++ears[p.z > 0 ? 1 : 0];
    if (p.x < -1.3 && p.y > 0.5) ++tail;
    if (p.x > 1.5) ++snout;
  }
  for (int n : feet) CHECK(n > 0);
  for (int n : ears) CHECK(n > 0);
  CHECK(tail > 0);
  CHECK(snout > 0);
  // Between the legs, under the belly, there is no surface: the legs stand apart.
  for (const Vec3d& p : m.positions) {
    const bool under_belly = p.y < -0.6 && std::abs(p.x) < 0.25;
    const bool between_left_and_right = p.y < -0.6 && std::abs(p.z) < 0.08;
    if (under_belly || between_left_and_right)
      FAIL("surface point between the legs at " << p.x << ", " << p.y << ", " << p.z);
  }
}

TEST_CASE("builtin face is a clean disk facing +z", "[builtin]") {
  const Mesh& m = builtin("face");
  CHECK(m.num_faces() >= 8000);
  CHECK(m.num_faces() <= 12000);
  const Topology t(m);
  REQUIRE(t.boundary_loops().size() == 1);
  CHECK(t.genus() == 0);
  CHECK(t.euler_characteristic() == 1);
  check_clean(m);
  // A height field over the xy-plane, every triangle facing the viewer on +z.
  int facing_away = 0;
  for (const Vec3d& n : face_normals(m)) facing_away += n.z <= 0;
  CHECK(facing_away == 0);
  // The nose sticks out beyond the cheeks.
  double nose = -1, cheek = -1;
  for (const Vec3d& p : m.positions) {
    if (std::abs(p.x) < 0.03 && std::abs(p.y + 0.13) < 0.05) nose = std::max(nose, p.z);
    if (std::abs(p.x - 0.38) < 0.05 && std::abs(p.y + 0.15) < 0.05) cheek = std::max(cheek, p.z);
  }
  CHECK(nose > cheek + 0.05);
}

TEST_CASE("builtin meshes are deterministic", "[builtin]") {
  for (const auto& name : builtin_names()) {
    const Mesh a = make_builtin(name);
    const Mesh& b = builtin(name);
    CHECK(a.faces == b.faces);
    CHECK(a.positions == b.positions);
  }
}

TEST_CASE("unknown builtin names are input errors listing the valid ones", "[builtin]") {
  try {
    make_builtin("dragon");
    FAIL("no exception");
  } catch (const InputError& e) {
    CHECK(e.file() == "builtin:dragon");
    CHECK(std::string(e.what()).find("creature") != std::string::npos);
  }
}
