// Tests of ShannonEdgeEntropy (docs/METHOD.md section 5): H_W = -sum p_l log2 p_l, p_l = w_l / sum w.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/graph/graph.hpp"

namespace {

/// The textbook formula, in long double, skipping zero weights.
long double naive_entropy(const std::vector<double>& w) {
  long double total = 0;
  for (double x : w) total += x;
  if (total == 0) return 0;
  long double h = 0;
  for (double x : w) {
    if (x == 0) continue;
    const long double p = x / total;
    h -= p * std::log2(p);
  }
  return h;
}

cge::Graph<double> weighted_graph(int n, const std::vector<cge::Edge<double>>& edges) {
  return cge::Graph<double>::from_edges(n, edges, true);
}

}  // namespace

TEST_CASE("ShannonEdgeEntropy: unit square with and without a diagonal", "[shannon][spec]") {
  const cge::ShannonEdgeEntropy<double> h;
  const std::vector<cge::Edge<double>> square{{0, 1, 1.0}, {1, 2, 1.0}, {2, 3, 1.0}, {3, 0, 1.0}};
  REQUIRE(h.compute(weighted_graph(4, square)) == Approx(2.0).epsilon(1e-15));
  std::vector<cge::Edge<double>> with_diagonal = square;
  with_diagonal.push_back({0, 2, std::sqrt(2.0)});
  REQUIRE(h.compute(weighted_graph(4, with_diagonal)) == Approx(2.30614985795795).epsilon(1e-13));
  // The same through the bare-weights entry point and in single precision.
  REQUIRE(h.compute_from_weights({1, 1, 1, 1, std::sqrt(2.0)}) == Approx(2.30614985795795).epsilon(1e-13));
  const std::vector<cge::Edge<float>> with_diagonal_f{
      {0, 1, 1.0f}, {1, 2, 1.0f}, {2, 3, 1.0f}, {3, 0, 1.0f}, {0, 2, std::sqrt(2.0f)}};
  REQUIRE(cge::ShannonEdgeEntropy<float>().compute(cge::Graph<float>::from_edges(4, with_diagonal_f, true)) ==
          Approx(2.30614985795795).epsilon(1e-6));
}

TEST_CASE("ShannonEdgeEntropy: degenerate inputs", "[shannon]") {
  const cge::ShannonEdgeEntropy<double> h;
  SECTION("no edges") {
    CHECK(h.compute(cge::Graph<double>()) == 0.0);
    CHECK(h.compute(weighted_graph(5, {})) == 0.0);
    CHECK(h.compute_from_weights({}) == 0.0);
  }
  SECTION("one edge") { CHECK(h.compute(weighted_graph(2, {{0, 1, 3.5}})) == 0.0); }
  SECTION("zero-length edges are skipped") {
    // Two unit edges plus two zero-length ones: 1 bit, as for the two unit edges alone.
    CHECK(h.compute(weighted_graph(5, {{0, 1, 0.0}, {1, 2, 1.0}, {2, 3, 0.0}, {3, 4, 1.0}})) ==
          Approx(1.0).epsilon(1e-15));
    CHECK(h.compute_from_weights({0.0, 2.0, 0.0, 2.0, 2.0, 2.0}) == Approx(2.0).epsilon(1e-15));
    // Only zero-length edges: no probability mass at all.
    CHECK(h.compute_from_weights({0.0, 0.0, 0.0}) == 0.0);
    CHECK(h.compute(weighted_graph(3, {{0, 1, 0.0}, {1, 2, 0.0}})) == 0.0);
  }
  SECTION("equal weights give log2 of the edge count") {
    for (int m = 1; m <= 40; ++m) {
      CHECK(h.compute_from_weights(std::vector<double>(static_cast<std::size_t>(m), 7.25)) ==
            Approx(std::log2(static_cast<double>(m))).epsilon(1e-14).margin(1e-15));
    }
  }
}

TEST_CASE("ShannonEdgeEntropy: invalid weights throw", "[shannon][errors]") {
  const cge::ShannonEdgeEntropy<double> h;
  CHECK_THROWS_AS(h.compute_from_weights({1.0, -1.0}), std::invalid_argument);
  CHECK_THROWS_AS(h.compute_from_weights({1.0, -1e-300}), std::invalid_argument);
  CHECK_THROWS_AS(h.compute_from_weights({std::numeric_limits<double>::quiet_NaN()}), std::invalid_argument);
  CHECK_THROWS_AS(h.compute_from_weights({1.0, std::numeric_limits<double>::infinity()}), std::invalid_argument);
  CHECK_THROWS_WITH(h.compute_from_weights({1.0, -1.0}), Catch::Contains("weight"));
  // A graph cannot even hold a negative weight.
  CHECK_THROWS_AS(weighted_graph(2, {{0, 1, -2.0}}), std::invalid_argument);
}

TEST_CASE("ShannonEdgeEntropy agrees with the textbook formula on random weights", "[shannon][oracle]") {
  std::mt19937 rng(2718);
  const cge::ShannonEdgeEntropy<double> h;
  for (int trial = 0; trial < 500; ++trial) {
    const int m = std::uniform_int_distribution<int>(1, 300)(rng);
    // Mix of scales, including heavy-tailed weights and some zero-length edges.
    const int style = trial % 4;
    std::vector<double> w(static_cast<std::size_t>(m));
    for (double& x : w) {
      switch (style) {
        case 0:
          x = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
          break;
        case 1:
          x = std::uniform_real_distribution<double>(1.0, 800.0)(rng);
          break;
        case 2:
          x = std::exp(std::uniform_real_distribution<double>(-20.0, 20.0)(rng));
          break;
        default:
          x = (rng() % 5 == 0) ? 0.0 : std::uniform_real_distribution<double>(0.0, 50.0)(rng);
          break;
      }
    }
    const long double expected = naive_entropy(w);
    INFO("trial " << trial << ", " << m << " weights, style " << style);
    const double got = h.compute_from_weights(w);
    REQUIRE(std::abs(static_cast<long double>(got) - expected) <= 1e-12L * std::max<long double>(1, expected));
    // Through a graph: a path with these weights.
    std::vector<cge::Edge<double>> edges;
    for (int i = 0; i < m; ++i) edges.push_back({i, i + 1, w[static_cast<std::size_t>(i)]});
    REQUIRE(h.compute(weighted_graph(m + 1, edges)) == got);
    // Scale invariance: p_l does not change when every length is multiplied by a power of two.
    std::vector<double> scaled = w;
    for (double& x : scaled) x *= 1024.0;
    REQUIRE(h.compute_from_weights(scaled) == Approx(got).epsilon(1e-13).margin(1e-14));
    // Bounds.
    REQUIRE(got >= -1e-13);
    REQUIRE(got <= std::log2(static_cast<double>(m)) + 1e-12);
  }
}
