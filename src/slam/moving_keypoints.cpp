#include "cge/slam/moving_keypoints.hpp"

#include <cstdint>
#include <stdexcept>
#include <string>

#include "cge/opencv/keypoint.hpp"

namespace cge {
namespace slam {

MovingKeypointCounts count_moving_keypoints(const std::vector<cv::KeyPoint>& keypoints,
                                            const std::vector<FeatureLabel>& labels, const cv::Mat& moving_mask) {
  if (moving_mask.empty() || moving_mask.type() != CV_8UC1) {
    throw std::invalid_argument("count_moving_keypoints: the moving mask must be a non-empty CV_8UC1 image");
  }
  if (labels.size() != keypoints.size()) {
    throw std::invalid_argument("count_moving_keypoints: " + std::to_string(labels.size()) + " labels for " +
                                std::to_string(keypoints.size()) + " keypoints");
  }
  MovingKeypointCounts counts;
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    if (moving_mask.at<std::uint8_t>(opencv::nearest_pixel(keypoints[i].pt, moving_mask.size())) == 0) continue;
    ++counts.moving_keypoints;
    counts.moving_kept += labels[i] == FeatureLabel::static_feature;
  }
  return counts;
}

cv::Mat moving_mask_of(const std::vector<SegmentedInstance>& instances, cv::Size image_size) {
  cv::Mat mask = cv::Mat::zeros(image_size, CV_8UC1);
  for (const SegmentedInstance& instance : instances) {
    if (!instance.moving.value_or(false)) continue;
    if (instance.mask.type() != CV_8UC1 || instance.mask.size() != image_size) {
      throw std::invalid_argument("moving_mask_of: the mask of instance " + std::to_string(instance.id) +
                                  " is not CV_8UC1 of the image's size");
    }
    mask.setTo(255, instance.mask);
  }
  return mask;
}

}  // namespace slam
}  // namespace cge
