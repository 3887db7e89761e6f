#include "isochart/geodesic.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "isochart/error.h"
#include "isochart/geo_test_meshes.h"

using namespace isochart;
using geo_test::kPi;

namespace {

struct ErrorStats {
  double mean_relative = 0;  // mean over vertices of |d − ref| / ref
  double max_relative = 0;
  double max_absolute = 0;
  int count = 0;
};

// Compares `d` with `ref` at vertices whose reference distance exceeds `min_ref`.
ErrorStats compare(const std::vector<double>& d, const std::vector<double>& ref, double min_ref) {
  ErrorStats s;
  for (std::size_t v = 0; v < d.size(); ++v) {
    if (!(ref[v] > min_ref) || !std::isfinite(ref[v])) continue;
    const double abs_err = std::abs(d[v] - ref[v]);
    s.mean_relative += abs_err / ref[v];
    s.max_relative = std::max(s.max_relative, abs_err / ref[v]);
    s.max_absolute = std::max(s.max_absolute, abs_err);
    ++s.count;
  }
  if (s.count) s.mean_relative /= s.count;
  return s;
}

double mean_edge(const Mesh& m) {
  return mean_edge_length(m, Topology(m));
}

// The straight-line distance can never exceed the distance over the surface (up to the float
// rounding of the solver's stored geometry, 1e-7 relative).
void check_euclidean_lower_bound(const Mesh& m, int source, const std::vector<double>& d) {
  int violations = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const double e = norm(m.positions[v] - m.positions[source]);
    if (d[v] < e * (1 - 1e-6)) ++violations;
  }
  CHECK(violations == 0);
}

}  // namespace

TEST_CASE("fast marching reproduces Euclidean distances on a plane", "[geodesic]") {
  struct Case {
    const char* name;
    Mesh mesh;
    double mean_tolerance, max_tolerance;
  };
  // A right-triangle grid (exact up to the solver's float geometry, measured 2e-8) and a
  // sheared, jittered one full of obtuse triangles (measured mean 8e-5, max 2%, at the source).
  const Case cases[] = {
      {"regular grid", geo_test::grid(40, 30, 4.0, 3.0), 1e-6, 1e-5},
      {"sheared jittered grid", geo_test::grid(40, 40, 4.0, 4.0, 0.6, 0.5), 5e-4, 0.05},
  };
  for (const Case& c : cases) {
    const GeodesicSolver solver(c.mesh);
    for (int source : {0, c.mesh.num_vertices() / 2 + 7, c.mesh.num_vertices() - 1}) {
      std::vector<double> d, ref(c.mesh.num_vertices());
      solver.distances({source}, d);
      for (int v = 0; v < c.mesh.num_vertices(); ++v)
        ref[v] = norm(c.mesh.positions[v] - c.mesh.positions[source]);
      const ErrorStats e = compare(d, ref, 0);
      INFO(c.name << " source " << source << ": mean relative error " << e.mean_relative << ", max relative "
                  << e.max_relative << ", max absolute " << e.max_absolute);
      CHECK(e.mean_relative < c.mean_tolerance);
      CHECK(e.max_relative < c.max_tolerance);
      CHECK(d[source] == 0);
      check_euclidean_lower_bound(c.mesh, source, d);
    }
  }
}

TEST_CASE("obtuse triangles are split by unfolding", "[geodesic]") {
  const Mesh m = geo_test::grid(20, 20, 2.0, 2.0, 0.8, 0.0);
  const GeodesicSolver solver(m);
  INFO("split " << solver.num_split_obtuse() << ", unsplit " << solver.num_unsplit_obtuse());
  CHECK(solver.num_split_obtuse() > 300);
  // Only corners along the boundary lack the triangles to unfold into.
  CHECK(solver.num_unsplit_obtuse() < 100);
  // Along the shear the triangles are very obtuse; distances must stay close to Euclidean.
  std::vector<double> d;
  const int source = 10 * 21 + 10;
  solver.distances({source}, d);
  std::vector<double> ref(m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v) ref[v] = norm(m.positions[v] - m.positions[source]);
  const ErrorStats e = compare(d, ref, 0);
  INFO("mean relative error " << e.mean_relative << ", max " << e.max_relative);
  CHECK(e.mean_relative < 5e-3);
  CHECK(e.max_relative < 0.03);
}

TEST_CASE("fast marching is close to CGAL's exact geodesics", "[geodesic][cgal]") {
  struct Case {
    const char* name;
    Mesh mesh;
  };
  const Case cases[] = {
      {"icosphere", geo_test::icosphere(4)},          // 2562 vertices
      {"torus", geo_test::torus(64, 28, 1.0, 0.35)},  // 1792 vertices
      {"bumpy patch", geo_test::bumpy_patch(44)},     // 2025 vertices, many obtuse triangles
  };
  for (const Case& c : cases) {
    const GeodesicSolver solver(c.mesh);
    const double h = mean_edge(c.mesh);
    const int n = c.mesh.num_vertices();
    double mean_sum = 0;
    int runs = 0;
    for (int source : {0, n / 3, (2 * n) / 3 + 5}) {
      const std::vector<double> ref = exact_geodesic_distances(c.mesh.positions, c.mesh.faces, source);
      std::vector<double> d;
      solver.distances({source}, d);
      // Relative error is meaningless right at the source; skip the first ring.
      const ErrorStats e = compare(d, ref, 1.5 * h);
      INFO(c.name << " source " << source << ": mean relative error " << e.mean_relative << ", max relative "
                  << e.max_relative << ", max absolute " << e.max_absolute << " (mean edge " << h << ", "
                  << e.count << " vertices)");
      CHECK(e.count > n / 2);
      CHECK(e.mean_relative < 0.02);
      CHECK(e.max_absolute < 3 * h);
      check_euclidean_lower_bound(c.mesh, source, d);
      // Fast marching may undercut the exact distance where unfolding flattens curvature, but
      // by a fraction of an edge at most.
      int below = 0;
      for (int v = 0; v < n; ++v)
        if (d[v] < ref[v] - 0.75 * h) ++below;
      CHECK(below == 0);
      mean_sum += e.mean_relative;
      ++runs;
    }
    INFO(c.name << ": mean relative error over sources " << mean_sum / runs);
    CHECK(mean_sum / runs < 0.02);
  }
}

TEST_CASE("fast marching on a sphere matches great-circle distances", "[geodesic]") {
  const Mesh m = geo_test::icosphere(4);
  const GeodesicSolver solver(m);
  std::vector<double> d;
  solver.distances({7}, d);
  std::vector<double> ref(m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v)
    ref[v] = std::acos(std::clamp(dot(m.positions[v], m.positions[7]), -1.0, 1.0));
  const ErrorStats e = compare(d, ref, 0.1);
  INFO("mean relative error " << e.mean_relative << ", max absolute " << e.max_absolute);
  // The polyhedron is slightly shorter than the sphere; the mean error stays within a percent.
  CHECK(e.mean_relative < 0.01);
  CHECK(e.max_absolute < 0.05);
}

TEST_CASE("distances are nearly symmetric", "[geodesic]") {
  const Mesh m = geo_test::bumpy_patch(30);
  const GeodesicSolver solver(m);
  const std::vector<int> ids{0, 100, 333, 500, 777, 960};
  const std::vector<double> rows = solver.distance_rows(ids);
  const std::size_t n = m.positions.size();
  for (std::size_t i = 0; i < ids.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const double a = rows[i * n + ids[j]], b = rows[j * n + ids[i]];
      CHECK(std::abs(a - b) < 0.01 * std::max(a, b));
    }
}

TEST_CASE("several sources, components, boundaries and unreferenced vertices", "[geodesic]") {
  // Two separate patches plus one isolated vertex.
  Mesh m = geo_test::grid(10, 10, 1.0, 1.0);
  const Mesh other = geo_test::grid(6, 6, 1.0, 1.0, 0.3);
  const int offset = m.num_vertices();
  for (const auto& p : other.positions) m.positions.push_back(p + Vec3d{5, 0, 0});
  for (const auto& f : other.faces) m.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  m.positions.push_back({9, 9, 9});
  const int isolated = m.num_vertices() - 1;
  const GeodesicSolver solver(m);
  CHECK_FALSE(solver.is_referenced(isolated));
  CHECK(solver.is_referenced(0));

  std::vector<double> d;
  solver.distances({0}, d);
  for (int v = 0; v < offset; ++v) CHECK(std::isfinite(d[v]));
  for (int v = offset; v < m.num_vertices(); ++v) CHECK(std::isinf(d[v]));

  // Two sources in different components reach both; an isolated source only itself.
  solver.distances({3, offset + 5, isolated}, d);
  for (int v = 0; v < m.num_vertices(); ++v) CHECK(std::isfinite(d[v]));
  CHECK(d[isolated] == 0);
  CHECK(d[offset + 5] == 0);

  // Two sources in one component: close to the minimum of the single-source fields, and never
  // below it (a triangle update mixing both fronts would cut the corner along the bisector).
  const Mesh bumpy = geo_test::bumpy_patch(40);
  const GeodesicSolver bumpy_solver(bumpy);
  const int last = bumpy.num_vertices() - 1;
  std::vector<double> a, b, both;
  bumpy_solver.distances({0}, a);
  bumpy_solver.distances({last}, b);
  bumpy_solver.distances({0, last}, both);
  const double h = mean_edge(bumpy);
  for (int v = 0; v <= last; ++v) {
    const double lo = std::min(a[v], b[v]);
    CHECK(both[v] >= lo - 1e-12);
    CHECK(both[v] <= lo + 0.01 * h);
  }
}

TEST_CASE("max_distance stops the front without changing the distances inside", "[geodesic]") {
  const Mesh m = geo_test::torus(48, 20, 1.0, 0.3);
  const GeodesicSolver solver(m);
  std::vector<double> full, part;
  solver.distances({5}, full);
  const double limit = 1.2;
  solver.distances({5}, part, limit);
  int inside = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (full[v] <= limit) {
      CHECK(part[v] == full[v]);
      ++inside;
    } else {
      CHECK(std::isinf(part[v]));
    }
  }
  CHECK(inside > 50);
  CHECK(inside < m.num_vertices() - 50);
}

TEST_CASE("lower_distances visits only the new cell and matches a two-source run", "[geodesic]") {
  const Mesh m = geo_test::bumpy_patch(40);
  const GeodesicSolver solver(m);
  const int n = m.num_vertices();
  std::vector<double> field(n, GeodesicSolver::inf);
  CHECK(solver.lower_distances(0, field) == n);
  std::vector<double> single;
  solver.distances({0}, single);
  for (int v = 0; v < n; ++v) CHECK(field[v] == single[v]);

  const int second = n - 1;
  const int visited = solver.lower_distances(second, field);
  CHECK(visited > n / 8);
  CHECK(visited < (3 * n) / 4);
  std::vector<double> both;
  solver.distances({0, second}, both);
  const double h = mean_edge(m);
  for (int v = 0; v < n; ++v) {
    CHECK(field[v] <= single[v]);
    CHECK(std::abs(field[v] - both[v]) < 0.1 * h);
  }
}

TEST_CASE("parallel rows equal sequential runs for any thread count", "[geodesic]") {
  const Mesh m = geo_test::icosphere(3);
  const GeodesicSolver solver(m);
  std::vector<int> sources;
  for (int i = 0; i < 24; ++i) sources.push_back((i * 97) % m.num_vertices());
  std::vector<double> seq;
  for (int s : sources) {
    std::vector<double> d;
    solver.distances({s}, d);
    seq.insert(seq.end(), d.begin(), d.end());
  }
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    CHECK(solver.distance_rows(sources) == seq);
  }
}

TEST_CASE("bad input is reported", "[geodesic]") {
  const std::vector<Vec3d> p{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  CHECK_THROWS_AS(GeodesicSolver(p, {{0, 1, 3}}), InputError);
  CHECK_THROWS_AS(GeodesicSolver({{0, 0, 0}, {1, 0, 0}, {0, std::nan(""), 0}}, {{0, 1, 2}}), InputError);
  const GeodesicSolver solver(p, {{0, 1, 2}});
  std::vector<double> d;
  CHECK_THROWS_AS(solver.distances({3}, d), Error);
  std::vector<double> short_field(2, GeodesicSolver::inf);
  CHECK_THROWS_AS(solver.lower_distances(0, short_field), Error);
  CHECK_THROWS_AS(solver.distances({-1}, d), Error);
  solver.distances({0}, d);
  CHECK(d[1] == Approx(1.0));
  CHECK(d[2] == Approx(1.0));
  // A degenerate face (repeated vertex) is ignored rather than trusted.
  const GeodesicSolver degenerate(p, {{0, 1, 1}});
  degenerate.distances({0}, d);
  CHECK(std::isinf(d[1]));
}
