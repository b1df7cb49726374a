#pragma once
// Frame: one RGB-D image pair reduced to what tracking needs (ORB keypoints and descriptors, a 3-D
// point per keypoint from depth, a dynamic label per keypoint), and FrameMaker, which makes it in
// two timed steps: extract() (features and depth) and label() (dynamic elimination by mode).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/frontend/depth_mad_filter.hpp"
#include "cge/frontend/feature_label.hpp"
#include "cge/opencv/undistort.hpp"
#include "cge/segmentation/instance_segmenter.hpp"
#include "cge/slam/settings.hpp"

namespace cge {
namespace slam {

struct Frame {
  int index = 0;           ///< frame number in the sequence
  double timestamp_s = 0;  ///< seconds
  cv::Size image_size;     ///< pixels

  std::vector<cv::KeyPoint> keypoints;           ///< level-0 pixel positions as detected (distorted image)
  /// Keypoint positions in the ideal pinhole camera, pixels (lens distortion removed; equal to
  /// keypoints[i].pt without distortion): what projection matching, PnP and refinement use.
  std::vector<cv::Point2f> undistorted_px;
  /// The image's extent in undistorted pixels: map points projecting outside it are not searched.
  opencv::ImageBounds undistorted_bounds;
  cv::Mat descriptors;                           ///< CV_8UC1, one 32-byte ORB row per keypoint
  std::vector<FeatureLabel> labels;              ///< all static until label()
  /// Back-projected from the undistorted position and the depth read at the detected pixel; NaN
  /// where depth is missing or outside FrameSettings' range.
  std::vector<Eigen::Vector3d> points_camera_m;

  std::vector<SemanticInstance<double>> instances;  ///< every segmented instance (all classes)
  cv::Mat dynamic_mask;                             ///< CV_8UC1, 255 on dynamic instances; empty when none was given

  cv::Mat bgr;      ///< the colour image (shared with the caller's Mat, not copied)
  cv::Mat depth_m;  ///< CV_32FC1 metres, 0 where invalid
  /// CV_16UC1 class id + 1 of the instance covering each pixel, 0 = none; only filled when the
  /// System keeps keyframe images (for the semantic maps).
  cv::Mat class_labels;

  int size() const { return static_cast<int>(keypoints.size()); }
  bool has_depth(int i) const { return std::isfinite(points_camera_m[static_cast<std::size_t>(i)].z()); }
  bool is_static(int i) const { return labels[static_cast<std::size_t>(i)] == FeatureLabel::static_feature; }
  int count(FeatureLabel label) const;
};

/// Pixel standard deviation of a keypoint detected at pyramid level `octave`: scale_factor^octave
/// (ORB-SLAM2's convention; a keypoint without an octave counts as level 0), pixels.
inline double keypoint_sigma_px(const cv::KeyPoint& keypoint, double scale_factor) {
  return std::pow(scale_factor, std::max(keypoint.octave, 0));
}

/// The seed of frame `frame_index`'s MAD samples: a mix (splitmix64) of the run's seed and the
/// index, so a frame's labels depend on that frame alone.
std::uint64_t frame_seed(std::uint64_t seed, int frame_index);

class FrameMaker {
 public:
  /// Throws std::invalid_argument for bad settings or intrinsics.
  FrameMaker(const SystemSettings& settings, const PinholeIntrinsics<double>& intrinsics);

  /// ORB features of `bgr` (CV_8UC3) and their depth from `depth` (CV_16UC1 in
  /// settings.frame.depth_units_per_metre units, or CV_32FC1 metres) of the same size. Labels are
  /// all static. Throws std::invalid_argument naming the problem for empty images, wrong types or
  /// sizes that differ. Keypoints are undistorted with settings.frame.distortion.
  Frame extract(int index, double timestamp_s, const cv::Mat& bgr, const cv::Mat& depth);

  /// Dynamic elimination of `frame` by the mode: none leaves every label static; Y labels keypoints
  /// on a dynamic instance's mask dynamic_by_mask; YM and YMK run the DepthMADFilter (mask test and
  /// MAD test) with a per-frame engine seeded by frame_seed(settings.seed, frame.index). Stores the
  /// instances (as SemanticInstance) and the union of the dynamic masks in the frame.
  void label(Frame& frame, const std::vector<SegmentedInstance>& instances);

  const PinholeIntrinsics<double>& intrinsics() const { return intrinsics_; }
  const SystemSettings& settings() const { return settings_; }

 private:
  /// cv::ORB with the settings' pyramid, oversampled feature count and this FAST threshold.
  cv::Ptr<cv::ORB> orb(int fast_threshold) const;
  /// ORB keypoints (no descriptors) at one FAST threshold, spread over the image by
  /// spread_over_cells (spread_oversampling > 1).
  std::vector<cv::KeyPoint> detect_spread(const cv::Mat& gray, int fast_threshold) const;

  SystemSettings settings_;
  PinholeIntrinsics<double> intrinsics_;
  DepthMADFilter<> mad_filter_;
  cv::Size bounds_size_;                 ///< the image size undistorted_bounds_ was computed for
  opencv::ImageBounds undistorted_bounds_;
};

}  // namespace slam
}  // namespace cge
