// Built-in meshes: procedural, deterministic (single-threaded, no randomness, fixed iteration
// orders) and clean by construction, so tests and demos need no files.
//
// The creature is an implicit surface (a smooth union of ellipsoids and round cones) turned into
// triangles by marching tetrahedra on a grid and then isotropically remeshed (Botsch & Kobbelt
// 2004: split long edges, collapse short ones, flip towards valence 6, tangential relaxation)
// with every vertex projected back onto the implicit, so the triangles are well shaped.
#include "isochart/builtin.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>

#include "isochart/error.h"

namespace isochart {

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// sphere: a subdivided icosahedron projected onto the unit sphere.

Mesh make_sphere(int subdivisions) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  Mesh m;
  m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : m.positions) p = normalized(p);
  m.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      const int id = m.num_vertices();
      m.positions.push_back(normalized(m.positions[a] + m.positions[b]));
      midpoint.emplace(key, id);
      return id;
    };
    std::vector<Face> faces;
    faces.reserve(m.faces.size() * 4);
    for (const Face& f : m.faces) {
      const int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      faces.push_back({f[0], ab, ca});
      faces.push_back({f[1], bc, ab});
      faces.push_back({f[2], ca, bc});
      faces.push_back({ab, bc, ca});
    }
    m.faces = std::move(faces);
  }
  return m;
}

// ---------------------------------------------------------------------------------------------
// torus: a regular (major × minor) grid, lying in the xz-plane around the y axis.

Mesh make_torus(int major_segments, int minor_segments, double major_radius, double minor_radius) {
  Mesh m;
  const int nu = major_segments, nv = minor_segments;
  m.positions.reserve(static_cast<std::size_t>(nu) * nv);
  for (int i = 0; i < nu; ++i) {
    const double theta = 2 * kPi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double phi = 2 * kPi * j / nv;
      const double ring = major_radius + minor_radius * std::cos(phi);
      m.positions.push_back({ring * std::cos(theta), minor_radius * std::sin(phi), ring * std::sin(theta)});
    }
  }
  auto id = [&](int i, int j) { return (i % nu) * nv + (j % nv); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      // Stepping along the minor circle first, then the major one, faces outwards.
      const int v00 = id(i, j), v01 = id(i, j + 1), v10 = id(i + 1, j), v11 = id(i + 1, j + 1);
      m.faces.push_back({v00, v01, v11});
      m.faces.push_back({v00, v11, v10});
    }
  }
  return m;
}

// ---------------------------------------------------------------------------------------------
// face: a height field over an elliptic disk. The disk is the hexagonal "rings" triangulation
// (ring i holds 6i vertices), whose triangles are close to equilateral.

double gauss(double x, double y, double cx, double cy, double sx, double sy) {
  const double dx = (x - cx) / sx, dy = (y - cy) / sy;
  return std::exp(-0.5 * (dx * dx + dy * dy));
}

constexpr double kFaceHalfWidth = 0.8;  // the disk is 1.6 wide and 2 high

// Height (towards the viewer, +z) of the face at (x, y).
double face_height(double x, double y) {
  const double u = x / kFaceHalfWidth;
  const double r2 = u * u + y * y;
  double z = 0.5 * std::sqrt(std::max(0.0, 1 - 0.75 * r2));  // the dome of the skull
  z += 0.06 * gauss(x, y, 0, 0.55, 0.35, 0.25);              // forehead
  for (double s : {-1.0, 1.0}) {
    z += 0.05 * gauss(x, y, s * 0.28, 0.28, 0.15, 0.05);     // brow ridge
    z -= 0.13 * gauss(x, y, s * 0.28, 0.12, 0.11, 0.08);     // eye socket
    z += 0.06 * gauss(x, y, s * 0.28, 0.11, 0.055, 0.04);    // eyeball
    z += 0.05 * gauss(x, y, s * 0.08, -0.17, 0.045, 0.035);  // nostril wing
    z += 0.05 * gauss(x, y, s * 0.38, -0.15, 0.15, 0.15);    // cheek
  }
  z += 0.08 * gauss(x, y, 0, 0.05, 0.05, 0.13);     // bridge of the nose
  z += 0.16 * gauss(x, y, 0, -0.13, 0.07, 0.06);    // tip of the nose
  z += 0.04 * gauss(x, y, 0, -0.38, 0.15, 0.035);   // upper lip
  z += 0.045 * gauss(x, y, 0, -0.48, 0.12, 0.035);  // lower lip
  z -= 0.03 * gauss(x, y, 0, -0.43, 0.14, 0.022);   // mouth
  z += 0.06 * gauss(x, y, 0, -0.72, 0.13, 0.1);     // chin
  return z;
}

Mesh make_face(int rings) {
  Mesh m;
  std::vector<int> ring_start(rings + 2);
  m.positions.push_back({0, 0, 0});
  ring_start[0] = 0;
  for (int i = 1; i <= rings; ++i) {
    ring_start[i] = m.num_vertices();
    const double r = static_cast<double>(i) / rings;
    for (int k = 0; k < 6 * i; ++k) {
      const double a = 2 * kPi * k / (6 * i);
      m.positions.push_back({r * std::cos(a), r * std::sin(a), 0});
    }
  }
  for (int i = 1; i <= rings; ++i) {
    const int n_in = i == 1 ? 1 : 6 * (i - 1), n_out = 6 * i;
    auto in = [&](int p) { return i == 1 ? 0 : ring_start[i - 1] + p % n_in; };
    auto out = [&](int q) { return ring_start[i] + q % n_out; };
    if (i == 1) {
      for (int q = 0; q < n_out; ++q) m.faces.push_back({0, out(q), out(q + 1)});
      continue;
    }
    // Zip the two rings by angle; angles compared exactly as fractions p/n_in vs q/n_out.
    int p = 0, q = 0;
    while (p < n_in || q < n_out) {
      const bool advance_inner = q == n_out || (p < n_in && static_cast<long long>(p + 1) * n_out <=
                                                                static_cast<long long>(q + 1) * n_in);
      if (advance_inner) {
        m.faces.push_back({in(p), out(q), in(p + 1)});
        ++p;
      } else {
        m.faces.push_back({in(p), out(q), out(q + 1)});
        ++q;
      }
    }
  }
  for (auto& v : m.positions) {
    v.x *= kFaceHalfWidth;
    v.z = face_height(v.x, v.y);
  }
  return m;
}

// ---------------------------------------------------------------------------------------------
// Implicit surfaces: signed-distance-like functions (negative inside) combined by smooth min.

// Polynomial smooth minimum: equal to min(a, b) when they differ by more than k.
double smooth_min(double a, double b, double k) {
  if (k <= 0) return std::min(a, b);
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - h * h * k * 0.25;
}

struct Primitive {
  enum Kind { Ellipsoid, RoundCone } kind = Ellipsoid;
  Vec3d a, b;             // ellipsoid: centre, radii; round cone: axis end points
  double ra = 0, rb = 0;  // round cone radii at a and b
  double blend = 0;       // smooth-min radius joining this primitive to the ones before it
  Vec3d flatten_dir;      // round cone: squash across this unit direction...
  double flatten = 1;     // ...by this factor (1 = circular cross-section)
  // eval(p) ≥ bound_scale · (|p − bound_centre| − bound_radius) wherever the right side is
  // positive (bound_scale = 0: no bound known). Lets Implicit skip parts that cannot change
  // the smooth minimum.
  Vec3d bound_centre;
  double bound_radius = 0, bound_scale = 0;

  void set_bound() {
    if (kind == Ellipsoid) {
      // k0 ≥ |q|/r_max and k1 ≤ |q|/r_min², so k0(k0−1)/k1 ≥ (r_min/r_max)²·(|q| − r_max)
      // wherever that is positive.
      const double rmax = std::max({b.x, b.y, b.z}), rmin = std::min({b.x, b.y, b.z});
      bound_centre = a;
      bound_radius = rmax;
      bound_scale = (rmin / rmax) * (rmin / rmax);
    } else if (flatten == 1) {
      // An exact distance is at least the distance to a sphere around the whole cone.
      bound_centre = (a + b) * 0.5;
      bound_radius = 0.5 * norm(b - a) + std::max(ra, rb);
      bound_scale = 1;
    }
  }

  double eval(const Vec3d& p) const {
    if (kind == Ellipsoid) {
      // Distance bound of an axis-aligned ellipsoid, accurate near its surface.
      const Vec3d q = p - a;
      const Vec3d s{q.x / b.x, q.y / b.y, q.z / b.z};
      const Vec3d s2{s.x / b.x, s.y / b.y, s.z / b.z};
      const double k0 = norm(s), k1 = norm(s2);
      if (k1 < 1e-12) return -std::min({b.x, b.y, b.z});
      return k0 * (k0 - 1) / k1;
    }
    Vec3d q = p - a;
    if (flatten != 1) q += flatten_dir * ((flatten - 1) * dot(q, flatten_dir));
    // Exact distance to the hull of two spheres, worked out in the (axial, radial) half plane.
    const Vec3d ab = b - a;
    const double len = norm(ab);
    const Vec3d axis = ab / len;
    const double x = dot(q, axis);
    const double y = norm(q - axis * x);
    const double s = (ra - rb) / len, c = std::sqrt(1 - s * s);
    const double along = c * x - s * y;  // coordinate along the tangent line
    if (along < 0) return std::sqrt(x * x + y * y) - ra;
    if (along > c * len) return std::sqrt((x - len) * (x - len) + y * y) - rb;
    return s * x + c * y - ra;
  }

  // A box that contains the primitive (generous for flattened cones).
  void bounds(Vec3d& lo, Vec3d& hi) const {
    if (kind == Ellipsoid) {
      lo = a - b;
      hi = a + b;
      return;
    }
    const double r = std::max(ra, rb);
    lo = {std::min(a.x, b.x) - r, std::min(a.y, b.y) - r, std::min(a.z, b.z) - r};
    hi = {std::max(a.x, b.x) + r, std::max(a.y, b.y) + r, std::max(a.z, b.z) + r};
  }
};

struct Implicit {
  std::vector<Primitive> parts;

  double operator()(const Vec3d& p) const {
    double d = parts[0].eval(p);
    for (std::size_t i = 1; i < parts.size(); ++i) {
      const Primitive& q = parts[i];
      // smooth_min(d, e, k) == d exactly when e ≥ d + k: skipping such a part changes nothing.
      if (q.bound_scale > 0) {
        const double lower = q.bound_scale * (norm(p - q.bound_centre) - q.bound_radius);
        if (lower > 0 && lower >= d + q.blend) continue;
      }
      d = smooth_min(d, q.eval(p), q.blend);
    }
    return d;
  }
  // Value and gradient (forward differences: four evaluations, the dominant cost of remeshing).
  double value_gradient(const Vec3d& p, Vec3d& g) const {
    const double e = 1e-6;
    const Implicit& f = *this;
    const double v = f(p);
    g = Vec3d{f({p.x + e, p.y, p.z}) - v, f({p.x, p.y + e, p.z}) - v, f({p.x, p.y, p.z + e}) - v} / e;
    return v;
  }
  Vec3d normal(const Vec3d& p) const {
    Vec3d g;
    value_gradient(p, g);
    return normalized(g);
  }
  // Newton steps along the gradient onto the zero level set.
  Vec3d project(Vec3d p, int steps) const {
    for (int i = 0; i < steps; ++i) {
      Vec3d g;
      const double v = value_gradient(p, g);
      const double g2 = squared_norm(g);
      if (g2 < 1e-12) break;
      p -= g * (v / g2);
    }
    return p;
  }
};

Primitive ellipsoid(Vec3d centre, Vec3d radii, double blend) {
  Primitive p;
  p.kind = Primitive::Ellipsoid;
  p.a = centre;
  p.b = radii;
  p.blend = blend;
  return p;
}

Primitive round_cone(Vec3d a, Vec3d b, double ra, double rb, double blend) {
  Primitive p;
  p.kind = Primitive::RoundCone;
  p.a = a;
  p.b = b;
  p.ra = ra;
  p.rb = rb;
  p.blend = blend;
  return p;
}

// A four-legged animal: +x is forward (head), +y up, z across; about 3 units long.
// Appendages are kept apart so that the smooth union never bridges them (genus 0).
Implicit creature_shape() {
  Implicit f;
  f.parts.push_back(ellipsoid({0, 0, 0}, {0.85, 0.42, 0.40}, 0));                    // belly
  f.parts.push_back(ellipsoid({0.45, 0.05, 0}, {0.45, 0.42, 0.38}, 0.2));            // chest
  f.parts.push_back(ellipsoid({-0.5, 0.02, 0}, {0.42, 0.38, 0.36}, 0.2));            // hips
  f.parts.push_back(round_cone({0.55, 0.2, 0}, {0.98, 0.62, 0}, 0.24, 0.18, 0.15));  // neck
  f.parts.push_back(ellipsoid({1.08, 0.74, 0}, {0.3, 0.26, 0.25}, 0.1));             // skull
  f.parts.push_back(round_cone({1.15, 0.7, 0}, {1.48, 0.6, 0}, 0.16, 0.1, 0.08));    // snout
  for (double s : {-1.0, 1.0}) {
    Primitive ear = round_cone({1.0, 0.88, s * 0.13}, {0.93, 1.25, s * 0.25}, 0.11, 0.05, 0.06);
    ear.flatten_dir = {1, 0, 0};
    ear.flatten = 1.4;
    f.parts.push_back(ear);
    f.parts.push_back(ellipsoid({1.28, 0.81, s * 0.16}, {0.045, 0.045, 0.045}, 0.02));  // eye
  }
  for (double s : {-1.0, 1.0}) {
    f.parts.push_back(
        round_cone({0.5, -0.15, s * 0.22}, {0.55, -0.95, s * 0.24}, 0.13, 0.09, 0.1));  // front leg
    f.parts.push_back(ellipsoid({0.6, -0.98, s * 0.24}, {0.14, 0.07, 0.1}, 0.06));      // front paw
    f.parts.push_back(
        round_cone({-0.55, -0.1, s * 0.22}, {-0.6, -0.95, s * 0.24}, 0.15, 0.09, 0.1));  // hind leg
    f.parts.push_back(ellipsoid({-0.55, -0.98, s * 0.24}, {0.14, 0.07, 0.1}, 0.06));     // hind paw
  }
  f.parts.push_back(round_cone({-0.75, 0.12, 0}, {-1.1, 0.3, 0}, 0.095, 0.075, 0.08));  // tail
  f.parts.push_back(round_cone({-1.1, 0.3, 0}, {-1.3, 0.55, 0}, 0.075, 0.062, 0.04));
  f.parts.push_back(round_cone({-1.3, 0.55, 0}, {-1.36, 0.82, 0}, 0.062, 0.05, 0.04));
  for (auto& p : f.parts) p.set_bound();
  return f;
}

// ---------------------------------------------------------------------------------------------
// Marching tetrahedra on a regular grid, each cube split into the six Kuhn tetrahedra around
// its main diagonal. The split is the same in every cube, so the tetrahedra conform and the
// surface is a closed 2-manifold whenever no grid value is exactly zero (zero counts as outside).

struct Soup {
  std::vector<Vec3d> positions;
  std::vector<Face> faces;
};

Soup marching_tetrahedra(const Implicit& f, double h) {
  Vec3d lo, hi;
  f.parts[0].bounds(lo, hi);
  for (const auto& p : f.parts) {
    Vec3d l, u;
    p.bounds(l, u);
    lo = {std::min(lo.x, l.x), std::min(lo.y, l.y), std::min(lo.z, l.z)};
    hi = {std::max(hi.x, u.x), std::max(hi.y, u.y), std::max(hi.z, u.z)};
  }
  lo -= Vec3d{2 * h, 2 * h, 2 * h};
  hi += Vec3d{2 * h, 2 * h, 2 * h};
  const int nx = static_cast<int>(std::ceil((hi.x - lo.x) / h)) + 1;
  const int ny = static_cast<int>(std::ceil((hi.y - lo.y) / h)) + 1;
  const int nz = static_cast<int>(std::ceil((hi.z - lo.z) / h)) + 1;
  auto index = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
  auto point = [&](int i, int j, int k) { return lo + Vec3d{i * h, j * h, k * h}; };

  const std::size_t n = static_cast<std::size_t>(nx) * ny * nz;
  std::vector<double> value(n);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) value[index(i, j, k)] = f(point(i, j, k));

  // Edges of the Kuhn tetrahedra join a grid point to one of 7 "upper" neighbours (offset bits
  // x=1, y=2, z=4); a crossing edge's vertex is stored under (lower point, offset code).
  std::vector<int> edge_vertex(n * 7, -1);
  Soup soup;
  const int offset[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                            {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  std::array<std::array<int, 4>, 6> tets;
  {
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int t = 0; t < 6; ++t) {
      const int b0 = 1 << perms[t][0], b1 = b0 | (1 << perms[t][1]);
      tets[t] = {0, b0, b1, 7};
    }
  }

  for (int k = 0; k + 1 < nz; ++k) {
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        int gid[8];
        bool inside[8];
        int count = 0;
        for (int c = 0; c < 8; ++c) {
          gid[c] = index(i + offset[c][0], j + offset[c][1], k + offset[c][2]);
          inside[c] = value[gid[c]] < 0;
          count += inside[c];
        }
        if (count == 0 || count == 8) continue;

        // Corners of a Kuhn tetrahedron form a chain (c1 ⊂ c2 as bit sets), so c2 ^ c1 is the
        // offset code of the edge from the lower corner.
        auto vertex_on = [&](int c1, int c2) {
          if (c1 > c2) std::swap(c1, c2);
          const std::size_t key = static_cast<std::size_t>(gid[c1]) * 7 + ((c1 ^ c2) - 1);
          int& v = edge_vertex[key];
          if (v < 0) {
            const double f1 = value[gid[c1]], f2 = value[gid[c2]];
            const double t = std::clamp(f1 / (f1 - f2), 0.01, 0.99);
            const Vec3d p1 = point(i + offset[c1][0], j + offset[c1][1], k + offset[c1][2]);
            const Vec3d p2 = point(i + offset[c2][0], j + offset[c2][1], k + offset[c2][2]);
            v = static_cast<int>(soup.positions.size());
            soup.positions.push_back(p1 + (p2 - p1) * t);
          }
          return v;
        };
        // Orientation is decided on the idealized surface through edge midpoints (integer
        // coordinates, never degenerate), so it is exact and consistent between tetrahedra.
        auto emit = [&](std::array<std::array<int, 2>, 3> tri, const int* in_corners, int n_in,
                        const int* out_corners, int n_out) {
          int m[3][3];
          for (int v = 0; v < 3; ++v)
            for (int d = 0; d < 3; ++d) m[v][d] = offset[tri[v][0]][d] + offset[tri[v][1]][d];
          const int e1[3] = {m[1][0] - m[0][0], m[1][1] - m[0][1], m[1][2] - m[0][2]};
          const int e2[3] = {m[2][0] - m[0][0], m[2][1] - m[0][1], m[2][2] - m[0][2]};
          const int nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                              e1[0] * e2[1] - e1[1] * e2[0]};
          int dir[3] = {0, 0, 0};
          for (int d = 0; d < 3; ++d) {
            for (int q = 0; q < n_out; ++q) dir[d] += n_in * offset[out_corners[q]][d];
            for (int q = 0; q < n_in; ++q) dir[d] -= n_out * offset[in_corners[q]][d];
          }
          if (nrm[0] * dir[0] + nrm[1] * dir[1] + nrm[2] * dir[2] < 0) std::swap(tri[1], tri[2]);
          soup.faces.push_back({vertex_on(tri[0][0], tri[0][1]), vertex_on(tri[1][0], tri[1][1]),
                                vertex_on(tri[2][0], tri[2][1])});
        };

        for (const auto& tet : tets) {
          int in_c[4], out_c[4], n_in = 0, n_out = 0;
          for (int c : tet) (inside[c] ? in_c[n_in++] : out_c[n_out++]) = c;
          if (n_in == 0 || n_out == 0) continue;
          if (n_in == 1) {
            const int a = in_c[0];
            emit({{{a, out_c[0]}, {a, out_c[1]}, {a, out_c[2]}}}, in_c, n_in, out_c, n_out);
          } else if (n_out == 1) {
            const int a = out_c[0];
            emit({{{a, in_c[0]}, {a, in_c[1]}, {a, in_c[2]}}}, in_c, n_in, out_c, n_out);
          } else {
            // Quad ac, ad, bd, bc (a, b inside; c, d outside), split along its shorter diagonal.
            const int a = in_c[0], b = in_c[1], c = out_c[0], d = out_c[1];
            const std::array<int, 2> ac{a, c}, ad{a, d}, bd{b, d}, bc{b, c};
            const int vac = vertex_on(a, c), vad = vertex_on(a, d), vbd = vertex_on(b, d),
                      vbc = vertex_on(b, c);
            const auto& P = soup.positions;
            const double d1 = squared_norm(P[vac] - P[vbd]), d2 = squared_norm(P[vad] - P[vbc]);
            if (d1 <= d2) {
              emit({{ac, ad, bd}}, in_c, n_in, out_c, n_out);
              emit({{ac, bd, bc}}, in_c, n_in, out_c, n_out);
            } else {
              emit({{ad, bd, bc}}, in_c, n_in, out_c, n_out);
              emit({{ad, bc, ac}}, in_c, n_in, out_c, n_out);
            }
          }
        }
      }
    }
  }
  return soup;
}

// ---------------------------------------------------------------------------------------------
// A half-edge mesh for closed triangle meshes. Half-edge 3f+k runs from corner k of face f to
// corner k+1, so `next`/`prev` are arithmetic and only the twin is stored.

class HalfedgeMesh {
 public:
  HalfedgeMesh(std::vector<Vec3d> positions, const std::vector<Face>& faces) : pos_(std::move(positions)) {
    const int nf = static_cast<int>(faces.size());
    corner_.resize(3 * static_cast<std::size_t>(nf));
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) corner_[3 * f + k] = faces[f][k];
    // Pair half-edges by sorting (min, max, h); a manifold closed mesh has exactly two per edge.
    std::vector<std::array<int, 3>> keys(corner_.size());
    for (int h = 0; h < num_halfedges(); ++h) {
      const int a = from(h), b = to(h);
      keys[h] = {std::min(a, b), std::max(a, b), h};
    }
    std::sort(keys.begin(), keys.end());
    twin_.assign(corner_.size(), -1);
    for (std::size_t i = 0; i < keys.size(); i += 2) {
      const auto& k0 = keys[i];
      const bool paired = i + 1 < keys.size() && keys[i + 1][0] == k0[0] && keys[i + 1][1] == k0[1] &&
                          from(keys[i + 1][2]) != from(k0[2]) &&
                          (i + 2 >= keys.size() || keys[i + 2][0] != k0[0] || keys[i + 2][1] != k0[1]);
      if (!paired) throw Error("builtin mesh: polygonization produced a non-manifold edge");
      twin_[k0[2]] = keys[i + 1][2];
      twin_[keys[i + 1][2]] = k0[2];
    }
    vout_.assign(pos_.size(), -1);
    for (int h = 0; h < num_halfedges(); ++h) vout_[from(h)] = h;
    face_dead_.assign(nf, 0);
    vertex_dead_.assign(pos_.size(), 0);
    valence_.assign(pos_.size(), 0);
    for (int h = 0; h < num_halfedges(); ++h) ++valence_[from(h)];
    mark_.assign(pos_.size(), 0);
  }

  static int next(int h) { return h % 3 == 2 ? h - 2 : h + 1; }
  static int prev(int h) { return h % 3 == 0 ? h + 2 : h - 1; }
  int num_halfedges() const { return static_cast<int>(corner_.size()); }
  int from(int h) const { return corner_[h]; }
  int to(int h) const { return corner_[next(h)]; }
  int twin(int h) const { return twin_[h]; }
  bool face_alive(int f) const { return !face_dead_[f]; }
  int num_vertices() const { return static_cast<int>(pos_.size()); }
  bool vertex_alive(int v) const { return !vertex_dead_[v]; }
  const Vec3d& position(int v) const { return pos_[v]; }
  void set_position(int v, const Vec3d& p) { pos_[v] = p; }
  double length2(int h) const { return squared_norm(pos_[to(h)] - pos_[from(h)]); }

  // Outgoing half-edges of v, in rotational order.
  template <class F>
  void for_each_outgoing(int v, F&& fn) const {
    const int start = vout_[v];
    int h = start;
    do {
      fn(h);
      h = twin_[prev(h)];
    } while (h != start);
  }

  // Splits the edge of h at p: two faces become four.
  void split(int h, const Vec3d& p) {
    const int t = twin_[h];
    const int f0 = h / 3, f1 = t / 3;
    const int a = from(h), b = to(h), c = to(next(h)), d = to(next(t));
    const int o_bc = twin_[next(h)], o_ca = twin_[prev(h)], o_ad = twin_[next(t)], o_db = twin_[prev(t)];
    const int m = static_cast<int>(pos_.size());
    pos_.push_back(p);
    vertex_dead_.push_back(0);
    mark_.push_back(0);
    valence_.push_back(4);
    vout_.push_back(-1);
    const int f2 = add_face(), f3 = add_face();
    set_face(f0, a, m, c);
    set_face(f2, m, b, c);
    set_face(f1, b, m, d);
    set_face(f3, m, a, d);
    link(3 * f0 + 0, 3 * f3 + 0);  // a-m
    link(3 * f0 + 1, 3 * f2 + 2);  // m-c
    link(3 * f0 + 2, o_ca);
    link(3 * f2 + 0, 3 * f1 + 0);  // m-b
    link(3 * f2 + 1, o_bc);
    link(3 * f1 + 1, 3 * f3 + 2);  // m-d
    link(3 * f1 + 2, o_db);
    link(3 * f3 + 1, o_ad);
    vout_[a] = 3 * f0 + 0;
    vout_[b] = 3 * f2 + 1;
    vout_[c] = 3 * f0 + 2;
    vout_[d] = 3 * f1 + 2;
    vout_[m] = 3 * f2 + 0;
    ++valence_[c];
    ++valence_[d];
  }

  // Replaces edge a-b (faces abc, bad) by c-d (faces cad, dbc).
  void flip(int h) {
    const int t = twin_[h];
    const int f0 = h / 3, f1 = t / 3;
    const int a = from(h), b = to(h), c = to(next(h)), d = to(next(t));
    const int o_bc = twin_[next(h)], o_ca = twin_[prev(h)], o_ad = twin_[next(t)], o_db = twin_[prev(t)];
    set_face(f0, c, a, d);
    set_face(f1, d, b, c);
    link(3 * f0 + 0, o_ca);
    link(3 * f0 + 1, o_ad);
    link(3 * f0 + 2, 3 * f1 + 2);
    link(3 * f1 + 0, o_db);
    link(3 * f1 + 1, o_bc);
    vout_[a] = 3 * f0 + 1;
    vout_[b] = 3 * f1 + 1;
    vout_[c] = 3 * f0 + 0;
    vout_[d] = 3 * f1 + 0;
    --valence_[a];
    --valence_[b];
    ++valence_[c];
    ++valence_[d];
  }

  // Can the edge of h be flipped without creating a duplicate edge or a valence-2 vertex?
  bool flip_ok(int h) const {
    const int t = twin_[h];
    const int a = from(h), b = to(h), c = to(next(h)), d = to(next(t));
    if (c == d || valence_[a] <= 3 || valence_[b] <= 3) return false;
    bool exists = false;
    for_each_outgoing(c, [&](int g) { exists = exists || to(g) == d; });
    return !exists;
  }

  // Link condition for collapsing the edge of h: a and b share exactly the two neighbours of
  // the edge's faces, so the collapse keeps the surface a manifold of the same topology.
  bool collapse_ok(int h) {
    const int a = from(h), b = to(h);
    ++stamp_;
    for_each_outgoing(a, [&](int g) { mark_[to(g)] = stamp_; });
    int shared = 0;
    for_each_outgoing(b, [&](int g) { shared += mark_[to(g)] == stamp_; });
    return shared == 2;
  }

  // Merges from(h) into to(h), which moves to p. Removes the edge's two faces.
  void collapse(int h, const Vec3d& p) {
    const int t = twin_[h];
    const int a = from(h), b = to(h), c = to(next(h)), d = to(next(t));
    const int o_bc = twin_[next(h)], o_ca = twin_[prev(h)], o_ad = twin_[next(t)], o_db = twin_[prev(t)];
    std::vector<int> ring;
    for_each_outgoing(a, [&](int g) { ring.push_back(g); });
    for (int g : ring) corner_[g] = b;
    link(o_bc, o_ca);
    link(o_ad, o_db);
    vout_[b] = o_ca;
    vout_[c] = o_bc;
    vout_[d] = o_ad;
    face_dead_[h / 3] = face_dead_[t / 3] = 1;
    vertex_dead_[a] = 1;
    pos_[b] = p;
    valence_[b] += valence_[a] - 4;
    --valence_[c];
    --valence_[d];
  }

  int valence(int v) const { return valence_[v]; }

  Mesh to_mesh() const {
    Mesh m;
    std::vector<int> remap(pos_.size(), -1);
    for (std::size_t v = 0; v < pos_.size(); ++v) {
      if (vertex_dead_[v]) continue;
      remap[v] = m.num_vertices();
      m.positions.push_back(pos_[v]);
    }
    for (std::size_t f = 0; f < face_dead_.size(); ++f) {
      if (face_dead_[f]) continue;
      m.faces.push_back({remap[corner_[3 * f]], remap[corner_[3 * f + 1]], remap[corner_[3 * f + 2]]});
    }
    return m;
  }

 private:
  int add_face() {
    corner_.insert(corner_.end(), 3, -1);
    twin_.insert(twin_.end(), 3, -1);
    face_dead_.push_back(0);
    return static_cast<int>(face_dead_.size()) - 1;
  }
  void set_face(int f, int a, int b, int c) {
    corner_[3 * f] = a;
    corner_[3 * f + 1] = b;
    corner_[3 * f + 2] = c;
  }
  void link(int h, int g) {
    twin_[h] = g;
    twin_[g] = h;
  }

  std::vector<Vec3d> pos_;
  std::vector<int> corner_, twin_, vout_, valence_;
  std::vector<char> face_dead_, vertex_dead_;
  std::vector<std::uint32_t> mark_;
  std::uint32_t stamp_ = 0;
};

Vec3d unit_normal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return normalized(cross(b - a, c - a));
}

// Isotropic remeshing towards edge length `target`, keeping vertices on the implicit surface.
void remesh(HalfedgeMesh& m, const Implicit& f, double target, int iterations) {
  const double hi2 = std::pow(4.0 / 3.0 * target, 2), lo2 = std::pow(0.8 * target, 2);
  std::vector<int> ring;
  for (int it = 0; it < iterations; ++it) {
    // 1. Split long edges at their midpoint; new faces are visited too, so every edge ends
    //    below the bound. (Projecting here could move a point of a chord across a thin part far
    //    away and split forever; step 4 projects.)
    for (int h = 0; h < m.num_halfedges(); ++h) {
      if (!m.face_alive(h / 3) || h > m.twin(h) || m.length2(h) <= hi2) continue;
      m.split(h, (m.position(m.from(h)) + m.position(m.to(h))) * 0.5);
    }

    // 2. Collapse short edges into their midpoint unless that creates a long edge or folds a
    //    neighbouring triangle.
    for (int h = 0; h < m.num_halfedges(); ++h) {
      if (!m.face_alive(h / 3) || h > m.twin(h) || m.length2(h) >= lo2) continue;
      const int a = m.from(h), b = m.to(h);
      if (!m.collapse_ok(h)) continue;
      const Vec3d p = (m.position(a) + m.position(b)) * 0.5;
      const int t = m.twin(h);
      bool ok = true;
      Vec3d surface_normal;
      bool have_surface_normal = false;
      for (int v : {a, b}) {
        m.for_each_outgoing(v, [&](int g) {
          if (!ok || g / 3 == h / 3 || g / 3 == t / 3) return;
          const Vec3d& y = m.position(m.to(g));
          const Vec3d& z = m.position(m.to(HalfedgeMesh::next(g)));
          if (squared_norm(y - p) > hi2) {
            ok = false;
            return;
          }
          const Vec3d n_new = cross(y - p, z - p);
          const double len_new = norm(n_new);
          if (len_new < 1e-14) {
            ok = false;
            return;
          }
          const Vec3d n_old = cross(y - m.position(v), z - m.position(v));
          const double len_old = norm(n_old);
          if (len_old > 1e-12 * target * target) {
            ok = dot(n_new, n_old) > 0.5 * len_new * len_old;
          } else {
            if (!have_surface_normal) {
              surface_normal = f.normal(p);
              have_surface_normal = true;
            }
            ok = dot(n_new, surface_normal) > 0.2 * len_new;
          }
        });
      }
      if (ok) m.collapse(h, p);
    }

    // 3. Flip edges when that brings the four vertices' valences closer to 6, unless the new
    //    triangles would fold over.
    for (int h = 0; h < m.num_halfedges(); ++h) {
      if (!m.face_alive(h / 3) || h > m.twin(h) || !m.flip_ok(h)) continue;
      const int t = m.twin(h);
      const int a = m.from(h), b = m.to(h), c = m.to(HalfedgeMesh::next(h)), d = m.to(HalfedgeMesh::next(t));
      auto dev = [](int v) { return (v - 6) * (v - 6); };
      const int before = dev(m.valence(a)) + dev(m.valence(b)) + dev(m.valence(c)) + dev(m.valence(d));
      const int after =
          dev(m.valence(a) - 1) + dev(m.valence(b) - 1) + dev(m.valence(c) + 1) + dev(m.valence(d) + 1);
      if (after >= before) continue;
      const Vec3d &pa = m.position(a), &pb = m.position(b), &pc = m.position(c), &pd = m.position(d);
      const Vec3d old_n = unit_normal(pa, pb, pc) + unit_normal(pb, pa, pd);
      const Vec3d n1 = unit_normal(pc, pa, pd), n2 = unit_normal(pd, pb, pc);
      if (dot(n1, old_n) <= 0.5 || dot(n2, old_n) <= 0.5 || dot(n1, n2) <= 0.5) continue;
      m.flip(h);
    }

    // 4. Tangential relaxation towards the 1-ring centroid, then back onto the surface.
    //    Computed for all vertices before any moves (Jacobi), so the order does not matter.
    std::vector<Vec3d> moved(m.num_vertices());
    for (int v = 0; v < m.num_vertices(); ++v) {
      if (!m.vertex_alive(v)) continue;
      const Vec3d p = m.position(v);
      Vec3d centroid;
      int n = 0;
      m.for_each_outgoing(v, [&](int g) {
        centroid += m.position(m.to(g));
        ++n;
      });
      centroid /= n;
      const Vec3d normal = f.normal(p);
      Vec3d step = centroid - p;
      step -= normal * dot(normal, step);
      // One Newton step suffices for a tangential move of half an edge; the last pass takes two.
      moved[v] = f.project(p + step * 0.5, it + 1 == iterations ? 2 : 1);
    }
    for (int v = 0; v < m.num_vertices(); ++v)
      if (m.vertex_alive(v)) m.set_position(v, moved[v]);
  }
}

Mesh make_creature() {
  const Implicit shape = creature_shape();
  const double target = 0.028;  // edge length: about 24k faces
  // A grid a little coarser than the target halves the polygonization's output (the remesher
  // refines it anyway) while still resolving the thinnest parts, the ear tips.
  Soup soup = marching_tetrahedra(shape, 1.25 * target);
  HalfedgeMesh hm(std::move(soup.positions), soup.faces);
  remesh(hm, shape, target, 6);
  return hm.to_mesh();
}

}  // namespace

std::vector<std::string> builtin_names() {
  return {"sphere", "torus", "creature", "face"};
}

Mesh make_builtin(const std::string& name) {
  if (name == "sphere") return make_sphere(4);
  if (name == "torus") return make_torus(72, 36, 1.0, 0.4);
  if (name == "creature") return make_creature();
  if (name == "face") return make_face(41);
  std::string names;
  for (const auto& n : builtin_names()) names += (names.empty() ? "" : ", ") + n;
  throw InputError("builtin:" + name, "unknown built-in mesh (available: " + names + ")");
}

}  // namespace isochart
