#pragma once

#include <vector>
// Internal: zippering (Sander et al. 2003 §3.3). Each chart's boundary ring of samples is
// aligned monotonically with the chart's boundary loop; cut-nodes go to ring samples in loop
// order; along every cut path the two sides' sample chains are merged into a monotone sequence
// of groups that share one position on the path. Mesh-boundary paths stay open.

#include "charts.h"
#include "isochart/progress.h"
#include "sampling.h"

namespace mcgim::detail {

struct ZipperStats {
  int cut_paths = 0;     // two-sided paths
  int empty_charts = 0;  // charts without samples, contracted to a point
  // Per chart: it was contracted, or one of its cut paths collapsed to a point (two cut nodes
  // in one group); packing it larger is what would help.
  std::vector<char> strained;
};

// Sets image.group / num_groups and the positions and normals of every zippered sample.
ZipperStats zipper(const AtlasCharts& atlas, const Placement& placement, Sampling& sampling,
                   const isochart::Progress& progress);

}  // namespace mcgim::detail
