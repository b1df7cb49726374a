#pragma once
// ShannonEdgeEntropy: Shannon entropy of the edge-length distribution of a weighted graph
// (docs/METHOD.md section 5): p_l = w_l / sum w, H_W = -sum p_l log2 p_l, in bits.
// Zero-length edges are skipped (they carry no probability); no edges or all zero: H_W = 0.

#include <cmath>
#include <stdexcept>
#include <vector>

#include "cge/graph/graph.hpp"

namespace cge {

template <typename Scalar = double>
class ShannonEdgeEntropy {
 public:
  /// From the graph's edge weights. Weights are validated by Graph (finite, non-negative).
  template <typename GraphScalar>
  Scalar compute(const Graph<GraphScalar>& g) const {
    std::vector<double> w;
    w.reserve(g.edges().size());
    for (const auto& e : g.edges()) w.push_back(static_cast<double>(e.weight));
    return compute_from_weights(w);
  }

  /// From bare weights; throws std::invalid_argument for a negative or non-finite weight.
  Scalar compute_from_weights(const std::vector<double>& weights) const {
    double total = 0.0;
    for (double w : weights) {
      if (!std::isfinite(w) || w < 0) throw std::invalid_argument("ShannonEdgeEntropy: negative or non-finite weight");
      total += w;
    }
    if (!(total > 0.0)) return Scalar(0);
    // H = log2 T - (1/T) sum w log2 w: one division, and exact 2 for four equal weights.
    double weighted = 0.0;
    for (double w : weights) {
      if (w > 0.0) weighted += w * std::log2(w);
    }
    return static_cast<Scalar>(std::log2(total) - weighted / total);
  }
};

}  // namespace cge
