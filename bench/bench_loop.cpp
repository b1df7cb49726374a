// Loop closing (docs/LOOP_CLOSING.md): the BoW transform of one frame's 1000 ORB descriptors in a
// k = 10, L = 4 vocabulary, and LoopCloser::process over a 100-keyframe loop sequence (rendered
// loop_dynamic, two laps, keyframes from ground-truth poses and masks as in the tests).

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "../tests/loop_test_support.hpp"
#include "cge/bow/vocabulary.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/vocabulary_training.hpp"

namespace {

std::vector<cge::bow::BinaryDescriptor> random_descriptors(std::size_t n, std::mt19937_64& rng) {
  std::vector<cge::bow::BinaryDescriptor> out(n);
  for (auto& d : out) d = {rng(), rng(), rng(), rng()};
  return out;
}

void BM_BowTransform1000(benchmark::State& state) {
  std::mt19937_64 rng(1);
  std::vector<std::vector<cge::bow::BinaryDescriptor>> images;
  for (int i = 0; i < 20; ++i) images.push_back(random_descriptors(1000, rng));
  cge::bow::VocabularySettings settings;  // k = 10, L = 4
  std::mt19937_64 engine(2);
  const cge::bow::Vocabulary vocabulary = cge::bow::Vocabulary::train(images, settings, engine);
  const std::vector<cge::bow::BinaryDescriptor> query = random_descriptors(1000, rng);
  for (auto _ : state) {
    cge::bow::BowVector v = vocabulary.transform(query);
    benchmark::DoNotOptimize(v.data());
  }
  state.counters["words"] = static_cast<double>(vocabulary.word_count());
}
BENCHMARK(BM_BowTransform1000)->Unit(benchmark::kMicrosecond);

struct LoopBenchScene {
  cge::sim::SequenceSpec spec;
  std::vector<cge::slam::Keyframe> keyframes;
  cge::bow::Vocabulary vocabulary;
};

const LoopBenchScene& loop_scene() {
  static const LoopBenchScene scene = [] {
    LoopBenchScene s;
    s.spec = cge::sim::make_preset("loop_dynamic", 100, 5, cge::sim::repeated_room_loop_settings(2));
    const cge::sim::SequenceRenderer renderer(s.spec);
    std::vector<cv::Mat> first;
    for (int i = 0; i < renderer.frame_count(); ++i) {
      const cge::sim::RenderedFrame f = renderer.render(i);
      s.keyframes.push_back(cge_test::keyframe_from_frame(f, s.spec.camera, s.spec.instances, i));
      if (i < 20) first.push_back(f.rgb);
    }
    s.vocabulary = cge::slam::train_vocabulary(first);
    return s;
  }();
  return scene;
}

/// One iteration = a fresh LoopCloser processing all 100 keyframes (the database grows to 100);
/// items_per_second gives keyframes per second. Arg: 0 = combined scoring (the default), 1 = bow_only.
void BM_LoopCloserProcess100(benchmark::State& state) {
  const LoopBenchScene& s = loop_scene();
  cge::slam::LoopCloserSettings settings;
  settings.scoring = state.range(0) == 0 ? cge::slam::LoopScoring::combined : cge::slam::LoopScoring::bow_only;
  int accepted = 0;
  for (auto _ : state) {
    cge::slam::LoopCloser closer(s.vocabulary, cge_test::intrinsics_of(s.spec.camera), s.spec.camera.width_px,
                                 s.spec.camera.height_px, settings);
    cge_test::PoseCovisibilityView view(s.keyframes, 5, 60.0);
    accepted = 0;
    for (const auto& kf : s.keyframes) {
      view.set_count(kf.id + 1);
      accepted += closer.process(kf, view).accepted ? 1 : 0;
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(s.keyframes.size()));
  state.counters["accepted"] = accepted;
  state.SetLabel(cge::slam::to_string(settings.scoring));
}
BENCHMARK(BM_LoopCloserProcess100)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);

}  // namespace

namespace {

/// One process() call for keyframe 99 with keyframes 0..98 in the database (their BoW entries and
/// cached entropies made untimed beforehand): the cost of one new keyframe late in a sequence.
/// Arg as above.
void BM_LoopCloserProcessLast(benchmark::State& state) {
  const LoopBenchScene& s = loop_scene();
  cge::slam::LoopCloserSettings settings;
  settings.scoring = state.range(0) == 0 ? cge::slam::LoopScoring::combined : cge::slam::LoopScoring::bow_only;
  const auto& last = s.keyframes.back();
  bool accepted = false;
  for (auto _ : state) {
    state.PauseTiming();
    cge::slam::LoopCloser closer(s.vocabulary, cge_test::intrinsics_of(s.spec.camera), s.spec.camera.width_px,
                                 s.spec.camera.height_px, settings);
    cge_test::PoseCovisibilityView view(s.keyframes, 5, 60.0);
    for (std::size_t i = 0; i + 1 < s.keyframes.size(); ++i) {
      view.set_count(static_cast<int>(i) + 1);
      closer.process(s.keyframes[i], view);
    }
    view.set_count(last.id + 1);
    state.ResumeTiming();
    accepted = closer.process(last, view).accepted;
  }
  state.counters["accepted"] = accepted ? 1 : 0;
  state.SetLabel(cge::slam::to_string(settings.scoring));
}
BENCHMARK(BM_LoopCloserProcessLast)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3)->Repetitions(3);

}  // namespace
