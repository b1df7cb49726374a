#include "cge/slam/vocabulary_training.hpp"

#include <random>
#include <stdexcept>
#include <string>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/opencv/binary_descriptor.hpp"

namespace cge {
namespace slam {

std::vector<bow::BinaryDescriptor> orb_descriptors(const cv::Mat& image, int features) {
  if (features < 1) throw std::invalid_argument("orb_descriptors: the feature count must be at least 1");
  if (image.empty()) throw std::invalid_argument("orb_descriptors: the image is empty");
  cv::Mat grey;
  if (image.type() == CV_8UC3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else if (image.type() == CV_8UC1) {
    grey = image;
  } else {
    throw std::invalid_argument("orb_descriptors: expected a CV_8UC3 (BGR) or CV_8UC1 image, got " +
                                cv::typeToString(image.type()));
  }
  cv::Ptr<cv::ORB> orb = cv::ORB::create(features);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  return opencv::to_binary_descriptors(descriptors);
}

bow::Vocabulary train_vocabulary_from_descriptors(const std::vector<std::vector<bow::BinaryDescriptor>>& documents,
                                                  const VocabularyTrainingSettings& settings) {
  std::mt19937_64 engine(settings.seed);
  return bow::Vocabulary::train(documents, settings.vocabulary, engine);
}

bow::Vocabulary train_vocabulary(const std::vector<cv::Mat>& images, const VocabularyTrainingSettings& settings) {
  if (images.empty()) throw std::invalid_argument("train_vocabulary: no images");
  settings.vocabulary.validate();
  std::vector<std::vector<bow::BinaryDescriptor>> documents;
  documents.reserve(images.size());
  for (std::size_t i = 0; i < images.size(); ++i) {
    try {
      documents.push_back(orb_descriptors(images[i], settings.orb_features));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("train_vocabulary: image " + std::to_string(i) + ": " + e.what());
    }
  }
  return train_vocabulary_from_descriptors(documents, settings);
}

bow::Vocabulary train_vocabulary(const sim::FrameSource& source, int first_frames,
                                                  const VocabularyTrainingSettings& settings) {
  if (settings.frame_step < 1) throw std::invalid_argument("train_vocabulary: frame_step must be at least 1");
  if (first_frames < 1 || first_frames > source.frame_count()) {
    throw std::invalid_argument("train_vocabulary: first_frames " + std::to_string(first_frames) + " is not in 1 .. " +
                                std::to_string(source.frame_count()));
  }
  std::vector<cv::Mat> images;
  for (int i = 0; i < first_frames; i += settings.frame_step) images.push_back(source.render(i).rgb);
  return train_vocabulary(images, settings);
}

}  // namespace slam
}  // namespace cge
