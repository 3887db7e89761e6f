// `isocharts bench [MESH...] --methods isochart,lscm,... --res 256 --out DIR`: atlases of every
// method on every mesh, measured the same way (our packer, our stretch, MCGIM PSNR at a matched
// number of defined samples, as in Iso-charts Table II), written as Markdown, CSV and PNG plots.

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "cli.h"
#include "isochart/atlas.h"
#include "isochart/baselines.h"
#include "isochart/builtin.h"
#include "isochart/error.h"
#include "isochart/image.h"
#include "mcgim/mcgim.h"
#include "mcgim/psnr.h"

namespace cli {

namespace {

namespace fs = std::filesystem;

// Without an error code these throw on a name too long to look up (an "internal error").
bool file_exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}
using Clock = std::chrono::steady_clock;

enum class Kind { Isochart, IsomapNocut, Lscm, LscmStretch, ExternalAuto, ExternalFile };

struct Method {
  Kind kind;
  std::string name;  // as given (external:FILE keeps its file)
  std::string file;  // ExternalFile only
};

struct BenchArgs {
  std::vector<std::string> meshes;
  std::string methods = "isochart,isomap-nocut,lscm,lscm+stretch,external";
  int res = 256;
  std::string out = "bench_out";
  std::string data = "../shared/data";
  bool data_given = false;
  double max_l2 = 1.1;
  double max_linf = 5.0;
  int pack_res = 512;
  long long psnr_samples = 300'000;
  std::vector<double> sweep = {1.03, 1.06, 1.1, 1.2, 1.4};
  int sweep_max_faces = 10'000;
  bool no_plots = false;
  double atlas_aspect = 0;  // external atlases' texture width / height; 0: read from the UVs
};

// One mesh × method.
struct Row {
  std::string mesh;
  int faces = 0;
  bool closed = false;
  std::string method;
  std::string note;  // "n/a: reason" when the run failed
  int charts = 0;
  double l2 = NAN, linf = NAN, packing = NAN;
  int width = 0, height = 0;
  long long defined = 0, unique = 0, target = 0;
  double psnr = NAN;
  double s_atlas = 0, s_pack = 0, s_mcgim = 0, s_psnr = 0;
};

struct SweepPoint {
  std::string mesh, method;
  double bound = 0;
  int charts = 0;
  double l2 = NAN;
};

std::vector<Method> parse_methods_impl(const std::string& list) {
  std::vector<Method> out;
  for (const std::string& m : split_items("--methods", list)) {
    Method x{Kind::Isochart, m, ""};
    if (m == "isochart" || m == "iso-charts")
      x = {Kind::Isochart, "isochart", ""};
    else if (m == "isomap-nocut")
      x.kind = Kind::IsomapNocut;
    else if (m == "lscm")
      x.kind = Kind::Lscm;
    else if (m == "lscm+stretch")
      x.kind = Kind::LscmStretch;
    else if (m == "external")
      x.kind = Kind::ExternalAuto;
    else if (m.rfind("external:", 0) == 0 && m.size() > 9) {
      x.kind = Kind::ExternalFile;
      x.file = m.substr(9);
      if (!file_exists(x.file)) throw isochart::InputError(x.file, "no such file (method " + m + ")");
    } else {
      throw isochart::InputError("", "unknown method '" + m +
                                         "' (expected isochart, isomap-nocut, lscm, lscm+stretch, external "
                                         "or external:FILE.obj)");
    }
    for (const Method& y : out)
      if (y.name == x.name) throw isochart::InputError("", "method '" + m + "' given twice");
    out.push_back(x);
  }
  return out;
}

std::string stem(const std::string& path) {
  const std::string b = "builtin:";
  if (path.rfind(b, 0) == 0) return path.substr(b.size());
  return fs::path(path).stem().string();
}

std::vector<std::string> default_meshes(const std::string& data) {
  std::vector<std::string> out;
  const fs::path dir = fs::path(data) / "meshes";
  std::error_code ec;
  if (fs::is_directory(dir, ec)) {
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".gltf" || ext == ".glb")
        out.push_back(e.path().string());
    }
    std::sort(out.begin(), out.end());
  }
  if (out.empty())
    for (const auto& n : isochart::builtin_names()) out.push_back("builtin:" + n);
  return out;
}

// DATA/baseline_atlases/NAME_TOOL.obj for mesh NAME, as ("external:TOOL", file), sorted.
std::vector<std::pair<std::string, std::string>> auto_externals(const std::string& data,
                                                                const std::string& name) {
  const fs::path dir = fs::path(data) / "baseline_atlases";
  std::error_code ec;
  std::vector<std::string> files;
  if (fs::is_directory(dir, ec))
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string s = e.path().stem().string();
      if (e.path().extension() == ".obj" && s.rfind(name + "_", 0) == 0 &&
          s.find('_', name.size() + 1) == std::string::npos)
        files.push_back(e.path().string());
    }
  std::sort(files.begin(), files.end());
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& f : files) out.push_back({"external:" + stem(f).substr(name.size() + 1), f});
  return out;
}

isochart::Mesh load_any(const Context& ctx, const std::string& path, bool atlas = false) {
  const std::string prefix = "builtin:";
  if (path.rfind(prefix, 0) == 0) return isochart::make_builtin(path.substr(prefix.size()));
  if (!file_exists(path)) throw isochart::InputError(path, "no such file");
  return ctx.load(path, atlas).mesh;
}

std::string fmt(double x, int digits) {
  // An exact remesh (a flat sliver) has infinite PSNR: not a failure, which reads "–".
  if (x == std::numeric_limits<double>::infinity()) return "inf";
  if (!std::isfinite(x)) return "–";
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << x;
  return s.str();
}

std::string csv_num(double x, int digits) {
  if (x == std::numeric_limits<double>::infinity()) return "inf";
  if (!std::isfinite(x)) return "";
  std::ostringstream s;
  s << std::setprecision(digits) << x;
  return s.str();
}

// An atlas built by one method, with the geometry it parameterizes.
struct BuiltAtlas {
  isochart::Mesh geometry;
  isochart::Atlas atlas;
  double s_atlas = 0, s_pack = 0;
};

double stage_seconds(const isochart::Atlas& a, const char* key) {
  const auto it = a.stats.seconds.find(key);
  return it == a.stats.seconds.end() ? 0.0 : it->second;
}

class Bench {
 public:
  Bench(const Context& ctx, const BenchArgs& a, std::vector<Method> methods)
      : ctx_(ctx), a_(a), methods_(std::move(methods)) {
    pack_.width = pack_.height = a.pack_res;
  }

  BuiltAtlas build(const isochart::Mesh& mesh, Kind kind, double max_l2, const isochart::Atlas* lscm_cache) {
    BuiltAtlas b;
    b.geometry = mesh;
    const auto t0 = Clock::now();
    if (kind == Kind::Isochart || kind == Kind::IsomapNocut) {
      isochart::AtlasOptions ao;
      ao.max_l2 = max_l2;
      ao.max_linf = a_.max_linf;
      ao.seed = ctx_.opts.seed;
      ao.graph_cut = kind == Kind::Isochart;
      ao.pack = pack_;
      b.atlas = isochart::build_atlas(mesh, ao, ctx_.progress());
    } else {
      if (lscm_cache) {
        b.atlas = *lscm_cache;
      } else {
        isochart::LscmOptions lo;
        lo.max_l2 = max_l2;
        lo.max_linf = a_.max_linf;
        lo.pack = pack_;
        b.atlas = isochart::build_lscm_atlas(mesh, lo, ctx_.progress());
      }
      if (kind == Kind::LscmStretch) {
        isochart::OptimizeOptions oo;
        oo.max_linf = a_.max_linf;
        oo.seed = ctx_.opts.seed;
        isochart::optimize_atlas_stretch(mesh, b.atlas, oo, pack_, ctx_.progress());
      }
    }
    b.s_pack = stage_seconds(b.atlas, "packing");
    b.s_atlas = std::chrono::duration<double>(Clock::now() - t0).count() - b.s_pack;
    if (lscm_cache) b.s_atlas += stage_seconds(*lscm_cache, "total") - stage_seconds(*lscm_cache, "packing");
    return b;
  }

  /// Loaded once: an explicit external:FILE is tried against every mesh. Its texture's shape
  /// is read (and said) once too.
  const std::pair<isochart::Mesh, double>& load_external(const std::string& file) {
    auto it = loaded_.find(file);
    if (it == loaded_.end()) {
      isochart::Mesh m = load_any(ctx_, file, true);
      const double aspect =
          a_.atlas_aspect > 0
              ? a_.atlas_aspect
              : read_texture_aspect(
                    ctx_, file, m, 1.0,
                    "its charts are measured and packed at that shape (--atlas-aspect sets it)");
      it = loaded_.emplace(file, std::make_pair(std::move(m), aspect)).first;
    }
    return it->second;
  }

  BuiltAtlas external(const std::string& file) {
    BuiltAtlas b;
    const auto t0 = Clock::now();
    const auto& loaded = load_external(file);
    b.geometry = loaded.first;
    try {
      b.atlas = isochart::atlas_from_uvs(b.geometry, loaded.second);
    } catch (const isochart::InputError& e) {
      throw isochart::InputError(file, e.what());
    }
    b.s_atlas = std::chrono::duration<double>(Clock::now() - t0).count();
    const auto tp = Clock::now();
    isochart::pack_atlas(b.geometry, b.atlas, pack_, ctx_.progress());
    b.s_pack = std::chrono::duration<double>(Clock::now() - tp).count();
    return b;
  }

  // The resolution whose defined samples are nearest `target`; the first within 2% ends the
  // search. Each trial packs anew, so counts move in steps of a few percent at small sizes: after
  // the rescaling steps, the neighbours of the best size are walked one side at a time. Trials
  // skip the sample optimization (it moves samples, never adds or drops them).
  // `note` says so when the match needs an image beyond the largest side.
  mcgim::Level matched_level(const isochart::Mesh& atlas_mesh, long long target, std::string& note) {
    mcgim::LevelOptions lo;
    lo.atlas_aspect = 1;  // every atlas here, external ones included, was packed square by pack_atlas
    const mcgim::ResolutionChoice rc =
        mcgim::match_resolution(atlas_mesh, target, lo, ctx_.progress(), kMaxImageSide);
    if (rc.capped)
      note = "at most " + std::to_string(kMaxImageSide) + "x" + std::to_string(kMaxImageSide) +
             ", fewer samples than the first method";
    lo.width = rc.width;
    lo.height = rc.height;
    mcgim::Level lv = mcgim::build_level(atlas_mesh, lo, ctx_.progress());
    // The search gives up after a few dozen sizes; a miss beyond the ±2 % the table promises is said.
    const double off =
        100.0 * static_cast<double>(lv.stats.defined_samples - target) / static_cast<double>(target);
    if (!rc.capped && std::abs(off) > 2)
      note = "defined samples " + fmt(off, 1) + " % off the first method's";
    return lv;
  }

  // Atlas figures, MCGIM at the matched budget (or at res² for the reference), PSNR.
  void measure(Row& r, const BuiltAtlas& b, long long& target) {
    const isochart::Atlas& at = b.atlas;
    r.charts = at.num_charts();
    r.l2 = at.stats.l2;
    r.linf = at.stats.linf;
    r.packing = at.stats.packing_ratio;
    r.s_atlas = b.s_atlas;
    r.s_pack = b.s_pack;
    const isochart::Mesh m = at.apply_to(b.geometry);
    const auto t0 = Clock::now();
    mcgim::Level lv;
    if (target <= 0) {
      mcgim::LevelOptions lo;
      lo.atlas_aspect = 1;
      lo.width = lo.height = a_.res;
      lv = mcgim::build_level(m, lo, ctx_.progress());
      target = lv.stats.defined_samples;
    } else {
      lv = matched_level(m, target, r.note);
    }
    r.s_mcgim = std::chrono::duration<double>(Clock::now() - t0).count();
    r.target = target;
    r.width = lv.stats.width;
    r.height = lv.stats.height;
    r.defined = lv.stats.defined_samples;
    r.unique = lv.stats.unique_vertices;
    mcgim::DistanceOptions dopt;
    dopt.samples = a_.psnr_samples;
    dopt.seed = ctx_.opts.seed;
    const mcgim::DistanceResult d =
        mcgim::measure_distance(b.geometry, lv.remesh.mesh, dopt, ctx_.progress());
    r.psnr = d.psnr;
    r.s_psnr = d.seconds;
    // An infinite stretch needs its reason (one turned triangle of thousands makes it infinite).
    if (!std::isfinite(r.l2)) {
      const std::string why = std::to_string(at.stats.flipped) +
                              (at.stats.flipped == 1 ? " UV triangle flipped or collapsed"
                                                     : " UV triangles flipped or collapsed") +
                              ": stretch infinite";
      r.note = r.note.empty() ? why : r.note + "; " + why;
    }
  }

  void line(const Row& r, int k, int n) const {
    if (ctx_.opts.quiet) return;
    ctx_.end_progress();
    std::cerr << "bench [" << k << "/" << n << "] " << r.mesh << " " << r.method << ": ";
    if (!r.note.empty() && r.note.rfind("n/a", 0) == 0)
      std::cerr << r.note;
    else
      std::cerr << r.charts << " charts, L2 " << fmt(r.l2, 3) << ", " << r.defined << " defined, PSNR "
                << fmt(r.psnr, 2) << " dB (" << fmt(r.s_atlas + r.s_pack + r.s_mcgim + r.s_psnr, 1) << " s)";
    std::cerr << "\n";
  }

  // Runs every method on one mesh; appends rows.
  void run_mesh(const std::string& path, const isochart::Mesh& mesh, int& k, int n) {
    const isochart::Topology topo(mesh);
    const std::string name = stem(path);
    const bool closed = topo.boundary_loops().empty();
    long long target = 0;
    std::unique_ptr<isochart::Atlas> lscm_cache;
    for (const Method& meth : methods_) {
      std::vector<std::pair<std::string, std::string>> externals;  // label, file
      if (meth.kind == Kind::ExternalAuto) {
        externals = auto_externals(a_.data, name);
        if (externals.empty()) {
          // No atlas from another tool for this mesh: silently skipped among other methods,
          // but a run asking only for them says so rather than printing an empty table.
          if (methods_.size() > 1) {
            without_baselines_.push_back(name);
            continue;
          }
          Row r;
          r.mesh = name;
          r.faces = mesh.num_faces();
          r.closed = closed;
          r.method = "external";
          r.note = "n/a: no baseline atlas " +
                   (fs::path(a_.data) / "baseline_atlases" / (name + "_*.obj")).string();
          rows_.push_back(r);
          line(r, ++k, n);
          continue;
        }
      } else if (meth.kind == Kind::ExternalFile) {
        externals.push_back({"external:" + stem(meth.file), meth.file});
      }
      const std::size_t runs = externals.empty() ? 1 : externals.size();
      for (std::size_t e = 0; e < runs; ++e) {
        Row r;
        r.mesh = name;
        r.faces = mesh.num_faces();
        r.closed = closed;
        r.method = externals.empty() ? meth.name : externals[e].first;
        try {
          BuiltAtlas b;
          if (!externals.empty()) {
            b = external(externals[e].second);
            if (b.geometry.num_faces() != mesh.num_faces())
              throw isochart::InputError("", "the atlas has " + std::to_string(b.geometry.num_faces()) +
                                                 " faces, the mesh " + std::to_string(mesh.num_faces()));
            // Its remesh is measured against its own geometry: that must be this mesh's.
            check_atlas_matches(mesh, b.geometry, "");
          } else {
            b = build(mesh, meth.kind, a_.max_l2,
                      meth.kind == Kind::LscmStretch ? lscm_cache.get() : nullptr);
            if (meth.kind == Kind::Lscm) lscm_cache = std::make_unique<isochart::Atlas>(b.atlas);
          }
          measure(r, b, target);
        } catch (const isochart::Cancelled&) {
          throw;
        } catch (const std::bad_alloc&) {
          throw;
        } catch (const std::exception& ex) {
          // One failing atlas (e.g. another tool's chart that is not a disk) must not end the bench.
          r.note = std::string("n/a: ") + ex.what();
          std::replace(r.note.begin(), r.note.end(), '\n', ' ');
          std::replace(r.note.begin(), r.note.end(), '|', '/');
        }
        rows_.push_back(r);
        line(r, ++k, n);
      }
    }
    if (a_.sweep_max_faces > 0 && mesh.num_faces() <= a_.sweep_max_faces && !a_.sweep.empty())
      sweep(mesh, name);
  }

  void sweep(const isochart::Mesh& mesh, const std::string& name) {
    std::map<double, isochart::Atlas> lscm;  // lscm+stretch optimizes the lscm charts of its bound
    for (const Method& meth : methods_) {
      if (meth.kind == Kind::ExternalAuto || meth.kind == Kind::ExternalFile) continue;
      for (double bound : a_.sweep) {
        SweepPoint p{name, meth.name, bound, 0, NAN};
        try {
          const auto it = lscm.find(bound);
          const bool reuse = meth.kind == Kind::LscmStretch && it != lscm.end();
          const BuiltAtlas b = build(mesh, meth.kind, bound, reuse ? &it->second : nullptr);
          if (meth.kind == Kind::Lscm) lscm[bound] = b.atlas;
          p.charts = b.atlas.num_charts();
          p.l2 = b.atlas.stats.l2;
        } catch (const isochart::Cancelled&) {
          throw;
        } catch (const std::bad_alloc&) {
          throw;
        } catch (const std::exception&) {
          continue;  // a bound a method cannot meet leaves a gap in its curve
        }
        sweep_.push_back(p);
      }
    }
    if (!ctx_.opts.quiet) {
      ctx_.end_progress();
      std::cerr << "bench sweep " << name << ": " << a_.sweep.size() << " L2 bounds done\n";
    }
  }

  const std::vector<Row>& rows() const { return rows_; }
  const std::vector<SweepPoint>& sweep_points() const { return sweep_; }
  /// Meshes whose `external` rows were left out for want of baseline atlases.
  const std::vector<std::string>& without_baselines() const { return without_baselines_; }

 private:
  const Context& ctx_;
  const BenchArgs& a_;
  std::vector<Method> methods_;
  isochart::PackOptions pack_;
  std::vector<Row> rows_;
  std::vector<std::string> without_baselines_;
  std::vector<SweepPoint> sweep_;
  std::map<std::string, std::pair<isochart::Mesh, double>> loaded_;  // external atlas, its texture aspect
};

// ---- Output ---------------------------------------------------------------------------------

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string to_csv(const std::vector<Row>& rows) {
  std::ostringstream s;
  s << "mesh,faces,closed,method,charts,l2,linf,packing_ratio,width,height,defined_samples,unique_samples,"
       "target_samples,defined_diff_percent,psnr_db,seconds_atlas,seconds_packing,seconds_mcgim,seconds_psnr,"
       "note\n";
  for (const Row& r : rows) {
    const bool ok = r.note.rfind("n/a", 0) != 0;
    s << csv_quote(r.mesh) << "," << r.faces << "," << (r.closed ? 1 : 0) << "," << csv_quote(r.method)
      << ",";
    if (ok) {
      s << r.charts << "," << csv_num(r.l2, 6) << "," << csv_num(r.linf, 6) << "," << csv_num(r.packing, 4)
        << "," << r.width << "," << r.height << "," << r.defined << "," << r.unique << "," << r.target << ","
        << csv_num(100.0 * (r.defined - r.target) / std::max<long long>(r.target, 1), 4) << ","
        << csv_num(r.psnr, 6) << ",";
    } else {
      s << ",,,,,,,,,,,";
    }
    s << csv_num(r.s_atlas, 4) << "," << csv_num(r.s_pack, 4) << "," << csv_num(r.s_mcgim, 4) << ","
      << csv_num(r.s_psnr, 4) << "," << csv_quote(r.note) << "\n";
  }
  return s.str();
}

std::string sweep_csv(const std::vector<SweepPoint>& pts) {
  std::ostringstream s;
  s << "mesh,method,max_l2,charts,l2\n";
  for (const auto& p : pts)
    s << csv_quote(p.mesh) << "," << csv_quote(p.method) << "," << p.bound << "," << p.charts << ","
      << csv_num(p.l2, 6) << "\n";
  return s.str();
}

std::string to_markdown(const std::vector<Row>& rows, const std::vector<SweepPoint>& pts,
                        const BenchArgs& a) {
  std::ostringstream s;
  s << "| mesh | faces | method | charts | L2 | Linf | packing | resolution | defined | unique | PSNR (dB) | "
       "atlas s | pack s | MCGIM s | PSNR s | note |\n"
    << "|---|---:|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Row& r : rows) {
    const bool ok = r.note.rfind("n/a", 0) != 0;
    s << "| " << r.mesh << " | " << r.faces << " | " << r.method << " | ";
    if (ok)
      s << r.charts << " | " << fmt(r.l2, 3) << " | " << fmt(r.linf, 2) << " | " << fmt(r.packing, 3) << " | "
        << r.width << "×" << r.height << " | " << r.defined << " | " << r.unique << " | " << fmt(r.psnr, 2)
        << " | ";
    else
      s << "– | – | – | – | – | – | – | – | ";
    s << fmt(r.s_atlas, 1) << " | " << fmt(r.s_pack, 1) << " | " << fmt(r.s_mcgim, 1) << " | "
      << fmt(r.s_psnr, 1) << " | " << r.note << " |\n";
  }
  // Iso-charts against the lscm baseline, per mesh: PSNR at matched samples and chart counts.
  std::map<std::string, std::map<std::string, const Row*>> by;
  std::vector<std::string> order;
  for (const Row& r : rows) {
    if (by.find(r.mesh) == by.end()) order.push_back(r.mesh);
    by[r.mesh][r.method] = &r;
  }
  std::ostringstream f;
  for (const auto& m : order) {
    const auto& mm = by[m];
    const auto i = mm.find("isochart"), l = mm.find("lscm");
    if (i == mm.end() || l == mm.end()) continue;
    const Row& ri = *i->second;
    const Row& rl = *l->second;
    if (!std::isfinite(ri.psnr) || !std::isfinite(rl.psnr)) {
      const Row& missing = std::isfinite(ri.psnr) ? rl : ri;
      f << "- " << m << ": no comparison ("
        << (std::isinf(ri.psnr) && std::isinf(rl.psnr) ? "both remeshes are exact (PSNR inf)"
            : std::isinf(missing.psnr)                 ? missing.method + "'s remesh is exact (PSNR inf)"
                                                       : missing.note)
        << ")\n";
      continue;
    }
    const double dp = ri.psnr - rl.psnr;
    f << "- " << m << (ri.closed ? " (closed)" : " (open)") << ": PSNR isochart − lscm = " << std::showpos
      << fmt(dp, 2) << std::noshowpos << " dB; charts " << ri.charts << " vs " << rl.charts << " at L2 "
      << fmt(ri.l2, 3) << " vs " << fmt(rl.l2, 3)
      << (dp >= 0.005   ? ""
          : dp > -0.005 ? " — a tie on PSNR"
                        : " — **lscm wins on PSNR**")  // as printed
      << (ri.charts < rl.charts ? "" : " — **isochart not fewer charts**") << "\n";
  }
  if (!f.str().empty()) s << "\nIso-charts against lscm, per mesh:\n\n" << f.str();
  if (!pts.empty()) {
    s << "\nStretch sweep (max-l2 bounds";
    for (double b : a.sweep) s << " " << b;
    s << "): charts / achieved L2 per bound.\n\n| mesh | method |";
    for (double b : a.sweep) s << " ≤" << b << " |";
    s << "\n|---|---|";
    for (std::size_t i = 0; i < a.sweep.size(); ++i) s << "---|";
    s << "\n";
    std::map<std::pair<std::string, std::string>, std::map<double, const SweepPoint*>> t;
    std::vector<std::pair<std::string, std::string>> keys;
    for (const auto& p : pts) {
      const auto key = std::make_pair(p.mesh, p.method);
      if (t.find(key) == t.end()) keys.push_back(key);
      t[key][p.bound] = &p;
    }
    for (const auto& key : keys) {
      s << "| " << key.first << " | " << key.second << " |";
      for (double b : a.sweep) {
        const auto it = t[key].find(b);
        if (it == t[key].end())
          s << " – |";
        else
          s << " " << it->second->charts << " / " << fmt(it->second->l2, 3) << " |";
      }
      s << "\n";
    }
  }
  return s.str();
}

// ---- Plots (drawn into an isochart::Image; a 3×5 bitmap font for labels) -------------------

struct Rgb {
  float r, g, b;
};
const Rgb kPalette[] = {{0.12f, 0.47f, 0.71f}, {1.0f, 0.5f, 0.05f},  {0.17f, 0.63f, 0.17f},
                        {0.84f, 0.15f, 0.16f}, {0.58f, 0.4f, 0.74f}, {0.55f, 0.34f, 0.29f},
                        {0.89f, 0.47f, 0.76f}, {0.5f, 0.5f, 0.5f}};
const Rgb kBlack{0, 0, 0}, kGrey{0.85f, 0.85f, 0.85f};

const char* glyph(char c) {
  static const std::map<char, const char*> g = {
      {'0', "111101101101111"}, {'1', "010110010010111"}, {'2', "111001111100111"}, {'3', "111001111001111"},
      {'4', "101101111001001"}, {'5', "111100111001111"}, {'6', "111100111101111"}, {'7', "111001001001001"},
      {'8', "111101111101111"}, {'9', "111101111001111"}, {'A', "010101111101101"}, {'B', "110101110101110"},
      {'C', "011100100100011"}, {'D', "110101101101110"}, {'E', "111100110100111"}, {'F', "111100110100100"},
      {'G', "011100101101011"}, {'H', "101101111101101"}, {'I', "111010010010111"}, {'J', "001001001101010"},
      {'K', "101101110101101"}, {'L', "100100100100111"}, {'M', "101111111101101"}, {'N', "110101101101101"},
      {'O', "010101101101010"}, {'P', "110101110100100"}, {'Q', "010101101110011"}, {'R', "110101110101101"},
      {'S', "011100010001110"}, {'T', "111010010010010"}, {'U', "101101101101111"}, {'V', "101101101101010"},
      {'W', "101101111111101"}, {'X', "101101010101101"}, {'Y', "101101010010010"}, {'Z', "111001010100111"},
      {'.', "000000000000010"}, {'-', "000000111000000"}, {'+', "000010111010000"}, {':', "000010000010000"},
      {'/', "001001010100100"}, {'_', "000000000000111"}, {'=', "000111000111000"}, {'(', "001010010010001"},
      {')', "100010010010100"}, {'%', "101001010100101"}, {' ', "000000000000000"}, {'<', "001010100010001"}};
  const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const auto it = g.find(u);
  return it == g.end() ? "111111111111111" : it->second;
}

class Canvas {
 public:
  Canvas(int w, int h) : img_(w, h, 3, 1.0f) {}
  void pixel(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return;
    img_.at(x, y, 0) = c.r;
    img_.at(x, y, 1) = c.g;
    img_.at(x, y, 2) = c.b;
  }
  void rect(int x0, int y0, int x1, int y1, Rgb c) {
    for (int y = std::min(y0, y1); y <= std::max(y0, y1); ++y)
      for (int x = std::min(x0, x1); x <= std::max(x0, x1); ++x) pixel(x, y, c);
  }
  void line(double x0, double y0, double x1, double y1, Rgb c, int thick = 1) {
    const int steps = static_cast<int>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1;
    for (int i = 0; i <= steps; ++i) {
      const double t = static_cast<double>(i) / steps;
      const int x = static_cast<int>(std::lround(x0 + (x1 - x0) * t));
      const int y = static_cast<int>(std::lround(y0 + (y1 - y0) * t));
      rect(x - thick / 2, y - thick / 2, x + (thick - 1) / 2, y + (thick - 1) / 2, c);
    }
  }
  // Text with its top-left corner at (x, y); 4·scale pixels per character.
  void text(int x, int y, const std::string& s, int scale = 2, Rgb c = kBlack) {
    for (std::size_t i = 0; i < s.size(); ++i) {
      const char* g = glyph(s[i]);
      for (int r = 0; r < 5; ++r)
        for (int q = 0; q < 3; ++q)
          if (g[r * 3 + q] == '1')
            rect(x + static_cast<int>(i) * 4 * scale + q * scale, y + r * scale,
                 x + static_cast<int>(i) * 4 * scale + q * scale + scale - 1, y + r * scale + scale - 1, c);
    }
  }
  static int text_width(const std::string& s, int scale = 2) {
    return static_cast<int>(s.size()) * 4 * scale;
  }
  const isochart::Image& image() const { return img_; }
  int width() const { return img_.width; }
  int height() const { return img_.height; }

 private:
  isochart::Image img_;
};

// Round tick step covering [lo, hi] with about n ticks.
double tick_step(double lo, double hi, int n) {
  const double raw = (hi - lo) / std::max(n, 1);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

std::string tick_label(double v, double step) {
  const int digits = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  return fmt(v, digits);
}

struct Axes {
  int x0, y0, x1, y1;  // plot area in pixels (y0 top)
  double xmin, xmax, ymin, ymax;
  double px(double x) const { return x0 + (x - xmin) / (xmax - xmin) * (x1 - x0); }
  double py(double y) const { return y1 - (y - ymin) / (ymax - ymin) * (y1 - y0); }
};

void draw_axes(Canvas& c, const Axes& ax, const std::string& title, const std::string& xlabel,
               const std::string& ylabel, bool xticks) {
  const double ys = tick_step(ax.ymin, ax.ymax, 6);
  for (double v = std::ceil(ax.ymin / ys) * ys; v <= ax.ymax + 1e-9; v += ys) {
    const int y = static_cast<int>(std::lround(ax.py(v)));
    c.line(ax.x0, y, ax.x1, y, kGrey);
    const std::string l = tick_label(v, ys);
    c.text(ax.x0 - 6 - Canvas::text_width(l), y - 5, l);
  }
  if (xticks) {
    const double xs = tick_step(ax.xmin, ax.xmax, 8);
    for (double v = std::ceil(ax.xmin / xs) * xs; v <= ax.xmax + 1e-9; v += xs) {
      const int x = static_cast<int>(std::lround(ax.px(v)));
      c.line(x, ax.y0, x, ax.y1, kGrey);
      const std::string l = tick_label(v, xs);
      c.text(x - Canvas::text_width(l) / 2, ax.y1 + 6, l);
    }
  }
  c.line(ax.x0, ax.y0, ax.x0, ax.y1, kBlack);
  c.line(ax.x0, ax.y1, ax.x1, ax.y1, kBlack);
  c.text(std::max(4, (ax.x0 + ax.x1 - Canvas::text_width(title, 3)) / 2), 8, title, 3);
  c.text((ax.x0 + ax.x1 - Canvas::text_width(xlabel)) / 2, c.height() - 18, xlabel);
  c.text(6, ax.y0 - 22, ylabel);
}

// One colour per method in every plot.
Rgb color_of(const std::string& method) {
  static const char* known[] = {"isochart",     "isomap-nocut",     "lscm",
                                "lscm+stretch", "external:uvatlas", "external:xatlas"};
  for (int i = 0; i < 6; ++i)
    if (method == known[i]) return kPalette[i];
  std::size_t h = 0;
  for (char ch : method) h = h * 31 + static_cast<unsigned char>(ch);
  return kPalette[6 + h % 2];
}

void legend(Canvas& c, int x, int y, const std::vector<std::string>& names) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    const int yy = y + static_cast<int>(i) * 16;
    c.rect(x, yy, x + 10, yy + 9, color_of(names[i]));
    c.text(x + 16, yy, names[i]);
  }
}

// Stretch against number of charts (Iso-charts Fig. 4), one curve per method.
isochart::Image plot_sweep(const std::vector<SweepPoint>& pts, const std::string& mesh) {
  std::vector<std::string> methods;
  double xmax = 1, ymin = 1e9, ymax = 0;
  for (const auto& p : pts) {
    if (p.mesh != mesh || !std::isfinite(p.l2)) continue;
    if (std::find(methods.begin(), methods.end(), p.method) == methods.end()) methods.push_back(p.method);
    xmax = std::max(xmax, static_cast<double>(p.charts));
    ymin = std::min(ymin, p.l2);
    ymax = std::max(ymax, p.l2);
  }
  Canvas c(640, 420);
  Axes ax{90, 50, 450, 370, 0, xmax * 1.08 + 1, std::max(1.0, ymin - 0.01), ymax + 0.01};
  draw_axes(c, ax, mesh + ": L2 STRETCH VS CHARTS", "CHARTS", "L2", true);
  for (std::size_t m = 0; m < methods.size(); ++m) {
    std::vector<const SweepPoint*> s;
    for (const auto& p : pts)
      if (p.mesh == mesh && p.method == methods[m] && std::isfinite(p.l2)) s.push_back(&p);
    // Ties in chart count (several bounds giving the same charts) go from high to low L2, so the
    // line runs down the column instead of zig-zagging in sweep order.
    std::sort(s.begin(), s.end(), [](auto* a, auto* b) {
      return a->charts != b->charts ? a->charts < b->charts : a->l2 > b->l2;
    });
    for (std::size_t i = 0; i < s.size(); ++i) {
      const double x = ax.px(s[i]->charts), y = ax.py(s[i]->l2);
      c.rect(static_cast<int>(x) - 3, static_cast<int>(y) - 3, static_cast<int>(x) + 3,
             static_cast<int>(y) + 3, color_of(methods[m]));
      if (i > 0) c.line(ax.px(s[i - 1]->charts), ax.py(s[i - 1]->l2), x, y, color_of(methods[m]), 2);
    }
  }
  legend(c, 465, 60, methods);
  return c.image();
}

// PSNR per mesh and method at matched defined samples: grouped bars.
isochart::Image plot_psnr(const std::vector<Row>& rows) {
  std::vector<std::string> meshes, methods;
  double lo = 1e9, hi = -1e9;
  for (const Row& r : rows) {
    if (!std::isfinite(r.psnr)) continue;
    if (std::find(meshes.begin(), meshes.end(), r.mesh) == meshes.end()) meshes.push_back(r.mesh);
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) methods.push_back(r.method);
    lo = std::min(lo, r.psnr);
    hi = std::max(hi, r.psnr);
  }
  if (meshes.empty()) return Canvas(320, 120).image();
  const int group = std::max(60, 10 * static_cast<int>(methods.size()) + 14);
  const int w = std::max(640, 90 + group * static_cast<int>(meshes.size()) + 190);
  Canvas c(w, 440);
  Axes ax{
      90, 50, 90 + group * static_cast<int>(meshes.size()), 370, 0, 1, std::floor(lo - 3), std::ceil(hi + 1)};
  draw_axes(c, ax, "GEOMETRY PSNR AT MATCHED DEFINED SAMPLES", "MESH", "PSNR DB", false);
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    const int gx = ax.x0 + static_cast<int>(mi) * group + 7;
    for (std::size_t k = 0; k < methods.size(); ++k)
      for (const Row& r : rows)
        if (r.mesh == meshes[mi] && r.method == methods[k] && std::isfinite(r.psnr)) {
          const int x = gx + static_cast<int>(k) * 10;
          c.rect(x, static_cast<int>(ax.py(r.psnr)), x + 8, ax.y1 - 1, color_of(methods[k]));
        }
    // Names at scale 1 on two staggered rows so long names do not collide.
    const std::string& n = meshes[mi];
    c.text(gx + (group - 14 - Canvas::text_width(n, 1)) / 2, ax.y1 + 6 + static_cast<int>(mi % 2) * 9, n, 1);
  }
  legend(c, ax.x1 + 16, 60, methods);
  return c.image();
}

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  for (const std::string& x : split_items("--sweep", s)) {
    double v = NAN;
    try {
      std::size_t used = 0;
      v = std::stod(x, &used);
      if (used != x.size() || !(v >= 1.0) || !std::isfinite(v)) throw std::invalid_argument(x);
    } catch (const std::exception&) {
      bad_option("--sweep: '" + x + "' is not an L2 bound (a number ≥ 1)");
    }
    // The same bound twice gave two identical rows.
    if (std::find(out.begin(), out.end(), v) != out.end()) bad_option("--sweep: " + x + " is given twice");
    out.push_back(v);
  }
  return out;
}

void run_bench(const Context& ctx, BenchArgs a, const std::string& sweep_text) {
  const auto t0 = Clock::now();
  // remesh's limit (about 600 bytes a sample): 4096 ran out of memory after minutes of work.
  if (a.res < 8 || a.res > 2048) bad_option("--res must be between 8 and 2048, not " + std::to_string(a.res));
  if (a.pack_res < 64 || a.pack_res > 8192) bad_option("--pack-res must be between 64 and 8192");
  // Infinite bounds passed here and failed every atlas row afterwards, quietly.
  if (!(a.max_l2 >= 1.0) || !std::isfinite(a.max_l2))
    bad_option("--max-l2 must be a finite number of at least 1");
  if (!(a.max_linf >= 1.0) || !std::isfinite(a.max_linf))
    bad_option("--max-linf must be a finite number of at least 1");
  if (!sweep_text.empty()) a.sweep = sweep_text == "none" ? std::vector<double>{} : parse_list(sweep_text);
  const std::vector<Method> methods = parse_methods_impl(a.methods);
  if (a.atlas_aspect > 0 && std::none_of(methods.begin(), methods.end(), [](const Method& m) {
        return m.kind == Kind::ExternalAuto || m.kind == Kind::ExternalFile;
      }))
    bad_option("--atlas-aspect goes with an external atlas (--methods external or external:FILE)");
  if (!a.sweep.empty() && a.sweep_max_faces <= 0)
    bad_option("--sweep-max-faces 0 sweeps no mesh; give --sweep none for no sweep");
  {
    // A mistyped --data would otherwise bench the built-in meshes without a word.
    std::error_code ec;
    if (a.data_given && !fs::is_directory(a.data, ec))
      throw isochart::InputError(a.data, "--data: no such directory");
  }
  if (a.meshes.empty()) {
    a.meshes = default_meshes(a.data);
    if (a.meshes.front().rfind("builtin:", 0) == 0)
      ctx.warn(a.data, "no meshes/ with meshes in it: benchmarking the built-in meshes");
  }
  // Rows, tables and plots are keyed by the mesh's file stem.
  for (std::size_t i = 0; i < a.meshes.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (stem(a.meshes[i]) == stem(a.meshes[j]))
        bad_option("meshes " + a.meshes[j] + " and " + a.meshes[i] + " are both named '" + stem(a.meshes[i]) +
                   "' in the tables; give them different file names");
  // Every mesh is read before any work: one unreadable file found hours in threw every finished
  // row away.
  std::vector<isochart::Mesh> meshes;
  for (const auto& m : a.meshes) meshes.push_back(load_any(ctx, m));
  Bench bench(ctx, a, methods);
  // An external:FILE that cannot be read is the user's mistake, like a missing one, not an
  // n/a row per mesh.
  for (const Method& meth : methods)
    if (meth.kind == Kind::ExternalFile) bench.load_external(meth.file);
  {
    std::error_code ec;
    // Only the directory itself is made, like every other output's: a mistyped parent would
    // otherwise grow a tree of directories without a word.
    const fs::path parent = fs::path(a.out).lexically_normal().parent_path();
    if (!parent.empty() && !fs::is_directory(parent, ec))
      throw isochart::InputError(a.out, "cannot write: directory " + parent.string() + " does not exist");
    fs::create_directory(a.out, ec);
    std::error_code kind;
    if (!fs::is_directory(a.out, kind)) {
      if (fs::exists(a.out, kind))
        throw isochart::InputError(
            a.out, "--out takes a directory (for bench.md, bench.csv and the plots); this is a file");
      throw isochart::InputError(
          a.out, "cannot create the output directory" + (ec ? ": " + ec.message() : std::string()));
    }
    const fs::path out(a.out);
    ctx.check_paths(
        {}, {(out / "bench.md").string(), (out / "bench.csv").string(), (out / "sweep.csv").string()});
  }

  int k = 0;
  int n = 0;
  for (const auto& m : a.meshes)
    for (const Method& meth : methods)
      if (meth.kind != Kind::ExternalAuto) {
        ++n;
      } else {
        // Alone, a mesh without baseline atlases still gets its n/a row.
        const int found = static_cast<int>(auto_externals(a.data, stem(m)).size());
        n += methods.size() > 1 ? found : std::max(1, found);
      }
  for (std::size_t i = 0; i < a.meshes.size(); ++i) bench.run_mesh(a.meshes[i], meshes[i], k, n);
  // A table of n/a rows only is a failed run, not a result; the rows say why.
  if (std::all_of(bench.rows().begin(), bench.rows().end(),
                  [](const Row& r) { return r.note.rfind("n/a", 0) == 0; })) {
    std::string why = bench.rows().empty() ? std::string("no rows") : bench.rows().front().note.substr(5);
    throw isochart::InputError(a.out, "no method gave a result on any mesh (" + why + ")");
  }
  if (!a.sweep.empty() && bench.sweep_points().empty())
    ctx.warn(a.out, "no mesh has at most --sweep-max-faces " + std::to_string(a.sweep_max_faces) +
                        " faces: the sweep is empty");

  const std::string md = to_markdown(bench.rows(), bench.sweep_points(), a);
  const fs::path out(a.out);
  isochart::write_file_atomic((out / "bench.csv").string(), to_csv(bench.rows()));
  // Without a sweep there is no sweep.csv; an earlier run's would be taken for this run's.
  const bool swept_any = !a.sweep.empty();
  if (swept_any) {
    isochart::write_file_atomic((out / "sweep.csv").string(), sweep_csv(bench.sweep_points()));
  } else {
    std::error_code ec;
    fs::remove(out / "sweep.csv", ec);
  }
  std::vector<std::string> plots;
  if (!a.no_plots) {
    isochart::write_image((out / "psnr.png").string(), plot_psnr(bench.rows()));
    plots.push_back("psnr.png");
    std::vector<std::string> swept;
    for (const auto& p : bench.sweep_points())
      if (std::find(swept.begin(), swept.end(), p.mesh) == swept.end()) swept.push_back(p.mesh);
    for (const auto& m : swept) {
      const std::string f = "stretch_" + m + ".png";
      isochart::write_image((out / f).string(), plot_sweep(bench.sweep_points(), m));
      plots.push_back(f);
    }
  }
  // Plots of an earlier run into the same directory (another mesh's sweep, or any plot under
  // --no-plots) would be taken for this run's.
  {
    std::error_code ec;
    std::vector<fs::path> stale;
    for (const auto& e : fs::directory_iterator(out, ec)) {
      const std::string name = e.path().filename().string();
      const bool ours =
          name == "psnr.png" || (name.rfind("stretch_", 0) == 0 && e.path().extension() == ".png");
      if (ours && std::find(plots.begin(), plots.end(), name) == plots.end()) stale.push_back(e.path());
    }
    for (const auto& f : stale) fs::remove(f, ec);
  }
  const double total = std::chrono::duration<double>(Clock::now() - t0).count();
  std::ostringstream doc;
  doc << md << "\nTotal " << fmt(total, 1) << " s; reference resolution " << a.res << "×" << a.res
      << ", PSNR from " << a.psnr_samples << " points per surface, packing ratio at " << a.pack_res << "².\n";
  // Rows missing without a word read as if the other tools had not been compared there.
  std::string skipped;
  for (const auto& m : bench.without_baselines()) skipped += (skipped.empty() ? "" : ", ") + m;
  const std::string skipped_note = skipped.empty()
                                       ? ""
                                       : "\nNo `external` rows for " + skipped + ": no baseline atlases in " +
                                             (fs::path(a.data) / "baseline_atlases").string() + ".\n";
  doc << skipped_note;
  for (const auto& p : plots) doc << "\n![" << p << "](" << p << ")\n";
  isochart::write_file_atomic((out / "bench.md").string(), doc.str());

  nlohmann::json j;
  j["rows"] = nlohmann::json::array();
  for (const Row& r : bench.rows()) {
    auto num = [](double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); };
    j["rows"].push_back(
        {{"mesh", r.mesh},
         {"faces", r.faces},
         {"method", r.method},
         {"charts", r.charts},
         {"l2", num(r.l2)},
         {"linf", num(r.linf)},
         {"packing_ratio", num(r.packing)},
         {"resolution", {r.width, r.height}},
         {"defined_samples", r.defined},
         {"unique_samples", r.unique},
         {"target_samples", r.target},
         {"psnr", num(r.psnr)},
         {"seconds", {{"atlas", r.s_atlas}, {"packing", r.s_pack}, {"mcgim", r.s_mcgim}, {"psnr", r.s_psnr}}},
         {"note", r.note}});
  }
  // The sweep was only in sweep.csv and bench.md.
  j["sweep"] = nlohmann::json::array();
  for (const SweepPoint& p : bench.sweep_points())
    j["sweep"].push_back({{"mesh", p.mesh},
                          {"method", p.method},
                          {"bound", p.bound},
                          {"charts", p.charts},
                          {"l2", std::isfinite(p.l2) ? nlohmann::json(p.l2) : nlohmann::json()}});
  j["plots"] = plots;
  j["without_baselines"] = bench.without_baselines();
  j["out"] = a.out;
  j["seconds"] = total;
  j["seed"] = ctx.opts.seed;
  ctx.emit(j, md + skipped_note + "\nWrote " + (out / "bench.md").string() + ", bench.csv" +
                  (swept_any ? ", sweep.csv" : "") +
                  (plots.empty() ? "" : " and " + std::to_string(plots.size()) + " plots") + "\n");
}

}  // namespace

void add_bench(CLI::App& app, Context& ctx, Action& action) {
  auto args = std::make_shared<BenchArgs>();
  auto sweep = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "bench", "Compare atlas methods on meshes: charts, stretch, packing, MCGIM PSNR at matched samples");
  sub->add_option("meshes", args->meshes,
                  "Meshes (files or builtin:NAME); default: every mesh in DATA/meshes, else the built-ins");
  sub->add_option(
         "--methods", args->methods,
         "Comma-separated: isochart, isomap-nocut, lscm, lscm+stretch, external (DATA/baseline_atlases/"
         "MESH_*.obj), external:FILE.obj")
      ->capture_default_str();
  sub->add_option(
         "--res", args->res,
         "Square MCGIM resolution of the first method (8 to 2048); the others get its defined samples (±2%)")
      ->capture_default_str();
  sub->add_option("--out", args->out,
                  "Output directory (bench.md, bench.csv, sweep.csv, PNG plots; an earlier run's plots there "
                  "are removed)")
      ->capture_default_str();
  sub->add_option("--data", args->data, "Shared data directory (meshes/, baseline_atlases/)")
      ->capture_default_str();
  sub->add_option("--max-l2", args->max_l2, "L2 stretch bound of every method")->capture_default_str();
  sub->add_option("--max-linf", args->max_linf, "Linf stretch bound of every method")->capture_default_str();
  sub->add_option("--atlas-aspect", args->atlas_aspect,
                  "Width / height of the texture the external atlases were laid out for (default: "
                  "read from each one's UVs)")
      ->check(number_in(1.0 / 16384, 16384.0));
  sub->add_option("--pack-res", args->pack_res,
                  "Texture size (square, 64 to 8192) the built atlases are packed for, gutters in its "
                  "texels; the packing-ratio "
                  "column, and the layout the geometry images resample, follow from it")
      ->capture_default_str();
  sub->add_option("--psnr-samples", args->psnr_samples, "Points per surface for the PSNR")
      ->check(CLI::Range(1000LL, 20'000'000LL))
      ->capture_default_str();
  sub->add_option("--sweep", *sweep,
                  "L2 bounds of the stretch-vs-charts sweep (default 1.03,1.06,1.1,1.2,1.4; 'none' to skip)");
  sub->add_option("--sweep-max-faces", args->sweep_max_faces, "Sweep only meshes up to this many faces")
      ->check(CLI::Range(0, 100'000'000))
      ->capture_default_str();
  sub->add_flag("--no-plots", args->no_plots, "Do not draw the PNG plots");
  sub->footer(
      "Every atlas is packed by our packer and measured the same way (the packer starts from each chart's "
      "orientation as given, so an atlas read back from a file can pack a few percent differently from the "
      "same charts as built). Per mesh, the first method's MCGIM is "
      "RES×RES; every other method's resolution is chosen so its defined samples match within 2% "
      "(Iso-charts Table II). A failing run is reported as 'n/a: reason' in its row.\n"
      "Examples:\n"
      "  isocharts bench --out bench_out\n"
      "  isocharts bench builtin:torus --methods isochart,lscm --res 128 --out /tmp/b\n"
      "  isocharts bench ../shared/data/meshes/bunny.obj --methods "
      "isochart,external:../shared/data/baseline_atlases/bunny_xatlas.obj");
  sub->callback([&ctx, args, sweep, sub, &action] {
    args->data_given = sub->count("--data") > 0;
    action = [&ctx, args, sweep] { run_bench(ctx, *args, *sweep); };
  });
}

}  // namespace cli
