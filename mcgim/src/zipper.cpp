#include "zipper.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "isochart/error.h"
#include "isochart/union_find.h"

namespace mcgim::detail {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Squared distance from p to segment ab; f receives the parameter of the closest point.
double segment_distance2(const Vec2d& p, const Vec2d& a, const Vec2d& b, double& f) {
  const Vec2d d = b - a;
  const double len2 = dot(d, d);
  f = len2 > 0 ? std::clamp(dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
  const Vec2d q = a + d * f;
  return squared_norm(p - q);
}

Vec2d sample_centre(int index, int width) {
  return {index % width + 0.5, index / width + 0.5};
}

// A side's samples from its start node to its end node, ordered along the cut path (start to
// end), with their arc length on the path.
struct Chain {
  std::vector<int> samples;
  std::vector<double> t;
  std::vector<Vec2d> texel;  // where each sample was snapped to, in its chart's texel space
};

struct ChartZip {
  std::vector<Chain> chains;  // per side of the chart (ch.sides order)
};

// Aligns the ring with the boundary loop: a cyclically non-decreasing loop parameter per ring
// sample minimizing the summed squared texel distance, anchored where ring and loop are
// closest. Returns the parameter relative to the anchor (in [0, L]) per ring sample, ring
// rotated so that the anchor sample comes first (`rotation` is the anchor's ring index).
std::vector<double> align_ring(const std::vector<Vec2d>& loop_pts, const std::vector<Vec2d>& ring_pts,
                               double& anchor_param, int& rotation) {
  const int L = static_cast<int>(loop_pts.size());
  const int m = static_cast<int>(ring_pts.size());
  // Cost of matching ring sample j with (the closest point of) loop edge e: squared texel
  // distance plus a term against opposite directions. Both run with the chart on their left,
  // so the direction tells apart the two sides of a slit or of a thin part, which lie at the
  // same distance.
  const double direction_weight = 1.0;
  std::vector<Vec2d> edge_dir(L), tangent(m);
  for (int e = 0; e < L; ++e) edge_dir[e] = normalized(loop_pts[(e + 1) % L] - loop_pts[e]);
  for (int j = 0; j < m; ++j) tangent[j] = normalized(ring_pts[(j + 1) % m] - ring_pts[(j + m - 1) % m]);
  auto direction_cost = [&](int j, int e) {
    if (squared_norm(edge_dir[e]) == 0 || squared_norm(tangent[j]) == 0) return 0.0;
    return direction_weight * (1.0 - dot(edge_dir[e], tangent[j]));
  };
  std::vector<double> d2(static_cast<std::size_t>(m) * L), fr(static_cast<std::size_t>(m) * L);
  std::vector<double> dmin(m, kInf);
  int best_j = 0, best_e = 0;
  double best_c = kInf;
  for (int j = 0; j < m; ++j)
    for (int e = 0; e < L; ++e) {
      double f;
      const double d = segment_distance2(ring_pts[j], loop_pts[e], loop_pts[(e + 1) % L], f);
      d2[static_cast<std::size_t>(j) * L + e] = d;
      fr[static_cast<std::size_t>(j) * L + e] = f;
      dmin[j] = std::min(dmin[j], d);
      const double c = d + direction_cost(j, e);
      if (c < best_c) {
        best_c = c;
        best_j = j;
        best_e = e;
      }
    }
  rotation = best_j;
  anchor_param = best_e + fr[static_cast<std::size_t>(best_j) * L + best_e];
  const double anchor_f = fr[static_cast<std::size_t>(best_j) * L + best_e];

  // Dense dynamic programming over (ring sample, loop edge): sample k maps to its closest point
  // on one edge; edges are taken in loop order from the anchor, state q = 0 being the anchor's
  // edge after the anchor, q = L the same edge before it. Staying on an edge is always
  // allowed (closest points on one edge need not come in order; the parameters are made
  // monotone afterwards), so the alignment always exists.
  const int Q = L + 1;
  auto edge_of = [&](int q) { return (best_e + (q == L ? 0 : q)) % L; };
  auto valid = [&](int j, int q) {
    if (q != 0 && q != L) return true;
    const double f = fr[static_cast<std::size_t>(j) * L + best_e];
    return q == 0 ? f >= anchor_f : f < anchor_f;
  };
  auto param = [&](int j, int q) {
    const double f = fr[static_cast<std::size_t>(j) * L + edge_of(q)];
    return q == 0 ? f - anchor_f : (q == L ? L - anchor_f + f : q - anchor_f + f);
  };
  std::vector<int> back(static_cast<std::size_t>(m) * Q, -1);
  std::vector<double> prev(Q, kInf), cur(Q, kInf);
  prev[0] = 0.0;  // the anchor sample sits at the anchor
  for (int k = 1; k < m; ++k) {
    const int j = (rotation + k) % m;
    double run = kInf;
    int run_q = -1;
    for (int q = 0; q < Q; ++q) {
      if (prev[q] < run) {
        run = prev[q];
        run_q = q;
      }
      cur[q] = kInf;
      if (run_q < 0 || !valid(j, q)) continue;
      const int e = edge_of(q);
      cur[q] = run + d2[static_cast<std::size_t>(j) * L + e] + direction_cost(j, e);
      back[static_cast<std::size_t>(k) * Q + q] = run_q;
    }
    std::swap(prev, cur);
  }
  int q = static_cast<int>(std::min_element(prev.begin(), prev.end()) - prev.begin());
  std::vector<double> r(m, 0.0);
  for (int k = m - 1; k >= 1; --k) {
    r[k] = param((rotation + k) % m, q);
    q = back[static_cast<std::size_t>(k) * Q + q];
  }
  for (int k = 1; k < m; ++k) r[k] = std::clamp(r[k], r[k - 1], static_cast<double>(L));
  return r;
}

// Builds the chains of every side of a chart with samples.
ChartZip zip_chart(const AtlasCharts& a, const Placement& pl, int c, const std::vector<int>& ring,
                   int width) {
  const Chart& ch = a.charts[c];
  const int L = static_cast<int>(ch.loop.size());
  const int m = static_cast<int>(ring.size());
  std::vector<Vec2d> loop_pts(L), ring_pts(m);
  for (int i = 0; i < L; ++i) loop_pts[i] = pl.texel[c][ch.loop[i]];
  for (int j = 0; j < m; ++j) ring_pts[j] = sample_centre(ring[j], width);
  double anchor = 0;
  int rotation = 0;
  const std::vector<double> r = align_ring(loop_pts, ring_pts, anchor, rotation);
  // Ring in anchor order, extended by one wrap so index u in [0, 2m] is valid.
  auto ring_at = [&](int u) { return ring[(rotation + u) % m]; };
  auto r_at = [&](int u) { return u < m ? r[u] : r[u - m] + L; };

  ChartZip z;
  z.chains.resize(ch.sides.size());
  const int n = static_cast<int>(ch.sides.size());
  const Side& first = a.sides[ch.sides[0]];
  if (!first.has_nodes) {
    // A whole loop on the mesh boundary: every ring sample lies on the one open path.
    const CutPath& path = a.paths[first.path];
    Chain& chain = z.chains[0];
    for (int u = 0; u < m; ++u) {
      double v = std::fmod(anchor + r[u], static_cast<double>(L));
      const int e = std::min(static_cast<int>(std::floor(v)), L - 1);
      const double f = std::clamp(v - e, 0.0, 1.0);
      chain.samples.push_back(ring_at(u));
      chain.t.push_back(path.arclen[e] + f * (path.arclen[e + 1] - path.arclen[e]));
      chain.texel.push_back(loop_pts[e] * (1 - f) + loop_pts[(e + 1) % L] * f);
    }
    return z;
  }
  // Nodes (side starts) relative to the anchor, assigned to ring samples in order.
  std::vector<double> node_r(n);
  for (int k = 0; k < n; ++k) {
    double v = a.sides[ch.sides[k]].first_edge - anchor;
    if (v < 0) v += L;
    node_r[k] = v;
  }
  std::vector<int> order(n);
  for (int k = 0; k < n; ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return node_r[x] < node_r[y]; });
  // A cut between two points of the mesh boundary must keep two distinct samples on each
  // side: contracting it would pinch the boundary (two holes touching at a vertex).
  auto keep_apart = [&](int k) {
    const Side& before = a.sides[ch.sides[(k + n - 1) % n]];
    const CutPath& p = a.paths[before.path];
    return p.side_b >= 0 && a.topology.is_boundary_vertex(p.vertices.front()) &&
           a.topology.is_boundary_vertex(p.vertices.back());
  };
  std::vector<int> assigned(n, 0);
  int prev = 0;
  bool first_node = true;
  for (int k : order) {
    const double rn = node_r[k];
    // Largest u in [0, m-1] with r_at(u) <= rn; r is non-decreasing and r[0] = 0 <= rn.
    int u = static_cast<int>(std::upper_bound(r.begin(), r.end(), rn) - r.begin()) - 1;
    u = std::max(u, 0);
    const Vec2d node_pt = loop_pts[a.sides[ch.sides[k]].first_edge];
    const double d0 = squared_norm(ring_pts[(rotation + u) % m] - node_pt);
    const double d1 = squared_norm(ring_pts[(rotation + u + 1) % m] - node_pt);
    int choice = d1 < d0 ? u + 1 : u;
    choice = std::max(choice, prev);
    if (!first_node && n > 1 && keep_apart(k) && choice == prev && prev + 1 <= m) ++choice;
    assigned[k] = choice;
    prev = choice;
    first_node = false;
  }
  const int last_in_order = order.back();
  for (int k = 0; k < n; ++k) {
    const Side& s = a.sides[ch.sides[k]];
    const CutPath& path = a.paths[s.path];
    const int start = assigned[k];
    const int end = (n == 1 || k == last_in_order) ? assigned[(k + 1) % n] + m : assigned[(k + 1) % n];
    const double rs = node_r[k];
    Chain& chain = z.chains[k];
    for (int u = start; u <= end; ++u) {
      double t;
      if (u == start) {
        t = s.reversed ? path.length() : 0.0;
        chain.texel.push_back(loop_pts[s.first_edge]);
      } else if (u == end) {
        t = s.reversed ? 0.0 : path.length();
        chain.texel.push_back(loop_pts[(s.first_edge + s.num_edges) % L]);
      } else {
        double v = r_at(u) - rs;
        if (v < 0) v += L;
        v = std::clamp(v, 0.0, static_cast<double>(s.num_edges));
        const int jl = std::min(static_cast<int>(std::floor(v)), s.num_edges - 1);
        const double f = std::clamp(v - jl, 0.0, 1.0);
        const int e = (s.first_edge + jl) % L;
        chain.texel.push_back(loop_pts[e] * (1 - f) + loop_pts[(e + 1) % L] * f);
        if (!s.reversed) {
          t = path.arclen[jl] + f * (path.arclen[jl + 1] - path.arclen[jl]);
        } else {
          const int pe = s.num_edges - 1 - jl;
          t = path.arclen[pe + 1] - f * (path.arclen[pe + 1] - path.arclen[pe]);
        }
      }
      chain.samples.push_back(ring_at(u));
      chain.t.push_back(t);
    }
    if (s.reversed) {
      std::reverse(chain.samples.begin(), chain.samples.end());
      std::reverse(chain.t.begin(), chain.t.end());
      std::reverse(chain.texel.begin(), chain.texel.end());
    }
    // Guard the monotone order against rounding.
    for (std::size_t i = 1; i < chain.t.size(); ++i) chain.t[i] = std::max(chain.t[i], chain.t[i - 1]);
  }
  return z;
}

// The point at arc length t of a side's path, in the texel space of the side's chart.
Vec2d side_texel(const AtlasCharts& a, const Placement& pl, int sid, double t) {
  const Side& s = a.sides[sid];
  const Chart& ch = a.charts[s.chart];
  const CutPath& p = a.paths[s.path];
  const int L = static_cast<int>(ch.loop.size());
  const int n = static_cast<int>(p.vertices.size()) - 1;  // path edges
  int pe = static_cast<int>(std::upper_bound(p.arclen.begin(), p.arclen.end(), t) - p.arclen.begin()) - 1;
  pe = std::clamp(pe, 0, n - 1);
  const double len = p.arclen[pe + 1] - p.arclen[pe];
  double f = len > 0 ? std::clamp((t - p.arclen[pe]) / len, 0.0, 1.0) : 0.0;
  int jl = pe;
  if (s.reversed) {
    jl = s.num_edges - 1 - pe;
    f = 1 - f;
  }
  const int e = (s.first_edge + jl) % L;
  return pl.texel[s.chart][ch.loop[e]] * (1 - f) + pl.texel[s.chart][ch.loop[(e + 1) % L]] * f;
}

// Merges the two chains of a cut path into a monotone sequence of groups, each holding one
// sample of one side and one or more consecutive samples of the other (dynamic time warping
// with that "star" constraint), minimizing the summed squared arc-length differences.
void merge_chains(const Chain& A, const Chain& B, isochart::UnionFind& uf) {
  const int M = static_cast<int>(A.samples.size()) - 1;
  const int N = static_cast<int>(B.samples.size()) - 1;
  auto cost = [&](int i, int j) {
    const double d = A.t[i] - B.t[j];
    return d * d;
  };
  const long long cells = static_cast<long long>(M + 1) * (N + 1);
  if (cells > 16'000'000) {
    // Too long for the table: a greedy monotone merge with the same constraint.
    int i = 0, j = 0, state = 0;  // 0 diagonal, 1 advancing A, 2 advancing B
    uf.unite(A.samples[0], B.samples[0]);
    while (i < M || j < N) {
      if (i == M) {
        ++j;
      } else if (j == N) {
        ++i;
      } else {
        const double dd = cost(i + 1, j + 1);
        const double dh = state != 2 ? cost(i + 1, j) : kInf;
        const double dv = state != 1 ? cost(i, j + 1) : kInf;
        if (dd <= dh && dd <= dv) {
          ++i;
          ++j;
          state = 0;
        } else if (dh <= dv) {
          ++i;
          state = 1;
        } else {
          ++j;
          state = 2;
        }
      }
      uf.unite(A.samples[i], B.samples[j]);
    }
    return;
  }
  // back: bits 0-1 predecessor state of D, bit 2 of H (0 D, 1 H), bit 3 of V (0 D, 1 V).
  std::vector<std::uint8_t> back(static_cast<std::size_t>(cells), 0);
  std::vector<double> pD(N + 1, kInf), pH(N + 1, kInf), pV(N + 1, kInf);
  std::vector<double> cD(N + 1, kInf), cH(N + 1, kInf), cV(N + 1, kInf);
  for (int i = 0; i <= M; ++i) {
    for (int j = 0; j <= N; ++j) {
      const double c = cost(i, j);
      std::uint8_t b = 0;
      double d = kInf, h = kInf, v = kInf;
      if (i == 0 && j == 0) {
        d = c;
      } else {
        if (i > 0 && j > 0) {
          double best = pD[j - 1];
          int s = 0;
          if (pH[j - 1] < best) best = pH[j - 1], s = 1;
          if (pV[j - 1] < best) best = pV[j - 1], s = 2;
          d = best + c;
          b |= static_cast<std::uint8_t>(s);
        }
        if (i > 0) {
          const bool from_h = pH[j] < pD[j];
          h = (from_h ? pH[j] : pD[j]) + c;
          if (from_h) b |= 4;
        }
        if (j > 0) {
          const bool from_v = cV[j - 1] < cD[j - 1];
          v = (from_v ? cV[j - 1] : cD[j - 1]) + c;
          if (from_v) b |= 8;
        }
      }
      cD[j] = d;
      cH[j] = h;
      cV[j] = v;
      back[static_cast<std::size_t>(i) * (N + 1) + j] = b;
    }
    std::swap(pD, cD);
    std::swap(pH, cH);
    std::swap(pV, cV);
  }
  int state = 0;
  if (pH[N] < pD[N]) state = 1;
  if (pV[N] < (state == 1 ? pH[N] : pD[N])) state = 2;
  int i = M, j = N;
  for (;;) {
    uf.unite(A.samples[i], B.samples[j]);
    if (i == 0 && j == 0) break;
    const std::uint8_t b = back[static_cast<std::size_t>(i) * (N + 1) + j];
    if (state == 0) {
      state = b & 3;
      --i;
      --j;
    } else if (state == 1) {
      state = (b & 4) ? 1 : 0;
      --i;
    } else {
      state = (b & 8) ? 2 : 0;
      --j;
    }
  }
}

}  // namespace

ZipperStats zipper(const AtlasCharts& a, const Placement& pl, Sampling& sm,
                   const isochart::Progress& progress) {
  GeometryImage& im = sm.image;
  const Mesh& mesh = *a.mesh;
  const int W = im.width;
  const int N = W * im.height;
  const int nc = static_cast<int>(a.charts.size());
  isochart::report(progress, isochart::Stage::Zippering, 0.0);
  std::vector<ChartZip> zips(nc);
  tbb::parallel_for(0, nc, [&](int c) {
    if (!sm.regions[c].ring.empty()) zips[c] = zip_chart(a, pl, c, sm.regions[c].ring, W);
  });
  isochart::report(progress, isochart::Stage::Zippering, 0.5);

  ZipperStats st;
  auto chain_of = [&](int sid) -> const Chain* {
    const Side& s = a.sides[sid];
    if (zips[s.chart].chains.empty()) return nullptr;
    const Chart& ch = a.charts[s.chart];
    const int k = static_cast<int>(std::find(ch.sides.begin(), ch.sides.end(), sid) - ch.sides.begin());
    return &zips[s.chart].chains[k];
  };
  // Union-find over samples and mesh vertices (nodes are N + vertex).
  isochart::UnionFind uf(0);
  // Where a ring sample lies on a path (for the positions of groups without nodes).
  std::vector<int> on_path;
  std::vector<double> on_t;
  for (;;) {
    uf = isochart::UnionFind(N + mesh.num_vertices());
    on_path.assign(N, -1);
    on_t.assign(N, 0.0);
    st.cut_paths = 0;
    for (std::size_t pid = 0; pid < a.paths.size(); ++pid) {
      const CutPath& p = a.paths[pid];
      const Side& sa = a.sides[p.side_a];
      const Chain* A = chain_of(p.side_a);
      const Chain* B = p.side_b >= 0 ? chain_of(p.side_b) : nullptr;
      const int vs = N + p.vertices.front(), ve = N + p.vertices.back();
      for (const Chain* ch : {A, B}) {
        if (!ch) continue;
        for (std::size_t i = 0; i < ch->samples.size(); ++i) {
          if (sa.has_nodes && (i == 0 || i + 1 == ch->samples.size())) continue;
          on_path[ch->samples[i]] = static_cast<int>(pid);
          on_t[ch->samples[i]] = ch->t[i];
        }
        if (sa.has_nodes) {
          uf.unite(ch->samples.front(), vs);
          uf.unite(ch->samples.back(), ve);
        }
      }
      if (p.side_b < 0) continue;
      ++st.cut_paths;
      if (A && B) {
        merge_chains(*A, *B, uf);
      } else if (A || B) {
        // The other side is an empty chart, contracted to a point: so is this side.
        for (int smp : (A ? A : B)->samples) uf.unite(smp, vs);
        uf.unite(vs, ve);
      } else {
        uf.unite(vs, ve);
      }
    }
    // A path whose two ends fell into one group (a short path elsewhere was contracted) must
    // keep at least two distinct groups inside on each side, or its two halves would become
    // one edge with four faces: contract it too. Repeat, as this can close other such loops.
    // (Node groups are found through the node ids N + vertex; any member works for unite.)
    for (bool again = true; again;) {
      again = false;
      for (const CutPath& p : a.paths) {
        const int vs = N + p.vertices.front(), ve = N + p.vertices.back();
        if (uf.find(vs) != uf.find(ve)) continue;
        const int node = uf.find(vs);
        bool thin = false;
        for (int sid : {p.side_a, p.side_b}) {
          if (sid < 0) continue;
          const Chain* ch = chain_of(sid);
          if (!ch) continue;
          std::vector<int> inner;
          for (int smp : ch->samples)
            if (uf.find(smp) != node) inner.push_back(uf.find(smp));
          std::sort(inner.begin(), inner.end());
          inner.erase(std::unique(inner.begin(), inner.end()), inner.end());
          if (!inner.empty() && inner.size() < 2) thin = true;
        }
        if (!thin) continue;
        for (int sid : {p.side_a, p.side_b}) {
          if (sid < 0) continue;
          if (const Chain* ch = chain_of(sid))
            for (int smp : ch->samples) uf.unite(smp, vs);
        }
        again = true;
      }
      // Likewise two cut paths reduced to the same single edge (no group between their ends)
      // would give that edge four faces: contract that edge.
      std::vector<std::array<int, 2>> single;
      for (const CutPath& p : a.paths) {
        if (p.side_b < 0) continue;
        const int gs = uf.find(N + p.vertices.front()), ge = uf.find(N + p.vertices.back());
        if (gs == ge) continue;
        const Chain* ch = chain_of(p.side_a);
        if (!ch) ch = chain_of(p.side_b);
        if (!ch) continue;
        bool inner = false;
        for (int smp : ch->samples) {
          const int g = uf.find(smp);
          inner = inner || (g != gs && g != ge);
        }
        if (!inner) single.push_back({std::min(gs, ge), std::max(gs, ge)});
      }
      std::sort(single.begin(), single.end());
      for (std::size_t i = 1; i < single.size(); ++i)
        if (single[i] == single[i - 1] && uf.find(single[i][0]) != uf.find(single[i][1])) {
          uf.unite(single[i][0], single[i][1]);
          again = true;
        }
    }
    // A chart whose ring now spans fewer than three groups would close up into a pocket
    // (its boundary contracted without its interior, e.g. an island chart in a hole too small
    // to be sampled): contract it entirely instead, and zipper again.
    bool emptied = false;
    for (int c = 0; c < nc; ++c) {
      const std::vector<int>& ring = sm.regions[c].ring;
      if (ring.empty()) continue;
      int distinct = 0;
      const int last = uf.find(ring.back());
      int prev = last;
      for (int smp : ring) {
        const int g = uf.find(smp);
        if (g != prev) ++distinct;
        prev = g;
      }
      if (distinct >= 3) continue;
      ChartRegion& reg = sm.regions[c];
      for (int smp : reg.samples) {
        im.chart[smp] = -1;
        im.face[smp] = -1;
        im.barycentric[smp] = {};
        im.positions[smp] = {};
        im.normals[smp] = {};
      }
      reg.removed += static_cast<long long>(reg.samples.size());
      sm.removed += static_cast<long long>(reg.samples.size());
      reg.samples.clear();
      reg.ring.clear();
      zips[c].chains.clear();
      emptied = true;
    }
    if (!emptied) break;
  }
  st.strained.assign(nc, 0);
  for (int c = 0; c < nc; ++c)
    if (sm.regions[c].ring.empty()) {
      ++st.empty_charts;
      st.strained[c] = 1;
    }
  for (const CutPath& p : a.paths) {
    if (p.vertices.front() == p.vertices.back()) continue;  // a closed loop has one node
    if (uf.find(N + p.vertices.front()) != uf.find(N + p.vertices.back())) continue;
    // The side with fewer samples is the one too coarse to carry the path.
    int worst = -1;
    for (int sid : {p.side_a, p.side_b}) {
      if (sid < 0) continue;
      const int c = a.sides[sid].chart;
      if (worst < 0 || sm.regions[c].samples.size() < sm.regions[worst].samples.size()) worst = c;
    }
    if (worst >= 0) st.strained[worst] = 1;
  }
  isochart::report(progress, isochart::Stage::Zippering, 0.8);

  // Group positions: the mean of the nodes a group holds, else the path point at its mean t.
  struct Acc {
    Vec3d node_sum, node_normal;
    int nodes = 0;
    double t_sum = 0;
    int t_count = 0;
    int path = -1;
  };
  std::vector<Acc> acc(N + mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!a.is_node[v]) continue;
    Acc& x = acc[uf.find(N + v)];
    x.node_sum += mesh.positions[v];
    x.node_normal += a.vertex_normals[v];
    ++x.nodes;
  }
  for (int i = 0; i < N; ++i) {
    if (!im.defined(i) || on_path[i] < 0) continue;
    Acc& x = acc[uf.find(i)];
    x.t_sum += on_t[i];
    ++x.t_count;
    x.path = on_path[i];
  }
  std::vector<int> group_of_root(N + mesh.num_vertices(), -1);
  int groups = 0;
  for (int i = 0; i < N; ++i) {
    if (!im.defined(i)) continue;
    const int root = uf.find(i);
    if (group_of_root[root] < 0) group_of_root[root] = groups++;
    im.group[i] = group_of_root[root];
    const Acc& x = acc[root];
    if (x.nodes > 0) {
      im.positions[i] = x.node_sum / x.nodes;
      im.normals[i] = normalized(x.node_normal);
    } else if (x.t_count > 0) {
      const PathPoint q = path_point(a, a.paths[x.path], x.t_sum / x.t_count);
      im.positions[i] = q.position;
      im.normals[i] = q.normal;
    }
  }
  im.num_groups = groups;
  // Parameter locations of the zippered samples: where their group's position lies on their
  // own chart's boundary.
  for (int c = 0; c < nc; ++c) {
    const Chart& ch = a.charts[c];
    for (std::size_t k = 0; k < zips[c].chains.size(); ++k) {
      const Chain& chain = zips[c].chains[k];
      const int sid = ch.sides[k];
      const int first = uf.find(chain.samples.front()), last = uf.find(chain.samples.back());
      for (std::size_t i = 0; i < chain.samples.size(); ++i) {
        const int root = uf.find(chain.samples[i]);
        const Acc& x = acc[root];
        Vec2d q = chain.texel[i];
        if (x.nodes > 0) {
          if (root == first) q = chain.texel.front();
          else if (root == last) q = chain.texel.back();
        } else if (x.t_count > 0) {
          q = side_texel(a, pl, sid, x.t_sum / x.t_count);
        }
        sm.param[chain.samples[i]] = q;
      }
    }
  }
  isochart::report(progress, isochart::Stage::Zippering, 1.0);
  return st;
}

}  // namespace mcgim::detail
