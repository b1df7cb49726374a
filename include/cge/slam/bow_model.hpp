#pragma once
// BowModel: the bag-of-words policy of the LoopCloser (docs/METHOD.md section 7: "the bag-of-words
// model is a policy, so a host SLAM system can feed its own"). VocabularyBowModel is ours (a
// cge::bow::Vocabulary plus an inverted-index cge::bow::BowDatabase); a host wraps DBoW2 or DBoW3
// by implementing the same three functions.
//
// Contract (what a host's wrapper must provide):
// - add(id, descriptors): store keyframe `id` described by `descriptors` (CV_8UC1, one 32-byte ORB
//   row per feature; the LoopCloser passes the static features only). Ids arrive strictly
//   increasing (0, 1, 2, ...); each once.
// - query(descriptors): for every stored keyframe that shares at least one visual word with the
//   query, its id, the number of words the two have in common and a similarity score in [0, 1]
//   (higher = more alike; DBoW2's L1 score fits), sorted by ascending id. Stored keyframes sharing
//   no word may be left out. The query itself is not stored. Same inputs, same output (no
//   randomness, no dependence on addresses).
// - clear(): forget every stored keyframe.
// A DBoW2 wrapper: transform() the rows with its vocabulary, keep the BowVectors, and count the
// common words over the vectors' word ids (DBoW2's Database::query gives the scores, not the
// counts; ORB-SLAM2 counts them through its own inverted file, as BowDatabase does).

#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/bow/database.hpp"
#include "cge/bow/vocabulary.hpp"
#include "cge/opencv/binary_descriptor.hpp"

namespace cge {
namespace slam {

struct BowQueryMatch {
  int keyframe_id = -1;
  int common_words = 0;
  double score = 0;  ///< in [0, 1]
};

class BowModel {
 public:
  virtual ~BowModel() = default;
  virtual void add(int keyframe_id, const cv::Mat& descriptors) = 0;
  virtual std::vector<BowQueryMatch> query(const cv::Mat& descriptors) const = 0;
  virtual void clear() = 0;

 protected:
  BowModel() = default;
  BowModel(const BowModel&) = default;
  BowModel& operator=(const BowModel&) = default;
};

/// Our model: descent in a cge::bow::Vocabulary, tf-idf, L1 score, inverted index.
class VocabularyBowModel final : public BowModel {
 public:
  explicit VocabularyBowModel(bow::Vocabulary vocabulary) : vocabulary_(std::move(vocabulary)) {
    if (vocabulary_.empty()) throw std::invalid_argument("VocabularyBowModel: the vocabulary has no words");
  }

  void add(int keyframe_id, const cv::Mat& descriptors) override {
    if (keyframe_id < 0 || (!ids_.empty() && keyframe_id <= ids_.back())) {
      throw std::invalid_argument("VocabularyBowModel::add: keyframe id " + std::to_string(keyframe_id) +
                                  " is negative or not above the last one added");
    }
    database_.add(transform(descriptors));
    ids_.push_back(keyframe_id);
  }

  std::vector<BowQueryMatch> query(const cv::Mat& descriptors) const override {
    std::vector<BowQueryMatch> out;
    for (const bow::DatabaseMatch& m : database_.query(transform(descriptors))) {
      out.push_back(BowQueryMatch{ids_[static_cast<std::size_t>(m.entry)], m.common_words, m.score});
    }
    return out;
  }

  void clear() override {
    database_.clear();
    ids_.clear();
  }

  bow::BowVector transform(const cv::Mat& descriptors) const {
    return vocabulary_.transform(opencv::to_binary_descriptors(descriptors));
  }
  const bow::Vocabulary& vocabulary() const { return vocabulary_; }

 private:
  bow::Vocabulary vocabulary_;
  bow::BowDatabase database_;
  std::vector<int> ids_;
};

}  // namespace slam
}  // namespace cge
