#include "cge/slam/frame.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "cge/core/splitmix64.hpp"
#include "cge/slam/keypoint_spread.hpp"
#include "cge/opencv.hpp"

namespace cge {
namespace slam {

int Frame::count(FeatureLabel label) const { return static_cast<int>(std::count(labels.begin(), labels.end(), label)); }

std::uint64_t frame_seed(std::uint64_t seed, int frame_index) {
  // Output frame_index + 1 of a splitmix64 stream seeded with the run's seed: distinct, well-mixed
  // seeds per frame, each computed directly.
  return splitmix64_nth(seed, static_cast<std::uint64_t>(frame_index) + 1);
}

FrameMaker::FrameMaker(const SystemSettings& settings, const PinholeIntrinsics<double>& intrinsics)
    : settings_(settings), intrinsics_(intrinsics), mad_filter_(settings.frame.mad) {
  settings_.validate();
  const auto ok = [](double v) { return std::isfinite(v); };
  if (!(ok(intrinsics.fx_px) && intrinsics.fx_px > 0 && ok(intrinsics.fy_px) && intrinsics.fy_px > 0 &&
        ok(intrinsics.cx_px) && ok(intrinsics.cy_px))) {
    throw std::invalid_argument("FrameMaker: the intrinsics must be finite with positive focal lengths");
  }
}

cv::Ptr<cv::ORB> FrameMaker::orb(int fast_threshold) const {
  const OrbSettings& o = settings_.frame.orb;
  return cv::ORB::create(o.features * o.spread_oversampling, static_cast<float>(o.scale_factor), o.levels,
                         o.edge_threshold_px, 0, 2, cv::ORB::HARRIS_SCORE, o.patch_size_px, fast_threshold);
}

std::vector<cv::KeyPoint> FrameMaker::detect_spread(const cv::Mat& gray, int fast_threshold) const {
  const OrbSettings& o = settings_.frame.orb;
  std::vector<cv::KeyPoint> keypoints;
  orb(fast_threshold)->detect(gray, keypoints);
  return spread_over_cells(keypoints, o.spread_oversampling, o.spread_cell_px, o.scale_factor);
}

Frame FrameMaker::extract(int index, double timestamp_s, const cv::Mat& bgr, const cv::Mat& depth) {
  const std::string where = "frame " + std::to_string(index) + ": ";
  if (bgr.empty()) throw std::invalid_argument(where + "the colour image is empty");
  if (bgr.type() != CV_8UC3) {
    throw std::invalid_argument(where + "the colour image has type " + cv::typeToString(bgr.type()) +
                                ", expected CV_8UC3");
  }
  if (depth.empty()) throw std::invalid_argument(where + "the depth image is empty");
  if (depth.type() != CV_16UC1 && depth.type() != CV_32FC1) {
    throw std::invalid_argument(where + "the depth image has type " + cv::typeToString(depth.type()) +
                                ", expected CV_16UC1 or CV_32FC1");
  }
  if (depth.size() != bgr.size()) {
    throw std::invalid_argument(where + "the depth image is " + std::to_string(depth.cols) + " x " +
                                std::to_string(depth.rows) + " pixels but the colour image " +
                                std::to_string(bgr.cols) + " x " + std::to_string(bgr.rows));
  }
  Frame f;
  f.index = index;
  f.timestamp_s = timestamp_s;
  f.image_size = bgr.size();
  f.bgr = bgr;
  if (depth.type() == CV_16UC1) {
    depth.convertTo(f.depth_m, CV_32F, 1.0 / settings_.frame.depth_units_per_metre);
  } else {
    f.depth_m = depth.clone();
  }

  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  const OrbSettings& o = settings_.frame.orb;
  // A second detection at the lower threshold when the first keeps fewer than `features`.
  const bool may_retry = o.min_fast_threshold < o.initial_fast_threshold;
  if (o.spread_oversampling == 1) {
    orb(o.initial_fast_threshold)->detectAndCompute(gray, cv::noArray(), f.keypoints, f.descriptors);
    if (static_cast<int>(f.keypoints.size()) < o.features && may_retry) {
      orb(o.min_fast_threshold)->detectAndCompute(gray, cv::noArray(), f.keypoints, f.descriptors);
    }
  } else {
    f.keypoints = detect_spread(gray, o.initial_fast_threshold);
    if (static_cast<int>(f.keypoints.size()) < o.features && may_retry) {
      f.keypoints = detect_spread(gray, o.min_fast_threshold);
    }
    // Descriptors once, for the keypoints kept (the FAST threshold does not enter them).
    orb(o.initial_fast_threshold)->compute(gray, f.keypoints, f.descriptors);
  }

  const FrameSettings& fs = settings_.frame;
  std::vector<cv::Point2f> detected(f.keypoints.size());
  for (std::size_t i = 0; i < f.keypoints.size(); ++i) detected[i] = f.keypoints[i].pt;
  f.undistorted_px = opencv::undistort_pixels(detected, intrinsics_, fs.distortion, fs.undistort);
  if (bounds_size_ != f.image_size) {
    undistorted_bounds_ = opencv::undistorted_image_bounds(f.image_size, intrinsics_, fs.distortion, fs.undistort);
    bounds_size_ = f.image_size;
  }
  f.undistorted_bounds = undistorted_bounds_;

  const double nan = std::numeric_limits<double>::quiet_NaN();
  f.labels.assign(f.keypoints.size(), FeatureLabel::static_feature);
  f.points_camera_m.assign(f.keypoints.size(), Eigen::Vector3d(nan, nan, nan));
  for (std::size_t i = 0; i < f.keypoints.size(); ++i) {
    // The depth image is registered to the (distorted) colour image: read it where the keypoint
    // was detected, back-project from where the ideal camera sees it.
    const double d = f.depth_m.at<float>(opencv::nearest_pixel(detected[i], f.depth_m.size()));
    if (std::isfinite(d) && d > fs.min_depth_m && d < fs.max_depth_m) {
      const cv::Point2f& u = f.undistorted_px[i];
      f.points_camera_m[i] = intrinsics_.backproject(u.x, u.y, d);
    }
  }
  return f;
}

void FrameMaker::label(Frame& frame, const std::vector<SegmentedInstance>& instances) {
  frame.instances.clear();
  for (const SegmentedInstance& inst : instances) frame.instances.push_back(to_semantic_instance<double>(inst));
  frame.dynamic_mask = union_dynamic_masks(instances, frame.image_size);
  const DynamicMode mode = settings_.mode;
  std::fill(frame.labels.begin(), frame.labels.end(), FeatureLabel::static_feature);
  if (!uses_masks(mode)) return;
  if (!uses_mad(mode)) {
    // Mask test only (step 1 of the filter), on the pixel the filter would read.
    for (std::size_t i = 0; i < frame.keypoints.size(); ++i) {
      const cv::Point pixel = opencv::nearest_pixel(frame.keypoints[i].pt, frame.image_size);
      if (frame.dynamic_mask.at<std::uint8_t>(pixel) != 0) frame.labels[i] = FeatureLabel::dynamic_by_mask;
    }
    return;
  }
  std::vector<DynamicInstance<cv::Mat>> dynamic;
  for (const SegmentedInstance& inst : instances) {
    if (inst.dynamic && cv::countNonZero(inst.mask) > 0) {
      dynamic.push_back(dynamic_instance(inst.mask, filter_box(inst, frame.image_size), inst.class_id));
    }
  }
  mad_filter_.engine.seed(frame_seed(settings_.seed, frame.index));
  const DepthMADResult result =
      mad_filter_.filter(frame.keypoints, opencv::DepthView::from_metres(frame.depth_m), dynamic);
  frame.labels = result.labels;
}

}  // namespace slam
}  // namespace cge
