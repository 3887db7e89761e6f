// Signal-specialized atlases (Iso-charts §7): signal-metric parameterization of charts and
// packing by signal-weighted chart size.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "atlas_charts.h"
#include "isochart/error.h"
#include "isochart/io.h"
#include "isochart/optimize.h"
#include "isochart/rng.h"
#include "isochart/signal.h"
#include "isochart/stretch.h"

namespace isochart {

namespace {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One chart of an atlas as its own small mesh (one vertex per texture coordinate).
std::vector<Imt> local_metric(const detail::AtlasChart& c, const std::vector<Imt>& metric) {
  std::vector<Imt> m(c.faces.size());
  for (size_t f = 0; f < c.faces.size(); ++f) m[f] = metric[c.faces[f]];
  return m;
}

// Σ A·tr(JᵀGJ) of a chart (its signal-metric energy) and its UV area.
void chart_energy(const detail::AtlasChart& c, const std::vector<Imt>& metric, double& energy, double& uv_area) {
  energy = uv_area = 0;
  for (size_t f = 0; f < c.tris.size(); ++f) {
    const Face& t = c.tris[f];
    const Vec3d& a = c.positions[t[0]];
    const Vec3d e1 = c.positions[t[1]] - a, e2 = c.positions[t[2]] - a;
    const double area = 0.5 * norm(cross(e1, e2));
    const Vec2d &p0 = c.uv[t[0]], &p1 = c.uv[t[1]], &p2 = c.uv[t[2]];
    const double d = cross(p1 - p0, p2 - p0);
    uv_area += 0.5 * std::abs(d);
    const double l1 = norm(e1);
    if (!(area > 0) || !(l1 > 0) || d == 0) continue;
    const double x1 = l1, x2 = dot(e2, e1 / l1), y2 = 2 * area / l1;
    const double inv = 1.0 / d;
    const Vec2d ss{(x1 * (p2.y - p0.y) + x2 * (p0.y - p1.y)) * inv, (y2 * (p0.y - p1.y)) * inv};
    const Vec2d st{(x1 * (p0.x - p2.x) + x2 * (p1.x - p0.x)) * inv, (y2 * (p1.x - p0.x)) * inv};
    const Imt& g = metric[c.faces[f]];
    energy += area * (g[0] * (ss.x * ss.x + st.x * st.x) + 2 * g[1] * (ss.x * ss.y + st.x * st.y) +
                      g[2] * (ss.y * ss.y + st.y * st.y));
  }
}

// Re-optimizes a chart in the signal metric; keeps the result only if it has no flip, no
// overlap and meets the geometric bounds. Returns true when the chart changed.
bool reoptimize(detail::AtlasChart& c, const std::vector<Imt>& metric, const AtlasOptions& o, double max_geometric_l2,
                std::uint64_t seed) {
  if (c.tris.size() < 2) return false;
  std::vector<Vec2d> uv = c.uv;
  OptimizeOptions opt;
  opt.passes = std::max(o.optimize_passes, 1) * 2;
  opt.max_linf = o.max_linf;
  opt.seed = seed;
  opt.face_metric = local_metric(c, metric);
  // Signal stretch pulls boundary notches shut where the signal changes fast, and texels
  // across such a pinch mix both sides' signal: on builtin:creature 91-94 % of the signal
  // error came from 0.01 % of the area, and the signal atlases lost to the geometric one.
  // (Geometric charts are left as they are: kept open there, gargoyle's atlas lost a merge
  // and its geometry image 23 dB.)
  opt.boundary_clearance = kSignalBoundaryClearance;
  optimize_stretch(c.positions, c.tris, uv, opt);
  const StretchStats st = measure_stretch(c.positions, c.tris, uv);
  if (st.flipped > 0 || !(st.linf <= o.max_linf * kStretchBoundSlack) ||
      !(st.l2 <= max_geometric_l2 * kStretchBoundSlack))
    return false;
  if (!uv_layout_is_embedding(c.tris, uv)) {
    std::vector<std::array<Vec2d, 3>> tris(c.tris.size());
    for (size_t f = 0; f < c.tris.size(); ++f)
      for (int k = 0; k < 3; ++k) tris[f][k] = uv[c.tris[f][k]];
    if (!overlapping_uv_pairs(tris, 1).empty()) return false;
  }
  c.uv = std::move(uv);
  return true;
}

// Packs the charts with UV area ∝ sqrt(E·A_uv): for a chart whose energy at UV scale s is
// E/s², minimizing Σ E_c/s_c² under a fixed total UV area Σ s_c²·A_c gives s_c⁴ ∝ E_c/A_c.
void pack_weighted(const Mesh& mesh, Atlas& atlas, std::vector<detail::AtlasChart>& charts,
                   const std::vector<Imt>& metric, const PackOptions& po, const Progress& progress) {
  std::vector<PackChart> pc(charts.size());
  double total_area = 0, total_weight = 0;
  for (size_t i = 0; i < charts.size(); ++i) {
    double e, a;
    chart_energy(charts[i], metric, e, a);
    pc[i].uv = charts[i].uv;
    pc[i].faces = charts[i].tris;
    pc[i].area_3d = std::sqrt(std::max(e, 0.0) * a);
    total_weight += pc[i].area_3d;
    for (int f : charts[i].faces) {
      const Face& F = mesh.faces[f];
      total_area += triangle_area(mesh.positions[F[0]], mesh.positions[F[1]], mesh.positions[F[2]]);
    }
  }
  // Same total as a geometric packing, so texel_size keeps its meaning on average.
  for (auto& c : pc)
    c.area_3d = total_weight > 0 && c.area_3d > 0 ? c.area_3d * total_area / total_weight : 0.0;
  const PackResult r = pack_charts(pc, po, progress);
  for (size_t i = 0; i < charts.size(); ++i) {
    charts[i].uv = pc[i].uv;
    for (size_t v = 0; v < charts[i].uv_ids.size(); ++v) atlas.uvs[charts[i].uv_ids[v]] = pc[i].uv[v];
  }
  const Mesh m = atlas.apply_to(mesh);
  const StretchStats st = measure_texture_stretch(m, static_cast<double>(po.width) / po.height);
  atlas.stats.l2 = st.l2;
  atlas.stats.linf = st.linf;
  atlas.stats.flipped = st.flipped;
  atlas.stats.overlapping_pairs = static_cast<long long>(overlapping_uv_pairs(m).size());
  atlas.stats.packing_ratio = r.packing_ratio;
  atlas.stats.seconds["packing"] += r.seconds;
}

// Per-vertex signal values: the linear signal's own, or a mapped signal averaged over the
// corners of each vertex.
std::vector<double> vertex_signal(const Mesh& mesh, const Signal& s) {
  if (!s.is_mapped()) return s.vertex_values;
  const int dim = s.dimension;
  std::vector<double> v(static_cast<size_t>(mesh.num_vertices()) * dim, 0.0), tmp(dim);
  std::vector<int> count(mesh.num_vertices(), 0);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      s.evaluate(mesh, f, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0, tmp.data());
      const int vi = mesh.faces[f][k];
      for (int c = 0; c < dim; ++c) v[static_cast<size_t>(vi) * dim + c] += tmp[c];
      ++count[vi];
    }
  for (int i = 0; i < mesh.num_vertices(); ++i)
    for (int c = 0; c < dim && count[i] > 0; ++c) v[static_cast<size_t>(i) * dim + c] /= count[i];
  return v;
}

}  // namespace

void validate_signal_options(const SignalAtlasOptions& so) {
  if (!(so.lambda >= 0) || !std::isfinite(so.lambda)) throw InputError("", "--lambda must be a number >= 0");
  if (!(so.chart_lambda >= 0) || !std::isfinite(so.chart_lambda))
    throw InputError("", "--chart-lambda must be a number >= 0");
  if (!(so.beta >= 0 && so.beta <= 1)) throw InputError("", "--beta must be in [0, 1]");
  if (!(so.split_efficiency >= 0 && so.split_efficiency <= 1))
    throw InputError("", "--split-efficiency must be in [0, 1]");
  if (!(so.max_geometric_l2 >= 1) || !std::isfinite(so.max_geometric_l2))
    throw InputError("", "--max-geometric-l2 must be a number >= 1 (1 is an isometry)");
}

Atlas build_signal_atlas(const Mesh& mesh, const Signal& signal, const AtlasOptions& options,
                         const SignalAtlasOptions& so, SignalAtlasStats* stats, const Progress& progress) {
  validate_options(options);
  validate_signal_options(so);
  auto t0 = std::chrono::steady_clock::now();
  const std::vector<Imt> imt = face_imt(mesh, signal);
  const std::vector<Imt> metric = signal_metric(mesh, imt, so.lambda);
  double seconds = since(t0);

  AtlasOptions o = options;
  if (so.use == SignalUse::Full) {
    o.face_metric = so.chart_lambda > 0 ? signal_metric(mesh, imt, so.chart_lambda) : metric;
    o.max_geometric_l2 = so.max_geometric_l2;
    o.signal_split_efficiency = so.split_efficiency;
    // A flat signal (face_imt zero everywhere) has no distances to add; a constant texture's
    // per-vertex values still differ by float rounding, which the distances' normalization
    // would turn into a full-weight signal.
    const bool flat = std::all_of(imt.begin(), imt.end(), [](const Imt& m) { return m == Imt{0, 0, 0}; });
    if (so.beta < 1 && !flat) {
      o.signal_beta = so.beta;
      o.signal_dimension = signal.dimension;
      o.vertex_signal = vertex_signal(mesh, signal);
    }
  }
  Atlas atlas = build_atlas(mesh, o, progress);

  SignalAtlasStats st;
  t0 = std::chrono::steady_clock::now();
  // The packed coordinates address a width × height texture: a unit of u is `aspect` times a
  // unit of v. Charts are optimized and measured in texels (u stretched back by `aspect`);
  // taken as they are, a 32:1 texture flattened every chart 32 times (L2 4.2 for 1.04).
  const double aspect = static_cast<double>(options.pack.width) / options.pack.height;
  auto in_texels = [aspect](std::vector<Vec2d> uv) {
    for (Vec2d& p : uv) p.x *= aspect;
    return uv;
  };
  if (so.use != SignalUse::None) {
    std::vector<detail::AtlasChart> charts = detail::split_atlas_charts(mesh, atlas);
    for (detail::AtlasChart& c : charts) c.uv = in_texels(std::move(c.uv));
    {
      // Geometric charts (Param) and signal charts (Full, whose parameterization only had to
      // meet the bound) are both optimized fully in the signal metric here.
      // A chart that cannot keep the geometric bounds at full signal weight tries a quarter.
      const std::vector<Imt> weak = signal_metric(mesh, imt, so.lambda / 4);
      std::vector<char> kept(charts.size(), 0);
      tbb::parallel_for(size_t(0), charts.size(), [&](size_t i) {
        const std::uint64_t seed =
            mix_seed(options.seed, static_cast<std::uint64_t>(charts[i].faces.front()));
        kept[i] = reoptimize(charts[i], metric, options, so.max_geometric_l2, seed) ||
                  reoptimize(charts[i], weak, options, so.max_geometric_l2, seed + 1);
      });
      for (char k : kept) st.reverted_charts += k ? 0 : 1;
    }
    pack_weighted(mesh, atlas, charts, metric, options.pack, progress);
    for (size_t i = 0; i < charts.size(); ++i) {
      const StretchStats cs = measure_stretch(charts[i].positions, charts[i].tris, in_texels(charts[i].uv));
      atlas.charts[i].l2 = cs.l2;
      atlas.charts[i].linf = cs.linf;
    }
  }
  Mesh m = atlas.apply_to(mesh);
  m.uvs = in_texels(std::move(m.uvs));
  st.signal_stretch = signal_stretch(m, imt);
  {
    std::vector<Vec2d> corner_uv;
    std::vector<Face> tris(mesh.num_faces());
    std::vector<Vec3d> pos;
    pos.reserve(3 * mesh.faces.size());
    corner_uv.reserve(3 * mesh.faces.size());
    for (int f = 0; f < mesh.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) {
        pos.push_back(mesh.positions[mesh.faces[f][k]]);
        corner_uv.push_back(m.uvs[m.face_uvs[f][k]]);
        tris[f][k] = 3 * f + k;
      }
    st.metric_l2 = metric_l2_stretch(pos, tris, corner_uv, metric);
  }
  seconds += since(t0);
  st.seconds = seconds;
  atlas.stats.seconds["signal"] = seconds;
  if (stats) *stats = st;
  return atlas;
}

void write_imt(const std::string& path, const std::vector<Imt>& imt) {
  std::string out;
  out.reserve(imt.size() * 48);
  char buf[96];
  for (const Imt& g : imt) {
    std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", g[0], g[1], g[2]);
    out += buf;
  }
  write_file_atomic(path, out);
}

}  // namespace isochart
