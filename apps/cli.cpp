#include "cli.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <sstream>

#include "isochart/error.h"
#include "isochart/image.h"
#include "isochart/stretch.h"

namespace cli {

struct Context::ProgressState {
  std::mutex mutex;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_print{};
  bool tty = isatty(fileno(stderr)) != 0;
  bool shown = false;
  int last_stage = -1;
};

struct Context::Warnings {
  std::mutex mutex;
  std::vector<std::string> list;
};

Context::Context()
    : warnings(std::make_shared<Warnings>()), progress_state(std::make_shared<ProgressState>()) {}

void Context::check_paths(const std::vector<std::string>& inputs, std::vector<std::string> outputs) const {
  if (!opts.report.empty()) outputs.push_back(opts.report);
  auto real = [](const std::string& p) { return !p.empty() && p.rfind("builtin:", 0) != 0; };
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const std::string& out = outputs[k];
    if (!real(out)) continue;
    for (const std::string& in : inputs)
      if (real(in) && isochart::same_file(in, out))
        throw isochart::InputError(out, "cannot write: it is an input of this run and would be overwritten");
    for (std::size_t j = 0; j < k; ++j)
      if (real(outputs[j]) && isochart::same_file(outputs[j], out))
        throw isochart::InputError(out, "cannot write: given as two outputs of this run");
    // A missing or read-only directory is found by the writers only after all the work.
    const auto slash = out.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : out.substr(0, slash);
    struct stat st;
    if (::stat(dir.c_str(), &st) != 0)
      throw isochart::InputError(out, "cannot write: directory " + dir + " does not exist");
    if (!S_ISDIR(st.st_mode)) throw isochart::InputError(out, "cannot write: " + dir + " is not a directory");
    if (::access(dir.c_str(), W_OK) != 0)
      throw isochart::InputError(out, "cannot write: " + std::string(std::strerror(errno)));
    // access() says yes to root on a read-only or special file system (/sys, a read-only
    // mount): only creating a file there tells.
    {
      const std::string probe =
          dir + "/.isocharts-probe-" + std::to_string(::getpid()) + "-" + std::to_string(k);
      const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
      if (fd < 0 && errno != EEXIST)
        throw isochart::InputError(out, "cannot write in " + dir + ": " + std::string(std::strerror(errno)));
      if (fd >= 0) {
        ::close(fd);
        ::unlink(probe.c_str());
      }
    }
    // Outputs are written to a temporary file and renamed, never into a device or a pipe
    // (/dev/null, /dev/stdout): refused now rather than after the work.
    // A read-only file is not replaced by the rename (which the directory allows) behind the
    // user's back, as a shell's `>` would not write it either.
    if (::stat(out.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(out.c_str(), W_OK) != 0)
      throw isochart::InputError(
          out, "cannot write: the file is read-only (" + std::string(std::strerror(errno)) + ")");
    if (::stat(out.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
      throw isochart::InputError(out, S_ISDIR(st.st_mode) ? "cannot write: is a directory"
                                                          : "cannot write: not a regular file (outputs are "
                                                            "written whole to a file, then renamed)");
    // Nor is a name the file system cannot hold found before the end.
    const std::string name = slash == std::string::npos ? out : out.substr(slash + 1);
    const long name_max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
    const std::size_t limit = name_max > 0 ? static_cast<std::size_t>(name_max) : 255;
    if (name.size() > limit)
      throw isochart::InputError(out, "cannot write: the file name has " + std::to_string(name.size()) +
                                          " bytes, more than the " + std::to_string(limit) +
                                          " the directory allows");
  }
}

void Context::warn(const std::string& file, const std::string& message) const {
  {
    // Once per run: a file given twice (the input and its --atlas) is loaded, and warned
    // about, twice.
    std::lock_guard<std::mutex> lock(warnings->mutex);
    const std::string line = (file.empty() ? "" : file + ": ") + message;
    if (std::find(warnings->list.begin(), warnings->list.end(), line) != warnings->list.end()) return;
    warnings->list.push_back(line);
  }
  if (opts.quiet) return;
  end_progress();
  std::cerr << "isocharts: warning: " << (file.empty() ? "" : file + ": ") << message << "\n";
}

void Context::info(const std::string& message) const {
  if (opts.verbose > 0 && !opts.quiet) {
    end_progress();
    std::cerr << "isocharts: " << message << "\n";
  }
}

isochart::Progress Context::progress() const {
  if (opts.quiet) return {};
  auto state = progress_state;
  return [state](isochart::Stage stage, double fraction) {
    using clock = std::chrono::steady_clock;
    std::lock_guard<std::mutex> lock(state->mutex);
    const auto now = clock::now();
    if (now - state->start < std::chrono::seconds(1)) return true;
    const int s = static_cast<int>(stage);
    if (state->tty) {
      if (s == state->last_stage && now - state->last_print < std::chrono::milliseconds(100)) return true;
      std::fprintf(stderr, "\r\033[K[%6.1fs] %-15s %3.0f%%",
                   std::chrono::duration<double>(now - state->start).count(), isochart::stage_name(stage),
                   100.0 * fraction);
      std::fflush(stderr);
      state->shown = true;
    } else {
      // Not a terminal: a line when the stage changes, at most one every five seconds (a bench
      // run alternates stages hundreds of times and filled logs with them).
      if (s == state->last_stage ||
          (state->last_print != clock::time_point{} && now - state->last_print < std::chrono::seconds(5)))
        return true;
      std::fprintf(stderr, "[%6.1fs] %s\n", std::chrono::duration<double>(now - state->start).count(),
                   isochart::stage_name(stage));
    }
    state->last_stage = s;
    state->last_print = now;
    return true;
  };
}

void Context::end_progress() const {
  if (!progress_state) return;
  std::lock_guard<std::mutex> lock(progress_state->mutex);
  if (progress_state->shown) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    progress_state->shown = false;
  }
}

void Context::check_image_outputs(const std::vector<std::string>& paths) const {
  for (const std::string& p : paths)
    if (!p.empty()) isochart::check_image_output(p);
}

isochart::LoadResult Context::load(const std::string& path, bool atlas) const {
  isochart::LoadOptions lo;
  lo.repair = !opts.no_repair;
  lo.weld = atlas || opts.weld;
  // Joining an atlas's corners at one position closes its UV seams, but for our own atlas of
  // a non-manifold or non-orientable input it would also undo the splits its repair made, then
  // warn about repairing them again (or refuse with --no-repair) for a file that reads as a
  // clean surface as it is.
  lo.weld_only_if_surface = atlas && !opts.weld;
  isochart::LoadResult r = isochart::load_mesh(path, lo);
  for (const auto& w : r.report.warnings) warn(path, w);
  return r;
}

void Context::emit(const nlohmann::json& given, const std::string& text) const {
  end_progress();
  nlohmann::json result = given;
  if (result.is_object() && !result.contains("warnings")) {
    std::lock_guard<std::mutex> lock(warnings->mutex);
    result["warnings"] = warnings->list;
  }
  if (!opts.report.empty()) isochart::write_file_atomic(opts.report, result.dump(2) + "\n");
  if (opts.json)
    std::cout << result.dump(2) << "\n";
  else
    std::cout << text;
  errno = 0;
  std::cout.flush();
  // The result is the point of the run: lost on the way out (a full disk, a closed terminal),
  // the run failed, and says so instead of exiting 0.
  if (!std::cout) {
    const int err = errno;
    std::cout.clear();
    throw isochart::Error(std::string("standard output: cannot write") +
                          (err ? std::string(": ") + std::strerror(err) : ""));
  }
}

void bad_option(const std::string& message) {
  throw isochart::InputError("", message);
}

isochart::MeshFormat output_mesh_format(const std::string& path,
                                        const std::vector<isochart::MeshFormat>& allowed,
                                        const std::string& writes) {
  const std::string ext = std::filesystem::path(path).extension().string();  // ".obj" alone has none
  if (path == "-") throw isochart::InputError(path, "standard output is not supported; give a file name");
  std::error_code ec;  // a name too long to look up is refused by check_paths, with a message
  if (std::filesystem::is_directory(path, ec))
    throw isochart::InputError(path, "cannot write: is a directory");
  if (ext.empty())
    throw isochart::InputError(path, "has no file extension (this command writes " + writes + ")");
  try {
    const isochart::MeshFormat f = isochart::format_from_path(path);
    if (std::find(allowed.begin(), allowed.end(), f) != allowed.end()) return f;
  } catch (const isochart::InputError&) {
  }
  throw isochart::InputError(path, "cannot write '" + ext + "' files (this command writes " + writes + ")");
}

namespace {

// "16384.000000" -> "16384", "0.000061" stays: CLI11 prints range ends with std::to_string.
std::string trim_number(std::string s) {
  if (s.find('.') == std::string::npos) return s;
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

const CLI::Option* find_option(const CLI::App& app, const std::string& name) {
  if (const CLI::Option* o = app.get_option_no_throw(name)) return o;
  for (const CLI::App* sub : app.get_subcommands())
    if (const CLI::Option* o = sub->get_option_no_throw(name)) return o;
  return nullptr;
}

// What an option takes, from the type CLI11 recorded for it ("INT", "UINT", "FLOAT", ...).
std::string expected_kind(const CLI::Option* o) {
  const std::string type = o ? o->get_type_name() : std::string();
  if (type.find("UINT") != std::string::npos) return "an integer >= 0";
  if (type.find("INT") != std::string::npos) return "an integer";
  if (type.find("FLOAT") != std::string::npos || type.find("NUMBER") != std::string::npos) return "a number";
  return "";
}

}  // namespace

std::string parse_error_message(const CLI::App& app, const CLI::ParseError& e) {
  const std::string msg = e.what();
  // "--atlas-size: At Most 1 required but received 2" (an option given twice).
  const auto most = msg.find(": At Most 1 required but received ");
  if (most != std::string::npos)
    return msg.substr(0, most) + ": given " + msg.substr(most + 34) + " times; give it once";
  // "Could not convert: --width = abc" (a value of the wrong type, or an integer too large).
  const std::string convert = "Could not convert: ";
  if (msg.rfind(convert, 0) == 0) {
    const std::string rest = msg.substr(convert.size());
    const auto eq = rest.find(" = ");
    if (eq == std::string::npos) return msg;
    const std::string name = rest.substr(0, eq), value = rest.substr(eq + 3);
    const std::string kind = expected_kind(find_option(app, name));
    if (kind.empty()) return msg;
    const bool integer = kind != "a number";
    const std::string digits = value.size() > 1 && value[0] == '-' ? value.substr(1) : value;
    if (integer && !digits.empty() && digits.find_first_not_of("0123456789") == std::string::npos)
      return name + ": " + value + " is out of range for an integer";
    return name + ": expected " + kind + ", got '" + value + "'";
  }
  // "--res: Value 12x not in range 2 to 2048" (CLI::Range, which also refuses what it cannot read).
  const auto colon = msg.find(": Value ");
  const auto range = msg.find(" not in range ");
  const auto to = msg.rfind(" to ");
  if (colon != std::string::npos && range != std::string::npos && to != std::string::npos && colon < range &&
      range < to) {
    const std::string name = msg.substr(0, colon);
    const std::string value = msg.substr(colon + 8, range - colon - 8);
    const std::string lo = trim_number(msg.substr(range + 14, to - range - 14));
    const std::string hi = trim_number(msg.substr(to + 4));
    std::string kind = expected_kind(find_option(app, name));
    if (kind.empty() || kind == "an integer >= 0") kind = "an integer";
    if (lo.find('.') != std::string::npos || hi.find('.') != std::string::npos) kind = "a number";
    return name + ": expected " + kind + " from " + lo + " to " + hi + ", got '" + value + "'";
  }
  return msg;
}

std::array<int, 2> layout_size(int longer, double aspect) {
  const int shorter = std::max(16, static_cast<int>(std::lround(longer / std::max(aspect, 1 / aspect))));
  return aspect >= 1 ? std::array<int, 2>{longer, shorter} : std::array<int, 2>{shorter, longer};
}

std::vector<std::string> split_items(const std::string& option, const std::string& text) {
  std::vector<std::string> items;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    items.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (items.back().empty()) bad_option(option + ": '" + text + "' has an empty item");
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return items;
}

std::vector<int> parse_levels(const std::vector<std::string>& given, int lo, int hi) {
  std::vector<int> levels;
  for (const std::string& text : given)
    for (const std::string& item : split_items("--levels", text)) {
      const bool digits = item.size() <= 9 && item.find_first_not_of("0123456789") == std::string::npos;
      const int side = digits ? std::stoi(item) : -1;
      if (side < lo || side > hi)
        bad_option("--levels: expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi) +
                   ", got '" + item + "'");
      if (std::find(levels.begin(), levels.end(), side) != levels.end())
        bad_option("--levels: " + item + " is given twice");
      levels.push_back(side);
    }
  return levels;
}

void warn_uvs_outside(const Context& ctx, const std::string& file, const isochart::AtlasQuality& q,
                      const std::string& consequence) {
  const double tol = 1e-9;
  if (q.uv_min.x >= -tol && q.uv_min.y >= -tol && q.uv_max.x <= 1 + tol && q.uv_max.y <= 1 + tol) return;
  std::ostringstream w;
  w << "texture coordinates reach outside [0, 1] (" << q.uv_min.x << ", " << q.uv_min.y << ") to ("
    << q.uv_max.x << ", " << q.uv_max.y << "); " << consequence;
  ctx.warn(file, w.str());
}

void warn_sparse_chart(const Context& ctx, const std::string& file, const isochart::ChartDensity& d,
                       const std::string& consequence) {
  // Real atlases keep every chart above half its share (signal-specialized ones included); a
  // hundredth is a chart shrunk by mistake, which passed every other check.
  if (d.first_face < 0 || d.density >= 0.01) return;
  std::ostringstream w;
  w << "the chart of face " << d.first_face << " (" << d.faces << (d.faces == 1 ? " face" : " faces")
    << ") gets " << std::setprecision(2) << d.density << " of the texture its surface area would get; "
    << consequence;
  ctx.warn(file, w.str());
}

namespace {

// "a square texture", "a texture 3.89 times as wide as high".
std::string describe_texture_aspect(double aspect) {
  if (aspect == 1.0) return "a square texture";
  const double r = aspect > 1 ? aspect : 1 / aspect;
  std::ostringstream w;
  w << "a texture ";
  if (r >= 100)
    w << std::llround(r);  // not 1.02e+03
  else
    w << std::setprecision(3) << r;
  w << (aspect > 1 ? " times as wide as high" : " times as high as wide");
  return w.str();
}

}  // namespace

double read_texture_aspect(const Context& ctx, const std::string& file, const isochart::Mesh& atlas,
                           double assumed, const std::string& consequence) {
  const double aspect = isochart::detect_texture_aspect(atlas);
  if (std::abs(std::log(aspect / assumed)) > std::log(1.1))
    ctx.warn(file, "the texture coordinates look laid out for " + describe_texture_aspect(aspect) + "; " +
                       consequence);
  return aspect;
}

void check_atlas_matches(const isochart::Mesh& input, const isochart::Mesh& atlas, const std::string& file) {
  const isochart::BoundingBox bi = isochart::bounding_box(input), ba = isochart::bounding_box(atlas);
  const double diag = bi.diagonal();
  const double off = std::max(isochart::norm(ba.min - bi.min), isochart::norm(ba.max - bi.max));
  const double ai = isochart::surface_area(input), aa = isochart::surface_area(atlas);
  if (!(off <= 1e-3 * diag) || !(std::abs(aa - ai) <= 0.01 * ai)) {
    std::ostringstream msg;
    msg << "the atlas is not of the input mesh (bounding boxes " << off / diag * 100
        << " % of the diagonal apart, areas " << aa << " and " << ai << ")";
    throw isochart::InputError(file, msg.str());
  }
}

isochart::Image read_mesh_texture(const isochart::MeshTexture& t, const std::string& beside,
                                  const std::string& mesh) {
  if (!t.file.empty()) return isochart::read_image(t.file);
  if (t.bytes.empty()) return {};
  const std::string tmp = isochart::temporary_path(beside, t.extension);
  isochart::track_temporary_file(tmp);
  isochart::Image image;
  try {
    std::ofstream(tmp, std::ios::binary).write(t.bytes.data(), static_cast<std::streamsize>(t.bytes.size()));
    image = isochart::read_image(tmp);
  } catch (const isochart::InputError& e) {
    // The temporary file's name means nothing to the user: the image is the mesh file's.
    isochart::remove_temporary_file(tmp);
    throw isochart::InputError(mesh, std::string("its embedded texture image: ") + e.what());
  } catch (...) {
    isochart::remove_temporary_file(tmp);
    throw;
  }
  isochart::remove_temporary_file(tmp);
  return image;
}

void check_material_coordinates(const std::string& file, const isochart::Mesh& moved) {
  for (const isochart::Vec2d& uv : moved.uvs)
    if (!isochart::is_finite(uv))
      throw isochart::InputError(file,
                                 "its material's texture map (map_Kd -s/-o or KHR_texture_transform) moves "
                                 "texture coordinates beyond any number");
}

MaterialImages read_material_images(const std::string& file, const isochart::Mesh& mesh,
                                    const std::string& beside, bool lenient) {
  const std::vector<isochart::MeshTexture> textures = isochart::find_material_textures(file, mesh);
  MaterialImages c;
  const int nf = mesh.num_faces();
  const int nt = static_cast<int>(textures.size());
  const auto known = [&](int m) { return m >= 0 && m < nt; };
  std::vector<int> source_of(textures.size(), -1);
  int plain = -1;  // faces of no material, or of one no file defines: white, as viewers show them
  c.face_source.resize(nf);
  for (int f = 0; f < nf; ++f) {
    const int m = f < static_cast<int>(mesh.face_materials.size()) ? mesh.face_materials[f] : -1;
    int& slot = known(m) ? source_of[m] : plain;
    if (slot < 0) {
      slot = static_cast<int>(c.sources.size());
      c.sources.emplace_back();
      if (known(m)) {
        const isochart::MeshTexture& t = textures[m];
        const std::string label = m < static_cast<int>(mesh.material_names.size())
                                      ? "material " + mesh.material_names[m]
                                      : "material " + std::to_string(m);
        c.sources.back().wrap = t.wrap;
        c.sources.back().colour = t.colour;
        try {
          if (!t.problem.empty()) throw isochart::InputError(file, t.problem + " (" + label + ")");
          c.sources.back().image = read_mesh_texture(t, beside, file);
          if (!t.file.empty()) c.files.push_back(t.file);
        } catch (const isochart::InputError& e) {
          if (!lenient) throw;
          const std::string where = e.file().empty() || e.file() == file ? "" : e.file() + ": ";
          c.skipped.push_back(label + ": " + where + e.what());
        }
      }
    }
    if (c.sources[slot].image.empty()) ++c.untextured_faces;
    c.face_source[f] = slot;
  }
  c.source = mesh;
  c.source.uvs.clear();
  c.source.uvs.reserve(3 * static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    const int m = f < static_cast<int>(mesh.face_materials.size()) ? mesh.face_materials[f] : -1;
    for (int k = 0; k < 3; ++k) {
      const isochart::Vec2d uv = mesh.uvs[mesh.face_uvs[f][k]];
      c.source.uvs.push_back(known(m) ? textures[m].uv_transform.apply(uv) : uv);
      c.source.face_uvs[f][k] = 3 * f + k;
    }
  }
  check_material_coordinates(file, c.source);
  return c;
}

isochart::Mesh as_material_reads(const isochart::MeshTexture& t, const isochart::Mesh& mesh) {
  isochart::Mesh moved = mesh;
  if (t.uv_transform.identity()) return moved;
  for (isochart::Vec2d& uv : moved.uvs) uv = t.uv_transform.apply(uv);
  return moved;
}

}  // namespace cli
