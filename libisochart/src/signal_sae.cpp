// Baking a signal into an atlas texture and the signal approximation error (Iso-charts §9.3;
// Sander et al. 2002 §5).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "isochart/error.h"
#include "isochart/signal.h"

namespace isochart {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Texel-space position of a texture coordinate: x to the right, y down from the top row.
Vec2d to_texel(const Vec2d& uv, int w, int h) {
  return {uv.x * w, (1.0 - uv.y) * h};
}

// Closest point of segment ab to p, as the parameter along ab.
double segment_param(const Vec2d& a, const Vec2d& b, const Vec2d& p) {
  const Vec2d d = b - a;
  const double l2 = squared_norm(d);
  return l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0.0;
}

// Closest point of triangle (t0, t1, t2) to p: its barycentrics (b1, b2) and distance.
double closest_point(const Vec2d t[3], const Vec2d& p, double& b1, double& b2) {
  const double area = cross(t[1] - t[0], t[2] - t[0]);
  if (std::abs(area) > 0) {
    const double l1 = cross(p - t[0], t[2] - t[0]) / area;
    const double l2 = cross(t[1] - t[0], p - t[0]) / area;
    if (l1 >= 0 && l2 >= 0 && l1 + l2 <= 1) {
      b1 = l1;
      b2 = l2;
      return 0;
    }
  }
  double best = kInf;
  for (int k = 0; k < 3; ++k) {
    const Vec2d& a = t[k];
    const Vec2d& b = t[(k + 1) % 3];
    const double s = segment_param(a, b, p);
    const double d = norm(a + (b - a) * s - p);
    if (d < best) {
      best = d;
      double bc[3] = {0, 0, 0};
      bc[k] = 1 - s;
      bc[(k + 1) % 3] = s;
      b1 = bc[1];
      b2 = bc[2];
    }
  }
  return best;
}

void check_size(int w, int h) {
  if (w < 1 || h < 1 || w > 16384 || h > 16384)
    throw InputError("", "texture size " + std::to_string(w) + "x" + std::to_string(h) +
                             " is out of range (1..16384 per side)");
}

}  // namespace

namespace {

// The rest of the gutter: breadth-first dilation from the `filled` texels, each new texel the
// mean of its filled 8-neighbours from earlier layers.
void fill_gutter(Image& img, std::vector<char> filled) {
  const int width = img.width, height = img.height, dim = img.channels;
  const size_t n = static_cast<size_t>(width) * height;
  std::vector<char> queued(n, 0);
  std::vector<int> layer;
  auto enqueue_neighbours = [&](size_t i) {
    const int x = static_cast<int>(i % width), y = static_cast<int>(i / width);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
        const size_t j = static_cast<size_t>(ny) * width + nx;
        if (!filled[j] && !queued[j]) {
          queued[j] = 1;
          layer.push_back(static_cast<int>(j));
        }
      }
  };
  for (size_t i = 0; i < n; ++i)
    if (filled[i]) enqueue_neighbours(i);
  while (!layer.empty()) {
    std::sort(layer.begin(), layer.end());  // row by row: the reads stay in cache
    const std::vector<int> current = std::move(layer);
    layer.clear();
    // A layer's texels read only earlier layers, so they are independent of each other and
    // of their order: in parallel, with the same result on any thread count.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, current.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                        std::vector<float> sum(dim);
                        for (size_t k = r.begin(); k < r.end(); ++k) {
                          const int i = current[k];
                          const int x = i % width, y = i / width;
                          std::fill(sum.begin(), sum.end(), 0.0f);
                          int count = 0;
                          for (int dy = -1; dy <= 1; ++dy)
                            for (int dx = -1; dx <= 1; ++dx) {
                              const int nx = x + dx, ny = y + dy;
                              if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
                              const size_t j = static_cast<size_t>(ny) * width + nx;
                              if (!filled[j]) continue;
                              for (int c = 0; c < dim; ++c) sum[c] += img.pixels[j * dim + c];
                              ++count;
                            }
                          for (int c = 0; c < dim; ++c)
                            img.pixels[static_cast<size_t>(i) * dim + c] = count ? sum[c] / count : 0.0f;
                        }
                      });
    for (int i : current) filled[i] = 1;
    for (int i : current) enqueue_neighbours(static_cast<size_t>(i));
  }
}

// Texels near a chart take the signal at the nearest point of the nearest triangle, so a
// bilinear lookup anywhere inside the chart only mixes the chart's own signal.
constexpr double kReach = 1.5;

// Rows [y_begin, y_end) of a width × height bake: each texel within kReach of a face of
// `faces` (every face when null; the earlier face at equal distance) takes `evaluate(f, b1,
// b2, out)`, `dim` values at barycentric point (1 − b1 − b2, b1, b2) of face f, into `values`
// (the rows' texels × dim, row y_begin first), its distance into `dist` (kInf elsewhere).
template <class Evaluate>
void bake_rows(const Mesh& mesh, int dim, int width, int height, int y_begin, int y_end,
               const std::vector<int>* faces, const Evaluate& evaluate, float* values, double* dist) {
  std::fill(dist, dist + static_cast<size_t>(y_end - y_begin) * width, kInf);
  std::vector<double> value(dim);
  const int count = faces ? static_cast<int>(faces->size()) : mesh.num_faces();
  for (int k = 0; k < count; ++k) {
    const int f = faces ? (*faces)[k] : k;
    Vec2d t[3];
    for (int c = 0; c < 3; ++c) t[c] = to_texel(mesh.uvs[mesh.face_uvs[f][c]], width, height);
    if (!is_finite(t[0]) || !is_finite(t[1]) || !is_finite(t[2])) continue;
    const double lo_x = std::min({t[0].x, t[1].x, t[2].x}) - kReach,
                 hi_x = std::max({t[0].x, t[1].x, t[2].x}) + kReach;
    const double lo_y = std::min({t[0].y, t[1].y, t[2].y}) - kReach,
                 hi_y = std::max({t[0].y, t[1].y, t[2].y}) + kReach;
    const int x0 = std::max(0, static_cast<int>(std::floor(lo_x - 0.5)));
    const int x1 = std::min(width - 1, static_cast<int>(std::ceil(hi_x - 0.5)));
    const int y0 = std::max({0, y_begin, static_cast<int>(std::floor(lo_y - 0.5))});
    const int y1 = std::min({height - 1, y_end - 1, static_cast<int>(std::ceil(hi_y - 0.5))});
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        double b1 = 0, b2 = 0;
        const double d = closest_point(t, {x + 0.5, y + 0.5}, b1, b2);
        const size_t i = static_cast<size_t>(y - y_begin) * width + x;
        if (d > kReach || !(d < dist[i])) continue;
        dist[i] = d;
        evaluate(f, b1, b2, value.data());
        for (int c = 0; c < dim; ++c) values[i * dim + c] = static_cast<float>(value[c]);
      }
  }
}

// bake_signal's work for any signal (bake_rows over the whole image), the gutter filled.
template <class Evaluate>
Image bake_faces(const Mesh& mesh, int dim, int width, int height, const Evaluate& evaluate) {
  Image img(width, height, dim, 0.0f);
  const size_t n = static_cast<size_t>(width) * height;
  std::vector<double> dist(n);
  bake_rows(mesh, dim, width, height, 0, height, nullptr, evaluate, img.pixels.data(), dist.data());
  std::vector<char> filled(n);
  for (size_t i = 0; i < n; ++i) filled[i] = dist[i] < kInf;
  fill_gutter(img, std::move(filled));
  return img;
}

}  // namespace

Image bake_signal(const Mesh& mesh, const Signal& signal, int width, int height) {
  if (!mesh.has_uvs()) throw InputError("", "cannot bake a signal: mesh has no texture coordinates");
  check_size(width, height);
  if (signal.dimension < 1 || signal.dimension > 16)
    throw InputError("", "signal must have 1 to 16 channels");
  if (static_cast<int>(mesh.face_uvs.size()) != mesh.num_faces())
    throw InputError("", "cannot bake a signal: texture coordinates for " +
                             std::to_string(mesh.face_uvs.size()) + " faces, the mesh has " +
                             std::to_string(mesh.num_faces()));
  if (!signal.is_mapped() &&
      signal.vertex_values.size() != static_cast<size_t>(mesh.num_vertices()) * signal.dimension)
    throw InputError("", "signal has values for " +
                             std::to_string(signal.vertex_values.size() / signal.dimension) +
                             " vertices, the mesh has " + std::to_string(mesh.num_vertices()));
  if (signal.is_mapped() && static_cast<int>(signal.face_uvs.size()) != mesh.num_faces())
    throw InputError("", "mapped signal has texture coordinates for " +
                             std::to_string(signal.face_uvs.size()) + " faces, the mesh has " +
                             std::to_string(mesh.num_faces()));
  return bake_faces(mesh, signal.dimension, width, height,
                    [&](int f, double b1, double b2, double* out) { signal.evaluate(mesh, f, b1, b2, out); });
}

Image transfer_texture(const Mesh& source, const Image& texture, const Mesh& target, int width, int height,
                       int supersample, const TextureWrap& wrap) {
  if (texture.empty() || texture.channels < 1 || texture.channels > 16)
    throw InputError("", "cannot transfer a texture of " + std::to_string(texture.channels) + " channels");
  std::vector<TextureSource> sources(1);
  sources[0].image = texture;
  sources[0].wrap = wrap;
  return transfer_textures(source, std::move(sources), std::vector<int>(source.faces.size(), 0), target,
                           width, height, supersample);
}

Image transfer_textures(const Mesh& source, std::vector<TextureSource> sources,
                        const std::vector<int>& face_source, const Mesh& target, int width, int height,
                        int supersample) {
  const int nf = target.num_faces();
  if (source.num_faces() != nf)
    throw InputError("", "cannot transfer a texture between meshes of " + std::to_string(source.num_faces()) +
                             " and " + std::to_string(nf) + " faces");
  for (const Mesh* m : {&source, &target})
    if (!m->has_uvs() || static_cast<int>(m->face_uvs.size()) != nf)
      throw InputError("", std::string("cannot transfer a texture: the ") +
                               (m == &source ? "source" : "target") + " mesh has no texture coordinates");
  const int ns = static_cast<int>(sources.size());
  if (ns == 0) throw InputError("", "cannot transfer a texture: no texture given");
  if (static_cast<int>(face_source.size()) != nf)
    throw InputError("", "cannot transfer a texture: sources named for " +
                             std::to_string(face_source.size()) + " of " + std::to_string(nf) + " faces");
  for (int f = 0; f < nf; ++f)
    if (face_source[f] < 0 || face_source[f] >= ns)
      throw InputError("", "cannot transfer a texture: face " + std::to_string(f) + " names source " +
                               std::to_string(face_source[f]) + " of " + std::to_string(ns));
  if (supersample < 1 || supersample > 4)
    throw InputError("", "texture supersampling must be 1 to 4, got " + std::to_string(supersample));
  check_size(width, height);
  check_size(width * supersample, height * supersample);

  // The result's channels: one image's own; several images (and colours) meet in grey or RGB,
  // with alpha when any has it.
  int channels = 0, alpha = -1, bits = 8;
  std::vector<std::string> names;
  if (ns == 1 && !sources[0].image.empty()) {
    const Image& t = sources[0].image;
    if (t.channels < 1 || t.channels > 16)
      throw InputError("", "cannot transfer a texture of " + std::to_string(t.channels) + " channels");
    channels = t.channels;
    alpha = t.alpha_channel();
    names = t.channel_names;
    bits = t.bits;
  } else {
    bool colour = false, any_alpha = false;
    for (const TextureSource& src : sources) {
      const Image& t = src.image;
      if (t.empty()) {
        colour = colour || !(src.colour.x == src.colour.y && src.colour.y == src.colour.z);
        continue;
      }
      const int a = t.alpha_channel();
      const int colours = t.channels - (a >= 0 ? 1 : 0);
      if (t.channels > 4 || (colours != 1 && colours != 3) || (a >= 0 && a != t.channels - 1))
        throw InputError("", "cannot combine a texture of " + std::to_string(t.channels) +
                                 " channels with others (grey or RGB, with or without alpha, can be)");
      colour = colour || colours == 3;
      any_alpha = any_alpha || a >= 0;
      bits = std::max(bits, t.bits);
    }
    channels = (colour ? 3 : 1) + (any_alpha ? 1 : 0);
    alpha = any_alpha ? channels - 1 : -1;
  }
  // Straight alpha: a transparent texel's stored colour (often black) would bleed into its
  // neighbours' under bilinear filtering, so colours are filtered premultiplied.
  auto scale_colours = [&](Image& img, bool divide) {
    if (alpha < 0) return;
    for (std::size_t i = 0; i < img.pixels.size(); i += channels) {
      const float a = img.pixels[i + alpha];
      for (int c = 0; c < channels; ++c) {
        if (c == alpha) continue;
        float& v = img.pixels[i + c];
        v = divide ? (a > 0 ? v / a : 0.0f) : v * a;
      }
    }
  };
  // Each source as a mapped signal in the result's channels, premultiplied.
  std::vector<Signal> signals(ns);
  std::vector<std::vector<double>> constant(ns);
  for (int i = 0; i < ns; ++i) {
    TextureSource& src = sources[i];
    Signal& sig = signals[i];
    sig.dimension = channels;
    if (src.image.empty()) {
      const double grey = (src.colour.x + src.colour.y + src.colour.z) / 3;
      constant[i] = channels < 3 ? std::vector<double>{grey}
                                 : std::vector<double>{src.colour.x, src.colour.y, src.colour.z};
      if (alpha >= 0) constant[i].push_back(1.0);
      continue;
    }
    const Image& t = src.image;
    if (t.channels == channels) {
      sig.texture = std::move(src.image);  // an 8192² RGBA texture is a GiB as floats
    } else {
      const int a = t.alpha_channel(), colours = t.channels - (a >= 0 ? 1 : 0);
      sig.texture = Image(t.width, t.height, channels, 1.0f);
      for (std::size_t p = 0, n = static_cast<std::size_t>(t.width) * t.height; p < n; ++p) {
        const float* in = &t.pixels[p * t.channels];
        float* out = &sig.texture.pixels[p * channels];
        const int out_colours = channels - (alpha >= 0 ? 1 : 0);
        for (int c = 0; c < out_colours; ++c) out[c] = colours == 3 ? in[c] : in[0];
        if (alpha >= 0 && a >= 0) out[alpha] = in[a];
      }
      src.image = Image{};
    }
    sig.set_texture_coordinates(source.uvs, source.face_uvs, src.wrap);
    scale_colours(sig.texture, false);
    sig.face_lod.assign(nf, 0.0f);
  }
  // A face that reads many source texels for each sample taken (a 4096² texture carried to
  // 1024², or parts a layout squeezed) would alias: it reads a reduced copy of the texture
  // instead, chosen per face by the longer axis of its map from sample texels to source texels
  // (as a GPU's mipmapping does; the blur goes along the shorter axis too).
  const double sw = double(width) * supersample, sh = double(height) * supersample;
  std::vector<double> deepest(ns, 0.0);
  for (int f = 0; f < nf; ++f) {
    const int i = face_source[f];
    const Image& texture = signals[i].texture;
    if (texture.empty()) continue;
    const Face &a = source.face_uvs[f], &b = target.face_uvs[f];
    auto src = [&](int k) {
      return Vec2d{source.uvs[a[k]].x * texture.width, source.uvs[a[k]].y * texture.height};
    };
    auto dst = [&](int k) { return Vec2d{target.uvs[b[k]].x * sw, target.uvs[b[k]].y * sh}; };
    const Vec2d s1 = src(1) - src(0), s2 = src(2) - src(0), t1 = dst(1) - dst(0), t2 = dst(2) - dst(0);
    const double det = cross(t1, t2);
    if (!(std::abs(det) > 0)) continue;
    // J = [s1 s2] · [t1 t2]⁻¹, its largest singular value from the 2×2 closed form.
    const double j00 = (s1.x * t2.y - s2.x * t1.y) / det, j01 = (s2.x * t1.x - s1.x * t2.x) / det;
    const double j10 = (s1.y * t2.y - s2.y * t1.y) / det, j11 = (s2.y * t1.x - s1.y * t2.x) / det;
    const double e = j00 * j00 + j01 * j01 + j10 * j10 + j11 * j11, d = j00 * j11 - j01 * j10;
    const double sigma = std::sqrt(0.5 * (e + std::sqrt(std::max(e * e - 4 * d * d, 0.0))));
    if (sigma > 1 && std::isfinite(sigma)) {
      signals[i].face_lod[f] = static_cast<float>(std::log2(sigma));
      deepest[i] = std::max(deepest[i], static_cast<double>(signals[i].face_lod[f]));
    }
  }
  for (int i = 0; i < ns; ++i) {
    Signal& sig = signals[i];
    if (sig.texture.empty()) continue;
    for (int l = 0; l < static_cast<int>(std::ceil(deepest[i])); ++l) {
      const Image& from = l == 0 ? sig.texture : sig.mips.back();
      if (from.width == 1 && from.height == 1) break;
      sig.mips.push_back(
          resize_area(from, std::max(1, (from.width + 1) / 2), std::max(1, (from.height + 1) / 2)));
    }
  }
  // Baked in bands of rows, supersampled: a texel is the mean of its samples near a chart
  // (the rest of the gutter is filled at the texture's own size), so the supersampled image
  // never exists whole (at 8192² and 2×2 it took 4 GiB of colours and 2 GiB of distances).
  const int fw = width * supersample, fh = height * supersample;
  constexpr int kBandRows = 16;  // texture rows per band
  const int bands = (height + kBandRows - 1) / kBandRows;
  std::vector<std::vector<int>> band_faces(bands);
  for (int f = 0; f < nf; ++f) {
    double lo = kInf, hi = -kInf;
    for (int k = 0; k < 3; ++k) {
      const double y = to_texel(target.uvs[target.face_uvs[f][k]], fw, fh).y;
      lo = std::min(lo, y);
      hi = std::max(hi, y);
    }
    if (!std::isfinite(lo) || !std::isfinite(hi)) continue;
    const double first = std::floor((lo - kReach - 0.5) / supersample / kBandRows);
    const double last = std::ceil((hi + kReach - 0.5) / supersample / kBandRows);
    for (int b = static_cast<int>(std::clamp(first, 0.0, double(bands))); b < bands && b <= last; ++b)
      band_faces[b].push_back(f);
  }
  Image out(width, height, channels);
  out.channel_names = names;
  out.bits = bits;  // a 16-bit or float texture is not rounded to 8 bits on the way
  std::vector<char> near(static_cast<size_t>(width) * height, 0);
  const auto evaluate = [&](int f, double b1, double b2, double* value) {
    const int i = face_source[f];
    if (signals[i].texture.empty())
      std::copy(constant[i].begin(), constant[i].end(), value);
    else
      signals[i].evaluate(target, f, b1, b2, value);
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& r) {
    std::vector<float> values;
    std::vector<double> dist;
    std::vector<double> sum(channels);
    for (int b = r.begin(); b < r.end(); ++b) {
      const int y_begin = b * kBandRows, y_end = std::min(height, y_begin + kBandRows);
      const int rows = (y_end - y_begin) * supersample;
      values.assign(static_cast<size_t>(rows) * fw * channels, 0.0f);
      dist.resize(static_cast<size_t>(rows) * fw);
      bake_rows(target, channels, fw, fh, y_begin * supersample, y_end * supersample, &band_faces[b],
                evaluate, values.data(), dist.data());
      for (int y = y_begin; y < y_end; ++y)
        for (int x = 0; x < width; ++x) {
          std::fill(sum.begin(), sum.end(), 0.0);
          int count = 0;
          for (int dy = 0; dy < supersample; ++dy)
            for (int dx = 0; dx < supersample; ++dx) {
              const size_t i =
                  static_cast<size_t>((y - y_begin) * supersample + dy) * fw + x * supersample + dx;
              if (!(dist[i] < kInf)) continue;
              for (int c = 0; c < channels; ++c) sum[c] += values[i * channels + c];
              ++count;
            }
          if (count == 0) continue;
          near[static_cast<size_t>(y) * width + x] = 1;
          for (int c = 0; c < channels; ++c) out.at(x, y, c) = static_cast<float>(sum[c] / count);
        }
    }
  });
  signals.clear();  // the textures, before the gutter's work
  fill_gutter(out, std::move(near));
  scale_colours(out, true);
  // Where the texture is wholly transparent its colour is lost in the premultiplied mean; a
  // reader filtering the straight colours (bilinear, mipmaps) would still mix it into the
  // visible texels next to it, so it takes theirs.
  if (alpha >= 0) {
    std::vector<char> visible(static_cast<std::size_t>(width) * height);
    for (std::size_t i = 0; i < visible.size(); ++i) visible[i] = out.pixels[i * channels + alpha] > 0;
    fill_from_nearest(out, visible, alpha);
  }
  return out;
}

SaeResult signal_approximation_error(const Mesh& mesh, const Signal& signal, int width, int height,
                                     Image* baked) {
  const auto t0 = std::chrono::steady_clock::now();
  const Image img = bake_signal(mesh, signal, width, height);
  const int dim = signal.dimension;
  std::vector<double> truth(dim), sum(dim, 0.0);
  float rec[16];
  double err = 0, sq = 0, total = 0;
  long long samples = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& F = mesh.faces[f];
    const double area = triangle_area(mesh.positions[F[0]], mesh.positions[F[1]], mesh.positions[F[2]]);
    if (!(area > 0)) continue;
    const Vec2d u[3] = {mesh.uvs[mesh.face_uvs[f][0]], mesh.uvs[mesh.face_uvs[f][1]],
                        mesh.uvs[mesh.face_uvs[f][2]]};
    double extent = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec2d d = u[(k + 1) % 3] - u[k];
      extent = std::max({extent, std::abs(d.x) * width, std::abs(d.y) * height});
    }
    // Sub-triangles of at most half a texel: the midpoint rule then resolves the bilinear
    // reconstruction's variation.
    const int n = std::clamp(static_cast<int>(std::ceil(2 * extent)), 1, 64);
    const double w = area / (static_cast<double>(n) * n);
    auto sample = [&](double b1, double b2) {
      signal.evaluate(mesh, f, b1, b2, truth.data());
      const Vec2d uv = u[0] * (1 - b1 - b2) + u[1] * b1 + u[2] * b2;
      sample_bilinear(img, uv.x, uv.y, rec, Wrap::Clamp);
      double d2 = 0;
      for (int c = 0; c < dim; ++c) {
        const double d = truth[c] - rec[c];
        d2 += d * d;
        sum[c] += w * truth[c];
        sq += w * truth[c] * truth[c];
      }
      err += w * d2;
      total += w;
      ++samples;
    };
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        sample((i + 1.0 / 3) / n, (j + 1.0 / 3) / n);
        if (i + j + 1 < n) sample((i + 2.0 / 3) / n, (j + 2.0 / 3) / n);
      }
  }
  SaeResult r;
  r.samples = samples;
  if (total > 0) {
    r.sae = std::sqrt(err / total);
    double mean2 = 0;
    for (int c = 0; c < dim; ++c) mean2 += (sum[c] / total) * (sum[c] / total);
    r.signal_rms = std::sqrt(std::max(sq / total - mean2, 0.0));
  }
  if (baked) *baked = std::move(img);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace isochart
