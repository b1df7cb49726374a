// Tests of the all-sources block-BFS kernels behind shortest_path_degree_sums (kernels/block_bfs.hpp,
// portable; kernels/block_bfs_avx512.hpp, where the CPU has AVX-512): each against path
// enumeration, and bit for bit against the plain reference (reference_degree_degree_entropy.hpp)
// and each other, on float graphs, on huge path counts, and the error for a kernel that cannot run.
#include <catch2/catch.hpp>

#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/reference_degree_degree_entropy.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/graph/graph.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

TEST_CASE("degree sum kernels: each available kernel agrees with path enumeration", "[dde][oracle][kernel]") {
  if (!cge::degree_sum_kernel_available(cge::DegreeSumKernel::avx512)) {
    WARN("skipped for the avx512 kernel: this CPU or build cannot run it; the portable kernel is checked");
  }
  std::vector<SmallGraph> zoo = small_graph_zoo(150);
  std::mt19937 rng(515);
  for (const int n : {63, 64, 65, 129}) zoo.push_back(random_connected(rng, n, n / 4, "block"));
  for (const SmallGraph& sg : zoo) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      const OracleTable expected = oracle_delta(sg, mode);
      for (const cge::DegreeSumKernel kernel : available_kernels()) {
        INFO("kernel " << kernel_name(kernel) << ", graph " << sg.name << ", ties " << tie_name(mode));
        require_table_matches(cge::shortest_path_degree_sums(g, mode, kernel), expected);
      }
    }
  }
}

TEST_CASE("degree sum kernels: bit for bit equal to the plain reference and to each other", "[dde][kernel]") {
  std::mt19937 rng(2718);
  std::vector<SmallGraph> graphs;
  graphs.push_back(geometric_graph(300, 11));
  graphs.push_back(geometric_graph(700, 12));  // 11 blocks of 64 sources
  graphs.push_back(grid_graph(20, 20));        // ties everywhere
  graphs.push_back(with_random_chords(rng, grid_graph(12, 15), 12));
  // Many lanes per node and per predecessor: more than 16 and more than 32 of the 64.
  graphs.push_back(complete_bipartite(3, 70));
  graphs.push_back(relabel(complete_bipartite(20, 110), random_permutation(rng, 130)));
  graphs.push_back(star_of_cliques(6, 9));  // degrees up to 54
  {
    SmallGraph g = disjoint_union(grid_graph(7, 9), disjoint_union(random_connected(rng, 90, 30, "d"), isolated(4)));
    graphs.push_back(relabel(g, random_permutation(rng, g.n)));  // blocks straddle components
  }
  graphs.push_back(random_gnp(rng, 200, 0.012, "sparse"));  // many small components
  // Path counts far beyond 2^53 with many significant bits (6^120, 7^100, about C(70, 35)), times
  // degree differences that are not powers of two (10, 12, 3, 5, ...): products and sums round, so
  // a fused multiply-add or another order of three or more predecessors shows (both checked by
  // planting them in the kernel).
  graphs.push_back(diamond_chain(6, 120));
  graphs.push_back(diamond_chain(7, 100));
  graphs.push_back(decorated_grid(36, 36, false));
  graphs.push_back(decorated_grid(36, 36, true));
  for (int i = 0; i < 20; ++i) {
    graphs.push_back(random_gnp(rng, std::uniform_int_distribution<int>(2, 160)(rng),
                                std::uniform_real_distribution<double>(0.01, 0.3)(rng), "r" + std::to_string(i)));
  }
  long long compared = 0;
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      const cge::DegreeSumTable expected = cge::reference_degree_sums(to_graph(sg), mode);
      for (const cge::DegreeSumKernel kernel : available_kernels()) {
        INFO("kernel " << kernel_name(kernel) << ", graph " << sg.name << " (" << sg.n << " nodes), ties "
                       << tie_name(mode));
        const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, mode, kernel);
        REQUIRE(same_bits(table, expected));
        compared += static_cast<long long>(table.values.size());
      }
    }
  }
  CHECK(compared > 100000);
}

TEST_CASE("degree sum kernels: graphs with float weights and DegreeDegreeEntropy<float>", "[dde][kernel]") {
  std::mt19937 rng(31);
  for (const SmallGraph& sg :
       {geometric_graph(200, 5), grid_graph(9, 11), complete_bipartite(4, 40), random_gnp(rng, 120, 0.03, "f")}) {
    std::vector<cge::Edge<float>> edges;
    for (const auto& [u, v] : sg.edges) edges.push_back(cge::Edge<float>{u, v, 1.0f});
    const cge::Graph<float> gf = cge::Graph<float>::from_edges(sg.n, edges, false);
    for (const TieMode mode : kTieModes) {
      const cge::DegreeSumTable expected = cge::reference_degree_sums(to_graph(sg), mode);
      cge::DegreeDegreeSettings<float> settings;
      settings.ties = mode;
      const cge::DegreeDegreeEntropy<float> dde(settings);
      const cge::DegreeDegreeResult<float> by_default = dde.compute(gf);
      for (const cge::DegreeSumKernel kernel : available_kernels()) {
        INFO("kernel " << kernel_name(kernel) << ", graph " << sg.name << ", ties " << tie_name(mode));
        const cge::DegreeSumTable table = cge::shortest_path_degree_sums(gf, mode, kernel);
        REQUIRE(same_bits(table, expected));
        const cge::DegreeDegreeResult<float> r = dde.from_table(table);
        REQUIRE(r.exponents == by_default.exponents);
        REQUIRE(r.entropy_bits == by_default.entropy_bits);
        REQUIRE(r.information_index == by_default.information_index);
      }
    }
  }
}

TEST_CASE("degree sum kernels: huge path counts (overflow, exact rescaling) behave the same",
          "[dde][kernel][numerics]") {
  // 8^345 = 2^1035 shortest paths: TieMode::all overflows to inf (and the entropy reports it),
  // TieMode::mean rescales whole levels by 2^-512, TieMode::min needs no counts.
  const SmallGraph sg = diamond_chain(8, 345);
  const cge::Graph<double> g = to_graph(sg);
  for (const TieMode mode : {TieMode::mean, TieMode::min}) {
    const cge::DegreeSumTable expected = cge::reference_degree_sums(to_graph(sg), mode);
    for (const cge::DegreeSumKernel kernel : available_kernels()) {
      INFO("kernel " << kernel_name(kernel) << ", ties " << tie_name(mode));
      REQUIRE(same_bits(cge::shortest_path_degree_sums(g, mode, kernel), expected));
    }
  }
  cge::DegreeDegreeSettings<double> all;
  all.ties = TieMode::all;
  for (const cge::DegreeSumKernel kernel : available_kernels()) {
    INFO("kernel " << kernel_name(kernel));
    const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, TieMode::all, kernel);
    CHECK_THROWS_AS(cge::DegreeDegreeEntropy<double>(all).from_table(table), std::overflow_error);
  }
}

TEST_CASE("degree sum kernels: availability and an explicit request that cannot run", "[dde][kernel][errors]") {
  CHECK(cge::degree_sum_kernel_available(cge::DegreeSumKernel::automatic));
  CHECK(cge::degree_sum_kernel_available(cge::DegreeSumKernel::portable));
  const cge::Graph<double> g = to_graph(path_graph(4));
  if (cge::degree_sum_kernel_available(cge::DegreeSumKernel::avx512)) {
    CHECK(same_bits(cge::shortest_path_degree_sums(g, TieMode::all, cge::DegreeSumKernel::avx512),
                    cge::shortest_path_degree_sums(g, TieMode::all, cge::DegreeSumKernel::portable)));
    WARN("skipped: the avx512 kernel runs here, so the error for an unavailable kernel is not exercised");
  } else {
    const std::string message = cge_test::invalid_argument_message(
        [&] { cge::shortest_path_degree_sums(g, TieMode::all, cge::DegreeSumKernel::avx512); });
    CHECK_THAT(message, Catch::Contains("avx512") && Catch::Contains("AVX-512"));
  }
  CHECK_THROWS_AS(cge::shortest_path_degree_sums(cge::Graph<double>{}, TieMode::all, cge::DegreeSumKernel::portable),
                  std::invalid_argument);
}
