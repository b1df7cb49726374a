// Tests of cge::Graph: canonical form of from_edges, CSR adjacency, and input validation.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cge/graph/graph.hpp"
#include "test_support.hpp"

namespace {

using G = cge::Graph<double>;
using E = cge::Edge<double>;

using cge_test::invalid_argument_message;

/// A random simple graph as a set of unordered pairs (u < v) with random weights.
std::vector<E> random_simple_edges(std::mt19937& rng, int n, double p) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> weight(0.0, 100.0);
  std::vector<E> edges;
  for (int u = 0; u < n; ++u) {
    for (int v = u + 1; v < n; ++v) {
      if (unit(rng) < p) edges.push_back(E{u, v, weight(rng)});
    }
  }
  return edges;
}

/// Checks every canonical-form guarantee of g against the edge set it was built from.
void check_canonical(const G& g, int n, const std::vector<E>& source) {
  REQUIRE(g.num_nodes() == n);
  REQUIRE(g.num_edges() == static_cast<std::int32_t>(source.size()));
  // Edges: u < v, strictly increasing by (u, v), same multiset of (u, v, weight) as the input.
  std::set<std::pair<int, int>> seen;
  for (std::size_t i = 0; i < g.edges().size(); ++i) {
    const E& e = g.edges()[i];
    REQUIRE(e.u < e.v);
    if (i > 0) {
      const E& prev = g.edges()[i - 1];
      REQUIRE(std::make_pair(prev.u, prev.v) < std::make_pair(e.u, e.v));
    }
    seen.insert({e.u, e.v});
    const auto it = std::find_if(source.begin(), source.end(),
                                 [&](const E& s) { return std::min(s.u, s.v) == e.u && std::max(s.u, s.v) == e.v; });
    REQUIRE(it != source.end());
    REQUIRE(it->weight == e.weight);
  }
  REQUIRE(seen.size() == source.size());
  // CSR: n + 1 offsets from 0, each list strictly ascending, u in N(v) iff {u, v} is an edge.
  REQUIRE(g.csr_offsets().size() == static_cast<std::size_t>(n) + 1);
  REQUIRE(g.csr_offsets().front() == 0);
  REQUIRE(g.csr_offsets().back() == static_cast<std::int32_t>(g.csr_adjacency().size()));
  long degree_sum = 0;
  for (int v = 0; v < n; ++v) {
    const cge::IndexSpan nb = g.neighbors(v);
    REQUIRE(static_cast<std::int32_t>(nb.size()) == g.degree(v));
    degree_sum += g.degree(v);
    for (std::size_t i = 0; i < nb.size(); ++i) {
      const int w = nb[i];
      REQUIRE(w >= 0);
      REQUIRE(w < n);
      REQUIRE(w != v);
      if (i > 0) REQUIRE(nb[i - 1] < w);
      REQUIRE(seen.count({std::min(v, w), std::max(v, w)}) == 1);
    }
  }
  REQUIRE(degree_sum == 2L * g.num_edges());
}

}  // namespace

TEST_CASE("Graph::from_edges: canonical form does not depend on edge or endpoint order", "[graph]") {
  std::mt19937 rng(12345);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = std::uniform_int_distribution<int>(0, 25)(rng);
    const double p = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
    const std::vector<E> edges = random_simple_edges(rng, n, p);
    const G reference = G::from_edges(n, edges, true);
    check_canonical(reference, n, edges);

    // Shuffle the edges and flip endpoints at random: the same graph, member by member.
    std::vector<E> scrambled = edges;
    std::shuffle(scrambled.begin(), scrambled.end(), rng);
    for (E& e : scrambled) {
      if (rng() & 1u) std::swap(e.u, e.v);
    }
    const G other = G::from_edges(n, scrambled, true);
    check_canonical(other, n, scrambled);
    REQUIRE(other == reference);
    REQUIRE(other.edges() == reference.edges());
    REQUIRE(other.csr_offsets() == reference.csr_offsets());
    REQUIRE(other.csr_adjacency() == reference.csr_adjacency());
  }
}

TEST_CASE("Graph::from_edges: small explicit example", "[graph]") {
  // Triangle 0-1-2 plus pendant 3 on 1, plus isolated node 4, given in a scrambled order.
  const G g = G::from_edges(5, {{3, 1, 2.0}, {2, 0, 1.5}, {1, 0, 1.0}, {2, 1, 0.5}}, true);
  REQUIRE(g.num_nodes() == 5);
  REQUIRE(g.num_edges() == 4);
  REQUIRE(g.weighted());
  const std::vector<E> expected{{0, 1, 1.0}, {0, 2, 1.5}, {1, 2, 0.5}, {1, 3, 2.0}};
  REQUIRE(g.edges() == expected);
  REQUIRE(g.csr_offsets() == std::vector<std::int32_t>{0, 2, 5, 7, 8, 8});
  REQUIRE(g.csr_adjacency() == std::vector<std::int32_t>{1, 2, 0, 2, 3, 0, 1, 1});
  REQUIRE(g.degree(4) == 0);
  REQUIRE(g.neighbors(4).empty());
  REQUIRE(g.positions().empty());
  REQUIRE(g.kinds().empty());
  REQUIRE(g.edge_rounds().empty());
}

TEST_CASE("Graph::from_edges: edge_rounds are reordered with the edges", "[graph]") {
  std::mt19937 rng(777);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = std::uniform_int_distribution<int>(2, 15)(rng);
    std::vector<E> edges = random_simple_edges(rng, n, 0.4);
    std::shuffle(edges.begin(), edges.end(), rng);
    // The round of an edge is a function of its endpoints, so we can check it after reordering.
    auto round_of = [n](int u, int v) {
      return static_cast<std::uint8_t>((std::min(u, v) * n + std::max(u, v)) % 251);
    };
    std::vector<std::uint8_t> rounds;
    for (E& e : edges) {
      rounds.push_back(round_of(e.u, e.v));
      if (rng() & 1u) std::swap(e.u, e.v);
    }
    const G g = G::from_edges(n, edges, false, {}, {}, rounds);
    REQUIRE(g.edge_rounds().size() == g.edges().size());
    for (std::size_t i = 0; i < g.edges().size(); ++i) {
      REQUIRE(g.edge_rounds()[i] == round_of(g.edges()[i].u, g.edges()[i].v));
    }
  }
}

TEST_CASE("Graph::from_edges: positions and kinds are kept", "[graph]") {
  const std::vector<G::Point> pos{G::Point(1, 2), G::Point(3, 4), G::Point(5, 6)};
  const std::vector<cge::NodeKind> kinds{cge::NodeKind::semantic, cge::NodeKind::feature,
                                         cge::NodeKind::representation};
  const G g = G::from_edges(3, {{2, 0, 1.0}}, true, pos, kinds);
  REQUIRE(g.positions() == pos);
  REQUIRE(g.kinds() == kinds);
  // Same structure with other positions is a different graph.
  std::vector<G::Point> moved = pos;
  moved[1] = G::Point(3, 5);
  REQUIRE(G::from_edges(3, {{2, 0, 1.0}}, true, moved, kinds) != g);
  REQUIRE(G::from_edges(3, {{0, 2, 1.0}}, true, pos, kinds) == g);
  REQUIRE(G::from_edges(3, {{0, 2, 2.0}}, true, pos, kinds) != g);
  REQUIRE(G::from_edges(3, {{0, 2, 1.0}}, false, pos, kinds) != g);
}

TEST_CASE("Graph: empty and edgeless graphs", "[graph]") {
  const G def;
  REQUIRE(def.empty());
  REQUIRE(def.num_nodes() == 0);
  REQUIRE(def.num_edges() == 0);
  const G zero = G::from_edges(0, {}, false);
  REQUIRE(zero.empty());
  REQUIRE(zero.csr_offsets() == std::vector<std::int32_t>{0});
  const G isolated = G::from_edges(4, {}, false);
  REQUIRE_FALSE(isolated.empty());
  for (int v = 0; v < 4; ++v) REQUIRE(isolated.degree(v) == 0);
}

TEST_CASE("Graph::from_edges: invalid edges are rejected with a message naming the edge", "[graph][errors]") {
  SECTION("self-loop") {
    const std::string msg = invalid_argument_message([] {
      G::from_edges(4, {{0, 1, 1.0}, {1, 2, 1.0}, {3, 3, 1.0}}, true);
    });
    CHECK_THAT(msg, Catch::Contains("edge #2") && Catch::Contains("(3, 3)") && Catch::Contains("self-loop"));
  }
  SECTION("repeated edge, same orientation") {
    const std::string msg = invalid_argument_message([] {
      G::from_edges(4, {{0, 1, 1.0}, {1, 2, 1.0}, {0, 1, 2.0}}, true);
    });
    CHECK_THAT(msg, Catch::Contains("edge #2") && Catch::Contains("edge #0") && Catch::Contains("repeats"));
  }
  SECTION("repeated edge, reversed orientation") {
    const std::string msg = invalid_argument_message([] {
      G::from_edges(4, {{2, 3, 1.0}, {1, 2, 1.0}, {3, 2, 1.0}}, true);
    });
    CHECK_THAT(msg, Catch::Contains("edge #2") && Catch::Contains("edge #0") && Catch::Contains("repeats"));
  }
  SECTION("endpoint beyond the node count") {
    const std::string msg = invalid_argument_message([] { G::from_edges(3, {{0, 1, 1.0}, {1, 3, 1.0}}, true); });
    CHECK_THAT(msg, Catch::Contains("edge #1") && Catch::Contains("(1, 3)") && Catch::Contains("[0, 3)"));
  }
  SECTION("negative endpoint") {
    const std::string msg = invalid_argument_message([] { G::from_edges(3, {{-1, 1, 1.0}}, true); });
    CHECK_THAT(msg, Catch::Contains("edge #0") && Catch::Contains("(-1, 1)"));
  }
  SECTION("any edge in a graph without nodes") {
    const std::string msg = invalid_argument_message([] { G::from_edges(0, {{0, 1, 1.0}}, true); });
    CHECK_THAT(msg, Catch::Contains("edge #0"));
  }
  SECTION("negative weight") {
    const std::string msg = invalid_argument_message([] { G::from_edges(3, {{0, 1, 1.0}, {1, 2, -0.5}}, true); });
    CHECK_THAT(msg, Catch::Contains("edge #1") && Catch::Contains("(1, 2)") && Catch::Contains("weight"));
  }
  SECTION("NaN weight") {
    const std::string msg = invalid_argument_message([] {
      G::from_edges(3, {{0, 1, std::numeric_limits<double>::quiet_NaN()}, {1, 2, 1.0}}, true);
    });
    CHECK_THAT(msg, Catch::Contains("edge #0") && Catch::Contains("(0, 1)") && Catch::Contains("weight"));
  }
  SECTION("infinite weight") {
    const std::string msg = invalid_argument_message([] {
      G::from_edges(3, {{0, 1, 1.0}, {2, 1, std::numeric_limits<double>::infinity()}}, true);
    });
    CHECK_THAT(msg, Catch::Contains("edge #1") && Catch::Contains("weight"));
  }
  SECTION("float graphs check weights too") {
    CHECK_THROWS_AS(cge::Graph<float>::from_edges(2, {{0, 1, -1.0f}}, true), std::invalid_argument);
    CHECK_THROWS_AS(cge::Graph<float>::from_edges(2, {{0, 1, std::numeric_limits<float>::quiet_NaN()}}, true),
                    std::invalid_argument);
  }
}

TEST_CASE("Graph::from_edges: inconsistent side arrays are rejected", "[graph][errors]") {
  CHECK_THAT(invalid_argument_message([] { G::from_edges(-1, {}, false); }), Catch::Contains("negative"));
  CHECK_THAT(invalid_argument_message([] { G::from_edges(3, {}, false, {G::Point(0, 0)}); }),
             Catch::Contains("positions"));
  CHECK_THAT(invalid_argument_message([] { G::from_edges(2, {}, false, {}, {cge::NodeKind::feature}); }),
             Catch::Contains("kinds"));
  CHECK_THAT(invalid_argument_message([] {
               G::from_edges(3, {{0, 1, 1.0}}, false, {}, {}, {1, 2});
             }),
             Catch::Contains("edge_rounds"));
}
