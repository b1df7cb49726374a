#pragma once
// Training a bag-of-words vocabulary from images: ORB descriptors per image, then
// cge::bow::Vocabulary::train. Used by the cge_vocab tool and by cge_slam, which, for a rendered run
// without a vocabulary file, trains one from frames of another rendered preset (never the frames it
// evaluates), so no vocabulary file has to be shipped (a few seconds for 20 images at 640 x 480,
// k = 10, L = 4). Such a vocabulary knows one synthetic room: fine there, weaker than a large generic
// vocabulary on real data (docs/LOOP_CLOSING.md).

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/bow/vocabulary.hpp"
#include "cge/sim/frame_source.hpp"

namespace cge {
namespace slam {

struct VocabularyTrainingSettings {
  int orb_features = 1000;             ///< ORB keypoints per image (cv::ORB, default pyramid), >= 1
  bow::VocabularySettings vocabulary;  ///< branching k, depth L, k-medians iterations
  std::uint64_t seed = 1;              ///< seeds the std::mt19937_64 that k-means++ draws from
  int frame_step = 1;                  ///< train_vocabulary(source, ...): use every frame_step-th frame, >= 1
};

/// ORB descriptors of one image (CV_8UC3 BGR or CV_8UC1 grey): at most `features` of them.
std::vector<bow::BinaryDescriptor> orb_descriptors(const cv::Mat& image, int features);

/// A vocabulary from the descriptors of each training document (one per image), the k-means++
/// draws from std::mt19937_64(settings.seed): the one place the seed becomes an engine, so that the
/// same images and seed give the same vocabulary in every caller.
bow::Vocabulary train_vocabulary_from_descriptors(const std::vector<std::vector<bow::BinaryDescriptor>>& documents,
                                                  const VocabularyTrainingSettings& settings);

/// A vocabulary from images (one training document per image). Throws std::invalid_argument for
/// no images, an empty or wrongly typed image (naming its index), or no features at all.
bow::Vocabulary train_vocabulary(const std::vector<cv::Mat>& images, const VocabularyTrainingSettings& settings = {});

/// A vocabulary from frames 0, step, 2 step, ... below first_frames of a synthetic sequence.
bow::Vocabulary train_vocabulary(const sim::FrameSource& source, int first_frames,
                                 const VocabularyTrainingSettings& settings = {});

}  // namespace slam
}  // namespace cge
