#include "isochart/progress.h"

#include "isochart/error.h"

namespace isochart {

const char* stage_name(Stage s) {
  switch (s) {
    case Stage::Load: return "load";
    case Stage::Geodesics: return "geodesics";
    case Stage::Embedding: return "embedding";
    case Stage::Optimization: return "optimization";
    case Stage::Clustering: return "clustering";
    case Stage::GraphCut: return "graph_cut";
    case Stage::Merging: return "merging";
    case Stage::Packing: return "packing";
    case Stage::Sampling: return "sampling";
    case Stage::Zippering: return "zippering";
    case Stage::Reconstruction: return "reconstruction";
    case Stage::Correspondence: return "correspondence";
    case Stage::Distance: return "distance";
    case Stage::Synthesis: return "synthesis";
    case Stage::Output: return "output";
  }
  return "unknown";
}

void report(const Progress& p, Stage s, double fraction) {
  if (p && !p(s, fraction)) throw Cancelled();
}

}  // namespace isochart
