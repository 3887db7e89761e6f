// Benchmark of fast marching and the landmark IsoMap embedding (libisochart geodesic.h,
// embedding.h): time per fast-marching run, landmark choice + rows + spectral stage with 1 and 2
// threads, the quality of each landmark method, and the dense vs Lanczos eigen solvers.
//
//   geodesic_bench [--reps N] [mesh ...]
//
// Meshes default to bunny.obj, feline.off (100k faces), hand.obj (fingers: close in space, far
// on the surface), face_mask.off (a disk, for the 2-D stretch), and bunny_lowres.off and
// eight.off, small enough (< 10k vertices) to compare with CGAL's exact geodesics, from the
// shared data folder. Times are wall clock, the median of N repetitions.

#include <Spectra/MatOp/DenseSymMatProd.h>
#include <Spectra/SymEigsSolver.h>
#include <tbb/global_control.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include "isochart/embedding.h"
#include "isochart/error.h"
#include "isochart/geodesic.h"
#include "isochart/io.h"
#include "isochart/mesh.h"
#include "isochart/stretch.h"

using namespace isochart;

namespace {

using Clock = std::chrono::steady_clock;

double seconds(const std::function<void()>& f) {
  const auto t0 = Clock::now();
  f();
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double cpu_seconds(clockid_t clock) {
  timespec t;
  clock_gettime(clock, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

// Wall and CPU (all threads of the process) seconds of one call. On a machine shared with other
// jobs the wall time includes waiting for a core; CPU time divided by the thread count is what
// the call would take on idle cores.
struct Timing {
  double wall, cpu;
};
Timing timed(const std::function<void()>& f) {
  const double c0 = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID);
  const double w = seconds(f);
  return {w, cpu_seconds(CLOCK_PROCESS_CPUTIME_ID) - c0};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

const char* method_name(LandmarkMethod m) {
  switch (m) {
    case LandmarkMethod::FastGeodesicFps:
      return "fast geodesic FPS";
    case LandmarkMethod::GeodesicFps:
      return "geodesic FPS";
    case LandmarkMethod::EuclideanFps:
      return "Euclidean FPS";
  }
  return "?";
}

// Embedding quality independent of the landmarks: the RMS over `probes` × all referenced
// vertices of (‖y_i − y_p‖ − d_geo(p, i)), relative to the mean geodesic distance. Probes are
// every (#ref / count)-th referenced vertex, the same for every method.
struct ProbeSet {
  std::vector<int> ids;
  std::vector<double> rows;  // ids.size() × #V
  double mean_distance = 0;
};

ProbeSet make_probes(const GeodesicSolver& solver, const std::vector<int>& ref, int count) {
  ProbeSet p;
  for (int k = 0; k < count; ++k) p.ids.push_back(ref[static_cast<std::size_t>(k) * ref.size() / count]);
  p.rows = solver.distance_rows(p.ids);
  double sum = 0;
  long n = 0;
  const std::size_t nv = static_cast<std::size_t>(solver.num_vertices());
  for (std::size_t k = 0; k < p.ids.size(); ++k)
    for (int v : ref) sum += p.rows[k * nv + v], ++n;
  p.mean_distance = sum / n;
  return p;
}

double probe_distortion(const Embedding& e, int dims, const ProbeSet& p, const std::vector<int>& ref) {
  const std::size_t nv = static_cast<std::size_t>(e.num_vertices);
  double sum = 0;
  long n = 0;
  for (std::size_t k = 0; k < p.ids.size(); ++k) {
    const int pv = p.ids[k];
    for (int v : ref) {
      if (v == pv) continue;
      double s = 0;
      for (int j = 0; j < dims; ++j) {
        const double t = e.coordinate(v, j) - e.coordinate(pv, j);
        s += t * t;
      }
      const double diff = std::sqrt(s) - p.rows[k * nv + v];
      sum += diff * diff;
      ++n;
    }
  }
  return std::sqrt(sum / n) / p.mean_distance;
}

double mean_of(const std::vector<double>& v, const std::vector<int>& ids) {
  double s = 0;
  for (int i : ids) s += v[i];
  return s / ids.size();
}

// B = −½ J D J from an embedding's landmark rows, as landmark_isomap builds it.
Eigen::MatrixXd centered_matrix(const Embedding& e) {
  const int q = static_cast<int>(e.landmarks.size());
  Eigen::MatrixXd d2(q, q);
  for (int i = 0; i < q; ++i)
    for (int j = 0; j < q; ++j) {
      const double a = e.landmark_distance(i, e.landmarks[j]), b = e.landmark_distance(j, e.landmarks[i]);
      d2(i, j) = 0.5 * (a * a + b * b);
    }
  const Eigen::VectorXd m = d2.rowwise().mean();
  const double mm = m.mean();
  Eigen::MatrixXd b(q, q);
  for (int i = 0; i < q; ++i)
    for (int j = 0; j < q; ++j) b(i, j) = -0.5 * (d2(i, j) - m[i] - m[j] + mm);
  return b;
}

void bench_eigen_solvers(const Embedding& e, int reps) {
  const Eigen::MatrixXd full = centered_matrix(e);
  // Leading principal blocks stand in for smaller landmark sets (same spectrum shape).
  for (int q : {20, 32, 48, 64, 80, 100}) {
    if (q > full.rows()) break;
    const Eigen::MatrixXd b = full.topLeftCorner(q, q);
    const int nev = std::min(10, q - 1);
    std::vector<double> dense, lanczos;
    Eigen::VectorXd dense_values, lanczos_values;
    for (int r = 0; r < reps * 10; ++r) {
      dense.push_back(seconds([&] {
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(b);
        dense_values = es.eigenvalues().tail(nev).reverse();
      }));
      lanczos.push_back(seconds([&] {
        Spectra::DenseSymMatProd<double> op(b);
        Spectra::SymEigsSolver<Spectra::DenseSymMatProd<double>> eigs(op, nev,
                                                                      std::min(q, std::max(2 * nev + 1, 20)));
        eigs.init();
        eigs.compute(Spectra::SortRule::LargestAlge, 1000, 1e-12);
        lanczos_values = eigs.eigenvalues();
      }));
    }
    const double diff = lanczos_values.size() == nev
                            ? (dense_values - lanczos_values).cwiseAbs().maxCoeff() / dense_values[0]
                            : -1.0;
    std::printf(
        "  eigen solver, q = %d, top %d: Eigen dense %.3f ms, Spectra Lanczos %.3f ms (max relative "
        "eigenvalue difference %.1e)\n",
        q, nev, 1e3 * median(dense), 1e3 * median(lanczos), diff);
  }
}

// Mean relative error of fast marching against CGAL's exact geodesics from a few sources,
// over vertices beyond 1.5 mean edge lengths from the source.
void bench_accuracy(const Mesh& mesh, const GeodesicSolver& solver, const std::vector<int>& ref) {
  const double h = mean_edge_length(mesh, Topology(mesh));
  double sum = 0, worst = 0;
  int runs = 0;
  std::vector<double> d;
  double exact_seconds = 0;
  for (int k = 0; k < 3; ++k) {
    const int src = ref[static_cast<std::size_t>(k) * ref.size() / 3];
    std::vector<double> exact;
    exact_seconds += seconds([&] { exact = exact_geodesic_distances(mesh.positions, mesh.faces, src); });
    solver.distances({src}, d);
    double rel = 0;
    int n = 0;
    for (int v : ref)
      if (exact[v] > 1.5 * h && std::isfinite(exact[v])) {
        rel += std::abs(d[v] - exact[v]) / exact[v];
        worst = std::max(worst, std::abs(d[v] - exact[v]) / h);
        ++n;
      }
    sum += rel / n;
    ++runs;
  }
  std::printf(
      "  accuracy vs CGAL exact geodesics (3 sources): mean relative error %.4f%%, max error %.2f mean edges "
      "(CGAL %.1f s per source)\n",
      100 * sum / runs, worst, exact_seconds / runs);
}

void bench_mesh(const std::string& path, int reps) {
  const Mesh mesh = load_mesh(path).mesh;
  const Topology topo(mesh);
  std::printf("%s: %d vertices (%d referenced), %d faces, %d components, %zu boundary loops\n", path.c_str(),
              mesh.num_vertices(), topo.num_referenced_vertices(), mesh.num_faces(), topo.num_components(),
              topo.boundary_loops().size());

  std::vector<double> t_build;
  for (int r = 0; r < reps; ++r) t_build.push_back(seconds([&] { GeodesicSolver s(mesh); }));
  const GeodesicSolver solver(mesh);
  std::printf("  solver construction %.1f ms; obtuse corners split %d, unsplit %d\n", 1e3 * median(t_build),
              solver.num_split_obtuse(), solver.num_unsplit_obtuse());

  std::vector<int> ref;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (solver.is_referenced(v)) ref.push_back(v);

  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    std::vector<double> d;
    std::vector<double> wall, cpu;
    for (int k = 0; k < 16 * reps; ++k) {
      const int src = ref[static_cast<std::size_t>(k) * ref.size() / (16 * reps)];
      const double c0 = cpu_seconds(CLOCK_THREAD_CPUTIME_ID);
      wall.push_back(seconds([&] { solver.distances({src}, d); }));
      cpu.push_back(cpu_seconds(CLOCK_THREAD_CPUTIME_ID) - c0);
    }
    std::printf(
        "  fast marching, one source, 1 thread: %.2f ms CPU, %.2f ms wall (medians of %zu runs; min %.2f ms "
        "CPU)\n",
        1e3 * median(cpu), 1e3 * median(wall), wall.size(), 1e3 * *std::min_element(cpu.begin(), cpu.end()));
  }

  if (ref.size() <= 10000) bench_accuracy(mesh, solver, ref);

  const ProbeSet probes = make_probes(solver, ref, 64);
  const bool disk = topo.num_components() == 1 && topo.boundary_loops().size() == 1 && topo.genus() == 0;
  Embedding fast_embedding;
  for (LandmarkMethod method :
       {LandmarkMethod::FastGeodesicFps, LandmarkMethod::GeodesicFps, LandmarkMethod::EuclideanFps}) {
    EmbeddingOptions options;
    options.landmark_method = method;
    Embedding e;
    for (int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      std::vector<double> wall, cpu, lm, rows, spec;
      for (int r = 0; r < reps; ++r) {
        const Timing t = timed([&] { e = landmark_isomap(solver, options); });
        wall.push_back(t.wall);
        cpu.push_back(t.cpu);
        lm.push_back(e.seconds_landmarks);
        rows.push_back(e.seconds_rows);
        spec.push_back(e.seconds_spectral);
      }
      std::printf(
          "  %-18s %d thread%s: wall %.3f s (min %.3f; landmarks %.3f, rows %.3f, spectral + placement "
          "%.3f), CPU %.3f s, CPU/threads %.3f s\n",
          method_name(method), threads, threads > 1 ? "s" : " ", median(wall),
          *std::min_element(wall.begin(), wall.end()), median(lm), median(rows), median(spec), median(cpu),
          median(cpu) / threads);
    }
    std::vector<double> g;
    const Timing tg = timed([&] { g = gdd(e, e.dimensions); });
    // Coverage: the largest distance from a vertex to its nearest landmark.
    double covering = 0;
    for (int v : ref) {
      double nearest = GeodesicSolver::inf;
      for (std::size_t k = 0; k < e.landmarks.size(); ++k)
        nearest = std::min(nearest, e.landmark_distance(static_cast<int>(k), v));
      covering = std::max(covering, nearest);
    }
    double energy3 = 0;
    for (int j = 0; j < std::min(3, e.dimensions); ++j) energy3 += e.eigenvalues[j];
    std::printf(
        "  %-18s quality: covering radius/mean dist %.4f, dims %d, top-3 energy %.3f, probe distortion %.4f "
        "(all dims) %.4f (2-D), mean GDD/mean dist %.4f",
        method_name(method), covering / probes.mean_distance, e.dimensions, energy3 / e.eigenvalue_sum,
        probe_distortion(e, e.dimensions, probes, ref), probe_distortion(e, 2, probes, ref),
        mean_of(g, ref) / probes.mean_distance);
    if (disk) {
      std::vector<Vec2d> uv(mesh.positions.size());
      for (int v : ref) uv[v] = {e.coordinate(v, 0), e.coordinate(v, 1)};
      StretchStats s = measure_stretch(mesh.positions, mesh.faces, uv);
      if (s.flipped > mesh.num_faces() / 2) {
        // Orientation is arbitrary; mirror when most faces came out clockwise.
        for (auto& p : uv) p.x = -p.x;
        s = measure_stretch(mesh.positions, mesh.faces, uv);
      }
      std::printf(", 2-D stretch L2 %.4f, flipped %d", s.l2, s.flipped);
      if (s.flipped) {
        // Stretch is infinite with flips; report the L2 over the unflipped faces for comparison.
        std::vector<int> ok;
        for (int f = 0; f < mesh.num_faces(); ++f) {
          const Face& t = mesh.faces[f];
          if (signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) > 0) ok.push_back(f);
        }
        Mesh m2 = mesh;
        m2.uvs = uv;
        m2.face_uvs = m2.faces;
        std::printf(" (L2 over unflipped faces %.4f)", measure_stretch(m2, ok).l2);
      }
    }
    std::printf(" (gdd %.3f s wall)\n", tg.wall);
    if (method == LandmarkMethod::FastGeodesicFps) fast_embedding = e;
  }
  bench_eigen_solvers(fast_embedding, reps);
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 3;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--reps" && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else if (a == "-h" || a == "--help") {
      std::printf("usage: geodesic_bench [--reps N] [mesh ...]\n");
      return 0;
    } else {
      meshes.push_back(a);
    }
  }
  if (meshes.empty()) {
    const std::string dir = std::string(ISOCHARTS_SHARED_DATA) + "/meshes/";
    meshes = {dir + "bunny.obj",     dir + "feline.off",       dir + "hand.obj",
              dir + "face_mask.off", dir + "bunny_lowres.off", dir + "eight.off"};
  }
  try {
    for (const auto& m : meshes) bench_mesh(m, reps);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geodesic_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
