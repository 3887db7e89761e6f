#include "cli.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "isochart/error.h"

namespace cli {

struct Context::ProgressState {
  std::mutex mutex;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_print{};
  bool tty = isatty(fileno(stderr)) != 0;
  bool shown = false;
  int last_stage = -1;
};

Context::Context() : progress_state(std::make_shared<ProgressState>()) {}

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
  }
}

void Context::warn(const std::string& file, const std::string& message) const {
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
      if (s == state->last_stage && now - state->last_print < std::chrono::milliseconds(100))
        return true;
      std::fprintf(stderr, "\r\033[K[%6.1fs] %-15s %3.0f%%",
                   std::chrono::duration<double>(now - state->start).count(),
                   isochart::stage_name(stage), 100.0 * fraction);
      std::fflush(stderr);
      state->shown = true;
    } else if (s != state->last_stage) {
      // Not a terminal: one line per stage keeps logs readable.
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

isochart::LoadResult Context::load(const std::string& path) const {
  isochart::LoadOptions lo;
  lo.repair = !opts.no_repair;
  isochart::LoadResult r = isochart::load_mesh(path, lo);
  for (const auto& w : r.report.warnings) warn(path, w);
  return r;
}

void Context::emit(const nlohmann::json& result, const std::string& text) const {
  end_progress();
  if (!opts.report.empty()) isochart::write_file_atomic(opts.report, result.dump(2) + "\n");
  if (opts.json)
    std::cout << result.dump(2) << "\n";
  else
    std::cout << text;
  std::cout.flush();
}

void bad_option(const std::string& message) { throw isochart::InputError("", message); }

std::array<int, 2> layout_size(int longer, double aspect) {
  const int shorter = std::max(16, static_cast<int>(std::lround(longer / std::max(aspect, 1 / aspect))));
  return aspect >= 1 ? std::array<int, 2>{longer, shorter} : std::array<int, 2>{shorter, longer};
}

void check_levels(const std::vector<int>& levels) {
  for (std::size_t i = 0; i < levels.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (levels[i] == levels[j]) bad_option("--levels: " + std::to_string(levels[i]) + " is given twice");
}

}  // namespace cli
