// Signals over the surface, their integrated metric tensors, signal stretch and the signal
// approximation error (Iso-charts §7, §9.3; Sander et al. 2002).

#include "isochart/signal.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "isochart/error.h"

namespace isochart {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The face in its own frame: q0 = (0,0), q1 = (x1,0), q2 = (x2,y2).
struct Flat {
  double x1 = 0, x2 = 0, y2 = 0, area = 0;
};

Flat flatten(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  Flat t;
  const Vec3d e1 = b - a, e2 = c - a;
  const double l1 = norm(e1);
  t.area = 0.5 * norm(cross(e1, e2));
  if (l1 <= 0) return t;
  t.x1 = l1;
  t.x2 = dot(e2, e1 / l1);
  t.y2 = std::sqrt(std::max(squared_norm(e2) - t.x2 * t.x2, 0.0));
  return t;
}

Flat flatten_face(const Mesh& m, int f) {
  const Face& F = m.faces[f];
  return flatten(m.positions[F[0]], m.positions[F[1]], m.positions[F[2]]);
}

// Adds ∫ ∇fᵀ∇f over the triangle with flat corners p0, p1, p2 and values v0, v1, v2 (linear
// interpolant; `dim` channels) to `g`.
void add_linear_imt(const Vec2d& p0, const Vec2d& p1, const Vec2d& p2, const double* v0, const double* v1,
                    const double* v2, int dim, Imt& g) {
  const Vec2d e1 = p1 - p0, e2 = p2 - p0;
  const double det = cross(e1, e2);
  if (!(std::abs(det) > 0)) return;
  const double area = 0.5 * std::abs(det);
  for (int c = 0; c < dim; ++c) {
    const double d1 = v1[c] - v0[c], d2 = v2[c] - v0[c];
    // Solve [e1ᵀ; e2ᵀ] ∇f = (d1, d2).
    const double gx = (d1 * e2.y - d2 * e1.y) / det;
    const double gy = (e1.x * d2 - e2.x * d1) / det;
    g[0] += area * gx * gx;
    g[1] += area * gx * gy;
    g[2] += area * gy * gy;
  }
}

void check_uvs(const Mesh& m, const char* what) {
  if (!m.has_uvs()) throw InputError("", std::string(what) + ": mesh has no texture coordinates");
  if (static_cast<int>(m.face_uvs.size()) != m.num_faces())
    throw InputError("", std::string(what) + ": face_uvs has " + std::to_string(m.face_uvs.size()) +
                             " entries for " + std::to_string(m.num_faces()) + " faces");
}

void check_signal(const Mesh& m, const Signal& s) {
  if (s.dimension < 1) throw InputError("", "signal has no channels");
  if (s.is_mapped()) {
    if (static_cast<int>(s.face_uvs.size()) != m.num_faces())
      throw InputError("", "mapped signal has texture coordinates for " + std::to_string(s.face_uvs.size()) +
                               " faces, the mesh has " + std::to_string(m.num_faces()));
  } else if (s.vertex_values.size() != static_cast<size_t>(m.num_vertices()) * s.dimension) {
    throw InputError("", "signal has " + std::to_string(s.vertex_values.size() / s.dimension) +
                             " vertex values, the mesh has " + std::to_string(m.num_vertices()) +
                             " vertices");
  }
}

}  // namespace

void Signal::set_texture_coordinates(const std::vector<Vec2d>& coordinates, const std::vector<Face>& corners,
                                     const TextureWrap& material) {
  uvs = coordinates;
  face_uvs = corners;
  bool out_u = false, out_v = false;
  for (const Vec2d& uv : uvs) {
    out_u = out_u || uv.x < 0 || uv.x > 1;
    out_v = out_v || uv.y < 0 || uv.y > 1;
  }
  tiling = out_u || out_v;
  wrap.u = out_u ? material.u : Wrap::Clamp;
  wrap.v = out_v ? material.v : Wrap::Clamp;
}

void Signal::evaluate(const Mesh& mesh, int f, double b1, double b2, double* out) const {
  const double b0 = 1 - b1 - b2;
  if (is_mapped()) {
    const Face& t = face_uvs[f];
    const Vec2d uv = uvs[t[0]] * b0 + uvs[t[1]] * b1 + uvs[t[2]] * b2;
    float tmp[16];
    const double lod = face_lod.empty() ? 0.0 : std::clamp<double>(face_lod[f], 0.0, double(mips.size()));
    const int l0 = static_cast<int>(lod);
    auto level = [&](int l) -> const Image& { return l == 0 ? texture : mips[l - 1]; };
    sample_bilinear(level(l0), uv.x, uv.y, tmp, wrap.u, wrap.v);
    const double w = lod - l0;
    if (w > 0) {
      float hi[16];
      sample_bilinear(level(l0 + 1), uv.x, uv.y, hi, wrap.u, wrap.v);
      for (int c = 0; c < dimension; ++c) tmp[c] = static_cast<float>((1 - w) * tmp[c] + w * hi[c]);
    }
    for (int c = 0; c < dimension; ++c) out[c] = tmp[c];
    return;
  }
  const Face& t = mesh.faces[f];
  const double* v0 = &vertex_values[static_cast<size_t>(t[0]) * dimension];
  const double* v1 = &vertex_values[static_cast<size_t>(t[1]) * dimension];
  const double* v2 = &vertex_values[static_cast<size_t>(t[2]) * dimension];
  for (int c = 0; c < dimension; ++c) out[c] = b0 * v0[c] + b1 * v1[c] + b2 * v2[c];
}

Signal make_signal(const Mesh& mesh, const std::string& spec, const std::string& file) {
  Signal s;
  auto from_vectors = [&](const std::vector<Vec3d>& v) {
    s.dimension = 3;
    s.vertex_values.resize(v.size() * 3);
    for (size_t i = 0; i < v.size(); ++i)
      for (int c = 0; c < 3; ++c) s.vertex_values[3 * i + c] = v[i][c];
  };
  if (spec == "normals") {
    // Files may store unnormalized normals (horse.ply's have lengths around 6).
    std::vector<Vec3d> n = mesh.has_normals() ? mesh.normals : vertex_normals(mesh);
    for (auto& v : n) v = normalized(v);
    from_vectors(n);
  } else if (spec == "colors" || spec == "colours") {
    if (!mesh.has_colors()) throw InputError(file, "--signal colors: mesh has no per-vertex colours");
    from_vectors(mesh.colors);
  } else if (spec.rfind("texture:", 0) == 0) {
    const std::string path = spec.substr(8);
    if (path.empty()) throw InputError(file, "--signal texture:IMG needs an image path");
    if (!mesh.has_uvs())
      throw InputError(file,
                       "--signal " + spec + ": mesh has no texture coordinates to map the texture with");
    s.texture = read_image(path);
    // Alpha is not part of the signal: dropped, wherever it is (EXR channels go by name, so
    // an "R,G" image keeps both).
    const int alpha = s.texture.alpha_channel();
    if (alpha >= 0) {
      const Image& in = s.texture;
      Image colour(in.width, in.height, in.channels - 1);
      for (int y = 0; y < in.height; ++y)
        for (int x = 0; x < in.width; ++x) {
          s.transparent_texels += in.at(x, y, alpha) >= 0.999f ? 0 : 1;
          for (int c = 0, k = 0; c < in.channels; ++c)
            if (c != alpha) colour.at(x, y, k++) = in.at(x, y, c);
        }
      s.texture = std::move(colour);
    }
    s.dimension = s.texture.channels;
    if (s.dimension > 16) throw InputError(path, "image has more than 16 channels");
    s.set_texture_coordinates(mesh.uvs, mesh.face_uvs);
  } else {
    throw InputError(file, "unknown --signal '" + spec + "' (expected normals, colors or texture:IMG)");
  }
  return s;
}

std::vector<Imt> face_imt(const Mesh& mesh, const Signal& signal) {
  check_signal(mesh, signal);
  const int nf = mesh.num_faces();
  const int dim = signal.dimension;
  std::vector<Imt> imt(nf, Imt{0, 0, 0});
  std::vector<double> vals;
  for (int f = 0; f < nf; ++f) {
    const Flat q = flatten_face(mesh, f);
    if (!(q.area > 0)) continue;
    const Vec2d p[3] = {{0, 0}, {q.x1, 0}, {q.x2, q.y2}};
    int n = 1;
    if (signal.is_mapped()) {
      // Sub-triangle edges of at most one source texel.
      const Face& t = signal.face_uvs[f];
      double extent = 0;
      for (int k = 0; k < 3; ++k) {
        const Vec2d d = signal.uvs[t[(k + 1) % 3]] - signal.uvs[t[k]];
        extent =
            std::max({extent, std::abs(d.x) * signal.texture.width, std::abs(d.y) * signal.texture.height});
      }
      n = std::clamp(static_cast<int>(std::ceil(extent)), 1, 32);
    }
    // Values on the barycentric grid (i, j), i + j ≤ n.
    auto at = [&](int i, int j) { return &vals[static_cast<size_t>((i * (n + 1) + j)) * dim]; };
    vals.assign(static_cast<size_t>(n + 1) * (n + 1) * dim, 0.0);
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) signal.evaluate(mesh, f, double(i) / n, double(j) / n, at(i, j));
    auto point = [&](int i, int j) {
      const double b1 = double(i) / n, b2 = double(j) / n;
      return p[0] * (1 - b1 - b2) + p[1] * b1 + p[2] * b2;
    };
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        add_linear_imt(point(i, j), point(i + 1, j), point(i, j + 1), at(i, j), at(i + 1, j), at(i, j + 1),
                       dim, imt[f]);
        if (i + j + 1 < n)
          add_linear_imt(point(i + 1, j), point(i + 1, j + 1), point(i, j + 1), at(i + 1, j),
                         at(i + 1, j + 1), at(i, j + 1), dim, imt[f]);
      }
  }
  // A constant texture read bilinearly in float leaves traces of 1e-16 to 1e-14 (1e-12 is far
  // under an 8-bit step), which every normalization by the signal's total turned into a
  // full-weight signal (7 charts instead of the geometric 4 on bunny_lowres, a signal stretch
  // of 1.04 for a flat grey image). A signal flat on every face is no signal.
  if (signal.is_mapped() &&
      std::all_of(imt.begin(), imt.end(), [](const Imt& m) { return !(0.5 * (m[0] + m[2]) >= 1e-12); }))
    std::fill(imt.begin(), imt.end(), Imt{0, 0, 0});
  return imt;
}

std::vector<Imt> signal_metric(const Mesh& mesh, const std::vector<Imt>& imt, double lambda) {
  const int nf = mesh.num_faces();
  if (static_cast<int>(imt.size()) != nf)
    throw InputError("",
                     "IMT has " + std::to_string(imt.size()) + " faces, the mesh has " + std::to_string(nf));
  const std::vector<double> area = face_areas(mesh);
  // A face's IMT trace is about the square of its signal's change across it. Below (1e-6)²,
  // far under an 8-bit step, the signal is flat there: a constant texture, read bilinearly in
  // float, gave traces of 1e-16 to 1e-14, which the normalization below made a full-weight
  // metric (76 charts instead of constant colours' 5).
  constexpr double kFlatTrace = 1e-12;
  auto flat = [&](int f) { return !(0.5 * (imt[f][0] + imt[f][2]) >= kFlatTrace); };
  double total_area = 0, total_trace = 0;
  for (int f = 0; f < nf; ++f) {
    total_area += area[f];
    if (!flat(f)) total_trace += 0.5 * (imt[f][0] + imt[f][2]);
  }
  const double nu = total_area > 0 ? total_trace / total_area : 0;
  std::vector<Imt> g(nf, Imt{1, 0, 1});
  if (!(nu > 0) || !(lambda > 0)) return g;
  for (int f = 0; f < nf; ++f) {
    if (!(area[f] > 0) || flat(f)) continue;
    const double s = lambda / (area[f] * nu);
    g[f] = {1 + s * imt[f][0], s * imt[f][1], 1 + s * imt[f][2]};
  }
  return g;
}

namespace {

// Texture → surface Jacobian columns (Ss, St) in the face frame; false when flipped/degenerate.
bool jacobian(const Flat& q, const Vec2d& p0, const Vec2d& p1, const Vec2d& p2, Vec2d& ss, Vec2d& st) {
  const double d = cross(p1 - p0, p2 - p0);
  if (!(d > 0)) return false;
  const double inv = 1.0 / d;
  ss = {(q.x1 * (p2.y - p0.y) + q.x2 * (p0.y - p1.y)) * inv, (q.y2 * (p0.y - p1.y)) * inv};
  st = {(q.x1 * (p0.x - p2.x) + q.x2 * (p1.x - p0.x)) * inv, (q.y2 * (p1.x - p0.x)) * inv};
  return true;
}

double trace_jgj(const Imt& g, const Vec2d& ss, const Vec2d& st) {
  return g[0] * (ss.x * ss.x + st.x * st.x) + 2 * g[1] * (ss.x * ss.y + st.x * st.y) +
         g[2] * (ss.y * ss.y + st.y * st.y);
}

}  // namespace

double metric_l2_stretch(const std::vector<Vec3d>& positions, const std::vector<Face>& faces,
                         const std::vector<Vec2d>& uv, const std::vector<Imt>& face_metric) {
  if (face_metric.size() != faces.size())
    throw Error("metric_l2_stretch: " + std::to_string(face_metric.size()) + " tensors for " +
                std::to_string(faces.size()) + " faces");
  double energy = 0, metric_area = 0, uv_area = 0;
  for (size_t f = 0; f < faces.size(); ++f) {
    const Face& t = faces[f];
    const Flat q = flatten(positions[t[0]], positions[t[1]], positions[t[2]]);
    const double a2 = signed_area(uv[t[0]], uv[t[1]], uv[t[2]]);
    if (!(a2 > 0)) return kInf;
    uv_area += a2;
    if (!(q.area > 0)) continue;
    Vec2d ss, st;
    if (!jacobian(q, uv[t[0]], uv[t[1]], uv[t[2]], ss, st)) return kInf;
    const Imt& g = face_metric[f];
    energy += q.area * 0.5 * trace_jgj(g, ss, st);
    metric_area += q.area * std::sqrt(std::max(g[0] * g[2] - g[1] * g[1], 0.0));
  }
  if (!(metric_area > 0)) return 0;
  return std::sqrt(energy * uv_area) / metric_area;
}

double signal_stretch(const Mesh& mesh, const std::vector<Imt>& imt) {
  check_uvs(mesh, "signal stretch");
  if (static_cast<int>(imt.size()) != mesh.num_faces())
    throw InputError("", "IMT has " + std::to_string(imt.size()) + " faces, the mesh has " +
                             std::to_string(mesh.num_faces()));
  double energy = 0, base = 0, area3 = 0, area_uv = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& t = mesh.face_uvs[f];
    Vec2d p0 = mesh.uvs[t[0]], p1 = mesh.uvs[t[1]], p2 = mesh.uvs[t[2]];
    const Flat q = flatten_face(mesh, f);
    area3 += q.area;
    area_uv += std::abs(signed_area(p0, p1, p2));
    if (!(q.area > 0)) continue;
    // How many texels the signal gets does not depend on which way a triangle faces: another
    // tool's mirrored charts (UVAtlas writes v downwards) measured infinite. Flips are
    // counted by measure_atlas; a collapsed triangle still has no texels at all.
    if (signed_area(p0, p1, p2) < 0) p0.x = -p0.x, p1.x = -p1.x, p2.x = -p2.x;
    Vec2d ss, st;
    if (!jacobian(q, p0, p1, p2, ss, st)) return kInf;
    // The IMT is already integrated over the face's surface area.
    energy += 0.5 * trace_jgj(imt[f], ss, st);
    base += 0.5 * (imt[f][0] + imt[f][2]);
  }
  if (!(base > 0) || !(area_uv > 0)) return 0;
  // Scale-invariant form of the normalization: k² = UV area / surface area.
  return std::sqrt(energy * (area_uv / area3) / base);
}

}  // namespace isochart
