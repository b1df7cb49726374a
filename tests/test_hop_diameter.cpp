// Tests of hop_diameter (cge/graph/hop_diameter.hpp), on neighbour lists and on adjacency
// bitsets: the diameter and component count against one plain BFS per node.
#include <catch2/catch.hpp>

#include <random>
#include <utility>
#include <vector>

#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/hop_diameter.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

namespace {

/// Eccentricities by one plain BFS per node (-1 distances ignored) and the component count.
std::pair<int, int> brute_diameter_and_components(const SmallGraph& sg) {
  const cge::Graph<double> g = to_graph(sg);
  int diameter = 0;
  std::vector<int> component(static_cast<std::size_t>(sg.n), -1);
  int components = 0;
  for (int s = 0; s < sg.n; ++s) {
    std::vector<int> dist(static_cast<std::size_t>(sg.n), -1);
    std::vector<int> queue{s};
    dist[static_cast<std::size_t>(s)] = 0;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      for (const int w : g.neighbors(queue[h])) {
        if (dist[static_cast<std::size_t>(w)] < 0) {
          dist[static_cast<std::size_t>(w)] = dist[static_cast<std::size_t>(queue[h])] + 1;
          queue.push_back(w);
        }
      }
    }
    for (const int d : dist) diameter = std::max(diameter, d);
    if (component[static_cast<std::size_t>(s)] < 0) {
      for (const int w : queue) component[static_cast<std::size_t>(w)] = components;
      ++components;
    }
  }
  return {diameter, components};
}

}  // namespace

TEST_CASE("hop_diameter equals the largest BFS eccentricity, with the component count", "[dde][diameter]") {
  std::vector<SmallGraph> graphs = small_graph_zoo(300);
  std::mt19937 rng(4242);
  graphs.push_back(geometric_graph(300, 3));
  graphs.push_back(geometric_graph(600, 4));
  graphs.push_back(grid_graph(15, 23));
  graphs.push_back(decorated_grid(12, 12, true));
  graphs.push_back(diamond_chain(3, 40));
  graphs.push_back(star_of_cliques(5, 6));
  for (int i = 0; i < 40; ++i) {
    const int n = std::uniform_int_distribution<int>(2, 200)(rng);
    graphs.push_back(
        random_gnp(rng, n, std::uniform_real_distribution<double>(0.005, 0.1)(rng), "d" + std::to_string(i)));
    graphs.push_back(random_connected(rng, n, std::uniform_int_distribution<int>(0, n)(rng), "c" + std::to_string(i)));
  }
  for (const SmallGraph& sg : graphs) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    const auto [diameter, components] = brute_diameter_and_components(sg);
    const cge::Graph<double> g = to_graph(sg);
    const cge::HopDiameter d = cge::hop_diameter(g);
    REQUIRE(d.diameter == diameter);
    REQUIRE(d.components == components);
    CHECK(d.searches <= sg.n);
    const cge::HopDiameter on_bitsets = cge::hop_diameter(g, cge::AdjacencyBitsets(g));
    REQUIRE(on_bitsets.diameter == diameter);
    REQUIRE(on_bitsets.components == components);
    REQUIRE(on_bitsets.searches == d.searches);  // the same distances, so the same sources
  }
  const cge::HopDiameter empty = cge::hop_diameter(cge::Graph<double>{});
  CHECK(empty.diameter == 0);
  CHECK(empty.components == 0);
  // Few searches where the bounds work: a long path needs only its two ends and a middle node.
  CHECK(cge::hop_diameter(to_graph(path_graph(500))).searches <= 3);
}
