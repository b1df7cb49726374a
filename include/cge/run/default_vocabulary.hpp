#pragma once
// The vocabulary of a rendered run given none: trained on another preset of the same room (another
// camera path, other walkers, another seed), so the evaluated frames never train it; 20 images
// spread over 10 s of it, k = 10, L = 4 (about 9 000 words, as cge_vocab's default).
#include <cstdint>
#include <string>

#include "cge/bow/vocabulary.hpp"

namespace cge {
namespace run {

struct DefaultVocabularySettings {
  static constexpr const char* kPreset = "walking_halfsphere";
  static constexpr const char* kPresetOtherwise = "walking_xyz";  ///< when walking_halfsphere is evaluated
  static constexpr int kPresetFrames = 300;
  static constexpr int kImages = 20;
};

/// The preset that trains the vocabulary of a rendered run of `evaluated` (never itself).
std::string vocabulary_preset(const std::string& evaluated);

/// The default vocabulary from `preset` rendered with `seed` (cge_vocab's training defaults:
/// 1000 ORB, k = 10, L = 4, seed 1).
bow::Vocabulary train_default_vocabulary(const std::string& preset, std::uint64_t seed);

/// What the run reports as its vocabulary source.
std::string default_vocabulary_description(const std::string& preset, std::uint64_t seed);

}  // namespace run
}  // namespace cge
