#pragma once
// Internal: rasterizing the charts into the image and making each chart's samples a disk.

#include <vector>

#include "charts.h"
#include "isochart/progress.h"
#include "mcgim/geometry_image.h"

namespace mcgim::detail {

// The samples of one chart after cleanup. A chart without samples is "empty": zippering
// contracts it to a point.
struct ChartRegion {
  std::vector<int> samples;  // image indices, ascending
  // Boundary ring of the reconstructed chart (image indices), oriented like the chart's
  // boundary loop; empty when the chart is empty.
  std::vector<int> ring;
  long long removed = 0;     // covered samples dropped by the cleanup
  long long cut_off = 0;     // of those, samples of parts cut off from the rest (thin necks)
  std::vector<int> bridges;  // covered samples dropped as bridges across notches, ascending
};

struct Sampling {
  // Positions, normals, chart, face and barycentric are set; group is not (zippering sets it).
  GeometryImage image;
  std::vector<ChartRegion> regions;  // per chart
  // W·H: where each sample sits in its chart's texel space: its centre, or for a zippered
  // sample the point of the chart boundary it was snapped to.
  std::vector<Vec2d> param;
  long long covered = 0;             // samples covered before cleanup
  long long removed = 0;
  long long forced = 0;              // samples given to charts too small for a triangle
};

// Rasterizes every chart of the placement. With `check_gap`, charts closer than one texel
// or overlapping are an InputError (the atlas's own layout); otherwise an internal Error.
Sampling sample_charts(const AtlasCharts& atlas, const Placement& placement, bool check_gap,
                       const isochart::Progress& progress);

// Samples covered by the charts (no cleanup), for the resolution search.
long long count_covered(const AtlasCharts& atlas, const Placement& placement);

}  // namespace mcgim::detail
