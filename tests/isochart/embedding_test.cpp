#include "isochart/embedding.h"

#include <tbb/global_control.h>

#include <Eigen/Dense>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <set>

#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/geo_test_meshes.h"

using namespace isochart;

namespace {

// RMS distance between `a` (n × 2) and the best rigid motion (rotation, translation, and
// reflection, since an embedding's orientation is arbitrary) of `b` (n × 2).
double procrustes_rms(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b) {
  const Eigen::RowVector2d ca = a.colwise().mean(), cb = b.colwise().mean();
  const Eigen::MatrixX2d a0 = a.rowwise() - ca, b0 = b.rowwise() - cb;
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(b0.transpose() * a0, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix2d r = svd.matrixU() * svd.matrixV().transpose();
  return std::sqrt((b0 * r - a0).rowwise().squaredNorm().mean());
}

bool same_embedding(const Embedding& a, const Embedding& b) {
  return a.landmarks == b.landmarks && a.landmark_distances == b.landmark_distances &&
         a.eigenvalues == b.eigenvalues && a.eigenvalue_sum == b.eigenvalue_sum &&
         a.eigenvectors == b.eigenvectors && a.coordinates == b.coordinates;
}

}  // namespace

TEST_CASE("a flat rectangle embeds isometrically in 2-D", "[embedding]") {
  const Mesh m = geo_test::grid(30, 20, 3.0, 2.0);  // 651 vertices, more than the 100 landmarks
  const GeodesicSolver solver(m);
  const Embedding e = landmark_isomap(solver);
  REQUIRE(e.landmarks.size() == 100);
  REQUIRE(e.dimensions == 2);
  CHECK((e.eigenvalues[0] + e.eigenvalues[1]) / e.eigenvalue_sum == Approx(1.0).epsilon(1e-6));

  Eigen::MatrixX2d xy(m.num_vertices(), 2), uv(m.num_vertices(), 2);
  for (int v = 0; v < m.num_vertices(); ++v) {
    xy.row(v) << m.positions[v].x, m.positions[v].y;
    uv.row(v) << e.coordinate(v, 0), e.coordinate(v, 1);
  }
  CHECK(procrustes_rms(xy, uv) < 1e-4);

  const std::vector<double> g = gdd(e, 2);
  CHECK(*std::max_element(g.begin(), g.end()) < 1e-4);
}

TEST_CASE("an open tube shows the tubular eigenvalue pattern", "[embedding]") {
  // Radius 0.5 (circumference 3.14), length 4: long and cyclic (Iso-charts §5.3).
  const Mesh m = geo_test::tube(32, 42, 0.5, 4.0);
  const GeodesicSolver solver(m);
  const Embedding e = landmark_isomap(solver);
  REQUIRE(e.dimensions >= 4);
  const std::vector<double>& l = e.eigenvalues;
  INFO("eigenvalues " << l[0] << " " << l[1] << " " << l[2] << " " << l[3] << ", sum " << e.eigenvalue_sum);
  CHECK((l[0] + l[1] + l[2]) / e.eigenvalue_sum > 0.9);
  CHECK(l[0] / l[1] > 3);
  CHECK(l[1] / l[2] < 2);
  CHECK(l[2] / l[3] > 3);
  // And a flat strip of the same size is not cyclic.
  const Mesh strip = geo_test::grid(40, 31, 4.0, 3.14);
  const Embedding s = landmark_isomap(GeodesicSolver(strip));
  REQUIRE(s.dimensions == 2);
}

TEST_CASE("with q >= #V every vertex is a landmark", "[embedding]") {
  const Mesh m = geo_test::grid(6, 6, 1.0, 1.0, 0.2);  // 49 vertices
  const GeodesicSolver solver(m);
  EmbeddingOptions options;
  options.landmarks = 100;
  const Embedding e = landmark_isomap(solver, options);
  REQUIRE(e.landmarks.size() == 49);
  for (int v = 0; v < 49; ++v) CHECK(e.landmarks[v] == v);
  CHECK(e.landmark_distances.size() == 49u * 49u);
  options.landmarks = 49;
  CHECK(landmark_isomap(solver, options).landmarks == e.landmarks);
  options.landmarks = 48;
  CHECK(landmark_isomap(solver, options).landmarks.size() == 48);
}

TEST_CASE("the embedding is deterministic and independent of the thread count", "[embedding]") {
  const Mesh m = geo_test::bumpy_patch(40);
  const GeodesicSolver solver(m);
  const Embedding a = landmark_isomap(solver);
  const Embedding b = landmark_isomap(solver);
  CHECK(same_embedding(a, b));
  for (LandmarkMethod method :
       {LandmarkMethod::FastGeodesicFps, LandmarkMethod::GeodesicFps, LandmarkMethod::EuclideanFps}) {
    EmbeddingOptions options;
    options.landmark_method = method;
    Embedding one, two;
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      one = landmark_isomap(solver, options);
    }
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
      two = landmark_isomap(solver, options);
    }
    CHECK(same_embedding(one, two));
    CHECK(gdd(one, one.dimensions) == gdd(two, two.dimensions));
  }
}

TEST_CASE("eigenvectors have fixed signs and unit length", "[embedding]") {
  const Embedding e = landmark_isomap(GeodesicSolver(geo_test::torus(48, 20, 1.0, 0.4)));
  const int q = static_cast<int>(e.landmarks.size());
  REQUIRE(e.dimensions >= 3);
  REQUIRE(static_cast<int>(e.eigenvectors.size()) == e.dimensions * q);
  for (int j = 0; j < e.dimensions; ++j) {
    double norm2 = 0, big = 0;
    for (int k = 0; k < q; ++k) {
      const double c = e.eigenvectors[j * q + k];
      norm2 += c * c;
      if (std::abs(c) > std::abs(big)) big = c;
    }
    CHECK(norm2 == Approx(1.0).epsilon(1e-9));
    CHECK(big > 0);
    if (j > 0) CHECK(e.eigenvalues[j] <= e.eigenvalues[j - 1]);
  }
}

TEST_CASE("place_points reproduces landmark coordinates", "[embedding]") {
  const Mesh m = geo_test::bumpy_patch(36);
  const GeodesicSolver solver(m);
  const Embedding e = landmark_isomap(solver);
  const int q = static_cast<int>(e.landmarks.size());
  const int dims = e.dimensions;
  double scale = 0;
  for (double c : e.coordinates) scale = std::max(scale, std::abs(c));
  std::vector<double> sq(q), out(dims);
  for (int k = 0; k < q; ++k) {
    // The landmark's own distance row, restricted to the landmarks.
    for (int j = 0; j < q; ++j) sq[j] = std::pow(e.landmark_distance(k, e.landmarks[j]), 2);
    place_points(e, dims, sq.data(), out.data());
    for (int j = 0; j < dims; ++j) CHECK(std::abs(out[j] - e.coordinate(e.landmarks[k], j)) < 1e-9 * scale);
    // Its column (the other landmarks' fronts reaching it) is the same after symmetrization.
    for (int j = 0; j < q; ++j)
      CHECK(e.landmark_distance(k, e.landmarks[j]) == e.landmark_distance(j, e.landmarks[k]));
  }
  // Every other vertex is placed by the same formula from its distance column.
  for (int v = 0; v < m.num_vertices(); v += 37) {
    for (int j = 0; j < q; ++j) sq[j] = e.landmark_distance(j, v) * e.landmark_distance(j, v);
    place_points(e, 2, sq.data(), out.data());
    const bool is_landmark = std::find(e.landmarks.begin(), e.landmarks.end(), v) != e.landmarks.end();
    if (!is_landmark)
      for (int j = 0; j < 2; ++j) CHECK(std::abs(out[j] - e.coordinate(v, j)) < 1e-12 * scale);
  }
  CHECK_THROWS_AS(place_points(e, dims + 1, sq.data(), out.data()), Error);
}

TEST_CASE("gdd follows equation 1 against the landmarks", "[embedding]") {
  const Embedding e = landmark_isomap(GeodesicSolver(geo_test::icosphere(3)));
  const int q = static_cast<int>(e.landmarks.size());
  for (int dims : {2, 3, e.dimensions}) {
    const std::vector<double> g = gdd(e, dims);
    for (int v : {0, 17, 300, 641}) {
      double s = 0;
      for (int k = 0; k < q; ++k) {
        double y = 0;
        for (int j = 0; j < dims; ++j) {
          const double t = e.coordinate(v, j) - e.coordinate(e.landmarks[k], j);
          y += t * t;
        }
        s += std::pow(std::sqrt(y) - e.landmark_distance(k, v), 2);
      }
      CHECK(g[v] == Approx(std::sqrt(s / (q - 1))).epsilon(1e-9));
    }
  }
  // A sphere needs its third dimension: distortion drops when it is used.
  const std::vector<double> g2 = gdd(e, 2), g3 = gdd(e, 3);
  double m2 = 0, m3 = 0;
  for (std::size_t v = 0; v < g2.size(); ++v) m2 += g2[v], m3 += g3[v];
  CHECK(m3 < 0.7 * m2);
}

TEST_CASE("landmarks are spread by farthest-point sampling", "[embedding]") {
  const Mesh m = geo_test::bumpy_patch(40);
  const GeodesicSolver solver(m);
  for (LandmarkMethod method : {LandmarkMethod::FastGeodesicFps, LandmarkMethod::GeodesicFps}) {
    const Embedding e = [&] {
      EmbeddingOptions o;
      o.landmark_method = method;
      return landmark_isomap(solver, o);
    }();
    const int q = static_cast<int>(e.landmarks.size());
    CHECK(std::set<int>(e.landmarks.begin(), e.landmarks.end()).size() == e.landmarks.size());
    // Farthest-point sampling: every vertex is closer to some landmark than any two landmarks
    // are to each other (covering radius <= packing distance), up to the marching's asymmetry
    // and, for the fast variant, its slight overestimates at cell borders.
    double covering = 0, packing = GeodesicSolver::inf;
    for (int v = 0; v < m.num_vertices(); ++v) {
      double nearest = GeodesicSolver::inf;
      for (int k = 0; k < q; ++k) nearest = std::min(nearest, e.landmark_distance(k, v));
      covering = std::max(covering, nearest);
    }
    for (int k = 0; k < q; ++k)
      for (int j = 0; j < k; ++j) packing = std::min(packing, e.landmark_distance(k, e.landmarks[j]));
    INFO("method " << static_cast<int>(method) << ": covering radius " << covering << ", packing distance "
                   << packing);
    CHECK(covering <= 1.05 * packing);
    CHECK(covering < 0.3);  // a 2 × 2 patch with 100 landmarks: spacing about 0.2
  }
  // The fast variant picks (nearly) the same landmarks as plain geodesic FPS.
  EmbeddingOptions plain;
  plain.landmark_method = LandmarkMethod::GeodesicFps;
  const std::vector<int> fast = choose_landmarks(solver, 100, LandmarkMethod::FastGeodesicFps);
  const std::vector<int> slow = choose_landmarks(solver, 100, LandmarkMethod::GeodesicFps);
  std::set<int> common(fast.begin(), fast.end());
  int shared = 0;
  for (int v : slow) shared += static_cast<int>(common.count(v));
  CHECK(shared >= 90);
  CHECK(fast.front() == slow.front());
}

TEST_CASE("disconnected meshes, unreferenced vertices and bad options", "[embedding]") {
  Mesh m = geo_test::grid(8, 8, 1.0, 1.0);
  m.positions.push_back({5, 5, 5});  // unreferenced
  const int isolated = m.num_vertices() - 1;
  {
    const GeodesicSolver solver(m);
    EmbeddingOptions o;
    o.landmarks = 20;
    const Embedding e = landmark_isomap(solver, o);
    CHECK(std::find(e.landmarks.begin(), e.landmarks.end(), isolated) == e.landmarks.end());
    for (int j = 0; j < e.dimensions; ++j) CHECK(e.coordinate(isolated, j) == 0);
    CHECK(gdd(e, e.dimensions)[isolated] == 0);
    CHECK(e.dimensions == 2);
    o.landmarks = 1000;  // all referenced vertices
    const Embedding all = landmark_isomap(solver, o);
    CHECK(all.landmarks.size() == 81);
  }
  // A second patch makes the surface disconnected.
  const Mesh other = geo_test::grid(3, 3, 1.0, 1.0);
  const int offset = m.num_vertices();
  for (const auto& p : other.positions) m.positions.push_back(p + Vec3d{3, 0, 0});
  for (const auto& f : other.faces) m.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  const GeodesicSolver split(m);
  for (LandmarkMethod method :
       {LandmarkMethod::FastGeodesicFps, LandmarkMethod::GeodesicFps, LandmarkMethod::EuclideanFps}) {
    EmbeddingOptions o;
    o.landmark_method = method;
    CHECK_THROWS_AS(landmark_isomap(split, o), Error);
    o.landmarks = 1000;
    CHECK_THROWS_AS(landmark_isomap(split, o), Error);
  }

  const GeodesicSolver solver(geo_test::grid(4, 4, 1.0, 1.0));
  EmbeddingOptions bad;
  bad.landmarks = 1;
  CHECK_THROWS_AS(landmark_isomap(solver, bad), InputError);
  bad = EmbeddingOptions{};
  bad.max_dimensions = 0;
  CHECK_THROWS_AS(landmark_isomap(solver, bad), InputError);
  CHECK_THROWS_AS(landmark_isomap(GeodesicSolver(std::vector<Vec3d>{{0, 0, 0}}, {})), InputError);
}

TEST_CASE("tiny charts embed exactly", "[embedding]") {
  // One triangle, then a quad of two: every vertex is a landmark and the 2-D embedding keeps
  // all edge lengths.
  const std::vector<Vec3d> p{{0, 0, 0}, {2, 0, 0.5}, {0.5, 1.5, 0}, {2.2, 1.8, 0.3}};
  for (const std::vector<Face>& faces :
       {std::vector<Face>{{0, 1, 2}}, std::vector<Face>{{0, 1, 2}, {1, 3, 2}}}) {
    const GeodesicSolver solver(p, faces);
    const Embedding e = landmark_isomap(solver);
    const int n = faces.size() == 1 ? 3 : 4;
    REQUIRE(static_cast<int>(e.landmarks.size()) == n);
    REQUIRE(e.dimensions >= 2);
    for (const Face& f : faces)
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        double y = 0;
        for (int j = 0; j < e.dimensions; ++j) y += std::pow(e.coordinate(a, j) - e.coordinate(b, j), 2);
        CHECK(std::sqrt(y) == Approx(norm(p[a] - p[b])).epsilon(1e-6));
      }
  }
}

TEST_CASE("a shape with many appendages spreads its energy beyond three eigenvalues", "[embedding]") {
  // §5.1: the general clustering case. The energy is the positive spectrum: with the trace
  // (negative eigenvalues included) as the total, nearly every shape would pass 90%.
  const Embedding e = landmark_isomap(GeodesicSolver(make_builtin("creature")));
  REQUIRE(e.dimensions >= 4);
  double top = 0;
  for (double l : e.eigenvalues) top += l;
  CHECK(e.eigenvalue_sum >= top * (1 - 1e-12));
  const double top3 = (e.eigenvalues[0] + e.eigenvalues[1] + e.eigenvalues[2]) / e.eigenvalue_sum;
  INFO("top-3 share " << top3);
  CHECK(top3 < 0.9);
}
