#include "cge/run/default_vocabulary.hpp"

#include "cge/sim/frame_source.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/vocabulary_training.hpp"

namespace cge {
namespace run {

using Defaults = DefaultVocabularySettings;

std::string vocabulary_preset(const std::string& evaluated) {
  return evaluated == Defaults::kPreset ? Defaults::kPresetOtherwise : Defaults::kPreset;
}

bow::Vocabulary train_default_vocabulary(const std::string& preset, std::uint64_t seed) {
  const sim::RendererFrameSource<sim::SequenceRenderer> frames(
      sim::SequenceRenderer(sim::make_preset(preset, Defaults::kPresetFrames, seed)));
  slam::VocabularyTrainingSettings training;
  training.frame_step = Defaults::kPresetFrames / Defaults::kImages;
  return slam::train_vocabulary(frames, Defaults::kPresetFrames, training);
}

std::string default_vocabulary_description(const std::string& preset, std::uint64_t seed) {
  return preset + " rendered, seed " + std::to_string(seed) + ", " + std::to_string(Defaults::kImages) +
         " images over its " + std::to_string(Defaults::kPresetFrames) +
         " frames (trained here; not the evaluated frames)";
}

}  // namespace run
}  // namespace cge
