// glTF 2.0 (.gltf / .glb) through tinygltf: reader (triangles, strips and fans of every mesh
// reached from the default scene, node transforms applied) and glb writer.
#include <sys/stat.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "io_internal.h"
#include "isochart/error.h"

namespace isochart::io_detail {

namespace {

using Mat4 = std::array<double, 16>;  // column-major, as glTF stores it

constexpr Mat4 kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

Mat4 multiply(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + rr] * b[c * 4 + k];
      r[c * 4 + rr] = s;
    }
  return r;
}

Mat4 local_transform(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    Mat4 m;
    std::copy(n.matrix.begin(), n.matrix.end(), m.begin());
    return m;
  }
  const double tx = n.translation.size() == 3 ? n.translation[0] : 0;
  const double ty = n.translation.size() == 3 ? n.translation[1] : 0;
  const double tz = n.translation.size() == 3 ? n.translation[2] : 0;
  double qx = 0, qy = 0, qz = 0, qw = 1;
  if (n.rotation.size() == 4) {
    qx = n.rotation[0], qy = n.rotation[1], qz = n.rotation[2], qw = n.rotation[3];
    const double len = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
    if (len > 0) qx /= len, qy /= len, qz /= len, qw /= len;
  }
  const double sx = n.scale.size() == 3 ? n.scale[0] : 1;
  const double sy = n.scale.size() == 3 ? n.scale[1] : 1;
  const double sz = n.scale.size() == 3 ? n.scale[2] : 1;
  // T * R * S, column-major.
  const double r00 = 1 - 2 * (qy * qy + qz * qz), r01 = 2 * (qx * qy - qz * qw),
               r02 = 2 * (qx * qz + qy * qw);
  const double r10 = 2 * (qx * qy + qz * qw), r11 = 1 - 2 * (qx * qx + qz * qz),
               r12 = 2 * (qy * qz - qx * qw);
  const double r20 = 2 * (qx * qz - qy * qw), r21 = 2 * (qy * qz + qx * qw),
               r22 = 1 - 2 * (qx * qx + qy * qy);
  return {r00 * sx, r10 * sx, r20 * sx, 0, r01 * sy, r11 * sy, r21 * sy, 0,
          r02 * sz, r12 * sz, r22 * sz, 0, tx,       ty,       tz,       1};
}

double det3(const Mat4& m) {
  return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
         m[8] * (m[1] * m[6] - m[5] * m[2]);
}

// Inverse transpose of the upper 3x3 (the cofactor matrix, up to the determinant's scale,
// which normalization removes; its sign is kept so mirrored normals still point outward).
std::array<double, 9> normal_matrix(const Mat4& m) {
  const double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
  const double s = det3(m) < 0 ? -1 : 1;
  // Rows of the cofactor matrix.
  return {s * (e * i - f * h), s * (f * g - d * i), s * (d * h - e * g),
          s * (c * h - b * i), s * (a * i - c * g), s * (b * g - a * h),
          s * (b * f - c * e), s * (c * d - a * f), s * (a * e - b * d)};
}

// A bounds-checked view of an accessor's elements.
struct AccessorView {
  const unsigned char* data = nullptr;  // null: all zeros (accessor without bufferView)
  std::size_t count = 0;
  std::size_t stride = 0;
  int component_type = TINYGLTF_COMPONENT_TYPE_FLOAT;
  int components = 1;
  bool normalized = false;

  double get(std::size_t i, int c) const {
    if (!data) return 0;
    const unsigned char* p = data + i * stride;
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        std::int8_t x;
        std::memcpy(&x, p + c, 1);
        return normalized ? std::max(x / 127.0, -1.0) : x;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? p[c] / 255.0 : p[c];
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t x;
        std::memcpy(&x, p + 2 * c, 2);
        return normalized ? std::max(x / 32767.0, -1.0) : x;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t x;
        std::memcpy(&x, p + 2 * c, 2);
        return normalized ? x / 65535.0 : x;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        std::uint32_t x;
        std::memcpy(&x, p + 4 * c, 4);
        return x;
      }
      case TINYGLTF_COMPONENT_TYPE_INT: {
        std::int32_t x;
        std::memcpy(&x, p + 4 * c, 4);
        return x;
      }
      default: {
        float x;
        std::memcpy(&x, p + 4 * c, 4);
        return x;
      }
    }
  }
};

class GltfReader {
 public:
  GltfReader(const std::string& path, const tinygltf::Model& model, const LoadOptions& options)
      : path_(path), model_(model), options_(options) {
    raw_.source = path;
  }

  RawMesh read() {
    for (const auto& ext : model_.extensionsRequired)
      if (ext == "KHR_draco_mesh_compression" || ext == "EXT_meshopt_compression")
        fail("requires the unsupported extension " + quoted(ext));
    visited_.assign(model_.nodes.size(), 0);
    if (model_.scenes.empty()) {
      // No scene to follow: every mesh once, untransformed.
      for (std::size_t m = 0; m < model_.meshes.size(); ++m) add_mesh(static_cast<int>(m), kIdentity);
    } else {
      const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      if (scene >= static_cast<int>(model_.scenes.size()))
        fail("default scene " + std::to_string(scene) + " does not exist");
      for (int n : model_.scenes[scene].nodes) visit(n, kIdentity);
    }
    finish();
    return std::move(raw_);
  }

 private:
  [[noreturn]] void fail(const std::string& message) const { throw InputError(path_, message); }

  // A transform of the wrong length would otherwise be dropped silently, placing the mesh
  // somewhere the file did not say.
  void check_transform(int node, const tinygltf::Node& n) const {
    const struct {
      const char* name;
      const std::vector<double>& values;
      std::size_t size;
    } parts[] = {{"matrix", n.matrix, 16},
                 {"translation", n.translation, 3},
                 {"rotation", n.rotation, 4},
                 {"scale", n.scale, 3}};
    for (const auto& p : parts) {
      if (!p.values.empty() && p.values.size() != p.size)
        fail("node " + std::to_string(node) + " has a " + p.name + " of " + std::to_string(p.values.size()) +
             " numbers, not " + std::to_string(p.size));
      if (!std::all_of(p.values.begin(), p.values.end(), [](double v) { return std::isfinite(v); }))
        fail("node " + std::to_string(node) + " has a " + p.name + " that is not finite");
    }
  }

  // Depth first, children in order, with a stack of its own: a chain of nodes as deep as the
  // file is long would overflow the call stack (20,000 levels did).
  void visit(int root, const Mat4& parent) {
    std::vector<std::pair<int, Mat4>> stack{{root, parent}};
    while (!stack.empty()) {
      const auto [node, above] = stack.back();
      stack.pop_back();
      if (node < 0 || node >= static_cast<int>(model_.nodes.size()))
        fail("node " + std::to_string(node) + " does not exist");
      // glTF nodes form a forest; a second visit means a cycle or a shared child, either of
      // which could make the traversal endless or exponential.
      if (visited_[node])
        fail("node " + std::to_string(node) + " is reached twice (a cycle or a node with two parents)");
      visited_[node] = 1;
      const tinygltf::Node& n = model_.nodes[node];
      check_transform(node, n);
      const Mat4 world = multiply(above, local_transform(n));
      if (n.mesh >= 0) add_mesh(n.mesh, world);
      for (auto c = n.children.rbegin(); c != n.children.rend(); ++c) stack.emplace_back(*c, world);
    }
  }

  // `components`: the component types allowed (any when empty), checked before the data so
  // that a wrong one is not reported as a short buffer.
  AccessorView view(int index, const std::string& what, std::initializer_list<int> types, bool need_data,
                    std::initializer_list<int> components = {}) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size()))
      fail(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[index];
    const std::string name = what + " (accessor " + std::to_string(index) + ")";
    if (a.sparse.isSparse) fail(name + " is sparse, which is not supported");
    if (std::find(types.begin(), types.end(), a.type) == types.end()) fail(name + " has the wrong type");
    if (components.size() > 0 &&
        std::find(components.begin(), components.end(), a.componentType) == components.end())
      fail(name + " has a non-integer component type");
    AccessorView v;
    v.count = a.count;
    v.component_type = a.componentType;
    v.components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type));
    v.normalized = a.normalized;
    const int csize = tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(a.componentType));
    if (csize <= 0 || csize == 8)
      fail(name + " has an unsupported component type " + std::to_string(a.componentType));
    const std::size_t elem = static_cast<std::size_t>(csize) * v.components;
    if (a.bufferView < 0) {
      // All zeros by the spec; allowed only where the count is bounded by real data.
      if (need_data) fail(name + " has no bufferView");
      return v;
    }
    if (a.bufferView >= static_cast<int>(model_.bufferViews.size()))
      fail(name + ": bufferView " + std::to_string(a.bufferView) + " does not exist");
    const tinygltf::BufferView& bv = model_.bufferViews[a.bufferView];
    if (bv.buffer < 0 || bv.buffer >= static_cast<int>(model_.buffers.size()))
      fail(name + ": buffer " + std::to_string(bv.buffer) + " does not exist");
    const auto& buf = model_.buffers[bv.buffer].data;
    if (bv.byteOffset > buf.size() || bv.byteLength > buf.size() - bv.byteOffset)
      fail(name + ": bufferView " + std::to_string(a.bufferView) + " runs past the end of its buffer");
    v.stride = bv.byteStride ? bv.byteStride : elem;
    if (v.stride < elem) fail(name + ": byteStride is smaller than an element");
    if (a.count > 0 &&
        (a.byteOffset > bv.byteLength || a.count - 1 > (bv.byteLength - a.byteOffset) / v.stride ||
         (a.count - 1) * v.stride + elem > bv.byteLength - a.byteOffset))
      fail(name + " runs past the end of its bufferView (truncated or corrupt file)");
    v.data = buf.data() + bv.byteOffset + a.byteOffset;
    return v;
  }

  void add_mesh(int mesh, const Mat4& world) {
    if (mesh < 0 || mesh >= static_cast<int>(model_.meshes.size()))
      fail("mesh " + std::to_string(mesh) + " does not exist");
    const bool mirror = det3(world) < 0;
    const auto nm = normal_matrix(world);
    // Primitives of one node that name the same attribute accessors share their vertices.
    std::map<std::array<int, 4>, std::pair<int, int>> shared;  // accessors → (vertex base, uv base)
    const auto& prims = model_.meshes[mesh].primitives;
    for (std::size_t pi = 0; pi < prims.size(); ++pi) {
      const tinygltf::Primitive& p = prims[pi];
      const std::string what = "mesh " + std::to_string(mesh) + " primitive " + std::to_string(pi);
      const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        ++skipped_primitives_;
        continue;
      }
      auto attr = [&](const char* name) {
        const auto it = p.attributes.find(name);
        return it == p.attributes.end() ? -1 : it->second;
      };
      const std::array<int, 4> ids = {attr("POSITION"), attr("NORMAL"), attr("TEXCOORD_0"), attr("COLOR_0")};
      if (ids[0] < 0) fail(what + " has no POSITION attribute");
      if (p.material < -1 || p.material >= static_cast<int>(model_.materials.size()))
        fail(what + " names material " + std::to_string(p.material) + ", and the file has " +
             std::to_string(model_.materials.size()) +
             (model_.materials.size() == 1 ? " material" : " materials"));
      // Lightmap UVs come as TEXCOORD_1; read silently as "no texture coordinates" they hid
      // why an atlas was missing.
      if (ids[2] < 0 && attr("TEXCOORD_1") >= 0) ++second_uvs_only_;
      const AccessorView pos = view(ids[0], what + " POSITION", {TINYGLTF_TYPE_VEC3}, true);
      const std::size_t nv = pos.count;
      auto check_count = [&](const AccessorView& v, const char* name) {
        if (v.count != nv)
          fail(what + " " + name + " has " + std::to_string(v.count) + " values for " + std::to_string(nv) +
               " vertices");
        return v;
      };
      int base = 0, uv_base = -1;
      const auto found = shared.find(ids);
      if (found != shared.end()) {
        std::tie(base, uv_base) = found->second;
      } else {
        base = static_cast<int>(raw_.positions.size());
        // Instancing can repeat a large vertex array; more than three vertices per allowed
        // face cannot be a mesh within the limit.
        if (static_cast<long long>(base) + static_cast<long long>(nv) > 3 * options_.max_faces + 3)
          fail("has more than " + std::to_string(3 * options_.max_faces + 3) +
               " vertices (3 per face of the limit of " + std::to_string(options_.max_faces) + " faces)");
        for (std::size_t i = 0; i < nv; ++i) {
          const double x = pos.get(i, 0), y = pos.get(i, 1), z = pos.get(i, 2);
          raw_.positions.push_back({world[0] * x + world[4] * y + world[8] * z + world[12],
                                    world[1] * x + world[5] * y + world[9] * z + world[13],
                                    world[2] * x + world[6] * y + world[10] * z + world[14]});
        }
        normals_.resize(raw_.positions.size());
        colors_.resize(raw_.positions.size());
        if (ids[1] >= 0) {
          const AccessorView n =
              check_count(view(ids[1], what + " NORMAL", {TINYGLTF_TYPE_VEC3}, false), "NORMAL");
          for (std::size_t i = 0; i < nv; ++i) {
            const double x = n.get(i, 0), y = n.get(i, 1), z = n.get(i, 2);
            normals_[base + i] =
                normalized(Vec3d{nm[0] * x + nm[1] * y + nm[2] * z, nm[3] * x + nm[4] * y + nm[5] * z,
                                 nm[6] * x + nm[7] * y + nm[8] * z});
          }
          with_normals_ += static_cast<long long>(nv);
        }
        if (ids[3] >= 0) {
          const AccessorView c = check_count(
              view(ids[3], what + " COLOR_0", {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4}, false), "COLOR_0");
          for (std::size_t i = 0; i < nv; ++i) colors_[base + i] = {c.get(i, 0), c.get(i, 1), c.get(i, 2)};
          with_colors_ += static_cast<long long>(nv);
        }
        if (ids[2] >= 0) {
          const AccessorView t =
              check_count(view(ids[2], what + " TEXCOORD_0", {TINYGLTF_TYPE_VEC2}, false), "TEXCOORD_0");
          uv_base = static_cast<int>(raw_.uvs.size());
          // glTF puts the texture origin at the top left, OBJ and we at the bottom left.
          for (std::size_t i = 0; i < nv; ++i) raw_.uvs.push_back({t.get(i, 0), 1.0 - t.get(i, 1)});
        }
        shared.emplace(ids, std::make_pair(base, uv_base));
      }

      // Corner indices of the primitive, then its triangles.
      std::vector<std::uint32_t> idx;
      if (p.indices >= 0) {
        const AccessorView iv =
            view(p.indices, what + " indices", {TINYGLTF_TYPE_SCALAR}, true,
                 {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
        idx.resize(iv.count);
        for (std::size_t i = 0; i < iv.count; ++i) {
          const double x = iv.get(i, 0);
          if (x >= static_cast<double>(nv))
            fail(what + ": index " + std::to_string(static_cast<long long>(x)) + " is out of range (" +
                 std::to_string(nv) + " vertices)");
          idx[i] = static_cast<std::uint32_t>(x);
        }
      } else {
        idx.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) idx[i] = static_cast<std::uint32_t>(i);
      }
      const std::size_t n = idx.size();
      // glTF requires it; the corners left over were dropped without a word.
      if (mode == TINYGLTF_MODE_TRIANGLES && n % 3 != 0)
        fail(what + ": triangles from " + std::to_string(n) + (p.indices >= 0 ? " indices" : " vertices") +
             ", not a multiple of 3");
      const std::size_t triangles = mode == TINYGLTF_MODE_TRIANGLES ? n / 3 : (n >= 2 ? n - 2 : 0);
      check_face_limit(path_, static_cast<long long>(raw_.polygons.size() + triangles), options_);
      const int group = groups_++;
      auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        if (mirror) std::swap(b, c);
        raw_.polygons.push_back(
            {base + static_cast<int>(a), base + static_cast<int>(b), base + static_cast<int>(c)});
        raw_.polygon_uvs.push_back(uv_base < 0 ? std::vector<int>{}
                                               : std::vector<int>{uv_base + static_cast<int>(a),
                                                                  uv_base + static_cast<int>(b),
                                                                  uv_base + static_cast<int>(c)});
        raw_.polygon_groups.push_back(group);
        raw_.polygon_materials.push_back(p.material < 0 ? -1 : p.material);
        with_uvs_ += uv_base < 0 ? 0 : 1;
      };
      if (mode == TINYGLTF_MODE_TRIANGLES) {
        for (std::size_t i = 0; i + 2 < n; i += 3) emit(idx[i], idx[i + 1], idx[i + 2]);
      } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        // Repeated indices in a strip join its pieces; they are not triangles.
        for (std::size_t i = 0; i + 2 < n; ++i) {
          const std::uint32_t a = idx[i], b = idx[i + 1], c = idx[i + 2];
          if (a == b || b == c || a == c) continue;
          if (i % 2 == 0)
            emit(a, b, c);
          else
            emit(b, a, c);
        }
      } else {
        for (std::size_t i = 1; i + 1 < n; ++i) emit(idx[0], idx[i], idx[i + 1]);
      }
    }
  }

  // Attributes present on only some primitives: texture coordinates are filled with (0, 0),
  // normals and colours dropped, each with a warning.
  void finish() {
    const long long nv = static_cast<long long>(raw_.positions.size());
    const long long nf = static_cast<long long>(raw_.polygons.size());
    if (with_uvs_ == 0) {
      raw_.uvs.clear();
      raw_.polygon_uvs.clear();
    } else if (with_uvs_ < nf) {
      const int zero = static_cast<int>(raw_.uvs.size());
      raw_.uvs.push_back({0, 0});
      for (auto& puv : raw_.polygon_uvs)
        if (puv.empty()) puv.assign(3, zero);
      raw_.warnings.push_back(std::to_string(nf - with_uvs_) +
                              (nf - with_uvs_ == 1 ? " face has" : " faces have") +
                              " no TEXCOORD_0; they get (0, 0)");
    }
    if (second_uvs_only_ > 0)
      raw_.warnings.push_back(std::to_string(second_uvs_only_) +
                              (second_uvs_only_ == 1 ? " primitive has" : " primitives have") +
                              " TEXCOORD_1 but no TEXCOORD_0; only TEXCOORD_0 is read");
    if (with_normals_ == nv && nv > 0)
      raw_.normals = std::move(normals_);
    else if (with_normals_ > 0)
      raw_.warnings.push_back("only some primitives have normals; normals ignored");
    if (with_colors_ == nv && nv > 0)
      raw_.colors = std::move(colors_);
    else if (with_colors_ > 0)
      raw_.warnings.push_back("only some primitives have colours; colours ignored");
    // Otherwise reported as "no vertices", which a file full of points is not.
    if (skipped_primitives_ > 0 && raw_.polygons.empty())
      fail("has only point and line primitives (" + std::to_string(skipped_primitives_) + "), no triangles");
    if (skipped_primitives_ > 0)
      raw_.warnings.push_back("ignored " + std::to_string(skipped_primitives_) +
                              " point and line primitives");
  }

  const std::string& path_;
  const tinygltf::Model& model_;
  const LoadOptions& options_;
  RawMesh raw_;
  std::vector<char> visited_;
  std::vector<Vec3d> normals_, colors_;
  long long with_normals_ = 0, with_colors_ = 0, with_uvs_ = 0;
  int groups_ = 0, skipped_primitives_ = 0, second_uvs_only_ = 0;
};

// Images are not needed to read a mesh, so they are not decoded.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
  return true;
}

std::string first_line(const std::string& s) {
  std::string_view v = s;
  while (!v.empty() && (v.front() == '\n' || v.front() == ' ')) v.remove_prefix(1);
  std::string_view line = v.substr(0, v.find('\n'));
  // nlohmann's messages start with an internal tag such as "[json.exception.parse_error.101] ".
  if (line.substr(0, 16) == "[json.exception." && line.find("] ") != std::string_view::npos)
    line.remove_prefix(line.find("] ") + 2);
  // tinygltf quotes a buffer's whole data: URI, base64 and all, and not what is wrong with it.
  if (line.substr(0, 30) == "Failed to decode 'uri' : data:")
    return "a buffer's data: URI does not decode to its byteLength (not base64, or shorter than byteLength)";
  return std::string(line.substr(0, 200));
}

template <typename T>
void append_pod(std::vector<unsigned char>& buf, const T& x) {
  const auto* p = reinterpret_cast<const unsigned char*>(&x);
  buf.insert(buf.end(), p, p + sizeof(T));
}

void pad4(std::vector<unsigned char>& buf) {
  while (buf.size() % 4) buf.push_back(0);
}

}  // namespace

// glTF keeps one vertex per combination of attributes, so a mesh arrives cut open along its
// UV and normal seams (every atlas we write is). Corners at bit-identical positions are
// joined again, texture coordinates staying per corner; where that joins surfaces that only
// touch, validation splits the non-manifold vertex or edge apart as for any other file.
void weld_equal_positions(RawMesh& raw) {
  struct Key {
    std::uint64_t b[3];
    bool operator==(const Key& o) const { return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2]; }
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 0x9e3779b97f4a7c15ull;
      for (std::uint64_t x : k.b) h = (h ^ x) * 0xff51afd7ed558ccdull, h ^= h >> 32;
      return static_cast<std::size_t>(h);
    }
  };
  const std::size_t nv = raw.positions.size();
  for (const auto& poly : raw.polygons)
    for (int v : poly)
      if (v < 0 || static_cast<std::size_t>(v) >= nv) return;  // validation names the bad index
  std::unordered_map<Key, int, Hash> first;
  first.reserve(nv);
  std::vector<int> to(nv), members;
  for (std::size_t v = 0; v < nv; ++v) {
    Key k{};
    for (int i = 0; i < 3; ++i) {
      const double x = raw.positions[v][i] == 0 ? 0.0 : raw.positions[v][i];  // −0 joins +0
      std::memcpy(&k.b[i], &x, sizeof x);
    }
    const auto [it, inserted] = first.emplace(k, static_cast<int>(members.size()));
    to[v] = it->second;
    if (inserted) members.push_back(0);
    ++members[to[v]];
  }
  if (members.size() == nv) return;

  // A join is undone where it is not a seam being closed but separate surfaces meeting: an edge
  // of more than two faces, a face repeated, or faces around the joined vertex that do not form
  // one fan (two cubes sharing a face, an edge or a corner stay two closed cubes, as in OBJ).
  const std::size_t nw = members.size();
  std::vector<char> bad(nw, 0);         // 1: undo the join, 2: one vertex per fan (3: to be decided)
  std::unordered_map<int, int> fan_of;  // for 2: input vertex -> its fan's id
  auto joined = [&](int w) { return members[w] > 1; };
  {
    std::unordered_map<std::uint64_t, int> edge_faces;
    std::unordered_map<std::uint64_t, std::vector<int>> seen_faces;  // sorted triple hash -> faces
    std::vector<std::vector<std::array<int, 3>>> fan(nw);  // per joined vertex and face: neighbours, corner
    for (std::size_t f = 0; f < raw.polygons.size(); ++f) {
      const auto& poly = raw.polygons[f];
      const std::size_t n = poly.size();
      for (std::size_t i = 0; i < n; ++i) {
        const int a = to[poly[i]], b = to[poly[(i + 1) % n]];
        const std::uint64_t key =
            (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
        if (++edge_faces[key] == 3)
          for (int w : {a, b})
            if (joined(w) && bad[w] == 0) bad[w] = 3;  // separated by fans below if it can be
        if (joined(a)) fan[a].push_back({to[poly[(i + n - 1) % n]], b, poly[i]});
      }
      std::vector<int> w(n), o(poly.begin(), poly.end());
      for (std::size_t i = 0; i < n; ++i) w[i] = to[poly[i]];
      std::sort(w.begin(), w.end());
      std::sort(o.begin(), o.end());
      std::uint64_t h = 1469598103934665603ull;
      for (int x : w) h = (h ^ static_cast<std::uint32_t>(x)) * 1099511628211ull;
      auto& same = seen_faces[h];
      for (int g : same) {
        std::vector<int> wg, og(raw.polygons[g].begin(), raw.polygons[g].end());
        for (int v : raw.polygons[g]) wg.push_back(to[v]);
        std::sort(wg.begin(), wg.end());
        std::sort(og.begin(), og.end());
        if (wg == w && og != o)  // a repeat made by the join, not by the file
          for (int x : w)
            if (joined(x)) bad[x] = 1;
      }
      same.push_back(static_cast<int>(f));
    }
    for (std::size_t w = 0; w < nw; ++w) {
      if (!joined(static_cast<int>(w)) || bad[w] == 1 || fan[w].size() < 2) continue;
      // Faces around w are linked through the neighbours they share.
      const std::size_t m = fan[w].size();
      std::vector<std::size_t> parent(m);
      for (std::size_t i = 0; i < m; ++i) parent[i] = i;
      auto find = [&](std::size_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
      };
      std::unordered_map<int, std::size_t> by_neighbour;
      for (std::size_t i = 0; i < m; ++i)
        for (int k = 0; k < 2; ++k) {
          // Only through edges of two faces: pieces meeting along an edge are not one fan.
          const int x = fan[w][i][k], lo = std::min(static_cast<int>(w), x),
                    hi = std::max(static_cast<int>(w), x);
          if (edge_faces[(static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint32_t>(hi)] > 2)
            continue;
          const auto [it, inserted] = by_neighbour.emplace(x, i);
          if (!inserted) parent[find(i)] = find(it->second);
        }
      std::size_t roots = 0;
      for (std::size_t i = 0; i < m; ++i) roots += find(i) == i;
      if (roots > 1) {
        // Each fan keeps its own joined vertex (the seams inside each piece stay closed).
        bad[w] = 2;
        for (std::size_t i = 0; i < m; ++i) fan_of.emplace(fan[w][i][2], static_cast<int>(find(i)));
      } else if (bad[w] == 3) {
        bad[w] = 1;  // one fan yet an edge of three faces or more: the join is undone
      }
    }
  }

  for (char& b : bad)
    if (b == 3) b = 1;
  std::vector<int> id(nw, -1), final_of(nv);
  std::map<std::pair<int, int>, int> fan_id;
  std::vector<Vec3d> positions, normals, colors;
  positions.reserve(nw);
  for (std::size_t v = 0; v < nv; ++v) {
    const int w = to[v];
    int* slot = &id[w];
    if (bad[w] == 2) {
      const auto f = fan_of.find(static_cast<int>(v));
      slot = &fan_id.try_emplace({w, f == fan_of.end() ? -1 - static_cast<int>(v) : f->second}, -1)
                  .first->second;
    }
    if (bad[w] == 1 || *slot < 0) {
      final_of[v] = static_cast<int>(positions.size());
      if (bad[w] != 1) *slot = final_of[v];
      positions.push_back(raw.positions[v]);
      if (!raw.normals.empty()) normals.push_back(raw.normals[v]);
      if (!raw.colors.empty()) colors.push_back(raw.colors[v]);
    } else {
      final_of[v] = *slot;
    }
  }
  if (positions.size() == nv) return;
  for (auto& poly : raw.polygons)
    for (int& v : poly) v = final_of[v];
  raw.positions = std::move(positions);
  if (!raw.normals.empty()) raw.normals = std::move(normals);
  if (!raw.colors.empty()) raw.colors = std::move(colors);
}

namespace {
// Whether a referenced file exists, by its status alone: tinygltf's own check opens the file,
// which waits forever on a FIFO.
bool path_exists(const std::string& path, void*) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

// External buffers are read like every input (a directory named as a buffer made tinygltf's own
// reader throw bad_alloc), and count as inputs of the run.
bool read_buffer_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
  try {
    const std::string bytes = read_file(path);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const InputError& e) {
    if (err) *err += std::string(e.what()) + "\n";
    return false;
  }
}

// Parses the glTF/glb held in `data` (its external buffers and images relative to `path`)
// with `loader`, whose image loader the caller has set. Exceptions of tinygltf pass through.
bool parse_gltf(tinygltf::TinyGLTF& loader, const std::string& path, std::string_view data, bool binary,
                tinygltf::Model& model, std::string& err) {
  loader.SetFsCallbacks(
      {&path_exists, &tinygltf::ExpandFilePath, &read_buffer_file, &tinygltf::WriteWholeFile, nullptr});
  std::string warn;
  const auto slash = path.find_last_of('/');
  const std::string base_dir = slash == std::string::npos ? "." : path.substr(0, slash);
  return binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                              reinterpret_cast<const unsigned char*>(data.data()),
                                              static_cast<unsigned int>(data.size()), base_dir)
                : loader.LoadASCIIFromString(&model, &err, &warn, data.data(),
                                             static_cast<unsigned int>(data.size()), base_dir);
}
}  // namespace

namespace {

// tinygltf reads a texCoord that is not a 32-bit integer (1.5, "1", 4294967296) as 0 or
// truncated, and the texture was then read through TEXCOORD_0 without a word. The key names
// nothing else in glTF, so its values are checked in the JSON text itself.
void check_tex_coords(const std::string& path, std::string_view json) {
  const std::string_view key = "\"texCoord\"";
  for (std::size_t at = json.find(key); at != std::string_view::npos; at = json.find(key, at + key.size())) {
    std::size_t i = at + key.size();
    while (i < json.size() && std::isspace(static_cast<unsigned char>(json[i]))) ++i;
    if (i >= json.size() || json[i] != ':') continue;  // the word inside a string
    ++i;
    while (i < json.size() && std::isspace(static_cast<unsigned char>(json[i]))) ++i;
    std::size_t end = i;
    while (end < json.size() && json[end] != ',' && json[end] != '}' && json[end] != ']' &&
           !std::isspace(static_cast<unsigned char>(json[end])))
      ++end;
    const std::string_view tok = json.substr(i, end - i);
    const bool digits =
        !tok.empty() && tok.size() <= 10 && tok.find_first_not_of("0123456789") == std::string_view::npos;
    if (digits && std::stoll(std::string(tok)) <= INT_MAX) continue;
    throw InputError(path, "a texture's texCoord " + quoted(std::string(tok.substr(0, 40))) +
                               " is not a texture coordinate set (a whole number from 0)");
  }
}

}  // namespace

RawMesh read_gltf(const std::string& path, std::string_view data, bool binary, const LoadOptions& options) {
  if (data.size() > 0xffffffffu) throw InputError(path, "glTF file is larger than 4 GiB");
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  tinygltf::Model model;
  std::string err;
  bool ok = false;
  try {
    ok = parse_gltf(loader, path, data, binary, model, err);
  } catch (const std::exception& e) {
    throw InputError(path, std::string("invalid glTF: ") + first_line(e.what()));
  }
  if (!ok)
    throw InputError(path, "invalid glTF: " + (err.empty() ? std::string("cannot parse") : first_line(err)));
  // glTF 1.0 files parse as 2.0 with their meshes missing; say what they are instead.
  if (model.asset.version.substr(0, 2) != "2.")
    throw InputError(path, "glTF version " + quoted(model.asset.version) + " is not supported (only 2.x)");
  if (binary) {
    // Bytes 4–7, little-endian; tinygltf has checked that the header is there.
    std::uint32_t version = 0;
    for (int i = 3; i >= 0; --i) version = version << 8 | static_cast<unsigned char>(data[4 + i]);
    if (version != 2)
      throw InputError(path,
                       "glb container version " + std::to_string(version) + " is not supported (only 2)");
  }
  if (binary) {
    // The JSON chunk: its length in bytes 12–15, its text from byte 20 (checked by tinygltf).
    std::uint32_t length = 0;
    for (int i = 3; i >= 0; --i) length = length << 8 | static_cast<unsigned char>(data[12 + i]);
    check_tex_coords(path, data.substr(20, length));
  } else {
    check_tex_coords(path, data);
  }
  return GltfReader(path, model, options).read();
}

std::string glb_bytes(const Mesh& m, const std::string& texture, bool transparent) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "isocharts";
  std::vector<unsigned char> buf;

  // glTF attributes are per vertex, so a vertex with several UVs (a seam) is split.
  std::vector<std::pair<int, int>> verts;  // (mesh vertex, uv index or -1)
  std::unordered_map<long long, std::uint32_t> vid;
  std::vector<std::array<std::uint32_t, 3>> tris(m.faces.size());
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = m.faces[f][k], t = m.has_uvs() ? m.face_uvs[f][k] : -1;
      const long long key = (static_cast<long long>(v) << 32) | static_cast<std::uint32_t>(t);
      const auto [it, inserted] = vid.emplace(key, static_cast<std::uint32_t>(verts.size()));
      if (inserted) verts.emplace_back(v, t);
      tris[f][k] = it->second;
    }

  auto add_view = [&](std::size_t offset, int target) {
    tinygltf::BufferView bv;
    bv.buffer = 0;
    bv.byteOffset = offset;
    bv.byteLength = buf.size() - offset;
    bv.target = target;
    model.bufferViews.push_back(bv);
    pad4(buf);
    return static_cast<int>(model.bufferViews.size()) - 1;
  };
  auto add_accessor = [&](int view, int ctype, int type, std::size_t count) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = ctype;
    a.type = type;
    a.count = count;
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size()) - 1;
  };
  auto add_vec3 = [&](auto&& value) {
    const std::size_t off = buf.size();
    for (const auto& vt : verts) {
      const Vec3d x = value(vt.first);
      for (int i = 0; i < 3; ++i) append_pod(buf, static_cast<float>(x[i]));
    }
    return add_accessor(add_view(off, TINYGLTF_TARGET_ARRAY_BUFFER), TINYGLTF_COMPONENT_TYPE_FLOAT,
                        TINYGLTF_TYPE_VEC3, verts.size());
  };

  std::map<std::string, int> attributes;
  // glTF positions are floats: a mesh far from the origin is stored around its box's centre,
  // moved back by the node's translation (a double), instead of losing its shape to rounding.
  const BoundingBox box = bounding_box(m);
  const Vec3d origin =
      float_positions_suffice(m.positions, Vec3d{}, box.diagonal()) ? Vec3d{} : (box.min + box.max) * 0.5;
  attributes["POSITION"] = add_vec3([&](int v) { return m.positions[v] - origin; });
  {
    // The spec requires POSITION bounds.
    tinygltf::Accessor& a = model.accessors.back();
    a.minValues.assign(3, verts.empty() ? 0.0 : 1e300);
    a.maxValues.assign(3, verts.empty() ? 0.0 : -1e300);
    for (const auto& vt : verts)
      for (int i = 0; i < 3; ++i) {
        const double x = static_cast<float>(m.positions[vt.first][i] - origin[i]);
        a.minValues[i] = std::min(a.minValues[i], x);
        a.maxValues[i] = std::max(a.maxValues[i], x);
      }
  }
  if (m.has_normals()) attributes["NORMAL"] = add_vec3([&](int v) { return normalized(m.normals[v]); });
  if (m.has_colors()) attributes["COLOR_0"] = add_vec3([&](int v) { return m.colors[v]; });
  if (m.has_uvs()) {
    const std::size_t off = buf.size();
    for (const auto& vt : verts) {
      append_pod(buf, static_cast<float>(m.uvs[vt.second].x));
      append_pod(buf, static_cast<float>(1.0 - m.uvs[vt.second].y));
    }
    attributes["TEXCOORD_0"] = add_accessor(add_view(off, TINYGLTF_TARGET_ARRAY_BUFFER),
                                            TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, verts.size());
  }

  int material = -1;
  if (!texture.empty()) {
    std::string bytes;
    try {
      bytes = read_file(OutputBatch::current_path(texture));  // written earlier in this run?
    } catch (const InputError& e) {
      throw InputError(texture, std::string("texture ") + e.what());
    }
    std::string mime;
    if (bytes.size() >= 8 && std::memcmp(bytes.data(), "\x89PNG\r\n\x1a\n", 8) == 0)
      mime = "image/png";
    else if (bytes.size() >= 3 && std::memcmp(bytes.data(), "\xff\xd8\xff", 3) == 0)
      mime = "image/jpeg";
    else
      throw InputError(texture, "texture is not a PNG or JPEG image");
    const std::size_t off = buf.size();
    buf.insert(buf.end(), bytes.begin(), bytes.end());
    tinygltf::Image image;
    image.bufferView = add_view(off, 0);
    image.mimeType = mime;
    model.images.push_back(image);
    tinygltf::Sampler sampler;
    sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
    sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
    model.samplers.push_back(sampler);
    tinygltf::Texture tex;
    tex.source = 0;
    tex.sampler = 0;
    model.textures.push_back(tex);
    tinygltf::Material mat;
    mat.name = "material0";
    mat.pbrMetallicRoughness.baseColorTexture.index = 0;
    mat.pbrMetallicRoughness.metallicFactor = 0;
    mat.pbrMetallicRoughness.roughnessFactor = 1;
    if (transparent) mat.alphaMode = "BLEND";
    model.materials.push_back(mat);
    material = 0;
  }

  // One primitive per face group (ascending ids), all sharing the vertex attributes.
  std::map<int, std::vector<int>> groups;
  const bool grouped = m.face_groups.size() == m.faces.size();
  for (int f = 0; f < m.num_faces(); ++f) groups[grouped ? m.face_groups[f] : 0].push_back(f);
  tinygltf::Mesh mesh;
  for (const auto& [g, faces] : groups) {
    const std::size_t off = buf.size();
    for (int f : faces)
      for (int k = 0; k < 3; ++k) append_pod(buf, tris[f][k]);
    tinygltf::Primitive prim;
    prim.attributes = attributes;
    prim.indices = add_accessor(add_view(off, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, 3 * faces.size());
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.material = material;
    mesh.primitives.push_back(prim);
  }
  model.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  if (origin != Vec3d{}) node.translation = {origin.x, origin.y, origin.z};
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes.push_back(0);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  tinygltf::Buffer buffer;
  buffer.data = std::move(buf);
  model.buffers.push_back(std::move(buffer));

  tinygltf::TinyGLTF writer;
  std::ostringstream os;
  if (!writer.WriteGltfSceneToStream(&model, os, false, true)) throw Error("cannot serialize the glb");
  return os.str();
}

namespace {

// Keeps each image's encoded bytes instead of decoding them.
bool keep_image_bytes(tinygltf::Image*, const int index, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void* user) {
  auto& kept = *static_cast<std::map<int, std::string>*>(user);
  kept[index].assign(reinterpret_cast<const char*>(bytes), static_cast<std::size_t>(std::max(size, 0)));
  return true;
}

}  // namespace

namespace {

// KHR_texture_transform: the image is read at T·R·S·uv in glTF's coordinates (v down), with
// the rotation turning the coordinates counter-clockwise as the extension's example reads it
// (offset [0, 1], rotation π/2, scale ½ picks the lower left quadrant), as three.js and
// Blender do. Returned as the same map in the mesh's coordinates (v up, v_gltf = 1 − v).
// `tex_coord` is overridden by the extension's own texCoord. False when a value is not a number
// or not finite.
bool read_texture_transform(const tinygltf::Value& ext, MeshTexture::UvTransform& out, int& tex_coord) {
  if (!ext.IsObject()) return false;
  bool ok = true;
  auto number = [&](const tinygltf::Value& v, double fallback) {
    if (!v.IsNumber()) {
      ok = false;
      return fallback;
    }
    const double x = v.GetNumberAsDouble();
    ok = ok && std::isfinite(x);
    return x;
  };
  auto pair = [&](const char* key, double fallback, double& x, double& y) {
    x = y = fallback;
    if (!ext.Has(key)) return;
    const tinygltf::Value& v = ext.Get(key);
    if (!v.IsArray() || v.ArrayLen() != 2) {
      ok = false;
      return;
    }
    x = number(v.Get(0), fallback);
    y = number(v.Get(1), fallback);
  };
  double ox, oy, sx, sy;
  pair("offset", 0, ox, oy);
  pair("scale", 1, sx, sy);
  const double r = ext.Has("rotation") ? number(ext.Get("rotation"), 0) : 0;
  if (ext.Has("texCoord")) {
    const tinygltf::Value& v = ext.Get("texCoord");
    if (!v.IsInt() || v.GetNumberAsInt() < 0) return false;
    tex_coord = v.GetNumberAsInt();
  }
  if (!ok) return false;
  // In glTF's coordinates: u' = c·sx·u + s·sy·v + ox, v' = −s·sx·u + c·sy·v + oy.
  const double c = std::cos(r), s = std::sin(r);
  const double ga = c * sx, gb = s * sy, gd = -s * sx, ge = c * sy;
  // Conjugated by the flip (u, v) ↦ (u, 1 − v).
  out.a = ga;
  out.b = -gb;
  out.c = gb + ox;
  out.d = -gd;
  out.e = ge;
  out.f = 1 - ge - oy;
  return true;
}

}  // namespace

namespace {

MeshTexture material_texture(const std::string& path, const tinygltf::Model& model,
                             std::map<int, std::string>& images, const tinygltf::Material& material) {
  MeshTexture t;
  const auto& factor = material.pbrMetallicRoughness.baseColorFactor;
  if (factor.size() >= 3 && std::isfinite(factor[0]) && std::isfinite(factor[1]) && std::isfinite(factor[2]))
    t.colour = {factor[0], factor[1], factor[2]};
  const tinygltf::TextureInfo& info = material.pbrMetallicRoughness.baseColorTexture;
  const int tex = info.index;
  if (tex < 0 && tex != -1) {
    t.problem = "its base-colour texture index " + std::to_string(tex) + " is invalid";
    return t;
  }
  if (tex < 0) return t;
  if (tex >= static_cast<int>(model.textures.size())) {
    t.problem = "its base-colour texture index " + std::to_string(tex) + " is out of range (" +
                std::to_string(model.textures.size()) + " textures)";
    return t;
  }
  // Only TEXCOORD_0 is read: a texture mapped through another set would be drawn or carried
  // over through the wrong coordinates.
  int tex_coord = info.texCoord;
  const auto transform = info.extensions.find("KHR_texture_transform");
  if (transform != info.extensions.end()) {
    if (!read_texture_transform(transform->second, t.uv_transform, tex_coord)) {
      t.problem = "its base-colour texture's KHR_texture_transform is malformed";
      return t;
    }
  }
  if (tex_coord != 0) {
    t.problem = "its base-colour texture is mapped through TEXCOORD_" + std::to_string(tex_coord) +
                ", and only TEXCOORD_0 is read";
    return t;
  }
  // glTF's sampler wraps: REPEAT (also the default without a sampler), CLAMP_TO_EDGE,
  // MIRRORED_REPEAT.
  const int sampler = model.textures[tex].sampler;
  if (sampler >= 0 && sampler < static_cast<int>(model.samplers.size())) {
    const tinygltf::Sampler& sm = model.samplers[sampler];
    for (const auto& [axis, mode] : {std::pair<const char*, int>{"wrapS", sm.wrapS}, {"wrapT", sm.wrapT}})
      if (mode != TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE && mode != TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT &&
          mode != TINYGLTF_TEXTURE_WRAP_REPEAT) {
        t.problem = "its base-colour texture's sampler has " + std::string(axis) + " " +
                    std::to_string(mode) + ", not a glTF wrap mode (33071, 33648 or 10497)";
        return t;
      }
    auto wrap = [](int mode) {
      if (mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return Wrap::Clamp;
      if (mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return Wrap::Mirror;
      return Wrap::Repeat;
    };
    t.wrap = {wrap(sm.wrapS), wrap(sm.wrapT)};
  } else if (sampler != -1) {
    t.problem = "its base-colour texture's sampler " + std::to_string(sampler) + " is out of range (" +
                std::to_string(model.samplers.size()) + " samplers)";
    return t;
  }
  const int source = model.textures[tex].source;
  if (source < 0 || source >= static_cast<int>(model.images.size())) {
    t.problem = "its base-colour texture names no image";
    return t;
  }
  // An image file is handed over by name, so reading it says what is wrong with it.
  const std::string& uri = model.images[source].uri;
  if (!uri.empty() && uri.compare(0, 5, "data:") != 0) {
    std::string name;
    for (std::size_t i = 0; i < uri.size(); ++i) {  // %XX escapes, as URIs in glTF may carry
      if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
          std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
        name += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
        i += 2;
      } else {
        name += uri[i];
      }
    }
    if (std::any_of(name.begin(), name.end(),
                    [](char ch) { return static_cast<unsigned char>(ch) < 0x20; })) {
      t.problem = "its base-colour image URI holds a control character, so it names no file";
      return t;
    }
    const auto slash = path.find_last_of('/');
    t.file = name.front() == '/' || slash == std::string::npos ? name : path.substr(0, slash + 1) + name;
    return t;
  }
  const auto found = images.find(source);
  if (found == images.end() || found->second.empty()) {
    t.problem = "its base-colour image is empty or cannot be decoded";
    return t;
  }
  t.bytes = found->second;  // materials may share an image
  const bool png = t.bytes.size() >= 4 && t.bytes.compare(0, 4, "\x89PNG") == 0;
  const bool jpeg = t.bytes.size() >= 2 && static_cast<unsigned char>(t.bytes[0]) == 0xFF &&
                    static_cast<unsigned char>(t.bytes[1]) == 0xD8;
  if (!png && !jpeg) {  // glTF allows only PNG and JPEG (extensions aside)
    t.bytes.clear();
    t.problem = "its base-colour image is not a PNG or JPEG image";
    return t;
  }
  t.extension = png ? ".png" : ".jpg";
  return t;
}

}  // namespace

std::vector<MeshTexture> gltf_textures(const std::string& path, std::string_view data, bool binary) {
  if (data.size() > 0xffffffffu) return {};
  std::map<int, std::string> images;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, &images);
  tinygltf::Model model;
  std::string err;
  bool ok = false;
  try {
    ok = parse_gltf(loader, path, data, binary, model, err);
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok) return {};
  std::set<int> used;
  for (const tinygltf::Mesh& mesh : model.meshes)
    for (const tinygltf::Primitive& prim : mesh.primitives) used.insert(prim.material);
  std::vector<MeshTexture> out;
  for (const tinygltf::Material& material : model.materials) {
    out.push_back(material_texture(path, model, images, material));
    out.back().several_materials = used.size() > 1;
  }
  return out;
}

MeshTexture gltf_texture(const std::string& path, std::string_view data, bool binary) {
  std::vector<MeshTexture> all = gltf_textures(path, data, binary);
  return all.empty() ? MeshTexture{} : std::move(all.front());
}

}  // namespace isochart::io_detail
