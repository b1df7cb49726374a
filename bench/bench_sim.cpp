// The synthetic RGB-D renderer (cge/sim/renderer.hpp): one 640 x 480 frame with RGB, realistic
// depth and instance labels, rendered into reused buffers, for each preset. Target: under 20 ms on
// one thread. Frames cycle through the sequence, so people, camera and occlusions vary.

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"

namespace {

constexpr int kFrames = 300;  // 10 s at 30 Hz, like the writer's target sequence

void BM_SimRenderFrame(benchmark::State& state) {
  const std::vector<std::string> names = cge::sim::preset_names();
  const std::string& name = names[static_cast<std::size_t>(state.range(0))];
  const cge::sim::SequenceRenderer renderer(cge::sim::make_preset(name, kFrames, 1));
  cge::sim::RenderedFrame frame;
  cge::sim::RenderWorkspace workspace;
  renderer.render_into(0, frame, workspace);  // first use builds the shared noise table
  int index = 0;
  for (auto _ : state) {
    renderer.render_into(index, frame, workspace);
    benchmark::DoNotOptimize(frame.depth.data);
    index = (index + 37) % kFrames;
  }
  state.SetLabel(name);
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimRenderFrame)->DenseRange(0, 6)->Unit(benchmark::kMillisecond);

/// Building a preset and its renderer (scene, people, trajectory, ground-truth loops, validation).
void BM_SimMakePreset(benchmark::State& state) {
  const std::vector<std::string> names = cge::sim::preset_names();
  const std::string& name = names[static_cast<std::size_t>(state.range(0))];
  for (auto _ : state) {
    const cge::sim::SequenceRenderer renderer(cge::sim::make_preset(name, kFrames, 1));
    benchmark::DoNotOptimize(renderer.frame_count());
  }
  state.SetLabel(name);
}
BENCHMARK(BM_SimMakePreset)->Arg(0)->Arg(5)->Unit(benchmark::kMillisecond);

}  // namespace
