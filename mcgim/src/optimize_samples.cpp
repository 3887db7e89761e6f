#include "optimize_samples.h"

#include <tbb/parallel_for.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/LU>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "closest_point.h"
#include "isochart/error.h"

namespace mcgim::detail {

namespace {

// One point of the original surface, located on the remesh.
struct FitPoint {
  int face;        // remesh face
  Vec3d weights;   // barycentric in that face
  Vec3d target;    // original surface point
  double area;     // surface area it stands for
  Vec3d normal{};  // the original surface's unit normal there (zero: unknown)
};

// Barycentric coordinates of q in the triangle (a, b, c); false when degenerate.
bool barycentric_2d(const Vec2d& q, const Vec2d& a, const Vec2d& b, const Vec2d& c, Vec3d& w) {
  const double d = cross(b - a, c - a);
  if (d == 0) return false;
  w.y = cross(q - a, c - a) / d;
  w.z = cross(b - a, q - a) / d;
  w.x = 1 - w.y - w.z;
  return true;
}

// Barycentric (u, v) of the centroids of the n×n subdivision of a triangle, n chosen for about
// `points` of them (at least one, n ≤ 64); `fn(u, v, n²)`, n² being the number of sub-triangles.
template <class Fn>
void for_each_subdivision_centroid(double points, Fn&& fn) {
  const int n = std::clamp(static_cast<int>(std::ceil(std::sqrt(points))), 1, 64);
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j)
      // Upright sub-triangle (i, j) and, when it exists, the inverted one next to it.
      for (int up = 0; up < 2; ++up) {
        if (up == 1 && i + j + 1 >= n) continue;
        const double u = up == 0 ? (i + 1.0 / 3) / n : (i + 2.0 / 3) / n;
        const double v = up == 0 ? (j + 1.0 / 3) / n : (j + 2.0 / 3) / n;
        fn(u, v, n * n);
      }
}

std::vector<FitPoint> fit_points(const AtlasCharts& a, const Placement& pl, const std::vector<Vec2d>& param,
                                 const GeometryImage& im, const Remesh& r) {
  const Mesh& mesh = *a.mesh;
  const int W = im.width, H = im.height;
  // Faces of each block (lower-left sample), at most two.
  std::vector<std::array<int, 2>> block_faces(static_cast<std::size_t>(W) * H, {-1, -1});
  for (int f = 0; f < static_cast<int>(r.face_samples.size()); ++f) {
    const auto& s = r.face_samples[f];
    int x = W, y = H;
    for (int k = 0; k < 3; ++k) {
      x = std::min(x, s[k] % W);
      y = std::min(y, s[k] / W);
    }
    auto& slot = block_faces[static_cast<std::size_t>(y) * W + x];
    (slot[0] < 0 ? slot[0] : slot[1]) = f;
  }
  std::vector<FitPoint> pts;
  // The remesh triangle holding q, in texture space: its corners at the samples' parameter
  // locations (zippered samples sit on the chart boundary, not at their centres, so the
  // triangle may reach into a neighbouring block).
  auto locate = [&](int chart, const Vec2d& q, const Vec3d& target, double area) {
    const int bx0 = static_cast<int>(std::floor(q.x - 0.5)), by0 = static_cast<int>(std::floor(q.y - 0.5));
    static constexpr int order[9][2] = {{0, 0}, {-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
    for (const auto& o : order) {
      const int bx = bx0 + o[0], by = by0 + o[1];
      if (bx < 0 || by < 0 || bx + 1 >= W || by + 1 >= H) continue;
      for (int f : block_faces[static_cast<std::size_t>(by) * W + bx]) {
        if (f < 0 || r.mesh.face_groups[f] != chart) continue;
        const auto& s = r.face_samples[f];
        Vec3d w;
        if (!barycentric_2d(q, param[s[0]], param[s[1]], param[s[2]], w)) continue;
        const double eps = -1e-9;
        if (w.x < eps || w.y < eps || w.z < eps) continue;
        pts.push_back({f, w, target, area});
        return;
      }
    }
  };
  for (std::size_t c = 0; c < a.charts.size(); ++c) {
    const Chart& ch = a.charts[c];
    for (std::size_t lf = 0; lf < ch.local_faces.size(); ++lf) {
      const Face& f = ch.local_faces[lf];
      const Face& pf = mesh.faces[ch.faces[lf]];
      const Vec2d t0 = pl.texel[c][f[0]], t1 = pl.texel[c][f[1]], t2 = pl.texel[c][f[2]];
      const Vec3d p0 = mesh.positions[pf[0]], p1 = mesh.positions[pf[1]], p2 = mesh.positions[pf[2]];
      const double area3 = isochart::triangle_area(p0, p1, p2);
      const double area_t = std::abs(isochart::signed_area(t0, t1, t2));
      // About two points per texel.
      for_each_subdivision_centroid(2.0 * area_t, [&](double u, double v, int cells) {
        const double b0 = 1 - u - v;
        locate(static_cast<int>(c), t0 * b0 + t1 * u + t2 * v, p0 * b0 + p1 * u + p2 * v, area3 / cells);
      });
    }
  }
  return pts;
}

// Points spread over the original faces (centroids of an n×n subdivision, about four per
// texel of surface), with the area each stands for. Four rather than two: when the original
// has about twice as many faces as the image has samples (the usual remeshing budget), two per
// texel means one point per face, its centroid, and the fit never sees the face corners, where
// a piecewise-flat surface bends (horse, feline and gargoyle at 47k samples, together with the
// pull 0.05 of LevelOptions::optimize_regularization: +0.12 to +0.16 dB, for about a third more
// optimization time).
void surface_points(const Mesh& mesh, double texel_area, std::vector<Vec3d>& pts, std::vector<double>& area,
                    std::vector<int>& face) {
  constexpr double points_per_texel = 4.0;
  // Faces smaller than a sixteenth of a texel (coarse levels) share their point: one centroid
  // per sixteenth of a texel of area, in face order (scanned meshes keep neighbours near each
  // other), each standing for the area it collected. One point per face costs as much at 32²
  // as at 256² for no better fit (at a quarter texel, the 128² and 64² levels lost 0.1-0.4 dB).
  // What is left pending after the last face (under a sixteenth of a texel) goes unsampled.
  constexpr double coarse_points_per_texel = 16.0;
  double pending = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3d p0 = mesh.positions[mesh.faces[f][0]], p1 = mesh.positions[mesh.faces[f][1]],
                p2 = mesh.positions[mesh.faces[f][2]];
    const double ar = isochart::triangle_area(p0, p1, p2);
    if (coarse_points_per_texel * ar < texel_area) {
      pending += ar;
      if (pending * coarse_points_per_texel < texel_area) continue;
      pts.push_back((p0 + p1 + p2) / 3.0);
      area.push_back(pending);
      face.push_back(f);
      pending = 0;
      continue;
    }
    for_each_subdivision_centroid(points_per_texel * ar / texel_area, [&](double u, double v, int cells) {
      pts.push_back(p0 * (1 - u - v) + p1 * u + p2 * v);
      area.push_back(ar / cells);
      face.push_back(f);
    });
  }
}

const SurfaceCache& original_surface(const AtlasCharts& a) {
  SurfaceCache& s = *a.surface;
  std::call_once(s.once, [&] {
    s.closest = std::make_unique<ClosestPoints>(*a.mesh);
    s.face_normals = isochart::face_normals(*a.mesh);
  });
  return s;
}

// Per sample, where it was taken on the original surface (face −1 if unknown): a close start
// for exact closest-point queries near the sample, however far the fit has moved it since.
// Fixed for a level (zippering and the fit move positions, not the sample's source).
std::vector<ClosestPoints::Hit> sample_sources(const ClosestPoints& original, const GeometryImage& im) {
  std::vector<ClosestPoints::Hit> out(im.group.size());
  if (im.face.empty()) return out;
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = original.point_at(im.face[i], im.barycentric[i]);
  return out;
}

// Of n candidate hits, the one nearest to q (face −1 if none is known).
ClosestPoints::Hit nearest(const ClosestPoints::Hit* h, int n, const Vec3d& q) {
  ClosestPoints::Hit best;
  double best2 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < n; ++k)
    if (h[k].face >= 0 && squared_norm(h[k].point - q) < best2) {
      best2 = squared_norm(h[k].point - q);
      best = h[k];
    }
  return best;
}

// Geometric correspondences (Hoppe et al. 1993's distance energy, both ways): each original
// point to its closest point on the remesh, and each remesh face centroid to its closest point
// on the original.
std::vector<FitPoint> closest_points(const ClosestPoints& original, const std::vector<Vec3d>& pts,
                                     const std::vector<double>& area, const std::vector<int>& pts_face,
                                     const std::vector<Vec3d>& original_normals,
                                     const std::vector<ClosestPoints::Hit>& source, const Remesh& r) {
  const ClosestPoints remesh(r.mesh);
  const std::size_t no = pts.size();
  const int nf = r.mesh.num_faces();
  std::vector<FitPoint> out(no + static_cast<std::size_t>(nf));
  if (remesh.empty()) return {};
  std::vector<int> hit_face(nf);
  tbb::parallel_for(0, nf, [&](int f) {
    const auto& F = r.mesh.faces[f];
    const Vec3d a = r.mesh.positions[F[0]], b = r.mesh.positions[F[1]], c = r.mesh.positions[F[2]];
    const Vec3d centroid = (a + b + c) / 3.0;
    const auto& fs = r.face_samples[f];
    const ClosestPoints::Hit s[3] = {source[fs[0]], source[fs[1]], source[fs[2]]};
    const ClosestPoints::Hit h = original.closest(centroid, nearest(s, 3, centroid));
    hit_face[f] = h.face;
    out[no + f] = {f, {1.0 / 3, 1.0 / 3, 1.0 / 3}, h.point, isochart::triangle_area(a, b, c),
                   original_normals[h.face]};
  });
  // Per original face, the first remesh face whose centroid lands on it: its centroid starts
  // the search for the original points of that face.
  std::vector<int> landed(original_normals.size(), -1);
  for (int f = nf - 1; f >= 0; --f) landed[hit_face[f]] = f;
  tbb::parallel_for(std::size_t(0), no, [&](std::size_t k) {
    ClosestPoints::Hit start;
    if (const int f = landed[pts_face[k]]; f >= 0) {
      const auto& F = r.mesh.faces[f];
      start = {f, (r.mesh.positions[F[0]] + r.mesh.positions[F[1]] + r.mesh.positions[F[2]]) / 3.0};
    }
    const ClosestPoints::Hit h = remesh.closest(pts[k], start);
    const auto& f = r.mesh.faces[h.face];
    out[k] = {h.face,
              barycentric_of(h.point, r.mesh.positions[f[0]], r.mesh.positions[f[1]], r.mesh.positions[f[2]]),
              pts[k], area[k], original_normals[pts_face[k]]};
  });
  return out;
}

// Per remesh vertex, the zippered position of its group: what the fit pulls towards.
std::vector<Vec3d> vertex_anchors(const std::vector<Vec3d>& group_anchor, const GeometryImage& im, const Remesh& r) {
  std::vector<Vec3d> anchor(r.mesh.num_vertices());
  for (std::size_t i = 0; i < im.group.size(); ++i)
    if (r.sample_vertex[i] >= 0) anchor[r.sample_vertex[i]] = group_anchor[im.group[i]];
  return anchor;
}

// No vertex ends further than `max_move` from its anchor.
void clamp_moves(const std::vector<Vec3d>& anchor, double max_move, std::vector<Vec3d>& pos) {
  for (std::size_t v = 0; v < pos.size(); ++v) {
    const Vec3d d = pos[v] - anchor[v];
    const double len = norm(d);
    pos[v] = anchor[v] + (len > max_move ? d * (max_move / len) : d);
  }
}

// The fitted vertex positions back into the image's samples, and the remesh rebuilt from it.
void write_back(const std::vector<Vec3d>& pos, GeometryImage& im, Remesh& r) {
  for (std::size_t i = 0; i < im.group.size(); ++i)
    if (r.sample_vertex[i] >= 0) im.positions[i] = pos[r.sample_vertex[i]];
  r = reconstruct(im, false);
}

// Least squares: Σ area·|Σ w_i x_i − target|² + λ Σ |x_v − anchor_v|², then each vertex kept
// within `max_move` of its anchor; writes the positions back to the image and rebuilds the
// remesh (the shorter diagonals may change, where the image has not fixed them).
// The solves below stop at a residual relative to their right-hand side, which grows with the
// distance from the origin: a mesh 1e9 units out was fitted to about a tenth of its size
// (eight: 60.96 dB at 64² against 69.34 at the origin). They run around this point, the
// anchors' centre rounded to a multiple of a power of two at least 64 box diagonals, which is
// the origin itself for any mesh lying within 32 diagonals of it (figures there unchanged).
Vec3d solve_origin(const std::vector<Vec3d>& anchor) {
  const isochart::BoundingBox box = isochart::bounding_box(anchor);
  const double diagonal = box.diagonal();
  if (!(diagonal > 0) || !std::isfinite(diagonal)) return {};
  const double grid = std::ldexp(1.0, std::ilogb(64 * diagonal) + 1);
  Vec3d o;
  for (int i = 0; i < 3; ++i) o[i] = grid * std::round((box.min[i] + box.max[i]) / 2 / grid);
  return o;
}

void solve(const std::vector<FitPoint>& pts, const std::vector<Vec3d>& group_anchor, double lambda,
           double max_move, GeometryImage& im, Remesh& r) {
  const int nv = r.mesh.num_vertices();
  const std::vector<Vec3d> anchor = vertex_anchors(group_anchor, im, r);
  const Vec3d o = solve_origin(anchor);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(pts.size() * 9 + nv);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nv, 3);
  for (const FitPoint& p : pts) {
    const auto& f = r.mesh.faces[p.face];
    const double w[3] = {p.weights.x, p.weights.y, p.weights.z};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) trip.emplace_back(f[i], f[j], p.area * w[i] * w[j]);
      for (int d = 0; d < 3; ++d) rhs(f[i], d) += p.area * w[i] * (p.target[d] - o[d]);
    }
  }
  for (int v = 0; v < nv; ++v) {
    trip.emplace_back(v, v, lambda);
    for (int d = 0; d < 3; ++d) rhs(v, d) += lambda * (anchor[v][d] - o[d]);
  }
  Eigen::SparseMatrix<double> A(nv, nv);
  A.setFromTriplets(trip.begin(), trip.end());
  // A mass matrix plus a diagonal: well conditioned, so diagonally preconditioned conjugate
  // gradients from the current positions converge in a few dozen iterations (a direct
  // factorization fills in badly on image-sized grids).
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> solver;
  solver.setTolerance(1e-8);
  solver.setMaxIterations(200);
  solver.compute(A);
  Eigen::MatrixXd x(nv, 3);
  for (int d = 0; d < 3; ++d) {
    Eigen::VectorXd guess(nv);
    for (int v = 0; v < nv; ++v) guess(v) = r.mesh.positions[v][d] - o[d];
    x.col(d) = solver.solveWithGuess(rhs.col(d), guess);
  }
  std::vector<Vec3d> pos(nv);
  for (int v = 0; v < nv; ++v) pos[v] = Vec3d{x(v, 0), x(v, 1), x(v, 2)} + o;
  clamp_moves(anchor, max_move, pos);
  write_back(pos, im, r);
}

// Point-to-plane least squares (the closest-point passes): Σ area·(n·(Σ w_i x_i − target))²
// + λ Σ |x_v − anchor_v|², n the original surface's unit normal at the target. The distance the
// PSNR measures lies along n; solve()'s point-to-point fit also holds each matched point to its
// target along the surface, which the fit pays for in normal accuracy (horse's signal atlas at
// 47k samples: 87.48 dB point-to-point with a pull of 0.05; point-to-plane with a pull of 0.01
// / 0.005 / 0.002: 89.09 / 89.65 / 90.41 dB before the turn-over guard below, a point-to-point
// share of 0.02 lowering each: 88.70 at 0.01, 88.95 at 0.005). Matrix-free conjugate
// gradients on the 3V unknowns with 3×3 block-Jacobi preconditioning (about a dozen
// iterations); products are gathered per vertex in a fixed order, so the result does not depend
// on the thread count.
void solve_plane(const std::vector<FitPoint>& pts, const std::vector<Vec3d>& group_anchor, double lambda,
                 double max_move, GeometryImage& im, Remesh& r) {
  const int nv = r.mesh.num_vertices();
  const std::vector<Vec3d> anchor = vertex_anchors(group_anchor, im, r);
  const Vec3d o = solve_origin(anchor);
  const std::size_t np = pts.size();
  // Compact copies of what the products read: the points' corners, weights, normals and areas,
  // and per vertex its (point, weight) incidences in point order.
  struct Row {
    int v[3];
    double w[3];
    Vec3d normal;
    double area;
  };
  struct Incidence {
    int point;
    double w;
  };
  std::vector<Row> rows(np);
  std::vector<int> off(nv + 1, 0);
  for (std::size_t i = 0; i < np; ++i) {
    const FitPoint& p = pts[i];
    const auto& f = r.mesh.faces[p.face];
    rows[i] = {{f[0], f[1], f[2]}, {p.weights.x, p.weights.y, p.weights.z}, p.normal, p.area};
    for (int k = 0; k < 3; ++k) ++off[f[k] + 1];
  }
  for (int v = 0; v < nv; ++v) off[v + 1] += off[v];
  std::vector<Incidence> inc(off[nv]);
  {
    std::vector<int> fill(off.begin(), off.end() - 1);
    for (std::size_t i = 0; i < np; ++i)
      for (int k = 0; k < 3; ++k) inc[fill[rows[i].v[k]]++] = {static_cast<int>(i), rows[i].w[k]};
  }
  // M_p v = area · n (n·v).
  auto apply_m = [](const Row& p, const Vec3d& v) { return p.normal * (dot(p.normal, v) * p.area); };
  // Block-Jacobi: inverse of Σ w² M_p + λ I per vertex.
  std::vector<Eigen::Matrix3d> inv(nv);
  tbb::parallel_for(0, nv, [&](int v) {
    Eigen::Matrix3d b = Eigen::Matrix3d::Identity() * lambda;
    for (int i = off[v]; i < off[v + 1]; ++i) {
      const Row& p = rows[inc[i].point];
      const double w = inc[i].w;
      const Eigen::Vector3d n(p.normal.x, p.normal.y, p.normal.z);
      b += (w * w * p.area) * (n * n.transpose());
    }
    inv[v] = b.inverse();
  });
  std::vector<Vec3d> mp(np);
  auto multiply = [&](const std::vector<Vec3d>& x, std::vector<Vec3d>& y) {
    tbb::parallel_for(std::size_t(0), np, [&](std::size_t i) {
      const Row& p = rows[i];
      mp[i] = apply_m(p, x[p.v[0]] * p.w[0] + x[p.v[1]] * p.w[1] + x[p.v[2]] * p.w[2]);
    });
    tbb::parallel_for(0, nv, [&](int v) {
      Vec3d s = x[v] * lambda;
      for (int i = off[v]; i < off[v + 1]; ++i) s += mp[inc[i].point] * inc[i].w;
      y[v] = s;
    });
  };
  std::vector<Vec3d> b(nv), x(nv), res(nv), z(nv), d(nv), q(nv);
  tbb::parallel_for(0, nv, [&](int v) {
    x[v] = r.mesh.positions[v] - o;
    Vec3d s = (anchor[v] - o) * lambda;
    for (int i = off[v]; i < off[v + 1]; ++i)
      s += apply_m(rows[inc[i].point], pts[inc[i].point].target - o) * inc[i].w;
    b[v] = s;
  });
  auto precondition = [&](const std::vector<Vec3d>& in, std::vector<Vec3d>& out) {
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d e = inv[v] * Eigen::Vector3d(in[v].x, in[v].y, in[v].z);
      out[v] = {e.x(), e.y(), e.z()};
    }
  };
  auto dotv = [&](const std::vector<Vec3d>& a, const std::vector<Vec3d>& c) {
    double s = 0;
    for (int v = 0; v < nv; ++v) s += dot(a[v], c[v]);
    return s;
  };
  multiply(x, q);
  for (int v = 0; v < nv; ++v) res[v] = b[v] - q[v];
  precondition(res, z);
  d = z;
  double rz = dotv(res, z);
  const double bnorm = std::sqrt(std::max(dotv(b, b), 1e-300));
  for (int it = 0; it < 200 && std::sqrt(dotv(res, res)) > 1e-8 * bnorm; ++it) {
    multiply(d, q);
    const double dq = dotv(d, q);
    if (!(dq > 0)) break;
    const double alpha = rz / dq;
    for (int v = 0; v < nv; ++v) {
      x[v] += d[v] * alpha;
      res[v] -= q[v] * alpha;
    }
    precondition(res, z);
    const double rz2 = dotv(res, z);
    const double beta = rz2 / rz;
    rz = rz2;
    for (int v = 0; v < nv; ++v) d[v] = z[v] + d[v] * beta;
  }
  std::vector<Vec3d> pos = std::move(x);
  for (Vec3d& p : pos) p += o;
  clamp_moves(anchor, max_move, pos);
  // Nothing but the pull resists sliding along the surface, so a triangle may turn over (horse
  // at 47k samples: edges with a dihedral angle over 90° 157 → 214 at a pull of 0.005). Such a
  // triangle's corners stay where they were, until no triangle turns (at worst every vertex
  // stays: the layout before). With it, 183 such edges and 89.60 dB.
  const auto& old = r.mesh.positions;
  for (bool reverted = true; reverted;) {
    reverted = false;
    for (const Face& f : r.mesh.faces) {
      const Vec3d n0 = cross(old[f[1]] - old[f[0]], old[f[2]] - old[f[0]]);
      const Vec3d n1 = cross(pos[f[1]] - pos[f[0]], pos[f[2]] - pos[f[0]]);
      if (dot(n0, n1) >= 0) continue;
      for (int k = 0; k < 3; ++k)
        if (!(pos[f[k]] == old[f[k]])) {
          pos[f[k]] = old[f[k]];
          reverted = true;
        }
    }
  }
  write_back(pos, im, r);
}

// Per full block, the diagonal whose two triangles lie closer to the original surface (squared
// distances of the diagonal's midpoint and the two triangles' centroids). The shorter diagonal
// bridges concave creases and saddles that the other one follows (the horse's tail joint). A
// block changes its diagonal only when the new one is not already an edge of the remesh `r`
// (built with the current diagonals) nor the new diagonal of another block: zippered samples
// are shared, so a seam block's diagonal can be an edge of the neighbouring chart, and using
// it twice would make it non-manifold. With `interior_only`, blocks touching a zippered sample
// keep their diagonal.
void choose_diagonals(const ClosestPoints& original, const std::vector<ClosestPoints::Hit>& source,
                      const Remesh& r, bool interior_only, GeometryImage& im) {
  const int W = im.width, H = im.height;
  std::vector<int> group_size(im.num_groups, 0);
  for (int g : im.group)
    if (g >= 0) ++group_size[g];
  const auto edge_key = [](int a, int b) {
    if (a > b) std::swap(a, b);
    return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
  };
  std::vector<std::uint64_t> edges;
  edges.reserve(r.mesh.faces.size() * 3);
  for (const Face& f : r.mesh.faces)
    for (int k = 0; k < 3; ++k) edges.push_back(edge_key(f[k], f[(k + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  const auto is_edge = [&](std::uint64_t e) { return std::binary_search(edges.begin(), edges.end(), e); };

  GeometryImage::Diagonals next(static_cast<std::size_t>(W) * H, 0);
  // Per row, the blocks that change and their new edge; merged in row order.
  std::vector<std::vector<std::pair<std::uint64_t, int>>> changed(std::max(H - 1, 0));
  tbb::parallel_for(0, H - 1, [&](int y) {
    for (int x = 0; x + 1 < W; ++x) {
      const int c[4] = {im.index(x, y), im.index(x + 1, y), im.index(x + 1, y + 1), im.index(x, y + 1)};
      if (!im.defined(c[0]) || !im.defined(c[1]) || !im.defined(c[2]) || !im.defined(c[3])) continue;
      const char cur = im.splits_13(c[0]);  // the diagonal the block has now
      next[c[0]] = cur;
      const int g[4] = {im.group[c[0]], im.group[c[1]], im.group[c[2]], im.group[c[3]]};
      if (g[0] == g[2] || g[1] == g[3]) continue;  // welded: reconstruct takes that diagonal
      if (interior_only && (group_size[g[0]] > 1 || group_size[g[1]] > 1 || group_size[g[2]] > 1 || group_size[g[3]] > 1))
        continue;
      const Vec3d p[4] = {im.positions[c[0]], im.positions[c[1]], im.positions[c[2]], im.positions[c[3]]};
      const ClosestPoints::Hit s[4] = {source[c[0]], source[c[1]], source[c[2]], source[c[3]]};
      auto d2 = [&](const Vec3d& q) { return squared_norm(original.closest(q, nearest(s, 4, q)).point - q); };
      const double e02 = d2((p[0] + p[2]) * 0.5) + d2((p[0] + p[1] + p[2]) / 3.0) + d2((p[0] + p[2] + p[3]) / 3.0);
      const double e13 = d2((p[1] + p[3]) * 0.5) + d2((p[0] + p[1] + p[3]) / 3.0) + d2((p[1] + p[2] + p[3]) / 3.0);
      const char want = e13 < e02 ? 1 : 0;
      if (want == cur) continue;
      // Nor may the block fold along its new diagonal: both triangles must face the way the
      // block does (its vector area, the same for either diagonal). A fold lies close to a
      // surface too, and the point-to-plane fit can leave a block bent enough for one.
      const Vec3d block_normal = cross(p[2] - p[0], p[3] - p[1]);
      const bool folds = want ? dot(cross(p[1] - p[0], p[3] - p[0]), block_normal) <= 0 ||
                                    dot(cross(p[2] - p[1], p[3] - p[1]), block_normal) <= 0
                              : dot(cross(p[1] - p[0], p[2] - p[0]), block_normal) <= 0 ||
                                    dot(cross(p[2] - p[0], p[3] - p[0]), block_normal) <= 0;
      if (folds) continue;
      const int a = r.sample_vertex[want ? c[1] : c[0]], b = r.sample_vertex[want ? c[3] : c[2]];
      if (a < 0 || b < 0) continue;
      const std::uint64_t e = edge_key(a, b);
      if (is_edge(e)) continue;
      next[c[0]] = want;
      changed[y].emplace_back(e, c[0]);
    }
  });
  std::vector<std::pair<std::uint64_t, int>> all;
  for (const auto& row : changed) all.insert(all.end(), row.begin(), row.end());
  std::sort(all.begin(), all.end());
  for (std::size_t i = 0; i < all.size();) {
    std::size_t j = i + 1;
    while (j < all.size() && all[j].first == all[i].first) ++j;
    if (j - i > 1)
      for (std::size_t k = i; k < j; ++k) next[all[k].second] ^= 1;  // two blocks want one new edge: neither
    i = j;
  }
  im.block_diagonal = std::move(next);
}

bool same_topology(const TopologyCheck& a, const TopologyCheck& b) {
  return a.boundary_edges == b.boundary_edges && a.nonmanifold_edges == b.nonmanifold_edges &&
         a.nonmanifold_vertices == b.nonmanifold_vertices && a.boundary_loops == b.boundary_loops &&
         a.components == b.components && a.euler_characteristic == b.euler_characteristic;
}

}  // namespace

SurfaceCache::SurfaceCache() = default;
SurfaceCache::~SurfaceCache() = default;

void optimize_samples(const AtlasCharts& a, const Placement& pl, const std::vector<Vec2d>& param,
                      const LevelOptions& o, GeometryImage& im, Remesh& r, const isochart::Progress& progress) {
  const int defined = im.defined_samples();
  if (defined == 0 || r.mesh.num_faces() == 0) return;
  const double texel_area = a.surface_area / defined;
  const double lambda = o.optimize_regularization * texel_area;
  const double plane_lambda = o.fit_regularization * texel_area;
  // No sample moves by more than a texel from where zippering put it (on the surface).
  const double max_move = std::sqrt(texel_area);
  // The pull is towards the zippered positions. Kept per group: the remesh's vertex numbering
  // may change when pockets appear or vanish.
  std::vector<Vec3d> group_anchor(im.num_groups);
  for (std::size_t i = 0; i < im.group.size(); ++i)
    if (im.group[i] >= 0) group_anchor[im.group[i]] = im.positions[i];
  const int passes = o.optimize_iterations + o.geometric_iterations;
  for (int it = 0; it < o.optimize_iterations; ++it) {
    isochart::report(progress, isochart::Stage::Optimization, static_cast<double>(it) / passes);
    std::vector<FitPoint> pts = fit_points(a, pl, param, im, r);
    // Points far from their triangle come from charts contracted or forced at this resolution,
    // where the texture-space correspondence says nothing about the surface: leave them out.
    const double reach2 = 9.0 * texel_area;
    pts.erase(std::remove_if(pts.begin(), pts.end(),
                             [&](const FitPoint& p) {
                               const auto& f = r.mesh.faces[p.face];
                               const Vec3d q = r.mesh.positions[f[0]] * p.weights.x +
                                               r.mesh.positions[f[1]] * p.weights.y +
                                               r.mesh.positions[f[2]] * p.weights.z;
                               return squared_norm(q - p.target) > reach2;
                             }),
              pts.end());
    solve(pts, group_anchor, lambda, max_move, im, r);
  }
  if (o.geometric_iterations > 0) {
    const SurfaceCache& surface = original_surface(a);
    const ClosestPoints& original = *surface.closest;
    std::vector<Vec3d> pts;
    std::vector<double> area;
    std::vector<int> pts_face;
    surface_points(*a.mesh, texel_area, pts, area, pts_face);
    const std::vector<Vec3d>& original_normals = surface.face_normals;
    const std::vector<ClosestPoints::Hit> source = sample_sources(original, im);
    // Fitted diagonals may not take the remesh further from the input's topology, nor change
    // its figures at the same distance; they may bring it closer (at coarse levels, where the
    // zippered seams are short, the old diagonals sometimes used an edge twice). Should the
    // edge test of choose_diagonals miss a case (pockets, pieces touching at a vertex), only
    // interior blocks get new diagonals for the rest of this level, and failing that the old
    // ones are kept.
    const auto distance = [&](const TopologyCheck& t) {
      return topology_distance(t, a.input_euler, a.input_boundary_loops);
    };
    const bool diagonals = o.fit_diagonals && !original.empty();
    bool interior_only = false;
    const auto pick_diagonals = [&] {
      const TopologyCheck before = check_topology(r.mesh);
      const GeometryImage::Diagonals kept = im.block_diagonal;
      for (;;) {
        im.block_diagonal = kept;
        choose_diagonals(original, source, r, interior_only, im);
        Remesh next = reconstruct(im, false);
        const TopologyCheck after = check_topology(next.mesh);
        if (distance(after) < distance(before) ||
            (distance(after) == distance(before) && same_topology(before, after))) {
          r = std::move(next);
          return;
        }
        if (interior_only) {
          im.block_diagonal = kept;
          return;
        }
        interior_only = true;
      }
    };
    for (int it = 0; it < o.geometric_iterations && !original.empty(); ++it) {
      isochart::report(progress, isochart::Stage::Optimization,
                       static_cast<double>(o.optimize_iterations + it) / passes);
      if (diagonals) pick_diagonals();
      solve_plane(closest_points(original, pts, area, pts_face, original_normals, source, r), group_anchor,
                  plane_lambda, max_move, im, r);
    }
    if (diagonals && o.geometric_iterations > 0) pick_diagonals();
  }
  isochart::report(progress, isochart::Stage::Optimization, 1.0);
}

}  // namespace mcgim::detail
