// Tests of the LoopCloser on rendered loop sequences (cge::sim presets loop_dynamic and
// loop_structure_change) with keyframes from ground-truth poses and masks, and of vocabulary
// training from images. Oracles: the sequences' ground-truth loop pairs and poses.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "cge/sim/frame_source.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/vocabulary_training.hpp"
#include "loop_test_support.hpp"
#include "test_support.hpp"

using cge::slam::Keyframe;
using cge::slam::LoopCloser;
using cge::slam::LoopCloserSettings;
using cge::slam::LoopDecision;
using cge::slam::LoopReason;
using cge::slam::LoopScoring;

namespace {

constexpr int kFrames = 80;      // two laps of 40 frames: 9 degrees per frame
constexpr int kLaps = 2;
constexpr int kVocabularyFrames = 20;  // the first half lap trains the vocabulary, as the pipeline's default does

struct LoopScene {
  cge::sim::SequenceSpec spec;
  std::vector<Keyframe> keyframes;
  std::vector<cv::Mat> images;
  std::set<std::pair<int, int>> loops;  // (query frame, match frame)
  cge::bow::Vocabulary vocabulary;
};

const LoopScene& scene(const std::string& preset) {
  static std::map<std::string, std::unique_ptr<LoopScene>> cache;
  auto it = cache.find(preset);
  if (it != cache.end()) return *it->second;
  auto s = std::make_unique<LoopScene>();
  cge::sim::PresetSettings settings;
  settings.loop_laps = kLaps;
  s->spec = cge::sim::make_preset(preset, kFrames, 5, settings);
  const cge::sim::SequenceRenderer renderer(s->spec);
  for (int i = 0; i < renderer.frame_count(); ++i) {
    const cge::sim::RenderedFrame f = renderer.render(i);
    s->keyframes.push_back(cge_test::keyframe_from_frame(f, s->spec.camera, s->spec.instances, i));
    s->images.push_back(f.rgb);
  }
  for (const auto& l : s->spec.loops) s->loops.emplace(l.query_frame, l.match_frame);
  cge::slam::VocabularyTrainingSettings vs;
  s->vocabulary = cge::slam::train_vocabulary(
      std::vector<cv::Mat>(s->images.begin(), s->images.begin() + kVocabularyFrames), vs);
  return *cache.emplace(preset, std::move(s)).first->second;
}

std::vector<LoopDecision> run(const LoopScene& s, const LoopCloserSettings& settings) {
  LoopCloser closer(s.vocabulary, cge_test::intrinsics_of(s.spec.camera), s.spec.camera.width_px,
                    s.spec.camera.height_px, settings);
  cge_test::PoseCovisibilityView view(s.keyframes, 5, 60.0);
  std::vector<LoopDecision> out;
  for (const Keyframe& kf : s.keyframes) {
    view.set_count(kf.id + 1);
    out.push_back(closer.process(kf, view));
  }
  return out;
}

}  // namespace

TEST_CASE("LoopCloser experiment: print decisions", "[.loopexp]") {
  for (const std::string preset : {"loop_dynamic", "loop_structure_change"}) {
    const LoopScene& s = scene(preset);
    for (LoopScoring mode : {LoopScoring::cge, LoopScoring::bow_only}) {
      LoopCloserSettings settings;
      settings.scoring = mode;
      settings.min_cge_score = 0;
      settings.min_bow_score = 0;
      settings.consistent_keyframes = 1;
      const auto d = run(s, settings);
      std::printf("== %s %s (vocabulary %zu words)\n", preset.c_str(), to_string(mode), s.vocabulary.word_count());
      for (const auto& x : d) {
        const bool gt = s.loops.count({x.query_keyframe, x.match_keyframe}) > 0;
        std::printf("q %2d m %2d gt %d cand %2d bow %.4f cge %.4f tent %3d inl %3d %s\n", x.query_keyframe,
                    x.match_keyframe, gt ? 1 : 0, x.candidates, x.bow_score, x.cge_score, x.tentative_matches,
                    x.matched_points, to_string(x.reason));
      }
    }
  }
}
