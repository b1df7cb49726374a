#pragma once
// What a synthetic dynamic RGB-D sequence is made of: the camera, the instances in the scene, the
// rendered frames and the ground-truth loops. Shared by the renderer (cge/sim/renderer.hpp), the
// segmentation error model and the writer of the TUM layout, and by tests that render in memory.
//
// Conventions (the same as the TUM RGB-D benchmark, so synthetic and real data read alike):
// - camera frame: x right, y down, z forward (optical axis); world frame: z up.
// - T_world_camera maps camera coordinates to world coordinates (the pose groundtruth.txt lists).
// - depth images are 16-bit, depth_units_per_metre (5000) per metre, 0 = no measurement.
// - instance-label images are 16-bit: 0 = background, otherwise an InstanceInfo::id.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace cge {
namespace sim {

/// Pinhole camera without distortion; defaults are the TUM fr3 intrinsics at 640 x 480.
struct PinholeCamera {
  double fx_px = 535.4;                  ///< focal length along x, pixels
  double fy_px = 539.2;                  ///< focal length along y, pixels
  double cx_px = 320.1;                  ///< principal point x, pixels
  double cy_px = 247.6;                  ///< principal point y, pixels
  int width_px = 640;                    ///< image width, pixels
  int height_px = 480;                   ///< image height, pixels
  double depth_units_per_metre = 5000;   ///< depth image scale (TUM: 5000 units = 1 m)
};

/// One object instance of a sequence (a wall or floor is background, not an instance).
struct InstanceInfo {
  std::uint16_t id = 0;  ///< value in the instance-label images, >= 1
  int class_id = 0;      ///< COCO class id (cge/segmentation/coco_classes.hpp), e.g. 0 person, 56 chair
  bool moving = false;   ///< true when the body moves in the world during the sequence (ground truth)
};

/// One rendered frame with its ground truth.
struct RenderedFrame {
  int index = 0;                                                ///< 0-based frame number
  double timestamp_s = 0;                                       ///< seconds, as in rgb.txt
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  ///< ground-truth camera pose
  cv::Mat rgb;              ///< CV_8UC3, BGR (OpenCV's channel order)
  cv::Mat depth;            ///< CV_16UC1, realistic depth (noise, quantisation, holes), 0 = none
  cv::Mat instance_labels;  ///< CV_16UC1, exact ground-truth instance ids, 0 = background
};

/// A ground-truth loop: the query frame revisits the place seen in the match frame (match < query).
struct LoopPair {
  int query_frame = 0;
  int match_frame = 0;
};

}  // namespace sim
}  // namespace cge
