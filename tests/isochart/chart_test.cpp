// Internal chart helpers: cutting charts into disks and the LSCM start.
#include <catch2/catch.hpp>
#include <cmath>

#include "../../libisochart/src/chart.h"
#include "isochart/stretch.h"

using namespace isochart;
using namespace isochart::detail;

namespace {

// An annulus in the plane, r in [1, 2], as a chart (two boundary loops).
ChartGeometry annulus(int n = 32, int m = 4) {
  ChartGeometry g;
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n, r = 1 + double(j) / m;
      g.positions.push_back({r * std::cos(a), r * std::sin(a), 0});
      g.vertex_parent.push_back(static_cast<int>(g.vertex_parent.size()));
    }
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * n + i, b = j * n + (i + 1) % n, c = a + n, d = b + n;
      g.tris.push_back({a, d, b});  // counter-clockwise: outward, then along the angle
      g.tris.push_back({a, c, d});
      g.faces.push_back(static_cast<int>(g.faces.size()));
      g.faces.push_back(static_cast<int>(g.faces.size()));
    }
  return g;
}

}  // namespace

TEST_CASE("cut_to_disk slits an annulus into one boundary loop", "[chart]") {
  ChartGeometry g = annulus();
  const int before = g.num_vertices();
  std::vector<int> origin;
  REQUIRE(cut_to_disk(g, &origin));
  const Topology t(g.tris, g.num_vertices());
  CHECK(t.boundary_loops().size() == 1);
  CHECK(t.num_components() == 1);
  CHECK(t.genus() == 0);
  CHECK(g.num_vertices() > before);  // the slit duplicated its vertices
  REQUIRE(origin.size() == static_cast<size_t>(g.num_vertices()));
  for (int v = 0; v < g.num_vertices(); ++v) {
    CHECK(g.positions[v] == g.positions[origin[v]]);
    CHECK(g.vertex_parent[v] == g.vertex_parent[origin[v]]);
  }
}

TEST_CASE("cut_to_disk refuses a closed surface", "[chart]") {
  ChartGeometry g;
  g.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  g.vertex_parent = {0, 1, 2, 3};
  g.tris = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  g.faces = {0, 1, 2, 3};
  CHECK_FALSE(cut_to_disk(g));
}

TEST_CASE("LSCM of a slit planar annulus is conformal and fold-free", "[chart]") {
  ChartGeometry g = annulus();
  REQUIRE(cut_to_disk(g));
  std::vector<Vec2d> uv;
  REQUIRE(lscm(g, uv));
  int negative = 0;
  for (const Face& t : g.tris) negative += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) < 0 ? 1 : 0;
  // Planar input: LSCM reproduces it up to a similarity (either orientation).
  CHECK((negative == 0 || negative == g.num_faces()));
  if (negative) for (auto& p : uv) p.y = -p.y;
  const StretchStats st = measure_stretch(g.positions, g.tris, uv);
  CHECK(st.l2 == Approx(1.0).margin(1e-6));
  CHECK(st.linf == Approx(1.0).margin(1e-6));
}

TEST_CASE("open_slits separates slit copies without flipping", "[chart]") {
  ChartGeometry g = annulus();
  std::vector<int> origin;
  REQUIRE(cut_to_disk(g, &origin));
  std::vector<Vec2d> uv(g.num_vertices());
  for (int v = 0; v < g.num_vertices(); ++v) uv[v] = {g.positions[v].x, g.positions[v].y};
  open_slits(g, origin, uv);
  std::vector<std::array<Vec2d, 3>> tris;
  for (const Face& t : g.tris) {
    CHECK(signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) > 0);
    tris.push_back({uv[t[0]], uv[t[1]], uv[t[2]]});
  }
  CHECK(overlapping_uv_pairs(tris).empty());
  bool moved = false;
  for (int v = 0; v < g.num_vertices(); ++v)
    if (origin[v] != v) moved = moved || uv[v] != uv[origin[v]];
  CHECK(moved);
}

TEST_CASE("multiply_covered_fraction tells a folded layout from a flat one", "[chart]") {
  // A 4×4 grid of squares, two triangles each: edges and corners shared, no overlap.
  std::vector<Vec2d> uv;
  std::vector<Face> tris;
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i) uv.push_back({double(i), double(j)});
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const int a = j * 5 + i, b = a + 1, c = a + 5, d = c + 1;
      tris.push_back({a, b, d});
      tris.push_back({a, d, c});
    }
  // Cell centres fall on the shared edges and corners at this grid size.
  CHECK(multiply_covered_fraction(tris, uv, 64) == 0.0);
  CHECK(multiply_covered_fraction(tris, uv, 10000) == 0.0);
  // The right half folded back over the left half: half the covered area twice.
  std::vector<Vec2d> folded = uv;
  for (auto& p : folded)
    if (p.x > 2) p.x = 4 - p.x;
  // Folding makes the right half's triangles clockwise: counted all the same.
  const double f = multiply_covered_fraction(tris, folded, 10000);
  CHECK(f == Approx(1.0).margin(0.02));  // the footprint is the left half, all of it twice
  // Two squares [0,2]² and [1,3]×[0,2]: a third of the covered area twice.
  const std::vector<Vec2d> sq = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}, {3, 0}, {3, 2}, {1, 2}};
  const std::vector<Face> st = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  CHECK(multiply_covered_fraction(st, sq, 90000) == Approx(1.0 / 3).margin(0.01));
}

TEST_CASE("a lone sliver triangle (height 1e-10 of its length) is laid out with area", "[chart]") {
  // Its height came from sqrt(|e2|² − x2²), which cancels to 0 here: the chart had no UV area
  // and the packer refused the mesh ("chart 2 has zero UV area").
  ChartGeometry g;
  g.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1e-10, 0}};
  g.vertex_parent = {0, 1, 2};
  g.tris = {{0, 1, 2}};
  g.faces = {0};
  const ChartParam p = parameterize(g, {}, ParamOptions{});
  REQUIRE(p.uv.size() == 3);
  CHECK(p.accepted);
  CHECK(signed_area(p.uv[0], p.uv[1], p.uv[2]) > 0);
  CHECK(signed_area(p.uv[0], p.uv[1], p.uv[2]) == Approx(0.5e-10).epsilon(1e-3));
}

namespace {

// A cone of k triangles around an apex at height h over a unit ring; the ring is the boundary.
ChartGeometry cone(int k, double h) {
  ChartGeometry g;
  g.positions.push_back({0, 0, h});
  for (int i = 0; i < k; ++i)
    g.positions.push_back({std::cos(2 * M_PI * i / k), std::sin(2 * M_PI * i / k), 0});
  for (int i = 0; i < k; ++i) {
    g.tris.push_back({0, 1 + i, 1 + (i + 1) % k});
    g.faces.push_back(i);
  }
  for (int v = 0; v <= k; ++v) g.vertex_parent.push_back(v);
  return g;
}

}  // namespace

TEST_CASE("the Linf lower bound from angle defects holds and spares hopeless charts", "[chart]") {
  const int k = 8;
  const ChartGeometry flat = cone(k, 0);
  CHECK(linf_lower_bound(flat, Topology(flat.tris, flat.num_vertices())) == Approx(1.0).margin(1e-12));

  const ChartGeometry g = cone(k, 1.0);
  const Topology topo(g.tris, g.num_vertices());
  const double bound = linf_lower_bound(g, topo);
  // The apex's angles sum to well under 2π: a layout must open them up.
  CHECK(bound > 1.1);
  CHECK(bound < 2);
  // The symmetric layout (a regular octagon around its centre) and the optimized one both
  // respect it.
  std::vector<Vec2d> regular;
  for (int v = 0; v < g.num_vertices(); ++v) regular.push_back({g.positions[v].x, g.positions[v].y});
  CHECK(measure_stretch(g.positions, g.tris, regular).linf >= bound);
  ParamOptions loose;
  loose.max_l2 = 10;
  loose.max_linf = 50;
  const ChartParam p = parameterize(g, regular, loose);
  REQUIRE(p.accepted);
  CHECK(p.linf >= bound);

  // Below the bound no layout can pass: the start (here stretched along x) is measured,
  // neither optimized nor replaced by LSCM.
  std::vector<Vec2d> stretched = regular;
  for (Vec2d& x : stretched) x.x *= 1.3;
  CHECK(linf_bound_unreachable(g, &topo, 0.99 * bound));
  CHECK_FALSE(linf_bound_unreachable(g, nullptr, 1.01 * bound));
  ParamOptions tight = loose;
  tight.max_linf = 0.99 * bound;
  const ChartParam q = parameterize(g, stretched, tight);
  CHECK_FALSE(q.accepted);
  CHECK(q.method == "isomap");
  CHECK(q.uv == stretched);
  // Just above it the chart is still worked on (and the layout moves).
  tight.max_linf = 1.01 * bound;
  CHECK(parameterize(g, stretched, tight).uv != stretched);
}
