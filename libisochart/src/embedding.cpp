#include "isochart/embedding.h"

#include <Spectra/MatOp/DenseSymMatProd.h>
#include <Spectra/SymEigsSolver.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "isochart/error.h"

namespace isochart {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Vertices per task in the per-vertex loops: big enough to stream the q rows through the cache
// in runs, small enough to balance two threads on a few-thousand-vertex chart.
constexpr int kVertexChunk = 256;

// Below this many landmarks the dense solver wins over Lanczos for the top 10 eigenpairs:
// bench/geodesic_bench measured 0.20 vs 0.24 ms at q = 64, 0.34 vs 0.29 ms at q = 80 and
// 0.64 vs 0.32 ms at q = 100.
constexpr int kMinLanczosSize = 72;

// Eigenvalues at or below this fraction of the largest are noise: the marching stores its
// geometry in float (1e-7 relative), and a flat grid's third eigenvalue measured 2e-9·λ1.
constexpr double kRelativeEigenvalueFloor = 1e-6;

std::vector<int> referenced_vertices(const GeodesicSolver& solver) {
  std::vector<int> ref;
  for (int v = 0; v < solver.num_vertices(); ++v)
    if (solver.is_referenced(v)) ref.push_back(v);
  if (ref.empty()) throw InputError("", "embedding: the mesh has no faces");
  return ref;
}

// The vertex of `ref` with the largest `field` value (the first one on ties).
int argmax(const std::vector<int>& ref, const std::vector<double>& field) {
  int best = ref.front();
  for (int v : ref)
    if (field[v] > field[best]) best = v;
  return best;
}

[[noreturn]] void throw_disconnected(int v, int from) {
  throw Error("embedding: vertex " + std::to_string(v) + " cannot be reached from vertex " +
              std::to_string(from) +
              " over the surface; the mesh has several components, embed each separately");
}

void check_reached(const std::vector<int>& ref, const double* row, int from) {
  for (int v : ref)
    if (!std::isfinite(row[v])) throw_disconnected(v, from);
}

// Top `nev` eigenpairs of the symmetric q × q matrix `b`, descending. Lanczos (Spectra) for
// larger q, with a dense fallback should it not converge.
void top_eigenpairs(const Eigen::MatrixXd& b_in, int nev, Eigen::VectorXd& values, Eigen::MatrixXd& vectors) {
  const int q = static_cast<int>(b_in.rows());
  // Spectra's convergence test has an absolute floor (eps^(2/3), about 4e-11), so on a mesh a
  // hundred-millionth of a unit across (squared distances near 1e-16) it stopped early and the
  // charts depended on the mesh's scale. The matrix is brought to a largest entry in [1, 2) by
  // a power of two, which changes no bit of the arithmetic elsewhere; eigenvalues are scaled
  // back.
  const double largest = b_in.cwiseAbs().maxCoeff();
  const int exponent = largest > 0 && std::isfinite(largest) ? std::ilogb(largest) : 0;
  Eigen::MatrixXd scaled;
  if (exponent != 0) scaled = b_in * std::ldexp(1.0, -exponent);
  const Eigen::MatrixXd& b = exponent != 0 ? scaled : b_in;
  if (q >= kMinLanczosSize && nev < q) {
    Spectra::DenseSymMatProd<double> op(b);
    const int ncv = std::min(q, std::max(2 * nev + 1, 20));
    Spectra::SymEigsSolver<Spectra::DenseSymMatProd<double>> eigs(op, nev, ncv);
    // Spectra throws when its tridiagonal step fails (distances spanning many orders of
    // magnitude, e.g. a vertex far out at 1e10): the dense solver below gets a go instead.
    try {
      eigs.init();
      eigs.compute(Spectra::SortRule::LargestAlge, 1000, 1e-12);
      if (eigs.info() == Spectra::CompInfo::Successful) {
        values = eigs.eigenvalues() * std::ldexp(1.0, exponent);
        vectors = eigs.eigenvectors();
        return;
      }
    } catch (const std::runtime_error&) {
    }
  }
  if (!b.allFinite())
    throw InputError("", "embedding: squared geodesic distances overflow (coordinates too large)");
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(b);
  if (es.info() != Eigen::Success) throw Error("embedding: the eigen solver failed");
  // Eigen sorts ascending.
  values = es.eigenvalues().tail(nev).reverse() * std::ldexp(1.0, exponent);
  vectors = es.eigenvectors().rightCols(nev).rowwise().reverse();
}

}  // namespace

namespace {

// choose_landmarks, calling `chosen(k, vertex)` (in the calling thread) as soon as landmark k is
// fixed, so that its distance row can be computed while the sampling goes on.
std::vector<int> sample_landmarks(const GeodesicSolver& solver, int count, LandmarkMethod method,
                                  std::vector<double>* rows, const std::function<void(int, int)>& chosen) {
  if (rows) rows->clear();
  if (count < 1)
    throw InputError("", "embedding: landmark count must be at least 1, got " + std::to_string(count));
  const std::vector<int> ref = referenced_vertices(solver);
  if (count >= static_cast<int>(ref.size())) {
    if (chosen)
      for (std::size_t k = 0; k < ref.size(); ++k) chosen(static_cast<int>(k), ref[k]);
    return ref;
  }

  const std::vector<Vec3d>& x = solver.positions();
  Vec3d centroid;
  for (int v : ref) centroid += x[v];
  centroid /= static_cast<double>(ref.size());
  int seed = ref.front();
  double far = -1;
  for (int v : ref) {
    const double d = squared_norm(x[v] - centroid);
    if (d > far) far = d, seed = v;
  }

  const std::size_t nv = static_cast<std::size_t>(solver.num_vertices());
  std::vector<int> landmarks{seed};
  landmarks.reserve(count);
  auto add = [&](int v) {
    landmarks.push_back(v);
    if (chosen) chosen(static_cast<int>(landmarks.size()) - 1, v);
  };
  std::vector<double> field(nv, GeodesicSolver::inf);
  switch (method) {
    case LandmarkMethod::FastGeodesicFps:
      solver.lower_distances(seed, field);
      check_reached(ref, field.data(), seed);
      if (chosen) chosen(0, seed);
      while (static_cast<int>(landmarks.size()) < count) {
        add(argmax(ref, field));
        solver.lower_distances(landmarks.back(), field);
      }
      break;
    case LandmarkMethod::GeodesicFps: {
      std::vector<double> local;
      std::vector<double>& r = rows ? *rows : local;
      r.assign(static_cast<std::size_t>(count) * nv, 0.0);
      if (chosen) chosen(0, seed);
      for (int k = 0;; ++k) {
        double* row = r.data() + k * nv;
        solver.distances(&landmarks[k], 1, row);
        if (k == 0) check_reached(ref, row, seed);
        for (int v : ref) field[v] = std::min(field[v], row[v]);
        if (k + 1 == count) break;
        add(argmax(ref, field));
      }
      break;
    }
    case LandmarkMethod::EuclideanFps:
      if (chosen) chosen(0, seed);
      while (true) {
        const Vec3d& p = x[landmarks.back()];
        for (int v : ref) field[v] = std::min(field[v], norm(x[v] - p));
        if (static_cast<int>(landmarks.size()) == count) break;
        add(argmax(ref, field));
      }
      break;
  }
  return landmarks;
}

}  // namespace

std::vector<int> choose_landmarks(const GeodesicSolver& solver, int count, LandmarkMethod method,
                                  std::vector<double>* rows) {
  return sample_landmarks(solver, count, method, rows, nullptr);
}

void embed_landmarks(Embedding& e, int max_dimensions, const std::function<bool(int)>& referenced) {
  const int nv = e.num_vertices;
  const int q = static_cast<int>(e.landmarks.size());
  const std::size_t stride = static_cast<std::size_t>(nv);
  // The front from landmark i reaching j and the one from j reaching i differ by the marching
  // error; both entries get their mean, so that D is symmetric and the rows agree with it
  // (place_points on a landmark's own row then gives back its coordinates exactly).
  double* dist = e.landmark_distances.data();
  for (int i = 0; i < q; ++i)
    for (int j = 0; j < i; ++j) {
      double& a = dist[i * stride + e.landmarks[j]];
      double& b = dist[j * stride + e.landmarks[i]];
      a = b = 0.5 * (a + b);
    }
  Eigen::MatrixXd d2(q, q);
  for (int i = 0; i < q; ++i)
    for (int j = 0; j < q; ++j) {
      const double a = dist[i * stride + e.landmarks[j]];
      d2(i, j) = i == j ? 0.0 : a * a;
    }
  const Eigen::VectorXd row_mean = d2.rowwise().mean();
  const double total_mean = row_mean.mean();
  Eigen::MatrixXd b(q, q);
  for (int i = 0; i < q; ++i)
    for (int j = 0; j < q; ++j) b(i, j) = -0.5 * (d2(i, j) - row_mean[i] - row_mean[j] + total_mean);
  // The energy shares of §5.1/§5.3 are taken over the positive spectrum: geodesic distances are
  // not Euclidean, so B has negative eigenvalues too, and with them in the sum (the trace) the
  // top three would claim about 100% of the energy of nearly any shape.
  {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> all(b, Eigen::EigenvaluesOnly);
    e.eigenvalue_sum = 0;
    for (int i = 0; i < q; ++i) e.eigenvalue_sum += std::max(all.eigenvalues()[i], 0.0);
  }
  e.mean_squared_distances.assign(row_mean.data(), row_mean.data() + q);

  const int nev = std::min(max_dimensions, q);
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
  top_eigenpairs(b, nev, values, vectors);
  for (int j = 0; j < values.size(); ++j) {
    if (!(values[j] > 0) || values[j] <= kRelativeEigenvalueFloor * values[0]) break;
    e.eigenvalues.push_back(values[j]);
  }
  e.dimensions = static_cast<int>(e.eigenvalues.size());
  const int dims = e.dimensions;
  e.eigenvectors.resize(static_cast<std::size_t>(dims) * q);
  for (int j = 0; j < dims; ++j) {
    int big = 0;
    for (int k = 1; k < q; ++k)
      if (std::abs(vectors(k, j)) > std::abs(vectors(big, j))) big = k;
    const double sign = vectors(big, j) < 0 ? -1.0 : 1.0;
    for (int k = 0; k < q; ++k) e.eigenvectors[j * q + k] = sign * vectors(k, j);
  }

  // Placement (§5.2.1) for every vertex, rows streamed in chunks of vertices; the sum over
  // landmarks runs in a fixed order, so chunking and threads do not change the result.
  e.coordinates.assign(stride * dims, 0.0);
  std::vector<double> scale(dims);
  for (int j = 0; j < dims; ++j) scale[j] = 0.5 / std::sqrt(e.eigenvalues[j]);
  const int num_chunks = (nv + kVertexChunk - 1) / kVertexChunk;
  tbb::parallel_for(tbb::blocked_range<int>(0, num_chunks), [&](const tbb::blocked_range<int>& r) {
    // Accumulators are dimension-major so that the inner loops run over contiguous vertices
    // (vectorized): per landmark k, acc_j += v_j[k] · (Δ̄_k − d_k²) for the whole chunk.
    std::vector<double> acc, t;
    for (int chunk = r.begin(); chunk != r.end(); ++chunk) {
      const int first = chunk * kVertexChunk, last = std::min(nv, first + kVertexChunk);
      const int m = last - first;
      acc.assign(static_cast<std::size_t>(m) * dims, 0.0);
      t.resize(m);
      for (int k = 0; k < q; ++k) {
        const double* row = dist + k * stride + first;
        const double mean = e.mean_squared_distances[k];
        for (int i = 0; i < m; ++i) t[i] = std::isfinite(row[i]) ? mean - row[i] * row[i] : 0.0;
        for (int j = 0; j < dims; ++j) {
          const double v = e.eigenvectors[j * q + k];
          double* a = acc.data() + static_cast<std::size_t>(j) * m;
          for (int i = 0; i < m; ++i) a[i] += v * t[i];
        }
      }
      for (int i = 0; i < m; ++i) {
        if (!referenced(first + i)) continue;
        for (int j = 0; j < dims; ++j)
          e.coordinates[(first + i) * static_cast<std::size_t>(dims) + j] =
              scale[j] * acc[static_cast<std::size_t>(j) * m + i];
      }
    }
  });
  for (int k = 0; k < q; ++k)
    for (int j = 0; j < dims; ++j)
      e.coordinates[e.landmarks[k] * static_cast<std::size_t>(dims) + j] =
          std::sqrt(e.eigenvalues[j]) * e.eigenvectors[j * q + k];
}

Embedding landmark_isomap(const GeodesicSolver& solver, const EmbeddingOptions& options) {
  if (options.landmarks < 2)
    throw InputError("", "embedding: landmarks must be at least 2, got " + std::to_string(options.landmarks));
  if (options.max_dimensions < 1)
    throw InputError(
        "", "embedding: max_dimensions must be at least 1, got " + std::to_string(options.max_dimensions));
  Embedding e;
  const int nv = solver.num_vertices();
  e.num_vertices = nv;
  const std::vector<int> ref = referenced_vertices(solver);

  auto t0 = Clock::now();
  const int q = std::min(options.landmarks, static_cast<int>(ref.size()));
  const std::size_t stride = static_cast<std::size_t>(nv);
  std::vector<double> rows;
  if (options.landmark_method == LandmarkMethod::GeodesicFps) {
    e.landmarks = sample_landmarks(solver, q, options.landmark_method, &rows, nullptr);
    e.seconds_landmarks = seconds_since(t0);
    t0 = Clock::now();
    if (rows.empty()) rows = solver.distance_rows(e.landmarks);  // all vertices are landmarks
  } else {
    // Each row is marched by a task spawned as soon as its landmark is chosen, so a second
    // thread computes rows while this one is still sampling. The q × #V buffer is allocated by
    // a task too: zero-filling fresh pages measured 25–80 ms for the bunny's 29 MB, as long as
    // the sampling itself. Rows chosen before it is ready wait in `pending`. With one thread
    // all tasks run in wait(). A row depends only on its landmark: the result is the same
    // either way.
    tbb::task_group tasks;
    std::atomic<bool> allocated{false};
    tasks.run([&rows, &allocated, n = static_cast<std::size_t>(q) * stride] {
      rows.resize(n);
      allocated.store(true, std::memory_order_release);
    });
    std::vector<std::pair<int, int>> pending;
    const auto spawn_ready = [&] {
      for (const auto& [k, v] : pending)
        tasks.run(
            [&solver, &rows, stride, k = k, v = v] { solver.distances(&v, 1, rows.data() + k * stride); });
      pending.clear();
    };
    const auto chosen = [&](int k, int v) {
      pending.emplace_back(k, v);
      if (allocated.load(std::memory_order_acquire)) spawn_ready();
    };
    try {
      e.landmarks = sample_landmarks(solver, q, options.landmark_method, nullptr, chosen);
    } catch (...) {
      tasks.cancel();
      tasks.wait();
      throw;
    }
    e.seconds_landmarks = seconds_since(t0);
    t0 = Clock::now();
    if (!allocated.load(std::memory_order_acquire)) {
      tasks.wait();  // runs the allocation (and any row already spawned)
    }
    spawn_ready();
    tasks.wait();
  }
  check_reached(ref, rows.data(), e.landmarks[0]);
  e.landmark_distances = std::move(rows);
  e.seconds_rows = seconds_since(t0);

  t0 = Clock::now();
  embed_landmarks(e, options.max_dimensions, [&](int v) { return solver.is_referenced(v); });
  e.seconds_spectral = seconds_since(t0);
  return e;
}

void place_points(const Embedding& e, int dims, const double* squared_distances_to_landmarks, double* out) {
  if (dims < 0 || dims > e.dimensions)
    throw Error("place_points: dims " + std::to_string(dims) + " outside [0, " +
                std::to_string(e.dimensions) + "]");
  const int q = static_cast<int>(e.landmarks.size());
  for (int j = 0; j < dims; ++j) {
    double s = 0;
    for (int k = 0; k < q; ++k)
      s += e.eigenvectors[j * q + k] * (e.mean_squared_distances[k] - squared_distances_to_landmarks[k]);
    out[j] = 0.5 * s / std::sqrt(e.eigenvalues[j]);
  }
}

std::vector<double> gdd(const Embedding& e, int dims) {
  if (dims < 0 || dims > e.dimensions)
    throw Error("gdd: dims " + std::to_string(dims) + " outside [0, " + std::to_string(e.dimensions) + "]");
  const int nv = e.num_vertices;
  const int q = static_cast<int>(e.landmarks.size());
  const std::size_t stride = static_cast<std::size_t>(nv);
  const int dim_stride = e.dimensions;
  std::vector<double> out(stride, 0.0);
  if (q < 2) return out;
  const int num_chunks = (nv + kVertexChunk - 1) / kVertexChunk;
  tbb::parallel_for(tbb::blocked_range<int>(0, num_chunks), [&](const tbb::blocked_range<int>& r) {
    // The chunk's coordinates dimension-major, so the inner loops run over contiguous vertices.
    std::vector<double> y, s2;
    for (int chunk = r.begin(); chunk != r.end(); ++chunk) {
      const int first = chunk * kVertexChunk, last = std::min(nv, first + kVertexChunk);
      const int m = last - first;
      y.resize(static_cast<std::size_t>(m) * dims);
      s2.resize(m);
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < dims; ++j)
          y[static_cast<std::size_t>(j) * m + i] =
              e.coordinates[(first + i) * static_cast<std::size_t>(dim_stride) + j];
      double* o = out.data() + first;
      for (int k = 0; k < q; ++k) {
        const double* row = e.landmark_distances.data() + k * stride + first;
        const double* yl = e.coordinates.data() + e.landmarks[k] * static_cast<std::size_t>(dim_stride);
        std::fill(s2.begin(), s2.end(), 0.0);
        for (int j = 0; j < dims; ++j) {
          const double* yj = y.data() + static_cast<std::size_t>(j) * m;
          const double c = yl[j];
          for (int i = 0; i < m; ++i) s2[i] += (yj[i] - c) * (yj[i] - c);
        }
        for (int i = 0; i < m; ++i) {
          const double diff = std::sqrt(s2[i]) - row[i];
          if (std::isfinite(diff)) o[i] += diff * diff;
        }
      }
      for (int i = 0; i < m; ++i) o[i] = std::sqrt(o[i] / (q - 1));
    }
  });
  return out;
}

}  // namespace isochart
