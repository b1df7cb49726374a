// Tests of the single-source BFS kernels that DegreeDegreeEntropy::compute_index runs
// (kernels/single_source_bfs.hpp on neighbour lists, kernels/single_source_bitset_bfs.hpp on
// adjacency bitsets): bit for bit the plain reference (reference_degree_degree_entropy.hpp), runs
// stopped after any level, the level lists, and node terms symmetric in the pair.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "cge/entropy/kernels/single_source_bfs.hpp"
#include "cge/entropy/kernels/single_source_bitset_bfs.hpp"
#include "cge/entropy/reference_degree_degree_entropy.hpp"
#include "cge/graph/graph.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

namespace {

/// Layers of `width` nodes, each node joined to 2..4 random nodes of the layer before: path counts
/// pass 2^53 after a few dozen layers and differ from node to node, so sums round and the order in
/// which a node adds its predecessors shows in the last bits (with integer-exact values any order
/// gives the same bits, and an order test could not fail).
SmallGraph random_layered(std::mt19937& rng, int layers, int width) {
  SmallGraph g{"layered " + std::to_string(layers) + "x" + std::to_string(width), layers * width, {}};
  std::uniform_int_distribution<int> pick(0, width - 1), fan(2, 4);
  for (int layer = 1; layer < layers; ++layer) {
    for (int i = 0; i < width; ++i) {
      std::set<int> preds;
      const int want = fan(rng);
      while (static_cast<int>(preds.size()) < want) preds.insert(pick(rng));
      for (const int p : preds) g.edges.push_back({(layer - 1) * width + p, layer * width + i});
    }
  }
  return g;
}

/// Graphs for the single-source kernels: the zoo, the tie-rich families, huge counts, and node
/// orders that give the bitset kernel both short rows (GraphBuilder's canonical order) and rows
/// that span every word (a random relabelling), with more than 64 nodes and isolated nodes.
std::vector<SmallGraph> single_source_graphs(std::mt19937& rng) {
  std::vector<SmallGraph> graphs = small_graph_zoo(60);
  graphs.push_back(geometric_graph(300, 11));
  graphs.push_back(relabel(geometric_graph(200, 12), random_permutation(rng, 200)));
  graphs.push_back(with_random_chords(rng, grid_graph(12, 15), 12));
  graphs.push_back(star_of_cliques(6, 9));
  graphs.push_back(diamond_chain(6, 120));  // products and sums that round
  graphs.push_back(diamond_chain(8, 345));  // TieMode::mean rescales, TieMode::all overflows
  graphs.push_back(decorated_grid(20, 20, true));
  graphs.push_back(disjoint_union(geometric_graph(150, 13), isolated(70)));
  graphs.push_back(random_layered(rng, 60, 5));
  graphs.push_back(relabel(random_layered(rng, 50, 6), random_permutation(rng, 300)));
  return graphs;
}

/// Runs every source of g twice with the kernel, in random order: first stopped after a random
/// level (its deltas so far must be the reference row's), then in full (the whole row). A stopped
/// run must leave nothing behind that changes a later one.
template <TieMode Mode, template <TieMode, typename> class Kernel>
void require_stopped_runs_match(std::mt19937& rng, const cge::Graph<double>& g, const cge::DegreeSumTable& ref) {
  KernelFor<Mode, Kernel> kernel(g);
  auto& sums = kernel.sums;
  const std::vector<int> sources = random_permutation(rng, g.num_nodes());
  for (const int s : sources) {
    const std::int32_t ecc = ref.eccentricity(s);
    const std::int32_t stop = std::uniform_int_distribution<std::int32_t>(1, std::max(ecc, 1))(rng);
    std::int32_t calls = 0;
    const std::int32_t last = sums.run(s, [&](std::int32_t k, double delta) {
      ++calls;
      REQUIRE(k <= ecc);
      REQUIRE(std::memcmp(&delta, &ref.values[static_cast<std::size_t>(ref.row_offsets[s] + k - 1)], sizeof delta) ==
              0);
      return k < stop;
    });
    REQUIRE(last == std::min(stop, ecc));
    REQUIRE(calls == last);
    std::int32_t full_calls = 0;
    REQUIRE(sums.run(s, [&](std::int32_t k, double delta) {
      ++full_calls;
      REQUIRE(std::memcmp(&delta, &ref.values[static_cast<std::size_t>(ref.row_offsets[s] + k - 1)], sizeof delta) ==
              0);
      return true;
    }) == ecc);
    REQUIRE(full_calls == ecc);
  }
}

template <TieMode Mode>
void require_bitset_kernel_matches(std::mt19937& rng, const SmallGraph& sg) {
  const cge::Graph<double> g = to_graph(sg);
  const cge::DegreeSumTable ref = cge::reference_degree_sums(to_graph(sg), Mode);
  REQUIRE(same_bits(single_source_table<Mode, cge::detail::SingleSourceBitsetBfsDegreeSums>(g), ref));
  require_stopped_runs_match<Mode, cge::detail::SingleSourceBitsetBfsDegreeSums>(rng, g, ref);
  require_stopped_runs_match<Mode, cge::detail::SingleSourceBfsDegreeSums>(rng, g, ref);
}

/// Hop distances from every node by plain BFS (-1: unreachable).
std::vector<std::vector<int>> all_distances(const SmallGraph& sg) {
  std::vector<std::vector<int>> adj(static_cast<std::size_t>(sg.n));
  for (const auto& [u, v] : sg.edges) {
    adj[static_cast<std::size_t>(u)].push_back(v);
    adj[static_cast<std::size_t>(v)].push_back(u);
  }
  std::vector<std::vector<int>> dist(static_cast<std::size_t>(sg.n),
                                     std::vector<int>(static_cast<std::size_t>(sg.n), -1));
  for (int s = 0; s < sg.n; ++s) {
    std::vector<int>& d = dist[static_cast<std::size_t>(s)];
    std::vector<int> queue{s};
    d[static_cast<std::size_t>(s)] = 0;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      for (const int w : adj[static_cast<std::size_t>(queue[h])]) {
        if (d[static_cast<std::size_t>(w)] < 0) {
          d[static_cast<std::size_t>(w)] = d[static_cast<std::size_t>(queue[h])] + 1;
          queue.push_back(w);
        }
      }
    }
  }
  return dist;
}

/// During every level of every source: level_begin()..level_end() are exactly the nodes at that
/// distance, ascending; Delta(s, k) is their node terms summed in that order, bit for bit; and the
/// term of (s, u) equals the term of (u, s), the symmetry weight_bounded_entropy builds on.
template <TieMode Mode, template <TieMode, typename> class Kernel>
void require_levels_and_symmetric_terms(const SmallGraph& sg) {
  const cge::Graph<double> g = to_graph(sg);
  const std::vector<std::vector<int>> dist = all_distances(sg);
  const std::size_t n = static_cast<std::size_t>(sg.n);
  std::vector<double> term(n * n, -1.0);
  KernelFor<Mode, Kernel> kernel(g);
  auto& sums = kernel.sums;
  for (int s = 0; s < sg.n; ++s) {
    sums.run(s, [&](std::int32_t k, double delta) {
      std::vector<std::int32_t> expected;
      for (int u = 0; u < sg.n; ++u) {
        if (dist[static_cast<std::size_t>(s)][static_cast<std::size_t>(u)] == k) expected.push_back(u);
      }
      REQUIRE(std::vector<std::int32_t>(sums.level_begin(), sums.level_end()) == expected);
      double layer = 0.0;
      for (const std::int32_t u : expected) {
        const double t = sums.node_term(u);
        layer += t;
        term[static_cast<std::size_t>(s) * n + static_cast<std::size_t>(u)] = t;
      }
      REQUIRE(std::memcmp(&layer, &delta, sizeof layer) == 0);
      return true;
    });
  }
  for (std::size_t s = 0; s < n; ++s) {
    for (std::size_t u = 0; u < n; ++u) {
      if (dist[s][u] <= 0) continue;
      INFO("pair " << s << ", " << u);
      REQUIRE(term[s * n + u] == Approx(term[u * n + s]).epsilon(1e-13));
    }
  }
}

}  // namespace

TEST_CASE("SingleSourceBfsDegreeSums: bit for bit the plain reference, and stops when asked", "[dde][kernel]") {
  std::mt19937 rng(31337);
  std::vector<SmallGraph> graphs = small_graph_zoo(60);
  graphs.push_back(geometric_graph(300, 11));
  graphs.push_back(with_random_chords(rng, grid_graph(12, 15), 12));
  graphs.push_back(star_of_cliques(6, 9));
  graphs.push_back(diamond_chain(6, 120));  // products and sums that round
  graphs.push_back(diamond_chain(8, 345));  // TieMode::mean rescales, TieMode::all overflows
  graphs.push_back(decorated_grid(20, 20, true));
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO(sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode));
      REQUIRE(same_bits(single_source_table(g, mode), cge::reference_degree_sums(to_graph(sg), mode)));
    }
  }
  // A run stopped after level 2 makes no further call, returns 2, and leaves the next run intact.
  const SmallGraph sg = grid_graph(6, 7);
  const cge::Graph<double> g = to_graph(sg);
  cge::detail::SingleSourceBfsDegreeSums<TieMode::all, double> sums(g);
  int calls = 0;
  CHECK(sums.run(0, [&](std::int32_t k, double) {
    ++calls;
    return k < 2;
  }) == 2);
  CHECK(calls == 2);
  CHECK(same_bits(single_source_table(g, TieMode::all), cge::reference_degree_sums(to_graph(sg), TieMode::all)));
}

TEST_CASE("SingleSourceBitsetBfsDegreeSums: bit for bit the plain reference, stopped anywhere", "[dde][kernel]") {
  std::mt19937 rng(4242);
  for (const SmallGraph& sg : single_source_graphs(rng)) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    require_bitset_kernel_matches<TieMode::all>(rng, sg);
    require_bitset_kernel_matches<TieMode::mean>(rng, sg);
    require_bitset_kernel_matches<TieMode::min>(rng, sg);
  }
}

TEST_CASE("single-source kernels: the level lists, and node terms symmetric in the pair", "[dde][kernel]") {
  std::mt19937 rng(5151);
  std::vector<SmallGraph> graphs = small_graph_zoo(30);
  graphs.push_back(geometric_graph(150, 14));
  graphs.push_back(relabel(geometric_graph(120, 15), random_permutation(rng, 120)));
  graphs.push_back(decorated_grid(8, 9, true));
  graphs.push_back(with_planted_twins(rng, star_of_cliques(3, 5), 4));
  for (const SmallGraph& sg : graphs) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    require_levels_and_symmetric_terms<TieMode::all, cge::detail::SingleSourceBfsDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::mean, cge::detail::SingleSourceBfsDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::min, cge::detail::SingleSourceBfsDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::all, cge::detail::SingleSourceBitsetBfsDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::mean, cge::detail::SingleSourceBitsetBfsDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::min, cge::detail::SingleSourceBitsetBfsDegreeSums>(sg);
  }
}
