// SCAFFOLD: minimal reader so the skeleton builds; replaced by the full I/O module.
#include "isochart/io.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "isochart/builtin.h"
#include "isochart/error.h"

namespace isochart {

MeshFormat format_from_path(const std::string& path) {
  if (path.rfind("builtin:", 0) == 0) return MeshFormat::Builtin;
  const auto dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == "obj") return MeshFormat::Obj;
  if (ext == "off") return MeshFormat::Off;
  if (ext == "ply") return MeshFormat::Ply;
  if (ext == "gltf") return MeshFormat::Gltf;
  if (ext == "glb") return MeshFormat::Glb;
  throw InputError(path, "unknown mesh format '." + ext + "' (expected .obj, .off, .ply, .gltf or .glb)");
}

RawMesh read_raw_mesh(const std::string& path, const LoadOptions&) {
  RawMesh raw;
  raw.source = path;
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file");
  const MeshFormat fmt = format_from_path(path);
  if (fmt == MeshFormat::Off) {
    std::string h;
    in >> h;
    long nv, nf, ne;
    in >> nv >> nf >> ne;
    raw.positions.resize(nv);
    for (auto& p : raw.positions) in >> p.x >> p.y >> p.z;
    raw.polygons.resize(nf);
    for (auto& poly : raw.polygons) {
      int n;
      in >> n;
      poly.resize(n);
      for (int& i : poly) in >> i;
    }
  } else if (fmt == MeshFormat::Obj) {
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::string tag;
      ls >> tag;
      if (tag == "v") {
        Vec3d p;
        ls >> p.x >> p.y >> p.z;
        raw.positions.push_back(p);
      } else if (tag == "f") {
        std::vector<int> poly;
        std::string tok;
        while (ls >> tok) poly.push_back(std::stoi(tok) - 1);
        raw.polygons.push_back(poly);
      }
    }
  } else {
    throw InputError(path, "format not supported yet");
  }
  return raw;
}

Mesh validate_mesh(const RawMesh& raw, bool, ValidationReport& report) {
  Mesh m;
  m.positions = raw.positions;
  for (const auto& p : raw.polygons) m.faces.push_back({p[0], p[1], p[2]});
  report.input_vertices = static_cast<int>(raw.positions.size());
  report.input_faces = static_cast<int>(raw.polygons.size());
  return m;
}

LoadResult load_mesh(const std::string& path, const LoadOptions& options) {
  LoadResult r;
  RawMesh raw = read_raw_mesh(path, options);
  r.mesh = validate_mesh(raw, options.repair, r.report);
  return r;
}

void write_file_atomic(const std::string& path, const std::string& data) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << data;
    if (!out) throw Error("cannot write " + path);
  }
  std::rename(tmp.c_str(), path.c_str());
}

}  // namespace isochart
