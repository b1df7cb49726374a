#pragma once
// summary.json of cge_slam (docs/SLAM.md): a finished run's figures (cge/run/run_summary.hpp), the
// settings it used and its evaluation, spelled as JSON. Private to the tool (the library has no
// JSON dependency).
#include <cmath>

#include <nlohmann/json.hpp>

#include "cge/run/slam_run.hpp"

namespace cge_tool {

inline nlohmann::ordered_json json_number_or_null(double v) {
  return std::isnan(v) ? nlohmann::ordered_json() : nlohmann::ordered_json(v);
}

inline nlohmann::ordered_json loop_settings_json(const cge::run::SlamRun& run) {
  const cge::slam::LoopCloserSettings& s = run.loop_settings();
  const bool bow_gate = s.scoring == cge::slam::LoopScoring::bow_only;
  nlohmann::ordered_json j = {{"enabled", run.loop_closing()},
                              {"scoring", cge::slam::to_string(s.scoring)},
                              {"min_score", bow_gate ? s.min_bow_score : s.min_cge_score},
                              {"min_score_setting", bow_gate ? "min_bow_score" : "min_cge_score"},
                              {"cge_scaling", s.exponent_scaling == cge::ScalingKind::raw ? "raw" : "normalised"},
                              {"cge_ties", run.options().cge_ties},
                              {"verified_members", s.verified_members},
                              {"verify_groups", run.options().loop_verify_groups},
                              {"min_group_total_ratio", s.min_group_total_ratio},
                              {"vocabulary", run.vocabulary_source()}};
  if (run.vocabulary_words()) j["vocabulary_words"] = *run.vocabulary_words();
  return j;
}

inline nlohmann::ordered_json loop_evaluation_json(const cge::metrics::LoopEvaluation& e) {
  nlohmann::ordered_json j = {{"ground_truth_pairs", e.ground_truth_pairs},
                              {"queried_keyframes", e.queried_keyframes},
                              {"detections", e.detections},
                              {"correct_detections", e.correct_detections},
                              {"precision", json_number_or_null(e.precision)},
                              {"loop_queries", e.loop_queries},
                              {"detected_loop_queries", e.detected_loop_queries},
                              {"query_recall", json_number_or_null(e.query_recall)},
                              {"loop_events", e.loop_events},
                              {"detected_loop_events", e.detected_loop_events},
                              {"event_recall", json_number_or_null(e.event_recall)},
                              {"open_loop_queries", e.open_loop_queries},
                              {"open_query_recall", json_number_or_null(e.open_query_recall)}};
  j["missed_by_reason"] = nlohmann::ordered_json::object();
  for (const auto& [reason, count] : e.missed_by_reason) j["missed_by_reason"][reason] = count;
  return j;
}

inline nlohmann::ordered_json slam_summary_json(const cge::run::SlamRun& run) {
  const cge::run::RunSummary& s = run.summary();
  const cge::run::SlamRunOptions& opt = run.options();
  const cge::slam::SystemSettings& used = run.system().settings();
  nlohmann::ordered_json j;
  j["frames"] = s.frames;
  j["tracked_frames"] = s.tracked_frames;
  j["lost_frames"] = s.lost_frames;
  j["odometry_frames"] = s.odometry_frames;
  j["relocalised_frames"] = s.relocalised_frames;
  j["keyframes"] = s.keyframes;
  j["keyframes_inserted"] = s.keyframes_inserted;
  j["map_points"] = s.map_points;
  j["map_points_created"] = s.map_points_created;
  j["loops"] = {{"candidates", s.loop_candidates}, {"accepted", s.loops_accepted}, {"corrections", s.loop_corrections}};
  j["mode"] = cge::slam::to_string(used.mode);
  j["segmentation"] = opt.segmentation;
  j["temporal_filter"] = opt.segmentation == "yolo" ? opt.temporal_filter : "off";
  if (opt.segmentation == "yolo" && opt.temporal_filter != "off") j["temporal_overlap"] = opt.temporal_overlap;
  j["depth_estimate"] = cge::to_string(used.frame.mad.depth_estimate);
  j["source"] = run.source_name();
  j["seed"] = opt.seed;
  j["loop_settings"] = loop_settings_json(run);
  // The tracking and mapping settings the run used (the flags that change the trajectory).
  j["mapping_settings"] = {{"tracking_depth_sigma", used.tracker.refinement_depth_sigma_per_m},
                           {"ba_depth_sigma", used.local_mapping.depth_sigma_per_m},
                           {"local_ba", used.local_mapping.bundle_adjustment ? "on" : "off"},
                           {"local_ba_window", used.local_mapping.covisible_keyframes},
                           {"local_ba_fixed", used.local_mapping.fixed_keyframes},
                           {"reference_min_observations", used.mapping.reference_min_observations},
                           {"keyframe_interval", used.patch_keyframes.interval_frames},
                           {"semantic_change_frames", used.patch_keyframes.semantic_change_frames},
                           {"coverage_guard_ratio", used.patch_keyframes.coverage_ratio},
                           {"semantic_instances", used.patch_keyframes.dynamic_instances_only ? "dynamic" : "all"},
                           {"keyframe_min_gap", used.orbslam2_keyframes.min_frame_gap},
                           {"orb_spread", used.frame.orb.spread_oversampling},
                           {"local_ba_iterations", used.local_mapping.bundle.solver.max_iterations},
                           {"local_ba_rounds_per_frame", used.local_mapping.ba_rounds_per_frame},
                           {"local_ba_from_next_frame", used.local_mapping.ba_from_next_frame},
                           {"local_ba_iterations_per_frame", used.local_mapping.ba_iterations_per_frame},
                           {"local_ba_solver", cge::bundle_adjustment_backend_name(used.local_mapping.bundle.backend)},
                           {"tracking_ransac", used.tracker.ransac_only_on_failure ? "on_failure" : "always"},
                           {"tracking_ransac_solver", cge::slam::tracking_ransac_solver_name(used.tracker.ransac_solver)},
                           {"tracking_solver", cge::pose_refinement_backend_name(used.tracker.refinement.backend)},
                           {"global_ba_solver", cge::bundle_adjustment_backend_name(used.loop_correction.bundle.backend)},
                           {"map_maintenance", opt.map_maintenance},
                           {"loop_correction", opt.loop_correction}};
  const cge::run::DynamicLeak& leak = s.dynamic_leak;
  j["dynamic_leak"] = {{"frames_with_ground_truth", leak.frames_with_ground_truth},
                       {"moving_keypoints", leak.moving_keypoints},
                       {"moving_kept", leak.moving_kept}};
  j["dynamic_leak"]["rate"] = leak.rate ? nlohmann::ordered_json(*leak.rate) : nullptr;
  if (s.trajectory_errors) {  // as cge_eval ate and cge_eval rpe (1 s)
    const cge::run::TrajectoryErrors& e = *s.trajectory_errors;
    if (e.ate_m) {
      const cge::metrics::ErrorStatistics& t = *e.ate_m;
      j["ate"] = {{"pairs", t.count}, {"rmse_m", t.rmse}, {"mean_m", t.mean}, {"median_m", t.median},
                  {"std_m", t.std},   {"min_m", t.min},   {"max_m", t.max}};
    } else {
      j["ate"] = {{"error", e.ate_error}};
    }
    if (e.rpe_translation_m) {
      j["rpe"] = {{"delta_s", e.rpe_delta_s},
                  {"pairs", e.rpe_translation_m->count},
                  {"translation_rmse_m", e.rpe_translation_m->rmse},
                  {"rotation_rmse_deg", e.rpe_rotation_deg->rmse}};
    } else {
      j["rpe"] = {{"error", e.rpe_error}};
    }
  }
  nlohmann::ordered_json stages;
  for (int i = 0; i < cge::slam::kStageCount; ++i) {
    const cge::run::StageTime& t = s.stages[static_cast<std::size_t>(i)];
    stages[cge::slam::to_string(static_cast<cge::slam::Stage>(i))] = {{"mean_ms", t.mean_ms}, {"median_ms", t.median_ms}};
  }
  j["stages"] = stages;
  if (run.vocabulary_training_s() > 0) j["vocabulary_training_s"] = run.vocabulary_training_s();
  if (run.loop_evaluation()) j["loop_evaluation"] = loop_evaluation_json(*run.loop_evaluation());
  if (const auto& f = run.map_figures()) {
    j["map"] = {{"keyframes", f->keyframes},
                {"cloud_points", f->cloud_points},
                {"occupied_voxels", f->occupied_voxels},
                {"integrity", f->integrity},
                {"fluctuation", f->fluctuation},
                {"entities", f->entities},
                {"octree_memory_bytes", f->octree_memory_bytes}};
  }
  return j;
}

}  // namespace cge_tool
