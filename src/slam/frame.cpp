#include "cge/slam/frame.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "cge/core/splitmix64.hpp"
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

namespace {

/// Of each pyramid level's candidates, its share (count / oversampling, rounded) taken cell by
/// cell: the best response of every cell, then every cell's second best, ... (cells visited by
/// their best response, ties by candidate order). Keeps the candidates' order otherwise.
std::vector<cv::KeyPoint> spread_over_cells(const std::vector<cv::KeyPoint>& candidates, int oversampling,
                                            int cell_px, double scale_factor) {
  std::map<int, std::vector<int>> by_level;
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    by_level[std::max(candidates[static_cast<std::size_t>(i)].octave, 0)].push_back(i);
  }
  std::vector<char> keep(candidates.size(), 0);
  for (const auto& [level, members] : by_level) {
    const double cell = cell_px * std::pow(scale_factor, level);
    std::map<std::pair<int, int>, std::vector<int>> cells;  // (row, col) -> candidates
    for (const int i : members) {
      const cv::Point2f& p = candidates[static_cast<std::size_t>(i)].pt;
      cells[{static_cast<int>(p.y / cell), static_cast<int>(p.x / cell)}].push_back(i);
    }
    const auto stronger = [&](int a, int b) {
      const float ra = candidates[static_cast<std::size_t>(a)].response;
      const float rb = candidates[static_cast<std::size_t>(b)].response;
      return ra != rb ? ra > rb : a < b;
    };
    std::vector<std::vector<int>> ranked;
    for (auto& entry : cells) {
      std::sort(entry.second.begin(), entry.second.end(), stronger);
      ranked.push_back(std::move(entry.second));
    }
    std::sort(ranked.begin(), ranked.end(),
              [&](const std::vector<int>& a, const std::vector<int>& b) { return stronger(a.front(), b.front()); });
    const std::size_t quota = (members.size() + static_cast<std::size_t>(oversampling) / 2) /
                              static_cast<std::size_t>(oversampling);
    std::size_t taken = 0;
    for (std::size_t rank = 0; taken < quota; ++rank) {
      for (const std::vector<int>& cell_members : ranked) {
        if (rank < cell_members.size() && taken < quota) {
          keep[static_cast<std::size_t>(cell_members[rank])] = 1;
          ++taken;
        }
      }
    }
  }
  std::vector<cv::KeyPoint> out;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (keep[i]) out.push_back(candidates[i]);
  }
  return out;
}

}  // namespace

std::vector<cv::KeyPoint> FrameMaker::detect(const cv::Mat& gray, int fast_threshold, cv::Mat& descriptors) const {
  const OrbSettings& o = settings_.frame.orb;
  const int s = o.spread_oversampling;
  cv::Ptr<cv::ORB> orb = cv::ORB::create(o.features * s, static_cast<float>(o.scale_factor), o.levels,
                                         o.edge_threshold_px, 0, 2, cv::ORB::HARRIS_SCORE, o.patch_size_px,
                                         fast_threshold);
  std::vector<cv::KeyPoint> keypoints;
  if (s == 1) {
    orb->detectAndCompute(gray, cv::noArray(), keypoints, descriptors);
    return keypoints;
  }
  orb->detect(gray, keypoints);
  keypoints = spread_over_cells(keypoints, s, o.spread_cell_px, o.scale_factor);
  orb->compute(gray, keypoints, descriptors);
  return keypoints;
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
  f.keypoints = detect(gray, o.initial_fast_threshold, f.descriptors);
  if (static_cast<int>(f.keypoints.size()) < o.features && o.min_fast_threshold < o.initial_fast_threshold) {
    f.keypoints = detect(gray, o.min_fast_threshold, f.descriptors);
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
