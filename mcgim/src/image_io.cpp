#include "mcgim/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "isochart/image.h"
#include "isochart/mesh.h"

namespace mcgim {

void write_exr(const GeometryImage& im, const std::string& path) {
  const int W = im.width, H = im.height;
  const int nch = 10;
  isochart::Image out(W, H, nch);
  out.channel_names = {"R", "G", "B", "N.X", "N.Y", "N.Z", "defined", "chart", "group", "diagonal"};
  std::string mirrored;
  for (char m : im.chart_mirrored) mirrored += m ? '1' : '0';
  out.attributes = {{"compression", "zip"},
                    {"isocharts:kind", "multi-chart geometry image"},
                    {"isocharts:chart_mirrored", mirrored},
                    {"isocharts:diagonal", "per 2x2 block at its lower-left sample: 1 splits (x+1,y)-(x,y+1), "
                                           "0 splits (x,y)-(x+1,y+1), -1 the shorter one"}};
  // EXR positions are 32-bit floats. A mesh far from the origin for its size would lose its
  // shape to their rounding (1e9 units out, a unit-sized mesh collapsed to a point), so there
  // the positions are stored relative to its box centre, given as isocharts:position_origin;
  // without that attribute they are absolute. Float error up to 1e-5 of the diagonal is kept
  // as it is (well under a sample's spacing), so ordinary meshes are written as before.
  isochart::Vec3d origin;
  std::vector<isochart::Vec3d> defined;
  for (std::size_t i = 0; i < im.positions.size(); ++i)
    if (im.defined(static_cast<int>(i))) defined.push_back(im.positions[i]);
  if (!defined.empty()) {
    const isochart::BoundingBox box = isochart::bounding_box(defined);
    const double max_abs = std::max({std::abs(box.min.x), std::abs(box.min.y), std::abs(box.min.z),
                                     std::abs(box.max.x), std::abs(box.max.y), std::abs(box.max.z)});
    if (std::ldexp(max_abs, -24) > 1e-5 * box.diagonal()) {
      origin = (box.min + box.max) * 0.5;
      char text[96];
      std::snprintf(text, sizeof text, "%.17g %.17g %.17g", origin.x, origin.y, origin.z);
      out.attributes.emplace_back("isocharts:position_origin", text);
    }
  }
  std::vector<float>& px = out.pixels;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const int i = im.index(x, y);
      float* p = &px[(static_cast<std::size_t>(H - 1 - y) * W + x) * nch];
      const bool def = im.defined(i);
      p[0] = static_cast<float>(im.positions[i].x - origin.x);
      p[1] = static_cast<float>(im.positions[i].y - origin.y);
      p[2] = static_cast<float>(im.positions[i].z - origin.z);
      p[3] = static_cast<float>(im.normals[i].x);
      p[4] = static_cast<float>(im.normals[i].y);
      p[5] = static_cast<float>(im.normals[i].z);
      p[6] = def ? 1.0f : 0.0f;
      p[7] = static_cast<float>(im.chart[i]);
      p[8] = static_cast<float>(def ? im.group[i] : -1);
      p[9] = im.block_diagonal.empty() ? -1.0f : static_cast<float>(im.block_diagonal[i]);
    }
  isochart::write_image(path, out);
}

void write_normal_preview(const GeometryImage& im, const std::string& path) {
  const int W = im.width, H = im.height;
  isochart::Image out(W, H, 3, 0.0f);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const int i = im.index(x, y);
      if (!im.defined(i)) continue;
      // Image rows run top to bottom; sample row 0 is the bottom (v = 0).
      for (int c = 0; c < 3; ++c)
        out.at(x, H - 1 - y, c) = static_cast<float>(0.5 * (im.normals[i][c] + 1.0));
    }
  isochart::write_image(path, out);
}

}  // namespace mcgim
