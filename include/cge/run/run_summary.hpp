#pragma once
// The figures of a SLAM run (summary.json of cge_slam, docs/SLAM.md): counts of frames, keyframes,
// map points and loops, the dynamic-feature leak, mean and median time per stage, and ATE / RPE
// against the ground truth as cge_eval computes them.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cge/metrics/error_statistics.hpp"
#include "cge/run/frame_source.hpp"
#include "cge/slam/system.hpp"

namespace cge {
namespace run {

/// Keypoints on the ground-truth moving bodies that the dynamic filter kept, over the frames with
/// a moving mask (FrameRecord::moving_keypoints >= 0).
struct DynamicLeak {
  long long frames_with_ground_truth = 0;
  long long moving_keypoints = 0;
  long long moving_kept = 0;
  /// moving_kept / moving_keypoints; none when no keypoint lay on a moving body.
  std::optional<double> rate;
};

struct StageTime {
  double mean_ms = 0;    ///< 0 without frames
  double median_ms = 0;  ///< the mean of the two middle values for an even count; 0 without frames
};

/// ATE and RPE (fixed delta of 1 s, cge_eval rpe's default) of the tracked frames; each either
/// computed or the reason it could not be (e.g. too few associated pairs).
struct TrajectoryErrors {
  std::optional<metrics::ErrorStatistics> ate_m;
  std::string ate_error;
  std::optional<metrics::ErrorStatistics> rpe_translation_m;
  std::optional<metrics::ErrorStatistics> rpe_rotation_deg;
  std::string rpe_error;
  double rpe_delta_s = 0;
};

struct RunSummary {
  std::size_t frames = 0;
  int tracked_frames = 0;  ///< every frame with a pose, odometry and relocalised ones included
  int lost_frames = 0;
  int odometry_frames = 0;
  int relocalised_frames = 0;
  // After map maintenance culled keyframes and erased points (ORB-SLAM2's counts), and all made.
  int keyframes = 0;
  int keyframes_inserted = 0;
  std::int64_t map_points = 0;
  std::int64_t map_points_created = 0;
  std::size_t loop_candidates = 0;
  int loops_accepted = 0;
  int loop_corrections = 0;
  DynamicLeak dynamic_leak;
  std::array<StageTime, slam::kStageCount> stages{};
  /// Set when there is ground truth and a tracked frame.
  std::optional<TrajectoryErrors> trajectory_errors;
};

/// The median of `values`: 0 when empty, otherwise metrics::error_statistics' median (which
/// refuses non-finite values with std::invalid_argument).
double median(std::vector<double> values);

DynamicLeak dynamic_leak(const std::vector<slam::FrameRecord>& frames);

/// Mean and median milliseconds of each slam::Stage over `frames`.
std::array<StageTime, slam::kStageCount> stage_times(const std::vector<slam::FrameRecord>& frames);

/// ATE and RPE of `estimate` against `ground_truth` (both non-empty).
TrajectoryErrors trajectory_errors(const GroundTruthPoses& ground_truth, const GroundTruthPoses& estimate);

/// Every figure of a finished run.
RunSummary summarise_run(const slam::System& system, const GroundTruthPoses& ground_truth);

}  // namespace run
}  // namespace cge
