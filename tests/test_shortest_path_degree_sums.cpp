// Tests of shortest_path_degree_sums (docs/METHOD.md section 4): the Delta table against an
// independent path-enumeration oracle (also beyond one block of 64 sources) and a scalar BFS in
// long double, and the three tie modes where they must differ.
#include <catch2/catch.hpp>

#include <random>
#include <vector>

#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/graph/graph.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

TEST_CASE("shortest_path_degree_sums agrees with shortest-path enumeration on small graphs", "[dde][oracle]") {
  const std::vector<SmallGraph> zoo = small_graph_zoo(400);
  int disconnected = 0;
  long long nonzero_values = 0;
  for (const SmallGraph& sg : zoo) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO("graph " << sg.name << " (" << sg.n << " nodes, " << sg.edges.size() << " edges), ties " << tie_name(mode));
      const OracleTable expected = oracle_delta(sg, mode);
      const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, mode);
      REQUIRE(table.num_nodes == sg.n);
      REQUIRE(table.diameter == expected.diameter);
      REQUIRE(table.connected == expected.connected);
      REQUIRE(table.row_offsets.size() == static_cast<std::size_t>(sg.n) + 1);
      for (int s = 0; s < sg.n; ++s) {
        REQUIRE(table.eccentricity(s) == expected.eccentricity[static_cast<std::size_t>(s)]);
        for (int k = 1; k <= expected.eccentricity[static_cast<std::size_t>(s)]; ++k) {
          const LD want = expected.delta[static_cast<std::size_t>(s)][static_cast<std::size_t>(k - 1)];
          INFO("Delta(" << s << ", " << k << ") = " << table.delta(s, k) << ", oracle " << static_cast<double>(want));
          REQUIRE(close(table.delta(s, k), want, 1e-12L));
          if (want != 0) ++nonzero_values;
        }
        // Beyond the eccentricity (and for k = 0) delta() reads 0.
        REQUIRE(table.delta(s, 0) == 0.0);
        REQUIRE(table.delta(s, expected.eccentricity[static_cast<std::size_t>(s)] + 1) == 0.0);
      }
      if (!expected.connected && mode == TieMode::all) ++disconnected;
    }
  }
  // The zoo must exercise what it claims to: disconnected inputs and non-trivial sums.
  CHECK(zoo.size() > 450);
  CHECK(disconnected > 50);
  CHECK(nonzero_values > 10000);
}

TEST_CASE("tie modes differ where paths tie with different sums", "[dde][oracle]") {
  // K_{1,2} glued: 0 - {1, 2} - 3 with 1 also joined to a pendant 4. Node 3 is reached from 0 by two
  // shortest paths through nodes of different degree, so the three tie modes must disagree.
  const SmallGraph sg{"diamond+pendant", 5, {{0, 1}, {0, 2}, {1, 3}, {2, 3}, {1, 4}}};
  // degrees: 0:2, 1:3, 2:2, 3:2, 4:1. Paths 0-1-3: 1 + 1 = 2; 0-2-3: 0 + 0 = 0.
  const cge::Graph<double> g = to_graph(sg);
  const auto all = cge::shortest_path_degree_sums(g, TieMode::all);
  const auto mean = cge::shortest_path_degree_sums(g, TieMode::mean);
  const auto min = cge::shortest_path_degree_sums(g, TieMode::min);
  // Distance 2 from 0: node 3 (sums 2 and 0) and node 4 via 0-1-4 (1 + 2 = 3).
  REQUIRE(all.delta(0, 2) == 5.0);
  REQUIRE(mean.delta(0, 2) == 4.0);
  REQUIRE(min.delta(0, 2) == 3.0);
  // Distance 1 from 0: nodes 1 (|2-3| = 1) and 2 (0): no ties, all modes agree.
  REQUIRE(all.delta(0, 1) == 1.0);
  REQUIRE(mean.delta(0, 1) == 1.0);
  REQUIRE(min.delta(0, 1) == 1.0);
}

TEST_CASE("shortest_path_degree_sums agrees with path enumeration beyond one block of 64 sources", "[dde][oracle]") {
  // The sweep runs 64 sources at a time: sizes around multiples of 64, and components that a
  // block straddles.
  std::mt19937 rng(6464);
  std::vector<SmallGraph> graphs;
  for (const int n : {63, 64, 65, 100, 127, 128, 129, 150}) {
    graphs.push_back(random_connected(rng, n, n / 5, "big"));
  }
  graphs.push_back(grid_graph(8, 9));
  graphs.push_back(relabel(grid_graph(7, 10), random_permutation(rng, 70)));
  graphs.push_back(complete_bipartite(3, 70));
  {
    SmallGraph g = disjoint_union(random_connected(rng, 40, 10, "a"),
                                  disjoint_union(random_connected(rng, 50, 8, "b"), isolated(3)));
    graphs.push_back(relabel(g, random_permutation(rng, g.n)));
  }
  graphs.push_back(random_gnp(rng, 130, 0.012, "sparse"));  // many small components
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO("graph " << sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode));
      require_table_matches(cge::shortest_path_degree_sums(g, mode), oracle_delta(sg, mode));
    }
  }
}

TEST_CASE("shortest_path_degree_sums agrees with a scalar BFS on larger tie-rich graphs", "[dde][oracle]") {
  std::mt19937 rng(31337);
  std::vector<SmallGraph> graphs;
  graphs.push_back(grid_graph(18, 20));
  graphs.push_back(with_random_chords(rng, grid_graph(15, 15), 20));
  graphs.push_back(relabel(complete_bipartite(20, 45), random_permutation(rng, 65)));
  graphs.push_back(random_connected(rng, 300, 150, "c"));
  {
    SmallGraph g = disjoint_union(grid_graph(9, 9), disjoint_union(random_connected(rng, 120, 60, "d"), isolated(5)));
    graphs.push_back(relabel(g, random_permutation(rng, g.n)));
  }
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO("graph " << sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode));
      require_table_matches(cge::shortest_path_degree_sums(g, mode), scalar_bfs_delta(sg, mode));
    }
  }
  // The scalar reference itself agrees with path enumeration on the small zoo.
  for (const SmallGraph& sg : small_graph_zoo(60)) {
    for (const TieMode mode : kTieModes) {
      const OracleTable a = oracle_delta(sg, mode);
      const OracleTable b = scalar_bfs_delta(sg, mode);
      REQUIRE(a.diameter == b.diameter);
      for (int v = 0; v < sg.n; ++v) {
        for (std::size_t k = 0; k < a.delta[static_cast<std::size_t>(v)].size(); ++k) {
          REQUIRE(close(b.delta[static_cast<std::size_t>(v)][k], a.delta[static_cast<std::size_t>(v)][k], 1e-15L));
        }
      }
    }
  }
}
