#pragma once
// Keyframe: what the reference pipeline keeps of a frame it selected as a keyframe, shared by the
// tracker (which makes it), the loop closer (which scores and verifies it), the optimisers (which
// move its pose) and the map builders (which back-project its static pixels).
//
// Conventions: poses are T_world_camera (maps camera coordinates to world coordinates), metres;
// camera frame x right, y down, z forward (OpenCV/TUM). Per-keypoint vectors have one entry per
// row of `descriptors`, in the same order.
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <cstdint>
#include <vector>

#include "cge/core/semantic_instance.hpp"
#include "cge/frontend/feature_label.hpp"

namespace cge {
namespace slam {

struct Keyframe {
  int id = -1;            ///< 0, 1, 2, ... in creation order; also the index in the map's keyframe list
  int frame_index = -1;   ///< index of the frame in the sequence
  double timestamp_s = 0; ///< the frame's timestamp, seconds

  /// Current estimate; updated in place by pose-graph optimisation and bundle adjustment.
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();

  // ---- features (all detected keypoints, dynamic ones included, so the graph builder sees the same
  //      point set the filter saw; use `labels` to pick the static ones) --------------------------------
  std::vector<cv::KeyPoint> keypoints;           ///< pixel positions as detected (distorted image), octave, angle
  /// Keypoint positions in the ideal pinhole camera (lens distortion removed), pixels: what every
  /// geometric step uses (projection matching, PnP, bundle adjustment, triangulation). Equal to
  /// keypoints[i].pt when the camera has no distortion.
  std::vector<cv::Point2f> undistorted_px;
  cv::Mat descriptors;                           ///< CV_8UC1, one 32-byte ORB row per keypoint
  std::vector<FeatureLabel> labels;              ///< static / dynamic_by_mask / dynamic_by_mad
  std::vector<Eigen::Vector3d> points_camera_m;  ///< back-projected from depth; NaN where no valid depth
  std::vector<std::int64_t> map_point_ids;       ///< the map point each keypoint observes, -1 if none

  // ---- culling (map maintenance) -------------------------------------------------------------------
  /// Culled as redundant: it observes no map point any more and its pose follows `parent` (the
  /// culled keyframe's pose is parent's pose times T_parent_camera, see Map::keyframe_pose).
  bool culled = false;
  int parent = -1;  ///< the keyframe this one's pose is kept relative to once culled
  Eigen::Isometry3d T_parent_camera = Eigen::Isometry3d::Identity();

  // ---- semantics ---------------------------------------------------------------------------------
  std::vector<SemanticInstance<double>> instances;  ///< every segmented instance, dynamic flag set
  cv::Mat dynamic_mask;  ///< CV_8UC1, 255 on pixels of dynamic instances (empty Mat: none)

  // ---- images kept for the dense maps (may be empty when the caller does not build maps) ------------
  cv::Mat bgr;              ///< CV_8UC3
  cv::Mat depth_m;          ///< CV_32FC1 metres, 0 where invalid
  cv::Mat class_labels;     ///< CV_16UC1: class id + 1 of the instance covering the pixel, 0 = none
};

/// Keypoint i's position in the ideal pinhole camera, pixels: undistorted_px[i] when the keyframe
/// carries undistorted positions (Map::add_keyframe fills them), else the detected position (a
/// keyframe built without them is taken to come from an undistorted camera).
inline cv::Point2f undistorted_position(const Keyframe& kf, std::size_t i) {
  return kf.undistorted_px.empty() ? kf.keypoints[i].pt : kf.undistorted_px[i];
}

}  // namespace slam
}  // namespace cge
