#pragma once
// Small meshes with hand-made atlases laid out in [0,1]² with gaps between charts, for the
// geometry-image tests.

#include <cmath>
#include <map>
#include <tuple>

#include "isochart/mesh.h"

namespace mcgim_test {

using isochart::Face;
using isochart::Mesh;
using isochart::Vec2d;
using isochart::Vec3d;

/// Cube [-1,1]³, each face an n×n grid of quads and one chart, the six charts in a 3×2 layout.
inline Mesh cube_atlas(int n, double margin = 0.03) {
  Mesh m;
  std::map<std::tuple<int, int, int>, int> index;
  auto vertex = [&](int x, int y, int z) {
    const auto key = std::make_tuple(x, y, z);
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    const int id = m.num_vertices();
    m.positions.push_back(Vec3d(x, y, z) / n);
    index.emplace(key, id);
    return id;
  };
  // Outward axis and two tangent axes with t1 × t2 = outward.
  const int axes[6][3][3] = {
      {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},   {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
      {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},   {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
      {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},   {{0, 0, -1}, {0, 1, 0}, {1, 0, 0}},
  };
  const double cw = 1.0 / 3, ch = 1.0 / 2;
  const double s = std::min(cw, ch) - 2 * margin;
  for (int k = 0; k < 6; ++k) {
    const auto& a = axes[k];
    const double u0 = (k % 3) * cw + margin, v0 = (k / 3) * ch + margin;
    const int uv_base = static_cast<int>(m.uvs.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.uvs.push_back({u0 + s * i / n, v0 + s * j / n});
    auto vid = [&](int i, int j) {
      const int p = 2 * i - n, q = 2 * j - n;
      int c[3];
      for (int d = 0; d < 3; ++d) c[d] = a[0][d] * n + a[1][d] * p + a[2][d] * q;
      return vertex(c[0], c[1], c[2]);
    };
    auto tid = [&](int i, int j) { return uv_base + j * (n + 1) + i; };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        m.faces.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
        m.face_uvs.push_back({tid(i, j), tid(i + 1, j), tid(i + 1, j + 1)});
        m.faces.push_back({vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
        m.face_uvs.push_back({tid(i, j), tid(i + 1, j + 1), tid(i, j + 1)});
        m.face_groups.push_back(k);
        m.face_groups.push_back(k);
      }
  }
  return m;
}

/// Sphere of radius `radius` (latitude-longitude, `rings` even) in two charts, the
/// hemispheres, each mapped to a disk by the azimuthal equidistant projection.
inline Mesh sphere_atlas(int rings, int segments, double radius = 1.0) {
  Mesh m;
  const double pi = std::acos(-1.0);
  m.positions.push_back({0, 0, radius});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double th = pi * r / rings, ph = 2 * pi * s / segments;
      m.positions.push_back({radius * std::sin(th) * std::cos(ph), radius * std::sin(th) * std::sin(ph),
                             radius * std::cos(th)});
    }
  m.positions.push_back({0, 0, -radius});
  const int south = m.num_vertices() - 1;
  auto ring_v = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.faces.push_back({0, ring_v(1, s), ring_v(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.faces.push_back({ring_v(r, s), ring_v(r + 1, s), ring_v(r + 1, s + 1)});
      m.faces.push_back({ring_v(r, s), ring_v(r + 1, s + 1), ring_v(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.faces.push_back({ring_v(rings - 1, s), south, ring_v(rings - 1, s + 1)});
  // Charts by hemisphere (face centroid), uvs per corner.
  const double R = 0.2;
  for (const Face& f : m.faces) {
    const Vec3d c = (m.positions[f[0]] + m.positions[f[1]] + m.positions[f[2]]) / 3.0;
    const int chart = c.z >= 0 ? 0 : 1;
    Face fu;
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = m.positions[f[k]] / radius;
      double th = std::acos(std::max(-1.0, std::min(1.0, p.z)));
      if (chart == 1) th = pi - th;
      double ph = std::atan2(p.y, p.x);
      // Pole corners take the angle of the face's other corners (any angle maps to the centre).
      const double rr = R * th / (pi / 2);
      if (chart == 1) ph = -ph;
      const Vec2d centre = chart == 0 ? Vec2d(0.25, 0.5) : Vec2d(0.75, 0.5);
      fu[k] = static_cast<int>(m.uvs.size());
      m.uvs.push_back(centre + Vec2d(rr * std::cos(ph), rr * std::sin(ph)));
    }
    m.face_uvs.push_back(fu);
    m.face_groups.push_back(chart);
  }
  return m;
}

/// Torus (major radius 1, minor 0.4), n×k quads, one rectangular chart cut along two loops.
inline Mesh torus_atlas(int n, int k, double margin = 0.05) {
  Mesh m;
  const double pi = std::acos(-1.0);
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < n; ++i) {
      const double u = 2 * pi * i / n, v = 2 * pi * j / k;
      m.positions.push_back({(1 + 0.4 * std::cos(v)) * std::cos(u), (1 + 0.4 * std::cos(v)) * std::sin(u),
                             0.4 * std::sin(v)});
    }
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i <= n; ++i)
      m.uvs.push_back({margin + (1 - 2 * margin) * i / n, margin + (1 - 2 * margin) * j / k});
  auto vid = [&](int i, int j) { return (j % k) * n + (i % n); };
  auto tid = [&](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < n; ++i) {
      m.faces.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
      m.face_uvs.push_back({tid(i, j), tid(i + 1, j), tid(i + 1, j + 1)});
      m.faces.push_back({vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
      m.face_uvs.push_back({tid(i, j), tid(i + 1, j + 1), tid(i, j + 1)});
    }
  m.face_groups.assign(m.faces.size(), 0);
  return m;
}

/// Open cylinder (radius 1, height 2), n segments × k rows, two charts (the halves), two
/// boundary loops.
inline Mesh cylinder_atlas(int n, int k, double margin = 0.04) {
  Mesh m;
  const double pi = std::acos(-1.0);
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * pi * i / n;
      m.positions.push_back({std::cos(a), std::sin(a), -1.0 + 2.0 * j / k});
    }
  auto vid = [&](int i, int j) { return j * n + (i % n); };
  const int half = n / 2;
  for (int c = 0; c < 2; ++c) {
    const int base = static_cast<int>(m.uvs.size());
    const double u0 = c * 0.5 + margin, w = 0.5 - 2 * margin;
    for (int j = 0; j <= k; ++j)
      for (int i = 0; i <= half; ++i) m.uvs.push_back({u0 + w * i / half, margin + (1 - 2 * margin) * j / k});
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < half; ++i) {
        const int gi = c * half + i;
        auto t = [&](int ii, int jj) { return base + jj * (half + 1) + ii; };
        m.faces.push_back({vid(gi, j), vid(gi + 1, j), vid(gi + 1, j + 1)});
        m.face_uvs.push_back({t(i, j), t(i + 1, j), t(i + 1, j + 1)});
        m.faces.push_back({vid(gi, j), vid(gi + 1, j + 1), vid(gi, j + 1)});
        m.face_uvs.push_back({t(i, j), t(i + 1, j + 1), t(i, j + 1)});
        m.face_groups.push_back(c);
        m.face_groups.push_back(c);
      }
  }
  return m;
}

/// Unit square (z = 0), n×n quads, with the quad (hi, hj) left out: a hole 1/n wide. One chart,
/// opened into a disk by a zero-width slit along the grid line y = hj/n from the hole's corner
/// (hi + 1, hj) to the right edge, as the atlas builder slits a chart around a hole: the faces
/// below the slit use their own texture vertices there, `width` lower in texture space (0: at
/// the same positions; a stretch optimizer moves the two sides slightly apart).
inline Mesh slit_plane_atlas(int n, int hi, int hj, double width = 0.0, double margin = 0.05) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back({static_cast<double>(i) / n, static_cast<double>(j) / n, 0.0});
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.uvs.push_back({margin + (1 - 2 * margin) * i / n, margin + (1 - 2 * margin) * j / n});
  auto vid = [&](int i, int j) { return j * (n + 1) + i; };
  // The slit's second side: copies of the texture vertices on y = hj/n, x >= (hi + 1)/n.
  std::map<int, int> lower;
  for (int i = hi + 1; i <= n; ++i) {
    lower[i] = static_cast<int>(m.uvs.size());
    m.uvs.push_back(m.uvs[vid(i, hj)] - Vec2d{0.0, i > hi + 1 ? width : 0.0});
  }
  auto tid = [&](int i, int j, bool below) {
    if (below && j == hj && lower.count(i)) return lower[i];
    return vid(i, j);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (i == hi && j == hj) continue;
      const bool below = j == hj - 1;  // the quads touching the slit from below
      m.faces.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
      m.face_uvs.push_back({tid(i, j, below), tid(i + 1, j, below), tid(i + 1, j + 1, below)});
      m.faces.push_back({vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
      m.face_uvs.push_back({tid(i, j, below), tid(i + 1, j + 1, below), tid(i, j + 1, below)});
    }
  m.face_groups.assign(m.faces.size(), 0);
  return m;
}

}  // namespace mcgim_test
