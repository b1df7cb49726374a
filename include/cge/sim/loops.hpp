#pragma once
// Ground-truth loops of a camera trajectory, decided from the poses alone.
//
// Frames m < q form a loop pair when the camera, between them, travelled at least min_travel_m
// along its path (so it left the place and came back; neighbouring frames never count), and at q
// it is back within max_distance_m of where it was at m, with optical axes at most max_angle_deg
// apart (it sees the same place). Every such pair is listed, sorted by (query, match).

#include <vector>

#include <Eigen/Geometry>

#include "cge/sim/sequence.hpp"

namespace cge {
namespace sim {

struct LoopSettings {
  double max_distance_m = 0.3;  ///< largest distance between the two camera centres, metres, > 0
  double max_angle_deg = 20;    ///< largest angle between the two optical axes, degrees, in (0, 180]
  double min_travel_m = 2.0;    ///< least path length travelled from match to query, metres, > 0
};

/// Throws std::invalid_argument for settings outside the ranges above or a non-finite pose.
std::vector<LoopPair> ground_truth_loops(const std::vector<Eigen::Isometry3d>& T_world_camera,
                                         const LoopSettings& settings = {});

}  // namespace sim
}  // namespace cge
