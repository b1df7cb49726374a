// Tests of twin_classes (cge/graph/twin_classes.hpp): the classes against a pairwise comparison of
// neighbourhoods, on the small graph zoo with planted true and false twins.
#include <catch2/catch.hpp>

#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "cge/graph/graph.hpp"
#include "cge/graph/twin_classes.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

namespace {

/// The twin classes by definition: for every pair, compare the neighbour sets (open, and closed
/// for adjacent pairs); a node's representative is the smallest node it shares either with.
std::vector<std::int32_t> brute_twin_representatives(const SmallGraph& sg) {
  std::vector<std::set<int>> open(static_cast<std::size_t>(sg.n));
  for (const auto& [u, v] : sg.edges) {
    open[static_cast<std::size_t>(u)].insert(v);
    open[static_cast<std::size_t>(v)].insert(u);
  }
  std::vector<std::int32_t> representative(static_cast<std::size_t>(sg.n));
  for (int v = 0; v < sg.n; ++v) {
    representative[static_cast<std::size_t>(v)] = v;
    for (int u = 0; u < v; ++u) {
      std::set<int> closed_u = open[static_cast<std::size_t>(u)], closed_v = open[static_cast<std::size_t>(v)];
      closed_u.insert(u);
      closed_v.insert(v);
      if (open[static_cast<std::size_t>(u)] == open[static_cast<std::size_t>(v)] || closed_u == closed_v) {
        representative[static_cast<std::size_t>(v)] = u;
        break;
      }
    }
  }
  return representative;
}

}  // namespace

TEST_CASE("twin_classes: the nodes with equal open or closed neighbourhoods, by pairwise comparison", "[dde][twins]") {
  std::mt19937 rng(2718);
  std::vector<SmallGraph> graphs = small_graph_zoo(150);
  const std::size_t plain = graphs.size();
  for (std::size_t i = 0; i < plain; ++i) {
    graphs.push_back(with_planted_twins(rng, graphs[i], std::uniform_int_distribution<int>(1, 6)(rng)));
  }
  graphs.push_back(star_of_cliques(4, 7));
  graphs.push_back(with_planted_twins(rng, geometric_graph(300, 17), 40));
  int with_twins = 0;
  for (const SmallGraph& sg : graphs) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    const std::vector<std::int32_t> expected = brute_twin_representatives(sg);
    const cge::TwinClasses twins = cge::twin_classes(to_graph(sg));
    REQUIRE(twins.representative == expected);
    std::int32_t classes = 0;
    for (std::int32_t v = 0; v < sg.n; ++v) classes += expected[static_cast<std::size_t>(v)] == v;
    REQUIRE(twins.num_classes == classes);
    with_twins += classes < sg.n;
  }
  CHECK(with_twins > 150);  // the planted ones at least
  CHECK(cge::twin_classes(cge::Graph<double>{}).num_classes == 0);
}
