// Tests of the plain reference (cge/entropy/reference_degree_degree_entropy.hpp), the oracle the
// kernels are held to bit for bit: its Delta table against shortest-path enumeration and a scalar
// BFS in long double, its E, H and I against the direct formula alpha^E, and
// DegreeDegreeEntropy::compute equal to it bit for bit.
#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/reference_degree_degree_entropy.hpp"
#include "cge/graph/graph.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST_CASE("reference_degree_sums agrees with shortest-path enumeration and a scalar BFS", "[dde][oracle][reference]") {
  std::vector<SmallGraph> graphs = small_graph_zoo(150);
  std::mt19937 rng(808);
  for (const int n : {63, 65, 129}) graphs.push_back(random_connected(rng, n, n / 4, "block"));
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO(sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode));
      require_table_matches(cge::reference_degree_sums(g, mode), oracle_delta(sg, mode));
    }
  }
  // Larger and tie-rich graphs, where enumeration is too slow.
  for (const SmallGraph& sg : {geometric_graph(300, 41), decorated_grid(12, 12, true), star_of_cliques(5, 8)}) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO(sg.name << ", ties " << tie_name(mode));
      require_table_matches(cge::reference_degree_sums(g, mode), scalar_bfs_delta(sg, mode));
    }
  }
  // 2^1035 shortest paths: TieMode::min needs no counts, TieMode::mean rescales them exactly.
  const SmallGraph chain = diamond_chain(8, 345);
  require_table_matches(cge::reference_degree_sums(to_graph(chain), TieMode::min),
                        scalar_bfs_delta(chain, TieMode::min));
  if (std::numeric_limits<LD>::max_exponent > 1100) {
    require_table_matches(cge::reference_degree_sums(to_graph(chain), TieMode::mean),
                          scalar_bfs_delta(chain, TieMode::mean));
  }
  CHECK_THROWS_AS(cge::reference_degree_sums(cge::Graph<double>{}), std::invalid_argument);
}

TEST_CASE("reference_degree_degree_entropy agrees with the direct formula alpha^E", "[dde][oracle][reference]") {
  long long checked = 0;
  for (const SmallGraph& sg : small_graph_zoo(60)) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      const OracleTable table = oracle_delta(sg, mode);
      for (const double alpha : {0.5, 0.9, 2.0}) {
        for (const cge::ScalingKind scaling : {cge::ScalingKind::raw, cge::ScalingKind::normalised_mean}) {
          INFO(sg.name << ", ties " << tie_name(mode) << ", alpha " << alpha << ", normalised "
                       << (scaling == cge::ScalingKind::normalised_mean));
          cge::DegreeDegreeSettings<double> s;
          s.alpha = alpha;
          s.lambda = 2.5;
          s.ties = mode;
          const OracleEntropy expected = oracle_entropy(table, &exp_coefficient,
                                                        scaling == cge::ScalingKind::normalised_mean, alpha, 2.5);
          const auto r = cge::reference_degree_degree_entropy(g, s, cge::StandardCoefficients{},
                                                              cge::ExponentScaling{scaling});
          REQUIRE(r.exponents.size() == expected.exponents.size());
          for (std::size_t v = 0; v < r.exponents.size(); ++v) {
            REQUIRE(close(r.exponents[v], expected.exponents[v], 1e-12L));
          }
          REQUIRE(close(r.entropy_bits, expected.entropy, 1e-12L));
          REQUIRE(close(r.information_index, expected.index, 1e-12L));
          REQUIRE(r.diameter == table.diameter);
          REQUIRE(r.connected == table.connected);
          ++checked;
        }
      }
    }
  }
  CHECK(checked > 1000);
}

TEST_CASE("DegreeDegreeEntropy::compute equals the reference bit for bit", "[dde][reference]") {
  std::mt19937 rng(909);
  std::vector<SmallGraph> graphs = small_graph_zoo(40);
  graphs.push_back(geometric_graph(300, 42));
  graphs.push_back(geometric_graph(700, 43));
  graphs.push_back(decorated_grid(15, 15, true));
  graphs.push_back(diamond_chain(6, 120));
  graphs.push_back(disjoint_union(geometric_graph(150, 44), random_gnp(rng, 60, 0.03, "sparse")));
  const cge::CoefficientKind kinds[] = {cge::CoefficientKind::exp, cge::CoefficientKind::linear,
                                        cge::CoefficientKind::constant};
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      for (const cge::CoefficientKind kind : kinds) {
        for (const cge::ScalingKind scaling : {cge::ScalingKind::raw, cge::ScalingKind::normalised_mean}) {
          INFO(sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode) << ", coefficients "
                       << static_cast<int>(kind));
          cge::DegreeDegreeSettings<double> s;
          s.ties = mode;
          s.alpha = 0.7;
          const cge::DegreeDegreeEntropy<double> dde(s, cge::StandardCoefficients{kind}, cge::ExponentScaling{scaling});
          const auto fast = dde.compute(g);
          const auto plain =
              cge::reference_degree_degree_entropy(g, s, cge::StandardCoefficients{kind}, cge::ExponentScaling{scaling});
          REQUIRE(fast.exponents.size() == plain.exponents.size());
          for (std::size_t v = 0; v < fast.exponents.size(); ++v) {
            REQUIRE(same_bits(fast.exponents[v], plain.exponents[v]));
          }
          REQUIRE(same_bits(fast.entropy_bits, plain.entropy_bits));
          REQUIRE(same_bits(fast.information_index, plain.information_index));
          REQUIRE(fast.diameter == plain.diameter);
          REQUIRE(fast.connected == plain.connected);
        }
      }
    }
  }
}
