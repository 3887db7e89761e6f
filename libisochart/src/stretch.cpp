#include "isochart/stretch.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/Polygon_2_algorithms.h>
#include <tbb/parallel_for.h>

#include "isochart/error.h"
#include "isochart/union_find.h"

namespace isochart {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Γ² and γ² from the metric tensor [a b; b c] of the texture → surface map.
void metric_tensor(const Vec3d q[3], const Vec2d p[3], double& a, double& b, double& c, double& area2) {
  const double s1 = p[0].x, t1 = p[0].y, s2 = p[1].x, t2 = p[1].y, s3 = p[2].x, t3 = p[2].y;
  area2 = (s2 - s1) * (t3 - t1) - (s3 - s1) * (t2 - t1);  // twice the signed UV area
  if (!(area2 > 0)) {
    a = b = c = 0;
    return;
  }
  const Vec3d Ss = (q[0] * (t2 - t3) + q[1] * (t3 - t1) + q[2] * (t1 - t2)) / area2;
  const Vec3d St = (q[0] * (s3 - s2) + q[1] * (s1 - s3) + q[2] * (s2 - s1)) / area2;
  a = dot(Ss, Ss);
  b = dot(Ss, St);
  c = dot(St, St);
}

// Accumulates stretch over triangles given an accessor for corners.
template <class Corners>
StretchStats accumulate(int nfaces, Corners corners) {
  StretchStats st;
  // First pass: areas for the normalization.
  double sum_l2 = 0;
  double max_g2 = 0, max_inv = 0;
  for (int i = 0; i < nfaces; ++i) {
    Vec3d q[3];
    Vec2d p[3];
    corners(i, q, p);
    const double a3 = triangle_area(q[0], q[1], q[2]);
    const double a2 = signed_area(p[0], p[1], p[2]);
    if (!(a3 > 0)) continue;  // zero-area surface triangles carry no stretch
    st.area_3d += a3;
    st.area_uv += std::abs(a2);
    double a, b, c, area2;
    metric_tensor(q, p, a, b, c, area2);
    if (!(area2 > 0)) {
      ++st.flipped;
      if (!(area2 < 0)) ++st.degenerate;
      if (st.worst_face < 0 || max_inv < kInf) st.worst_face = i;
      max_inv = kInf;
      continue;
    }
    sum_l2 += a3 * 0.5 * (a + c);
    const double disc = std::sqrt((a - c) * (a - c) + 4 * b * b);
    const double g2max = 0.5 * (a + c + disc);
    const double g2min = std::max(0.5 * (a + c - disc), 0.0);
    const double inv = g2min > 0 ? 1.0 / g2min : kInf;
    // Compare candidates after normalization below; keep both maxima separately.
    if (g2max > max_g2) max_g2 = g2max;
    if (inv > max_inv) {
      max_inv = inv;
      st.worst_face = i;
    }
  }
  if (st.area_3d <= 0) return st;
  if (st.flipped > 0 || st.area_uv <= 0) {
    st.l2 = st.linf = kInf;
    return st;
  }
  // Scaling texture coordinates by s = sqrt(A3D / AUV) divides the Jacobian by s.
  const double n2 = st.area_uv / st.area_3d;  // 1 / s²
  st.l2 = std::sqrt(sum_l2 / st.area_3d * n2);
  const double linf_stretch = std::sqrt(max_g2 * n2);
  const double linf_shrink = std::sqrt(max_inv / n2);
  st.linf = std::max(linf_stretch, linf_shrink);
  if (linf_stretch >= linf_shrink) {
    // Find the face reaching the stretch maximum for reporting.
    for (int i = 0; i < nfaces; ++i) {
      Vec3d q[3];
      Vec2d p[3];
      corners(i, q, p);
      if (!(triangle_area(q[0], q[1], q[2]) > 0)) continue;
      double a, b, c, area2;
      metric_tensor(q, p, a, b, c, area2);
      const double disc = std::sqrt((a - c) * (a - c) + 4 * b * b);
      if (0.5 * (a + c + disc) == max_g2) {
        st.worst_face = i;
        break;
      }
    }
  }
  return st;
}

}  // namespace

TriangleStretch triangle_stretch(const Vec3d q[3], const Vec2d p[3]) {
  TriangleStretch t;
  double a, b, c, area2;
  metric_tensor(q, p, a, b, c, area2);
  if (!(area2 > 0)) {
    t.flipped = true;
    t.l2 = t.linf = kInf;
    return t;
  }
  const double disc = std::sqrt((a - c) * (a - c) + 4 * b * b);
  t.gamma_max = std::sqrt(0.5 * (a + c + disc));
  t.gamma_min = std::sqrt(std::max(0.5 * (a + c - disc), 0.0));
  t.l2 = std::sqrt(0.5 * (a + c));
  t.linf = std::max(t.gamma_max, t.gamma_min > 0 ? 1.0 / t.gamma_min : kInf);
  return t;
}

StretchStats measure_stretch(const Mesh& mesh, const std::vector<int>& faces) {
  if (!mesh.has_uvs()) throw InputError("", "mesh has no texture coordinates");
  const int n = faces.empty() ? mesh.num_faces() : static_cast<int>(faces.size());
  StretchStats st = accumulate(n, [&](int i, Vec3d* q, Vec2d* p) {
    const int f = faces.empty() ? i : faces[i];
    for (int k = 0; k < 3; ++k) {
      q[k] = mesh.positions[mesh.faces[f][k]];
      p[k] = mesh.uvs[mesh.face_uvs[f][k]];
    }
  });
  if (!faces.empty() && st.worst_face >= 0) st.worst_face = faces[st.worst_face];
  return st;
}

StretchStats measure_texture_stretch(const Mesh& mesh, double texture_aspect) {
  if (!mesh.has_uvs()) throw InputError("", "mesh has no texture coordinates");
  return accumulate(mesh.num_faces(), [&](int f, Vec3d* q, Vec2d* p) {
    for (int k = 0; k < 3; ++k) {
      q[k] = mesh.positions[mesh.faces[f][k]];
      const Vec2d& uv = mesh.uvs[mesh.face_uvs[f][k]];
      p[k] = {uv.x * texture_aspect, uv.y};
    }
  });
}

double detect_texture_aspect(const Mesh& mesh) {
  if (!mesh.has_uvs()) return 1.0;
  int nc = 0;
  const std::vector<int> chart = uv_charts(mesh, nc);
  // Per chart, the area-weighted mean of log(|∂p/∂u| / |∂p/∂v|).
  std::vector<double> weight(nc, 0.0), log_sum(nc, 0.0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3d& q0 = mesh.positions[mesh.faces[f][0]];
    const Vec3d e1 = mesh.positions[mesh.faces[f][1]] - q0, e2 = mesh.positions[mesh.faces[f][2]] - q0;
    const Vec2d& p0 = mesh.uvs[mesh.face_uvs[f][0]];
    const Vec2d d1 = mesh.uvs[mesh.face_uvs[f][1]] - p0, d2 = mesh.uvs[mesh.face_uvs[f][2]] - p0;
    const double det = d1.x * d2.y - d2.x * d1.y;
    const double area = 0.5 * norm(cross(e1, e2));
    if (!(std::abs(det) > 0) || !(area > 0)) continue;
    // The Jacobian's columns: the surface's rate of change along u and along v.
    const double su = norm((e1 * d2.y - e2 * d1.y) / det), sv = norm((e2 * d1.x - e1 * d2.x) / det);
    const double l = std::log(su / sv);
    if (!std::isfinite(l)) continue;
    weight[chart[f]] += area;
    log_sum[chart[f]] += area * l;
  }
  double total = 0, sum = 0;
  for (int c = 0; c < nc; ++c) total += weight[c], sum += log_sum[c];
  if (!(total > 0)) return 1.0;
  const double mean = sum / total;
  // Charts that disagree (a square atlas with one chart stretched along u, beside undistorted
  // ones) say nothing about the texture: on isocharts', UVAtlas's and xatlas's atlases the
  // charts' RMS spread is within a factor 1.18, a stretched cylinder beside its caps 1.94.
  double spread = 0;
  for (int c = 0; c < nc; ++c)
    if (weight[c] > 0) spread += weight[c] * std::pow(log_sum[c] / weight[c] - mean, 2);
  if (std::sqrt(spread / total) > std::log(1.4)) return 1.0;
  // Uneven stretch in charts of every orientation leaves a few percent of noise (a 2048×256
  // atlas reads 7.80, a 4:1 signal atlas 4.26, xatlas's square horse 1.063); textures are
  // nearly always a power of two times as wide as high, so within 10 % of one it is that.
  const double k = std::round(mean / std::log(2.0));
  if (std::abs(mean - k * std::log(2.0)) < std::log(1.1)) return std::ldexp(1.0, static_cast<int>(k));
  return std::exp(mean);
}

StretchStats measure_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                             const std::vector<Vec2d>& uv) {
  return accumulate(static_cast<int>(faces.size()), [&](int f, Vec3d* q, Vec2d* p) {
    for (int k = 0; k < 3; ++k) {
      q[k] = positions[faces[f][k]];
      p[k] = uv[faces[f][k]];
    }
  });
}

std::vector<TriangleStretch> per_face_stretch(const Mesh& mesh) {
  const StretchStats st = measure_stretch(mesh);
  std::vector<TriangleStretch> out(mesh.faces.size());
  const double s = st.area_uv > 0 ? std::sqrt(st.area_3d / st.area_uv) : 1.0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    Vec3d q[3];
    Vec2d p[3];
    for (int k = 0; k < 3; ++k) {
      q[k] = mesh.positions[mesh.faces[f][k]];
      p[k] = mesh.uvs[mesh.face_uvs[f][k]] * s;
    }
    out[f] = triangle_stretch(q, p);
  }
  return out;
}

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = K::Point_2;

// Interiors of two non-degenerate triangles are disjoint iff one of the six edge lines
// separates them (separating axis theorem for convex polygons), tested with exact predicates.
bool separated_by_edge_of(const P2 a[3], const P2 b[3]) {
  // Orient a counter-clockwise: inside is the left side of each edge.
  const bool ccw = CGAL::orientation(a[0], a[1], a[2]) == CGAL::LEFT_TURN;
  for (int k = 0; k < 3; ++k) {
    const P2& u = a[k];
    const P2& v = a[(k + 1) % 3];
    bool all_outside = true;
    for (int j = 0; j < 3 && all_outside; ++j) {
      const CGAL::Orientation o = CGAL::orientation(u, v, b[j]);
      all_outside = ccw ? (o != CGAL::LEFT_TURN) : (o != CGAL::RIGHT_TURN);
    }
    if (all_outside) return true;
  }
  return false;
}

bool interiors_overlap(const std::array<Vec2d, 3>& x, const std::array<Vec2d, 3>& y) {
  const P2 a[3] = {{x[0].x, x[0].y}, {x[1].x, x[1].y}, {x[2].x, x[2].y}};
  const P2 b[3] = {{y[0].x, y[0].y}, {y[1].x, y[1].y}, {y[2].x, y[2].y}};
  if (CGAL::collinear(a[0], a[1], a[2]) || CGAL::collinear(b[0], b[1], b[2])) return false;
  return !separated_by_edge_of(a, b) && !separated_by_edge_of(b, a);
}

}  // namespace

std::vector<std::pair<int, int>> overlapping_uv_pairs(const std::vector<std::array<Vec2d, 3>>& tris,
                                                      std::size_t max_pairs) {
  using Box = CGAL::Box_intersection_d::Box_with_handle_d<double, 2, std::size_t,
                                                          CGAL::Box_intersection_d::ID_EXPLICIT>;
  std::vector<Box> boxes;
  boxes.reserve(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const auto& t = tris[i];
    double lo[2], hi[2];
    for (int d = 0; d < 2; ++d) {
      lo[d] = std::min({t[0][d], t[1][d], t[2][d]});
      hi[d] = std::max({t[0][d], t[1][d], t[2][d]});
    }
    if (!(std::isfinite(lo[0]) && std::isfinite(lo[1]) && std::isfinite(hi[0]) && std::isfinite(hi[1])))
      continue;
    boxes.emplace_back(CGAL::Bbox_2(lo[0], lo[1], hi[0], hi[1]), i);
  }
  std::vector<std::pair<int, int>> pairs;
  // Boxes are closed, so triangles touching at a point are candidates and the exact test
  // decides. Open boxes would miss nothing since overlapping interiors have overlapping
  // open boxes, and they save work on meshes whose triangles share corners.
  auto report_pair = [&](const Box& a, const Box& b) {
    if (max_pairs && pairs.size() >= max_pairs) return;
    const int i = static_cast<int>(a.handle()), j = static_cast<int>(b.handle());
    if (interiors_overlap(tris[i], tris[j])) pairs.emplace_back(std::min(i, j), std::max(i, j));
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), report_pair, std::ptrdiff_t(10),
                                CGAL::Box_intersection_d::HALF_OPEN);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

bool uv_layout_is_embedding(const std::vector<Face>& tris, const std::vector<Vec2d>& uv, const Topology& topo) {
  const int nv = static_cast<int>(uv.size());
  if (tris.empty() || topo.num_faces() != static_cast<int>(tris.size())) return false;
  auto point = [&](int v) { return P2(uv[v].x, uv[v].y); };
  for (const Face& t : tris)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv || !is_finite(uv[t[k]])) return false;
  // One strict orientation for all.
  const CGAL::Orientation sign = CGAL::orientation(point(tris[0][0]), point(tris[0][1]), point(tris[0][2]));
  if (sign == CGAL::COLLINEAR) return false;
  for (const Face& t : tris)
    if (CGAL::orientation(point(t[0]), point(t[1]), point(t[2])) != sign) return false;
  // A disk: connected, manifold, one boundary loop, χ = 1.
  if (!topo.is_manifold() || topo.num_components() != 1 || topo.boundary_loops().size() != 1 ||
      topo.euler_characteristic() != 1)
    return false;
  // Consistently oriented: the two faces of an interior edge run along it in opposite
  // directions (otherwise both lie on one side of it and the degree argument fails).
  std::vector<signed char> along(topo.num_edges(), 0);
  for (int f = 0; f < topo.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int e = topo.face_edge(f, k);
      along[e] += tris[f][k] == topo.edge(e).v0 ? 1 : -1;
    }
  for (int e = 0; e < topo.num_edges(); ++e)
    if (topo.edge_faces(e).size() == 2 && along[e] != 0) return false;
  const std::vector<int>& loop = topo.boundary_loops()[0];
  if (loop.size() < 3) return false;
  // The boundary polygon must be simple: consecutive segments meet only at their shared
  // vertex (collinear only when going on straight ahead), other pairs not at all.
  const std::size_t nb = loop.size();
  for (std::size_t i = 0; i < nb; ++i) {
    const P2 a = point(loop[i]), b = point(loop[(i + 1) % nb]), c = point(loop[(i + 2) % nb]);
    if (CGAL::orientation(a, b, c) == CGAL::COLLINEAR && (b == a || b == c || !CGAL::collinear_are_strictly_ordered_along_line(a, b, c)))
      return false;
  }
  using Box = CGAL::Box_intersection_d::Box_with_handle_d<double, 2, std::size_t,
                                                          CGAL::Box_intersection_d::ID_EXPLICIT>;
  std::vector<Box> boxes;
  boxes.reserve(nb);
  for (std::size_t i = 0; i < nb; ++i) {
    const Vec2d& a = uv[loop[i]];
    const Vec2d& b = uv[loop[(i + 1) % nb]];
    boxes.emplace_back(CGAL::Bbox_2(std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)), i);
  }
  bool simple = true;
  auto check = [&](const Box& x, const Box& y) {
    if (!simple) return;
    const std::size_t i = x.handle(), j = y.handle();
    if ((i + 1) % nb == j || (j + 1) % nb == i) return;  // consecutive: checked above
    const K::Segment_2 si(point(loop[i]), point(loop[(i + 1) % nb]));
    const K::Segment_2 sj(point(loop[j]), point(loop[(j + 1) % nb]));
    if (CGAL::do_intersect(si, sj)) simple = false;
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), check, std::ptrdiff_t(10),
                                CGAL::Box_intersection_d::CLOSED);
  return simple;
}

bool uv_layout_is_embedding(const std::vector<Face>& tris, const std::vector<Vec2d>& uv) {
  return uv_layout_is_embedding(tris, uv, Topology(tris, static_cast<int>(uv.size())));
}

namespace {

// More charts than this and the pairwise nesting test below would cost more than it saves.
constexpr int kMaxProvenCharts = 4096;

// Proves that no two UV triangles of `mesh` overlap without testing triangle pairs: each
// group of faces joined through shared texture coordinates must be proven one-to-one on its
// own (uv_layout_is_embedding), and then the groups' regions, bounded by simple polygons,
// overlap only if two boundaries meet or one region lies inside another. So no boundary
// segment may meet one of another group (exact test), and no group may have a boundary vertex
// inside another's polygon. False means "not proven": any doubt (a group that is no disk, a
// touching pair, too many groups) leaves it to the all-pairs test.
bool uv_groups_proven_disjoint(const Mesh& mesh) {
  const int nf = mesh.num_faces();
  const int nu = static_cast<int>(mesh.uvs.size());
  if (nf == 0 || static_cast<int>(mesh.face_uvs.size()) != nf) return false;
  UnionFind uv_sets(nu);
  for (const Face& t : mesh.face_uvs) {
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nu) return false;
    uv_sets.unite(t[0], t[1]);
    uv_sets.unite(t[0], t[2]);
  }
  std::vector<int> group_of(nu, -1), local(nu, -1);
  std::vector<std::vector<Face>> tris;
  std::vector<std::vector<Vec2d>> uv;
  for (const Face& t : mesh.face_uvs) {
    const int r = uv_sets.find(t[0]);
    if (group_of[r] < 0) {
      if (static_cast<int>(tris.size()) == kMaxProvenCharts) return false;
      group_of[r] = static_cast<int>(tris.size());
      tris.emplace_back();
      uv.emplace_back();
    }
    const int g = group_of[r];
    Face lt;
    for (int k = 0; k < 3; ++k) {
      if (local[t[k]] < 0) {
        local[t[k]] = static_cast<int>(uv[g].size());
        uv[g].push_back(mesh.uvs[t[k]]);
      }
      lt[k] = local[t[k]];
    }
    tris[g].push_back(lt);
  }
  const int ng = static_cast<int>(tris.size());
  std::vector<std::vector<int>> loop(ng);
  std::vector<char> proven(ng, 0);
  tbb::parallel_for(0, ng, [&](int g) {
    const Topology topo(tris[g], static_cast<int>(uv[g].size()));
    if (!uv_layout_is_embedding(tris[g], uv[g], topo)) return;
    loop[g] = topo.boundary_loops()[0];
    proven[g] = 1;
  });
  if (std::find(proven.begin(), proven.end(), 0) != proven.end()) return false;
  if (ng == 1) return true;

  using Box = CGAL::Box_intersection_d::Box_with_handle_d<double, 2, std::size_t,
                                                          CGAL::Box_intersection_d::ID_EXPLICIT>;
  std::vector<Box> boxes;
  std::vector<std::pair<int, int>> segment;  // (group, index in its loop)
  std::vector<CGAL::Bbox_2> extent(ng);
  for (int g = 0; g < ng; ++g) {
    const std::size_t n = loop[g].size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2d& a = uv[g][loop[g][i]];
      const Vec2d& b = uv[g][loop[g][(i + 1) % n]];
      const CGAL::Bbox_2 box(std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y));
      extent[g] = i == 0 ? box : extent[g] + box;
      boxes.emplace_back(box, segment.size());
      segment.emplace_back(g, static_cast<int>(i));
    }
  }
  auto point = [&](int g, int i) {
    const Vec2d& p = uv[g][loop[g][i % loop[g].size()]];
    return P2(p.x, p.y);
  };
  bool apart = true;
  auto check = [&](const Box& x, const Box& y) {
    if (!apart) return;
    const auto [ga, ia] = segment[x.handle()];
    const auto [gb, ib] = segment[y.handle()];
    if (ga == gb) return;  // within a group: proven simple already
    if (CGAL::do_intersect(K::Segment_2(point(ga, ia), point(ga, ia + 1)),
                           K::Segment_2(point(gb, ib), point(gb, ib + 1))))
      apart = false;
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), check, std::ptrdiff_t(10),
                                CGAL::Box_intersection_d::CLOSED);
  if (!apart) return false;
  // Boundaries apart: each pair of regions is disjoint or nested, and a region can only lie
  // inside another whose extent holds its own.
  auto inside = [](const CGAL::Bbox_2& a, const CGAL::Bbox_2& b) {
    return a.xmin() >= b.xmin() && a.xmax() <= b.xmax() && a.ymin() >= b.ymin() && a.ymax() <= b.ymax();
  };
  std::vector<std::vector<P2>> polygon(ng);  // made when first needed
  for (int a = 0; a < ng; ++a)
    for (int b = 0; b < ng; ++b) {
      if (a == b || !inside(extent[a], extent[b])) continue;
      if (polygon[b].empty())
        for (std::size_t i = 0; i < loop[b].size(); ++i) polygon[b].push_back(point(b, static_cast<int>(i)));
      if (CGAL::bounded_side_2(polygon[b].begin(), polygon[b].end(), point(a, 0), K()) != CGAL::ON_UNBOUNDED_SIDE)
        return false;
    }
  return true;
}

}  // namespace

std::vector<std::pair<int, int>> overlapping_uv_pairs(const Mesh& mesh, std::size_t max_pairs) {
  if (uv_groups_proven_disjoint(mesh)) return {};
  std::vector<std::array<Vec2d, 3>> tris(mesh.faces.size());
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) tris[f][k] = mesh.uvs[mesh.face_uvs[f][k]];
  return overlapping_uv_pairs(tris, max_pairs);
}

namespace {

// True when the two faces of interior edge e use the same texture coordinates at both ends.
bool uv_continuous(const Mesh& mesh, const Topology& topo, int e) {
  const IndexRange ef = topo.edge_faces(e);
  if (ef.size() != 2) return false;
  auto uv_at = [&](int f, int v) {
    for (int k = 0; k < 3; ++k)
      if (mesh.faces[f][k] == v) return mesh.uvs[mesh.face_uvs[f][k]];
    return Vec2d{};
  };
  const auto& ed = topo.edge(e);
  return uv_at(ef[0], ed.v0) == uv_at(ef[1], ed.v0) && uv_at(ef[0], ed.v1) == uv_at(ef[1], ed.v1);
}

std::vector<int> uv_charts(const Mesh& mesh, const Topology& topo, int& num_charts) {
  const int nf = mesh.num_faces();
  std::vector<int> parent(nf);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int e = 0; e < topo.num_edges(); ++e) {
    if (!uv_continuous(mesh, topo, e)) continue;
    const int a = find(topo.edge_faces(e)[0]), b = find(topo.edge_faces(e)[1]);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<int> id(nf, -1), chart(nf);
  num_charts = 0;
  for (int f = 0; f < nf; ++f) {
    const int r = find(f);
    if (id[r] < 0) id[r] = num_charts++;
    chart[f] = id[r];
  }
  return chart;
}

}  // namespace

std::vector<int> uv_charts(const Mesh& mesh, int& num_charts) {
  if (!mesh.has_uvs()) throw InputError("", "mesh has no texture coordinates");
  return uv_charts(mesh, Topology(mesh), num_charts);
}

namespace {

ChartDensity sparsest_of(const Mesh& mesh, const std::vector<int>& chart, int num_charts) {
  std::vector<double> chart_uv(num_charts, 0), chart_area(num_charts, 0);
  std::vector<int> first(num_charts, -1), count(num_charts, 0);
  const std::vector<double> areas = face_areas(mesh);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& t = mesh.face_uvs[f];
    const int c = chart[f];
    chart_uv[c] += std::abs(signed_area(mesh.uvs[t[0]], mesh.uvs[t[1]], mesh.uvs[t[2]]));
    chart_area[c] += areas[f];
    if (first[c] < 0) first[c] = f;
    ++count[c];
  }
  const double total_uv = std::accumulate(chart_uv.begin(), chart_uv.end(), 0.0);
  const double total_area = std::accumulate(chart_area.begin(), chart_area.end(), 0.0);
  ChartDensity d;
  if (!(total_uv > 0) || !(total_area > 0)) return d;
  for (int c = 0; c < num_charts; ++c) {
    if (!(chart_area[c] > 0)) continue;
    const double density = (chart_uv[c] / total_uv) / (chart_area[c] / total_area);
    if (d.first_face < 0 || density < d.density) d = {density, first[c], count[c]};
  }
  return d;
}

}  // namespace

ChartDensity sparsest_chart(const Mesh& mesh) {
  if (!mesh.has_uvs()) throw InputError("", "mesh has no texture coordinates");
  int n = 0;
  const std::vector<int> chart = uv_charts(mesh, n);
  return sparsest_of(mesh, chart, n);
}

AtlasQuality measure_atlas(const Mesh& mesh, double texture_aspect) {
  if (!mesh.has_uvs()) throw InputError("", "mesh has no texture coordinates");
  AtlasQuality q;
  const Topology topo(mesh);
  const std::vector<int> chart = uv_charts(mesh, topo, q.charts);
  // A chart is mirrored when most of its UV area is turned over.
  std::vector<double> turned(q.charts, 0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& t = mesh.face_uvs[f];
    turned[chart[f]] += signed_area(mesh.uvs[t[0]], mesh.uvs[t[1]], mesh.uvs[t[2]]);
  }
  std::vector<char> mirrored(q.charts, 0);
  for (int c = 0; c < q.charts; ++c) mirrored[c] = turned[c] < 0;
  q.mirrored_charts = static_cast<int>(std::count(mirrored.begin(), mirrored.end(), 1));
  q.stretch = accumulate(mesh.num_faces(), [&](int f, Vec3d* pos, Vec2d* p) {
    const double flip = mirrored[chart[f]] ? -1 : 1;
    for (int k = 0; k < 3; ++k) {
      pos[k] = mesh.positions[mesh.faces[f][k]];
      const Vec2d& uv = mesh.uvs[mesh.face_uvs[f][k]];
      p[k] = {flip * uv.x * texture_aspect, uv.y};
    }
  });
  q.overlapping_pairs = static_cast<long long>(overlapping_uv_pairs(mesh).size());
  q.uv_area = 0;
  bool first = true;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    Vec2d p[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = mesh.uvs[mesh.face_uvs[f][k]];
      if (first) {
        q.uv_min = q.uv_max = p[k];
        first = false;
      }
      q.uv_min = {std::min(q.uv_min.x, p[k].x), std::min(q.uv_min.y, p[k].y)};
      q.uv_max = {std::max(q.uv_max.x, p[k].x), std::max(q.uv_max.y, p[k].y)};
    }
    q.uv_area += std::abs(signed_area(p[0], p[1], p[2]));
  }
  const double box = (q.uv_max.x - q.uv_min.x) * (q.uv_max.y - q.uv_min.y);
  q.packing_ratio = box > 0 ? q.uv_area / box : 0;
  q.sparsest = sparsest_of(mesh, chart, q.charts);
  for (int e = 0; e < topo.num_edges(); ++e) {
    // Mesh boundary edges are not seams; interior edges are when the UVs differ across them.
    if (topo.edge_faces(e).size() < 2 || uv_continuous(mesh, topo, e)) continue;
    q.seam_length += norm(mesh.positions[topo.edge(e).v0] - mesh.positions[topo.edge(e).v1]);
  }
  const double area = surface_area(mesh);
  q.seam_length_relative = area > 0 ? q.seam_length / std::sqrt(area) : 0;
  return q;
}

}  // namespace isochart
