// `isocharts info FILE`: counts, topology and the problems found in a mesh.

#include <sstream>

#include "cli.h"
#include "isochart/mesh.h"

namespace cli {

namespace {

struct InfoArgs {
  std::string input;
};

void run_info(const Context& ctx, const InfoArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  ctx.check_paths({a.input}, {});
  isochart::LoadResult r = ctx.load(a.input);
  const isochart::Mesh& m = r.mesh;
  const isochart::Topology topo(m);
  const auto& rep = r.report;
  const auto box = isochart::bounding_box(m);

  nlohmann::json j;
  j["file"] = a.input;
  j["vertices"] = rep.input_vertices;
  j["faces"] = rep.input_faces;
  j["components"] = topo.num_components();
  j["boundary_loops"] = static_cast<int>(topo.boundary_loops().size());
  j["genus"] = topo.genus();
  j["euler_characteristic"] = topo.euler_characteristic();
  j["closed"] = topo.boundary_loops().empty();
  j["nonmanifold_edges"] = rep.nonmanifold_edges;
  j["nonmanifold_vertices"] = rep.nonmanifold_vertices;
  j["degenerate_faces"] = rep.degenerate_faces;
  j["duplicate_faces"] = rep.duplicate_faces;
  j["double_sided_faces"] = rep.double_sided_faces;
  j["unreferenced_vertices"] = rep.unreferenced_vertices;
  j["polygons_triangulated"] = rep.polygons;
  j["reoriented_faces"] = rep.reoriented_faces;
  // A Möbius strip is cut open to be oriented: the topology above is the cut surface's (a disk).
  j["orientable"] = rep.cut_edges == 0;
  j["cut_edges"] = rep.cut_edges;
  // The mesh the tools work on (triangulated, repaired), whose topology is reported above.
  j["used_vertices"] = m.num_vertices();
  j["used_triangles"] = m.num_faces();
  j["edges"] = topo.num_edges();
  j["surface_area"] = isochart::surface_area(m);
  j["bbox_diagonal"] = box.diagonal();
  j["bbox_min"] = {box.min.x, box.min.y, box.min.z};
  j["bbox_max"] = {box.max.x, box.max.y, box.max.z};
  j["has_uvs"] = m.has_uvs();
  j["has_normals"] = m.has_normals();
  j["has_colors"] = m.has_colors();
  j["warnings"] = rep.warnings;
  j["seconds"] = seconds_since(t0);

  std::ostringstream t;
  t << a.input << "\n"
    << "  vertices             " << rep.input_vertices << "\n"
    << "  faces                " << rep.input_faces << "\n";
  // Polygons are triangulated and repairs drop faces and vertices: the topology below is that
  // of the mesh the tools use, so its counts are shown when they differ from the file's.
  if (m.num_faces() != rep.input_faces || m.num_vertices() != rep.input_vertices)
    t << "  used                 " << m.num_vertices() << " vertices, " << m.num_faces() << " triangles, "
      << topo.num_edges() << " edges (the topology below)\n";
  t << "  components           " << topo.num_components() << "\n"
    << "  boundary loops       " << topo.boundary_loops().size() << "\n"
    << "  genus                " << topo.genus() << "\n"
    << "  euler characteristic " << topo.euler_characteristic() << "\n"
    << "  orientable           "
    << (rep.cut_edges == 0
            ? std::string("yes")
            : "no (cut open along " + std::to_string(rep.cut_edges) +
                  (rep.cut_edges == 1 ? " edge" : " edges") + "; the counts above are of the cut surface)")
    << "\n"
    << "  non-manifold edges   " << rep.nonmanifold_edges << "\n"
    << "  non-manifold vertices " << rep.nonmanifold_vertices << "\n"
    << "  degenerate faces     " << rep.degenerate_faces << "\n"
    << "  duplicate faces      " << rep.duplicate_faces << "\n"
    << (rep.double_sided_faces > 0 ? "  double-sided faces   " + std::to_string(rep.double_sided_faces) +
                                         " (kept as a separate back sheet)\n"
                                   : std::string())
    << "  unreferenced vertices " << rep.unreferenced_vertices << "\n"
    << "  attributes          " << (m.has_uvs() ? " uv" : "") << (m.has_normals() ? " normals" : "")
    << (m.has_colors() ? " colors" : "") << (m.has_uvs() || m.has_normals() || m.has_colors() ? "" : " none")
    << "\n"
    << "  bbox diagonal        " << box.diagonal() << "\n";
  ctx.emit(j, t.str());
}

}  // namespace

void add_info(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* sub = app.add_subcommand("info", "Counts, topology and problems of a mesh");
  sub->add_option("input", args->input, "Mesh file (OBJ/OFF/PLY/glTF) or builtin:NAME")->required();
  sub->footer("Example: isocharts info ../shared/data/meshes/bunny.obj --json");
  sub->callback([&ctx, args, &action] { action = [&ctx, args] { run_info(ctx, *args); }; });
}

}  // namespace cli
