// Example 1: the three entropy measures of one small graph.
//
// A graph is built from an edge list with Graph::from_edges. DegreeDegreeEntropy gives the
// degree-degree association entropy H (bits) and the information index I = lambda (log2|V| - H);
// ShannonEdgeEntropy gives H_W, the entropy of the edge-length distribution (docs/METHOD.md sections 4-5).

#include <cmath>
#include <cstdio>

#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/graph/graph.hpp"

int main() {
  // The unit square 0-1-2-3 with the diagonal 0-2, weights = Euclidean edge lengths.
  //   3 --- 2
  //   |   / |
  //   | /   |
  //   0 --- 1
  const double diagonal = std::sqrt(2.0);
  const auto g = cge::Graph<double>::from_edges(
      /*num_nodes=*/4, {{0, 1, 1.0}, {1, 2, 1.0}, {2, 3, 1.0}, {3, 0, 1.0}, {0, 2, diagonal}}, /*weighted=*/true);

  // Degree-degree entropy with the defaults: alpha = 0.5, lambda = 1, exponential coefficients,
  // every tied shortest path counted. The settings are public members; change them freely.
  cge::DegreeDegreeEntropy<double> degree_entropy;
  degree_entropy.settings.alpha = 0.5;
  const auto r = degree_entropy.compute(g);

  // Edge entropy: p_l = w_l / sum w, H_W = -sum p_l log2 p_l.
  const double h_w = cge::ShannonEdgeEntropy<double>().compute(g);

  std::printf("nodes %d, edges %d, diameter %d\n", g.num_nodes(), g.num_edges(), r.diameter);
  for (int v = 0; v < g.num_nodes(); ++v) {
    std::printf("  E(%d) = %.6f (degree %d)\n", v, r.exponents[static_cast<std::size_t>(v)], g.degree(v));
  }
  std::printf("H   = %.15g bits (at most log2|V| = %.15g)\n", r.entropy_bits, r.max_entropy_bits);
  std::printf("I   = %.15g\n", r.information_index);
  std::printf("H_W = %.15g bits\n", h_w);  // 2.30614985795795 for this graph
  return 0;
}
