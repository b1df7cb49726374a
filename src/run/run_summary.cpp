#include "cge/run/run_summary.hpp"

#include <stdexcept>
#include <utility>

#include "cge/metrics/ate.hpp"
#include "cge/metrics/error_statistics.hpp"
#include "cge/metrics/rpe.hpp"

namespace cge {
namespace run {

double median(std::vector<double> values) {
  return values.empty() ? 0.0 : metrics::error_statistics(std::move(values)).median;
}

DynamicLeak dynamic_leak(const std::vector<slam::FrameRecord>& frames) {
  DynamicLeak leak;
  for (const auto& r : frames) {
    if (r.moving_keypoints < 0) continue;
    ++leak.frames_with_ground_truth;
    leak.moving_keypoints += r.moving_keypoints;
    leak.moving_kept += r.moving_kept;
  }
  if (leak.moving_keypoints > 0) {
    leak.rate = static_cast<double>(leak.moving_kept) / static_cast<double>(leak.moving_keypoints);
  }
  return leak;
}

std::array<StageTime, slam::kStageCount> stage_times(const std::vector<slam::FrameRecord>& frames) {
  std::array<StageTime, slam::kStageCount> stages{};
  for (int s = 0; s < slam::kStageCount; ++s) {
    std::vector<double> ms;
    double sum = 0;
    for (const auto& r : frames) {
      ms.push_back(r.times_ms[static_cast<std::size_t>(s)]);
      sum += ms.back();
    }
    StageTime& t = stages[static_cast<std::size_t>(s)];
    t.mean_ms = frames.empty() ? 0.0 : sum / static_cast<double>(frames.size());
    t.median_ms = median(std::move(ms));
  }
  return stages;
}

TrajectoryErrors trajectory_errors(const GroundTruthPoses& ground_truth, const GroundTruthPoses& estimate) {
  metrics::Trajectory gt, est;
  for (const auto& p : ground_truth) gt.push_back({p.first, p.second});
  for (const auto& p : estimate) est.push_back({p.first, p.second});
  TrajectoryErrors e;
  try {
    e.ate_m = metrics::compute_ate(gt, est).translation_m;
  } catch (const std::invalid_argument& error) {
    e.ate_error = error.what();
  }
  e.rpe_delta_s = metrics::RpeSettings{}.delta;
  try {
    const metrics::RpeResult rpe = metrics::compute_rpe(gt, est);
    e.rpe_translation_m = rpe.translation_m;
    e.rpe_rotation_deg = rpe.rotation_deg;
  } catch (const std::invalid_argument& error) {
    e.rpe_error = error.what();
  }
  return e;
}

RunSummary summarise_run(const slam::System& system, const GroundTruthPoses& ground_truth) {
  RunSummary s;
  const std::vector<slam::FrameRecord>& frames = system.frames();
  GroundTruthPoses estimate;
  for (const auto& r : frames) {
    s.tracked_frames += r.has_pose();
    s.odometry_frames += r.state == slam::TrackingState::odometry;
    s.relocalised_frames += r.state == slam::TrackingState::relocalised;
    if (r.has_pose()) estimate.emplace_back(r.timestamp_s, system.pose_of(r));
  }
  s.frames = frames.size();
  s.lost_frames = static_cast<int>(frames.size()) - s.tracked_frames;
  s.keyframes = system.map().active_keyframe_count();
  s.keyframes_inserted = system.map().keyframe_count();
  s.map_points = system.map().active_map_point_count();
  s.map_points_created = system.map().map_point_count();
  s.loop_candidates = system.loops().size();
  for (const auto& l : system.loops()) s.loops_accepted += l.accepted;
  s.loop_corrections = system.loop_corrections();
  s.dynamic_leak = dynamic_leak(frames);
  s.stages = stage_times(frames);
  if (!ground_truth.empty() && !estimate.empty()) s.trajectory_errors = trajectory_errors(ground_truth, estimate);
  return s;
}

}  // namespace run
}  // namespace cge
