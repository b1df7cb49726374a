// The degree-degree entropy's kernels one by one (cge/entropy/kernels/), on the graphs the loop
// closer builds (the two ORB-like frames' graphs, a few hundred nodes) and on larger user graphs
// (GraphBuilder's and disc graphs of 2000 and 10000 random points): what each kernel costs, so
// that each one kept is one that pays somewhere (docs/BENCHMARK.md, "Entropy kernels").
//
// All-sources tables (what DegreeDegreeEntropy::compute needs, TieMode::all):
//   BM_DegreeSums_BlockBfs, _BlockBfsAvx512: shortest_path_degree_sums with each block kernel;
//   BM_DegreeSums_SingleSourceBfs, _SingleSourceBitsetBfs: one single-source search per node;
//   BM_DegreeSums_Reference: the plain code of reference_degree_degree_entropy.hpp.
// The bounded search of compute_index (raw exponents, exp coefficients, alpha 0.5, G = 100):
//   BM_BoundedEntropy_SingleSourceBfs, _SingleSourceBitsetBfs: weight_bounded_entropy with each kernel;
//   BM_Index_Default: DegreeDegreeEntropy::compute_index as CGESimilarity calls it (its kernel choice);
//   BM_Index_LoopCloser: the same with LoopCloser's exponents scaled by their mean, which the
//   bounded search cannot serve: the all-sources table runs.

#include <cmath>
#include <cstdint>
#include <map>
#include <type_traits>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_data.hpp"
#include "cge/entropy/cge_similarity.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/kernels/single_source_bfs.hpp"
#include "cge/entropy/kernels/single_source_bitset_bfs.hpp"
#include "cge/entropy/kernels/weight_bounded_entropy.hpp"
#include "cge/entropy/reference_degree_degree_entropy.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/hop_diameter.hpp"

namespace {

using cge::TieMode;

enum class Input {
  frame,    ///< Arg 0 or 1: the graph of ORB-like frame 0 or 1, built as CGESimilarity::score builds it
  builder,  ///< Arg n: GraphBuilder's graph of n random points (cge_bench::rgg_graph)
  disc,     ///< Arg n: the disc graph of the same points (cge_bench::disc_graph)
};

const cge::Graph<double>& frame_graph(int which) {
  static std::map<int, cge::Graph<double>> cache;
  auto it = cache.find(which);
  if (it != cache.end()) return it->second;
  const cge::CGESimilarity<double> similarity;
  const cge_bench::Frame& own = cge_bench::orb_frame(which);
  const cge_bench::Frame& other = cge_bench::orb_frame(1 - which);
  cge::Graph<double> g = similarity.graph_builder.build(cge_bench::image_region(), own.keypoints, own.dynamic_mask,
                                                        other.dynamic_mask, own.instances);
  return cache.emplace(which, std::move(g)).first->second;
}

const cge::Graph<double>& input_graph(Input input, int arg) {
  if (input == Input::frame) return frame_graph(arg);
  return cge_bench::family_graph(input == Input::builder ? cge_bench::GraphFamily::builder : cge_bench::GraphFamily::disc,
                                 arg);
}

void counters(benchmark::State& state, const cge::Graph<double>& g) {
  state.counters["nodes"] = g.num_nodes();
  state.counters["edges"] = g.num_edges();
  state.counters["mean_degree"] = cge_bench::mean_degree(g);
  state.counters["rows_pay"] = cge::AdjacencyBitsets::rows_pay(g) ? 1 : 0;
}

// The inputs: the loop closer's graphs and user graphs of 2000 and 10000 nodes.
void frames(benchmark::internal::Benchmark* b) { b->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond); }
void users(benchmark::internal::Benchmark* b) { b->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond); }

#define CGE_KERNEL_BENCHMARK(function)                                  \
  BENCHMARK_CAPTURE(function, frame, Input::frame)->Apply(frames);     \
  BENCHMARK_CAPTURE(function, builder, Input::builder)->Apply(users); \
  BENCHMARK_CAPTURE(function, disc, Input::disc)->Apply(users)

// ---- all-sources tables ---------------------------------------------------------------------------

void block_bfs(benchmark::State& state, Input input, cge::DegreeSumKernel kernel) {
  const cge::Graph<double>& g = input_graph(input, static_cast<int>(state.range(0)));
  if (!cge::degree_sum_kernel_available(kernel)) {
    state.SkipWithError("this CPU cannot run the kernel");
    return;
  }
  for (auto _ : state) {
    cge::DegreeSumTable t = cge::shortest_path_degree_sums(g, TieMode::all, kernel);
    benchmark::DoNotOptimize(t.values.data());
  }
  counters(state, g);
}
void BM_DegreeSums_BlockBfs(benchmark::State& state, Input input) {
  block_bfs(state, input, cge::DegreeSumKernel::portable);
}
void BM_DegreeSums_BlockBfsAvx512(benchmark::State& state, Input input) {
  block_bfs(state, input, cge::DegreeSumKernel::avx512);
}
CGE_KERNEL_BENCHMARK(BM_DegreeSums_BlockBfs);
CGE_KERNEL_BENCHMARK(BM_DegreeSums_BlockBfsAvx512);

/// Every source searched alone, never stopped; the levels' Delta summed so nothing is optimised out.
template <typename Sums>
double all_sources(Sums& sums, std::int32_t n) {
  double total = 0.0;
  for (std::int32_t s = 0; s < n; ++s) {
    sums.run(s, [&](std::int32_t, double delta) {
      total += delta;
      return true;
    });
  }
  return total;
}

void BM_DegreeSums_SingleSourceBfs(benchmark::State& state, Input input) {
  const cge::Graph<double>& g = input_graph(input, static_cast<int>(state.range(0)));
  for (auto _ : state) {
    cge::detail::SingleSourceBfsDegreeSums<TieMode::all, double> sums(g);
    benchmark::DoNotOptimize(all_sources(sums, g.num_nodes()));
  }
  counters(state, g);
}
void BM_DegreeSums_SingleSourceBitsetBfs(benchmark::State& state, Input input) {
  const cge::Graph<double>& g = input_graph(input, static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const cge::AdjacencyBitsets rows(g);
    cge::detail::SingleSourceBitsetBfsDegreeSums<TieMode::all, double> sums(g, rows);
    benchmark::DoNotOptimize(all_sources(sums, g.num_nodes()));
  }
  counters(state, g);
}
CGE_KERNEL_BENCHMARK(BM_DegreeSums_SingleSourceBfs);
// Not on the 10000-node disc graph: its random node order spreads every row over all 157 words
// (AdjacencyBitsets::rows_pay says no), and one pass takes over a minute; 2000 nodes show that.
BENCHMARK_CAPTURE(BM_DegreeSums_SingleSourceBitsetBfs, frame, Input::frame)->Apply(frames);
BENCHMARK_CAPTURE(BM_DegreeSums_SingleSourceBitsetBfs, builder, Input::builder)->Apply(users);
BENCHMARK_CAPTURE(BM_DegreeSums_SingleSourceBitsetBfs, disc, Input::disc)->Arg(2000)->Unit(benchmark::kMillisecond);

void BM_DegreeSums_Reference(benchmark::State& state, Input input) {
  const cge::Graph<double>& g = input_graph(input, static_cast<int>(state.range(0)));
  for (auto _ : state) {
    cge::DegreeSumTable t = cge::reference_degree_sums(g, TieMode::all);
    benchmark::DoNotOptimize(t.values.data());
  }
  counters(state, g);
}
BENCHMARK_CAPTURE(BM_DegreeSums_Reference, frame, Input::frame)->Apply(frames);
BENCHMARK_CAPTURE(BM_DegreeSums_Reference, builder, Input::builder)->Arg(2000)->Unit(benchmark::kMillisecond);

// ---- the bounded search of compute_index ----------------------------------------------------------

template <template <TieMode, typename> class Kernel>
void bounded_entropy(benchmark::State& state, Input input) {
  const cge::Graph<double>& g = input_graph(input, static_cast<int>(state.range(0)));
  const cge::StandardCoefficients coefficient;
  const std::int32_t rho = cge::hop_diameter(g).diameter;
  std::vector<double> c(static_cast<std::size_t>(rho) + 1, 0.0);
  for (std::int32_t k = 1; k <= rho; ++k) c[static_cast<std::size_t>(k)] = coefficient(k, rho);
  const double log_alpha = std::log(0.5);
  cge::detail::WeightBoundedEntropy r;
  for (auto _ : state) {
    if constexpr (std::is_same<Kernel<TieMode::all, double>,
                               cge::detail::SingleSourceBitsetBfsDegreeSums<TieMode::all, double>>::value) {
      const cge::AdjacencyBitsets rows(g);
      Kernel<TieMode::all, double> sums(g, rows);
      r = cge::detail::weight_bounded_entropy_with(g, sums, c, log_alpha, 100.0);
    } else {
      Kernel<TieMode::all, double> sums(g);
      r = cge::detail::weight_bounded_entropy_with(g, sums, c, log_alpha, 100.0);
    }
    benchmark::DoNotOptimize(r.entropy_bits);
  }
  counters(state, g);
  state.counters["exponents_evaluated"] = r.exponents_evaluated;
}
void BM_BoundedEntropy_SingleSourceBfs(benchmark::State& state, Input input) {
  bounded_entropy<cge::detail::SingleSourceBfsDegreeSums>(state, input);
}
void BM_BoundedEntropy_SingleSourceBitsetBfs(benchmark::State& state, Input input) {
  bounded_entropy<cge::detail::SingleSourceBitsetBfsDegreeSums>(state, input);
}
CGE_KERNEL_BENCHMARK(BM_BoundedEntropy_SingleSourceBfs);
CGE_KERNEL_BENCHMARK(BM_BoundedEntropy_SingleSourceBitsetBfs);

void index_with(benchmark::State& state, Input input, cge::ScalingKind scaling) {
  const cge::Graph<double>& g = input_graph(input, static_cast<int>(state.range(0)));
  cge::DegreeDegreeEntropy<double> dde;
  dde.scaling.kind = scaling;
  for (auto _ : state) benchmark::DoNotOptimize(dde.compute_index(g).information_index);
  counters(state, g);
}
void BM_Index_Default(benchmark::State& state, Input input) { index_with(state, input, cge::ScalingKind::raw); }
void BM_Index_LoopCloser(benchmark::State& state, Input input) {
  index_with(state, input, cge::ScalingKind::normalised_mean);
}
CGE_KERNEL_BENCHMARK(BM_Index_Default);
CGE_KERNEL_BENCHMARK(BM_Index_LoopCloser);

}  // namespace
