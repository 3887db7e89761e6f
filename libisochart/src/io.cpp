// Mesh I/O entry points: format dispatch, whole-file reading, atomic writing, and the text
// scanning helpers the OBJ/OFF/PLY readers share.
#include "isochart/io.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <set>

#include "io_internal.h"
#include "isochart/builtin.h"
#include "isochart/error.h"

namespace isochart {

namespace fs = std::filesystem;

namespace io_detail {

std::string quoted(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  static const char* hex = "0123456789abcdef";
  for (std::size_t i = 0; i < token.size() && i < kMax; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (token.size() > kMax) out += "...";
  return out + "'";
}

void fail_at_line(const std::string& path, long long line, const std::string& message) {
  throw InputError(path, "line " + std::to_string(line) + ": " + message);
}

void check_face_limit(const std::string& path, long long faces, const LoadOptions& options) {
  if (faces > options.max_faces)
    throw InputError(path, "has " + std::to_string(faces) + " faces, more than the limit of " +
                               std::to_string(options.max_faces));
}

LineScanner::LineScanner(const std::string& path, std::string_view data) : path_(path), data_(data) {
  if (data_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;
  find_next_lf();
}

void LineScanner::find_next_lf() {
  const void* nl = std::memchr(data_.data() + pos_, '\n', data_.size() - pos_);
  next_lf_ = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - data_.data()) : data_.size();
}

bool LineScanner::next(std::string_view& line) {
  if (pos_ >= data_.size()) return false;
  const char* begin = data_.data() + pos_;
  // The next LF is remembered, so that a file of lone CRs is not searched to its end per line.
  if (next_lf_ < pos_) find_next_lf();
  std::size_t len = next_lf_ - pos_;
  std::size_t skip = next_lf_ < data_.size() ? 1 : 0;
  if (const void* cr = std::memchr(begin, '\r', len)) {
    const std::size_t at = static_cast<std::size_t>(static_cast<const char*>(cr) - begin);
    skip = at + 1 == len && skip ? 2 : 1;  // CR LF, or a lone CR ending the line
    len = at;
  }
  pos_ += len + skip;
  ++line_;
  line = std::string_view(begin, len);
  if (std::memchr(line.data(), '\0', line.size()))
    fail_at_line(path_, line_, "unexpected binary data (NUL byte); this is not a text mesh file");
  return true;
}

bool parse_double(std::string_view token, double& value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto r = std::from_chars(token.data(), end, value);
  if (r.ec == std::errc::result_out_of_range && r.ptr == end) {
    // A number beyond the double range is still a number: ±inf (which callers refuse as out
    // of range), or towards 0 when it underflows, as strtod reads it.
    value = std::strtod(std::string(token).c_str(), nullptr);
    return true;
  }
  return r.ec == std::errc() && r.ptr == end;
}

std::string not_finite(std::string_view token) {
  std::string lower(token);
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  const bool named = lower.find("inf") != std::string::npos || lower.find("nan") != std::string::npos;
  return quoted(token) + (named ? " is not finite" : " is out of range (beyond 1.8e308)");
}

bool parse_int(std::string_view token, long long& value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto r = std::from_chars(token.data(), end, value);
  return r.ec == std::errc() && r.ptr == end;
}

bool is_integer_text(std::string_view token) {
  if (!token.empty() && (token[0] == '-' || token[0] == '+')) token.remove_prefix(1);
  return !token.empty() &&
         std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; });
}

double expect_number(std::string_view& rest, const std::string& path, long long line, const char* what,
                     const char* name) {
  std::string_view tok;
  if (!next_token(rest, tok)) fail_at_line(path, line, std::string("expected ") + what);
  double v = 0;
  if (!parse_double(tok, v)) fail_at_line(path, line, quoted(tok) + " is not a number");
  if (!std::isfinite(v)) fail_at_line(path, line, std::string(name) + " " + not_finite(tok));
  return v;
}

bool float_positions_suffice(const std::vector<Vec3d>& positions, const Vec3d& origin, double diagonal) {
  const double tolerance = 1e-7 * diagonal;
  for (const Vec3d& p : positions)
    for (int i = 0; i < 3; ++i) {
      const double x = p[i] - origin[i];
      if (std::abs(static_cast<double>(static_cast<float>(x)) - x) > tolerance) return false;
    }
  return true;
}

void append_number(std::string& out, double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

void append_number(std::string& out, float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

void append_number(std::string& out, long long v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

std::string read_file(const std::string& path) {
  // O_NONBLOCK: opening a FIFO would otherwise wait for a writer before it could be refused.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw InputError(path, std::string("cannot open file: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    throw InputError(path, std::string("cannot read file: ") + std::strerror(err));
  }
  if (S_ISDIR(st.st_mode)) {
    ::close(fd);
    throw InputError(path, "is a directory, not a mesh file");
  }
  note_input_file(st);
  // A device or pipe (/dev/zero, a FIFO) may never end: it would be read until memory ran out.
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError(path, "is not a regular file (a device, pipe or socket)");
  }
  if (static_cast<unsigned long long>(st.st_size) > kMaxInputFileBytes) {
    ::close(fd);
    throw InputError(path, "is " + std::to_string(st.st_size >> 20) + " MiB, larger than the " +
                               std::to_string(kMaxInputFileBytes >> 20) + " MiB an input may be");
  }
  std::string data;
  data.reserve(static_cast<std::size_t>(st.st_size));
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw InputError(path, std::string("cannot read file: ") + std::strerror(err));
    }
    data.append(buf, static_cast<std::size_t>(n));
    if (data.size() > kMaxInputFileBytes) {  // grew while being read
      ::close(fd);
      throw InputError(path, "grew past the " + std::to_string(kMaxInputFileBytes >> 20) +
                                 " MiB an input may be while it was read");
    }
  }
  ::close(fd);
  return data;
}

}  // namespace io_detail

using namespace io_detail;

MeshFormat format_from_path(const std::string& path) {
  if (path.rfind("builtin:", 0) == 0) return MeshFormat::Builtin;
  if (path.empty()) throw InputError("", "an empty file name was given for a mesh");
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) {
    // Say what the name is when it is something else than a file without an extension.
    struct stat st {};
    if (path == "-") throw InputError(path, "standard input and output are not supported; give a file name");
    if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
      throw InputError(path, "is a directory, not a mesh file");
    throw InputError(path, "has no file extension (expected .obj, .off, .ply, .gltf or .glb)");
  }
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == "obj") return MeshFormat::Obj;
  if (ext == "off") return MeshFormat::Off;
  if (ext == "ply") return MeshFormat::Ply;
  if (ext == "gltf") return MeshFormat::Gltf;
  if (ext == "glb") return MeshFormat::Glb;
  throw InputError(path, "unknown mesh format " + io_detail::quoted("." + ext) +
                             " (expected .obj, .off, .ply, .gltf or .glb)");
}

RawMesh read_raw_mesh(const std::string& path, const LoadOptions& options) {
  const MeshFormat fmt = format_from_path(path);
  if (fmt == MeshFormat::Builtin) return to_raw_mesh(make_builtin(path.substr(8)), path);
  const std::string data = read_file(path);
  if (data.empty()) throw InputError(path, "file is empty");
  switch (fmt) {
    case MeshFormat::Obj:
      return read_obj(path, data, options);
    case MeshFormat::Off:
      return read_off(path, data, options);
    case MeshFormat::Ply:
      return read_ply(path, data, options);
    case MeshFormat::Gltf:
      return read_gltf(path, data, false, options);
    case MeshFormat::Glb:
      return read_gltf(path, data, true, options);
    case MeshFormat::Builtin:
      break;
  }
  throw Error("unhandled mesh format");
}

MeshTexture find_mesh_texture(const std::string& path) {
  const MeshFormat fmt = format_from_path(path);
  if (fmt != MeshFormat::Obj && fmt != MeshFormat::Gltf && fmt != MeshFormat::Glb) return {};
  const std::string data = read_file(path);
  return fmt == MeshFormat::Obj ? obj_texture(path, data) : gltf_texture(path, data, fmt == MeshFormat::Glb);
}

std::vector<MeshTexture> find_material_textures(const std::string& path, const Mesh& mesh) {
  if (mesh.face_materials.empty()) return {};
  const MeshFormat fmt = format_from_path(path);
  if (fmt != MeshFormat::Obj && fmt != MeshFormat::Gltf && fmt != MeshFormat::Glb) return {};
  const std::string data = read_file(path);
  return fmt == MeshFormat::Obj ? obj_textures(path, data, mesh.material_names)
                                : gltf_textures(path, data, fmt == MeshFormat::Glb);
}

namespace {

// Used vertices at the bit-identical position of an earlier used vertex (−0 equal to +0).
// A triangle with two corners on one point has no area and validation drops it, so it uses
// no vertex: its corners are not a cut in the surface.
long long count_coincident(const RawMesh& raw) {
  const long long nv = static_cast<long long>(raw.positions.size());
  std::vector<char> used(raw.positions.size(), 0);
  const auto in_range = [&](int v) { return v >= 0 && v < nv; };
  for (const auto& poly : raw.polygons) {
    if (poly.size() == 3 && std::all_of(poly.begin(), poly.end(), in_range)) {
      const Vec3d &a = raw.positions[poly[0]], &b = raw.positions[poly[1]], &c = raw.positions[poly[2]];
      if (a == b || b == c || a == c) continue;
    }
    for (int v : poly)
      if (in_range(v)) used[v] = 1;
  }
  std::vector<std::array<double, 3>> p;
  p.reserve(raw.positions.size());
  for (long long v = 0; v < nv; ++v)
    if (used[v]) {
      std::array<double, 3> x;
      for (int i = 0; i < 3; ++i) {
        // NaN would break the sort's ordering; validation rejects the file anyway.
        if (!std::isfinite(raw.positions[v][i])) return 0;
        x[i] = raw.positions[v][i] == 0 ? 0.0 : raw.positions[v][i];
      }
      p.push_back(x);
    }
  std::sort(p.begin(), p.end());
  long long n = 0;
  for (std::size_t i = 1; i < p.size(); ++i) n += p[i] == p[i - 1] ? 1 : 0;
  return n;
}

// Repairs that only joining vertices at one position can call for.
bool needs_surface_repair(const ValidationReport& r) {
  return r.nonmanifold_edges > 0 || r.nonmanifold_vertices > 0 || r.cut_edges > 0;
}

// Whether a repairing validation changed anything, i.e. whether the same input would be
// refused without repair.
bool repaired_anything(const ValidationReport& r) {
  return needs_surface_repair(r) || r.polygons > 0 || r.degenerate_faces > 0 || r.duplicate_faces > 0 ||
         r.double_sided_faces > 0 || r.unreferenced_vertices > 0 || r.reoriented_faces > 0;
}

}  // namespace

LoadResult load_mesh(const std::string& path, const LoadOptions& options) {
  RawMesh raw = read_raw_mesh(path, options);
  const MeshFormat fmt = format_from_path(path);
  const bool gltf = fmt == MeshFormat::Gltf || fmt == MeshFormat::Glb;
  // The limit is on triangles, so polygons count with their triangulation.
  long long triangles = 0;
  for (const auto& poly : raw.polygons)
    triangles += std::max<long long>(1, static_cast<long long>(poly.size()) - 2);
  check_face_limit(path, triangles, options);
  LoadResult r;
  bool welded = options.weld || gltf;
  bool validated = false;  // r holds the repairing validation of `raw`
  if (options.weld && options.weld_only_if_surface && !gltf) {
    RawMesh joined = raw;
    io_detail::weld_equal_positions(joined);
    r.mesh = validate_mesh(joined, true, r.report);
    validated = true;
    if (needs_surface_repair(r.report)) {
      LoadResult as_is;
      as_is.mesh = validate_mesh(raw, true, as_is.report);
      if (!needs_surface_repair(as_is.report)) {
        r = std::move(as_is);
        welded = false;
      }
    }
    if (welded) raw = std::move(joined);
  } else if (welded) {
    io_detail::weld_equal_positions(raw);
  }
  // Unjoined corners at one position are a cut, unless they are what keeps the surface one.
  const bool kept_split = options.weld && !welded;
  long long coincident = welded ? 0 : count_coincident(raw);
  if (coincident > 0 && !kept_split) {
    // The two sides of a double-sided sheet, as we write them, lie on each other by design.
    RawMesh joined = raw, split;
    io_detail::weld_equal_positions(joined);
    if (split_double_sided(joined, split) > 0) coincident = count_coincident(split);
  }
  // Without repair, validation refuses the file, naming its first problem; a file that
  // needed nothing validates to the mesh already in hand.
  if (!validated || (!options.repair && repaired_anything(r.report))) {
    r.report = ValidationReport{};
    r.mesh = validate_mesh(raw, options.repair, r.report);
  }
  r.report.coincident_vertices = coincident;
  if (coincident > 0 && !kept_split)
    r.report.warnings.push_back(std::to_string(coincident) +
                                (coincident == 1 ? " vertex lies" : " vertices lie") +
                                " at the position of another vertex without being joined to it, so the "
                                "surface is cut there (--weld joins them)");
  return r;
}

std::string material_path(const std::string& obj_path) {
  const auto slash = obj_path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "" : obj_path.substr(0, slash + 1);
  std::string stem = slash == std::string::npos ? obj_path : obj_path.substr(slash + 1);
  stem = stem.substr(0, stem.find_last_of('.'));
  // `mtllib` takes a list of names separated by spaces: a name with spaces in it would be
  // read as several missing files by other tools, so the MTL's has underscores instead.
  for (char& c : stem)
    if (c == ' ' || c == '\t') c = '_';
  return dir + stem + ".mtl";
}

void save_mesh(const Mesh& mesh, const std::string& path, const SaveOptions& options) {
  const MeshFormat fmt = format_from_path(path);
  switch (fmt) {
    case MeshFormat::Obj: {
      if (options.texture.empty()) {
        write_file_atomic(path, obj_text(mesh, "", options.write_groups));
        return;
      }
      // The MTL goes first so that a finished OBJ never points at a missing MTL, and is
      // removed again if the OBJ fails.
      const std::string mtl_path = material_path(path);
      write_file_atomic(mtl_path, mtl_text(options.texture, options.texture_transparent));
      try {
        write_file_atomic(path, obj_text(mesh, fs::path(mtl_path).filename().string(), options.write_groups));
      } catch (...) {
        if (!OutputBatch::open()) std::remove(mtl_path.c_str());  // else the batch removes it
        throw;
      }
      return;
    }
    case MeshFormat::Ply:
      write_file_atomic(path, ply_bytes(mesh, options.binary_ply));
      return;
    case MeshFormat::Glb:
      write_file_atomic(path, glb_bytes(mesh, options.texture, options.texture_transparent));
      return;
    case MeshFormat::Off:
    case MeshFormat::Gltf:
    case MeshFormat::Builtin:
      break;
  }
  throw InputError(path, "cannot write this format (expected .obj, .ply or .glb)");
}

namespace {
// The file `path`'s symbolic links lead to (`path` itself when it is none).
std::string follow_links(const std::string& path) {
  std::string p = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st;
    if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) break;
    std::string to(4096, '\0');
    const ssize_t n = ::readlink(p.c_str(), &to[0], to.size());
    if (n <= 0 || static_cast<std::size_t>(n) >= to.size()) break;
    to.resize(static_cast<std::size_t>(n));
    const auto slash = p.find_last_of('/');
    p = to[0] == '/' || slash == std::string::npos ? to : p.substr(0, slash + 1) + to;
  }
  return p;
}
}  // namespace

namespace {
std::mutex batch_mutex;
OutputBatch* batch = nullptr;
// The files read while the batch is open (device, inode): an output must not replace one.
std::set<std::pair<dev_t, ino_t>> batch_inputs;
}  // namespace

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  const bool ea = ::stat(a.c_str(), &sa) == 0, eb = ::stat(b.c_str(), &sb) == 0;
  if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (ea != eb) return false;
  // Neither exists: compare the resolved directories and the names.
  auto resolved = [](const std::string& p) {
    const auto slash = p.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : p.substr(0, slash);
    const std::string name = slash == std::string::npos ? p : p.substr(slash + 1);
    char buf[PATH_MAX];
    return ::realpath(dir.c_str(), buf) ? std::string(buf) + "/" + name : p;
  };
  return resolved(a) == resolved(b);
}

namespace io_detail {
void note_input_file(const struct stat& st) {
  if (!S_ISREG(st.st_mode)) return;
  std::lock_guard<std::mutex> lock(batch_mutex);
  if (batch) batch_inputs.insert({st.st_dev, st.st_ino});
}
}  // namespace io_detail

void note_input_file(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) io_detail::note_input_file(st);
}

std::string output_target(const std::string& path) {
  // An output path that is a symbolic link is written through: the rename replaces the file the
  // link points at, and the link stays (renaming over the link itself would replace it).
  const std::string p = follow_links(path);
  // Renaming over a device or a directory would replace it (as root, /dev/full became a file).
  struct stat st;
  if (::stat(p.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw InputError(
        path, S_ISDIR(st.st_mode) ? "cannot write: is a directory" : "cannot write: not a regular file");
  if (::stat(p.c_str(), &st) == 0) {
    // Replacing a file this run read would destroy the input (`atlas a.obj -o a.obj`, a
    // report over its mesh); refused before anything is written.
    std::lock_guard<std::mutex> lock(batch_mutex);
    if (batch_inputs.count({st.st_dev, st.st_ino}))
      throw InputError(path, "cannot write: it is an input of this run and would be overwritten");
  }
  return p;
}

namespace {
// Fixed storage, written before a slot is marked tracked, so that the signal handler reads only
// lock-free atomics and plain characters and calls only unlink (async-signal-safe).
constexpr int kTrackedFiles = 256;
std::atomic<int> tracked_state[kTrackedFiles];  // 0 free, 1 being filled, 2 tracked
char tracked_path[kTrackedFiles][PATH_MAX];

extern "C" void remove_tracked_and_reraise(int sig) {
  for (int i = 0; i < kTrackedFiles; ++i)
    if (tracked_state[i].load(std::memory_order_acquire) == 2) ::unlink(tracked_path[i]);
  ::signal(sig, SIG_DFL);
  ::raise(sig);  // delivered when the handler returns: the process ends as killed by `sig`
}
}  // namespace

void track_temporary_file(const std::string& path) {
  if (path.size() >= PATH_MAX) return;
  for (int i = 0; i < kTrackedFiles; ++i) {
    int free_slot = 0;
    if (tracked_state[i].compare_exchange_strong(free_slot, 1)) {
      std::memcpy(tracked_path[i], path.c_str(), path.size() + 1);
      tracked_state[i].store(2, std::memory_order_release);
      return;
    }
  }
}

void untrack_temporary_file(const std::string& path) {
  for (int i = 0; i < kTrackedFiles; ++i)
    if (tracked_state[i].load(std::memory_order_acquire) == 2 && path == tracked_path[i]) {
      tracked_state[i].store(0, std::memory_order_release);
      return;
    }
}

void remove_temporary_file(const std::string& path) {
  std::remove(path.c_str());
  untrack_temporary_file(path);
}

void remove_temporary_files_on_interrupt() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old_action {};
    if (::sigaction(sig, nullptr, &old_action) != 0 || old_action.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = remove_tracked_and_reraise;
    sigemptyset(&action.sa_mask);
    ::sigaction(sig, &action, nullptr);
  }
}

std::string temporary_path(const std::string& target, const std::string& ext) {
  // pid + counter makes the name unique across processes and threads writing beside each
  // other; the same directory makes the final rename atomic.
  static std::atomic<unsigned> counter{0};
  const fs::path t(target);
  std::string base = ext.empty() ? t.filename().string() : "." + t.stem().string();
  const std::string tag = ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  // A file name has at most 255 bytes: an output named with 240 of them was refused ("File name
  // too long") after the whole run, for its temporary file's name alone.
  constexpr std::size_t kNameMax = 255;
  if (base.size() + tag.size() + ext.size() > kNameMax)
    base.resize(kNameMax > tag.size() + ext.size() ? kNameMax - tag.size() - ext.size() : 0);
  return (t.parent_path() / (base + tag + ext)).string();
}

namespace {
// A file replaced by renaming a new one over it would take the new file's mode (0644 where
// it was 0444 or 0600): the replacement gets the old file's permission bits.
void keep_mode(const std::string& tmp, const std::string& target) {
  struct stat st;
  if (::stat(target.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::chmod(tmp.c_str(), st.st_mode & 07777);
}
}  // namespace

void write_file_atomic(const std::string& path, const std::string& data) {
  const std::string target = output_target(path);
  const std::string tmp = temporary_path(target);
  track_temporary_file(tmp);
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    const int err = errno;
    untrack_temporary_file(tmp);
    throw InputError(path, std::string("cannot write: ") + std::strerror(err));
  }
  bool ok = data.empty() || std::fwrite(data.data(), 1, data.size(), f) == data.size();
  int err = ok ? 0 : errno;
  if (std::fclose(f) != 0 && ok) {
    ok = false;
    err = errno;
  }
  if (ok && OutputBatch::stage(tmp, target)) return;
  if (ok) keep_mode(tmp, target);
  if (ok && std::rename(tmp.c_str(), target.c_str()) != 0) {
    ok = false;
    err = errno;
  }
  if (ok) untrack_temporary_file(tmp);
  if (!ok) {
    remove_temporary_file(tmp);
    // The file could be created, so the path was fine: the system failed (a full disk, an I/O
    // error), as when an image write fails: exit 1, not the bad-input 2.
    throw Error(path + ": cannot write: " + std::strerror(err));
  }
}

OutputBatch::OutputBatch() {
  std::lock_guard<std::mutex> lock(batch_mutex);
  if (batch) throw Error("OutputBatch: a batch is already open");
  batch = this;
}

OutputBatch::~OutputBatch() {
  std::lock_guard<std::mutex> lock(batch_mutex);
  for (const auto& [tmp, target] : staged_) remove_temporary_file(tmp);
  batch = nullptr;
  batch_inputs.clear();
}

bool OutputBatch::stage(const std::string& tmp, const std::string& target) {
  std::lock_guard<std::mutex> lock(batch_mutex);
  if (!batch) return false;
  // Two outputs of one run on one path (`-o a.obj -o a.obj`, --texture-out and --imt-out
  // alike): the first would be lost, so the run is refused.
  for (auto& [t, g] : batch->staged_)
    if (g == target || same_file(g, target)) {
      remove_temporary_file(tmp);
      throw InputError(target, "cannot write: given as two outputs of this run");
    }
  batch->staged_.emplace_back(tmp, target);
  return true;
}

bool OutputBatch::open() {
  std::lock_guard<std::mutex> lock(batch_mutex);
  return batch != nullptr;
}

std::string OutputBatch::current_path(const std::string& path) {
  // A lookup for reading: no writability check here.
  const std::string target = follow_links(path);
  std::lock_guard<std::mutex> lock(batch_mutex);
  if (batch)
    for (const auto& [tmp, t] : batch->staged_)
      if (t == target) return tmp;
  return path;
}

void OutputBatch::commit() {
  std::lock_guard<std::mutex> lock(batch_mutex);
  // What makes a rename fail within one directory (a directory in the way) is checked for all
  // first, so that a failure leaves none of the outputs.
  for (const auto& [tmp, target] : staged_) {
    struct stat st;
    if (::stat(target.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
      throw InputError(target, "cannot write: Is a directory");
  }
  // Any other failure (an I/O error, a directory gone) can come midway. The files replaced so
  // far are then put back: each existing target is first kept under a second name (a hard
  // link, nothing copied), restored over the new file on failure and unlinked on success.
  std::vector<std::string> kept(staged_.size());
  auto drop_kept = [&] {
    for (const std::string& k : kept)
      if (!k.empty()) remove_temporary_file(k);
  };
  for (std::size_t i = 0; i < staged_.size(); ++i) {
    const std::string& target = staged_[i].second;
    const std::string k = temporary_path(target, ".kept");
    track_temporary_file(k);
    if (::link(target.c_str(), k.c_str()) == 0)
      kept[i] = k;
    else
      untrack_temporary_file(k);  // no file there yet, or no hard links: nothing to restore
  }
  for (std::size_t i = 0; i < staged_.size(); ++i) {
    const auto& [tmp, target] = staged_[i];
    keep_mode(tmp, target);
    if (std::rename(tmp.c_str(), target.c_str()) != 0) {
      const int err = errno;
      const std::string failed = target;
      for (std::size_t j = 0; j < i; ++j) {
        const std::string& done = staged_[j].second;
        if (kept[j].empty()) {
          std::remove(done.c_str());
        } else if (std::rename(kept[j].c_str(), done.c_str()) == 0) {
          untrack_temporary_file(kept[j]);
          kept[j].clear();
        }
      }
      drop_kept();
      staged_.erase(staged_.begin(), staged_.begin() + static_cast<std::ptrdiff_t>(i));  // the rest: removed
      throw Error(failed + ": cannot write: " + std::strerror(err));
    }
    untrack_temporary_file(tmp);
  }
  drop_kept();
  staged_.clear();
}

}  // namespace isochart
