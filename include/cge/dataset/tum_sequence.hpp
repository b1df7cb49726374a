#pragma once
// TumSequence: a TUM RGB-D sequence folder (or a synthetic one written by cge::sim, same layout),
// opened once and read frame by frame.
//
// The folder (docs/DATASETS.md):
//   rgb.txt, depth.txt     `timestamp path` lists (cge/dataset/tum_list.hpp), required unless the
//                          associations file is used
//   associations.txt       `t_rgb rgb_path t_depth depth_path` (associate.py output), optional; used
//                          only when TumSequenceSettings::use_associations_file (default: the lists
//                          win and associations.txt is ignored, so one rule decides every frame)
//   groundtruth.txt        `timestamp tx ty tz qx qy qz qw` (T_world_camera), optional
//   masks/, segmentation/  mask folders (docs/SEGMENTATION.md), optional; only reported here
//   camera.yaml            ORB-SLAM2 settings (cge/dataset/orbslam2_settings.hpp), optional; reported
//
// The constructor reads and checks the text files; images are read by load(i) only. A frame is an
// associated (RGB, depth) pair, in RGB-timestamp order; its timestamp is the RGB one (the TUM
// convention for trajectories). Errors are std::invalid_argument naming the file and line.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/segmentation/instance_segmenter.hpp"

namespace cge {
namespace dataset {

struct TumSequenceSettings {
  /// Largest |t_rgb - (t_depth + depth_time_offset_s)| of an associated pair, seconds (associate.py: 0.02).
  double max_time_difference_s = 0.02;
  /// Added to the depth timestamps before the association, seconds (associate.py --offset).
  double depth_time_offset_s = 0.0;
  /// Take the pairs from associations.txt (when present) instead of associating rgb.txt and depth.txt.
  bool use_associations_file = false;
  /// Depth image units per metre (ORB-SLAM2 DepthMapFactor; TUM and cge::sim: 5000).
  double depth_units_per_metre = 5000.0;
  /// Largest |‖q‖ - 1| accepted for a ground-truth quaternion (TUM writes 4 decimals); it is normalised.
  double quaternion_norm_tolerance = 1e-2;
};

/// Throws std::invalid_argument naming the first setting out of range.
void check_settings(const TumSequenceSettings& settings);

/// Where an associated frame's files are.
struct TumFrameFiles {
  double rgb_timestamp_s = 0;
  double depth_timestamp_s = 0;
  std::filesystem::path rgb_path;    ///< resolved against the sequence folder
  std::filesystem::path depth_path;  ///< resolved against the sequence folder
  std::string rgb_source;            ///< "<list file>:<line>" that named the RGB image
  std::string depth_source;          ///< "<list file>:<line>" that named the depth image
};

/// One frame, loaded.
struct TumFrame {
  int index = 0;               ///< 0-based position in the sequence
  double rgb_timestamp_s = 0;  ///< the frame's timestamp
  double depth_timestamp_s = 0;
  std::string rgb_stem;  ///< RGB file name without extension (mask-folder key, TUM: the timestamp)
  std::string depth_stem;
  cv::Mat bgr;    ///< CV_8UC3, BGR
  cv::Mat depth;  ///< CV_16UC1 as stored, depth_units_per_metre units per metre, 0 = none
  double depth_units_per_metre = 5000.0;

  /// Depth in metres, CV_32FC1 (0 stays 0 = no measurement).
  cv::Mat depth_metres() const;
  /// What a segmenter takes (shares the pixels).
  FrameImage frame_image() const { return FrameImage{bgr, rgb_stem}; }
};

/// One ground-truth pose.
struct GroundTruthPose {
  double timestamp_s = 0;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

class TumSequence {
 public:
  /// Reads the lists (and groundtruth.txt when present) and associates them. Throws
  /// std::invalid_argument for invalid settings, a missing folder or list, a malformed line
  /// (file:line), decreasing timestamps, no associated pair, or an empty list.
  explicit TumSequence(std::filesystem::path folder, TumSequenceSettings settings = {});

  int frame_count() const { return static_cast<int>(files_.size()); }

  /// Reads frame `index`. Throws std::out_of_range for an index outside 0 .. frame_count() - 1, and
  /// std::invalid_argument naming the image (and the list line) when an image is missing or cannot
  /// be decoded, the depth image is not single-channel 16-bit, or the two differ in size.
  TumFrame load(int index) const;

  /// The files of frame `index` (std::out_of_range outside the sequence).
  const TumFrameFiles& files(int index) const;
  /// The frame's (RGB) timestamp.
  double timestamp_s(int index) const { return files(index).rgb_timestamp_s; }

  /// RGB entries without a depth partner (dropped by the association).
  int unassociated_rgb_count() const { return unassociated_rgb_; }

  /// groundtruth.txt, in file order (timestamps non-decreasing; a repeated timestamp keeps both
  /// lines, as in TUM's fr2_desk); empty when the file is absent.
  const std::vector<GroundTruthPose>& ground_truth() const { return ground_truth_; }
  bool has_ground_truth() const { return !ground_truth_.empty(); }

  /// The exact-ground-truth mask folder (masks/), when it exists.
  const std::optional<std::filesystem::path>& masks_folder() const { return masks_folder_; }
  /// The mask folder after the segmentation error model (segmentation/), when it exists.
  const std::optional<std::filesystem::path>& segmentation_folder() const { return segmentation_folder_; }
  /// camera.yaml, when it exists.
  const std::optional<std::filesystem::path>& camera_settings_file() const { return camera_settings_file_; }

  const std::filesystem::path& folder() const { return folder_; }
  const TumSequenceSettings& settings() const { return settings_; }

 private:
  std::filesystem::path folder_;
  TumSequenceSettings settings_;
  std::vector<TumFrameFiles> files_;
  int unassociated_rgb_ = 0;
  std::vector<GroundTruthPose> ground_truth_;
  std::optional<std::filesystem::path> masks_folder_, segmentation_folder_, camera_settings_file_;
};

}  // namespace dataset
}  // namespace cge
