// Tests of AdjacencyBitsets (cge/graph/adjacency_bitsets.hpp): the rows are the neighbour sets,
// stored over tight word spans, and rows_pay picks them on GraphBuilder's node order only.
#include <catch2/catch.hpp>

#include <cstdint>
#include <random>
#include <set>

#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/graph.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

TEST_CASE("AdjacencyBitsets: the rows are the neighbour sets, and pay on short rows only", "[dde][kernel]") {
  std::mt19937 rng(6161);
  const SmallGraph built = geometric_graph(1000, 16);
  const SmallGraph shuffled = relabel(built, random_permutation(rng, built.n));
  CHECK(cge::AdjacencyBitsets::rows_pay(to_graph(built)));
  CHECK_FALSE(cge::AdjacencyBitsets::rows_pay(to_graph(shuffled)));
  CHECK_FALSE(cge::AdjacencyBitsets::rows_pay(cge::Graph<double>{}));
  for (const SmallGraph& sg : {built, shuffled, disjoint_union(star_of_cliques(3, 30), isolated(70))}) {
    const cge::Graph<double> g = to_graph(sg);
    const cge::AdjacencyBitsets rows(g);
    REQUIRE(rows.words() == (static_cast<std::size_t>(sg.n) + 63) / 64);
    std::size_t stored = 0;
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
      std::set<std::int32_t> expected(g.neighbors(v).begin(), g.neighbors(v).end());
      std::set<std::int32_t> found;
      const cge::AdjacencyBitsets::Span span = rows.span(v);
      for (std::size_t w = span.first; w < span.end; ++w) {
        for (int b = 0; b < 64; ++b) {
          if ((rows.stored_row(v)[w - span.first] >> b) & 1u)
            found.insert(static_cast<std::int32_t>(w * 64 + static_cast<std::size_t>(b)));
        }
      }
      REQUIRE(found == expected);
      if (!expected.empty()) {  // the span is tight: its first and last words hold a neighbour
        REQUIRE(span.first == static_cast<std::size_t>(*expected.begin()) / 64);
        REQUIRE(span.end == static_cast<std::size_t>(*expected.rbegin()) / 64 + 1);
      } else {
        REQUIRE(span.end == span.first);
      }
      stored += span.end - span.first;
    }
    REQUIRE(rows.stored_words() == stored);
  }
}
