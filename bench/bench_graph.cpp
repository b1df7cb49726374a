// Graph construction and the entropy measures on random geometric graphs, with igraph's all-pairs
// distances and a plain all-sources BFS as peers (docs/BENCHMARK.md).

#include <cstdint>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_data.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/graph/neighbor_search.hpp"

#ifdef CGE_BENCH_HAVE_IGRAPH
#include <igraph.h>
#endif

namespace {

using cge_bench::family_graph;
using cge_bench::GraphFamily;
using cge_bench::mean_degree;
using cge_bench::rgg_graph;
using cge_bench::rgg_points;

void graph_counters(benchmark::State& state, const cge::Graph<double>& g) {
  state.counters["nodes"] = g.num_nodes();
  state.counters["edges"] = g.num_edges();
  state.counters["mean_degree"] = mean_degree(g);
}

void rgg_sizes(benchmark::internal::Benchmark* b) {
  for (int n : {100, 300, 1000, 3000}) b->Arg(n);
}

// ---- 1. GraphBuilder, per neighbour-search policy ---------------------------------------------------

template <typename NeighborSearch>
void BM_GraphBuilder(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const cge_bench::Points& pts = rgg_points(n);
  const cge::GraphBuilder<double, NeighborSearch> builder(cge_bench::rgg_settings(n));
  const cge::ImageRegion<double> image = cge_bench::image_region();
  for (auto _ : state) {
    cge::Graph<double> g = builder.build(image, pts);
    benchmark::DoNotOptimize(g);
  }
  graph_counters(state, rgg_graph(n));
  state.counters["R_px"] = cge_bench::rgg_radius_px(n);
  state.SetComplexityN(n);
}
BENCHMARK_TEMPLATE(BM_GraphBuilder, cge::GridNeighborSearch<double>)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();
BENCHMARK_TEMPLATE(BM_GraphBuilder, cge::BruteForceNeighborSearch<double>)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();

/// The allocation-free form: one workspace and one output graph reused across iterations, as a
/// host scoring many frames would hold them.
void BM_GraphBuilder_ReusedWorkspace(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const cge::GraphBuilder<double> builder(cge_bench::rgg_settings(n));
  const auto& points = rgg_points(n);
  const auto image = cge_bench::image_region();
  cge::GraphBuilderWorkspace<double> workspace;
  cge::Graph<double> graph;
  for (auto _ : state) {
    builder.build(image, points, cge::NoMask{}, cge::NoMask{}, {}, graph, workspace);
    benchmark::DoNotOptimize(graph.num_edges());
  }
  graph_counters(state, graph);
  state.SetComplexityN(n);
}
BENCHMARK(BM_GraphBuilder_ReusedWorkspace)->Apply(rgg_sizes)->Unit(benchmark::kMicrosecond)->Complexity();

/// The allocating grid build with each candidate-scan kernel (automatic is BM_GraphBuilder above).
void BM_GraphBuilder_Scan(benchmark::State& state, cge::GridScanKernel kernel) {
  const int n = static_cast<int>(state.range(0));
  if (!cge::GridNeighborSearch<double>::scan_kernel_available(kernel)) {
    state.SkipWithError("this CPU cannot run the scan kernel");
    return;
  }
  cge::GridNeighborSearch<double> search;
  search.scan_kernel = kernel;
  const cge::GraphBuilder<double> builder(cge_bench::rgg_settings(n), search);
  const auto& points = rgg_points(n);
  const auto image = cge_bench::image_region();
  for (auto _ : state) {
    cge::Graph<double> g = builder.build(image, points);
    benchmark::DoNotOptimize(g);
  }
  graph_counters(state, rgg_graph(n));
}
BENCHMARK_CAPTURE(BM_GraphBuilder_Scan, portable, cge::GridScanKernel::portable)
    ->Arg(1000)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_GraphBuilder_Scan, avx512, cge::GridScanKernel::avx512)->Arg(1000)->Unit(benchmark::kMicrosecond);

// ---- 2. DegreeDegreeEntropy::compute ----------------------------------------------------------------

void BM_DegreeDegreeEntropy(benchmark::State& state, GraphFamily family) {
  const int n = static_cast<int>(state.range(0));
  const cge::Graph<double>& g = family_graph(family, n);
  const cge::DegreeDegreeEntropy<double> dde;  // TieMode::all, exp coefficients, alpha 0.5, lambda 1
  int diameter = 0;
  for (auto _ : state) {
    cge::DegreeDegreeResult<double> r = dde.compute(g);
    benchmark::DoNotOptimize(r);
    diameter = r.diameter;
  }
  graph_counters(state, g);
  state.counters["diameter"] = diameter;
  state.SetComplexityN(n);
}
BENCHMARK_CAPTURE(BM_DegreeDegreeEntropy, builder, GraphFamily::builder)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();
BENCHMARK_CAPTURE(BM_DegreeDegreeEntropy, disc, GraphFamily::disc)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();

/// What CGESimilarity calls: H and I without the per-node exponents; with alpha 0.5 and raw
/// exponents only the nodes within e^-100 of the heaviest are completed (exponents_evaluated).
void BM_DegreeDegreeIndex(benchmark::State& state, GraphFamily family) {
  const int n = static_cast<int>(state.range(0));
  const cge::Graph<double>& g = family_graph(family, n);
  const cge::DegreeDegreeEntropy<double> dde;
  cge::DegreeDegreeResult<double> r;
  for (auto _ : state) {
    r = dde.compute_index(g);
    benchmark::DoNotOptimize(r);
  }
  graph_counters(state, g);
  state.counters["diameter"] = r.diameter;
  state.counters["exponents_evaluated"] = r.exponents_evaluated;
  state.SetComplexityN(n);
}
BENCHMARK_CAPTURE(BM_DegreeDegreeIndex, builder, GraphFamily::builder)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();
BENCHMARK_CAPTURE(BM_DegreeDegreeIndex, disc, GraphFamily::disc)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();

void BM_DegreeDegreeEntropy_Ties(benchmark::State& state, cge::TieMode ties) {
  const int n = static_cast<int>(state.range(0));
  const cge::Graph<double>& g = rgg_graph(n);
  cge::DegreeDegreeEntropy<double> dde;
  dde.settings.ties = ties;
  for (auto _ : state) {
    cge::DegreeDegreeResult<double> r = dde.compute(g);
    benchmark::DoNotOptimize(r);
  }
  graph_counters(state, g);
}
BENCHMARK_CAPTURE(BM_DegreeDegreeEntropy_Ties, mean, cge::TieMode::mean)->Arg(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DegreeDegreeEntropy_Ties, min, cge::TieMode::min)->Arg(1000)->Unit(benchmark::kMicrosecond);

/// The Delta table alone, with each kernel of the sweep (automatic is what compute() uses).
void BM_DegreeSums(benchmark::State& state, GraphFamily family, cge::DegreeSumKernel kernel) {
  const int n = static_cast<int>(state.range(0));
  const cge::Graph<double>& g = family_graph(family, n);
  if (!cge::degree_sum_kernel_available(kernel)) {
    state.SkipWithError("this CPU cannot run the kernel");
    return;
  }
  for (auto _ : state) {
    cge::DegreeSumTable t = cge::shortest_path_degree_sums(g, cge::TieMode::all, kernel);
    benchmark::DoNotOptimize(t);
  }
  graph_counters(state, g);
}
BENCHMARK_CAPTURE(BM_DegreeSums, builder_portable, GraphFamily::builder, cge::DegreeSumKernel::portable)
    ->Arg(300)
    ->Arg(1000)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DegreeSums, builder_avx512, GraphFamily::builder, cge::DegreeSumKernel::avx512)
    ->Arg(300)
    ->Arg(1000)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DegreeSums, disc_portable, GraphFamily::disc, cge::DegreeSumKernel::portable)
    ->Arg(1000)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DegreeSums, disc_avx512, GraphFamily::disc, cge::DegreeSumKernel::avx512)
    ->Arg(1000)
    ->Unit(benchmark::kMicrosecond);

// ---- 3. Peers: all-pairs unweighted distances ---------------------------------------------------------

/// Hop distances from every source by a plain BFS over the CSR arrays; the distances are reduced
/// to a checksum (no n x n matrix is written, as the degree-degree entropy writes none either).
void BM_AllSourcesBfs(benchmark::State& state, GraphFamily family) {
  const int n = static_cast<int>(state.range(0));
  const cge::Graph<double>& g = family_graph(family, n);
  const std::int32_t* offsets = g.csr_offsets().data();
  const std::int32_t* adjacency = g.csr_adjacency().data();
  std::vector<std::int32_t> dist(static_cast<std::size_t>(n), -1);
  std::vector<std::int32_t> queue(static_cast<std::size_t>(n));
  for (auto _ : state) {
    std::int64_t checksum = 0;
    for (std::int32_t s = 0; s < n; ++s) {
      dist[static_cast<std::size_t>(s)] = 0;
      queue[0] = s;
      std::int32_t head = 0, tail = 1;
      while (head < tail) {
        const std::int32_t u = queue[static_cast<std::size_t>(head++)];
        const std::int32_t next = dist[static_cast<std::size_t>(u)] + 1;
        for (std::int32_t e = offsets[u]; e < offsets[u + 1]; ++e) {
          const std::int32_t v = adjacency[e];
          if (dist[static_cast<std::size_t>(v)] < 0) {
            dist[static_cast<std::size_t>(v)] = next;
            queue[static_cast<std::size_t>(tail++)] = v;
            checksum += next;
          }
        }
      }
      for (std::int32_t i = 0; i < tail; ++i) dist[static_cast<std::size_t>(queue[static_cast<std::size_t>(i)])] = -1;
    }
    benchmark::DoNotOptimize(checksum);
  }
  graph_counters(state, g);
  state.SetComplexityN(n);
}
BENCHMARK_CAPTURE(BM_AllSourcesBfs, builder, GraphFamily::builder)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();
BENCHMARK_CAPTURE(BM_AllSourcesBfs, disc, GraphFamily::disc)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();

#ifdef CGE_BENCH_HAVE_IGRAPH
/// igraph_distances(all, all, IGRAPH_ALL) on the same graph, converted to an igraph_t once outside
/// the timed loop; the n x n result matrix is allocated once too (igraph only refills it).
void BM_IgraphDistances(benchmark::State& state, GraphFamily family) {
  const int n = static_cast<int>(state.range(0));
  const cge::Graph<double>& g = family_graph(family, n);
  igraph_vector_int_t edge_list;
  igraph_vector_int_init(&edge_list, 2 * static_cast<igraph_integer_t>(g.num_edges()));
  igraph_integer_t k = 0;
  for (const cge::Edge<double>& e : g.edges()) {
    VECTOR(edge_list)[k++] = e.u;
    VECTOR(edge_list)[k++] = e.v;
  }
  igraph_t ig;
  if (igraph_create(&ig, &edge_list, n, IGRAPH_UNDIRECTED) != IGRAPH_SUCCESS) {
    igraph_vector_int_destroy(&edge_list);
    state.SkipWithError("igraph_create failed");
    return;
  }
  igraph_vector_int_destroy(&edge_list);
  igraph_matrix_t res;
  igraph_matrix_init(&res, n, n);
  for (auto _ : state) {
    if (igraph_distances(&ig, &res, igraph_vss_all(), igraph_vss_all(), IGRAPH_ALL) != IGRAPH_SUCCESS) {
      state.SkipWithError("igraph_distances failed");
      break;
    }
    benchmark::DoNotOptimize(MATRIX(res, 0, n - 1));
    benchmark::ClobberMemory();
  }
  igraph_matrix_destroy(&res);
  igraph_destroy(&ig);
  graph_counters(state, g);
  state.SetComplexityN(n);
}
BENCHMARK_CAPTURE(BM_IgraphDistances, builder, GraphFamily::builder)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();
BENCHMARK_CAPTURE(BM_IgraphDistances, disc, GraphFamily::disc)
    ->Apply(rgg_sizes)
    ->Unit(benchmark::kMicrosecond)
    ->Complexity();
#endif

// ---- 5. ShannonEdgeEntropy ----------------------------------------------------------------------------

void BM_ShannonEdgeEntropy(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const cge::Graph<double>& g = rgg_graph(n);
  const cge::ShannonEdgeEntropy<double> shannon;
  for (auto _ : state) {
    double h = shannon.compute(g);
    benchmark::DoNotOptimize(h);
  }
  graph_counters(state, g);
  state.SetComplexityN(n);
}
BENCHMARK(BM_ShannonEdgeEntropy)->Apply(rgg_sizes)->Unit(benchmark::kMicrosecond)->Complexity();

}  // namespace
