#include "isochart/signal.h"

#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "../../libisochart/src/signal_distance.h"
#include "isochart/builtin.h"
#include "isochart/embedding.h"
#include "isochart/error.h"
#include "isochart/geodesic.h"
#include "isochart/io.h"
#include "isochart/stretch.h"

using namespace isochart;

namespace {

// An n × n grid over [0,1]² in the plane z = 0, with uv = (x, y) as its atlas.
Mesh plane(int n) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back({double(i) / n, double(j) / n, 0});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.faces.push_back({a, b, d});
      m.faces.push_back({a, d, c});
    }
  for (const auto& p : m.positions) m.uvs.push_back({p.x, p.y});
  m.face_uvs = m.faces;
  return m;
}

// `image` mapped through the mesh's own texture coordinates.
Signal mapped_signal(const Mesh& m, const Image& image) {
  Signal s;
  s.dimension = image.channels;
  s.texture = image;
  s.uvs = m.uvs;
  s.face_uvs = m.face_uvs;
  return s;
}

Signal scalar_signal(const Mesh& m, double (*f)(double, double)) {
  Signal s;
  s.dimension = 1;
  for (const auto& p : m.positions) s.vertex_values.push_back(f(p.x, p.y));
  return s;
}

double linear(double x, double y) {
  return 2 * x + 3 * y;
}
double wave(double x, double y) {
  return std::sin(6 * x) * std::cos(5 * y);
}

}  // namespace

TEST_CASE("IMT of a linear signal on a plane is exact", "[signal]") {
  const Mesh m = plane(4);
  const std::vector<Imt> imt = face_imt(m, scalar_signal(m, linear));
  const std::vector<double> area = face_areas(m);
  REQUIRE(imt.size() == m.faces.size());
  for (size_t f = 0; f < imt.size(); ++f) {
    // The gradient (2, 3) has |∇f|² = 13 whatever the face frame, and rank 1.
    CHECK(imt[f][0] + imt[f][2] == Approx(13 * area[f]).epsilon(1e-12));
    CHECK(imt[f][0] * imt[f][2] - imt[f][1] * imt[f][1] == Approx(0).margin(1e-12));
  }
  // Face 0 = (a, b, d): corner 0 → 1 along +x, corner 2 above, so the frame is the world's.
  CHECK(imt[0][0] == Approx(4 * area[0]));
  CHECK(imt[0][1] == Approx(6 * area[0]));
  CHECK(imt[0][2] == Approx(9 * area[0]));
}

TEST_CASE("IMT of a mapped ramp texture matches its gradient", "[signal]") {
  Mesh m = plane(3);
  // A texture ramp in u: texel centres hold u, so bilinear lookup is exactly u inside.
  Image ramp(64, 8, 1);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 64; ++x) ramp.at(x, y, 0) = static_cast<float>((x + 0.5) / 64);
  for (auto& uv : m.uvs) uv = {0.1 + 0.5 * uv.x, 0.2 + 0.5 * uv.y};
  const Signal s = mapped_signal(m, ramp);
  const std::vector<Imt> imt = face_imt(m, s);
  const std::vector<double> area = face_areas(m);
  for (size_t f = 0; f < imt.size(); ++f) {
    // f = 0.1 + 0.5 x on the surface: |∇f|² = 0.25.
    CHECK(imt[f][0] + imt[f][2] == Approx(0.25 * area[f]).epsilon(1e-4));
  }
}

namespace {

// Signal distances along the geodesics from `landmarks` on plane(n) for the scalar signal f.
std::vector<double> plane_signal_rows(const Mesh& m, const std::vector<int>& landmarks,
                                      double (*f)(double, double)) {
  const GeodesicSolver solver(m);
  const std::vector<double> rows = solver.distance_rows(landmarks);
  return detail::geodesic_signal_distances(m.positions, m.faces, landmarks, rows,
                                           scalar_signal(m, f).vertex_values, 1);
}

double ramp_x(double x, double) {
  return x;
}
// A narrow hill of height 1 at the plane's centre, ~0 at its boundary.
double hill(double x, double y) {
  return std::exp(-((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5)) / (2 * 0.1 * 0.1));
}

}  // namespace

TEST_CASE("signal distance reaches vertices whose distances come before all their neighbours'", "[signal]") {
  // Rows whose distances are not monotone along the mesh (ties among coincident vertices,
  // landmark entries averaged over both directions) leave vertices with no visited neighbour
  // at their turn. One pass over them left a vertex whose neighbours all waited too at +inf,
  // and `atlas face_mask.off --signal normals` failed with "distances overflow".
  const int n = 6;
  const Mesh m = plane(n);
  const int centre = (n / 2) * (n + 1) + n / 2;
  const GeodesicSolver solver(m);
  std::vector<double> rows = solver.distance_rows({0});
  const Topology topo(m);
  rows[centre] = 0.01;  // first of all, then its ring
  for (int v : topo.vertex_neighbors(centre)) rows[v] = 0.02;
  const std::vector<double> s = detail::geodesic_signal_distances(m.positions, m.faces, {0}, rows,
                                                                  scalar_signal(m, ramp_x).vertex_values, 1);
  for (int v = 0; v < m.num_vertices(); ++v) {
    INFO(v);
    CHECK(std::isfinite(s[v]));
  }
}

TEST_CASE("signal distance along geodesics equals the signal change on a linear ramp", "[signal]") {
  const int n = 20;
  const Mesh m = plane(n);
  const int left = (n / 2) * (n + 1), centre = left + n / 2;  // (0, 0.5) and (0.5, 0.5)
  const std::vector<double> s = plane_signal_rows(m, {left, centre}, ramp_x);
  double worst_left = 0, worst_centre = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const double x = m.positions[v].x;
    REQUIRE(std::isfinite(s[v]));
    // From the left edge every geodesic runs in +x: the sum of |Δf| is exactly Δx.
    worst_left = std::max(worst_left, std::abs(s[v] - x));
    // From the centre the geodesic crosses no extremum of f either: |x − 0.5|, up to the
    // linear interpolation of the kink at x = 0.5 between the two upwind vertices.
    worst_centre = std::max(worst_centre, std::abs(s[m.num_vertices() + v] - std::abs(x - 0.5)));
  }
  CHECK(worst_left < 1e-9);
  CHECK(worst_centre < 0.5 / n);
}

TEST_CASE("signal distance follows the geodesic, not the path of least signal change", "[signal]") {
  const int n = 40;
  const Mesh m = plane(n);
  const int left = (n / 2) * (n + 1), right = left + n;  // (0, 0.5) and (1, 0.5)
  const std::vector<double> s = plane_signal_rows(m, {left}, hill);
  // The geodesic is the straight line y = 0.5 over the top of the hill: up 1 and down 1.
  const double expected = 2 - 2 * hill(0, 0.5);
  CHECK(s[right] == Approx(expected).margin(0.02));
  // The path of least signal change goes around the hill along the boundary, where f ≈ 0:
  // summing over its edges gives almost nothing, which the old Dijkstra distance measured.
  auto f_at = [&](int i, int j) { return hill(double(i) / n, double(j) / n); };
  double around = 0;
  for (int j = n / 2; j > 0; --j) around += std::abs(f_at(0, j) - f_at(0, j - 1));
  for (int i = 0; i < n; ++i) around += std::abs(f_at(i + 1, 0) - f_at(i, 0));
  for (int j = 0; j < n / 2; ++j) around += std::abs(f_at(n, j + 1) - f_at(n, j));
  CHECK(around < 0.01);
  // Every vertex gets the signal change along its own straight geodesic from the landmark, up
  // to the smearing of s across neighbouring geodesics by its linear interpolation at the
  // update's foot (largest beside the hill, where the neighbours' paths crossed its top). The
  // scheme is first order: halving the edge length halves the error.
  auto errors = [&](int k, double& worst, double& mean) {
    const Mesh mk = plane(k);
    const int lk = (k / 2) * (k + 1);
    const std::vector<double> sk = plane_signal_rows(mk, {lk}, hill);
    worst = mean = 0;
    for (int v = 0; v < mk.num_vertices(); ++v) {
      const Vec3d p = mk.positions[v];
      double sum = 0, prev = hill(0, 0.5);
      for (int i = 1; i <= 400; ++i) {
        const double t = i / 400.0, cur = hill(t * p.x, 0.5 + t * (p.y - 0.5));
        sum += std::abs(cur - prev);
        prev = cur;
      }
      worst = std::max(worst, std::abs(sk[v] - sum));
      mean += std::abs(sk[v] - sum) / mk.num_vertices();
    }
  };
  double worst20, mean20, worst40, mean40;
  errors(20, worst20, mean20);
  errors(40, worst40, mean40);
  CHECK(mean40 < 0.025);
  CHECK(worst40 < 0.15);
  CHECK(mean40 < 0.6 * mean20);
  CHECK(worst40 < 0.6 * worst20);
}

TEST_CASE("the combined distance of eq. 6 mixes geodesic and geodesic-path signal distances", "[signal]") {
  const int n = 20;
  const Mesh m = plane(n);
  std::vector<int> all(m.num_faces());
  for (int f = 0; f < m.num_faces(); ++f) all[f] = f;
  const detail::ChartGeometry g = detail::make_chart(m, all);
  const GeodesicSolver solver(g.positions, g.tris);
  EmbeddingOptions eo;
  eo.landmarks = 30;
  const Embedding geo = landmark_isomap(solver, eo);
  std::vector<double> f(m.num_vertices()), flat(m.num_vertices(), 0.25);
  for (int v = 0; v < m.num_vertices(); ++v) f[v] = hill(m.positions[v].x, m.positions[v].y);
  // β = 1 or a constant signal: the geodesic embedding itself.
  CHECK(detail::combined_embedding(g, geo, f, 1, 1.0).landmark_distances == geo.landmark_distances);
  CHECK(detail::combined_embedding(g, geo, flat, 1, 0.5).landmark_distances == geo.landmark_distances);
  const Embedding e = detail::combined_embedding(g, geo, f, 1, 0.5);
  REQUIRE(e.dimensions >= 2);
  std::vector<double> local(g.num_vertices());
  for (int v = 0; v < g.num_vertices(); ++v) local[v] = f[g.vertex_parent[v]];
  const std::vector<double> sig =
      detail::geodesic_signal_distances(g.positions, g.tris, geo.landmarks, geo.landmark_distances, local, 1);
  double sum_geo = 0, sum_sig = 0;
  for (size_t i = 0; i < sig.size(); ++i) {
    sum_geo += geo.landmark_distances[i];
    sum_sig += sig[i];
  }
  // Off the landmark block (which embed_landmarks symmetrizes) every entry is eq. 6 in units
  // of length: β·d_geo + (1 − β)·d_sig·avg_geo/avg_sig.
  const int nv = g.num_vertices();
  double worst = 0;
  for (int k = 0; k < static_cast<int>(geo.landmarks.size()); ++k)
    for (int v = 0; v < nv; ++v) {
      if (std::find(geo.landmarks.begin(), geo.landmarks.end(), v) != geo.landmarks.end()) continue;
      const size_t i = static_cast<size_t>(k) * nv + v;
      const double want = 0.5 * geo.landmark_distances[i] + 0.5 * sig[i] * sum_geo / sum_sig;
      worst = std::max(worst, std::abs(e.landmark_distances[i] - want));
    }
  CHECK(worst < 1e-12);
  CHECK(e.landmark_distances != geo.landmark_distances);
}

TEST_CASE("signal stretch is 1 for an isometry and lower when texels follow the signal", "[signal]") {
  Mesh m = plane(16);
  // Signal varying only for x > 0.5.
  const Signal s =
      scalar_signal(m, [](double x, double) { return x > 0.5 ? 4 * (x - 0.5) * (x - 0.5) * 10 : 0.0; });
  const std::vector<Imt> imt = face_imt(m, s);
  CHECK(signal_stretch(m, imt) == Approx(1.0).epsilon(1e-9));
  // Give the right half twice the texture width.
  Mesh warped = m;
  for (auto& uv : warped.uvs) uv.x = uv.x <= 0.5 ? uv.x * 0.5 : 0.25 + (uv.x - 0.5) * 1.5;
  CHECK(signal_stretch(warped, imt) < 0.95);
  // The opposite allocation is worse than the isometry.
  Mesh bad = m;
  for (auto& uv : bad.uvs) uv.x = uv.x <= 0.5 ? uv.x * 1.5 : 0.75 + (uv.x - 0.5) * 0.5;
  CHECK(signal_stretch(bad, imt) > 1.05);
  // A mirrored layout gets the same texels (UVAtlas writes v downwards; it measured infinite).
  Mesh mirrored = warped;
  for (auto& uv : mirrored.uvs) uv.y = 1 - uv.y;
  CHECK(signal_stretch(mirrored, imt) == Approx(signal_stretch(warped, imt)).epsilon(1e-12));
  // A triangle collapsed in UV gets none: infinite.
  Mesh collapsed = m;
  collapsed.face_uvs[0][2] = collapsed.face_uvs[0][1];
  CHECK(std::isinf(signal_stretch(collapsed, imt)));
}

TEST_CASE("metric L2 stretch equals geometric L2 stretch for the identity metric", "[signal]") {
  Mesh m = plane(6);
  for (auto& uv : m.uvs) uv = {uv.x * (1 + 0.3 * uv.y), uv.y};
  const std::vector<Imt> identity(m.faces.size(), Imt{1, 0, 1});
  std::vector<Vec2d> uv = m.uvs;
  CHECK(metric_l2_stretch(m.positions, m.faces, uv, identity) ==
        Approx(measure_stretch(m.positions, m.faces, uv).l2).epsilon(1e-12));
  // signal_metric with λ = 0 is the identity.
  const std::vector<Imt> g = signal_metric(m, face_imt(m, scalar_signal(m, wave)), 0.0);
  for (const Imt& t : g) CHECK((t[0] == 1 && t[1] == 0 && t[2] == 1));
}

TEST_CASE("a signal flat up to rounding gives the identity metric", "[signal]") {
  // A constant texture read in float leaves IMT traces of 1e-16..1e-14; normalized by their
  // mean they became a full-weight metric and split a 5-chart mesh into 76 charts.
  const Mesh m = plane(6);
  std::vector<Imt> noise(m.faces.size());
  for (std::size_t f = 0; f < noise.size(); ++f)
    noise[f] = {1e-16 * (1 + f % 7), 3e-17 * (f % 3), 2e-15 / (1 + f % 5)};
  for (const Imt& t : signal_metric(m, noise, 2.0)) CHECK((t[0] == 1 && t[1] == 0 && t[2] == 1));
  // A real signal on some faces still weighs those, and only those.
  std::vector<Imt> some = noise;
  some[0] = {1e-3, 0, 1e-3};
  const std::vector<Imt> g = signal_metric(m, some, 2.0);
  CHECK(g[0][0] > 1.5);
  for (std::size_t f = 1; f < g.size(); ++f) CHECK((g[f][0] == 1 && g[f][1] == 0 && g[f][2] == 1));
}

TEST_CASE("a texture flat up to float rounding is no signal", "[signal]") {
  // A flat grey image read bilinearly differs from itself by float rounding: as a signal it
  // gave bunny_lowres 5 to 7 charts instead of the geometric 4, and a signal stretch of 1.04.
  const Mesh geo = load_mesh(std::string(ISOCHARTS_SHARED_DATA) + "/meshes/bunny_lowres.off").mesh;
  AtlasOptions o;
  const Atlas plain = build_atlas(geo, o);
  const Mesh m = plain.apply_to(geo);
  Image grey(32, 32, 3);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      for (int c = 0; c < 3; ++c) grey.at(x, y, c) = 0.5f + ((x + y + c) % 2 ? 3e-8f : 0.0f);
  const Signal s = mapped_signal(m, grey);
  const std::vector<Imt> imt = face_imt(m, s);
  CHECK(std::all_of(imt.begin(), imt.end(), [](const Imt& t) { return t == Imt{0, 0, 0}; }));
  CHECK(signal_stretch(m, imt) == 0);
  SignalAtlasOptions so;
  so.use = SignalUse::Full;
  const Atlas a = build_signal_atlas(m, s, o, so);
  CHECK(a.charts.size() == plain.charts.size());
}

TEST_CASE("SAE is tiny for a linear signal and decreases with resolution", "[signal]") {
  // Inset from the texture border, as an atlas with a gutter is (lookups clamp there).
  Mesh m = plane(32);
  for (auto& uv : m.uvs) uv = {0.1 + 0.8 * uv.x, 0.1 + 0.8 * uv.y};
  // A linear signal is reproduced exactly by bilinear interpolation of exact texel values.
  const SaeResult lin = signal_approximation_error(m, scalar_signal(m, linear), 64, 64);
  CHECK(lin.signal_rms > 0.5);
  CHECK(lin.sae < 1e-5);
  const Signal s = scalar_signal(m, wave);
  const double e16 = signal_approximation_error(m, s, 16, 16).sae;
  const double e64 = signal_approximation_error(m, s, 64, 64).sae;
  const SaeResult r256 = signal_approximation_error(m, s, 256, 256);
  CHECK(e16 > e64);
  CHECK(e64 > r256.sae);
  CHECK(r256.sae < 0.02 * r256.signal_rms);
  CHECK(r256.samples > 32 * 32 * 2);
}

TEST_CASE("bake_signal fills the gutter", "[signal]") {
  Mesh m = plane(4);
  for (auto& uv : m.uvs) uv = {0.25 + 0.5 * uv.x, 0.25 + 0.5 * uv.y};
  const Image img = bake_signal(m, scalar_signal(m, [](double, double) { return 0.75; }), 32, 32);
  REQUIRE(img.channels == 1);
  for (float v : img.pixels) CHECK(v == Approx(0.75f));
}

TEST_CASE("signals from a mesh and their errors", "[signal]") {
  Mesh m = plane(2);
  CHECK(make_signal(m, "normals").dimension == 3);
  // Stored normals are normalized.
  Mesh scaled = m;
  scaled.normals.assign(m.positions.size(), Vec3d{0, 0, 6});
  CHECK(make_signal(scaled, "normals").vertex_values[2] == 1.0);
  CHECK_THROWS_AS(make_signal(m, "colors", "plane.obj"), InputError);
  CHECK_THROWS_AS(make_signal(m, "curvature", "plane.obj"), InputError);
  CHECK_THROWS_AS(make_signal(m, "texture:/nonexistent/x.png", "plane.obj"), InputError);
  CHECK_THROWS_AS(signal_approximation_error(m, make_signal(m, "normals"), 0, 16), InputError);
  m.colors.assign(m.positions.size(), Vec3d{0.5, 0.2, 0.1});
  const Signal c = make_signal(m, "colors");
  std::vector<double> out(3);
  c.evaluate(m, 0, 0.3, 0.3, out.data());
  CHECK(out[0] == Approx(0.5));
  Mesh bare = plane(2);
  bare.face_uvs.clear();
  CHECK_THROWS_AS(bake_signal(bare, c, 8, 8), InputError);
}

namespace {

// The face builtin with a colour pattern baked to its vertices: stripes only on the right half,
// so a signal atlas should spend its texels there.
Mesh striped_face() {
  Mesh m = make_builtin("face");
  for (const auto& p : m.positions) {
    const double s = p.x > 0.2 ? 0.5 + 0.5 * std::sin(25 * p.y) : 0.5;
    m.colors.push_back({s, 0.5, 1 - s});
  }
  return m;
}

}  // namespace

TEST_CASE("signal atlases keep the geometric guarantees and lower the signal error", "[signal]") {
  const Mesh m = striped_face();
  const Signal s = make_signal(m, "colors");
  AtlasOptions o;
  o.pack.width = o.pack.height = 128;
  o.seed = 3;
  SignalAtlasOptions so;
  double sae[3] = {0, 0, 0}, sst[3] = {0, 0, 0};
  const SignalUse uses[3] = {SignalUse::None, SignalUse::Param, SignalUse::Full};
  for (int i = 0; i < 3; ++i) {
    so.use = uses[i];
    SignalAtlasStats st;
    const Atlas a = build_signal_atlas(m, s, o, so, &st);
    INFO("use " << i);
    CHECK(a.stats.flipped == 0);
    CHECK(a.stats.overlapping_pairs == 0);
    // Every chart meets the geometric Linf bound in its own normalization; the whole atlas's
    // figure exceeds it by design once charts get different texel densities.
    if (i == 0) CHECK(a.stats.linf <= o.max_linf);
    for (const auto& c : a.charts) CHECK(c.linf <= o.max_linf);
    const Mesh out = a.apply_to(m);
    for (const Vec2d& uv : out.uvs) CHECK((uv.x >= 0 && uv.x <= 1 && uv.y >= 0 && uv.y <= 1));
    sae[i] = signal_approximation_error(out, s, 128, 128).sae;
    sst[i] = st.signal_stretch;
  }
  CHECK(sst[1] < sst[0]);
  CHECK(sae[1] < sae[0]);
  CHECK(sae[2] < sae[0]);
}

TEST_CASE("signal atlases of the creature beat its geometric atlas at the size packed for",
          "[signal][slow]") {
  // They lost (SAE at 1024²: 0.00207 param, 0.00210 full, 0.00136 geometric): the stretch
  // optimizer let a chart's boundary close in on itself, and bilinear reads across the pinch
  // mixed normals from far-apart surface points, 80-94 % of the error from 0.01 % of the area.
  const Mesh m = make_builtin("creature");
  const Signal s = make_signal(m, "normals");
  AtlasOptions o;
  SignalAtlasOptions so;
  double sae[3] = {0, 0, 0};
  const SignalUse uses[3] = {SignalUse::None, SignalUse::Param, SignalUse::Full};
  for (int i = 0; i < 3; ++i) {
    so.use = uses[i];
    const Atlas a = build_signal_atlas(m, s, o, so, nullptr);
    sae[i] = signal_approximation_error(a.apply_to(m), s, o.pack.width, o.pack.height).sae;
  }
  INFO("SAE none " << sae[0] << ", param " << sae[1] << ", full " << sae[2]);
  CHECK(sae[1] < sae[0]);
  CHECK(sae[2] < sae[0]);
}

TEST_CASE("signal atlases in a non-square texture are optimized and measured in texels", "[signal]") {
  // The packed coordinates of a 2048×128 atlas were taken as the charts' own: every chart was
  // re-optimized 16 times flattened (L2 4.2 and Linf 10.7 at 32:1 against 1.04 and 1.9 in a
  // square), and the signal stretch was measured on the squashed layout.
  const Mesh m = striped_face();
  const Signal s = make_signal(m, "colors");
  SignalAtlasOptions so;
  so.use = SignalUse::Param;
  AtlasOptions o;
  o.seed = 3;
  o.pack.width = o.pack.height = 512;
  SignalAtlasStats square;
  const Atlas a = build_signal_atlas(m, s, o, so, &square);
  o.pack.width = 2048;
  o.pack.height = 128;
  SignalAtlasStats wide;
  const Atlas b = build_signal_atlas(m, s, o, so, &wide);
  CHECK(b.stats.l2 <= so.max_geometric_l2);
  CHECK(b.stats.linf <= o.max_linf);
  CHECK(b.stats.l2 == Approx(a.stats.l2).epsilon(0.05));
  CHECK(wide.signal_stretch == Approx(square.signal_stretch).epsilon(0.05));
  REQUIRE(a.charts.size() == b.charts.size());
  for (std::size_t c = 0; c < a.charts.size(); ++c)
    CHECK(b.charts[c].l2 == Approx(a.charts[c].l2).epsilon(0.05));
}

TEST_CASE("signal atlases are identical for one and two threads", "[signal]") {
  const Mesh m = striped_face();
  const Signal s = make_signal(m, "colors");
  AtlasOptions o;
  o.pack.width = o.pack.height = 128;
  SignalAtlasOptions so;
  Atlas a, b;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    a = build_signal_atlas(m, s, o, so);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    b = build_signal_atlas(m, s, o, so);
  }
  CHECK(a.face_chart == b.face_chart);
  REQUIRE(a.uvs.size() == b.uvs.size());
  bool same = true;
  for (size_t i = 0; i < a.uvs.size(); ++i) same = same && a.uvs[i] == b.uvs[i];
  CHECK(same);
}

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST_CASE("isocharts sae reports the field sae", "[signal]") {
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() / ("isocharts_signal_test_" + std::to_string(::getpid()));
  const std::string dir = tmp.string();
  std::string cmd = "mkdir -p '" + dir + "' && \"" + std::string(ISOCHARTS_CLI) +
                    "\" -q atlas builtin:face -o " + dir +
                    "/face.obj --width 128 --height 128 > /dev/null && \"" + ISOCHARTS_CLI +
                    "\" -q --json sae " + dir + "/face.obj --signal normals --res 64 > " + dir + "/sae.json";
  REQUIRE(std::system(cmd.c_str()) == 0);
  const std::string json = read_text(dir + "/sae.json");
  CHECK(json.find("\"sae\":") != std::string::npos);
  // The signal stretch is measured in texels of the texture named: the same atlas, packed for
  // 512×64, read as square gave 2.1 where it is 1.0.
  auto stretch = [&](const std::string& size) {
    const std::string c = "\"" + std::string(ISOCHARTS_CLI) + "\" -q --json sae " + dir +
                          "/wide.obj --signal normals " + size + " > " + dir + "/wide.json";
    REQUIRE(std::system(c.c_str()) == 0);
    const std::string text = read_text(dir + "/wide.json");
    const auto at = text.find("\"signal_stretch\":");
    REQUIRE(at != std::string::npos);
    return std::stod(text.substr(at + 17));
  };
  cmd = "\"" + std::string(ISOCHARTS_CLI) + "\" -q atlas builtin:face -o " + dir +
        "/wide.obj --width 512 --height 64 > /dev/null";
  REQUIRE(std::system(cmd.c_str()) == 0);
  const double in_texels = stretch("--width 512 --height 64"), squashed = stretch("--res 512");
  CHECK(in_texels < 1.5);
  CHECK(squashed > 1.5);
  // Measured square, the 8:1 atlas is named; a lone --width (read with --res's height) refused.
  auto stderr_of = [&](const std::string& args) {
    const std::string c = "\"" + std::string(ISOCHARTS_CLI) + "\" sae " + dir +
                          "/wide.obj --signal normals " + args + " > /dev/null 2> " + dir + "/err.txt";
    const int code = std::system(c.c_str());
    return std::make_pair(WEXITSTATUS(code), read_text(dir + "/err.txt"));
  };
  auto [square_rc, square_err] = stderr_of("--res 64");
  CHECK(square_rc == 0);
  CHECK(
      square_err.find("look laid out for a texture 8 times as wide as high; the texture measured is 64x64") !=
      std::string::npos);
  CHECK(stderr_of("--width 512 --height 64").second.find("look laid out") == std::string::npos);
  {
    // atlas --signal bakes its SAE texture in the atlas's shape (it was --sae-res square).
    const std::string c = "\"" + std::string(ISOCHARTS_CLI) +
                          "\" -q --json atlas builtin:face --signal normals -o " + dir +
                          "/ws.obj --width 512 --height 64 --sae-res 64 > " + dir + "/ws.json";
    REQUIRE(std::system(c.c_str()) == 0);
    const std::string report = read_text(dir + "/ws.json");
    CHECK(report.find("\"sae_width\": 181") != std::string::npos);
    CHECK(report.find("\"sae_height\": 23") != std::string::npos);
    // Without --sae-res it is the texture the atlas was packed for: at 256² a 1024² atlas's
    // chart borders weighed four times more and reversed rankings against geometric atlases.
    const std::string d =
        "\"" + std::string(ISOCHARTS_CLI) + "\" -q --json atlas builtin:face --signal normals -o " + dir +
        "/wd.obj --width 512 --height 64 --signal-texture-out " + dir + "/wd.png > " + dir + "/wd.json";
    REQUIRE(std::system(d.c_str()) == 0);
    const std::string packed = read_text(dir + "/wd.json");
    CHECK(packed.find("\"sae_width\": 512") != std::string::npos);
    CHECK(packed.find("\"sae_height\": 64") != std::string::npos);
    CHECK(packed.find("\"signal_texture\": \"" + dir + "/wd.png\"") != std::string::npos);  // was not named
  }
  auto [lone_rc, lone_err] = stderr_of("--width 512");
  CHECK(lone_rc == 2);
  CHECK(lone_err.find("--width and --height go together") != std::string::npos);
  // An atlas without UVs is refused with exit code 2.
  cmd = "\"" + std::string(ISOCHARTS_CLI) + "\" -q sae builtin:sphere --signal normals 2>/dev/null";
  const int rc = std::system(cmd.c_str());
  CHECK(WEXITSTATUS(rc) == 2);
  std::filesystem::remove_all(tmp);
}

TEST_CASE("a texture signal repeats where the texture coordinates leave the unit square", "[signal]") {
  // As render and the glTF sampler read the mesh; the signal clamped instead, so atlases were
  // optimized for, and sae scored, another signal than the one the mesh shows.
  const std::string png =
      (std::filesystem::temp_directory_path() / ("isocharts_tiling_" + std::to_string(::getpid()) + ".png"))
          .string();
  Image img(4, 1, 3, 0.0f);
  for (int x = 0; x < 4; ++x) img.at(x, 0, 0) = x < 2 ? 1.0f : 0.0f;  // red on the left half
  write_image(png, img);
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}};
  m.face_uvs = m.faces;
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  double v[3];
  const Signal inside = make_signal(m, "texture:" + png);
  CHECK_FALSE(inside.tiling);
  m.uvs = {{1, 0}, {2, 0}, {1, 1}};  // the same triangle one tile to the right
  const Signal tiled = make_signal(m, "texture:" + png);
  CHECK(tiled.tiling);
  tiled.evaluate(m, 0, 0.125, 0.1, v);  // u = 1.125: the first texel of the next tile (0 clamped)
  CHECK(v[0] == Approx(1.0));
  std::filesystem::remove(png);
}

TEST_CASE("a texture signal wraps per axis as the material says, and clamps an axis kept inside",
          "[signal]") {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}};
  Signal s;
  s.texture = Image(4, 4, 1, 0.0f);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) s.texture.at(x, y, 0) = x < 2 ? 1.0f : 0.0f;  // bright left half
  s.dimension = 1;
  // Only u leaves [0, 1]: the material's mirror applies along u, v stays clamped even though
  // the material repeats it (v's coordinates never ask for a second tile).
  s.set_texture_coordinates({{1, 0}, {2, 0}, {1, 1}}, m.faces, TextureWrap{Wrap::Mirror, Wrap::Repeat});
  CHECK(s.tiling);
  CHECK((s.wrap.u == Wrap::Mirror && s.wrap.v == Wrap::Clamp));
  double v = -1;
  s.evaluate(m, 0, 0.125, 0.1, &v);  // u = 1.125 mirrors to 0.875: the dark right half
  CHECK(v == Approx(0.0));
  s.set_texture_coordinates({{1, 0}, {2, 0}, {1, 1}}, m.faces);  // repeated by default
  CHECK(s.wrap.u == Wrap::Repeat);
  s.evaluate(m, 0, 0.125, 0.1, &v);  // u = 1.125 repeats to 0.125: the bright left half
  CHECK(v == Approx(1.0));
  s.set_texture_coordinates({{0, 0}, {1, 0}, {0, 1}}, m.faces, TextureWrap{Wrap::Mirror, Wrap::Mirror});
  CHECK_FALSE(s.tiling);
  CHECK((s.wrap.u == Wrap::Clamp && s.wrap.v == Wrap::Clamp));
}

TEST_CASE("a texture signal drops alpha wherever it is and counts transparent texels", "[signal]") {
  const std::string base =
      (std::filesystem::temp_directory_path() / ("isocharts_alpha_" + std::to_string(::getpid()))).string();
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}};
  m.face_uvs = m.faces;
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  // RGBA, half of it transparent: the colour is the signal, as stored.
  Image rgba(4, 4, 4, 0.25f);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) rgba.at(x, y, 3) = x < 2 ? 0.0f : 1.0f;
  write_image(base + ".png", rgba);
  const Signal s = make_signal(m, "texture:" + base + ".png");
  CHECK(s.dimension == 3);
  CHECK(s.texture.channels == 3);
  CHECK(s.transparent_texels == 8);
  double v[3];
  s.evaluate(m, 0, 0.1, 0.1, v);
  CHECK(v[0] == Approx(0.25).epsilon(0.01));
  // Two channels named R and G are two signal channels, not grey and alpha.
  Image rg(4, 4, 2, 0.5f);
  rg.channel_names = {"R", "G"};
  write_image(base + ".exr", rg);
  const Signal t = make_signal(m, "texture:" + base + ".exr");
  CHECK(t.dimension == 2);
  CHECK(t.transparent_texels == 0);
  std::filesystem::remove(base + ".png");
  std::filesystem::remove(base + ".exr");
}

TEST_CASE("a mapped texture signal bakes back to itself through its own atlas", "[signal]") {
  // The plane's atlas is the texture's own mapping, so the SAE only sees resampling.
  Mesh m = plane(8);
  for (auto& uv : m.uvs) uv = {0.1 + 0.8 * uv.x, 0.1 + 0.8 * uv.y};
  Image tex(64, 64, 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c)
        tex.at(x, y, c) = static_cast<float>(0.5 + 0.4 * std::sin(0.2 * x + 0.1 * c * y));
  const Signal s = mapped_signal(m, tex);
  const SaeResult same = signal_approximation_error(m, s, 64, 64);
  const SaeResult coarse = signal_approximation_error(m, s, 16, 16);
  CHECK(same.signal_rms > 0.1);
  CHECK(same.sae < 0.2 * coarse.sae);
  const std::vector<Imt> imt = face_imt(m, s);
  double total = 0;
  for (const Imt& g : imt) total += g[0] + g[2];
  CHECK(total > 0);
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("isocharts_signal_imt_" + std::to_string(::getpid()) + ".txt"))
                               .string();
  write_imt(path, imt);
  std::ifstream in(path);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  CHECK(lines == m.num_faces());
  std::filesystem::remove(path);
}

namespace {

// A smooth RGB pattern and its value at texture coordinate (u, v).
Image smooth_texture(int size) {
  Image tex(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 3; ++c)
        tex.at(x, y, c) = static_cast<float>(0.5 + 0.4 * std::sin(0.15 * x + 0.1 * (c + 1) * y));
  return tex;
}

// A checker of single texels, black and white: its mean over any few texels is grey.
Image checker_image(int size) {
  Image checker(size, size, 1);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) checker.at(x, y, 0) = (x + y) % 2 ? 1.0f : 0.0f;
  return checker;
}

// The plane laid out anew: a quarter turn, shrunk to 40 % and moved, as another atlas would.
Mesh turned_layout(const Mesh& m) {
  Mesh t = m;
  for (auto& uv : t.uvs) uv = {0.3 + 0.4 * (1 - uv.y), 0.2 + 0.4 * uv.x};
  return t;
}

}  // namespace

TEST_CASE("a texture is carried in bands of rows as one bake, on any thread count", "[signal]") {
  // The supersampled bake runs band by band (an 8192² bake held 4 GiB of samples whole): one
  // sample a texel, it gives the very texels of baking the mapped texture whole, and bands
  // are independent, so the thread count changes nothing.
  Mesh src = plane(16);
  for (auto& uv : src.uvs) uv = {0.1 + 0.8 * uv.x, 0.1 + 0.8 * uv.y};
  const Mesh dst = turned_layout(plane(16));
  const Image tex = smooth_texture(32);  // magnified: no reduced copies read
  Signal whole;
  whole.dimension = 3;
  whole.texture = tex;
  whole.set_texture_coordinates(src.uvs, src.face_uvs, {});
  const Image expected = bake_signal(dst, whole, 300, 200);  // 13 bands of 16 rows
  const Image one = transfer_texture(src, tex, dst, 300, 200, 1);
  CHECK(one.pixels == expected.pixels);
  Image two, serial;
  two = transfer_texture(src, tex, dst, 300, 200, 2);
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    serial = transfer_texture(src, tex, dst, 300, 200, 2);
  }
  CHECK(serial.pixels == two.pixels);
  // 2×2 samples: the gutter is filled everywhere, and the charts read as with one sample.
  double diff = 0;
  float lo = 1, hi = 0;
  int not_finite = 0;
  for (std::size_t i = 0; i < two.pixels.size(); ++i) {
    not_finite += std::isfinite(two.pixels[i]) ? 0 : 1;
    lo = std::min(lo, two.pixels[i]);
    hi = std::max(hi, two.pixels[i]);
    diff += std::abs(two.pixels[i] - one.pixels[i]);
  }
  CHECK(not_finite == 0);
  CHECK(lo >= 0.09f);  // the texture's range: no unfilled (0) or undefined texel
  CHECK(hi <= 0.91f);
  CHECK(diff / two.pixels.size() < 0.01);
}

TEST_CASE("a texture carried to another layout reads the same on the surface", "[signal]") {
  Mesh src = plane(16);
  for (auto& uv : src.uvs) uv = {0.1 + 0.8 * uv.x, 0.1 + 0.8 * uv.y};
  const Mesh dst = turned_layout(plane(16));
  const Image tex = smooth_texture(128);
  const Image out = transfer_texture(src, tex, dst, 128, 128);
  REQUIRE(out.width == 128);
  REQUIRE(out.channels == 3);
  Image deep = tex;
  deep.bits = 16;  // a 16-bit source is baked into a 16-bit image, not rounded to 8 bits
  CHECK(out.bits == 8);
  CHECK(transfer_texture(src, deep, dst, 16, 16).bits == 16);
  // Surface points read through the new layout give what they gave through the old one.
  double sum = 0, worst = 0;
  int n = 0;
  for (int f = 0; f < src.num_faces(); f += 7)
    for (const auto& [b1, b2] : {std::pair{0.2, 0.3}, std::pair{0.6, 0.1}, std::pair{0.25, 0.5}}) {
      auto at = [&](const Mesh& m) {
        const Face& t = m.face_uvs[f];
        return m.uvs[t[0]] * (1 - b1 - b2) + m.uvs[t[1]] * b1 + m.uvs[t[2]] * b2;
      };
      float a[3], b[3];
      const Vec2d p = at(src), q = at(dst);
      sample_bilinear(tex, p.x, p.y, a);
      sample_bilinear(out, q.x, q.y, b);
      for (int c = 0; c < 3; ++c) {
        sum += std::abs(a[c] - b[c]);
        worst = std::max(worst, static_cast<double>(std::abs(a[c] - b[c])));
        ++n;
      }
    }
  CHECK(sum / n < 0.01);
  CHECK(worst < 0.05);
  // Every texel is filled, inside the chart and out (no black gutter for mipmaps to bleed).
  float darkest = 1;
  for (float v : out.pixels) darkest = std::min(darkest, v);
  CHECK(darkest > 0.05f);
}

TEST_CASE("a texture carried from coordinates outside the unit square wraps as the material says",
          "[signal]") {
  Mesh src = plane(8);
  for (auto& uv : src.uvs) uv.x += 1;  // the plane laid over the second tile along u
  const Mesh dst = plane(8);
  Image tex(16, 16, 3, 0.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) tex.at(x, y, 0) = x < 8 ? 1.0f : 0.0f;  // red on the left half
  auto red_at = [](const Image& img, double u) {
    float c[3];
    sample_bilinear(img, u, 0.5, c);
    return c[0];
  };
  const Image repeated = transfer_texture(src, tex, dst, 32, 32);  // glTF's default
  CHECK(red_at(repeated, 0.2) == Approx(1.0).margin(0.02));
  CHECK(red_at(repeated, 0.8) == Approx(0.0).margin(0.02));
  const Image mirrored = transfer_texture(src, tex, dst, 32, 32, 2, TextureWrap{Wrap::Mirror, Wrap::Repeat});
  CHECK(red_at(mirrored, 0.2) == Approx(0.0).margin(0.02));
  CHECK(red_at(mirrored, 0.8) == Approx(1.0).margin(0.02));
  // Clamped, the whole second tile reads the right edge's texels: no red anywhere.
  const Image clamped = transfer_texture(src, tex, dst, 32, 32, 2, TextureWrap{Wrap::Clamp, Wrap::Clamp});
  CHECK(red_at(clamped, 0.2) == Approx(0.0).margin(0.02));
  CHECK(red_at(clamped, 0.8) == Approx(0.0).margin(0.02));
}

TEST_CASE("a texture carried to a little fewer texels is averaged, not point-sampled", "[signal]") {
  // A checker of single texels shrunk to 85 % (too little to be filtered first): point samples
  // at texel centres, bilinear in the checker, land anywhere between black and white; several
  // samples a texel average to grey.
  Mesh src = plane(4);
  const Image checker = checker_image(64);
  Mesh dst = src;
  for (auto& uv : dst.uvs) uv = {0.05 + 0.85 * uv.x, 0.1 + 0.85 * uv.y};
  auto spread = [&](int supersample) {
    const Image out = transfer_texture(src, checker, dst, 64, 64, supersample);
    double off = 0;
    int n = 0;
    for (int y = 12; y < 52; ++y)  // inside the chart, which covers [0.05, 0.9] × [0.1, 0.95]
      for (int x = 8; x < 52; ++x) {
        off += std::abs(out.at(x, y, 0) - 0.5);
        ++n;
      }
    return off / n;
  };
  const double point = spread(1), averaged = spread(4);
  // Measured: 0.097 with point samples (the reduction they read from, a quarter of the way to
  // the first, averages a little), 0.041 with 4×4 samples a texel (a box 1.4 checker texels
  // wide is not exactly grey).
  INFO("point " << point << ", averaged " << averaged);
  CHECK(point > 0.07);
  CHECK(averaged < 0.5 * point);
}

TEST_CASE("a texture squeezed in parts is filtered where it is squeezed", "[signal]") {
  // The source layout packs the plane's right side tightly along u (u = x³: three times the
  // texels per unit near x = 1, a third near 0), as a lat-long map squeezes its poles; one
  // reduction for the whole texture blurs the left or aliases the right.
  Mesh src = plane(32);
  for (auto& uv : src.uvs) uv = {uv.x * uv.x * uv.x, 0.1 + 0.8 * uv.y};
  Mesh dst = plane(32);
  for (auto& uv : dst.uvs) uv = {0.05 + 0.9 * uv.x, 0.05 + 0.9 * uv.y};  // samples off the texel grid
  const Image out = transfer_texture(src, checker_image(256), dst, 61, 61);
  double worst = 0;
  for (int y = 5; y < 56; ++y)
    for (int x = 34; x < 56; ++x) worst = std::max(worst, std::abs(out.at(x, y, 0) - 0.5));
  // Measured: 0.39 without reductions per face, 0 with them.
  INFO("largest departure from grey on the squeezed side " << worst);
  CHECK(worst < 0.1);
}

TEST_CASE("a carried texture keeps alpha and lends no colour from transparent texels", "[signal]") {
  // Left half transparent black, right half opaque red: filtered straight, the texels along the
  // edge would come out dark red; premultiplied they stay red, with partial alpha.
  Mesh src = plane(8);
  for (auto& uv : src.uvs) uv = {0.1 + 0.8 * uv.x, 0.1 + 0.8 * uv.y};
  Image tex(32, 32, 4, 0.0f);
  for (int y = 0; y < 32; ++y)
    for (int x = 16; x < 32; ++x) {
      tex.at(x, y, 0) = 1.0f;
      tex.at(x, y, 3) = 1.0f;
    }
  const Image out = transfer_texture(src, tex, turned_layout(src), 64, 64);
  REQUIRE(out.channels == 4);
  int partial = 0;
  float reddest_off = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const float a = out.at(x, y, 3);
      if (a > 0.05f && a < 0.95f) ++partial;
      if (a > 0.05f) reddest_off = std::max(reddest_off, std::abs(out.at(x, y, 0) - 1.0f));
    }
  CHECK(partial > 0);
  CHECK(reddest_off < 0.01f);
  // Wholly transparent texels carry the nearest visible colour, not black: a reader filtering
  // the straight colours (mipmaps) would darken the edge otherwise.
  int clear = 0;
  float darkest_clear = 1;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      if (out.at(x, y, 3) == 0) {
        ++clear;
        darkest_clear = std::min(darkest_clear, out.at(x, y, 0));
      }
  CHECK(clear > 0);
  CHECK(darkest_clear > 0.99f);
}

TEST_CASE("a texture far denser than the atlas is filtered before it is carried", "[signal]") {
  // A 256² checker of single texels carried to 32²: 64 source texels a new texel. Point or 2×2
  // samples alias into moiré; the mean is grey.
  Mesh src = plane(4);
  const Image checker = checker_image(256);
  Mesh dst = src;
  for (auto& uv : dst.uvs) uv = {0.1 + 0.8 * uv.x, 0.1 + 0.8 * uv.y};  // samples off the texel grid
  const Image out = transfer_texture(src, checker, dst, 37, 37);
  double worst = 0;
  for (int y = 6; y < 31; ++y)
    for (int x = 6; x < 31; ++x) worst = std::max(worst, std::abs(out.at(x, y, 0) - 0.5));
  // Measured: 0.23 point-sampled, 0 from the reduced copy.
  INFO("largest departure from grey " << worst);
  CHECK(worst < 0.05);
}

TEST_CASE("carrying a texture refuses what it cannot do", "[signal]") {
  const Mesh m = plane(2);
  const Image tex = smooth_texture(8);
  Mesh bare = m;
  bare.uvs.clear();
  bare.face_uvs.clear();
  CHECK_THROWS_AS(transfer_texture(bare, tex, m, 8, 8), InputError);
  CHECK_THROWS_AS(transfer_texture(m, tex, bare, 8, 8), InputError);
  Mesh fewer = m;
  fewer.faces.pop_back();
  fewer.face_uvs.pop_back();
  CHECK_THROWS_AS(transfer_texture(m, tex, fewer, 8, 8), InputError);
  CHECK_THROWS_AS(transfer_texture(m, tex, m, 8, 8, 0), InputError);
  CHECK_THROWS_AS(transfer_texture(m, Image{}, m, 8, 8), InputError);
}

TEST_CASE("isocharts atlas --bake-texture carries the input's texture onto the atlas", "[signal]") {
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() / ("isocharts_bake_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(tmp);
  const std::string dir = tmp.string();
  // A textured input: a bent grid (so the atlas is not its own layout) with its texture named
  // by its material.
  Mesh m = plane(24);
  for (auto& p : m.positions) p.z = 0.3 * std::sin(3 * p.x) * std::cos(2 * p.y);
  for (auto& uv : m.uvs) uv = {0.05 + 0.9 * uv.x, 0.05 + 0.9 * uv.y};
  const Image tex = smooth_texture(256);
  write_image(dir + "/tex.png", tex);
  SaveOptions so;
  so.texture = "tex.png";
  save_mesh(m, dir + "/in.obj", so);
  const std::string cli = "\"" + std::string(ISOCHARTS_CLI) + "\" ";
  auto run = [&](const std::string& args) {
    const int code = std::system((cli + args + " > " + dir + "/out.txt 2> " + dir + "/err.txt").c_str());
    return WEXITSTATUS(code);
  };
  REQUIRE(run("-q --json atlas " + dir + "/in.obj -o " + dir + "/out.obj -o " + dir +
              "/out.glb --width 256 " + "--height 256 --max-l2 1.02 --bake-texture " + dir + "/baked.png") ==
          0);
  const std::string report = read_text(dir + "/out.txt");
  CHECK(report.find("\"" + dir + "/baked.png\"") != std::string::npos);
  CHECK(report.find("\"" + dir + "/out.mtl\"") != std::string::npos);
  CHECK(read_text(dir + "/out.mtl").find("map_Kd baked.png") != std::string::npos);
  CHECK(read_text(dir + "/err.txt").empty());
  // Read back as a user would: the OBJ's material names the baked texture, and every face
  // reads from it what it read from the input's texture.
  const MeshTexture found = find_mesh_texture(dir + "/out.obj");
  CHECK(found.file == dir + "/baked.png");
  const Image baked = read_image(dir + "/baked.png");
  const Mesh out = load_mesh(dir + "/out.obj").mesh;
  REQUIRE(out.num_faces() == m.num_faces());
  double sum = 0;
  int n = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    auto centre = [&](const Mesh& mesh) {
      const Face& t = mesh.face_uvs[f];
      return (mesh.uvs[t[0]] + mesh.uvs[t[1]] + mesh.uvs[t[2]]) / 3.0;
    };
    float a[3], b[3];
    const Vec2d p = centre(m), q = centre(out);
    sample_bilinear(tex, p.x, p.y, a);
    sample_bilinear(baked, q.x, q.y, b);
    for (int c = 0; c < 3; ++c, ++n) sum += std::abs(a[c] - b[c]);
  }
  CHECK(sum / n < 0.02);
  // A material that reads its image moved (map_Kd -s/-o) is baked as it reads: the baked atlas
  // shows what a viewer of the input shows, not the image at the file's coordinates.
  {
    std::string obj = read_text(dir + "/in.obj");
    const auto lib = obj.find("mtllib in.mtl");
    REQUIRE(lib != std::string::npos);
    obj.replace(lib, 13, "mtllib moved.mtl");
    std::ofstream(dir + "/moved.obj") << obj;
    std::string mtl = read_text(dir + "/in.mtl");
    const auto map = mtl.find("map_Kd tex.png");
    REQUIRE(map != std::string::npos);
    mtl.replace(map, 14, "map_Kd -s 0.5 0.5 1 -o 0.25 0.25 0 tex.png");
    std::ofstream(dir + "/moved.mtl") << mtl;
  }
  REQUIRE(run("-q atlas " + dir + "/moved.obj -o " + dir + "/moved_out.obj --width 256 --height 256 " +
              "--max-l2 1.02 --bake-texture " + dir + "/moved.png") == 0);
  {
    const Image moved = read_image(dir + "/moved.png");
    const Mesh mo = load_mesh(dir + "/moved_out.obj").mesh;
    REQUIRE(mo.num_faces() == m.num_faces());
    double as_read = 0, as_stored = 0;
    for (int f = 0; f < m.num_faces(); ++f) {
      auto centre = [&](const Mesh& mesh) {
        const Face& t = mesh.face_uvs[f];
        return (mesh.uvs[t[0]] + mesh.uvs[t[1]] + mesh.uvs[t[2]]) / 3.0;
      };
      float a[3], b[3], c[3];
      const Vec2d p = centre(m), q = centre(mo);
      sample_bilinear(tex, 0.5 * p.x + 0.25, 0.5 * p.y + 0.25, a);
      sample_bilinear(tex, p.x, p.y, c);
      sample_bilinear(moved, q.x, q.y, b);
      for (int k = 0; k < 3; ++k) {
        as_read += std::abs(a[k] - b[k]);
        as_stored += std::abs(c[k] - b[k]);
      }
    }
    CHECK(as_read / n < 0.02);
    CHECK(as_stored / n > 0.05);
  }
  // The glb embeds it: carried over once more from there, without naming a texture.
  CHECK(run("-q atlas " + dir + "/out.glb -o " + dir + "/again.glb --width 256 --height 256 --bake-texture " +
            dir + "/again.png") == 0);
  CHECK(std::filesystem::exists(dir + "/again.png"));
  // Without --bake-texture the outputs lose the texture, which the user hears about.
  CHECK(run("atlas " + dir + "/in.obj -o " + dir + "/plain.obj --width 256 --height 256") == 0);
  CHECK(read_text(dir + "/err.txt").find("--bake-texture FILE resamples it onto the atlas") !=
        std::string::npos);
  // Faces of a second material read their own; one defined in no library is named, unless
  // --texture says which image every face reads.
  {
    std::string obj = read_text(dir + "/in.obj");
    const auto face = obj.find("\nf ", obj.find("\nf ") + 1);
    REQUIRE(face != std::string::npos);
    obj.insert(face + 1, "usemtl other\n");
    std::ofstream(dir + "/multi.obj") << obj;
  }
  CHECK(run("-q atlas " + dir + "/multi.obj -o " + dir + "/m.obj --bake-texture " + dir + "/m.png") == 2);
  CHECK(read_text(dir + "/err.txt").find("its material other is defined in no material library it names") !=
        std::string::npos);
  CHECK(run("-q atlas " + dir + "/multi.obj -o " + dir + "/m.obj --bake-texture " + dir +
            "/m.png --texture " + dir + "/tex.png") == 0);
  // Refused before any work: an OBJ material naming a path with spaces (readers split there), a
  // glb embedding anything but PNG or JPEG, no mesh output, and baking over the texture the
  // input's material names (it belongs to the input model, even when --texture names another).
  std::filesystem::create_directories(dir + "/sp ace");
  CHECK(run("-q atlas " + dir + "/in.obj -o " + dir + "/s.obj --bake-texture '" + dir + "/sp ace/s.png'") ==
        2);
  CHECK(read_text(dir + "/err.txt").find("material readers split file names at spaces") != std::string::npos);
  CHECK(run("-q atlas " + dir + "/in.obj -o " + dir + "/s.glb --bake-texture " + dir + "/s.exr") == 2);
  CHECK(read_text(dir + "/err.txt").find("can embed only a PNG or JPEG image") != std::string::npos);
  CHECK(run("-q atlas " + dir + "/in.obj --bake-texture " + dir + "/s.png") == 2);
  CHECK(run("-q atlas " + dir + "/in.obj -o " + dir + "/s.obj --bake-texture " + dir + "/tex.png --texture " +
            dir + "/baked.png") == 2);
  CHECK(read_text(dir + "/err.txt").find("it is an input of this run") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir + "/s.obj"));
  // A texture with transparency stays transparent where it is read: the glb blends it, the MTL
  // names it as the alpha map; a JPEG cannot hold it and says so.
  {
    Image rgba(64, 64, 4, 1.0f);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 32; ++x) rgba.at(x, y, 3) = 0.0f;
    write_image(dir + "/rgba.png", rgba);
  }
  REQUIRE(run("-q atlas " + dir + "/in.obj -o " + dir + "/t.obj -o " + dir +
              "/t.glb --width 256 --height 256 " + "--bake-texture " + dir + "/t.png --texture " + dir +
              "/rgba.png") == 0);
  CHECK(read_text(dir + "/t.mtl").find("map_d t.png") != std::string::npos);
  CHECK(read_text(dir + "/t.glb").find("\"alphaMode\":\"BLEND\"") != std::string::npos);
  CHECK(run("atlas " + dir + "/in.obj -o " + dir + "/j.obj --width 256 --height 256 --bake-texture " + dir +
            "/j.jpg --texture " + dir + "/rgba.png") == 0);
  CHECK(read_text(dir + "/err.txt").find("JPEG has no alpha") != std::string::npos);
  CHECK(read_text(dir + "/j.mtl").find("map_d") == std::string::npos);
  // A mesh without texture coordinates has nothing to carry; --texture alone bakes nothing.
  CHECK(run("-q atlas builtin:face -o " + dir + "/f.obj --bake-texture " + dir + "/f.png") == 2);
  CHECK(read_text(dir + "/err.txt").find("has no texture coordinates") != std::string::npos);
  CHECK(run("-q atlas " + dir + "/in.obj -o " + dir + "/f.obj --texture " + dir + "/tex.png") == 2);
  CHECK_FALSE(std::filesystem::exists(dir + "/f.obj"));
  std::filesystem::remove_all(tmp);
}

TEST_CASE("isocharts atlas --bake-texture carries each material's texture, or its colour, over", "[signal]") {
  // A model of three materials, as exporters write characters (body, clothes, plain parts):
  // the atlas's one texture shows every face what its own material showed.
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() / ("isocharts_materials_" + std::to_string(::getpid()));
  std::filesystem::create_directories(tmp);
  const std::string dir = tmp.string();
  Mesh m = plane(24);
  for (auto& p : m.positions) p.z = 0.3 * std::sin(3 * p.x) * std::cos(2 * p.y);
  const Image smooth = smooth_texture(128);
  Image green(32, 32, 3, 0.0f);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) green.at(x, y, 1) = 0.5f + 0.4f * (x / 31.0f);
  write_image(dir + "/a.png", smooth);
  write_image(dir + "/b.png", green);
  {
    std::ofstream mtl(dir + "/in.mtl");
    mtl << "newmtl a\nKd 1 1 1\nmap_Kd a.png\nnewmtl b\nmap_Kd -s 2 1 1 b.png\nnewmtl c\nKd 0.1 0.2 0.9\n";
    std::ofstream obj(dir + "/in.obj");
    obj << "mtllib in.mtl\n";
    for (const auto& p : m.positions) obj << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (const auto& uv : m.uvs) obj << "vt " << uv.x << ' ' << uv.y << '\n';
    std::string last;
    for (int f = 0; f < m.num_faces(); ++f) {
      const double x = m.positions[m.faces[f][0]].x;
      const std::string mat = x < 0.3 ? "a" : (x < 0.6 ? "b" : "c");
      if (mat != last) obj << "usemtl " << mat << '\n';
      last = mat;
      obj << 'f';
      for (int k = 0; k < 3; ++k) obj << ' ' << m.faces[f][k] + 1 << '/' << m.faces[f][k] + 1;
      obj << '\n';
    }
  }
  const std::string cli = "\"" + std::string(ISOCHARTS_CLI) + "\" ";
  auto run = [&](const std::string& args) {
    const int code = std::system((cli + args + " > " + dir + "/out.txt 2> " + dir + "/err.txt").c_str());
    return WEXITSTATUS(code);
  };
  const LoadResult in = load_mesh(dir + "/in.obj");
  REQUIRE(in.mesh.face_materials.size() == in.mesh.faces.size());
  CHECK(in.mesh.material_names == std::vector<std::string>{"a", "b", "c"});
  const std::vector<MeshTexture> textures = find_material_textures(dir + "/in.obj", in.mesh);
  REQUIRE(textures.size() == 3);
  CHECK(textures[0].file == dir + "/a.png");
  CHECK(textures[1].uv_transform.a == 2);
  CHECK((textures[2].file.empty() && textures[2].colour.z == Approx(0.9)));
  REQUIRE(run("-q atlas " + dir + "/in.obj -o " + dir + "/out.obj --width 256 --height 256 --bake-texture " +
              dir + "/baked.png") == 0);
  const Image baked = read_image(dir + "/baked.png");
  const Mesh out = load_mesh(dir + "/out.obj").mesh;
  REQUIRE(out.num_faces() == in.mesh.num_faces());
  double diff[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  for (int f = 0; f < out.num_faces(); ++f) {
    auto centre = [&](const Mesh& mesh) {
      const Face& t = mesh.face_uvs[f];
      return (mesh.uvs[t[0]] + mesh.uvs[t[1]] + mesh.uvs[t[2]]) / 3.0;
    };
    const int mat = in.mesh.face_materials[f];
    const Vec2d p = centre(in.mesh), q = centre(out);
    float want[3], got[3];
    if (mat == 0) sample_bilinear(smooth, p.x, p.y, want);
    if (mat == 1) sample_bilinear(green, 2 * p.x, p.y, want, Wrap::Repeat);
    if (mat == 2) want[0] = 0.1f, want[1] = 0.2f, want[2] = 0.9f;
    sample_bilinear(baked, q.x, q.y, got);
    for (int c = 0; c < 3; ++c) diff[mat] += std::abs(want[c] - got[c]) / 3;
    ++count[mat];
  }
  for (int i = 0; i < 3; ++i) {
    INFO("material " << i);
    REQUIRE(count[i] > 50);
    CHECK(diff[i] / count[i] < 0.03);
  }
  CHECK(read_text(dir + "/err.txt").empty());  // -q
  REQUIRE(run("atlas " + dir + "/in.obj -o " + dir + "/out.obj --width 256 --height 256 --bake-texture " +
              dir + "/baked.png") == 0);
  CHECK(read_text(dir + "/err.txt")
            .find("faces read no texture in its material; baked in the material's colour") !=
        std::string::npos);
  // A material whose image is missing is named; baking over a material's image is refused.
  std::filesystem::rename(dir + "/b.png", dir + "/b_gone.png");
  CHECK(run("-q atlas " + dir + "/in.obj -o " + dir + "/out.obj --bake-texture " + dir + "/baked.png") == 2);
  CHECK(read_text(dir + "/err.txt").find("b.png") != std::string::npos);
  std::filesystem::rename(dir + "/b_gone.png", dir + "/b.png");
  CHECK(run("-q atlas " + dir + "/in.obj -o " + dir + "/out.obj --bake-texture " + dir + "/b.png") == 2);
  CHECK(read_image(dir + "/b.png").width == 32);  // untouched
  // render draws every material: blue (material c) on the right of the plane, green (b, its
  // image) in the middle, where the first material's texture alone had neither.
  REQUIRE(run("--json render " + dir + "/in.obj -o " + dir +
              "/r.png --views 1 --ortho --up z --width 240 "
              "--height 240") == 0);
  CHECK(read_text(dir + "/err.txt").find("first") == std::string::npos);
  CHECK(read_text(dir + "/out.txt").find("\"materials\": 3") != std::string::npos);
  const Image r = read_image(dir + "/r.png");
  int bluish = 0, greenish = 0;
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x) {
      const float cr = r.at(x, y, 0), cg = r.at(x, y, 1), cb = r.at(x, y, 2);
      bluish += cb > 2 * cr && cb > 1.5f * cg;
      greenish += cg > 2 * cr && cg > 2 * cb;
    }
  CHECK(bluish > 2000);
  CHECK(greenish > 2000);
  // A material whose image is missing is drawn in its colour, the others textured, and said.
  std::filesystem::rename(dir + "/b.png", dir + "/b_gone.png");
  REQUIRE(run("--json render " + dir + "/in.obj -o " + dir +
              "/r2.png --views 1 --ortho --up z --width 240 "
              "--height 240") == 0);
  CHECK(read_text(dir + "/err.txt").find("material b") != std::string::npos);
  CHECK(read_text(dir + "/out.txt").find("\"textured\"") != std::string::npos);
  std::filesystem::rename(dir + "/b_gone.png", dir + "/b.png");
  if (!std::getenv("KEEP_MATERIALS_TEST")) std::filesystem::remove_all(tmp);
}
