// Multiresolution texture synthesis over an MCGIM pyramid (Wei–Levoy 2001 on Iso-charts §8
// geometry images), quality figures, and the transfer back onto the atlas.

#include "synth/synth.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <deque>
#include <flann/flann.hpp>
#include <limits>
#include <numeric>
#include <string>

#include "isochart/error.h"
#include "isochart/rng.h"
#include "synth/exemplar.h"

namespace synth {

namespace {

// printf into a string of whatever length the text needs (a scale of 1e-300 printed a
// 300-digit size and cut the message's advice off at a fixed buffer's end).
[[gnu::format(printf, 1, 2)]] std::string format(const char* fmt, ...) {
  va_list args, again;
  va_start(args, fmt);
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, fmt, args);
  va_end(args);
  std::string out(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(out.data(), out.size() + 1, fmt, again);
  va_end(again);
  return out;
}

// A bound printed to four digits, rounded towards the side that works: up for a least value,
// down for a greatest one.
double round_up_4(double x) {
  const double digits = std::pow(10.0, 3 - std::floor(std::log10(x)));
  return std::ceil(x * digits - 1e-6) / digits;
}
double round_down_4(double x) {
  const double digits = std::pow(10.0, 3 - std::floor(std::log10(x)));
  return std::floor(x * digits + 1e-6) / digits;
}

}  // namespace

using isochart::Image;
using isochart::Vec2d;
using isochart::Vec3d;
using Color = std::array<float, 3>;

namespace {

// The globally smoothest N-direction field (Knöppel et al. 2013, "Globally optimal direction
// fields"): per vertex a complex number z in a tangent basis (e1 = the start direction, e2 =
// n × e1) whose argument is N times the direction's angle; the field minimizing
// Σ_edges |z_j − r_ij z_i|², r_ij = e^{iN(α_j − α_i)} the discrete Levi-Civita transport (α the
// edge's angle in each basis), is the smallest eigenvector of that Hermitian form, found by
// inverse iteration from the start field (z = 1), which also fixes the free global rotation.
// N-direction fields place singularities of index k/N where a vector field needs whole ones.
std::vector<Vec3d> smoothest_field(const isochart::Mesh& mesh, const isochart::Topology& topo,
                                   const std::vector<Vec3d>& normals, const std::vector<Vec3d>& start,
                                   int symmetry, int iterations) {
  const int nv = mesh.num_vertices();
  std::vector<Vec3d> e1(nv), e2(nv);
  for (int i = 0; i < nv; ++i) {
    Vec3d a = start[i];
    if (isochart::norm(a) < 1e-12) {
      const Vec3d axis = std::fabs(normals[i].x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
      a = axis - normals[i] * isochart::dot(axis, normals[i]);
    }
    e1[i] = isochart::normalized(a);
    e2[i] = isochart::cross(normals[i], e1[i]);
  }
  // Real form of the Hermitian matrix A + εI on [Re z; Im z].
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<double> diag(nv, 0.0);
  for (int i = 0; i < nv; ++i) {
    for (int j : topo.vertex_neighbors(i)) {
      if (j <= i) continue;
      const Vec3d e = mesh.positions[j] - mesh.positions[i];
      const double ai = std::atan2(isochart::dot(e, e2[i]), isochart::dot(e, e1[i]));
      const double aj = std::atan2(isochart::dot(e, e2[j]), isochart::dot(e, e1[j]));
      const double c = std::cos(symmetry * (aj - ai)), sn = std::sin(symmetry * (aj - ai));
      diag[i] += 1;
      diag[j] += 1;
      // A_ji = −r, A_ij = −conj(r): rows of x_j, y_j and x_i, y_i.
      trip.emplace_back(j, i, -c);
      trip.emplace_back(j, nv + i, sn);
      trip.emplace_back(nv + j, i, -sn);
      trip.emplace_back(nv + j, nv + i, -c);
      trip.emplace_back(i, j, -c);
      trip.emplace_back(i, nv + j, -sn);
      trip.emplace_back(nv + i, j, sn);
      trip.emplace_back(nv + i, nv + j, -c);
    }
  }
  double mean_degree = 0;
  for (double v : diag) mean_degree += v;
  mean_degree = nv ? mean_degree / nv : 1;
  const double eps = 1e-6 * std::max(1.0, mean_degree);
  for (int i = 0; i < nv; ++i) {
    trip.emplace_back(i, i, diag[i] + eps);
    trip.emplace_back(nv + i, nv + i, diag[i] + eps);
  }
  Eigen::SparseMatrix<double> a(2 * nv, 2 * nv);
  a.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);
  if (solver.info() != Eigen::Success) throw isochart::Error("synth: direction-field factorization failed");
  Eigen::VectorXd z = Eigen::VectorXd::Zero(2 * nv);
  z.head(nv).setOnes();
  z.normalize();
  const int steps = std::clamp(iterations / 10, 5, 40);
  for (int it = 0; it < steps; ++it) {
    z = solver.solve(z);
    const double len = z.norm();
    if (!(len > 0) || !std::isfinite(len)) throw isochart::Error("synth: direction-field iteration diverged");
    z /= len;
  }
  std::vector<Vec3d> d(nv);
  for (int i = 0; i < nv; ++i) {
    const double t = std::atan2(z[nv + i], z[i]) / symmetry;
    d[i] = e1[i] * std::cos(t) + e2[i] * std::sin(t);
  }
  return d;
}

// A projected direction shorter than this (the direction within about 17° of the normal) is
// blended with a perpendicular axis in direction_field.
constexpr double kMinProjected = 0.3;

}  // namespace

double direction_along_normal_share(const isochart::Mesh& mesh, const Vec3d& direction) {
  if (!(isochart::norm(direction) > 0)) return 0;
  const Vec3d d = isochart::normalized(direction);
  const double cos_limit = std::sqrt(1 - kMinProjected * kMinProjected);
  double total = 0, along = 0;
  for (const auto& f : mesh.faces) {
    const Vec3d n = isochart::cross(mesh.positions[f[1]] - mesh.positions[f[0]],
                                    mesh.positions[f[2]] - mesh.positions[f[0]]);
    const double area2 = isochart::norm(n);
    if (!(area2 > 0)) continue;
    total += area2;
    if (std::fabs(isochart::dot(n, d)) > cos_limit * area2) along += area2;
  }
  return total > 0 ? along / total : 0;
}

std::vector<Vec3d> direction_field(const isochart::Mesh& mesh, const Vec3d& direction, int iterations,
                                   int symmetry) {
  if (symmetry < 1) throw isochart::InputError("", "direction-field symmetry must be at least 1");
  const std::vector<Vec3d> normals = isochart::vertex_normals(mesh);
  const bool user = isochart::norm(direction) > 0;
  const Vec3d primary = user ? isochart::normalized(direction) : Vec3d{1, 0, 0};
  // Where the primary axis is nearly normal, a perpendicular axis keeps the field defined.
  const Vec3d secondary = std::fabs(primary.y) < 0.9 ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1};
  const int nv = mesh.num_vertices();
  std::vector<Vec3d> d(nv);
  auto project = [&](const Vec3d& v, int i) {
    Vec3d p = v - normals[i] * isochart::dot(v, normals[i]);
    return p;
  };
  for (int i = 0; i < nv; ++i) {
    Vec3d p = project(primary, i);
    if (isochart::norm(p) < kMinProjected) {
      const Vec3d q = project(secondary, i);
      p = isochart::norm(p) < 1e-6 ? q : p + q * (kMinProjected - isochart::norm(p));
    }
    d[i] = isochart::norm(p) > 1e-12 ? isochart::normalized(p) : Vec3d{0, 0, 0};
  }
  if (user || iterations <= 0) return d;
  const isochart::Topology topo(mesh);
  if (symmetry > 1) return smoothest_field(mesh, topo, normals, d, symmetry, iterations);
  std::vector<Vec3d> next(nv);
  for (int it = 0; it < iterations; ++it) {
    tbb::parallel_for(0, nv, [&](int i) {
      Vec3d sum = d[i];
      for (int j : topo.vertex_neighbors(i)) sum = sum + d[j];
      const Vec3d p = project(sum, i);
      next[i] = isochart::norm(p) > 1e-12 ? isochart::normalized(p) : d[i];
    });
    std::swap(d, next);
  }
  return d;
}

namespace {

// Of the `symmetry` rotations of d about `normal` by multiples of 360°/symmetry, the one
// closest to `reference`.
Vec3d symmetric_representative(const Vec3d& d, const Vec3d& normal, int symmetry, const Vec3d& reference) {
  if (symmetry <= 1) return d;
  const Vec3d b = isochart::cross(normal, d);
  Vec3d best = d;
  double best_dot = -std::numeric_limits<double>::infinity();
  for (int m = 0; m < symmetry; ++m) {
    const double a = 2 * M_PI * m / symmetry;
    const Vec3d r = d * std::cos(a) + b * std::sin(a);
    const double v = isochart::dot(r, reference);
    if (v > best_dot + 1e-12) best_dot = v, best = r;
  }
  return best;
}

// Exemplar-pixel offset from sample s to its image neighbour t: their surface offset in the
// mean of their direction-field frames (+b on the surface is up in the exemplar, so y flips).
Vec2d field_offset(const mcgim::GeometryImage& g, const LevelGeometry& geo, double spacing, int s, int t) {
  const Vec3d w = g.positions[t] - g.positions[s];
  const Vec3d a1 = geo.t1(s) + geo.t1(t), a2 = geo.t2(s) + geo.t2(t);
  return {isochart::dot(a1, w) / (2 * spacing), -isochart::dot(a2, w) / (2 * spacing)};
}

// Exemplar coordinates of every reached sample of `g` (one per zipper group) minimizing
// Σ |c_t − c_s − d_st|² over image neighbours in one chart, d_st their surface offset in the
// field's frame (in exemplar pixels): the breadth-first copy follows the field along its tree
// only, and where two fronts meet the field's curl piles up as a shear line; the least-squares
// fit spreads it as a slow bend. Pairs whose frames disagree (the cut around the N-direction
// field's singularities) are left out. A weak pull toward the breadth-first coordinates fixes
// each component's translation.
// Returns the fraction of the fitted pairs whose copy offset is more than 1.3× longer or shorter
// than the field's (where the copy magnifies or shrinks the exemplar).
double relax_exemplar_coords(const mcgim::GeometryImage& g, const LevelGeometry& geo, double spacing,
                             std::vector<Vec2d>& coord, const std::vector<char>& reached, int rigid_rounds) {
  const int groups = g.num_groups;
  std::vector<int> rep(groups, -1);
  for (int s = 0; s < g.width * g.height; ++s)
    if (g.defined(s) && reached[s] && rep[g.group[s]] < 0) rep[g.group[s]] = s;
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::VectorXd bx = Eigen::VectorXd::Zero(groups), by = Eigen::VectorXd::Zero(groups);
  struct Pair {
    int s, t;
    Vec2d d;
  };
  std::vector<Pair> pairs;
  // Far below the smallest non-zero eigenvalue of the grid Laplacian (~1e-4 for 200 samples
  // across, ~1e-5 for 1000), so that only the translation is held.
  const double anchor = 1e-7;
  for (int gi = 0; gi < groups; ++gi) {
    if (rep[gi] < 0) {
      trip.emplace_back(gi, gi, 1.0);
      continue;
    }
    trip.emplace_back(gi, gi, anchor);
    bx[gi] += anchor * coord[rep[gi]].x;
    by[gi] += anchor * coord[rep[gi]].y;
  }
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const int s = g.index(x, y);
      if (!g.defined(s) || !reached[s]) continue;
      const int nb[2][2] = {{x + 1, y}, {x, y + 1}};
      for (const auto& q : nb) {
        if (q[0] >= g.width || q[1] >= g.height) continue;
        const int t = g.index(q[0], q[1]);
        if (!g.defined(t) || !reached[t] || g.chart[t] != g.chart[s]) continue;
        const int gs = g.group[s], gt = g.group[t];
        if (gs == gt || isochart::dot(geo.t1(s), geo.t1(t)) < 0.5) continue;
        const Vec2d d = field_offset(g, geo, spacing, s, t);
        trip.emplace_back(gs, gs, 1.0);
        trip.emplace_back(gt, gt, 1.0);
        trip.emplace_back(gs, gt, -1.0);
        trip.emplace_back(gt, gs, -1.0);
        pairs.push_back({gs, gt, d});
      }
    }
  Eigen::SparseMatrix<double> a(groups, groups);
  a.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);
  if (solver.info() != Eigen::Success) throw isochart::Error("synth: exemplar-copy factorization failed");
  // Solves with each pair's offset turned by the mean of its two samples' turns (unit complex
  // numbers; none: the offsets as they are).
  Eigen::VectorXd cx, cy;
  auto solve = [&](const std::vector<Vec2d>* turn) {
    Eigen::VectorXd rx = bx, ry = by;
    for (const Pair& p : pairs) {
      Vec2d d = p.d;
      if (turn) {
        const double c = 0.5 * ((*turn)[p.s].x + (*turn)[p.t].x), sn = 0.5 * ((*turn)[p.s].y + (*turn)[p.t].y);
        d = {c * p.d.x - sn * p.d.y, sn * p.d.x + c * p.d.y};
      }
      rx[p.s] -= d.x, rx[p.t] += d.x;
      ry[p.s] -= d.y, ry[p.t] += d.y;
    }
    cx = solver.solve(rx);
    cy = solver.solve(ry);
  };
  solve(nullptr);
  // As rigid as possible (local/global, Sorkine & Alexa 2007): offsets that do not close (the
  // field turns on a curved surface) are shortened by the plain fit, which magnifies the
  // exemplar there; turning each sample's offsets by the rotation that best matches its
  // neighbours' keeps the exemplar's scale, at the price of directions drifting from the field.
  std::vector<double> sum_dot, sum_cross;
  std::vector<Vec2d> turn;
  for (int round = 0; round < rigid_rounds; ++round) {
    sum_dot.assign(groups, 0.0);
    sum_cross.assign(groups, 0.0);
    for (const Pair& p : pairs) {
      const Vec2d e{cx[p.t] - cx[p.s], cy[p.t] - cy[p.s]};
      const double dt = p.d.x * e.x + p.d.y * e.y, cr = p.d.x * e.y - p.d.y * e.x;
      sum_dot[p.s] += dt, sum_dot[p.t] += dt;
      sum_cross[p.s] += cr, sum_cross[p.t] += cr;
    }
    turn.assign(groups, Vec2d{1, 0});
    for (int gi = 0; gi < groups; ++gi) {
      const double r = std::hypot(sum_dot[gi], sum_cross[gi]);
      if (r > 0) turn[gi] = {sum_dot[gi] / r, sum_cross[gi] / r};
    }
    solve(&turn);
  }
  for (int s = 0; s < g.width * g.height; ++s)
    if (g.defined(s) && reached[s]) coord[s] = {cx[g.group[s]], cy[g.group[s]]};
  long long off = 0;
  for (const Pair& p : pairs) {
    const double want = std::hypot(p.d.x, p.d.y), got = std::hypot(cx[p.t] - cx[p.s], cy[p.t] - cy[p.s]);
    if (got > 1.3 * want || 1.3 * got < want) ++off;
  }
  return pairs.empty() ? 0.0 : static_cast<double>(off) / static_cast<double>(pairs.size());
}

}  // namespace

namespace {

// The sample at the corner of the coarser level's remesh face nearest to where a normal-shooting
// correspondence `cr` (with a face) landed.
int nearest_corner(const mcgim::Level& coarser, const mcgim::Correspondence& cr) {
  const auto& corners = coarser.remesh.face_samples[cr.face];
  int best = 0;
  for (int c = 1; c < 3; ++c)
    if (cr.barycentric[c] > cr.barycentric[best]) best = c;
  return corners[best];
}

// A kd-tree over the PCA projection of components [first, first + count) of the exemplar's
// neighbourhood vectors.
struct KdIndex {
  int first = 0, count = 0, pca = 0;
  Eigen::VectorXf mean;
  Eigen::MatrixXf basis;            // count × pca
  std::vector<float> projected;     // candidates × pca
  std::unique_ptr<flann::Index<flann::L2<float>>> index;
};

// Exemplar neighbourhood vectors of one level and their kd-trees.
struct Matcher {
  int dim = 0;
  int width = 0, height = 0;
  std::vector<int> centres;         // exemplar pixel of each candidate
  std::vector<int> candidate_of;    // exemplar pixel → candidate, −1 when not one
  std::vector<float> features;      // candidates × dim
  KdIndex full;                     // every component (non-causal passes)
  double variance = 0;              // mean per-component variance of the exemplar colours
  // k-coherence (Tong et al. 2002): per candidate, the exemplar pixels of its `similar_k` most
  // similar other neighbourhoods (exact distance among kd-tree candidates), −1 padded.
  int similar_k = 0;
  std::vector<int> similar;
};

float pixel_clamped(const Image& img, double x, double y, int c) {
  // Bilinear with clamped borders; x, y in pixel-centre coordinates.
  x = std::clamp(x, 0.0, img.width - 1.0);
  y = std::clamp(y, 0.0, img.height - 1.0);
  const int x0 = std::min(static_cast<int>(x), img.width - 1), y0 = std::min(static_cast<int>(y), img.height - 1);
  const int x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
  const double ax = x - x0, ay = y - y0;
  return static_cast<float>((1 - ay) * ((1 - ax) * img.at(x0, y0, c) + ax * img.at(x1, y0, c)) +
                            ay * ((1 - ax) * img.at(x0, y1, c) + ax * img.at(x1, y1, c)));
}

// Neighbourhood of exemplar pixel (x, y): the n×n square at this level (row offsets flipped:
// +b on the surface is up in the image), then the nc×nc square of the coarser level.
void exemplar_neighborhood(const Image& e, const Image* coarse, double ratio, int n, int nc, int x,
                           int y, float* out) {
  const int r = n / 2, rc = nc / 2;
  int k = 0;
  for (int b = -r; b <= r; ++b)
    for (int a = -r; a <= r; ++a)
      for (int c = 0; c < 3; ++c)
        out[k++] = e.at(std::clamp(x + a, 0, e.width - 1), std::clamp(y - b, 0, e.height - 1), c);
  if (!coarse) return;
  const double cx = (x + 0.5) * ratio - 0.5, cy = (y + 0.5) * ratio - 0.5;
  for (int b = -rc; b <= rc; ++b)
    for (int a = -rc; a <= rc; ++a)
      for (int c = 0; c < 3; ++c) out[k++] = pixel_clamped(*coarse, cx + a, cy - b, c);
}

Matcher build_matcher(const Image& e, const Image* coarse, double ratio, int n, int nc, int pca_dims, int similar_k) {
  Matcher m;
  m.width = e.width;
  m.height = e.height;
  m.dim = 3 * (n * n + (coarse ? nc * nc : 0));
  // Centres whose square lies inside the exemplar, when there are enough of them: clamped
  // borders are not part of the pattern.
  const int r = n / 2;
  const bool inner = e.width - 2 * r >= 8 && e.height - 2 * r >= 8;
  for (int y = inner ? r : 0; y < (inner ? e.height - r : e.height); ++y)
    for (int x = inner ? r : 0; x < (inner ? e.width - r : e.width); ++x) m.centres.push_back(y * e.width + x);
  const int count = static_cast<int>(m.centres.size());
  m.candidate_of.assign(static_cast<std::size_t>(e.width) * e.height, -1);
  for (int i = 0; i < count; ++i) m.candidate_of[m.centres[i]] = i;
  m.features.resize(static_cast<std::size_t>(count) * m.dim);
  tbb::parallel_for(0, count, [&](int i) {
    exemplar_neighborhood(e, coarse, ratio, n, nc, m.centres[i] % e.width, m.centres[i] / e.width,
                          &m.features[static_cast<std::size_t>(i) * m.dim]);
  });
  Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> f(m.features.data(), count, m.dim);
  auto build = [&](KdIndex& kd, int first, int comps) {
    kd.first = first;
    kd.count = comps;
    const Eigen::MatrixXf block = f.middleCols(first, comps);
    kd.mean = block.colwise().mean().transpose();
    const Eigen::MatrixXf centred = block.rowwise() - kd.mean.transpose();
    const Eigen::MatrixXd cov = (centred.transpose() * centred).cast<double>() / std::max(1, count);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
    kd.pca = std::min(pca_dims, comps);
    // Eigenvalues come in increasing order: keep the last `pca` vectors.
    kd.basis = eig.eigenvectors().rightCols(kd.pca).cast<float>();
    kd.projected.resize(static_cast<std::size_t>(count) * kd.pca);
    Eigen::Map<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> p(kd.projected.data(), count, kd.pca);
    p = centred * kd.basis;
    flann::Matrix<float> data(kd.projected.data(), count, kd.pca);
    kd.index = std::make_unique<flann::Index<flann::L2<float>>>(data, flann::KDTreeSingleIndexParams(12));
    kd.index->buildIndex();
  };
  build(m.full, 0, m.dim);
  m.similar_k = std::min(similar_k, count - 1);
  if (m.similar_k > 0) {
    m.similar.assign(static_cast<std::size_t>(count) * m.similar_k, -1);
    // Neighbours closer than this in the exemplar mostly repeat the candidate's own shift.
    const int exclude = std::max(1, n / 2);
    const int want = std::min(count, m.similar_k + 1 + (2 * exclude + 1) * (2 * exclude + 1));
    tbb::parallel_for(tbb::blocked_range<int>(0, count, 256), [&](const tbb::blocked_range<int>& range) {
      std::vector<int> idx(want);
      std::vector<float> dist(want);
      for (int i = range.begin(); i < range.end(); ++i) {
        flann::Matrix<float> qm(&m.full.projected[static_cast<std::size_t>(i) * m.full.pca], 1, m.full.pca);
        flann::Matrix<int> im(idx.data(), 1, want);
        flann::Matrix<float> dm(dist.data(), 1, want);
        m.full.index->knnSearch(qm, im, dm, want, flann::SearchParams(-1, 0.0f));
        const int xi = m.centres[i] % e.width, yi = m.centres[i] / e.width;
        int k = 0;
        for (int j = 0; j < want && k < m.similar_k; ++j) {
          if (idx[j] < 0) continue;
          const int xj = m.centres[idx[j]] % e.width, yj = m.centres[idx[j]] / e.width;
          if (std::abs(xj - xi) <= exclude && std::abs(yj - yi) <= exclude) continue;
          m.similar[static_cast<std::size_t>(i) * m.similar_k + k++] = m.centres[idx[j]];
        }
      }
    });
  }
  double var = 0;
  for (int c = 0; c < 3; ++c) {
    double s = 0, s2 = 0;
    for (int i = 0; i < e.width * e.height; ++i) {
      s += e.pixels[i * 3 + c];
      s2 += double(e.pixels[i * 3 + c]) * e.pixels[i * 3 + c];
    }
    const double mu = s / (e.width * e.height);
    var += std::max(0.0, s2 / (e.width * e.height) - mu * mu);
  }
  m.variance = var / 3;
  return m;
}

struct Match {
  int pixel = -1;     // exemplar pixel index
  double error = 0;   // mean squared difference per valid component (unbiased)
};

// `query`: dim values; `valid`: dim/3 flags per tap (a missing tap is left out).
// `coherent`: exemplar pixels to re-rank first (Ashikhmin's coherent candidates: where the
// already-synthesized neighbours' exemplar positions say this sample should continue, and
// their k-coherence sets). `candidates` more come from `kd` (missing components at the mean);
// their exact distance is multiplied by 1 + `bias` when compared, so that a patch is only left
// for a clearly better match elsewhere (Hertzmann et al. 2001's coherence parameter).
Match best_match(const Matcher& m, const KdIndex& kd, const float* query, const std::vector<char>& valid,
                 int candidates, double bias, const std::vector<int>& coherent) {
  int count = 0;
  for (int i = 0; i < m.dim; ++i) count += valid[i / 3] ? 1 : 0;
  Match best;
  best.error = std::numeric_limits<double>::infinity();
  double best_score = best.error;
  auto consider = [&](int cand, double factor) {
    const float* f = &m.features[static_cast<std::size_t>(cand) * m.dim];
    double d = 0;
    for (int i = 0; i < m.dim; ++i)
      if (valid[i / 3]) d += double(query[i] - f[i]) * (query[i] - f[i]);
    d /= std::max(1, count);
    const double score = d * factor;
    const int px = m.centres[cand];
    if (score < best_score || (score == best_score && px < best.pixel)) best = {px, d}, best_score = score;
  };
  for (int px : coherent)
    if (px >= 0 && m.candidate_of[px] >= 0) consider(m.candidate_of[px], 1.0);
  if (candidates <= 0 && best.pixel >= 0) return best;
  Eigen::VectorXf q(kd.count);
  for (int i = 0; i < kd.count; ++i) {
    const int c = kd.first + i;
    q[i] = valid[c / 3] ? query[c] - kd.mean[i] : 0.0f;
  }
  Eigen::VectorXf proj = kd.basis.transpose() * q;
  const int k = std::min<int>(std::max(1, candidates), static_cast<int>(m.centres.size()));
  std::vector<int> idx(k);
  std::vector<float> dist(k);
  flann::Matrix<float> qm(proj.data(), 1, kd.pca);
  flann::Matrix<int> im(idx.data(), 1, k);
  flann::Matrix<float> dm(dist.data(), 1, k);
  kd.index->knnSearch(qm, im, dm, k, flann::SearchParams(-1, 1.0f));
  const double factor = coherent.empty() ? 1.0 : 1.0 + bias;
  for (int j : idx)
    if (j >= 0) consider(j, factor);
  return best;
}

struct LevelTaps {
  int fine = 0, coarse = 0;       // taps per group
  std::vector<Tap> taps;          // groups × (fine + coarse)
};

}  // namespace

SynthResult synthesize(const isochart::Mesh& atlas, const std::vector<mcgim::Level>& pyramid,
                       const Image& exemplar, const SynthOptions& o, const isochart::Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (pyramid.empty()) throw isochart::InputError("", "synthesis needs at least one MCGIM level");
  if (o.neighborhood < 3 || o.neighborhood % 2 == 0)
    throw isochart::InputError("", "neighborhood must be odd and at least 3");
  if (o.coarse_neighborhood < 1 || o.coarse_neighborhood % 2 == 0)
    throw isochart::InputError("", "coarse neighborhood must be odd and at least 1");
  if (o.first_pass_batch < 1 || o.full_passes < 0 || o.coarsest_passes < 0 || o.candidates < 1 || o.pca_dims < 1 ||
      o.k_coherence < 0)
    throw isochart::InputError("", "synthesis passes, batches, candidates and PCA dimensions must be positive");
  if (o.rigid_copy_rounds < -1)
    throw isochart::InputError("", "rigid copy rounds must be -1 (automatic) or at least 0");
  if (!(o.coherence >= 0) || !std::isfinite(o.coherence))
    throw isochart::InputError("", "coherence bias must be a non-negative number");
  if (!(o.scale >= 0) || !std::isfinite(o.scale)) throw isochart::InputError("", "scale must be positive");
  if (o.direction_symmetry < 0 || o.direction_symmetry > 8)
    throw isochart::InputError("", "direction symmetry must be in 0..8 (0: automatic)");
  if (!(o.symmetry_ratio >= 1) || !std::isfinite(o.symmetry_ratio))
    throw isochart::InputError("", "symmetry ratio must be at least 1");
  if (!std::isfinite(o.smoothness_threshold))
    throw isochart::InputError("", "smoothness threshold must be a number");
  if (!(o.correlation_threshold > -1 && o.correlation_threshold < 1))
    throw isochart::InputError("", "correlation threshold must lie in (-1, 1)");
  if (exemplar.channels != 3 || exemplar.width < 4 || exemplar.height < 4)
    throw isochart::InputError("", "the exemplar must be RGB and at least 4x4 (see load_exemplar)");

  SynthResult res;
  const int nl = static_cast<int>(pyramid.size());
  if (!(o.pixels_per_texel >= 0) || !std::isfinite(o.pixels_per_texel))
    throw isochart::InputError("", "pixels per texel must be positive");
  res.scale = o.pixels_per_texel > 0 && pyramid[0].stats.texel_size > 0 ? o.pixels_per_texel / pyramid[0].stats.texel_size
              : o.scale > 0                                               ? o.scale
                                        : exemplar.width / (0.1 * isochart::bounding_box(atlas).diagonal());
  res.requested_scale = res.scale;

  // Each limit on the scale below moves the default scale to the limit, and refuses a scale the
  // user asked for, saying why and what works.
  const bool default_scale = o.scale <= 0 && o.pixels_per_texel <= 0;
  const auto move_or_refuse = [&](double limit, const std::string& why, bool exemplar_size = false) {
    if (!default_scale) throw ScaleError(why, exemplar_size);
    res.scale = limit;
  };

  // An exemplar magnified past the size of the finest level's whole image would be copied as
  // one blown-up piece, and its pyramid (and the neighbourhoods searched in it) would not fit
  // in memory for scales a little smaller still: the scale has a floor. The default scale is
  // raised to it; a scale asked for below it is refused, saying what it would have cost.
  {
    double finest_texel = 0, level_pixels = 0;
    for (const mcgim::Level& lv : pyramid) {
      if (lv.stats.texel_size > 0 && (finest_texel == 0 || lv.stats.texel_size < finest_texel))
        finest_texel = lv.stats.texel_size;
      level_pixels = std::max(level_pixels, double(lv.image.width) * lv.image.height);
    }
    const double ex_pixels = double(exemplar.width) * exemplar.height;
    const double max_pixels = std::max(ex_pixels, level_pixels);
    const double min_factor = std::sqrt(ex_pixels / max_pixels);  // ≤ 1: at most this magnification
    if (finest_texel > 0 && res.scale * finest_texel < min_factor * (1 - 1e-9)) {
      const double min_scale = min_factor / finest_texel;
      const double f = res.scale * finest_texel;
      move_or_refuse(
          min_scale,
          format("exemplar scale too small: it would magnify the %dx%d exemplar %.4g times, to %.4gx%.4g "
                 "pixels, more than both its own size and the finest level's %.0f samples; the smallest "
                 "scale is %.4g exemplar pixels per unit length (%.4g per texel)",
                 exemplar.width, exemplar.height, 1 / f, exemplar.width / f, exemplar.height / f,
                 level_pixels, round_up_4(min_scale), round_up_4(min_factor)));
    }
  }

  // The other end: resampling keeps at least 4 exemplar pixels across, so a scale that would
  // shrink the exemplar further at the finest level would be silently capped there (--scale
  // 1e9 ran as 32 pixels per texel and reported 1e9). Refused when asked for, like a scale
  // below the floor; the default scale is capped and reported as used.
  if (pyramid[0].stats.texel_size > 0) {
    const double max_factor = exemplar.width / 4.0;
    const double f = res.scale * pyramid[0].stats.texel_size;
    if (f > max_factor * (1 + 1e-9)) {
      const double max_scale = max_factor / pyramid[0].stats.texel_size;
      move_or_refuse(
          max_scale,
          format("exemplar scale too large: a texel of the finest level would cover %.6g exemplar pixels, "
                 "shrinking the %dx%d exemplar below 4 pixels across; the largest scale is %.4g exemplar "
                 "pixels per unit length (%.4g per texel)",
                 f, exemplar.width, exemplar.height, round_down_4(max_scale), round_down_4(max_factor)));
    }
  }

  // The exemplar as searched at the finest level (one pixel per texel) costs about 1.2 KB of
  // neighbourhood vectors and search tree per pixel: a 4096² photograph at one pixel per texel
  // reached 17 GB on a 1,536-face mesh before it was stopped, 1024² took 1.3 GB and 68 s. Above
  // 1024² pixels the default scale shrinks the exemplar, and a scale asked for is refused.
  if (pyramid[0].stats.texel_size > 0) {
    constexpr double kMaxSearchedPixels = 1024.0 * 1024.0;
    const double f = res.scale * pyramid[0].stats.texel_size;  // exemplar pixels per texel
    const double searched = double(exemplar.width) * exemplar.height / (f * f);
    if (searched > kMaxSearchedPixels * (1 + 1e-9)) {
      const double min_factor = std::sqrt(double(exemplar.width) * exemplar.height / kMaxSearchedPixels);
      const double min_scale = min_factor / pyramid[0].stats.texel_size;
      move_or_refuse(
          min_scale,
          format("exemplar too large at this scale: the %dx%d exemplar at %.4g exemplar pixel%s per texel "
                 "would be searched as %.4g pixels (about %.2g GB); at most %.0f (1024x1024) are: use a "
                 "scale of at least %.4g exemplar pixels per unit length (%.4g per texel) "
                 "or a smaller exemplar",
                 exemplar.width, exemplar.height, f, f == 1 ? "" : "s", searched, searched * 1.2e3 / 1e9,
                 kMaxSearchedPixels, round_up_4(min_scale), round_up_4(min_factor)),
          true);
    }
  }

  // Exemplar pyramid: one level per MCGIM level, a pixel the size of that level's texel.
  std::vector<double> factors(nl);
  for (int l = 0; l < nl; ++l) factors[l] = res.scale * pyramid[l].stats.texel_size;
  const std::vector<ExemplarLevel> ex = exemplar_pyramid(exemplar, factors);

  const int n = o.neighborhood, nc = o.coarse_neighborhood;
  // Levels too small for a neighbourhood to fit in their charts only add noise: synthesis
  // starts at the coarsest level with enough samples (the finest one at the latest) when that
  // level's neighbourhoods are wide enough to see the exemplar's structure; otherwise a
  // coarse level matches blurred colours without the structure and scatters it into
  // fragments that finer neighbourhoods, seeing even less of it, cannot reassemble, so the
  // finest level's coherent exemplar copy is the better start.
  int top = 0;
  while (top + 1 < nl && pyramid[top + 1].image.num_groups >= o.min_level_samples) ++top;
  const std::array<double, 4> reach = correlation_lengths(exemplar, o.correlation_threshold);
  res.correlation_length = *std::max_element(reach.begin(), reach.end());
  res.smoothness = exemplar_smoothness(exemplar, ex[0].actual_factor);
  res.coarse_footprint = n * ex[top].actual_factor;
  if (o.start_level >= 0) {
    top = std::min(top, o.start_level);
  } else if (res.coarse_footprint < res.correlation_length || res.smoothness < o.smoothness_threshold) {
    top = 0;
  }
  res.start_level = top;

  // Automatic symmetry: an exemplar that decorrelates alike along x and y is taken as looking
  // alike turned by 90° (4 directions); otherwise it is only taken as unchanged by a half
  // turn (2), which keeps rows such as bricks or strands from turning by 90° at the field's
  // cuts while still allowing half-turn singularities.
  const double short_axis = std::min(reach[0], reach[1]), long_axis = std::max(reach[0], reach[1]);
  const int sym = o.direction_symmetry > 0 ? o.direction_symmetry
                  : long_axis <= o.symmetry_ratio * short_axis ? 4
                                                                : 2;
  res.direction_symmetry = sym;
  const std::vector<Vec3d> field = direction_field(atlas, o.direction, o.relax_iterations, sym);
  const std::vector<Vec3d> vnormals = sym > 1 ? isochart::vertex_normals(atlas) : std::vector<Vec3d>{};

  std::vector<std::vector<int>> reps(nl);  // a sample per zipper group
  std::vector<std::vector<int>> sources(nl);  // per level and group: its exemplar pixel or −1
  std::vector<std::vector<Vec3d>> level_dirs(nl);  // per level and group: the tangent direction
  for (int l = nl - 1; l >= 0; --l) {
    const mcgim::GeometryImage& g = pyramid[l].image;
    const int ns = g.width * g.height;
    std::vector<Vec3d>& group_dir = level_dirs[l];
    group_dir.assign(g.num_groups, Vec3d{0, 0, 0});
    reps[l].assign(g.num_groups, -1);
    for (int s = 0; s < ns; ++s) {
      if (!g.defined(s)) continue;
      const bool first = reps[l][g.group[s]] < 0;
      if (first) reps[l][g.group[s]] = s;
      const int f = g.face[s];
      if (f < 0 || f >= atlas.num_faces()) continue;
      Vec3d d{0, 0, 0};
      if (sym == 1) {
        for (int k = 0; k < 3; ++k) d = d + field[atlas.faces[f][k]] * g.barycentric[s][k];
        group_dir[g.group[s]] = group_dir[g.group[s]] + d;
      } else if (first) {
        // Corners matched to the first one before blending (any of their N rotations is the
        // same direction); one member per zipper group so that its charts agree.
        const Vec3d ref = field[atlas.faces[f][0]];
        for (int k = 0; k < 3; ++k) {
          const int v = atlas.faces[f][k];
          d = d + symmetric_representative(field[v], vnormals[v], sym, ref) * g.barycentric[s][k];
        }
        group_dir[g.group[s]] = d;
      }
    }
    if (sym > 1 && l <= top) {
      // One representative of the N per group, chosen to vary continuously: on finer levels
      // the one nearest the coarser level's at the normal-shooting landing point (so that
      // coordinate upsampling continues patches in the same orientation), on the first
      // synthesized level breadth-first over the samples' image neighbours and zipper groups.
      // Around the field's singularities a cut where two orientations meet is unavoidable.
      auto rep_of = [&](int gi, const Vec3d& ref) {
        const int s = reps[l][gi];
        return symmetric_representative(group_dir[gi], g.normals[s], sym, ref);
      };
      std::vector<char> done(g.num_groups, 0);
      if (l < top) {
        const mcgim::GeometryImage& cg = pyramid[l + 1].image;
        for (int gi = 0; gi < g.num_groups; ++gi) {
          const int s = reps[l][gi];
          if (s < 0 || isochart::norm(group_dir[gi]) < 1e-12) continue;
          const mcgim::Correspondence& cr = pyramid[l].coarser[s];
          if (cr.face < 0) continue;
          const Vec3d ref = level_dirs[l + 1][cg.group[nearest_corner(pyramid[l + 1], cr)]];
          if (isochart::norm(ref) < 1e-12) continue;
          group_dir[gi] = rep_of(gi, ref);
          done[gi] = 1;
        }
      }
      // Group adjacency through 4-neighbours in the same chart.
      std::vector<std::pair<int, int>> edges;
      for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x) {
          const int s = g.index(x, y);
          if (!g.defined(s)) continue;
          if (x + 1 < g.width && g.defined(g.index(x + 1, y)) && g.chart[g.index(x + 1, y)] == g.chart[s])
            edges.push_back({g.group[s], g.group[g.index(x + 1, y)]});
          if (y + 1 < g.height && g.defined(g.index(x, y + 1)) && g.chart[g.index(x, y + 1)] == g.chart[s])
            edges.push_back({g.group[s], g.group[g.index(x, y + 1)]});
        }
      const std::size_t ne = edges.size();
      for (std::size_t i = 0; i < ne; ++i) edges.push_back({edges[i].second, edges[i].first});
      std::sort(edges.begin(), edges.end());
      edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
      std::vector<int> first_edge(g.num_groups + 1, 0);
      for (const auto& e : edges) ++first_edge[e.first + 1];
      for (int gi = 0; gi < g.num_groups; ++gi) first_edge[gi + 1] += first_edge[gi];
      std::deque<int> queue;
      for (int gi = 0; gi < g.num_groups; ++gi)
        if (done[gi]) queue.push_back(gi);
      for (int root = 0; root < g.num_groups; ++root) {
        if (queue.empty()) {
          if (done[root] || reps[l][root] < 0 || isochart::norm(group_dir[root]) < 1e-12) continue;
          done[root] = 1;
          queue.push_back(root);
        }
        while (!queue.empty()) {
          const int gi = queue.front();
          queue.pop_front();
          for (int k = first_edge[gi]; k < first_edge[gi + 1]; ++k) {
            const int h = edges[k].second;
            if (done[h] || reps[l][h] < 0 || isochart::norm(group_dir[h]) < 1e-12) continue;
            group_dir[h] = rep_of(h, group_dir[gi]);
            done[h] = 1;
            queue.push_back(h);
          }
        }
      }
    }
  }
  std::vector<LevelGeometry> geo;
  geo.reserve(nl);
  for (int l = 0; l < nl; ++l) {
    const mcgim::GeometryImage& g = pyramid[l].image;
    std::vector<Vec3d> dir(static_cast<std::size_t>(g.width) * g.height, Vec3d{0, 0, 0});
    for (int s = 0; s < g.width * g.height; ++s)
      if (g.defined(s)) dir[s] = level_dirs[l][g.group[s]];
    geo.emplace_back(pyramid[l], dir);
  }
  isochart::report(progress, isochart::Stage::Synthesis, 0.05);

  res.group_colors.resize(nl);
  res.levels.resize(nl);
  for (int l = top + 1; l < nl; ++l) {
    res.levels[l].width = pyramid[l].image.width;
    res.levels[l].height = pyramid[l].image.height;
    res.levels[l].texel_size = pyramid[l].stats.texel_size;
  }
  for (int l = top; l >= 0; --l) {
    const auto tl = std::chrono::steady_clock::now();
    const mcgim::Level& lv = pyramid[l];
    const mcgim::GeometryImage& g = lv.image;
    const bool has_coarse = l < top;
    const int groups = g.num_groups;
    const Image& e = ex[l].image;
    const double spacing = ex[l].actual_factor / res.scale;
    SynthLevelStats& st = res.levels[l];
    st.width = g.width;
    st.height = g.height;
    st.exemplar_width = e.width;
    st.exemplar_height = e.height;
    st.texel_size = lv.stats.texel_size;
    st.exemplar_factor = ex[l].actual_factor;
    st.groups = groups;

    // Taps of every group: n×n at this level, nc×nc on the coarser level around the sample's
    // normal-shooting landing point.
    LevelTaps lt;
    lt.fine = n * n;
    lt.coarse = has_coarse ? nc * nc : 0;
    const int per = lt.fine + lt.coarse;
    lt.taps.resize(static_cast<std::size_t>(groups) * per);
    const double cspacing = has_coarse ? ex[l + 1].actual_factor / res.scale : 0;
    tbb::parallel_for(0, groups, [&](int gi) {
      const int s = reps[l][gi];
      Tap* out = &lt.taps[static_cast<std::size_t>(gi) * per];
      if (s < 0) return;
      const int r = n / 2;
      int k = 0;
      for (int b = -r; b <= r; ++b)
        for (int a = -r; a <= r; ++a) out[k++] = geo[l].locate(s, a * spacing, b * spacing);
      if (!has_coarse) return;
      const mcgim::Correspondence& cr = lv.coarser[s];
      if (cr.face < 0) return;
      const int frame = nearest_corner(pyramid[l + 1], cr);  // its frame orients the taps
      const int rc = nc / 2;
      for (int b = -rc; b <= rc; ++b)
        for (int a = -rc; a <= rc; ++a)
          out[k++] = geo[l + 1].locate(cr.image_xy, cr.chart, frame, a * cspacing, b * cspacing);
    });
    for (const Tap& t : lt.taps) {
      st.missing_taps += t.valid() ? 0 : 1;
      st.seam_taps += t.crossed ? 1 : 0;
    }

    const Image* coarse_img = has_coarse ? &ex[l + 1].image : nullptr;
    const double ratio = has_coarse ? ex[l].actual_factor / ex[l + 1].actual_factor : 1;
    const Matcher matcher = build_matcher(e, coarse_img, ratio, n, has_coarse ? nc : 0, o.pca_dims, o.k_coherence);

    // Per fine tap, the group that dominates it and its offset from the sample in exemplar
    // pixels, measured on the surface (the tap's nominal offset is off by up to a texel).
    std::vector<std::array<int, 3>> shift(static_cast<std::size_t>(groups) * lt.fine, {-1, 0, 0});
    tbb::parallel_for(0, groups, [&](int gi) {
      const int s = reps[l][gi];
      if (s < 0) return;
      const Tap* t = &lt.taps[static_cast<std::size_t>(gi) * per];
      for (int k = 0; k < lt.fine; ++k) {
        if (!t[k].valid()) continue;
        int j = 0;
        for (int i = 1; i < 4 && t[k].sample[i] >= 0; ++i)
          if (t[k].weight[i] > t[k].weight[j]) j = i;
        const Vec3d w = g.positions[t[k].sample[j]] - g.positions[s];
        shift[static_cast<std::size_t>(gi) * lt.fine + k] = {
            g.group[t[k].sample[j]], static_cast<int>(std::lround(isochart::dot(geo[l].t1(s), w) / spacing)),
            static_cast<int>(std::lround(isochart::dot(geo[l].t2(s), w) / spacing))};
      }
    });

    std::vector<Color>& col = res.group_colors[l];
    col.assign(groups, Color{0.5f, 0.5f, 0.5f});
    std::vector<int>& src = sources[l];  // exemplar pixel each group was copied from
    src.assign(groups, -1);
    auto set_pixel = [&](std::vector<Color>& cs, std::vector<int>& ss, int gi, int px) {
      for (int c = 0; c < 3; ++c) cs[gi][c] = e.pixels[px * 3 + c];
      ss[gi] = px;
    };
    if (!has_coarse) {
      // Coarsest level: each chart starts as a copy of the exemplar at a random offset, grown
      // outwards from the chart's central sample: every sample continues the exemplar position
      // of the sample it was reached from, shifted by their surface offset in its own frame, so
      // that the copy follows the direction field locally (per-sample noise would make the
      // non-causal passes regress to the exemplar's mean colour).
      std::vector<std::array<double, 3>> centre(g.num_charts, {0, 0, 0});
      for (int gi = 0; gi < groups; ++gi) {
        const int s = reps[l][gi];
        if (s < 0) continue;
        auto& c = centre[g.chart[s]];
        c[0] += s % g.width + 0.5, c[1] += s / g.width + 0.5, c[2] += 1;
      }
      std::vector<int> seed_sample(g.num_charts, -1);
      std::vector<double> seed_d(g.num_charts, std::numeric_limits<double>::infinity());
      for (int s = 0; s < g.width * g.height; ++s) {
        if (!g.defined(s)) continue;
        const int ch = g.chart[s];
        const double ddx = s % g.width + 0.5 - centre[ch][0] / centre[ch][2];
        const double ddy = s / g.width + 0.5 - centre[ch][1] / centre[ch][2];
        if (ddx * ddx + ddy * ddy < seed_d[ch]) seed_d[ch] = ddx * ddx + ddy * ddy, seed_sample[ch] = s;
      }
      auto reflect = [](double v, int size) {
        const double period = 2.0 * size;
        v = std::fmod(v, period);
        if (v < 0) v += period;
        if (v >= size) v = period - v - 1e-9;
        return std::clamp(static_cast<int>(v), 0, size - 1);
      };
      std::vector<Vec2d> coord(static_cast<std::size_t>(g.width) * g.height, Vec2d{0, 0});
      std::vector<char> reached(coord.size(), 0);
      // Samples of each zipper group (one surface point on several charts' borders): the copy
      // continues through them into the neighbour chart, so that seams start continuous.
      std::vector<int> group_start(groups + 1, 0), group_members;
      for (int s = 0; s < g.width * g.height; ++s)
        if (g.defined(s)) ++group_start[g.group[s] + 1];
      for (int gi = 0; gi < groups; ++gi) group_start[gi + 1] += group_start[gi];
      group_members.resize(group_start[groups]);
      {
        std::vector<int> fill(group_start.begin(), group_start.end() - 1);
        for (int s = 0; s < g.width * g.height; ++s)
          if (g.defined(s)) group_members[fill[g.group[s]]++] = s;
      }
      // Charts by decreasing size seed the copy; a chart already reached through a seam is not
      // seeded again.
      std::vector<int> chart_order(g.num_charts);
      std::iota(chart_order.begin(), chart_order.end(), 0);
      std::stable_sort(chart_order.begin(), chart_order.end(),
                       [&](int x, int y) { return centre[x][2] > centre[y][2]; });
      std::deque<int> queue;
      for (int ch : chart_order) {
        if (seed_sample[ch] < 0 || reached[seed_sample[ch]]) continue;
        isochart::Rng rng(isochart::mix_seed(o.seed, 5000u + static_cast<std::uint64_t>(ch)));
        coord[seed_sample[ch]] = {rng.uniform() * e.width, rng.uniform() * e.height};
        reached[seed_sample[ch]] = 1;
        queue.push_back(seed_sample[ch]);
        while (!queue.empty()) {
          const int s = queue.front();
          queue.pop_front();
          const int grp = g.group[s];
          for (int k = group_start[grp]; k < group_start[grp + 1]; ++k) {
            const int t = group_members[k];
            if (reached[t]) continue;
            coord[t] = coord[s];
            reached[t] = 1;
            queue.push_back(t);
          }
          const int x = s % g.width, y = s / g.width;
          const int nb[4][2] = {{x + 1, y}, {x - 1, y}, {x, y + 1}, {x, y - 1}};
          for (const auto& q : nb) {
            if (q[0] < 0 || q[1] < 0 || q[0] >= g.width || q[1] >= g.height) continue;
            const int t = g.index(q[0], q[1]);
            if (reached[t] || g.chart[t] != g.chart[s]) continue;
            coord[t] = coord[s] + field_offset(g, geo[l], spacing, s, t);
            reached[t] = 1;
            queue.push_back(t);
          }
        }
      }
      // The factorization's fill grows faster than the samples (grid Laplacians, measured: 0.1 s
      // for 40k unknowns, 8 s and 0.5 GB for 640k, 18 s and 0.8 GB for 1M), so larger levels
      // keep the breadth-first copy. 300 conjugate-gradient steps from it instead left long
      // wavy smears on bunny at 1024² (663k samples), worse than the copy itself.
      if (o.relax_copy && groups <= o.relax_copy_max)
        res.copy_scale_off = relax_exemplar_coords(g, geo[l], spacing, coord, reached,
                              o.rigid_copy_rounds >= 0 ? o.rigid_copy_rounds : (sym >= 4 ? 20 : 0));
      for (int gi = 0; gi < groups; ++gi) {
        const int s = reps[l][gi];
        if (s < 0 || !reached[s]) continue;
        set_pixel(col, src, gi, reflect(coord[s].y, e.height) * e.width + reflect(coord[s].x, e.width));
      }
    } else {
      // Coordinate upsampling (Lefebvre & Hoppe 2005): each sample continues the exemplar
      // patch of the coarser sample nearest to its normal-shooting landing point, shifted by
      // its surface offset from that sample in the local frame; the coarser level's structure
      // thus carries over whole instead of as blurred colours. Samples without a landing
      // point take the interpolated coarser colour and no exemplar position.
      const std::vector<Color>& cc = res.group_colors[l + 1];
      const std::vector<int>& csrc = sources[l + 1];
      const mcgim::GeometryImage& cg = pyramid[l + 1].image;
      const Image& ce = ex[l + 1].image;
      const double up = ex[l + 1].actual_factor / ex[l].actual_factor;
      for (int gi = 0; gi < groups; ++gi) {
        const int s = reps[l][gi];
        if (s < 0) continue;
        const mcgim::Correspondence& cr = lv.coarser[s];
        if (cr.face < 0) continue;
        const auto& corners = pyramid[l + 1].remesh.face_samples[cr.face];
        const int cs = nearest_corner(pyramid[l + 1], cr);
        const int pc = csrc[cg.group[cs]];
        if (pc < 0) {
          Color v{0, 0, 0};
          for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) v[c] += static_cast<float>(cr.barycentric[k]) * cc[cg.group[corners[k]]][c];
          col[gi] = v;
          continue;
        }
        const Vec3d w = g.positions[s] - cg.positions[cs];
        const double fx = (pc % ce.width + 0.5) * up - 0.5 + isochart::dot(geo[l + 1].t1(cs), w) / spacing;
        const double fy = (pc / ce.width + 0.5) * up - 0.5 - isochart::dot(geo[l + 1].t2(cs), w) / spacing;
        const int px = std::clamp(static_cast<int>(std::lround(fx)), 0, e.width - 1);
        const int py = std::clamp(static_cast<int>(std::lround(fy)), 0, e.height - 1);
        set_pixel(col, src, gi, py * e.width + px);
      }
    }
    const std::vector<Color>* coarse_col = has_coarse ? &res.group_colors[l + 1] : nullptr;
    const mcgim::GeometryImage* cgi = has_coarse ? &pyramid[l + 1].image : nullptr;

    auto gather = [&](int gi, float* q, std::vector<char>& valid) {
      const Tap* t = &lt.taps[static_cast<std::size_t>(gi) * per];
      for (int k = 0; k < per; ++k) {
        const bool fine = k < lt.fine;
        const mcgim::GeometryImage& gg = fine ? g : *cgi;
        const std::vector<Color>& cs = fine ? col : *coarse_col;
        const bool ok = t[k].valid();
        float v[3] = {0, 0, 0};
        for (int j = 0; ok && j < 4 && t[k].sample[j] >= 0; ++j) {
          const int grp = gg.group[t[k].sample[j]];
          for (int c = 0; c < 3; ++c) v[c] += t[k].weight[j] * cs[grp][c];
        }
        valid[k] = ok ? 1 : 0;
        for (int c = 0; c < 3; ++c) q[k * 3 + c] = v[c];
      }
    };
    // Candidates: the exemplar pixel that continues each neighbour's patch at this sample, and
    // the same shift applied to the neighbour's k-coherence set (Tong et al. 2002).
    auto coherent = [&](int gi, std::vector<int>& out) {
      out.clear();
      const std::array<int, 3>* sh = &shift[static_cast<std::size_t>(gi) * lt.fine];
      for (int k = 0; k < lt.fine; ++k) {
        if (sh[k][0] < 0) continue;
        const int from = src[sh[k][0]];
        if (from < 0) continue;
        auto add = [&](int px) {
          const int x = px % e.width - sh[k][1], y = px / e.width + sh[k][2];
          if (x >= 0 && y >= 0 && x < e.width && y < e.height) out.push_back(y * e.width + x);
        };
        add(from);
        const int cand = matcher.candidate_of[from];
        if (cand < 0) continue;
        for (int j = 0; j < matcher.similar_k; ++j) {
          const int px = matcher.similar[static_cast<std::size_t>(cand) * matcher.similar_k + j];
          if (px >= 0) add(px);
        }
      }
      std::sort(out.begin(), out.end());
      out.erase(std::unique(out.begin(), out.end()), out.end());
    };
    // One pass over every sample in a random order: batches of consecutive samples are matched
    // in parallel, each seeing the results of the batches before it, so the result does not
    // depend on the thread count and is close to a sequential (Gauss–Seidel) pass.
    const int batch = std::max(1, o.first_pass_batch);
    auto pass = [&](std::uint64_t salt, std::vector<double>* errors) {
      std::vector<int> order(groups);
      std::iota(order.begin(), order.end(), 0);
      isochart::Rng rng(isochart::mix_seed(o.seed, salt));
      for (int i = groups - 1; i > 0; --i) std::swap(order[i], order[rng.below(static_cast<std::uint64_t>(i) + 1)]);
      std::vector<Match> picked(batch);
      for (int start = 0; start < groups; start += batch) {
        const int count = std::min(batch, groups - start);
        tbb::parallel_for(tbb::blocked_range<int>(0, count, 8), [&](const tbb::blocked_range<int>& range) {
          std::vector<float> q(matcher.dim);
          std::vector<char> valid(per);
          std::vector<int> coh;
          for (int i = range.begin(); i < range.end(); ++i) {
            const int gi = order[start + i];
            picked[i] = Match{};
            if (reps[l][gi] < 0) continue;
            gather(gi, q.data(), valid);
            if (std::none_of(valid.begin(), valid.end(), [](char c) { return c != 0; })) continue;
            coherent(gi, coh);
            picked[i] = best_match(matcher, matcher.full, q.data(), valid, o.candidates, o.coherence, coh);
          }
        });
        for (int i = 0; i < count; ++i) {
          const int gi = order[start + i];
          if (picked[i].pixel < 0) continue;
          if (errors) (*errors)[gi] = picked[i].error;
          else set_pixel(col, src, gi, picked[i].pixel);
        }
      }
    };
    const int passes = has_coarse ? o.full_passes : o.coarsest_passes;
    for (int p = 0; p < passes; ++p) {
      pass(1000u + 64u * static_cast<std::uint64_t>(l) + static_cast<std::uint64_t>(p), nullptr);
      isochart::report(progress, isochart::Stage::Synthesis,
                       0.05 + 0.9 * ((nl - 1 - l) + (p + 1.0) / (passes + 1.0)) / nl);
    }
    if (l == 0) {
      // Quality: the final neighbourhoods against their best matches (colours unchanged).
      std::vector<double> errors(groups, 0.0);
      pass(999u, &errors);
      double sum = 0;
      long long count = 0;
      for (int gi = 0; gi < groups; ++gi)
        if (reps[l][gi] >= 0) sum += errors[gi], ++count;
      const double mean = count ? sum / count : 0;
      res.match_error = matcher.variance > 1e-12 ? mean / matcher.variance : mean;
    }
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - tl).count();
    isochart::report(progress, isochart::Stage::Synthesis, 0.05 + 0.9 * (nl - l) / double(nl));
  }

  res.exemplar_pixels = sources[0];
  {
    // The exemplar's continuation around each finest sample, for transfer_to_atlas: image
    // steps to the chart's neighbours as surface offsets, in the sample's field frame (the
    // convention of the copy and of the coherent candidates: +t1 → +x, +t2 → −y).
    const mcgim::GeometryImage& g = pyramid[0].image;
    const double spacing = ex[0].actual_factor / res.scale;
    res.exemplar_jacobians.assign(static_cast<std::size_t>(g.width) * g.height, {0.f, 0.f, 0.f, 0.f});
    tbb::parallel_for(0, g.height, [&](int y) {
      for (int x = 0; x < g.width; ++x) {
        const int s = g.index(x, y);
        if (!g.defined(s)) continue;
        auto step = [&](int dx, int dy, Vec3d& w) {
          int found = 0;
          w = Vec3d{0, 0, 0};
          for (int sign : {1, -1}) {
            const int qx = x + sign * dx, qy = y + sign * dy;
            if (qx < 0 || qy < 0 || qx >= g.width || qy >= g.height) continue;
            const int t = g.index(qx, qy);
            if (!g.defined(t) || g.chart[t] != g.chart[s]) continue;
            w += (g.positions[t] - g.positions[s]) * static_cast<double>(sign);
            ++found;
          }
          if (found > 0) w /= static_cast<double>(found);
          return found > 0;
        };
        Vec3d wx, wy;
        if (!step(1, 0, wx) || !step(0, 1, wy)) continue;
        const Vec3d t1 = geo[0].t1(s), t2 = geo[0].t2(s);
        res.exemplar_jacobians[s] = {static_cast<float>(isochart::dot(t1, wx) / spacing),
                                     static_cast<float>(isochart::dot(t1, wy) / spacing),
                                     static_cast<float>(-isochart::dot(t2, wx) / spacing),
                                     static_cast<float>(-isochart::dot(t2, wy) / spacing)};
      }
    });
  }
  // Seam error and texel-scale spread on the finest level.
  {
    const mcgim::GeometryImage& g = pyramid[0].image;
    const std::vector<Color>& col = res.group_colors[0];
    const double d = 2 * ex[0].actual_factor / res.scale;
    std::vector<std::array<double, 4>> acc(reps[0].size(), {0, 0, 0, 0});
    tbb::parallel_for(0, static_cast<int>(reps[0].size()), [&](int gi) {
      const int s = reps[0][gi];
      if (s < 0) return;
      const double dirs[4][2] = {{d, 0}, {-d, 0}, {0, d}, {0, -d}};
      for (const auto& dd : dirs) {
        const Tap t = geo[0].locate(s, dd[0], dd[1]);
        if (!t.valid()) continue;
        double v[3] = {0, 0, 0};
        for (int j = 0; j < 4 && t.sample[j] >= 0; ++j)
          for (int c = 0; c < 3; ++c) v[c] += t.weight[j] * col[g.group[t.sample[j]]][c];
        const double diff = (std::fabs(v[0] - col[gi][0]) + std::fabs(v[1] - col[gi][1]) + std::fabs(v[2] - col[gi][2])) / 3;
        if (t.crossed) acc[gi][0] += diff, acc[gi][1] += 1;
        else acc[gi][2] += diff, acc[gi][3] += 1;
      }
    });
    double seam = 0, seam_n = 0, inner = 0, inner_n = 0;
    for (const auto& a : acc) seam += a[0], seam_n += a[1], inner += a[2], inner_n += a[3];
    res.seam_pairs = static_cast<long long>(seam_n);
    const double ms = seam_n > 0 ? seam / seam_n : 0, mi = inner_n > 0 ? inner / inner_n : 0;
    // Differences below float rounding of colours count as none.
    // No tap crossed a seam: there is no seam error to measure (NaN, null in the JSON), not a
    // perfect one.
    res.seam_error = seam_n == 0 ? std::numeric_limits<double>::quiet_NaN()
                     : mi > 1e-6 ? ms / mi
                                 : (ms > 1e-6 ? std::numeric_limits<double>::infinity() : 0.0);
    double s1 = 0, s2 = 0;
    long long cnt = 0;
    for (int s = 0; s < g.width * g.height; ++s) {
      if (!g.defined(s) || geo[0].texel_size(s) <= 0) continue;
      const double lg = std::log(geo[0].texel_size(s));
      s1 += lg;
      s2 += lg * lg;
      ++cnt;
    }
    res.texel_scale_spread = cnt ? std::sqrt(std::max(0.0, s2 / cnt - (s1 / cnt) * (s1 / cnt))) : 0;

    // The texture image, rows flipped (sample row 0 is the image's bottom).
    res.texture = Image(g.width, g.height, 3);
    std::vector<char> filled(static_cast<std::size_t>(g.width) * g.height, 0);
    for (int y = 0; y < g.height; ++y)
      for (int x = 0; x < g.width; ++x) {
        const int s = g.index(x, y);
        if (!g.defined(s)) continue;
        const int row = g.height - 1 - y;
        for (int c = 0; c < 3; ++c) res.texture.at(x, row, c) = col[g.group[s]][c];
        filled[static_cast<std::size_t>(row) * g.width + x] = 1;
      }
    isochart::fill_from_nearest(res.texture, filled);
  }
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

Image transfer_to_atlas(const isochart::Mesh& atlas, const mcgim::Level& level, const Image& texture, int size,
                        const SynthResult* synthesis, const Image* exemplar) {
  if (size < 2 || size > 16384) throw isochart::InputError("", "atlas texture size must be in 2..16384");
  if (!atlas.has_uvs()) throw isochart::InputError("", "the atlas has no texture coordinates");
  const mcgim::GeometryImage& g = level.image;
  const bool magnify = synthesis && exemplar;
  if (magnify) {
    const auto ns = static_cast<std::size_t>(g.width) * g.height;
    if (synthesis->exemplar_jacobians.size() != ns || synthesis->levels.empty() ||
        synthesis->exemplar_pixels.size() != static_cast<std::size_t>(g.num_groups) ||
        synthesis->levels[0].exemplar_width < 1 || exemplar->channels != 3 || exemplar->width < 1)
      throw isochart::InputError("", "transfer: the synthesis result does not belong to this level");
  }
  const int nf = atlas.num_faces();
  // Per image chart, the affine map atlas uv → image xy, least squares over its samples.
  std::vector<Eigen::Matrix3d> ata(g.num_charts, Eigen::Matrix3d::Zero());
  std::vector<Eigen::Matrix<double, 3, 2>> atb(g.num_charts, Eigen::Matrix<double, 3, 2>::Zero());
  std::vector<int> face_chart(nf, -1);
  auto face_uv = [&](int f, const Vec3d& b) {
    const auto& fu = atlas.face_uvs[f];
    return atlas.uvs[fu[0]] * b.x + atlas.uvs[fu[1]] * b.y + atlas.uvs[fu[2]] * b.z;
  };
  for (int s = 0; s < g.width * g.height; ++s) {
    if (!g.defined(s) || g.face[s] < 0 || g.face[s] >= nf) continue;
    const Vec2d uv = face_uv(g.face[s], g.barycentric[s]);
    const Eigen::Vector3d a(uv.x, uv.y, 1);
    const int c = g.chart[s];
    ata[c] += a * a.transpose();
    atb[c].col(0) += a * (s % g.width + 0.5);
    atb[c].col(1) += a * (s / g.width + 0.5);
    face_chart[g.face[s]] = c;
  }
  std::vector<Eigen::Matrix<double, 3, 2>> affine(g.num_charts);
  std::vector<char> fitted(g.num_charts, 0);
  for (int c = 0; c < g.num_charts; ++c) {
    if (ata[c](2, 2) < 3) continue;
    Eigen::FullPivLU<Eigen::Matrix3d> lu(ata[c]);
    if (lu.rank() < 3) continue;
    affine[c] = lu.solve(atb[c]);
    fitted[c] = 1;
  }
  // Faces too small to hold a sample take the chart of a uv-continuous neighbour.
  {
    const isochart::Topology topo(atlas);
    std::deque<int> queue;
    for (int f = 0; f < nf; ++f)
      if (face_chart[f] >= 0) queue.push_back(f);
    auto uv_of = [&](int f, int v) {
      for (int k = 0; k < 3; ++k)
        if (atlas.faces[f][k] == v) return atlas.face_uvs[f][k];
      return -1;
    };
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop_front();
      for (int k = 0; k < 3; ++k) {
        const int h = topo.opposite_face(f, k);
        if (h < 0 || face_chart[h] >= 0) continue;
        if (!atlas.face_groups.empty() && atlas.face_groups[h] != atlas.face_groups[f]) continue;
        const int v0 = atlas.faces[f][k], v1 = atlas.faces[f][(k + 1) % 3];
        if (uv_of(h, v0) != atlas.face_uvs[f][k] || uv_of(h, v1) != atlas.face_uvs[f][(k + 1) % 3]) continue;
        face_chart[h] = face_chart[f];
        queue.push_back(h);
      }
    }
  }
  Image out(size, size, 3);
  std::vector<char> filled(static_cast<std::size_t>(size) * size, 0);
  auto tex = [&](int s, int c) { return texture.at(s % g.width, g.height - 1 - s / g.width, c); };

  // Exemplar lookups: the original exemplar prefiltered to about one pixel per atlas texel
  // (the median over charts of finest-level exemplar pixels per atlas texel), so that the
  // atlas gets the detail its resolution holds and no aliasing.
  ExemplarLevel look;
  double level_to_look = 1;  // finest-exemplar-level pixels → lookup pixels
  int ex_w = 1;
  if (magnify) {
    std::vector<double> per_texel;
    for (int c = 0; c < g.num_charts; ++c)
      if (fitted[c]) per_texel.push_back(std::sqrt(std::fabs(affine[c].topLeftCorner<2, 2>().determinant())) / size);
    std::sort(per_texel.begin(), per_texel.end());
    const double samples_per_texel = per_texel.empty() ? 1.0 : per_texel[per_texel.size() / 2];
    const double f0 = synthesis->levels[0].exemplar_factor > 0 ? synthesis->levels[0].exemplar_factor : 1.0;
    // Jacobians map sample steps to finest-level pixels, which are f0 original pixels each.
    double jac = 0;
    long long nj = 0;
    for (const auto& j : synthesis->exemplar_jacobians)
      if (j[0] != 0 || j[1] != 0 || j[2] != 0 || j[3] != 0) jac += std::sqrt(std::fabs(double(j[0]) * j[3] - double(j[1]) * j[2])), ++nj;
    const double level_px_per_sample = nj > 0 ? jac / nj : 1.0;
    look = resample_exemplar(*exemplar, std::max(1.0, f0 * level_px_per_sample * samples_per_texel));
    level_to_look = f0 / look.actual_factor;
    ex_w = synthesis->levels[0].exemplar_width;
  }
  auto mirror = [](int i, int n) {
    const int period = 2 * n;
    i %= period;
    if (i < 0) i += period;
    return i < n ? i : period - 1 - i;
  };
  // Bilinear exemplar colour at lookup-image position (u, v), pixel centres at +0.5.
  auto read = [&](double u, double v, double* rgb) {
    const double fu = u - 0.5, fv = v - 0.5;
    const double iu = std::floor(fu), iv = std::floor(fv);
    const double au = fu - iu, av = fv - iv;
    const int x0 = static_cast<int>(iu), y0 = static_cast<int>(iv);
    const int xs[2] = {mirror(x0, look.image.width), mirror(x0 + 1, look.image.width)};
    const int ys[2] = {mirror(y0, look.image.height), mirror(y0 + 1, look.image.height)};
    for (int c = 0; c < 3; ++c)
      rgb[c] = (1 - av) * ((1 - au) * look.image.at(xs[0], ys[0], c) + au * look.image.at(xs[1], ys[0], c)) +
               av * ((1 - au) * look.image.at(xs[0], ys[1], c) + au * look.image.at(xs[1], ys[1], c));
  };
  // The exemplar position of sample s continued to image position (px, py), in finest-level
  // exemplar pixels; false when the sample has none (or a degenerate frame sends it off to
  // where the lookup's integer pixel indices would overflow).
  auto continued = [&](int s, double px, double py, double& ex, double& ey) {
    const int src = magnify ? synthesis->exemplar_pixels[g.group[s]] : -1;
    if (src < 0) return false;
    const auto& j = synthesis->exemplar_jacobians[s];
    const double dx = px - (s % g.width + 0.5), dy = py - (s / g.width + 0.5);
    ex = src % ex_w + 0.5 + j[0] * dx + j[1] * dy;
    ey = src / ex_w + 0.5 + j[2] * dx + j[3] * dy;
    return std::fabs(ex) < 1e8 && std::fabs(ey) < 1e8;
  };
  // Colour at image position (px, py) from up to four samples with weights: samples whose
  // continued positions agree (within a pixel) with the heaviest one's continue one patch and
  // are read once at their weighted mean position, which keeps the patch sharp; the others are
  // read on their own and blended by weight.
  auto blend = [&](const int* smp, const double* wgt, int n, double px, double py, double* v) {
    double qx[4], qy[4];
    bool has[4];
    int lead = -1;
    for (int k = 0; k < n; ++k) {
      has[k] = continued(smp[k], px, py, qx[k], qy[k]);
      if (has[k] && (lead < 0 || wgt[k] > wgt[lead])) lead = k;
    }
    double total = 0, mx = 0, my = 0, mw = 0;
    v[0] = v[1] = v[2] = 0;
    for (int k = 0; k < n; ++k) {
      double rgb[3];
      if (has[k] && std::fabs(qx[k] - qx[lead]) <= 1 && std::fabs(qy[k] - qy[lead]) <= 1) {
        mx += wgt[k] * qx[k], my += wgt[k] * qy[k], mw += wgt[k];
        total += wgt[k];
        continue;
      }
      if (has[k]) {
        read(qx[k] * level_to_look, qy[k] * level_to_look, rgb);
      } else {
        for (int c = 0; c < 3; ++c) rgb[c] = tex(smp[k], c);
      }
      for (int c = 0; c < 3; ++c) v[c] += wgt[k] * rgb[c];
      total += wgt[k];
    }
    if (mw > 0) {
      double rgb[3];
      read(mx / mw * level_to_look, my / mw * level_to_look, rgb);
      for (int c = 0; c < 3; ++c) v[c] += mw * rgb[c];
    }
    return total;
  };
  // Colour of chart c at atlas texel position p (texel units), from the chart's samples.
  auto shade = [&](int c, const Vec2d& p, double* v) {
    const Eigen::Vector3d a(p.x / size, p.y / size, 1);
    const Eigen::Vector2d xy = affine[c].transpose() * a;
    if (!(std::fabs(xy.x()) < 1e6 && std::fabs(xy.y()) < 1e6)) return 0.0;
    // Bilinear over the chart's samples, renormalized where the footprint leaves it.
    const double fx = xy.x() - 0.5, fy = xy.y() - 0.5;
    const int ix = static_cast<int>(std::floor(fx)), iy = static_cast<int>(std::floor(fy));
    const double ax = fx - ix, ay = fy - iy;
    double wsum = 0;
    int smp[4], n = 0;
    double wts[4];
    for (int k = 0; k < 4; ++k) {
      const int sx = ix + (k & 1), sy = iy + (k >> 1);
      if (sx < 0 || sy < 0 || sx >= g.width || sy >= g.height || g.chart[g.index(sx, sy)] != c) continue;
      const double wgt = ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay);
      if (wgt <= 0) continue;
      smp[n] = g.index(sx, sy), wts[n] = wgt, ++n;
    }
    if (n > 0) wsum = blend(smp, wts, n, xy.x(), xy.y(), v);
    if (wsum <= 0) {
      // Outside the chart's samples (its boundary): the nearest sample of the chart.
      const int cx = static_cast<int>(std::lround(fx)), cy = static_cast<int>(std::lround(fy));
      double best = std::numeric_limits<double>::infinity();
      for (int r = 1; r <= 4 && !std::isfinite(best); ++r)
        for (int sy = cy - r; sy <= cy + r; ++sy)
          for (int sx = cx - r; sx <= cx + r; ++sx) {
            if (sx < 0 || sy < 0 || sx >= g.width || sy >= g.height || g.chart[g.index(sx, sy)] != c)
              continue;
            const double d = (sx - fx) * (sx - fx) + (sy - fy) * (sy - fy);
            if (d < best) {
              best = d;
              const int one = g.index(sx, sy);
              const double w1 = 1;
              wsum = blend(&one, &w1, 1, xy.x(), xy.y(), v);
            }
          }
    }
    return wsum;
  };
  // A chart whose samples do not span an affine map (fewer than three, or all on one line: a
  // needle) is coloured by its sample nearest in the atlas's uv.
  auto shade_unfitted = [&](int c, const Vec2d& p, double* v) {
    const Vec2d uv{p.x / size, p.y / size};
    double best = std::numeric_limits<double>::infinity();
    int nearest = -1;
    for (int smp = 0; smp < g.width * g.height; ++smp) {
      if (g.chart[smp] != c || g.face[smp] < 0 || g.face[smp] >= nf) continue;
      const Vec2d d = face_uv(g.face[smp], g.barycentric[smp]) - uv;
      if (d.x * d.x + d.y * d.y < best) best = d.x * d.x + d.y * d.y, nearest = smp;
    }
    if (nearest < 0) return 0.0;
    const double w1 = 1;
    return blend(&nearest, &w1, 1, nearest % g.width + 0.5, nearest / g.width + 0.5, v);
  };
  auto put = [&](int x, int y, const double* v, double wsum) {
    const int row = size - 1 - y;
    for (int ch = 0; ch < 3; ++ch) out.at(x, row, ch) = static_cast<float>(v[ch] / wsum);
    filled[static_cast<std::size_t>(row) * size + x] = 1;
  };
  for (int f = 0; f < nf; ++f) {
    const int c = face_chart[f];
    if (c < 0) continue;
    const auto& fu = atlas.face_uvs[f];
    const Vec2d p0 = atlas.uvs[fu[0]] * size, p1 = atlas.uvs[fu[1]] * size, p2 = atlas.uvs[fu[2]] * size;
    const double area = isochart::signed_area(p0, p1, p2);
    bool wrote = false;
    if (fitted[c] && std::fabs(area) >= 1e-14) {
      const int x0 = std::max(0, static_cast<int>(std::floor(std::min({p0.x, p1.x, p2.x}))));
      const int x1 = std::min(size - 1, static_cast<int>(std::ceil(std::max({p0.x, p1.x, p2.x}))));
      const int y0 = std::max(0, static_cast<int>(std::floor(std::min({p0.y, p1.y, p2.y}))));
      const int y1 = std::min(size - 1, static_cast<int>(std::ceil(std::max({p0.y, p1.y, p2.y}))));
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const Vec2d p{x + 0.5, y + 0.5};
          const double b0 = isochart::signed_area(p, p1, p2) / area,
                       b1 = isochart::signed_area(p0, p, p2) / area;
          const double b2 = 1 - b0 - b1;
          const double eps = -1e-6;
          if (b0 < eps || b1 < eps || b2 < eps) continue;
          double v[3] = {0, 0, 0};
          const double wsum = shade(c, p, v);
          if (wsum <= 0) continue;
          put(x, y, v, wsum);
          wrote = true;
        }
      }
    }
    if (wrote) continue;
    // A face covering no texel centre (a sliver, or smaller than a texel) still colours the
    // texel under its centroid, unless another face did: a chart made only of such faces came
    // out black, with nothing for the gutter fill to spread.
    const Vec2d pc = (p0 + p1 + p2) * (1.0 / 3);
    if (!(pc.x >= 0 && pc.y >= 0 && pc.x < size && pc.y < size)) continue;
    const int x = static_cast<int>(pc.x), y = static_cast<int>(pc.y);
    if (filled[static_cast<std::size_t>(size - 1 - y) * size + x]) continue;
    double v[3] = {0, 0, 0};
    const double wsum = fitted[c] ? shade(c, pc, v) : shade_unfitted(c, pc, v);
    if (wsum > 0) put(x, y, v, wsum);
  }
  isochart::fill_from_nearest(out, filled);
  return out;
}

}  // namespace synth
