#pragma once
// Helpers shared by the I/O, validation, shared-mesh and CLI tests.

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "isochart/mesh.h"

namespace io_test {

namespace fs = std::filesystem;

inline std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> e;
  for (const auto& d : fs::directory_iterator(dir)) e.push_back(d.path().filename().string());
  std::sort(e.begin(), e.end());
  return e;
}

inline std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void write_bytes(const fs::path& p, const std::string& data) {
  std::ofstream(p, std::ios::binary) << data;
}

/// A fresh directory under the system temp directory, removed with everything in it.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag = "io") {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("isocharts_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path / name).string(); }
  std::string write(const std::string& name, const std::string& content) const {
    write_bytes(path / name, content);
    return file(name);
  }
  std::vector<std::string> entries() const { return io_test::entries(path); }
};

/// Binary records in a chosen byte order.
struct Bytes {
  std::string data;
  bool big_endian = false;
  template <typename T>
  Bytes& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big_endian) std::reverse(b, b + sizeof(T));
    data.append(b, sizeof(T));
    return *this;
  }
};

inline std::string base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < in.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, in.size() - i);
    unsigned v = 0;
    for (std::size_t k = 0; k < 3; ++k) v = v << 8 | (k < n ? static_cast<unsigned char>(in[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) out += k <= n ? t[(v >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

/// Signed volume enclosed by the faces (positive when they face outward).
inline double signed_volume(const isochart::Mesh& m) {
  using isochart::cross;
  using isochart::dot;
  double v = 0;
  const isochart::Vec3d o = m.positions.empty() ? isochart::Vec3d{} : m.positions[0];
  for (const auto& f : m.faces)
    v += dot(m.positions[f[0]] - o, cross(m.positions[f[1]] - o, m.positions[f[2]] - o)) / 6;
  return v;
}

/// Every edge with two faces is run in opposite directions by them.
inline bool consistently_oriented(const isochart::Mesh& m, const isochart::Topology& t) {
  for (int e = 0; e < t.num_edges(); ++e) {
    const isochart::IndexRange ef = t.edge_faces(e);
    if (ef.size() != 2) continue;
    int dir[2] = {0, 0};
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 3; ++k)
        if (t.face_edge(ef[i], k) == e) dir[i] = m.faces[ef[i]][k] == t.edge(e).v0 ? 1 : -1;
    if (dir[0] == dir[1]) return false;
  }
  return true;
}

}  // namespace io_test
