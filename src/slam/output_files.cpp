#include "cge/slam/output_files.hpp"

#include <cstdio>

#include "cge/metrics/tum_trajectory_io.hpp"

namespace cge {
namespace slam {

namespace {

std::string format(const char* fmt, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, fmt, v);
  return buffer;
}

}  // namespace

std::string tum_pose_line(double timestamp_s, const Eigen::Isometry3d& T_world_camera) {
  return metrics::format_tum_pose(timestamp_s, T_world_camera, metrics::TumDigits::significant_9);
}

void write_trajectory(std::ostream& out, const System& system) {
  out << "# cge_slam trajectory: timestamp tx ty tz qx qy qz qw (T_world_camera, metres), lost frames omitted\n";
  for (const FrameRecord& r : system.frames()) {
    if (r.has_pose()) out << tum_pose_line(r.timestamp_s, system.pose_of(r)) << '\n';
  }
}

void write_keyframes(std::ostream& out, const Map& map) {
  out << "# cge_slam keyframes: timestamp tx ty tz qx qy qz qw (T_world_camera, metres)\n";
  for (const Keyframe& kf : map.keyframes()) out << tum_pose_line(kf.timestamp_s, kf.T_world_camera) << '\n';
}

void write_loops_csv(std::ostream& out, const std::vector<LoopRecord>& loops) {
  out << "query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_points,accepted,"
         "reason,tentative_matches,verified_keyframes,connected_keyframes\n";
  for (const LoopRecord& l : loops) {
    const bool match = l.match_keyframe >= 0;
    out << format("%.6f", l.query_timestamp_s) << ',' << (match ? format("%.6f", l.match_timestamp_s) : "") << ','
        << l.query_keyframe << ',' << (match ? std::to_string(l.match_keyframe) : "") << ','
        << (match ? format("%.9g", l.bow_score) : "") << ',' << (match ? format("%.9g", l.cge_score) : "") << ','
        << l.matched_points << ',' << (l.accepted ? 1 : 0) << ',' << l.reason << ',' << l.tentative_matches << ','
        << l.verified_keyframes << ',';
    for (std::size_t i = 0; i < l.connected_keyframes.size(); ++i) out << (i ? " " : "") << l.connected_keyframes[i];
    out << '\n';
  }
}

void write_timings_csv(std::ostream& out, const std::vector<FrameRecord>& frames) {
  out << "frame,timestamp";
  for (int s = 0; s < kStageCount; ++s) out << ',' << to_string(static_cast<Stage>(s)) << "_ms";
  out << '\n';
  for (const FrameRecord& r : frames) {
    out << r.index << ',' << format("%.6f", r.timestamp_s);
    for (const double ms : r.times_ms) out << ',' << format("%.3f", ms);
    out << '\n';
  }
}

void write_frames_csv(std::ostream& out, const std::vector<FrameRecord>& frames) {
  out << "frame,timestamp,state,keypoints,dynamic_by_mask,dynamic_by_mad,instances,matches,inliers,keyframe,"
         "keyframe_rule,moving_keypoints,moving_kept\n";
  for (const FrameRecord& r : frames) {
    out << r.index << ',' << format("%.6f", r.timestamp_s) << ',' << to_string(r.state) << ',' << r.keypoints << ','
        << r.dynamic_by_mask << ',' << r.dynamic_by_mad << ',' << r.instances << ',' << r.matches << ',' << r.inliers
        << ',' << (r.keyframe_id >= 0 ? std::to_string(r.keyframe_id) : "") << ','
        << (r.keyframe_id >= 0 ? r.keyframe_rule : "") << ',' << r.moving_keypoints << ',' << r.moving_kept << '\n';
  }
}

}  // namespace slam
}  // namespace cge
