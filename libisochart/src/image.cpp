// Image files through OpenImageIO. OIIO keeps per-thread and global error strings; every
// failure path reads them (which also clears them, so OIIO does not complain at exit).
#include "isochart/image.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "isochart/error.h"

namespace isochart {

namespace {

namespace fs = std::filesystem;

// Images beyond this many values are refused up front rather than exhausting memory.
constexpr long long kMaxImageValues = 1LL << 30;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// One line from OIIO's error text: the first non-empty line.
std::string one_line(std::string message) {
  const auto start = message.find_first_not_of(" \t\r\n");
  if (start == std::string::npos) return {};
  message = message.substr(start);
  const auto end = message.find_first_of("\r\n");
  if (end != std::string::npos) message.resize(end);
  return message;
}

std::string with_detail(const std::string& message, const std::string& detail) {
  const std::string d = one_line(detail);
  return d.empty() ? message : message + " (" + d + ")";
}

int wrap_index(int i, int n, Wrap wrap) {
  if (wrap == Wrap::Repeat) {
    i %= n;
    return i < 0 ? i + n : i;
  }
  return std::clamp(i, 0, n - 1);
}

}  // namespace

void sample_bilinear(const Image& image, double u, double v, float* out, Wrap wrap) {
  const int w = image.width, h = image.height, nc = image.channels;
  if (image.empty()) {
    std::fill(out, out + nc, 0.0f);
    return;
  }
  if (!std::isfinite(u) || !std::isfinite(v)) u = v = 0;
  // Texel (x, y) covers [x, x+1] × [y, y+1] in pixel units with its centre at +0.5; rows
  // count from the top while v counts from the bottom.
  const double px = u * w - 0.5, py = (1.0 - v) * h - 0.5;
  const double fx = std::floor(px), fy = std::floor(py);
  const float ax = static_cast<float>(px - fx), ay = static_cast<float>(py - fy);
  // Clamp before converting so far-away coordinates cannot overflow an int.
  const double limit = 1e9;
  const int x0 = static_cast<int>(std::clamp(fx, -limit, limit));
  const int y0 = static_cast<int>(std::clamp(fy, -limit, limit));
  const int xs[2] = {wrap_index(x0, w, wrap), wrap_index(x0 + 1, w, wrap)};
  const int ys[2] = {wrap_index(y0, h, wrap), wrap_index(y0 + 1, h, wrap)};
  for (int c = 0; c < nc; ++c) {
    const float top = image.at(xs[0], ys[0], c) * (1 - ax) + image.at(xs[1], ys[0], c) * ax;
    const float bottom = image.at(xs[0], ys[1], c) * (1 - ax) + image.at(xs[1], ys[1], c) * ax;
    out[c] = top * (1 - ay) + bottom * ay;
  }
}

Image read_image(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "image file not found");
  if (fs::is_directory(path, ec)) throw InputError(path, "is a directory, not an image file");

  // Keep alpha as stored (straight): OIIO would otherwise premultiply PNG colours by alpha.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in)
    throw InputError(path,
                     with_detail("cannot read image: unknown format or unreadable file", OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    in->geterror();
    throw InputError(path, "image has no pixels (" + std::to_string(spec.width) + "x" +
                               std::to_string(spec.height) + ", " + std::to_string(spec.nchannels) +
                               " channels)");
  }
  if (spec.depth > 1) throw InputError(path, "volume images are not supported");
  const long long values = static_cast<long long>(spec.width) * spec.height * spec.nchannels;
  if (values > kMaxImageValues)
    throw InputError(path, "image too large (" + std::to_string(spec.width) + "x" +
                               std::to_string(spec.height) + "x" + std::to_string(spec.nchannels) + ")");

  Image image(spec.width, spec.height, spec.nchannels);
  const bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data());
  if (!ok) {
    const std::string detail = in->geterror();
    OIIO::geterror();
    throw InputError(path, with_detail("cannot read image: corrupt or truncated file", detail));
  }
  in->close();
  // Some readers leave warnings behind even on success; drop them.
  in->geterror();
  for (float& x : image.pixels)
    if (!std::isfinite(x)) x = 0.0f;
  return image;
}

void write_image(const std::string& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * image.channels)
    throw Error("write_image: inconsistent image " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + "x" + std::to_string(image.channels) + " with " +
                std::to_string(image.pixels.size()) + " values");

  const fs::path target(path);
  const std::string ext = lower_extension(path);
  if (ext.empty()) throw InputError(path, "output image needs an extension (.png, .jpg, .exr, ...)");
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(path, "output directory does not exist");

  // Same directory (so the rename is atomic), same extension (so OIIO picks the format),
  // unique per process and call.
  static std::atomic<unsigned> counter{0};
  const fs::path tmp = dir / ("." + target.stem().string() + ".tmp" + std::to_string(::getpid()) + "-" +
                              std::to_string(counter++) + target.extension().string());

  auto out = OIIO::ImageOutput::create(tmp.string());
  if (!out) {
    OIIO::geterror();  // names the temporary file; ours is clearer
    throw InputError(path, "unsupported image format '" + ext + "' (use .png, .jpg, .exr, .tif, ...)");
  }

  const bool is_float = ext == ".exr" || ext == ".hdr" || ext == ".pfm";
  int channels = image.channels;
  // JPEG has no alpha; keep colour (or grey) only.
  if ((ext == ".jpg" || ext == ".jpeg") && (channels == 2 || channels == 4)) --channels;
  OIIO::ImageSpec spec(image.width, image.height, channels,
                       is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  if (channels == 4 || channels == 2) {
    spec.alpha_channel = channels - 1;
    // Our pixels have straight alpha; without this the writer would divide colours by alpha.
    spec.attribute("oiio:UnassociatedAlpha", 1);
  }

  auto fail = [&](const std::string& detail) {
    out.reset();
    fs::remove(tmp, ec);
    OIIO::geterror();
    throw Error(with_detail("cannot write image " + path, detail));
  };
  if (!out->open(tmp.string(), spec)) fail(out->geterror());
  const auto xstride = static_cast<OIIO::stride_t>(sizeof(float)) * image.channels;
  if (!out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data(), xstride)) fail(out->geterror());
  if (!out->close()) fail(out->geterror());
  out.reset();
  fs::rename(tmp, target, ec);
  if (ec) {
    const std::string reason = ec.message();
    fs::remove(tmp, ec);
    throw Error("cannot write image " + path + " (" + reason + ")");
  }
}

}  // namespace isochart
