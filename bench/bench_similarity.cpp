// CGESimilarity end to end on two ORB-like frames of 1000 keypoints each, plus its two stages
// (building both graphs; the entropies of both graphs) to show where the time goes.

#include <benchmark/benchmark.h>

#include "bench_data.hpp"
#include "cge/entropy/cge_similarity.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"

namespace {

using cge_bench::Frame;
using cge_bench::orb_frame;

using Similarity = cge::CGESimilarity<double>;  // grid neighbour search, default settings throughout

/// The two frame graphs, each built with respect to the other frame (as score() builds them).
struct FrameGraphs {
  cge::Graph<double> current;
  cge::Graph<double> candidate;
};

FrameGraphs build_graphs(const Similarity& sim, const Frame& a, const Frame& b) {
  const cge::ImageRegion<double> image = cge_bench::image_region();
  return {sim.graph_builder.build(image, a.keypoints, a.dynamic_mask, b.dynamic_mask, a.instances),
          sim.graph_builder.build(image, b.keypoints, b.dynamic_mask, a.dynamic_mask, b.instances)};
}

void frame_counters(benchmark::State& state, const Similarity& sim) {
  const FrameGraphs g = build_graphs(sim, orb_frame(0), orb_frame(1));
  state.counters["cur_nodes"] = g.current.num_nodes();
  state.counters["cur_edges"] = g.current.num_edges();
  state.counters["cand_nodes"] = g.candidate.num_nodes();
  state.counters["cand_edges"] = g.candidate.num_edges();
  state.counters["cur_diameter"] = sim.degree_entropy.compute(g.current).diameter;
  state.counters["cand_diameter"] = sim.degree_entropy.compute(g.candidate).diameter;
}

// ---- 4. CGESimilarity::score, both graphs built and scored -------------------------------------------

void BM_CGESimilarity_Score(benchmark::State& state) {
  const Frame& a = orb_frame(0);
  const Frame& b = orb_frame(1);
  const Similarity sim;
  const cge::ImageRegion<double> image = cge_bench::image_region();
  const auto current = cge::frame_view(a.keypoints, a.dynamic_mask, a.instances);
  const auto candidate = cge::frame_view(b.keypoints, b.dynamic_mask, b.instances);
  Similarity::Score s;
  for (auto _ : state) {
    s = sim.score(image, current, candidate);
    benchmark::DoNotOptimize(s);
  }
  frame_counters(state, sim);
  state.counters["similarity"] = s.similarity;
  state.SetLabel(s.used_edge_entropy ? "degree+edge entropy" : "degree entropy only");
}
BENCHMARK(BM_CGESimilarity_Score)->Unit(benchmark::kMicrosecond);

/// Stage 1 of score(): the two GraphBuilder::build calls.
void BM_CGESimilarity_BuildGraphs(benchmark::State& state) {
  const Similarity sim;
  for (auto _ : state) {
    FrameGraphs g = build_graphs(sim, orb_frame(0), orb_frame(1));
    benchmark::DoNotOptimize(g);
  }
  frame_counters(state, sim);
}
BENCHMARK(BM_CGESimilarity_BuildGraphs)->Unit(benchmark::kMicrosecond);

/// Stage 2 of score(): degree-degree index and edge entropy of both (prebuilt) graphs.
void BM_CGESimilarity_Entropies(benchmark::State& state) {
  const Similarity sim;
  const FrameGraphs g = build_graphs(sim, orb_frame(0), orb_frame(1));
  for (auto _ : state) {
    cge::GraphEntropies<double> ec = sim.entropies(g.current);
    cge::GraphEntropies<double> ed = sim.entropies(g.candidate);
    benchmark::DoNotOptimize(ec);
    benchmark::DoNotOptimize(ed);
  }
  frame_counters(state, sim);
}
BENCHMARK(BM_CGESimilarity_Entropies)->Unit(benchmark::kMicrosecond);

}  // namespace
