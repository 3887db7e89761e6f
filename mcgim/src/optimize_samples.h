#pragma once
// Internal: moving the samples (groups together) so that the reconstructed surface fits the
// original surface (Sander et al. 2003 §3.4: the final optimization of the MCGIM).

#include "charts.h"
#include "isochart/progress.h"
#include "mcgim/geometry_image.h"
#include "mcgim/mcgim.h"

namespace mcgim::detail {

// Least-squares fit: points spread over the original faces are located in the image through
// their texture coordinates, hence on a remesh triangle (with corners at the samples' `param`
// locations, see Sampling::param) with barycentric weights; vertex
// positions minimize Σ area·|remesh point − original point|² + a pull towards their current
// position. `remesh` is rebuilt after each pass (the shorter diagonals may change). With
// options.fit_diagonals, each closest-point pass first splits the blocks along the diagonal
// closer to the original surface (image.block_diagonal), unless that takes the remesh further
// from the input's topology.
void optimize_samples(const AtlasCharts& atlas, const Placement& placement, const std::vector<Vec2d>& param,
                      const LevelOptions& options, GeometryImage& image, Remesh& remesh,
                      const isochart::Progress& progress);

}  // namespace mcgim::detail
