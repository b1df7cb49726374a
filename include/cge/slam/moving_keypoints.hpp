#pragma once
// The dynamic-feature leak (paper Figure 4): how many keypoints on bodies that really move in the
// world survive dynamic elimination. The ground truth is a moving mask: CV_8UC1, non-zero on the
// pixels of a moving body (from a synthetic sequence's masks/ folder or the renderer's labels).
//
// Pixels: a keypoint at (u, v) lies on pixel (round(u), round(v)), halves away from zero, clamped
// into the image; the pixel the DepthMADFilter and FrameMaker read (cge/frontend/depth_mad_filter.hpp).

#include <vector>

#include <opencv2/core.hpp>

#include "cge/frontend/feature_label.hpp"
#include "cge/segmentation/instance_segmenter.hpp"

namespace cge {
namespace slam {

struct MovingKeypointCounts {
  int moving_keypoints = 0;  ///< keypoints whose pixel is set in the moving mask
  int moving_kept = 0;       ///< of those, labelled static_feature (passed on to tracking)
};

/// Counts the keypoints on the moving mask and, of those, the ones labelled static. Throws
/// std::invalid_argument when the mask is empty or not CV_8UC1, or labels and keypoints differ in
/// number.
MovingKeypointCounts count_moving_keypoints(const std::vector<cv::KeyPoint>& keypoints,
                                            const std::vector<FeatureLabel>& labels, const cv::Mat& moving_mask);

/// The union of the masks of the instances known to move (SegmentedInstance::moving == true):
/// CV_8UC1 of image_size, 255 on them, 0 elsewhere; instances whose motion is unknown count as
/// not moving. Throws std::invalid_argument when such an instance's mask is not CV_8UC1 of
/// image_size.
cv::Mat moving_mask_of(const std::vector<SegmentedInstance>& instances, cv::Size image_size);

}  // namespace slam
}  // namespace cge
