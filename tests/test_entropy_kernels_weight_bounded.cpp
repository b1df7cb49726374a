// Tests of weight_bounded_entropy (kernels/weight_bounded_entropy.hpp), the search behind
// DegreeDegreeEntropy::compute_index: the same bits with either single-source kernel, and searches
// skipped by the terms other searches hand over. What its result must be is checked through
// compute_index in test_degree_degree_entropy.cpp.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cge/entropy/kernels/single_source_bfs.hpp"
#include "cge/entropy/kernels/single_source_bitset_bfs.hpp"
#include "cge/entropy/kernels/weight_bounded_entropy.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/hop_diameter.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

namespace {

template <TieMode Mode>
void require_kernels_agree_on_bounded_entropy(const cge::Graph<double>& g, const std::vector<double>& c, double alpha,
                                              double cut, int& graphs_with_skips) {
  using cge::detail::SingleSourceBitsetBfsDegreeSums;
  using cge::detail::SingleSourceBfsDegreeSums;
  const double log_alpha = std::log(alpha);
  KernelFor<Mode, SingleSourceBfsDegreeSums> list_kernel(g);
  KernelFor<Mode, SingleSourceBitsetBfsDegreeSums> bitset_kernel(g);
  const auto list = cge::detail::weight_bounded_entropy_with(g, list_kernel.sums, c, log_alpha, cut);
  const auto bits = cge::detail::weight_bounded_entropy_with(g, bitset_kernel.sums, c, log_alpha, cut);
  REQUIRE(std::memcmp(&list.entropy_bits, &bits.entropy_bits, sizeof(double)) == 0);
  REQUIRE(list.exponents_evaluated == bits.exponents_evaluated);
  REQUIRE(list.searches_skipped == bits.searches_skipped);
  graphs_with_skips += list.searches_skipped > 0;
}

}  // namespace

TEST_CASE("weight_bounded_entropy: the same bits with either kernel; other searches' terms skip searches",
          "[dde][index]") {
  // What the result must be is the [index] definition test's business (through compute_index);
  // here: the kernel changes nothing, and the bound from other searches' terms does skip searches.
  std::mt19937 rng(7373);
  std::vector<SmallGraph> graphs;
  for (int i = 0; i < 20; ++i) graphs.push_back(random_connected(rng, 60 + 5 * i, 40 + 3 * i, "r" + std::to_string(i)));
  graphs.push_back(geometric_graph(300, 17));
  graphs.push_back(geometric_graph(600, 18));
  graphs.push_back(with_planted_twins(rng, geometric_graph(250, 19), 40));
  graphs.push_back(decorated_grid(12, 12, true));
  int graphs_with_skips = 0;
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    const cge::HopDiameter d = cge::hop_diameter(g);
    std::vector<double> c(static_cast<std::size_t>(d.diameter) + 1, 0.0);
    for (std::int32_t k = 1; k <= d.diameter; ++k) c[static_cast<std::size_t>(k)] = d.diameter * std::exp(1.0 - k);
    for (const double alpha : {0.5, 0.95}) {
      for (const double cut : {3.0, 100.0}) {
        INFO(sg.name << ", alpha " << alpha << ", G " << cut);
        require_kernels_agree_on_bounded_entropy<TieMode::all>(g, c, alpha, cut, graphs_with_skips);
        require_kernels_agree_on_bounded_entropy<TieMode::mean>(g, c, alpha, cut, graphs_with_skips);
        require_kernels_agree_on_bounded_entropy<TieMode::min>(g, c, alpha, cut, graphs_with_skips);
      }
    }
  }
  CHECK(graphs_with_skips > 30);
}
