// Image files: checks, temporary files and renames here; the format work in the OpenImageIO
// module (image_module.h), loaded the first time an image is read or written.
#include "isochart/image.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <system_error>

#include "image_module.h"
#include "isochart/error.h"
#include "isochart/io.h"

namespace isochart {

namespace {

namespace fs = std::filesystem;

// Images beyond this many values (pixels × 4) are refused up front rather than exhausting
// memory: 8192² pixels, read as 1 GB of floats.
constexpr long long kMaxImageValues = 1LL << 28;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

#ifndef ISOCHARTS_IMAGE_MODULE_PATH
#define ISOCHARTS_IMAGE_MODULE_PATH ""
#endif

constexpr const char* kModuleName = "libisocharts_imageio.so";

const IsochartsImageModule* try_load(const std::string& file, std::string& errors) {
  void* handle = ::dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* e = ::dlerror();
    errors += std::string(errors.empty() ? "" : "; ") + (e ? e : file + ": cannot load");
    return nullptr;
  }
  auto entry = reinterpret_cast<IsochartsImageModuleEntry>(::dlsym(handle, "isocharts_image_module"));
  const IsochartsImageModule* m = entry ? entry() : nullptr;
  if (!m || m->abi != ISOCHARTS_IMAGE_MODULE_ABI) {
    errors +=
        std::string(errors.empty() ? "" : "; ") + file + ": not an isocharts image module of this version";
    ::dlclose(handle);
    return nullptr;
  }
  return m;  // kept loaded for the life of the process
}

const IsochartsImageModule* load_module() {
  // A module named in the environment is the only one tried: the user asked for that file.
  std::vector<std::string> candidates;
  std::error_code ec;
  if (const char* env = std::getenv("ISOCHARTS_IMAGE_MODULE"); env && *env) {
    candidates.emplace_back(env);
  } else {
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) candidates.push_back((exe.parent_path() / kModuleName).string());
    if (*ISOCHARTS_IMAGE_MODULE_PATH) candidates.emplace_back(ISOCHARTS_IMAGE_MODULE_PATH);
  }
  std::string errors;
  for (const std::string& c : candidates) {
    if (!fs::exists(c, ec)) {
      errors += (errors.empty() ? "" : "; ") + c + ": no such file";
      continue;
    }
    if (const IsochartsImageModule* m = try_load(c, errors)) return m;
  }
  if (errors.empty()) errors = "no place to look for it";
  throw Error(std::string("image I/O is unavailable: ") + kModuleName + " could not be loaded (" + errors +
              "); keep it next to the program or set ISOCHARTS_IMAGE_MODULE");
}

const IsochartsImageModule& image_module() {
  // A failed load throws and is retried by the next call.
  static const IsochartsImageModule* module = load_module();
  return *module;
}

int wrap_index(int i, int n, Wrap wrap) {
  switch (wrap) {
    case Wrap::Repeat:
      i %= n;
      return i < 0 ? i + n : i;
    case Wrap::Mirror: {
      // Period 2n: the texture, then its mirror image (texel n is texel n − 1 again).
      const long long period = 2LL * n;
      long long k = i % period;
      if (k < 0) k += period;
      return static_cast<int>(k < n ? k : period - 1 - k);
    }
    case Wrap::Clamp:
      break;
  }
  return std::clamp(i, 0, n - 1);
}

}  // namespace

void fill_from_nearest(Image& img, std::vector<char>& filled, int keep) {
  const int w = img.width, h = img.height;
  std::deque<int> queue;
  for (int i = 0; i < w * h; ++i)
    if (filled[i]) queue.push_back(i);
  while (!queue.empty()) {
    const int i = queue.front();
    queue.pop_front();
    const int x = i % w, y = i / w;
    const int nb[4][2] = {{x + 1, y}, {x - 1, y}, {x, y + 1}, {x, y - 1}};
    for (const auto& p : nb) {
      if (p[0] < 0 || p[1] < 0 || p[0] >= w || p[1] >= h) continue;
      const int j = p[1] * w + p[0];
      if (filled[j]) continue;
      filled[j] = 1;
      for (int c = 0; c < img.channels; ++c)
        if (c != keep)
          img.pixels[static_cast<std::size_t>(j) * img.channels + c] =
              img.pixels[static_cast<std::size_t>(i) * img.channels + c];
      queue.push_back(j);
    }
  }
}

Image resize_area(const Image& in, int width, int height) {
  if (width < 1 || height < 1 || in.empty()) throw Error("resize_area: empty image or size");
  Image out(width, height, in.channels);
  out.channel_names = in.channel_names;
  // Separable: the box of new texel i spans old texels [i·s, (i + 1)·s) in each direction.
  auto weights = [](int from, int to) {
    std::vector<std::vector<std::pair<int, double>>> wts(to);
    const double s = static_cast<double>(from) / to;
    for (int i = 0; i < to; ++i) {
      const double a = i * s, b = (i + 1) * s;
      for (int k = static_cast<int>(std::floor(a)); k < std::min(from, static_cast<int>(std::ceil(b))); ++k) {
        const double overlap = std::min(b, k + 1.0) - std::max(a, static_cast<double>(k));
        if (overlap > 0) wts[i].emplace_back(k, overlap / s);
      }
    }
    return wts;
  };
  const auto wx = weights(in.width, width), wy = weights(in.height, height);
  const int ch = in.channels;
  std::vector<double> row(static_cast<std::size_t>(width) * ch);
  for (int y = 0; y < height; ++y) {
    std::fill(row.begin(), row.end(), 0.0);
    for (const auto& [sy, fy] : wy[y])
      for (int x = 0; x < width; ++x)
        for (const auto& [sx, fx] : wx[x])
          for (int c = 0; c < ch; ++c)
            row[static_cast<std::size_t>(x) * ch + c] += fy * fx * in.at(sx, sy, c);
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < ch; ++c)
        out.at(x, y, c) = static_cast<float>(row[static_cast<std::size_t>(x) * ch + c]);
  }
  return out;
}

void sample_bilinear(const Image& image, double u, double v, float* out, Wrap wrap_u, Wrap wrap_v) {
  const int w = image.width, h = image.height, nc = image.channels;
  if (image.empty()) {
    std::fill(out, out + nc, 0.0f);
    return;
  }
  if (!std::isfinite(u) || !std::isfinite(v)) u = v = 0;
  // Far out (a material scaling its coordinates by 1e300), u · width would overflow and the
  // filter weights turn NaN: the coordinate is first brought into its period, or to the border.
  auto reduce = [](double t, Wrap wrap) {
    if (std::abs(t) < 1e6) return t;
    if (wrap == Wrap::Clamp) return t < 0 ? -1.0 : 2.0;
    const double period = wrap == Wrap::Mirror ? 2.0 : 1.0;
    return t - period * std::floor(t / period);
  };
  u = reduce(u, wrap_u);
  v = reduce(v, wrap_v);
  // Texel (x, y) covers [x, x+1] × [y, y+1] in pixel units with its centre at +0.5; rows
  // count from the top while v counts from the bottom.
  const double px = u * w - 0.5, py = (1.0 - v) * h - 0.5;
  const double fx = std::floor(px), fy = std::floor(py);
  const float ax = static_cast<float>(px - fx), ay = static_cast<float>(py - fy);
  // Clamp before converting so far-away coordinates cannot overflow an int.
  const double limit = 1e9;
  const int x0 = static_cast<int>(std::clamp(fx, -limit, limit));
  const int y0 = static_cast<int>(std::clamp(fy, -limit, limit));
  const int xs[2] = {wrap_index(x0, w, wrap_u), wrap_index(x0 + 1, w, wrap_u)};
  const int ys[2] = {wrap_index(y0, h, wrap_v), wrap_index(y0 + 1, h, wrap_v)};
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
  // The image library would read a device or pipe (/dev/zero, a FIFO) without end.
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "is not a regular file (a device, pipe or socket)");
  note_input_file(path);

  const IsochartsImageModule& m = image_module();
  Image image;
  float* data = nullptr;
  char names[4096] = {0};
  char message[1024] = {0};
  const int status = m.read(path.c_str(), kMaxImageValues, &image.width, &image.height, &image.channels,
                            &image.bits, &data, names, sizeof names, message, sizeof message);
  if (status == kIsochartsImageInputError) throw InputError(path, message);
  if (status != kIsochartsImageOk) throw Error("cannot read image " + path + ": " + message);
  const std::size_t n = static_cast<std::size_t>(image.width) * image.height * image.channels;
  try {
    image.pixels.assign(data, data + n);
  } catch (...) {
    m.free_pixels(data);
    throw;
  }
  m.free_pixels(data);
  for (const char* p = names; *p;) {
    const char* e = std::strchr(p, '\n');
    if (!e) break;
    image.channel_names.emplace_back(p, e);
    p = e + 1;
  }
  return image;
}

void check_image_output(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext.empty()) throw InputError(path, "output image needs an extension (.png, .jpg, .exr, ...)");
  if (!image_module().can_write(path.c_str()))
    throw InputError(path, "unsupported image format '" + ext + "' (use .png, .jpg, .exr, .tif, ...)");
  if (ext == ".pbm")
    throw InputError(path, "PBM holds black and white only (use .pgm for grey, .png or .ppm)");
}

void write_image(const std::string& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * image.channels)
    throw Error("write_image: inconsistent image " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + "x" + std::to_string(image.channels) + " with " +
                std::to_string(image.pixels.size()) + " values");

  const fs::path target(output_target(path));
  const std::string ext = lower_extension(path);
  if (ext.empty()) throw InputError(path, "output image needs an extension (.png, .jpg, .exr, ...)");
  if (ext == ".pbm")
    throw InputError(path, "PBM holds black and white only (use .pgm for grey, .png or .ppm)");
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(path, fs::exists(dir, ec) ? "cannot write: " + dir.string() + " is not a directory"
                                               : "output directory does not exist");
  const IsochartsImageModule& m = image_module();

  // Named with the extension asked for, so the writer picks that format.
  const fs::path tmp = temporary_path(target.string(), fs::path(path).extension().string());

  const bool is_float = ext == ".exr" || ext == ".hdr" || ext == ".pfm";
  // 16 bits where the format holds them (PNG, TIFF, PNM); JPEG and the like keep 8.
  const bool deep = image.bits >= 16 && (ext == ".png" || ext == ".tif" || ext == ".tiff" || ext == ".ppm" ||
                                         ext == ".pgm" || ext == ".pnm");
  const int bits = is_float ? 32 : deep ? 16 : 8;
  int channels = image.channels;
  const bool named = static_cast<int>(image.channel_names.size()) == image.channels;
  // JPEG has no alpha; keep colour (or grey) only.
  if (!named && (ext == ".jpg" || ext == ".jpeg") && (channels == 2 || channels == 4)) --channels;
  const float* pixels = image.pixels.data();
  // PGM holds grey only, but the PNM writer puts colour (P6) into a .pgm file as asked.
  std::vector<float> grey;
  if (!named && ext == ".pgm" && channels >= 3) {
    grey.resize(static_cast<std::size_t>(image.width) * image.height);
    for (std::size_t i = 0; i < grey.size(); ++i) {
      const float* p = pixels + i * image.channels;
      grey[i] = 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];  // Rec. 709 luminance
    }
    pixels = grey.data();
    channels = 1;
  }
  const int stride = grey.empty() ? image.channels : 1;
  const int alpha = channels < image.channels ? -1 : image.alpha_channel();  // JPEG dropped it
  std::string names;
  if (named)
    for (int c = 0; c < channels; ++c) names += image.channel_names[c] + "\n";
  std::vector<const char*> attributes;
  bool level_given = false;
  for (const auto& [key, value] : image.attributes) {
    attributes.push_back(key.c_str());
    attributes.push_back(value.c_str());
    level_given = level_given || key == "png:compressionLevel";
  }
  // zlib's level 3 instead of the writer's 6: an 8192² RGBA bake wrote in 9.3 s instead of
  // 18.5 s, 1.3 % larger.
  if (ext == ".png" && !level_given) {
    attributes.push_back("png:compressionLevel");
    attributes.push_back("3");
  }
  attributes.push_back(nullptr);

  char message[1024] = {0};
  track_temporary_file(tmp.string());
  const int status = m.write(tmp.c_str(), image.width, image.height, channels, stride, pixels, bits, alpha,
                             named ? names.c_str() : nullptr, attributes.data(), message, sizeof message);
  if (status != kIsochartsImageOk) remove_temporary_file(tmp.string());
  if (status == kIsochartsImageUnsupported)
    throw InputError(path, "unsupported image format '" + ext + "' (use .png, .jpg, .exr, .tif, ...)");
  if (status != kIsochartsImageOk) {
    // The writers name the file they wrote, our temporary one; the user knows only `path`.
    std::string detail = message;
    for (std::size_t at; (at = detail.find(tmp.string())) != std::string::npos;)
      detail.replace(at, tmp.string().size(), path);
    if (status == kIsochartsImageInputError)
      throw InputError(
          path, "cannot write this image in that format" + (detail.empty() ? std::string() : ": " + detail));
    throw Error(path + ": cannot write" + (detail.empty() ? std::string() : ": " + detail));
  }
  if (OutputBatch::stage(tmp.string(), target.string())) return;
  fs::rename(tmp, target, ec);
  if (ec) {
    const std::string reason = ec.message();
    remove_temporary_file(tmp.string());
    throw Error(path + ": cannot write: " + reason);
  }
  untrack_temporary_file(tmp.string());
}

}  // namespace isochart
