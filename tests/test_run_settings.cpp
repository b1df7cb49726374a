// cge::run's options onto the pipeline's settings (cge/run/run_settings.hpp): what each option
// sets, the defaults it fills, and the message of each refusal.
#include <catch2/catch.hpp>

#include <stdexcept>
#include <string>
#include <vector>

#include "cge/run/run_settings.hpp"

namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("run settings: the temporal filter option", "[run][settings]") {
  cge::dataset::SegmentationSourceSettings seg;
  cge::run::apply_temporal_filter("2/5", "mask", seg);
  CHECK(seg.temporal_filter.min_frames_seen == 2);
  CHECK(seg.temporal_filter.window_frames == 5);
  CHECK(seg.temporal_filter.overlap == cge::TemporalOverlap::mask);
  CHECK(seg.temporal_filter_sources.count(cge::dataset::SegmentationSource::yolo) == 1);
  cge::run::apply_temporal_filter("off", "box", seg);
  CHECK(seg.temporal_filter_sources.empty());
  CHECK(seg.temporal_filter.overlap == cge::TemporalOverlap::box);
  for (const std::string bad : {"2", "2/", "a/3", "2/3x", "2/3/4", " 2/3", "+2/3", "2/ 3", "-1/3", "99999/3"}) {
    CAPTURE(bad);
    CHECK(message_of([&] { cge::run::apply_temporal_filter(bad, "box", seg); }) ==
          "--temporal-filter: '" + bad + "' is not N/M (e.g. 2/3) or off");
  }
  CHECK(message_of([&] { cge::run::apply_temporal_filter("4/3", "box", seg); }).rfind("--temporal-filter: ", 0) == 0);
}

TEST_CASE("run settings: the System's settings from the options", "[run][settings]") {
  cge::run::SlamRunOptions opt;
  const cge::slam::SystemSettings defaults = cge::run::system_settings_from(opt);
  CHECK(defaults.mode == cge::slam::DynamicMode::YMK);
  CHECK(defaults.local_mapping.cull_map_points);
  CHECK(defaults.local_mapping.cull_keyframes);
  CHECK(defaults.loop_correction.enabled);
  CHECK(defaults.loop_correction.bundle_adjustment);

  opt.mode = "YM";
  opt.seed = 42;
  opt.map_maintenance = "cull_points,fuse";
  opt.loop_correction = "pgo";
  opt.local_ba = "off";
  opt.map = true;
  opt.keyframe_interval = 7;
  opt.semantic_change_frames = 3;
  opt.local_ba_iterations_per_frame = 4;
  opt.local_ba_from_next_frame = "off";
  opt.local_ba_solver = "ceres";
  opt.tracking_solver = "ceres";
  opt.tracking_ransac = "on_failure";
  opt.tracking_ransac_solver = "epnp";
  opt.semantic_instances = "all";
  const cge::slam::SystemSettings s = cge::run::system_settings_from(opt);
  CHECK(s.local_mapping.bundle.backend == cge::BundleAdjustmentBackend::ceres);
  CHECK(defaults.local_mapping.bundle.backend == cge::BundleAdjustmentBackend::schur_lm);
  CHECK(s.tracker.refinement.backend == cge::PoseRefinementBackend::ceres);
  CHECK(defaults.tracker.refinement.backend == cge::PoseRefinementBackend::pose_lm);
  CHECK(s.tracker.ransac_only_on_failure);
  CHECK_FALSE(defaults.tracker.ransac_only_on_failure);
  CHECK(s.tracker.ransac_solver == cge::slam::TrackingRansacSolver::epnp);
  CHECK(defaults.tracker.ransac_solver == cge::slam::TrackingRansacSolver::rigid);
  CHECK_FALSE(s.patch_keyframes.dynamic_instances_only);
  CHECK(defaults.patch_keyframes.dynamic_instances_only);
  CHECK(s.local_mapping.ba_iterations_per_frame == 4);
  CHECK(defaults.local_mapping.ba_iterations_per_frame == 0);  // whole rounds unless asked
  CHECK_FALSE(s.local_mapping.ba_from_next_frame);
  CHECK(defaults.local_mapping.ba_from_next_frame);
  CHECK(s.patch_keyframes.interval_frames == 7);
  CHECK(s.patch_keyframes.semantic_change_frames == 3);
  CHECK(s.mode == cge::slam::DynamicMode::YM);
  CHECK(s.seed == 42);
  CHECK(s.local_mapping.cull_map_points);
  CHECK(s.local_mapping.fuse_map_points);
  CHECK_FALSE(s.local_mapping.triangulate_points);
  CHECK_FALSE(s.local_mapping.cull_keyframes);
  CHECK(s.loop_correction.enabled);
  CHECK_FALSE(s.loop_correction.bundle_adjustment);
  CHECK_FALSE(s.local_mapping.bundle_adjustment);
  CHECK(s.keep_keyframe_images);

  opt.map_maintenance = "none";
  const cge::slam::SystemSettings none = cge::run::system_settings_from(opt);
  CHECK_FALSE(none.local_mapping.cull_map_points);
  CHECK_FALSE(none.local_mapping.fuse_map_points);

  opt.map_maintenance = "fuse,sweep";
  CHECK(message_of([&] { cge::run::system_settings_from(opt); }) ==
        "--map-maintenance: unknown rule 'sweep' (expected all, none or a comma list of cull_points, triangulate, "
        "fuse, cull_keyframes)");
  opt.mode = "XY";
  CHECK(message_of([&] { cge::run::system_settings_from(opt); }).rfind("--mode: ", 0) == 0);
}

TEST_CASE("run settings: checks of the frames and segmentation options", "[run][settings]") {
  std::vector<std::string> warnings;
  const auto warn = [&](const std::string& w) { warnings.push_back(w); };
  cge::run::SlamRunOptions opt;
  opt.out = "out";
  cge::run::check_run_options(opt, cge::slam::DynamicMode::YMK, warn);
  CHECK(opt.segmentation == "ground_truth");
  cge::run::SlamRunOptions plain = opt;
  plain.segmentation.clear();
  cge::run::check_run_options(plain, cge::slam::DynamicMode::none, warn);
  CHECK(plain.segmentation == "none");
  CHECK(warnings.empty());

  cge::run::SlamRunOptions with_model = opt;
  with_model.model = "net.onnx";
  cge::run::check_run_options(with_model, cge::slam::DynamicMode::YMK, warn);
  CHECK(warnings == std::vector<std::string>{"--model is used only with --segmentation yolo; ignored"});

  cge::run::SlamRunOptions bad = opt;
  bad.frames = 0;
  bad.frames_given = true;
  CHECK(message_of([&] { cge::run::check_run_options(bad, cge::slam::DynamicMode::YMK, warn); }) ==
        "--frames must be at least 1, got 0 (omit it for every frame)");
  bad = opt;
  bad.dataset = "folder";
  bad.preset = "loop_dynamic";
  CHECK(message_of([&] { cge::run::check_run_options(bad, cge::slam::DynamicMode::YMK, warn); }) ==
        "--preset renders a sequence: it cannot be combined with --dataset");
  bad = opt;
  bad.preset = "no_such_preset";
  CHECK(message_of([&] { cge::run::check_run_options(bad, cge::slam::DynamicMode::YMK, warn); })
            .rfind("--preset: unknown preset 'no_such_preset' (known: ", 0) == 0);
  bad = opt;
  bad.segmentation = "yolo";
  CHECK(message_of([&] { cge::run::check_run_options(bad, cge::slam::DynamicMode::YMK, warn); }) ==
        "--segmentation yolo needs --model ONNX");
  bad = opt;
  bad.out.clear();
  CHECK(message_of([&] { cge::run::check_run_options(bad, cge::slam::DynamicMode::YMK, warn); }) ==
        "--out must name a folder");
}

TEST_CASE("run settings: the loop closer's settings and their gate", "[run][settings]") {
  cge::run::SlamRunOptions opt;
  const cge::slam::LoopCloserSettings defaults;
  opt.loop_scoring = "bow_only";
  opt.loop_min_score = 0.07;
  opt.loop_min_score_given = true;
  opt.cge_ties = "min";
  opt.cge_scaling = "normalised";
  cge::slam::LoopCloserSettings s = cge::run::loop_closer_settings_from(opt);
  CHECK(s.scoring == cge::slam::LoopScoring::bow_only);
  CHECK(s.min_bow_score == 0.07);
  CHECK(s.min_cge_score == defaults.min_cge_score);  // the other gate keeps its default
  CHECK(s.degree_entropy.ties == cge::TieMode::min);
  CHECK(s.exponent_scaling == cge::ScalingKind::normalised_mean);

  opt.loop_scoring = "cge";
  s = cge::run::loop_closer_settings_from(opt);
  CHECK(s.min_cge_score == 0.07);
  CHECK(s.min_bow_score == defaults.min_bow_score);

  opt.loop_min_score = std::numeric_limits<double>::infinity();
  CHECK(message_of([&] { cge::run::loop_closer_settings_from(opt); }) == "--loop-min-score must be a finite number");
  opt.loop_min_score_given = false;
  opt.cge_ties = "max";
  CHECK(message_of([&] { cge::run::loop_closer_settings_from(opt); }) ==
        "--cge-ties: 'max' is not all, mean or min");
  CHECK(cge::run::parse_tie_mode("--ties", "mean") == cge::TieMode::mean);
  CHECK(message_of([] { cge::run::parse_tie_mode("--ties", "All"); }) == "--ties: 'All' is not all, mean or min");
}

TEST_CASE("run settings: the first image against the settings", "[run][settings]") {
  cge::slam::OrbSettings orb;
  CHECK_NOTHROW(cge::run::check_first_image(cv::Size(640, 480), std::nullopt, orb));
  orb.levels = 30;
  orb.scale_factor = 1.2;
  CHECK(message_of([&] { cge::run::check_first_image(cv::Size(64, 48), std::nullopt, orb); }) ==
        "the settings: ORBextractor.nLevels 30 is too many for 64 x 48 images at scaleFactor 1.2 (the coarsest "
        "level keeps no pixel)");
}
