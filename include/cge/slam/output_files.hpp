#pragma once
// The output files of the reference pipeline (formats fixed in the pipeline's brief, docs/CLI.md):
//   trajectory.txt  TUM format, every frame with a pose (lost frames omitted), T_world_camera
//   keyframes.txt   TUM format, the keyframes' current poses
//   loops.csv       one row per keyframe the loop closer processed
//   timings.csv     per frame and stage, milliseconds (measurements: differ between runs)
//   frames.csv      per frame: tracking state, feature and match counts, keyframe, keypoints on
//                   moving bodies and of those the kept ones (-1 without ground truth) (deterministic)
// TUM lines: metrics::format_tum_pose with 9 significant digits (timestamp with 6 decimals, the
// quaternion with qw >= 0, ties at qw == 0 by the first non-zero component; one spelling of zero).
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cge/slam/map.hpp"
#include "cge/slam/system.hpp"

namespace cge {
namespace slam {

/// One TUM trajectory line (no newline).
std::string tum_pose_line(double timestamp_s, const Eigen::Isometry3d& T_world_camera);

void write_trajectory(std::ostream& out, const System& system);
void write_keyframes(std::ostream& out, const Map& map);
void write_loops_csv(std::ostream& out, const std::vector<LoopRecord>& loops);
void write_timings_csv(std::ostream& out, const std::vector<FrameRecord>& frames);
void write_frames_csv(std::ostream& out, const std::vector<FrameRecord>& frames);

}  // namespace slam
}  // namespace cge
