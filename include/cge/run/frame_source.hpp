#pragma once
// FrameSource: the frames a SLAM run processes, read from a dataset folder
// (cge/run/dataset_frame_source.hpp) or rendered in memory (cge/run/rendered_frame_source.hpp),
// with the ground truth the source knows for the run's evaluation.
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/segmentation/instance_segmenter.hpp"
#include "cge/slam/system.hpp"

namespace cge {
namespace run {

/// Ground-truth poses: (timestamp in seconds, T_world_camera).
using GroundTruthPoses = std::vector<std::pair<double, Eigen::Isometry3d>>;

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual int frame_count() const = 0;
  /// Frame `index`, 0 <= index < frame_count(); frames are asked for in order, frame 0 possibly twice.
  virtual slam::FrameInput frame(int index) = 0;
  /// Whether the source segments its frames itself (rendered ground truth); the System's
  /// segmenter is used otherwise.
  virtual bool provides_instances() const { return false; }
  /// The instances of the frame last returned by frame(index).
  virtual std::vector<SegmentedInstance> instances(int /*index*/) { return {}; }
  /// Ground-truth poses, when known (empty otherwise).
  virtual GroundTruthPoses ground_truth() const { return {}; }
  /// Ground-truth loops, when known (std::nullopt: none to evaluate against). `queries`: the stamps
  /// (as "%.6f") of the keyframes the loop closer queried; a source may keep only their loops.
  virtual std::optional<std::vector<metrics::GroundTruthLoop>> ground_truth_loops(
      const std::set<std::string>& /*queries*/) const {
    return std::nullopt;
  }
};

}  // namespace run
}  // namespace cge
