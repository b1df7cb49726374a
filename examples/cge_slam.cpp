// cge_slam: the reference pipeline on an RGB-D sequence (TUM layout) or, without --dataset, on a
// synthetic preset rendered in memory (--preset, walking_xyz by default): cge::run::SlamRun
// (cge/run/slam_run.hpp) writes trajectory.txt, keyframes.txt, loops.csv, frames.csv, timings.csv,
// groundtruth.txt and loops.txt (rendered), the maps (--map); this tool adds summary.json (counts,
// settings, dynamic-feature leak, ATE, RPE, loop evaluation, mean/median time per stage) and prints
// the evaluation as `name value` lines. Every file but timings.csv and summary.json's `stages` is
// deterministic (same inputs and seed: same bytes).
//
// Output folder (cge/run/output_folder.hpp): refused when not empty unless --force, which replaces
// only the files above; written through a staging folder, so a failed or interrupted run leaves
// --out as it was. Options and files: docs/CLI.md. Standard error: diagnostics and, on a terminal
// only, a progress bar. Exit codes: 0 success; 1 failure while running (a file that cannot be
// written); 2 bad usage or bad input (missing dataset, malformed list file, unreadable image, ...).

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <opencv2/core/utils/logger.hpp>

#include "cge/run/loop_report.hpp"
#include "cge/run/output_folder.hpp"
#include "cge/run/rendered_frame_source.hpp"
#include "cge/run/run_settings.hpp"
#include "cge/run/slam_run.hpp"
#include "cge/sim/presets.hpp"

#include "slam_summary_json.hpp"
#include "tool_support.hpp"

#ifndef CGE_VERSION_STRING
#define CGE_VERSION_STRING "unknown"
#endif

namespace {

constexpr const char* kProgram = "cge_slam";
cge_tool::ProgressBar progress_bar{kProgram};  // drawn only on a terminal

int run(cge::run::SlamRunOptions options) {
  const auto warn = [](const std::string& text) { std::fprintf(stderr, "%s: warning: %s\n", kProgram, text.c_str()); };
  cge::run::SlamRun slam(std::move(options), warn);
  const cge::run::SlamRunOptions& opt = slam.options();
  cge::run::OutputFolder out(opt.out, opt.force, kProgram, cge::run::SlamRun::output_names());
  slam.prepare_vocabulary();  // the first work, after every check
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed_s = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const bool progress = ::isatty(::fileno(stderr)) != 0;
  slam.process([&](int done, int total) {
    if (progress) progress_bar.draw(done, total, elapsed_s());
  });
  const int n = slam.frame_count();
  if (slam.every_frame_lost()) {
    progress_bar.end_line();
    std::fprintf(stderr,
                 "%s: warning: every frame was lost (%d of %d): the trajectory is empty (wrong settings, "
                 "depth scale or images?)\n",
                 kProgram, n, n);
  }
  slam.write_outputs(out);
  out.write("summary.json", [&](std::ostream& f) { f << cge_tool::slam_summary_json(slam).dump(2) << '\n'; });
  out.commit();

  const cge::run::RunSummary& s = slam.summary();
  std::printf("%s: %d frames, %d tracked, %d lost, %d keyframes; wrote %s in %.1f s\n", kProgram, n, s.tracked_frames,
              s.lost_frames, s.keyframes, opt.out.c_str(), elapsed_s());
  // The evaluation as `name value` lines (the figures of summary.json a reader looks for first).
  const auto print_line = [](const char* name, double value) { std::printf("%s %.6g\n", name, value); };
  print_line("keyframes", s.keyframes);
  std::printf("vocabulary %s\n", slam.vocabulary_source().c_str());
  if (slam.vocabulary_training_s() > 0) print_line("vocabulary_training_s", slam.vocabulary_training_s());
  print_line("loop_queries", static_cast<double>(s.loop_candidates));
  print_line("loops_accepted", s.loops_accepted);
  print_line("loop_corrections", s.loop_corrections);
  if (slam.loop_evaluation()) {
    std::fputs(cge::run::loop_evaluation_report(slam.system().loops(), *slam.ground_truth_loops(), slam.ground_truth(),
                                                *slam.loop_evaluation())
                   .c_str(),
               stdout);
  } else if (slam.loop_closing() && slam.rendered()) {
    std::printf("loop_evaluation skipped: more than %d rendered frames (ground-truth loops grow with the square of "
                "the length)\n",
                cge::run::RenderedFrameSource::kMaxLoopTruthFrames);
  }
  if (s.dynamic_leak.rate) print_line("dynamic_leak_rate", *s.dynamic_leak.rate);
  if (s.trajectory_errors && s.trajectory_errors->ate_m) print_line("ate_rmse_m", s.trajectory_errors->ate_m->rmse);
  if (s.trajectory_errors && s.trajectory_errors->rpe_translation_m) {
    print_line("rpe_translation_rmse_m", s.trajectory_errors->rpe_translation_m->rmse);
    print_line("rpe_rotation_rmse_deg", s.trajectory_errors->rpe_rotation_deg->rmse);
  }
  print_line("tracking_median_ms", s.stages[static_cast<std::size_t>(cge::slam::Stage::tracking)].median_ms);
  print_line("total_median_ms", s.stages[static_cast<std::size_t>(cge::slam::Stage::total)].median_ms);
  if (!cge_tool::standard_output_written(kProgram)) return cge_tool::kExitFailure;
  return cge_tool::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  cge::run::SlamRunOptions opt;
  CLI::App app{"Runs the cge reference SLAM pipeline (cge " CGE_VERSION_STRING
               ") on an RGB-D sequence in the TUM layout, or without --dataset on a\n"
               "synthetic preset rendered in memory (walking_xyz by default), and writes trajectory.txt,\n"
               "keyframes.txt, loops.csv, frames.csv, timings.csv and summary.json into --out.",
               kProgram};
  app.set_version_flag("--version", std::string(kProgram) + " " + CGE_VERSION_STRING);
  app.add_option("--dataset", opt.dataset, "TUM folder (rgb.txt, depth.txt, camera.yaml); none: render --preset");
  app.add_option("--preset", opt.preset,
                 "without --dataset: the synthetic preset rendered in memory (cge_sim's names, e.g. loop_dynamic)")
      ->capture_default_str();
  app.add_option("--mode", opt.mode, "dynamic handling: none, Y (masks), YM (masks + MAD), YMK (+ patch keyframes)")
      ->capture_default_str();
  app.add_option("--segmentation", opt.segmentation,
                 "none, ground_truth (the synthetic segmentation/ folder, or the rendered masks), yolo, precomputed "
                 "(default: ground_truth, none in mode none)");
  app.add_option("--model", opt.model, "YOLOv8-seg ONNX model (--segmentation yolo)");
  app.add_option("--masks", opt.masks, "mask folder (--segmentation precomputed)");
  app.add_option("--temporal-filter", opt.temporal_filter,
                 "--segmentation yolo: pass a static object's instance on once detected in N of the last M frames "
                 "(N/M), people at once; off: every detection as the network gives it (docs/SEGMENTATION.md)")
      ->capture_default_str();
  app.add_option("--depth-estimate", opt.depth_estimate,
                 "modes YM, YMK: where a person's depth mean and MAD come from: box_samples (n random samples in the "
                 "box, the paper's) or mask_pixels (every mask pixel with depth; docs/SEGMENTATION.md)")
      ->check(CLI::IsMember({"box_samples", "mask_pixels"}))
      ->capture_default_str();
  app.add_option("--temporal-overlap", opt.temporal_overlap,
                 "what the temporal filter's association compares between frames: box or mask IoU")
      ->check(CLI::IsMember({"box", "mask"}))
      ->capture_default_str();
  app.add_option("--settings", opt.settings, "ORB-SLAM2 TUM YAML settings (default: DATASET/camera.yaml)");
  app.add_option("--vocabulary", opt.vocabulary,
                 "bag-of-words vocabulary (cge_vocab) for loop closing; none: loop closing off; not given: rendered "
                 "runs train one on another preset (walking_halfsphere, seed + 1), --dataset runs close no loops");
  app.add_option("--loop-correction", opt.loop_correction,
                 "what an accepted loop triggers: none (detect and log only), pgo (pose graph), pgo+ba (and global "
                 "bundle adjustment)")
      ->check(CLI::IsMember({"none", "pgo", "pgo+ba"}));
  app.add_option("--tracking-depth-sigma", opt.tracking_depth_sigma,
                 "depth term of the tracking refinement: sigma_z = X * z^2 per matched keypoint with depth, 1/m; 0 = "
                 "pixels only")
      ->check(cge_tool::at_least_zero())
      ->capture_default_str()
      ->each([&opt](const std::string&) { opt.tracking_depth_sigma_given = true; });
  app.add_option("--local-ba", opt.local_ba,
                 "local bundle adjustment of the new keyframe's covisible window after each keyframe insertion "
                 "(timed as local_mapping)")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  app.add_option("--local-ba-window", opt.local_ba_window,
                 "local BA window: the new keyframe and at most this many most covisible keyframes, optimised")
      ->check(cge_tool::at_least_zero())
      ->capture_default_str();
  app.add_option("--local-ba-fixed", opt.local_ba_fixed,
                 "local BA fixed observers: at most this many further covisible keyframes, held fixed (0: none)")
      ->check(cge_tool::at_least_zero())
      ->capture_default_str();
  app.add_option("--loop-scoring", opt.loop_scoring,
                 "what ranks and gates loop candidates: cge (S_sum, the paper), bow_only (BoW score), combined "
                 "(S_sum x relative BoW score)")
      ->check(CLI::IsMember({"cge", "bow_only", "combined"}))
      ->capture_default_str();
  app.add_option("--loop-min-score", opt.loop_min_score,
                 "acceptance gate of the chosen scoring: least S_sum (cge, combined; default " +
                     cge::run::short_number(cge::slam::LoopCloserSettings{}.min_cge_score) +
                     ") or BoW score (bow_only; default " +
                     cge::run::short_number(cge::slam::LoopCloserSettings{}.min_bow_score) + ")")
      ->each([&opt](const std::string&) { opt.loop_min_score_given = true; });
  app.add_option("--loop-verified-members", opt.loop_verified_members,
                 "geometric check of each verifiable group's best this many members; the most PnP inliers wins")
      ->check(cge_tool::above_zero())
      ->capture_default_str();
  app.add_option("--loop-verify-groups", opt.loop_verify_groups,
                 "which groups the geometric check verifies: best (the best-scored group only) or consistent (every "
                 "group passing the gate and the continuity check, as ORB-SLAM2)")
      ->check(CLI::IsMember({"best", "consistent"}))
      ->capture_default_str();
  app.add_option("--loop-min-group-ratio", opt.loop_min_group_ratio,
                 "verify only groups whose score total reaches this fraction of the best group's (ORB-SLAM2: 0.75)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--cge-scaling", opt.cge_scaling,
                 std::string("exponent scaling of the degree-degree entropy in the loop closer: raw (the paper's) or "
                             "normalised (by the mean exponent); default ") +
                     (cge::slam::LoopCloserSettings{}.exponent_scaling == cge::ScalingKind::raw ? "raw" : "normalised"))
      ->check(CLI::IsMember({"raw", "normalised"}));
  app.add_option("--cge-ties", opt.cge_ties,
                 "tied shortest paths in the loop closer's degree sums: all (every path), mean (one averaged path "
                 "per node) or min (the path with the smallest sum, closest to the paper's rule)")
      ->check(CLI::IsMember({"all", "mean", "min"}))
      ->capture_default_str();
  app.add_option("--seed", opt.seed, "seed of the MAD samples (and of the rendered sequence)")
      ->check(cge_tool::seed_check())
      ->capture_default_str();
  app.add_option("--frames", opt.frames,
                 "process at most this many frames, >= 1 (rendered: default 300, at most " +
                     std::to_string(cge::sim::kMaxPresetFrames) + ")")
      ->each([&opt](const std::string&) { opt.frames_given = true; });
  app.add_option("--reference-min-observations", opt.reference_min_observations,
                 "ORB-SLAM2 keyframe baseline: count the reference keyframe's map points seen by >= this many "
                 "keyframes (ORB-SLAM2's nMinObs)")
      ->capture_default_str();
  app.add_option("--keyframe-min-gap", opt.keyframe_min_gap,
                 "modes none, Y, YM: frames after a keyframe before the ORB-SLAM2 policy's ratio rule may insert "
                 "the next (stands in for the time ORB-SLAM2's local-mapping thread is busy)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--map-maintenance", opt.map_maintenance,
                 "map maintenance after each keyframe: 'all', 'none' or a comma list of cull_points, triangulate, "
                 "fuse, cull_keyframes");
  app.add_option("--local-ba-iterations", opt.local_ba_iterations,
                 "Levenberg-Marquardt iterations per round of the local BA (its time budget per keyframe; 2 rounds)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--local-ba-rounds-per-frame", opt.local_ba_rounds_per_frame,
                 "local BA rounds solved per frame, before it is tracked: 1 one round a frame, 2 both in one frame")
      ->check(CLI::Range(1, 2));
  app.add_option("--local-ba-from-next-frame", opt.local_ba_from_next_frame,
                 "on: the keyframe's frame does the map maintenance and the local BA's rounds start with the "
                 "next frame; off: the keyframe's frame solves the first round (changes the trajectory)")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  app.add_option("--local-ba-iterations-per-frame", opt.local_ba_iterations_per_frame,
                 "local BA iterations solved per frame, across its rounds, restarting from the current estimate "
                 "(0: whole rounds, --local-ba-rounds-per-frame; other values change the trajectory)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--local-ba-solver", opt.local_ba_solver,
                 "local BA solver: ceres, or schur_lm (cge's own Levenberg-Marquardt with the points eliminated by "
                 "the Schur complement; same problem, rounds and tolerances)")
      ->check(CLI::IsMember({"ceres", "schur_lm"}))
      ->capture_default_str();
  app.add_option("--tracking-ransac", opt.tracking_ransac,
                 "local-map tracking: always (RANSAC on the prediction's matches, then the refinement) or "
                 "on_failure (the refinement from the prediction first, RANSAC only when it fails, as ORB-SLAM2)")
      ->check(CLI::IsMember({"always", "on_failure"}))
      ->capture_default_str();
  app.add_option("--tracking-ransac-solver", opt.tracking_ransac_solver,
                 "hypotheses of tracking's RANSAC: epnp (OpenCV's EPnP on five matches) or rigid (three matches "
                 "with depth fitted in 3-D); both score every match by its reprojection error")
      ->check(CLI::IsMember({"epnp", "rigid"}))
      ->capture_default_str();
  app.add_option("--tracking-solver", opt.tracking_solver,
                 "tracking refinement solver: pose_lm (cge's own 6x6 Levenberg-Marquardt) or ceres; same problem, "
                 "rounds and tolerances")
      ->check(CLI::IsMember({"ceres", "pose_lm"}))
      ->capture_default_str();
  app.add_option("--global-ba-solver", opt.global_ba_solver,
                 "the global BA after a loop correction: schur_lm (cge's own, dense reduced system; more than " +
                     std::to_string(cge::slam::LoopCorrectionSettings{}.bundle.schur_lm_max_free_poses) +
                     " free keyframes go to Ceres' sparse Schur) or ceres; same rounds, iterations and tolerances")
      ->check(CLI::IsMember({"ceres", "schur_lm"}))
      ->capture_default_str();
  app.add_option("--orb-spread", opt.orb_spread,
                 "ORB candidates per kept keypoint, spread over the image cell by cell (1: cv::ORB's own choice)")
      ->check(CLI::Range(1, 8));
  app.add_option("--keyframe-interval", opt.keyframe_interval,
                 "mode YMK: frames per interval of the patch keyframe selector (k; its best candidate is inserted "
                 "at the end of each interval)")
      ->check(cge_tool::above_zero())
      ->capture_default_str();
  app.add_option("--semantic-change-frames", opt.semantic_change_frames,
                 "mode YMK: consecutive frames a semantic change must hold before it inserts a keyframe")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--coverage-guard-ratio", opt.coverage_guard_ratio,
                 "mode YMK: insert a keyframe when the frame tracks under this fraction of its own close points "
                 "(ours, not the paper's; 0: off)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--semantic-instances", opt.semantic_instances,
                 "mode YMK: instances the keyframe rule's semantic change and centroid count: dynamic (ours: only "
                 "dynamic classes, people by default) or all (the paper's rule)")
      ->check(CLI::IsMember({"all", "dynamic"}))
      ->capture_default_str();
  app.add_option("--out", opt.out, "output folder; must not exist or be empty, unless --force")->required();
  app.add_flag("--map", opt.map,
               "also build the semantic maps from the keyframes: map.ply (dense cloud), map.ot/map.bt (octree), "
               "map_top.png; their figures go to summary.json (docs/MAPS.md)");
  app.add_flag("--force", opt.force, "write into a non-empty folder: replace cge_slam's own files, delete nothing");

  if (const int exit_code = cge_tool::parse_command_line(app, argc, argv, kProgram); exit_code >= 0) return exit_code;
  // OpenCV's own warnings would come before the tool's message; its errors arrive as exceptions.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
  return cge_tool::run_reporting_errors(kProgram, &progress_bar, [&] { return run(std::move(opt)); });
}
