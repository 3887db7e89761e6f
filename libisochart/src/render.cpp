// Software rasterizer: a visibility pass (z-buffer of face ids per sample) followed by a
// shading pass, so every sample is shaded once and wireframe distances come from the same
// screen-space barycentrics. Views are rendered in parallel into disjoint columns of the
// output, so the pixels do not depend on the thread count.
#include "isochart/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <malloc.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "isochart/error.h"
#include "isochart/stretch.h"

namespace isochart {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxSide = 16384;
// Samples per render after supersampling: 12 bytes each for the 3D renderer (depth, face),
// 12 for the UV layout (RGB), so at most about 400 MB.
constexpr long long kMaxSamples = 1LL << 25;

// Light, distinct hues; neighbouring entries differ strongly so a greedy pick looks varied.
const Vec3d kPalette[] = {
    {0.93, 0.56, 0.47}, {0.52, 0.72, 0.91}, {0.62, 0.83, 0.50}, {0.96, 0.80, 0.42},
    {0.74, 0.62, 0.90}, {0.44, 0.81, 0.78}, {0.94, 0.63, 0.80}, {0.80, 0.79, 0.44},
    {0.56, 0.63, 0.87}, {0.97, 0.68, 0.38}, {0.64, 0.87, 0.72}, {0.82, 0.55, 0.62},
};
constexpr int kPaletteSize = static_cast<int>(sizeof(kPalette) / sizeof(kPalette[0]));

const Vec3d kGrey{0.80, 0.79, 0.77};
const Vec3d kWire{0.12, 0.12, 0.14};

void check_size(int width, int height, int supersample) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw InputError("", "image size " + std::to_string(width) + "x" + std::to_string(height) +
                             " is out of range (1 to " + std::to_string(kMaxSide) + " pixels per side)");
  if (static_cast<long long>(width) * height * supersample * supersample > kMaxSamples)
    throw InputError(
        "", "image size " + std::to_string(width) + "x" + std::to_string(height) + " at " + std::to_string(supersample) +
                "x" + std::to_string(supersample) + " samples per pixel is too large to render (at most " +
                std::to_string(kMaxSamples) + " samples in all)");
}

void check_mesh(const Mesh& mesh) {
  if (mesh.faces.empty()) throw InputError("", "mesh has no faces; nothing to render");
  const int nv = mesh.num_vertices();
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.faces[f])
      if (v < 0 || v >= nv)
        throw InputError("", "face " + std::to_string(f) + " has vertex index " + std::to_string(v) +
                                 " out of range (" + std::to_string(nv) + " vertices)");
  for (const Face& f : mesh.faces)
    for (int v : f)
      if (!is_finite(mesh.positions[v]))
        throw InputError("", "vertex " + std::to_string(v) + " is not finite");
}

void check_uvs(const Mesh& mesh) {
  if (mesh.face_uvs.size() != mesh.faces.size())
    throw InputError("", "mesh has texture coordinates for " + std::to_string(mesh.face_uvs.size()) + " of " +
                             std::to_string(mesh.faces.size()) + " faces");
  const int nt = static_cast<int>(mesh.uvs.size());
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int t : mesh.face_uvs[f]) {
      if (t < 0 || t >= nt)
        throw InputError("", "face " + std::to_string(f) + " has texture coordinate index " +
                                 std::to_string(t) + " out of range (" + std::to_string(nt) + ")");
      if (!is_finite(mesh.uvs[t]))
        throw InputError("", "texture coordinate " + std::to_string(t) + " is not finite");
    }
}

// Renumbers arbitrary ids to 0..n-1 in increasing order of the original id.
std::vector<int> compact_ids(const std::vector<int>& ids, int& n) {
  std::vector<int> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<int> out(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i)
    out[i] = static_cast<int>(std::lower_bound(sorted.begin(), sorted.end(), ids[i]) - sorted.begin());
  n = static_cast<int>(sorted.size());
  return out;
}

// Per-corner normals (3 per face): area-weighted face normals around the vertex, only from
// faces within 60° of the corner's face, so creases stay sharp and smooth parts look smooth.
std::vector<Vec3d> corner_normals(const Mesh& mesh, const std::vector<Vec3d>& fn) {
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  std::vector<int> offset(nv + 1, 0), incident(3 * static_cast<std::size_t>(nf));
  for (const Face& f : mesh.faces)
    for (int v : f) ++offset[v + 1];
  for (int v = 0; v < nv; ++v) offset[v + 1] += offset[v];
  std::vector<int> fill(offset.begin(), offset.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int v : mesh.faces[f]) incident[fill[v]++] = f;
  std::vector<Vec3d> weighted(nf);
  for (int f = 0; f < nf; ++f) {
    const Face& t = mesh.faces[f];
    const auto& p = mesh.positions;
    weighted[f] = cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]);  // normal × twice the area
  }
  const double cos_crease = std::cos(60.0 * kPi / 180.0);
  std::vector<Vec3d> out(3 * static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.faces[f][k];
      Vec3d sum;
      for (int i = offset[v]; i < offset[v + 1]; ++i) {
        const int g = incident[i];
        if (dot(fn[f], fn[g]) >= cos_crease) sum += weighted[g];
      }
      const Vec3d n = normalized(sum);
      out[3 * f + k] = squared_norm(n) > 0 ? n : fn[f];
    }
  }
  return out;
}

struct ViewAngles {
  double azimuth, elevation;  // degrees
};
const ViewAngles kViews[8] = {{0, 15}, {90, 15}, {180, 15}, {270, 15},
                              {0, 90}, {0, -90}, {45, 30},  {225, 30}};

struct Camera {
  Vec3d eye, right, up, forward;
  bool perspective = true;
};

Camera make_camera(const Vec3d& model_up, const ViewAngles& view, const Vec3d& centre, double radius,
                   bool perspective) {
  Vec3d u = normalized(model_up);
  if (squared_norm(u) == 0) u = {0, 1, 0};
  Vec3d f0 = Vec3d{0, 0, 1} - u * u.z;
  if (squared_norm(f0) < 1e-12) f0 = Vec3d{1, 0, 0} - u * u.x;
  f0 = normalized(f0);
  const Vec3d r0 = cross(u, f0);
  const double az = view.azimuth * kPi / 180, el = view.elevation * kPi / 180;
  const Vec3d dir = (r0 * std::sin(az) + f0 * std::cos(az)) * std::cos(el) + u * std::sin(el);
  Camera c;
  c.perspective = perspective;
  c.forward = -dir;
  // Looking straight down (up), the model's front is at the bottom (top) of the image.
  const Vec3d ref = std::abs(view.elevation) > 89 ? (view.elevation > 0 ? -f0 : f0) : u;
  c.right = normalized(cross(c.forward, ref));
  c.up = cross(c.right, c.forward);
  // A 30° field of view just containing the bounding sphere; the fit below rescales.
  c.eye = centre + dir * (radius / std::sin(15.0 * kPi / 180.0));
  return c;
}

// Everything the shading pass needs about one face's projection.
struct ScreenVertex {
  double x, y;   // sample coordinates (x right, y down)
  double key;    // larger is closer; linear in screen space
  double inv_w;  // 1/depth for perspective-correct interpolation (1 for orthographic)
};

struct Shared {
  const Mesh* mesh;
  const RenderOptions* options;
  std::vector<Vec3d> face_normal;
  std::vector<Vec3d> corner_normal;
  std::vector<Vec3d> face_color;  // Shaded / Charts
  // Textured: what each material's faces read (one material for RenderOptions::texture).
  struct Material {
    const Image* texture = nullptr;  // null: `colour`
    TextureWrap wrap;
    int alpha = -1;  // the texture's alpha channel, if it has one
    // With alpha, the texture with its colours multiplied by alpha: filtered straight, the
    // colour of transparent texels bled in as a fringe along alpha edges.
    Image premultiplied;
    Vec3d colour{1, 1, 1};
  };
  std::vector<Material> materials;
  std::vector<int> face_material;  // empty: material 0
  Vec3d centre;
  double radius;
  std::vector<char> referenced;
};

// Renders view `view` into columns [x0, x0 + tile_w) of `out`.
void render_view(const Shared& s, int view, int x0, int tile_w, Image& out) {
  const Mesh& mesh = *s.mesh;
  const RenderOptions& o = *s.options;
  const int ss = o.supersample;
  const int W = tile_w * ss, H = out.height * ss;
  const Camera cam = make_camera(o.up, kViews[view], s.centre, s.radius, o.perspective);

  // Project to the image plane, then fit the projected extent into the tile (lens shift and
  // zoom), so every view fills its column whatever the model's shape.
  const int nv = mesh.num_vertices();
  std::vector<ScreenVertex> sv(nv);
  double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
  for (int v = 0; v < nv; ++v) {
    if (!s.referenced[v]) continue;
    const Vec3d d = mesh.positions[v] - cam.eye;
    const double z = dot(d, cam.forward);
    double u = dot(d, cam.right), w = dot(d, cam.up);
    if (cam.perspective) {
      u /= z;
      w /= z;
    }
    sv[v] = {u, w, cam.perspective ? 1 / z : -z, cam.perspective ? 1 / z : 1.0};
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, w);
    vmax = std::max(vmax, w);
  }
  const double margin = 0.92;
  const double du = umax - umin, dv = vmax - vmin;
  double scale = std::min(du > 0 ? W * margin / du : std::numeric_limits<double>::infinity(),
                          dv > 0 ? H * margin / dv : std::numeric_limits<double>::infinity());
  if (!std::isfinite(scale)) scale = 1;
  const double uc = 0.5 * (umin + umax), vc = 0.5 * (vmin + vmax);
  for (int v = 0; v < nv; ++v) {
    if (!s.referenced[v]) continue;
    sv[v].x = 0.5 * W + scale * (sv[v].x - uc);
    sv[v].y = 0.5 * H - scale * (sv[v].y - vc);
  }

  // Visibility pass.
  const std::size_t n_samples = static_cast<std::size_t>(W) * H;
  std::vector<double> zbuf(n_samples, -std::numeric_limits<double>::infinity());
  std::vector<int> fid(n_samples, -1);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& t = mesh.faces[f];
    const ScreenVertex &a = sv[t[0]], &b = sv[t[1]], &c = sv[t[2]];
    const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (!(std::abs(area2) > 1e-12)) continue;
    const double inv = 1 / area2;
    const int xa = std::max(0, static_cast<int>(std::ceil(std::min({a.x, b.x, c.x}) - 0.5)));
    const int xb = std::min(W - 1, static_cast<int>(std::floor(std::max({a.x, b.x, c.x}) - 0.5)));
    const int ya = std::max(0, static_cast<int>(std::ceil(std::min({a.y, b.y, c.y}) - 0.5)));
    const int yb = std::min(H - 1, static_cast<int>(std::floor(std::max({a.y, b.y, c.y}) - 0.5)));
    for (int y = ya; y <= yb; ++y) {
      const double py = y + 0.5;
      for (int x = xa; x <= xb; ++x) {
        const double px = x + 0.5;
        const double l0 = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) * inv;
        const double l1 = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) * inv;
        const double l2 = 1 - l0 - l1;
        if (l0 < 0 || l1 < 0 || l2 < 0) continue;
        const double key = l0 * a.key + l1 * b.key + l2 * c.key;
        const std::size_t i = static_cast<std::size_t>(y) * W + x;
        if (key > zbuf[i]) {
          zbuf[i] = key;
          fid[i] = f;
        }
      }
    }
  }

  // Shading pass, one output pixel at a time (its samples shaded and box-filtered), so no
  // per-sample colour buffer is needed. Lights are fixed to the camera: a key light from the
  // upper left and a weaker fill from the right, both from the viewer's side.
  const Vec3d key_light = normalized(cam.right * -0.45 + cam.up * 0.55 - cam.forward * 0.7);
  const Vec3d fill_light = normalized(cam.right * 0.6 + cam.up * 0.1 - cam.forward * 0.5);
  const double wire_half_width = 0.5 * ss;  // one output pixel in total, half from each side
  float texel[64];
  const bool textured = o.color == ColorMode::Textured;
  auto shade = [&](int x, int y, int f) {
    const Face& t = mesh.faces[f];
    const ScreenVertex &a = sv[t[0]], &b = sv[t[1]], &c = sv[t[2]];
    const double px = x + 0.5, py = y + 0.5;
    const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    double l[3];
    l[0] = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area2;
    l[1] = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area2;
    l[2] = 1 - l[0] - l[1];
    // Perspective-correct weights for attributes.
    double m[3] = {l[0] * a.inv_w, l[1] * b.inv_w, l[2] * c.inv_w};
    const double msum = m[0] + m[1] + m[2];
    for (double& w : m) w /= msum;

    Vec3d n = normalized(s.corner_normal[3 * f] * m[0] + s.corner_normal[3 * f + 1] * m[1] +
                         s.corner_normal[3 * f + 2] * m[2]);
    if (squared_norm(n) == 0) n = s.face_normal[f];
    const Vec3d p = mesh.positions[t[0]] * m[0] + mesh.positions[t[1]] * m[1] + mesh.positions[t[2]] * m[2];
    const Vec3d to_eye = cam.perspective ? normalized(cam.eye - p) : -cam.forward;
    const bool back = dot(s.face_normal[f], to_eye) < 0;
    if (dot(n, to_eye) < 0) n = -n;

    Vec3d base;
    const Shared::Material* mat =
        !textured ? nullptr : &s.materials[s.face_material.empty() ? 0 : s.face_material[f]];
    if (mat && mat->texture) {
      const Image& tex = mat->alpha >= 0 ? mat->premultiplied : *mat->texture;
      const auto& uv = mesh.face_uvs[f];
      const Vec2d q = mesh.uvs[uv[0]] * m[0] + mesh.uvs[uv[1]] * m[1] + mesh.uvs[uv[2]] * m[2];
      sample_bilinear(tex, q.x, q.y, texel, mat->wrap.u, mat->wrap.v);
      base = tex.channels >= 3 ? Vec3d{texel[0], texel[1], texel[2]} : Vec3d{texel[0], texel[0], texel[0]};
      // A texture with alpha (RGBA, or grey and alpha) lies over the plain grey surface, as in
      // a viewer's blend, instead of showing the colour of its transparent texels.
      if (mat->alpha >= 0) {
        const double alpha = std::clamp<double>(texel[mat->alpha], 0.0, 1.0);
        base = base + kGrey * (1 - alpha);  // already multiplied by alpha
      }
    } else if (mat) {
      base = mat->colour;
    } else {
      base = s.face_color[f];
    }
    const double diffuse =
        0.22 + 0.66 * std::max(0.0, dot(n, key_light)) + 0.22 * std::max(0.0, dot(n, fill_light));
    const Vec3d half = normalized(key_light + to_eye);
    const double specular = 0.12 * std::pow(std::max(0.0, dot(n, half)), 40.0);
    Vec3d col = base * (diffuse * (back ? 0.6 : 1.0)) + Vec3d{specular, specular, specular};

    if (o.wireframe) {
      // Distance (in samples) to the nearest edge: barycentric × the opposite altitude.
      const double twice_area = std::abs(area2);
      const double e0 = std::hypot(c.x - b.x, c.y - b.y), e1 = std::hypot(a.x - c.x, a.y - c.y),
                   e2 = std::hypot(b.x - a.x, b.y - a.y);
      const double d = std::min({l[0] * twice_area / e0, l[1] * twice_area / e1, l[2] * twice_area / e2});
      if (d < wire_half_width) col = col * 0.15 + kWire * 0.85;
    }
    return Vec3d{std::clamp(col.x, 0.0, 1.0), std::clamp(col.y, 0.0, 1.0), std::clamp(col.z, 0.0, 1.0)};
  };

  const int nc = out.channels;
  const double total = ss * ss;
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < tile_w; ++x) {
      Vec3d sum;
      int hits = 0;
      for (int sy = 0; sy < ss; ++sy)
        for (int sx = 0; sx < ss; ++sx) {
          const int X = x * ss + sx, Y = y * ss + sy;
          const int f = fid[static_cast<std::size_t>(Y) * W + X];
          if (f < 0) continue;
          ++hits;
          sum += shade(X, Y, f);
        }
      // Straight alpha: a transparent image keeps the colour of the covered part; an opaque
      // one is composited over white.
      const Vec3d col = o.transparent ? (hits > 0 ? sum / hits : Vec3d{1, 1, 1})
                                      : (sum + Vec3d{1, 1, 1} * (total - hits)) / total;
      out.at(x0 + x, y, 0) = static_cast<float>(col.x);
      out.at(x0 + x, y, 1) = static_cast<float>(col.y);
      out.at(x0 + x, y, 2) = static_cast<float>(col.z);
      if (nc == 4) out.at(x0 + x, y, 3) = static_cast<float>(hits / total);
    }
  }
}

// Anti-aliased segment into an RGB sample buffer: coverage falls off over one sample.
void draw_segment(std::vector<float>& buf, int W, int H, Vec2d a, Vec2d b, double half_width,
                  const Vec3d& col, double alpha) {
  const double r = half_width + 1;
  const int xa = std::max(0, static_cast<int>(std::floor(std::min(a.x, b.x) - r)));
  const int xb = std::min(W - 1, static_cast<int>(std::ceil(std::max(a.x, b.x) + r)));
  const int ya = std::max(0, static_cast<int>(std::floor(std::min(a.y, b.y) - r)));
  const int yb = std::min(H - 1, static_cast<int>(std::ceil(std::max(a.y, b.y) + r)));
  const Vec2d ab = b - a;
  const double len2 = squared_norm(ab);
  for (int y = ya; y <= yb; ++y) {
    for (int x = xa; x <= xb; ++x) {
      const Vec2d p{x + 0.5, y + 0.5};
      const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
      const double d = norm(p - (a + ab * t));
      const double coverage = std::clamp(half_width + 0.5 - d, 0.0, 1.0);
      if (coverage <= 0) continue;
      const double w = alpha * coverage;
      float* px = &buf[3 * (static_cast<std::size_t>(y) * W + x)];
      px[0] = static_cast<float>(px[0] + (col.x - px[0]) * w);
      px[1] = static_cast<float>(px[1] + (col.y - px[1]) * w);
      px[2] = static_cast<float>(px[2] + (col.z - px[2]) * w);
    }
  }
}

}  // namespace

std::vector<Vec3d> chart_colors(const Mesh& mesh, const std::vector<int>& face_chart, int num_charts) {
  if (face_chart.size() != mesh.faces.size())
    throw InputError("", "chart ids for " + std::to_string(face_chart.size()) + " faces, mesh has " +
                             std::to_string(mesh.faces.size()));
  for (int c : face_chart)
    if (c < 0 || c >= num_charts)
      throw InputError(
          "", "chart id " + std::to_string(c) + " out of range (" + std::to_string(num_charts) + " charts)");
  std::vector<std::pair<int, int>> adjacent;
  const Topology topo(mesh);
  for (int e = 0; e < topo.num_edges(); ++e) {
    const IndexRange faces = topo.edge_faces(e);
    for (int i = 0; i < faces.size(); ++i)
      for (int j = 0; j < faces.size(); ++j) {
        const int a = face_chart[faces[i]], b = face_chart[faces[j]];
        if (a < b) adjacent.push_back({b, a});  // (later chart, earlier chart)
      }
  }
  std::sort(adjacent.begin(), adjacent.end());
  adjacent.erase(std::unique(adjacent.begin(), adjacent.end()), adjacent.end());

  // Greedy colouring in chart order: the first palette entry, starting at the chart's own
  // slot, that no earlier neighbour uses.
  std::vector<int> slot(num_charts);
  std::size_t k = 0;
  for (int c = 0; c < num_charts; ++c) {
    std::uint32_t used = 0;
    for (; k < adjacent.size() && adjacent[k].first == c; ++k) used |= 1u << slot[adjacent[k].second];
    slot[c] = c % kPaletteSize;
    for (int j = 0; j < kPaletteSize; ++j) {
      const int candidate = (c + j) % kPaletteSize;
      if (!(used & (1u << candidate))) {
        slot[c] = candidate;
        break;
      }
    }
  }
  std::vector<Vec3d> colors(num_charts);
  for (int c = 0; c < num_charts; ++c) colors[c] = kPalette[slot[c]];
  return colors;
}

Image render_mesh(const Mesh& input, const RenderOptions& options) {
  const RenderOptions& o = options;
  if (o.views < 1 || o.views > 8)
    throw InputError("", "views must be between 1 and 8, not " + std::to_string(o.views));
  if (o.supersample < 1 || o.supersample > 4)
    throw InputError("", "supersample must be between 1 and 4, not " + std::to_string(o.supersample));
  check_size(o.width, o.height, o.supersample);
  if (o.width < o.views)
    throw InputError("", "image width " + std::to_string(o.width) + " is too small for " +
                             std::to_string(o.views) + " views");
  check_mesh(input);
  // Drawn around the origin at unit size: the camera stood at least 1e-12 units away, so a
  // mesh 1e-28 across came out blank (its coordinates lost against the eye's), and 1e-14 across
  // already had noisy edges. Shading, chart colours and UVs do not depend on position or size.
  Mesh mesh = input;
  {
    Vec3d lo = mesh.positions[mesh.faces[0][0]], hi = lo;
    for (const Face& f : mesh.faces)
      for (int v : f) {
        const Vec3d& p = mesh.positions[v];
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      }
    const Vec3d centre = (lo + hi) * 0.5;
    const double half = 0.5 * norm(hi - lo);
    const double unit = half > 0 && std::isfinite(1 / half) ? 1 / half : 1.0;
    for (Vec3d& p : mesh.positions) p = (p - centre) * unit;
  }

  Shared s;
  s.mesh = &mesh;
  s.options = &o;
  const int nf = mesh.num_faces();
  s.face_normal = face_normals(mesh);
  s.corner_normal = corner_normals(mesh, s.face_normal);
  s.referenced.assign(mesh.num_vertices(), 0);
  Vec3d lo = mesh.positions[mesh.faces[0][0]], hi = lo;
  for (const Face& f : mesh.faces)
    for (int v : f) {
      s.referenced[v] = 1;
      const Vec3d& p = mesh.positions[v];
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
  s.centre = (lo + hi) * 0.5;
  s.radius = std::max(0.5 * norm(hi - lo), 1e-12 * (1 + norm(s.centre)));

  switch (o.color) {
    case ColorMode::Shaded:
      s.face_color.assign(nf, kGrey);
      break;
    case ColorMode::Charts: {
      std::vector<int> ids;
      if (!o.face_charts.empty()) {
        if (o.face_charts.size() != mesh.faces.size())
          throw InputError("", "face_charts has " + std::to_string(o.face_charts.size()) + " entries for " +
                                   std::to_string(nf) + " faces");
        ids = o.face_charts;
      } else if (!mesh.face_groups.empty()) {
        if (mesh.face_groups.size() != mesh.faces.size())
          throw InputError("", "mesh has face groups for " + std::to_string(mesh.face_groups.size()) +
                                   " of " + std::to_string(nf) + " faces");
        ids = mesh.face_groups;
      } else if (mesh.has_uvs()) {
        check_uvs(mesh);
        int n = 0;
        ids = uv_charts(mesh, n);
      } else {
        throw InputError("",
                         "colouring by chart needs face groups or texture coordinates; the mesh has neither");
      }
      int n = 0;
      const std::vector<int> chart = compact_ids(ids, n);
      const std::vector<Vec3d> colors = chart_colors(mesh, chart, n);
      s.face_color.resize(nf);
      for (int f = 0; f < nf; ++f) s.face_color[f] = colors[chart[f]];
      break;
    }
    case ColorMode::Textured:
      if (!mesh.has_uvs())
        throw InputError("", "textured rendering needs texture coordinates; the mesh has none");
      check_uvs(mesh);
      if (o.materials.empty()) {
        if (!o.texture || o.texture->empty())
          throw InputError("", "textured rendering needs a texture image");
        s.materials.push_back({o.texture, o.texture_wrap, -1, {}, {1, 1, 1}});
      } else {
        if (o.face_material.size() != mesh.faces.size())
          throw InputError("", "face_material has " + std::to_string(o.face_material.size()) +
                                   " entries for " + std::to_string(nf) + " faces");
        for (const int m : o.face_material)
          if (m < 0 || m >= static_cast<int>(o.materials.size()))
            throw InputError("", "face material " + std::to_string(m) + " out of range (" +
                                     std::to_string(o.materials.size()) + " materials)");
        for (const RenderOptions::Material& m : o.materials)
          s.materials.push_back(
              {m.texture && !m.texture->empty() ? m.texture : nullptr, m.wrap, -1, {}, m.colour});
        s.face_material = o.face_material;
      }
      {
        // An atlas (all UVs in the unit square) must not bleed across the texture's borders;
        // an axis the coordinates leave is read as the material says (by default it repeats).
        const int nm = static_cast<int>(s.materials.size());
        std::vector<char> out_u(nm, 0), out_v(nm, 0);
        for (int f = 0; f < nf; ++f) {
          const int m = s.face_material.empty() ? 0 : s.face_material[f];
          for (const int t : mesh.face_uvs[f]) {
            const Vec2d& uv = mesh.uvs[t];
            out_u[m] = out_u[m] || uv.x < 0 || uv.x > 1;
            out_v[m] = out_v[m] || uv.y < 0 || uv.y > 1;
          }
        }
        for (int m = 0; m < nm; ++m) {
          Shared::Material& mat = s.materials[m];
          if (!out_u[m]) mat.wrap.u = Wrap::Clamp;
          if (!out_v[m]) mat.wrap.v = Wrap::Clamp;
        }
      }
      for (Shared::Material& mat : s.materials) {
        if (!mat.texture) continue;
        if (mat.texture->channels > 64) throw InputError("", "texture has too many channels");
        mat.alpha = mat.texture->alpha_channel();
        if (mat.alpha < 0) continue;
        mat.premultiplied = *mat.texture;
        Image& pm = mat.premultiplied;
        for (std::size_t i = 0; i < pm.pixels.size(); i += pm.channels) {
          const float alpha = std::clamp(pm.pixels[i + mat.alpha], 0.0f, 1.0f);
          for (int c = 0; c < pm.channels; ++c)
            if (c != mat.alpha) pm.pixels[i + c] *= alpha;
        }
      }
      break;
  }

  Image out(o.width, o.height, o.transparent ? 4 : 3, 1.0f);
  tbb::parallel_for(tbb::blocked_range<int>(0, o.views, 1), [&](const tbb::blocked_range<int>& r) {
    for (int view = r.begin(); view < r.end(); ++view) {
      const int x0 = static_cast<int>(static_cast<long long>(view) * o.width / o.views);
      const int x1 = static_cast<int>(static_cast<long long>(view + 1) * o.width / o.views);
      render_view(s, view, x0, x1 - x0, out);
    }
  });
  return out;
}

Image render_uv_layout(const Mesh& mesh, int width, int height, double texture_aspect) {
  if (!mesh.has_uvs()) throw InputError("", "mesh has no texture coordinates; there is no UV layout to draw");
  if (!(texture_aspect > 0) || !std::isfinite(texture_aspect))
    throw InputError("", "the texture aspect ratio of a UV layout must be a positive number");
  const int ss = kUvLayoutSupersample;
  check_size(width, height, ss);
  check_mesh(mesh);
  check_uvs(mesh);

  int n_charts = 0;
  const std::vector<int> chart = uv_charts(mesh, n_charts);
  const std::vector<Vec3d> colors = chart_colors(mesh, chart, n_charts);

  Vec2d lo = mesh.uvs[mesh.face_uvs[0][0]], hi = lo;
  for (const Face& t : mesh.face_uvs)
    for (int i : t) {
      lo = {std::min(lo.x, mesh.uvs[i].x), std::min(lo.y, mesh.uvs[i].y)};
      hi = {std::max(hi.x, mesh.uvs[i].x), std::max(hi.y, mesh.uvs[i].y)};
    }
  // The view covers whole texture tiles (the unit square and its repeats), with their borders
  // drawn, so UVs that leave [0,1]² are seen against the texture; a layout spread over too
  // many tiles for that is drawn alone.
  const bool unit_square = lo.x >= -1e-9 && lo.y >= -1e-9 && hi.x <= 1 + 1e-9 && hi.y <= 1 + 1e-9;
  if (unit_square) {
    lo = {0, 0};
    hi = {1, 1};
  }
  constexpr double kMaxTiles = 16;
  const bool tiles = unit_square || (std::ceil(hi.x - 1e-9) - std::floor(lo.x + 1e-9) <= kMaxTiles &&
                                     std::ceil(hi.y - 1e-9) - std::floor(lo.y + 1e-9) <= kMaxTiles);
  if (tiles && !unit_square) {
    lo = {std::floor(lo.x + 1e-9), std::floor(lo.y + 1e-9)};
    hi = {std::ceil(hi.x - 1e-9), std::ceil(hi.y - 1e-9)};
  }
  // A unit of u is texture_aspect times as long as a unit of v on the texture.
  const double du = std::max((hi.x - lo.x) * texture_aspect, 1e-12), dv = std::max(hi.y - lo.y, 1e-12);
  const int W = width * ss, H = height * ss;
  const double margin = 0.03 * std::min(W, H);
  const double scale = std::max(std::min((W - 2 * margin) / du, (H - 2 * margin) / dv), 1e-300);
  const double ox = 0.5 * (W - du * scale), oy = 0.5 * (H - dv * scale);
  auto to_px = [&](const Vec2d& uv) {
    return Vec2d{ox + (uv.x - lo.x) * texture_aspect * scale, oy + (hi.y - uv.y) * scale};
  };

  // Segments to draw, in drawing order: the unit square, edges inside a chart thin and faint
  // (fainter when triangles are only a few pixels big, so dense charts keep their colour), then
  // chart boundaries (seams and mesh borders) dark.
  struct Segment {
    Vec2d a, b;
    double half_width;
    Vec3d col;
    double alpha;
  };
  double edge_length_sum = 0;
  std::vector<std::array<Vec2d, 3>> tri_px(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const auto& t = mesh.face_uvs[f];
    const Vec2d a = to_px(mesh.uvs[t[0]]), b = to_px(mesh.uvs[t[1]]), c = to_px(mesh.uvs[t[2]]);
    tri_px[f] = {a, b, c};
    edge_length_sum += norm(b - a) + norm(c - b) + norm(a - c);
  }
  const Topology topo(mesh);
  auto same_uv_across = [&](int f, int k, int g) {
    const int a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
    const Vec2d ua = mesh.uvs[mesh.face_uvs[f][k]], ub = mesh.uvs[mesh.face_uvs[f][(k + 1) % 3]];
    for (int j = 0; j < 3; ++j) {
      if (mesh.faces[g][j] == b && mesh.faces[g][(j + 1) % 3] == a)
        return mesh.uvs[mesh.face_uvs[g][j]] == ub && mesh.uvs[mesh.face_uvs[g][(j + 1) % 3]] == ua;
      if (mesh.faces[g][j] == a && mesh.faces[g][(j + 1) % 3] == b)  // inconsistent orientation
        return mesh.uvs[mesh.face_uvs[g][j]] == ua && mesh.uvs[mesh.face_uvs[g][(j + 1) % 3]] == ub;
    }
    return false;
  };
  const double mean_edge_px = edge_length_sum / (3.0 * mesh.num_faces()) / ss;
  const double inner_alpha = std::clamp((mean_edge_px - 1.5) / 8.0, 0.12, 0.55);
  std::vector<Segment> segments, boundary;
  if (tiles) {
    const Vec3d grey{0.6, 0.6, 0.6};
    for (double u = lo.x; u <= hi.x + 0.5; u += 1)
      segments.push_back({to_px({u, lo.y}), to_px({u, hi.y}), 0.5 * ss, grey, 1});
    for (double v = lo.y; v <= hi.y + 0.5; v += 1)
      segments.push_back({to_px({lo.x, v}), to_px({hi.x, v}), 0.5 * ss, grey, 1});
  }
  for (int f = 0; f < mesh.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const IndexRange faces = topo.edge_faces(topo.face_edge(f, k));
      int other = -1;
      if (faces.size() == 2) other = faces[0] == f ? faces[1] : faces[0];
      const Vec2d a = tri_px[f][k], b = tri_px[f][(k + 1) % 3];
      const bool inner = other >= 0 && chart[other] == chart[f] && same_uv_across(f, k, other);
      if (!inner)
        boundary.push_back({a, b, 0.6 * ss, {0.1, 0.1, 0.12}, 1});
      else if (f < other)
        segments.push_back({a, b, 0.3 * ss, colors[chart[f]] * 0.45, inner_alpha});
    }
  }
  segments.insert(segments.end(), boundary.begin(), boundary.end());

  // Bands of rows in parallel: fill, then the segments, then the box filter into the output.
  // The supersampled buffer covers one band at a time per worker.
  Image out(width, height, 3);
  const float norm_factor = 1.0f / (ss * ss);
  constexpr int kBandRows = 32;  // output rows per band
  const int bands = (height + kBandRows - 1) / kBandRows;
  tbb::parallel_for(0, bands, [&](int band) {
    const int oy0 = band * kBandRows, oy1 = std::min(height, oy0 + kBandRows);
    const int y0 = oy0 * ss, y1 = oy1 * ss;
    // Rows [y0, y1) of the W × H picture, stored from row 0 of `buf`; drawing shifts by y0.
    std::vector<float> buf(3 * static_cast<std::size_t>(W) * (y1 - y0), 1.0f);
    const Vec2d shift{0, static_cast<double>(y0)};
    for (int f = 0; f < mesh.num_faces(); ++f) {
      const Vec2d a = tri_px[f][0], b = tri_px[f][1], c = tri_px[f][2];
      const double area2 = cross(b - a, c - a);
      if (!(std::abs(area2) > 1e-12)) continue;
      const int ya = std::max(y0, static_cast<int>(std::ceil(std::min({a.y, b.y, c.y}) - 0.5)));
      const int yb = std::min(y1 - 1, static_cast<int>(std::floor(std::max({a.y, b.y, c.y}) - 0.5)));
      if (ya > yb) continue;
      const int xa = std::max(0, static_cast<int>(std::ceil(std::min({a.x, b.x, c.x}) - 0.5)));
      const int xb = std::min(W - 1, static_cast<int>(std::floor(std::max({a.x, b.x, c.x}) - 0.5)));
      const Vec3d& col = colors[chart[f]];
      for (int y = ya; y <= yb; ++y)
        for (int x = xa; x <= xb; ++x) {
          const Vec2d p{x + 0.5, y + 0.5};
          const double l0 = cross(c - b, p - b) / area2, l1 = cross(a - c, p - c) / area2;
          if (l0 < 0 || l1 < 0 || 1 - l0 - l1 < 0) continue;
          float* px = &buf[3 * (static_cast<std::size_t>(y - y0) * W + x)];
          px[0] = static_cast<float>(col.x);
          px[1] = static_cast<float>(col.y);
          px[2] = static_cast<float>(col.z);
        }
    }
    for (const Segment& g : segments) {
      const double r = g.half_width + 1;
      if (std::max(g.a.y, g.b.y) + r < y0 || std::min(g.a.y, g.b.y) - r >= y1) continue;
      draw_segment(buf, W, y1 - y0, g.a - shift, g.b - shift, g.half_width, g.col, g.alpha);
    }
    for (int y = oy0; y < oy1; ++y)
      for (int x = 0; x < width; ++x)
        for (int k = 0; k < 3; ++k) {
          float sum = 0;
          for (int sy = 0; sy < ss; ++sy)
            for (int sx = 0; sx < ss; ++sx)
              sum += buf[3 * (static_cast<std::size_t>((y - oy0) * ss + sy) * W + x * ss + sx) + k];
          out.at(x, y, k) = sum * norm_factor;
        }
  });
  tri_px = {};
  segments = {};
  boundary = {};
  // The drawing's tens of megabytes in pieces stay with malloc after they are freed; give them
  // back before the caller loads the image writer (itself ~100 MB), or they add to the peak.
  malloc_trim(0);
  return out;
}

}  // namespace isochart
