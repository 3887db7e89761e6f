#pragma once
// Conventions shared by every subcommand: global options, progress line, warnings, and
// how results reach stdout (text or JSON) and the --report file.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "isochart/error.h"
#include "isochart/io.h"
#include "isochart/progress.h"
#include "isochart/signal.h"
#include "isochart/stretch.h"

namespace cli {

struct GlobalOptions {
  int threads = 0;         // 0 = all cores
  std::uint64_t seed = 1;  // every random choice derives from this
  bool quiet = false;
  int verbose = 0;
  bool json = false;       // print the result as one JSON object
  std::string report;      // also save the JSON result here
  bool no_repair = false;  // treat repairable mesh problems as errors
  bool weld = false;       // join vertices at identical positions in every input
};

/// Shared state handed to subcommands.
struct Context {
  Context();
  GlobalOptions opts;
  void warn(const std::string& file, const std::string& message) const;
  void info(const std::string& message) const;  // only with -v
  /// A progress callback printing one line on stderr, shown once a run passes one second.
  isochart::Progress progress() const;
  /// Clears the progress line (call before printing results).
  void end_progress() const;
  /// Loads a mesh with the global repair setting, printing repair warnings.
  /// Loads a mesh, warning about what was repaired. An atlas (a mesh laid out in UV by any
  /// tool) has its corners at equal positions joined, as tools split vertices at UV seams.
  isochart::LoadResult load(const std::string& path, bool atlas = false) const;
  /// Image outputs (empty ones skipped): an extension with a writer, checked before any work.
  void check_image_outputs(const std::vector<std::string>& paths) const;
  /// Refuses, before any work, an output (the --report file included) that is one of the
  /// inputs or another output; the writers check again at the end (outputs named later).
  void check_paths(const std::vector<std::string>& inputs, std::vector<std::string> outputs) const;
  /// Prints `text` (or the JSON when --json) on stdout, and writes the --report file. The JSON
  /// gets the run's warnings ("FILE: message", also with -q) as `warnings` unless it has them.
  void emit(const nlohmann::json& result, const std::string& text) const;

  struct Warnings;
  std::shared_ptr<Warnings> warnings;

  struct ProgressState;
  std::shared_ptr<ProgressState> progress_state;
};

/// The largest geometry image side any command builds. A level takes about 600 bytes a
/// sample at 2048² (2.4 GB, 14 s on eight.off); 4096² took over 14 GB and 300 s without
/// finishing.
constexpr int kMaxImageSide = 2048;

/// CLI11's own PositiveNumber prints the range 0 .. DBL_MAX in full; this names the rule.
inline const CLI::Validator positive{[](std::string& v) {
                                       try {
                                         std::size_t used = 0;
                                         const double x = std::stod(v, &used);
                                         if (used == v.size() && x > 0 && x <= 1e300) return std::string();
                                       } catch (const std::exception&) {
                                       }
                                       return "expected a positive number, got '" + v + "'";
                                     },
                                     "POSITIVE"};

/// A finite number >= 0.
inline const CLI::Validator non_negative{[](std::string& v) {
                                           try {
                                             std::size_t used = 0;
                                             const double x = std::stod(v, &used);
                                             if (used == v.size() && x >= 0 && x <= 1e300)
                                               return std::string();
                                           } catch (const std::exception&) {
                                           }
                                           return "expected a number >= 0, got '" + v + "'";
                                         },
                                         "NON-NEGATIVE"};

/// `x` in fixed notation without trailing zeros ("0.000061", "16384").
inline std::string plain_number(double x) {
  std::string t = std::to_string(x);
  if (t.find('.') != std::string::npos) {
    while (t.back() == '0') t.pop_back();
    if (t.back() == '.') t.pop_back();
  }
  return t;
}

/// A range's end in fixed notation with the fewest decimals that keep it inside the range
/// (rounded up for a lower end, down for an upper one): 1/16384 printed as "0.000061" was
/// below the range, and typed back it was refused by the range it was quoted from.
inline std::string bound_number(double x, bool lower) {
  for (int decimals = 6; decimals <= 20; ++decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
    const double back = std::strtod(buf, nullptr);
    if (!(lower ? back >= x : back <= x)) continue;
    std::string t = buf;
    if (t.find('.') != std::string::npos) {
      while (t.back() == '0') t.pop_back();
      if (t.back() == '.') t.pop_back();
    }
    return t;
  }
  return plain_number(x);
}

/// A number in [lo, hi]. CLI::Range compares with < and >, so "nan" passed it.
inline CLI::Validator number_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& v) {
        try {
          std::size_t used = 0;
          const double x = std::stod(v, &used);
          if (used == v.size() && x >= lo && x <= hi) return std::string();
        } catch (const std::exception&) {
        }
        // CLI::Range's wording, which Context rewrites for every range alike.
        return "Value " + v + " not in range " + bound_number(lo, true) + " to " + bound_number(hi, false);
      },
      // The help's wording of CLI::Range, with the bounds written as the error writes them
      // (0.00006104, not 6.10352e-05).
      "FLOAT in [" + bound_number(lo, true) + " - " + bound_number(hi, false) + "]");
}

/// A seed: 0 .. 2^64 − 1 in decimal. CLI11 would take "-1" or a 30-digit number silently
/// (wrapped or saturated), and a run could not be repeated from its printed seed.
inline const CLI::Validator seed_value{
    [](std::string& v) {
      const bool digits =
          !v.empty() && v.size() <= 20 && v.find_first_not_of("0123456789") == std::string::npos;
      if (digits && (v.size() < 20 || v <= "18446744073709551615")) return std::string();
      return "expected an integer from 0 to 18446744073709551615, got '" + v + "'";
    },
    "UINT64"};

/// A subcommand: registers its options on `sub` and returns the action to run.
using Action = std::function<void()>;

void add_info(CLI::App& app, Context& ctx, Action& action);
void add_stats(CLI::App& app, Context& ctx, Action& action);
void add_render(CLI::App& app, Context& ctx, Action& action);
void add_atlas(CLI::App& app, Context& ctx, Action& action);
void add_remesh(CLI::App& app, Context& ctx, Action& action);
void add_psnr(CLI::App& app, Context& ctx, Action& action);
void add_synth(CLI::App& app, Context& ctx, Action& action);
void add_bench(CLI::App& app, Context& ctx, Action& action);
void add_sae(CLI::App& app, Context& ctx, Action& action);

/// CLI11's message for a value it could not read or that is out of a CLI::Range, in our
/// words ("--width: expected an integer, got 'abc'"); other messages unchanged.
std::string parse_error_message(const CLI::App& app, const CLI::ParseError& e);

/// Throws InputError(file, msg) for an invalid option value (exit code 2).
[[noreturn]] void bad_option(const std::string& message);

/// Which of some options were typed on the command line, so that one that would do nothing
/// is refused instead of ignored. `record` runs in the subcommand's callback, after parsing.
struct GivenOptions {
  std::vector<std::string> names;
  void record(const CLI::App* sub, std::initializer_list<const char*> options) {
    for (const char* name : options)
      if (sub->count(name) > 0) names.push_back(name);
  }
  bool has(const char* name) const { return std::find(names.begin(), names.end(), name) != names.end(); }
};

/// The format of an output mesh `path`, which must be one of `allowed`; otherwise an InputError
/// naming the file and what the command writes (`writes`, e.g. ".obj, .glb or .ply"), before
/// any work is done.
isochart::MeshFormat output_mesh_format(const std::string& path,
                                        const std::vector<isochart::MeshFormat>& allowed,
                                        const std::string& writes);

/// An external atlas must lay out the input's surface (its own vertices and faces may be split
/// or renumbered): the same bounding box within 0.1 % of its diagonal and the same area within
/// 1 %. Otherwise its remesh would be of another mesh, measured against this one.
/// \throw InputError(file, ...) when it does not.
void check_atlas_matches(const isochart::Mesh& input, const isochart::Mesh& atlas, const std::string& file);

/// Warns about a chart with under 1 % of the texels its surface area would get (a chart shrunk
/// to a speck by a broken atlas), saying `consequence`.
void warn_sparse_chart(const Context& ctx, const std::string& file, const isochart::ChartDensity& d,
                       const std::string& consequence);

/// Warns "texture coordinates reach outside [0, 1] (u0, v0) to (u1, v1); " + `consequence` when
/// the atlas's UVs (q.uv_min, q.uv_max) leave the unit square.
void warn_uvs_outside(const Context& ctx, const std::string& file, const isochart::AtlasQuality& q,
                      const std::string& consequence);

/// The width / height of the texture an atlas's UVs look laid out for
/// (isochart::detect_texture_aspect). Warns "the texture coordinates look laid out for a texture
/// 3.89 times as wide as high; " + `consequence` when that is more than 10 % from `assumed`, the
/// shape the command would otherwise use.
double read_texture_aspect(const Context& ctx, const std::string& file, const isochart::Mesh& atlas,
                           double assumed, const std::string& consequence);

/// The items of a comma-separated option value. An empty item ("64,,32", a trailing comma) is
/// refused: CLI11's own splitting dropped them silently.
std::vector<std::string> split_items(const std::string& option, const std::string& text);

/// --levels, given as comma-separated lists: sides from lo to hi, none twice (it would be built
/// and written twice to the same file).
std::vector<int> parse_levels(const std::vector<std::string>& given, int lo, int hi);

/// A layout picture in a texture's proportions (width / height = `aspect`), its longer side
/// `longer` pixels and its shorter at least 16.
std::array<int, 2> layout_size(int longer, double aspect);

/// The image of a `texture:IMG` signal (an input of the run), else "".
inline std::string signal_texture(const std::string& signal) {
  return signal.rfind("texture:", 0) == 0 ? signal.substr(8) : std::string();
}

/// The signal `spec` on `mesh`, which was read from `file` as `loaded` (the mesh itself, or one
/// numbered otherwise from the same load). A texture signal is read through the mesh's texture
/// coordinates: faces the file gave none would all read the texel at (0, 0), a signal made up
/// for them, so that is refused. Alpha is dropped from a texture signal; where the image has
/// transparent texels their stored colour (often arbitrary) becomes signal, which the user
/// hears about.
inline isochart::Signal load_signal(const Context& ctx, const std::string& spec,
                                    const isochart::LoadResult& loaded, const isochart::Mesh& mesh,
                                    const std::string& file) {
  const long long without = loaded.report.faces_without_uvs;
  if (spec.rfind("texture:", 0) == 0 && without > 0)
    throw isochart::InputError(file, std::to_string(without) + (without == 1 ? " face has" : " faces have") +
                                         " no texture coordinates to read --signal " + spec + " through");
  isochart::Signal s = isochart::make_signal(mesh, spec, file);
  if (s.transparent_texels > 0) {
    const double share = 100.0 * s.transparent_texels / (double(s.texture.width) * s.texture.height);
    ctx.warn(signal_texture(spec), std::to_string(s.transparent_texels) + " texels (" +
                                       plain_number(std::round(share * 10) / 10) +
                                       " %) are not opaque; alpha is not part of the signal, so their stored "
                                       "colour counts as it is");
  }
  return s;
}

/// The image of a texture a mesh file names or carries (isochart::find_mesh_texture): read from
/// its file, or decoded from its embedded bytes through a temporary file beside `beside` (the
/// image library reads files). Empty when `t` names none.
/// \throw isochart::InputError when the image cannot be read, naming its file, or `mesh`
///        for an embedded one.
isochart::Image read_mesh_texture(const isochart::MeshTexture& t, const std::string& beside,
                                  const std::string& mesh);

/// `mesh` with its texture coordinates moved to where material `t` reads its image (OBJ
/// `map_Kd -s/-o`, glTF KHR_texture_transform); `mesh` itself when the material moves none.
isochart::Mesh as_material_reads(const isochart::MeshTexture& t, const isochart::Mesh& mesh);

/// \throw isochart::InputError naming `file` when some texture coordinate of `moved` (the
///        file's, moved by its materials' maps) is not finite: a map so large it overflows.
void check_material_coordinates(const std::string& file, const isochart::Mesh& moved);

/// A model's materials as its faces read them (several `usemtl` materials, glTF primitives'
/// materials): each material's image read once, or its colour where it names none.
struct MaterialImages {
  std::vector<isochart::TextureSource> sources;
  std::vector<int> face_source;      // per face, into sources
  isochart::Mesh source;             // the mesh with the coordinates its materials read
  long long untextured_faces = 0;    // faces reading a colour, no image
  std::vector<std::string> files;    // the image files read
  std::vector<std::string> skipped;  // with `lenient`: why a material's image was not read
};
/// Reads every material of `mesh` (loaded from `file`): faces of no material, or of one no
/// file defines, read white; coordinates moved per face by its material's map.
/// \throw isochart::InputError naming `file` and the material when one cannot be used, or its
///        image when that cannot be read (read_mesh_texture, embedded images through `beside`);
///        with `lenient` such a material's faces read its colour instead, and `skipped` says why.
MaterialImages read_material_images(const std::string& file, const isochart::Mesh& mesh,
                                    const std::string& beside, bool lenient = false);

/// Seconds since `t0`.
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace cli
