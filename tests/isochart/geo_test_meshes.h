#pragma once
// Small deterministic meshes for the geodesic and embedding tests.

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <utility>

#include "isochart/mesh.h"

namespace geo_test {

using isochart::Face;
using isochart::Mesh;
using isochart::Vec3d;

constexpr double kPi = 3.14159265358979323846;

// A reproducible value in [-0.5, 0.5) from two integers (a hash, not a random generator).
inline double hash_unit(int i, int j) {
  std::uint64_t z =
      (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32) ^ static_cast<std::uint32_t>(j);
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) / 9007199254740992.0 - 0.5;
}

// A (nx+1) × (ny+1) vertex grid over [0, w] × [0, h] in the plane z = 0, two triangles per cell,
// counter-clockwise seen from +z. `shear` moves row j by shear·j·(w/nx) in x, `jitter` moves
// interior vertices by up to ±jitter/2 cell sizes; both create obtuse triangles. `height`
// gives z from (x, y).
inline Mesh grid(int nx, int ny, double w, double h, double shear = 0, double jitter = 0,
                 const std::function<double(double, double)>& height = nullptr) {
  Mesh m;
  const double cx = w / nx, cy = h / ny;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      double x = i * cx + shear * j * cx, y = j * cy;
      if (i > 0 && i < nx && j > 0 && j < ny) {
        x += jitter * cx * hash_unit(i, j);
        y += jitter * cy * hash_unit(j + 7919, i);
      }
      m.positions.push_back({x, y, height ? height(x, y) : 0.0});
    }
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        m.faces.push_back({a, b, c});
        m.faces.push_back({a, c, d});
      } else {
        m.faces.push_back({a, b, d});
        m.faces.push_back({b, c, d});
      }
    }
  return m;
}

// Icosahedron subdivided `levels` times (each level splits every triangle in four), on the
// unit sphere: 10·4^levels + 2 vertices.
inline Mesh icosphere(int levels) {
  Mesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : m.positions) p = isochart::normalized(p);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(isochart::normalized(m.positions[a] + m.positions[b]));
      const int v = m.num_vertices() - 1;
      mid.emplace(key, v);
      return v;
    };
    std::vector<Face> next;
    for (const Face& f : m.faces) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.faces = std::move(next);
  }
  return m;
}

// Torus with major radius R and minor radius r, nu × nv vertices.
inline Mesh torus(int nu, int nv, double R, double r) {
  Mesh m;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      m.positions.push_back(
          {(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  auto id = [&](int i, int j) { return (j % nv) * nu + (i % nu); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

// Open tube of radius r along z from 0 to length, n around × (rings) along.
inline Mesh tube(int n, int rings, double r, double length) {
  Mesh m;
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < n; ++i) {
      const double u = 2 * kPi * (i + 0.5 * (j % 2)) / n;
      m.positions.push_back({r * std::cos(u), r * std::sin(u), length * j / (rings - 1)});
    }
  auto id = [&](int i, int j) { return j * n + (i % n); };
  for (int j = 0; j + 1 < rings; ++j)
    for (int i = 0; i < n; ++i) {
      if (j % 2 == 0) {
        m.faces.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        m.faces.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  return m;
}

// A bumpy height field over [0, 2] × [0, 2]: sheared and jittered so that many triangles are
// obtuse.
inline Mesh bumpy_patch(int n) {
  auto height = [](double x, double y) {
    return 0.25 * std::exp(-((x - 1.2) * (x - 1.2) + (y - 0.8) * (y - 0.8)) / 0.08) -
           0.2 * std::exp(-((x - 0.6) * (x - 0.6) + (y - 1.4) * (y - 1.4)) / 0.12) +
           0.05 * std::sin(5 * x) * std::cos(4 * y);
  };
  return grid(n, n, 2.0, 2.0, 0.45, 0.5, height);
}

}  // namespace geo_test
