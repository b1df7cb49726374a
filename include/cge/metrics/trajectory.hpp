#pragma once
// A camera trajectory: timestamped poses T_world_camera, as the TUM RGB-D benchmark stores them.
// The metrics (association, ATE, RPE) want the timestamps finite and strictly increasing; the TUM
// reader guarantees it, and every metric checks it again for trajectories built in code.

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace cge {
namespace metrics {

struct StampedPose {
  double timestamp_s = 0.0;                                          ///< seconds (any epoch)
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  ///< camera to world
};

using Trajectory = std::vector<StampedPose>;

/// The timestamps of a trajectory, in order.
inline std::vector<double> timestamps(const Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const StampedPose& pose : trajectory) stamps.push_back(pose.timestamp_s);
  return stamps;
}

/// Throws std::invalid_argument naming `what` and the first offending index unless every
/// timestamp is finite and larger than the one before.
inline void require_increasing_timestamps(const std::vector<double>& stamps_s, const std::string& what) {
  for (std::size_t i = 0; i < stamps_s.size(); ++i) {
    if (!std::isfinite(stamps_s[i])) {
      throw std::invalid_argument(what + ": timestamp " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(stamps_s[i] > stamps_s[i - 1])) {
      throw std::invalid_argument(what + ": timestamp " + std::to_string(i) + " does not come after timestamp " +
                                  std::to_string(i - 1) + " (timestamps must increase)");
    }
  }
}

/// Throws std::invalid_argument naming `what` unless the timestamps increase (as above) and every
/// pose is finite.
inline void require_valid_trajectory(const Trajectory& trajectory, const std::string& what) {
  require_increasing_timestamps(timestamps(trajectory), what);
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    if (!trajectory[i].T_world_camera.matrix().allFinite()) {
      throw std::invalid_argument(what + ": pose " + std::to_string(i) + " is not finite");
    }
  }
}

}  // namespace metrics
}  // namespace cge
