#include "mcgim/image_io.h"

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <string>
#include <vector>

#include "isochart/error.h"
#include "isochart/image.h"

namespace mcgim {

namespace {

// "dir/name.ext" -> "dir/name.tmp.ext": the writer picks the format from the extension.
std::string temporary_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + ".tmp";
  return path.substr(0, dot) + ".tmp" + path.substr(dot);
}

template <typename T>
void write_pixels(const std::string& path, const OIIO::ImageSpec& spec, const std::vector<T>& pixels,
                  OIIO::TypeDesc type) {
  const std::string tmp = temporary_name(path);
  auto out = OIIO::ImageOutput::create(tmp);
  if (!out) throw isochart::Error("cannot write " + path + ": no image writer for its extension");
  if (!out->open(tmp, spec) || !out->write_image(type, pixels.data()) || !out->close()) {
    const std::string msg = out->geterror();
    std::remove(tmp.c_str());
    throw isochart::Error("cannot write " + path + ": " + msg);
  }
  out.reset();
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw isochart::Error("cannot write " + path + ": rename failed");
  }
}

}  // namespace

void write_exr(const GeometryImage& im, const std::string& path) {
  const int W = im.width, H = im.height;
  const int nch = 9;
  OIIO::ImageSpec spec(W, H, nch, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"R", "G", "B", "N.X", "N.Y", "N.Z", "defined", "chart", "group"};
  spec.alpha_channel = -1;
  spec.attribute("compression", "zip");
  spec.attribute("isocharts:kind", "multi-chart geometry image");
  std::string mirrored;
  for (char m : im.chart_mirrored) mirrored += m ? '1' : '0';
  spec.attribute("isocharts:chart_mirrored", mirrored);
  std::vector<float> px(static_cast<std::size_t>(W) * H * nch, 0.0f);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const int i = im.index(x, y);
      float* p = &px[(static_cast<std::size_t>(H - 1 - y) * W + x) * nch];
      const bool def = im.defined(i);
      p[0] = static_cast<float>(im.positions[i].x);
      p[1] = static_cast<float>(im.positions[i].y);
      p[2] = static_cast<float>(im.positions[i].z);
      p[3] = static_cast<float>(im.normals[i].x);
      p[4] = static_cast<float>(im.normals[i].y);
      p[5] = static_cast<float>(im.normals[i].z);
      p[6] = def ? 1.0f : 0.0f;
      p[7] = static_cast<float>(im.chart[i]);
      p[8] = static_cast<float>(def ? im.group[i] : -1);
    }
  write_pixels(path, spec, px, OIIO::TypeDesc::FLOAT);
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
