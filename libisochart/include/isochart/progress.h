#pragma once
/// Progress reporting and cancellation through one callback (see STYLE.md).

#include <functional>

namespace isochart {

/// Pipeline stages, reported to the progress callback and timed in reports.
enum class Stage {
  Load,
  Geodesics,
  Embedding,
  Optimization,
  Clustering,
  GraphCut,
  Merging,
  Packing,
  Sampling,
  Zippering,
  Reconstruction,
  Correspondence,
  Distance,
  Synthesis,
  Output,
};

const char* stage_name(Stage s);

/// Called with the stage and a completed fraction in [0, 1]. Return false to cancel, in
/// which case the library throws `Cancelled`. May be called from any thread; implementations
/// must be thread-safe. An empty function means "no reporting".
using Progress = std::function<bool(Stage, double)>;

/// Calls `p` if set and throws Cancelled when it returns false.
void report(const Progress& p, Stage s, double fraction);

}  // namespace isochart
