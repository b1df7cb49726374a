#pragma once
// SlamRunOptions: what a user chooses for a SLAM run (cge_slam's command line, docs/CLI.md), as
// text and numbers; cge/run/run_settings.hpp turns them into the pipeline's settings. Defaults come
// from the settings structs they override (each documents its own source).
#include <cstdint>
#include <string>

#include "cge/frontend/depth_mad_filter.hpp"
#include "cge/segmentation/temporal_instance_filter.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/settings.hpp"

namespace cge {
namespace run {

/// The rendered preset of a run without a dataset.
constexpr const char* kDefaultPreset = "walking_xyz";
/// Frames of a rendered run when none are asked for: 10 s at 30 fps.
constexpr int kDefaultPresetFrames = 300;
/// The vocabulary value that switches loop closing off.
constexpr const char* kNoVocabulary = "none";

/// The temporal filter's default as the option spells it: "N/M" of TemporalInstanceFilterSettings.
inline std::string default_temporal_filter() {
  const TemporalInstanceFilterSettings d;
  return std::to_string(d.min_frames_seen) + "/" + std::to_string(d.window_frames);
}

struct SlamRunOptions {
  std::string dataset;                  ///< TUM folder; empty: render `preset`
  std::string preset = kDefaultPreset;  ///< rendered when there is no dataset
  std::string mode = "YMK";             ///< none, Y, YM, YMK
  std::string segmentation;             ///< empty: ground_truth, or none in mode none
  std::string model;                    ///< YOLOv8-seg ONNX (segmentation yolo)
  std::string masks;                    ///< mask folder (segmentation precomputed)
  /// Temporal instance filter of the network sources: "N/M" (seen in N of the last M frames) or "off".
  std::string temporal_filter = default_temporal_filter();
  std::string temporal_overlap = to_string(TemporalInstanceFilterSettings{}.overlap);
  std::string depth_estimate = to_string(DepthMADSettings{}.depth_estimate);  ///< modes YM, YMK
  std::string settings;    ///< ORB-SLAM2 settings file; empty: DATASET/camera.yaml
  std::string vocabulary;  ///< vocabulary file; kNoVocabulary; empty: trained (rendered) or none (dataset)
  std::uint64_t seed = 0;
  int frames = 0;  ///< not given: all (dataset) or kDefaultPresetFrames (rendered)
  bool frames_given = false;
  int reference_min_observations = slam::MappingSettings{}.reference_min_observations;
  int keyframe_interval = PatchKeyframeSettings<double>{}.interval_frames;  ///< mode YMK: k
  /// Mode YMK: consecutive frames a semantic change must hold before it inserts a keyframe.
  int semantic_change_frames = PatchKeyframeSettings<double>{}.semantic_change_frames;
  /// Mode YMK: the coverage guard's fraction of the frame's own close points that must be tracked (0: off).
  double coverage_guard_ratio = PatchKeyframeSettings<double>{}.coverage_ratio;
  /// Mode YMK: which instances the keyframe rule's semantic terms count: all | dynamic.
  std::string semantic_instances = PatchKeyframeSettings<double>{}.dynamic_instances_only ? "dynamic" : "all";
  int orb_spread = slam::OrbSettings{}.spread_oversampling;
  int local_ba_iterations = slam::LocalMappingSettings{}.bundle.solver.max_iterations;
  int local_ba_rounds_per_frame = slam::LocalMappingSettings{}.ba_rounds_per_frame;
  /// on: the local BA's rounds start with the frame after the keyframe's (ba_from_next_frame).
  std::string local_ba_from_next_frame = slam::LocalMappingSettings{}.ba_from_next_frame ? "on" : "off";
  int local_ba_iterations_per_frame = slam::LocalMappingSettings{}.ba_iterations_per_frame;  ///< 0: whole rounds
  /// Local BA solver: ceres | schur_lm (BundleAdjustmentSettings::backend).
  std::string local_ba_solver = bundle_adjustment_backend_name(slam::LocalMappingSettings{}.bundle.backend);
  /// Local-map tracking's RANSAC: always | on_failure (TrackerSettings::ransac_only_on_failure).
  std::string tracking_ransac = slam::TrackerSettings{}.ransac_only_on_failure ? "on_failure" : "always";
  /// Hypotheses of tracking's RANSAC: epnp | rigid (TrackerSettings::ransac_solver).
  std::string tracking_ransac_solver = slam::tracking_ransac_solver_name(slam::TrackerSettings{}.ransac_solver);
  /// Tracking refinement solver: ceres | pose_lm (PoseRefinementSettings::backend).
  std::string tracking_solver = pose_refinement_backend_name(slam::TrackerSettings{}.refinement.backend);
  /// Global BA solver after a loop correction: ceres | schur_lm (LoopCorrectionSettings::bundle).
  std::string global_ba_solver = bundle_adjustment_backend_name(slam::LoopCorrectionSettings{}.bundle.backend);
  std::string map_maintenance = "all";  ///< all, none or a comma list of rules
  int keyframe_min_gap = slam::SystemSettings{}.orbslam2_keyframes.min_frame_gap;
  std::string loop_correction = "pgo+ba";  ///< none | pgo | pgo+ba
  /// Depth term of the tracking refinement (0: pixels only); wins over the settings file when given.
  double tracking_depth_sigma = slam::TrackerSettings{}.refinement_depth_sigma_per_m;
  bool tracking_depth_sigma_given = false;
  std::string local_ba = slam::LocalMappingSettings{}.bundle_adjustment ? "on" : "off";
  int local_ba_window = slam::LocalMappingSettings{}.covisible_keyframes;
  int local_ba_fixed = slam::LocalMappingSettings{}.fixed_keyframes;
  std::string loop_scoring = slam::to_string(slam::LoopCloserSettings{}.scoring);
  double loop_min_score = 0;  ///< used only when loop_min_score_given
  bool loop_min_score_given = false;
  int loop_verified_members = slam::LoopCloserSettings{}.verified_members;
  double loop_min_group_ratio = slam::LoopCloserSettings{}.min_group_total_ratio;
  std::string loop_verify_groups =
      slam::LoopCloserSettings{}.verify_all_consistent_groups ? "consistent" : "best";  ///< best | consistent
  std::string cge_scaling;       ///< raw | normalised; empty: the LoopCloserSettings default
  std::string cge_ties = "all";  ///< all | mean | min: TieMode of the loop closer's degree sums
  bool map = false;              ///< also build the semantic maps
  std::string out;
  bool force = false;
};

}  // namespace run
}  // namespace cge
