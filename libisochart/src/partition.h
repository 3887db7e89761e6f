#pragma once
// Internal: splitting a chart (Iso-charts §5): spectral clustering, graph-cut boundaries,
// and making every part a single edge-connected piece.

#include <string>
#include <vector>

#include "chart.h"

namespace isochart {

struct Embedding;

namespace detail {

struct SplitOptions {
  double alpha = 0.5;             ///< §5.2 eq. 2
  double medial_fraction = 0.3;   ///< §5.2
  bool graph_cut = true;
  double min_rep_distance = 0;    ///< §5.1 step 5: 10 × the input's mean edge length
  /// General (2n-way) clustering is allowed; otherwise binary or tubular only. The paper
  /// observes a single non-binary subdivision at the first level (§5.3, last paragraph).
  bool allow_general = true;
};

/// Which §5 rule chose the split.
enum class SplitKind { General, Tubular, Binary, Fallback };
const char* split_kind_name(SplitKind k);

/// Face labels 0..m−1 from surface spectral clustering (§5.1 general, §5.3 tubular, binary).
/// May return fewer than two labels when the embedding is degenerate.
std::vector<int> spectral_partition(const ChartGeometry& g, const Embedding& e, const SplitOptions& o,
                                    SplitKind& kind, int& num_labels);

/// Two parts grown from the two landmarks farthest apart (used when spectral clustering fails);
/// as a last resort the faces nearest to one landmark against the rest.
std::vector<int> fallback_partition(const ChartGeometry& g, const Topology& topo, const Embedding& e,
                                    int& num_labels);

/// Optimizes the boundary of every pair of adjacent parts by a min cut over their medial region
/// (§5.2), with capacities mixing dihedral angle and the GDD balance between the two parts'
/// landmark embeddings (§5.2.1).
void optimize_boundaries(const ChartGeometry& g, const Topology& topo, const Embedding& e,
                         std::vector<int>& labels, int num_labels, const SplitOptions& o);

/// Straightens jagged part boundaries: a face whose other two neighbours (through edges) both
/// carry one other label takes that label, for up to `passes` sweeps. Returns faces changed.
int smooth_labels(const Topology& topo, std::vector<int>& labels, int passes = 4);

/// Makes every label one edge-connected piece: stray pieces join the neighbouring label they
/// share the longest boundary with. Labels are renumbered 0..m−1 by first face; returns m.
int make_labels_connected(const Topology& topo, const std::vector<Vec3d>& positions,
                          std::vector<int>& labels);

}  // namespace detail
}  // namespace isochart
