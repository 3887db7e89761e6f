// Exemplar input, resampling to MCGIM texel sizes, and the procedural exemplars.

#include "synth/exemplar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "isochart/error.h"
#include "isochart/rng.h"

namespace synth {

using isochart::Image;
using isochart::InputError;

Image to_rgb_exemplar(const Image& image, const std::string& name, long long* clipped) {
  if (clipped) *clipped = 0;
  if (image.width < 4 || image.height < 4)
    throw InputError(name, "exemplar is " + std::to_string(image.width) + "x" +
                               std::to_string(image.height) + " pixels; at least 4x4 is needed");
  // The same rule as the renderer and the writer for which channel is alpha, so an EXR whose
  // fourth channel is, say, depth is not taken for a transparent exemplar.
  const int alpha = image.alpha_channel();
  // Named channels are taken by name (an EXR may store B, G, R or carry extra channels), the
  // rest by position.
  std::vector<int> colour;
  const auto& names = image.channel_names;
  if (static_cast<int>(names.size()) == image.channels) {
    for (const char* want : {"R", "G", "B"}) {
      const auto it = std::find(names.begin(), names.end(), want);
      if (it != names.end()) colour.push_back(static_cast<int>(it - names.begin()));
    }
    if (colour.size() != 3) colour.clear();
  }
  // Without R, G and B by name, the channels are taken by position, so there may be no more
  // than grey+alpha or RGBA; with them, other channels (depth, normals) are left out.
  if (colour.empty() && (image.channels < 1 || image.channels > 4))
    throw InputError(name, "exemplar has " + std::to_string(image.channels) +
                               " channels; expected grey, grey+alpha, RGB or RGBA");
  if (colour.empty())
    for (int c = 0; c < image.channels; ++c)
      if (c != alpha) colour.push_back(c);
  if (colour.size() != 1 && colour.size() != 3) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ",") + n;
    throw InputError(name, "exemplar has " + std::to_string(colour.size()) + " colour channels" +
                               (list.empty() ? "" : " (" + list + ")") +
                               "; expected grey, grey+alpha, RGB or RGBA");
  }
  Image rgb(image.width, image.height, 3);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      if (alpha >= 0) {
        const float a = image.at(x, y, alpha);
        if (!(a >= 0.999f))
          throw InputError(name, "exemplar pixel (" + std::to_string(x) + "," + std::to_string(y) +
                                     ") is transparent (alpha " + std::to_string(a) +
                                     "); exemplars must be opaque");
      }
      for (int c = 0; c < 3; ++c) {
        const float v = image.at(x, y, colour[colour.size() == 1 ? 0 : c]);
        if (!std::isfinite(v))
          throw InputError(name, "exemplar pixel (" + std::to_string(x) + "," + std::to_string(y) +
                                     ") is not a finite number");
        rgb.at(x, y, c) = std::clamp(v, 0.0f, 1.0f);
        if (clipped && rgb.at(x, y, c) != v) ++*clipped;
      }
    }
  }
  return rgb;
}

Image load_exemplar(const std::string& path, long long* clipped) {
  return to_rgb_exemplar(isochart::read_image(path), path, clipped);
}

ExemplarLevel resample_exemplar(const Image& rgb, double factor) {
  ExemplarLevel out;
  const int w = std::max(4, static_cast<int>(std::lround(rgb.width / factor)));
  const int h = std::max(4, static_cast<int>(std::lround(rgb.height * w / double(rgb.width))));
  out.actual_factor = rgb.width / double(w);
  const double fx = rgb.width / double(w), fy = rgb.height / double(h);
  out.image = Image(w, h, 3);
  auto px = [&](int x, int y, int c) {
    return rgb.at(std::clamp(x, 0, rgb.width - 1), std::clamp(y, 0, rgb.height - 1), c);
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double cx = (x + 0.5) * fx - 0.5, cy = (y + 0.5) * fy - 0.5;
      float acc[3] = {0, 0, 0};
      if (fx <= 1.0 && fy <= 1.0) {
        const int x0 = static_cast<int>(std::floor(cx)), y0 = static_cast<int>(std::floor(cy));
        const double ax = cx - x0, ay = cy - y0;
        for (int c = 0; c < 3; ++c)
          acc[c] = static_cast<float>((1 - ay) * ((1 - ax) * px(x0, y0, c) + ax * px(x0 + 1, y0, c)) +
                                      ay * ((1 - ax) * px(x0, y0 + 1, c) + ax * px(x0 + 1, y0 + 1, c)));
      } else {
        // Gaussian pre-filter: wide enough that the shrunk pattern does not alias.
        const double sx = 0.5 * std::max(fx, 1.0), sy = 0.5 * std::max(fy, 1.0);
        const int rx = static_cast<int>(std::ceil(2.5 * sx)), ry = static_cast<int>(std::ceil(2.5 * sy));
        const int ix = static_cast<int>(std::lround(cx)), iy = static_cast<int>(std::lround(cy));
        double wsum = 0, sum[3] = {0, 0, 0};
        for (int j = iy - ry; j <= iy + ry; ++j) {
          for (int i = ix - rx; i <= ix + rx; ++i) {
            const double dx = (i - cx) / sx, dy = (j - cy) / sy;
            const double wgt = std::exp(-0.5 * (dx * dx + dy * dy));
            wsum += wgt;
            for (int c = 0; c < 3; ++c) sum[c] += wgt * px(i, j, c);
          }
        }
        for (int c = 0; c < 3; ++c) acc[c] = static_cast<float>(sum[c] / wsum);
      }
      for (int c = 0; c < 3; ++c) out.image.at(x, y, c) = acc[c];
    }
  }
  return out;
}

std::vector<ExemplarLevel> exemplar_pyramid(const Image& rgb, const std::vector<double>& factors) {
  std::vector<ExemplarLevel> levels;
  levels.reserve(factors.size());
  for (double f : factors) levels.push_back(resample_exemplar(rgb, f));
  return levels;
}

double correlation_length(const Image& rgb, double threshold) {
  const std::array<double, 4> c = correlation_lengths(rgb, threshold);
  return *std::max_element(c.begin(), c.end());
}

std::array<double, 4> correlation_lengths(const Image& rgb, double threshold) {
  std::array<double, 4> out{{0, 0, 0, 0}};
  const int w = rgb.width, h = rgb.height, ch = rgb.channels;
  if (w < 2 || h < 2 || ch < 1) return out;
  std::vector<double> centred(static_cast<std::size_t>(w) * h * ch);
  double var = 0;
  for (int c = 0; c < ch; ++c) {
    double mean = 0;
    for (int i = 0; i < w * h; ++i) mean += rgb.pixels[static_cast<std::size_t>(i) * ch + c];
    mean /= w * h;
    for (int i = 0; i < w * h; ++i) {
      const double v = rgb.pixels[static_cast<std::size_t>(i) * ch + c] - mean;
      centred[static_cast<std::size_t>(i) * ch + c] = v;
      var += v * v;
    }
  }
  var /= w * h;
  const int max_lag = std::max(1, std::min(w, h) / 2);
  if (var <= 1e-12) return out;
  // A regular sub-grid keeps the cost bounded for large exemplars.
  const int step = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(w) * h / 65536.0))));
  const int dirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
  for (int di = 0; di < 4; ++di) {
    const auto& d = dirs[di];
    const double unit = std::sqrt(double(d[0] * d[0] + d[1] * d[1]));
    double reach = max_lag * unit;
    for (int k = 1; k <= max_lag; ++k) {
      const int ax = d[0] * k, ay = d[1] * k;
      double sum = 0;
      long long n = 0;
      for (int y = std::max(0, -ay); y < std::min(h, h - ay); y += step)
        for (int x = std::max(0, -ax); x < std::min(w, w - ax); x += step) {
          const double* a = &centred[(static_cast<std::size_t>(y) * w + x) * ch];
          const double* b = &centred[(static_cast<std::size_t>(y + ay) * w + x + ax) * ch];
          for (int c = 0; c < ch; ++c) sum += a[c] * b[c];
          ++n;
        }
      if (n == 0 || sum / n / var <= threshold) {
        reach = k * unit;
        break;
      }
    }
    out[di] = reach;
  }
  return out;
}

double exemplar_smoothness(const Image& rgb, double lag) {
  const int w = rgb.width, h = rgb.height, ch = rgb.channels;
  const int k = std::max(1, static_cast<int>(std::lround(lag)));
  if (w <= k || h <= k || ch < 1) return 1;
  std::vector<double> mean(ch, 0.0);
  for (int i = 0; i < w * h; ++i)
    for (int c = 0; c < ch; ++c) mean[c] += rgb.pixels[static_cast<std::size_t>(i) * ch + c];
  for (double& m : mean) m /= w * h;
  double var = 0;
  for (int i = 0; i < w * h; ++i)
    for (int c = 0; c < ch; ++c) {
      const double v = rgb.pixels[static_cast<std::size_t>(i) * ch + c] - mean[c];
      var += v * v;
    }
  var /= w * h;
  if (var <= 1e-12) return 1;
  auto corr = [&](int ax, int ay) {
    double sum = 0;
    long long n = 0;
    for (int y = 0; y + ay < h; ++y)
      for (int x = 0; x + ax < w; ++x) {
        for (int c = 0; c < ch; ++c)
          sum += (rgb.pixels[(static_cast<std::size_t>(y) * w + x) * ch + c] - mean[c]) *
                 (rgb.pixels[(static_cast<std::size_t>(y + ay) * w + x + ax) * ch + c] - mean[c]);
        ++n;
      }
    return sum / n / var;
  };
  return std::min(corr(k, 0), corr(0, k));
}

std::vector<std::string> exemplar_names() { return {"bricks", "cells", "weave", "noise"}; }

namespace {

// Periodic value noise on a lattice of `period` cells over [0,1)², smooth (quintic) blending.
struct PeriodicNoise {
  int period;
  std::uint64_t seed;
  double lattice(int i, int j) const {
    i = ((i % period) + period) % period;
    j = ((j % period) + period) % period;
    return isochart::Rng(isochart::mix_seed(seed, std::uint64_t(i) * 7919u + std::uint64_t(j))).uniform();
  }
  double operator()(double u, double v) const {
    const double x = u * period, y = v * period;
    const int i = static_cast<int>(std::floor(x)), j = static_cast<int>(std::floor(y));
    auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
    const double a = fade(x - i), b = fade(y - j);
    return (1 - b) * ((1 - a) * lattice(i, j) + a * lattice(i + 1, j)) +
           b * ((1 - a) * lattice(i, j + 1) + a * lattice(i + 1, j + 1));
  }
};

double fractal(std::uint64_t seed, double u, double v, int base, int octaves) {
  double sum = 0, amp = 0.5, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * PeriodicNoise{base << o, isochart::mix_seed(seed, o)}(u, v);
    norm += amp;
    amp *= 0.5;
  }
  return sum / norm;
}

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

}  // namespace

Image make_exemplar(const std::string& name, int size, std::uint64_t seed) {
  const std::string label = "builtin:" + name;
  if (size < 8) throw InputError(label, "exemplar size " + std::to_string(size) + " is below 8");
  const auto names = exemplar_names();
  if (std::find(names.begin(), names.end(), name) == names.end())
    throw InputError(label, "unknown exemplar; known: bricks, cells, weave, noise");
  Image img(size, size, 3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size, v = (y + 0.5) / size;
      const double grain = fractal(seed ^ 0x51u, u, v, 8, 4);
      double rgb[3] = {0, 0, 0};
      if (name == "bricks") {
        // 4 rows of 2 bricks, every other row offset by half a brick.
        const double rows = 4, cols = 2;
        const double ry = v * rows;
        const int row = static_cast<int>(std::floor(ry));
        double rx = u * cols + (row % 2) * 0.5;
        const int col = static_cast<int>(std::floor(rx));
        const double fy = ry - row, fx = rx - col;
        const double mortar_y = std::min(fy, 1 - fy) * (1.0 / rows);
        const double mortar_x = std::min(fx, 1 - fx) * (1.0 / cols);
        const double m = smoothstep(0.008, 0.018, std::min(mortar_x, mortar_y));
        isochart::Rng r(isochart::mix_seed(seed, std::uint64_t(row * 16 + (col % int(cols)))));
        const double tone = 0.8 + 0.35 * r.uniform();
        const double brick[3] = {0.62 * tone, 0.26 * tone, 0.17 * tone};
        const double mortar[3] = {0.78, 0.76, 0.7};
        for (int c = 0; c < 3; ++c)
          rgb[c] = (m * brick[c] + (1 - m) * mortar[c]) * (0.8 + 0.4 * grain);
      } else if (name == "cells") {
        // Periodic Worley cells: dark borders where the two nearest sites are equidistant.
        const int n = 5;
        double d1 = 1e9, d2 = 1e9;
        int id = 0;
        for (int j = -1; j <= n; ++j) {
          for (int i = -1; i <= n; ++i) {
            const int ci = ((i % n) + n) % n, cj = ((j % n) + n) % n;
            isochart::Rng r(isochart::mix_seed(seed + 77, std::uint64_t(cj * n + ci)));
            const double sx = (i + 0.15 + 0.7 * r.uniform()) / n, sy = (j + 0.15 + 0.7 * r.uniform()) / n;
            const double d = std::hypot(u - sx, v - sy);
            if (d < d1) {
              d2 = d1;
              d1 = d;
              id = cj * n + ci;
            } else if (d < d2) {
              d2 = d;
            }
          }
        }
        isochart::Rng r(isochart::mix_seed(seed + 99, std::uint64_t(id)));
        const double t = 0.7 + 0.3 * r.uniform();
        const double border = smoothstep(0.006, 0.02, d2 - d1);
        const double inner = 1 - 0.35 * d1 * n;
        const double cell[3] = {0.35 * t * inner, 0.62 * t * inner, 0.3 * t * inner};
        for (int c = 0; c < 3; ++c) rgb[c] = border * cell[c] + (1 - border) * 0.08;
      } else if (name == "weave") {
        // Basket weave: 4×4 blocks alternating horizontal and vertical strands.
        const double n = 4;
        const int bx = static_cast<int>(std::floor(u * n)), by = static_cast<int>(std::floor(v * n));
        const bool horizontal = (bx + by) % 2 == 0;
        const double a = horizontal ? v * n * 3 : u * n * 3;  // 3 strands per block
        const double along = horizontal ? u * n : v * n;
        const double s = std::sin(M_PI * (a - std::floor(a)));
        const double shade = (0.35 + 0.65 * s) * (0.85 + 0.15 * std::cos(2 * M_PI * along));
        const double base[3] = {0.8, 0.65, 0.4};
        for (int c = 0; c < 3; ++c) rgb[c] = base[c] * shade * (0.9 + 0.2 * grain);
      } else {  // noise
        const double f = fractal(seed, u, v, 4, 5);
        const double g = fractal(seed + 3, u, v, 4, 3);
        rgb[0] = 0.25 + 0.6 * f;
        rgb[1] = 0.3 + 0.5 * g;
        rgb[2] = 0.45 + 0.4 * (1 - f);
      }
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(std::clamp(rgb[c], 0.0, 1.0));
    }
  }
  return img;
}

Image exemplar_from(const std::string& spec, long long* clipped) {
  const std::string prefix = "builtin:";
  if (clipped) *clipped = 0;
  if (spec.rfind(prefix, 0) == 0) return make_exemplar(spec.substr(prefix.size()));
  return load_exemplar(spec, clipped);
}

}  // namespace synth
