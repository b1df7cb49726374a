#include <catch2/catch.hpp>
#include "cge/cge.hpp"
TEST_CASE("smoke: star graph index", "[smoke]") {
  auto g = cge::Graph<double>::from_edges(5, {{0, 1}, {0, 2}, {0, 3}, {0, 4}}, false);
  REQUIRE(cge::DegreeDegreeEntropy<>().compute(g).information_index == Approx(0.2650519561258).epsilon(1e-12));
}
