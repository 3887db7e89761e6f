#include <tbb/global_control.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <set>
#include <vector>

#include "isochart/atlas.h"
#include "isochart/baselines.h"
#include "isochart/pack.h"
#include "isochart/stretch.h"

using namespace isochart;

namespace {

// A flat grid of unit squares (two triangles each) over the cells for which `keep(i, j)` is
// true, with its own xy as UVs: one chart, stretch 1 everywhere.
template <class Keep>
Mesh flat_grid(int nx, int ny, const Keep& keep) {
  Mesh m;
  std::vector<int> id((nx + 1) * (ny + 1), -1);
  auto vertex = [&](int i, int j) {
    int& v = id[j * (nx + 1) + i];
    if (v < 0) {
      v = m.num_vertices();
      m.positions.push_back({static_cast<double>(i), static_cast<double>(j), 0});
      m.uvs.push_back({static_cast<double>(i), static_cast<double>(j)});
    }
    return v;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (!keep(i, j)) continue;
      const int a = vertex(i, j), b = vertex(i + 1, j), c = vertex(i + 1, j + 1), d = vertex(i, j + 1);
      m.faces.push_back({a, b, c});
      m.faces.push_back({a, c, d});
    }
  m.face_uvs = m.faces;
  return m;
}

// An L: a 40×8 bar and an 8×40 bar sharing a corner square.
Mesh l_shape() {
  return flat_grid(40, 40, [](int i, int j) { return i < 8 || j < 8; });
}

}  // namespace

TEST_CASE("an L-shaped chart is cut into two bars that pack better", "[pack]") {
  const Mesh mesh = l_shape();
  Atlas whole = atlas_from_uvs(mesh);
  REQUIRE(whole.num_charts() == 1);
  Atlas cut = whole;
  const PackSplitResult r = split_charts_for_packing(mesh, cut);
  CHECK(r.added == 1);
  REQUIRE(cut.num_charts() == 2);
  CHECK(r.rect_fill_after > r.rect_fill_before + 0.2);

  // Each piece is a disk with its own texture coordinates (none shared between charts).
  std::vector<std::vector<int>> faces(2);
  for (int f = 0; f < mesh.num_faces(); ++f) faces[cut.face_chart[f]].push_back(f);
  std::vector<int> owner(cut.uvs.size(), -1);
  for (int c = 0; c < 2; ++c) {
    CHECK(is_disk(mesh, faces[c]));
    CHECK(cut.charts[c].faces == static_cast<int>(faces[c].size()));
    for (const int f : faces[c])
      for (const int u : cut.face_uvs[f]) {
        CHECK((owner[u] < 0 || owner[u] == c));
        owner[u] = c;
      }
  }
  // Both bars are long; each piece keeps most of one bar.
  CHECK(faces[0].size() >= 2 * 8 * 24);
  CHECK(faces[1].size() >= 2 * 8 * 24);

  const PackResult pw = pack_atlas(mesh, whole, {}), pc = pack_atlas(mesh, cut, {});
  INFO("whole " << pw.packing_ratio << ", cut " << pc.packing_ratio);
  // Two bars in a square texture still leave room, but far less than the L.
  CHECK(pc.packing_ratio > pw.packing_ratio + 0.05);
  CHECK(cut.stats.flipped == 0);
  CHECK(cut.stats.overlapping_pairs == 0);
  CHECK(cut.stats.l2 == Approx(1.0).epsilon(1e-6));
}

TEST_CASE("a rectangle or a chart the bounds forbid cutting stays whole", "[pack]") {
  const Mesh rect = flat_grid(30, 10, [](int, int) { return true; });
  Atlas a = atlas_from_uvs(rect);
  CHECK(split_charts_for_packing(rect, a).added == 0);
  CHECK(a.num_charts() == 1);

  // The L with its upright bar's UVs squeezed 3× across: the whole chart meets L2 ≤ 1.4
  // only thanks to the wide horizontal bar, which no piece without it can do.
  Mesh l = l_shape();
  for (std::size_t v = 0; v < l.uvs.size(); ++v)
    if (l.positions[v].y > 8) l.uvs[v].x = l.positions[v].x / 3;
  Atlas b = atlas_from_uvs(l);
  const StretchStats whole = measure_stretch(b.apply_to(l));
  REQUIRE(whole.flipped == 0);
  PackSplitOptions o;
  o.max_l2 = whole.l2 * 1.001;
  o.max_linf = 1e9;
  const PackSplitResult r = split_charts_for_packing(l, b, o);
  INFO("whole L2 " << whole.l2);
  const Mesh out = b.apply_to(l);
  for (int c = 0; c < b.num_charts(); ++c) {
    std::vector<int> faces;
    for (int f = 0; f < l.num_faces(); ++f)
      if (b.face_chart[f] == c) faces.push_back(f);
    const StretchStats s = measure_stretch(out, faces);
    CHECK(s.l2 <= o.max_l2);
  }
  // And with no budget nothing is cut.
  Atlas c = atlas_from_uvs(l_shape());
  PackSplitOptions none;
  none.max_added = 0;
  CHECK(split_charts_for_packing(l_shape(), c, none).added == 0);
  CHECK(r.added <= 1);
}

TEST_CASE("cutting charts is identical with 1 and 2 threads", "[pack]") {
  // Two Ls and a bar: several candidates of equal gain, so ties must break the same way.
  Mesh m = flat_grid(90, 40, [](int i, int j) {
    return (i < 8 || (i < 40 && j < 8)) || (i >= 48 && (i < 56 || (i < 88 && j >= 32))) || (i >= 60 && j < 4);
  });
  Atlas a1, a2;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a1 = atlas_from_uvs(m);
    split_charts_for_packing(m, a1);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    a2 = atlas_from_uvs(m);
    split_charts_for_packing(m, a2);
  }
  CHECK(a1.num_charts() >= 4);
  CHECK(a1.face_chart == a2.face_chart);
  CHECK(a1.face_uvs == a2.face_uvs);
  REQUIRE(a1.uvs.size() == a2.uvs.size());
  for (std::size_t i = 0; i < a1.uvs.size(); ++i)
    CHECK((a1.uvs[i].x == a2.uvs[i].x && a1.uvs[i].y == a2.uvs[i].y));
}
