// Per-level local geometry for neighbourhood gathering: tangent frames, the image-to-surface
// Jacobian of each sample, and taps that cross chart seams through the surface.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "isochart/error.h"
#include "synth/synth.h"

namespace synth {

using isochart::Vec2d;
using isochart::Vec3d;

struct LevelGeometry::Impl {
  const mcgim::GeometryImage* img = nullptr;
  std::vector<Vec3d> t1, t2, dx, dy, gx, gy;
  std::vector<double> texel;
  double cell = 1;
  double texel_level = 1;
  Vec3d origin;
  std::vector<std::pair<std::uint64_t, int>> hash;  // sorted (cell key, sample)

  std::uint64_t key(long long ix, long long iy, long long iz) const {
    const long long o = 1 << 20;
    return (std::uint64_t(ix + o) << 42) | (std::uint64_t(iy + o) << 21) | std::uint64_t(iz + o);
  }
  std::array<long long, 3> cell_of(const Vec3d& p) const {
    return {static_cast<long long>(std::floor((p.x - origin.x) / cell)),
            static_cast<long long>(std::floor((p.y - origin.y) / cell)),
            static_cast<long long>(std::floor((p.z - origin.z) / cell))};
  }
  bool in_chart(int x, int y, int chart) const {
    return x >= 0 && y >= 0 && x < img->width && y < img->height && img->chart[img->index(x, y)] == chart;
  }
  // Bilinear lookup in `chart` at continuous image position xy; weights of corners outside the
  // chart are dropped. Returns the in-chart weight before renormalization.
  double bilinear(Vec2d xy, int chart, Tap& tap) const {
    tap = Tap{};
    // Far outside the image (or not a number): no sample; keeps the int conversions defined.
    if (!(std::fabs(xy.x) < 1e6 && std::fabs(xy.y) < 1e6)) return 0;
    const double fx = xy.x - 0.5, fy = xy.y - 0.5;
    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
    const double ax = fx - x0, ay = fy - y0;
    const int xs[4] = {x0, x0 + 1, x0, x0 + 1}, ys[4] = {y0, y0, y0 + 1, y0 + 1};
    const double ws[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
    double sum = 0;
    int k = 0;
    tap = Tap{};
    for (int c = 0; c < 4; ++c) {
      if (ws[c] <= 1e-9 || !in_chart(xs[c], ys[c], chart)) continue;
      tap.sample[k] = img->index(xs[c], ys[c]);
      tap.weight[k] = static_cast<float>(ws[c]);
      sum += ws[c];
      ++k;
    }
    if (sum > 0)
      for (int c = 0; c < k; ++c) tap.weight[c] = static_cast<float>(tap.weight[c] / sum);
    return sum;
  }
  Vec2d centre(int s) const { return {s % img->width + 0.5, s / img->width + 0.5}; }
  // Nearest sample to q whose normal is within about 80 degrees of `n`, or -1.
  int nearest(const Vec3d& q, const Vec3d& n) const {
    const auto cq = cell_of(q);
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (long long i = cq[0] - 1; i <= cq[0] + 1; ++i)
      for (long long j = cq[1] - 1; j <= cq[1] + 1; ++j)
        for (long long k = cq[2] - 1; k <= cq[2] + 1; ++k) {
          const std::uint64_t kk = key(i, j, k);
          auto it = std::lower_bound(hash.begin(), hash.end(), std::make_pair(kk, -1));
          for (; it != hash.end() && it->first == kk; ++it) {
            const int s = it->second;
            if (isochart::dot(img->normals[s], n) < 0.2) continue;
            const double d = isochart::squared_norm(img->positions[s] - q);
            if (d < best_d || (d == best_d && s < best)) best_d = d, best = s;
          }
        }
    return best;
  }
};

LevelGeometry::LevelGeometry(const mcgim::Level& level, const std::vector<Vec3d>& directions)
    : impl_(new Impl) {
  const mcgim::GeometryImage& g = level.image;
  Impl& m = *impl_;
  m.img = &g;
  const int n = g.width * g.height;
  if (static_cast<int>(directions.size()) != n)
    throw isochart::Error("synth: direction array does not match the geometry image");
  m.t1.assign(n, {});
  m.t2.assign(n, {});
  m.dx.assign(n, {});
  m.dy.assign(n, {});
  m.gx.assign(n, {});
  m.gy.assign(n, {});
  m.texel.assign(n, 0);
  const double texel = level.stats.texel_size > 0 ? level.stats.texel_size : 1.0;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int s = g.index(x, y);
      if (!g.defined(s)) continue;
      const int c = g.chart[s];
      const Vec3d nrm = g.normals[s];
      // Central differences where both neighbours are in the chart, one-sided otherwise.
      auto diff = [&](int ddx, int ddy, Vec3d& out) {
        const bool fwd = m.in_chart(x + ddx, y + ddy, c), bwd = m.in_chart(x - ddx, y - ddy, c);
        if (fwd && bwd) out = (g.positions[g.index(x + ddx, y + ddy)] - g.positions[g.index(x - ddx, y - ddy)]) * 0.5;
        else if (fwd) out = g.positions[g.index(x + ddx, y + ddy)] - g.positions[s];
        else if (bwd) out = g.positions[s] - g.positions[g.index(x - ddx, y - ddy)];
        else return false;
        return isochart::norm(out) > 1e-12 * texel;
      };
      Vec3d ex, ey;
      const bool hx = diff(1, 0, ex), hy = diff(0, 1, ey);
      const double sign = (c < static_cast<int>(g.chart_mirrored.size()) && g.chart_mirrored[c]) ? -1.0 : 1.0;
      // A missing direction is completed so that (dx, dy, n) keeps the chart's orientation.
      if (hx && !hy) ey = isochart::cross(nrm, ex) * sign;
      if (hy && !hx) ex = isochart::cross(ey, nrm) * sign;
      if (!hx && !hy) {
        Vec3d a = std::fabs(nrm.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
        ex = isochart::normalized(a - nrm * isochart::dot(a, nrm)) * texel;
        ey = isochart::cross(nrm, ex) * sign;
      }
      double a = isochart::dot(ex, ex), b = isochart::dot(ex, ey), cc = isochart::dot(ey, ey);
      double det = a * cc - b * b;
      if (!(det > 1e-12 * a * cc)) {  // collinear differences: rebuild dy from dx
        ey = isochart::cross(nrm, ex) * sign;
        a = isochart::dot(ex, ex), b = isochart::dot(ex, ey), cc = isochart::dot(ey, ey);
        det = a * cc - b * b;
      }
      m.dx[s] = ex;
      m.dy[s] = ey;
      m.gx[s] = (ex * cc - ey * b) * (1.0 / det);
      m.gy[s] = (ey * a - ex * b) * (1.0 / det);
      m.texel[s] = std::sqrt(isochart::norm(isochart::cross(ex, ey)));
      Vec3d d = directions[s] - nrm * isochart::dot(directions[s], nrm);
      if (isochart::norm(d) < 1e-9) d = ex - nrm * isochart::dot(ex, nrm);
      m.t1[s] = isochart::normalized(d);
      m.t2[s] = isochart::cross(nrm, m.t1[s]);
    }
  }
  // Spatial hash of the samples, cells about two texels wide.
  m.cell = 2.0 * texel;
  m.texel_level = texel;
  m.origin = {0, 0, 0};
  bool first = true;
  for (int s = 0; s < n; ++s) {
    if (!g.defined(s)) continue;
    if (first) m.origin = g.positions[s], first = false;
    m.origin = {std::min(m.origin.x, g.positions[s].x), std::min(m.origin.y, g.positions[s].y),
                std::min(m.origin.z, g.positions[s].z)};
  }
  for (int s = 0; s < n; ++s) {
    if (!g.defined(s)) continue;
    const auto c = m.cell_of(g.positions[s]);
    m.hash.push_back({m.key(c[0], c[1], c[2]), s});
  }
  std::sort(m.hash.begin(), m.hash.end());
}

LevelGeometry::~LevelGeometry() { delete impl_; }
LevelGeometry::LevelGeometry(LevelGeometry&& o) noexcept : impl_(o.impl_) { o.impl_ = nullptr; }
LevelGeometry& LevelGeometry::operator=(LevelGeometry&& o) noexcept {
  std::swap(impl_, o.impl_);
  return *this;
}

Vec3d LevelGeometry::t1(int s) const { return impl_->t1[s]; }
Vec3d LevelGeometry::t2(int s) const { return impl_->t2[s]; }
Vec3d LevelGeometry::dpdx(int s) const { return impl_->dx[s]; }
Vec3d LevelGeometry::dpdy(int s) const { return impl_->dy[s]; }
double LevelGeometry::texel_size(int s) const { return impl_->texel[s]; }

Vec3d LevelGeometry::position(const Tap& t) const {
  Vec3d p{0, 0, 0};
  for (int k = 0; k < 4; ++k)
    if (t.sample[k] >= 0) p = p + impl_->img->positions[t.sample[k]] * double(t.weight[k]);
  return p;
}

Tap LevelGeometry::locate(int s, double a, double b) const {
  return locate(impl_->centre(s), impl_->img->chart[s], s, a, b);
}

Tap LevelGeometry::locate(Vec2d xy, int chart, int frame, double a, double b) const {
  const Impl& m = *impl_;
  const mcgim::GeometryImage& g = *m.img;
  const Vec3d w = m.t1[frame] * a + m.t2[frame] * b;
  Tap tap;
  const Vec2d target{xy.x + isochart::dot(m.gx[frame], w), xy.y + isochart::dot(m.gy[frame], w)};
  if (m.bilinear(target, chart, tap) > 1 - 1e-9) return tap;
  // The tap leaves the chart: walk the offset over the surface in steps of half a texel,
  // snapping to the nearest sample facing the same way (which may belong to the neighbour
  // chart across the seam) and turning the direction with the normal, so that the walk
  // unfolds across seams and creases alike.
  const Vec2d c0 = m.centre(frame);
  Vec3d p = g.positions[frame] + m.dx[frame] * (xy.x - c0.x) + m.dy[frame] * (xy.y - c0.y);
  Vec3d nrm = g.normals[frame];
  double remaining = isochart::norm(w);
  if (remaining <= 0) return tap;
  Vec3d dir = w / remaining;
  const double step = 0.5 * m.texel_level;
  int best = frame;
  for (int iter = 0; remaining > 1e-9 * step && iter < 1000; ++iter) {
    const double h = std::min(remaining, step);
    remaining -= h;
    const Vec3d q = p + dir * h;
    best = m.nearest(q, nrm);
    if (best < 0) return Tap{};
    const double reach = 1.2 * std::max(isochart::norm(m.dx[best]), isochart::norm(m.dy[best]));
    const Vec3d nb = g.normals[best];
    const double off = isochart::dot(q - g.positions[best], nb);
    const Vec3d r = q - nb * off;
    if (isochart::norm(r - g.positions[best]) > reach) return Tap{};  // off the mesh boundary
    // Turn the direction by the rotation taking the old normal to the new one.
    const Vec3d axis = isochart::cross(nrm, nb);
    const double sn = isochart::norm(axis), cs = isochart::dot(nrm, nb);
    if (sn > 1e-12) {
      const Vec3d k = axis / sn;
      dir = dir * cs + isochart::cross(k, dir) * sn + k * (isochart::dot(k, dir) * (1 - cs));
    }
    dir = dir - nb * isochart::dot(dir, nb);
    if (isochart::norm(dir) < 1e-12) return Tap{};
    dir = isochart::normalized(dir);
    p = r;
    nrm = nb;
  }
  const Vec3d rr = p - g.positions[best];
  const Vec2d cb = m.centre(best);
  const Vec2d xyb{cb.x + isochart::dot(m.gx[best], rr), cb.y + isochart::dot(m.gy[best], rr)};
  if (m.bilinear(xyb, g.chart[best], tap) <= 0) {
    tap = Tap{};
    tap.sample[0] = best;
    tap.weight[0] = 1;
  }
  tap.crossed = g.chart[best] != chart;
  return tap;
}

}  // namespace synth
