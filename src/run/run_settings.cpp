#include "cge/run/run_settings.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/sim/presets.hpp"
#include "cge/slam/settings_from_orbslam2.hpp"

namespace cge {
namespace run {

std::string short_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

slam::DynamicMode parse_mode_option(const std::string& text) {
  try {
    return slam::parse_dynamic_mode(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--mode: ") + e.what());
  }
}

TieMode parse_tie_mode(const std::string& option, const std::string& text) {
  if (text == "all") return TieMode::all;
  if (text == "mean") return TieMode::mean;
  if (text == "min") return TieMode::min;
  throw std::invalid_argument(option + ": '" + text + "' is not all, mean or min");
}

void apply_temporal_filter(const std::string& text, const std::string& overlap,
                           dataset::SegmentationSourceSettings& seg) {
  seg.temporal_filter.overlap = overlap == "mask" ? TemporalOverlap::mask : TemporalOverlap::box;
  if (text == "off") {
    seg.temporal_filter_sources.clear();
    return;
  }
  const std::string not_n_of_m = "--temporal-filter: '" + text + "' is not N/M (e.g. 2/3) or off";
  // Digits only: std::stoi alone would also take blanks and signs (" 2/3", "+2/3").
  const auto frame_count = [&](const std::string& digits) {
    if (digits.empty() || digits.size() > 4 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw std::invalid_argument(not_n_of_m);
    return std::stoi(digits);
  };
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos) throw std::invalid_argument(not_n_of_m);
  seg.temporal_filter.min_frames_seen = frame_count(text.substr(0, slash));
  seg.temporal_filter.window_frames = frame_count(text.substr(slash + 1));
  try {
    seg.temporal_filter.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--temporal-filter: ") + e.what());
  }
}

namespace {

/// --map-maintenance: all, none or a comma list of the rules, into the local mapping settings.
void apply_map_maintenance(const std::string& text, slam::LocalMappingSettings& lm) {
  if (text == "all") return;
  std::set<std::string> rules;
  std::stringstream list(text == "none" ? "" : text);
  for (std::string rule; std::getline(list, rule, ',');) {
    if (rule != "cull_points" && rule != "triangulate" && rule != "fuse" && rule != "cull_keyframes") {
      throw std::invalid_argument("--map-maintenance: unknown rule '" + rule +
                                  "' (expected all, none or a comma list of cull_points, triangulate, fuse, "
                                  "cull_keyframes)");
    }
    rules.insert(rule);
  }
  lm.cull_map_points = rules.count("cull_points") > 0;
  lm.triangulate_points = rules.count("triangulate") > 0;
  lm.fuse_map_points = rules.count("fuse") > 0;
  lm.cull_keyframes = rules.count("cull_keyframes") > 0;
}

}  // namespace

slam::SystemSettings system_settings_from(const SlamRunOptions& opt) {
  slam::SystemSettings settings;
  settings.mode = parse_mode_option(opt.mode);
  settings.seed = opt.seed;
  settings.frame.mad.depth_estimate =
      opt.depth_estimate == "mask_pixels" ? DepthEstimate::mask_pixels : DepthEstimate::box_samples;
  settings.mapping.reference_min_observations = opt.reference_min_observations;
  settings.patch_keyframes.interval_frames = opt.keyframe_interval;
  settings.patch_keyframes.semantic_change_frames = opt.semantic_change_frames;
  settings.patch_keyframes.coverage_ratio = opt.coverage_guard_ratio;
  settings.patch_keyframes.dynamic_instances_only = opt.semantic_instances == "dynamic";
  settings.frame.orb.spread_oversampling = opt.orb_spread;
  settings.local_mapping.bundle.solver.max_iterations = opt.local_ba_iterations;
  settings.local_mapping.ba_rounds_per_frame = opt.local_ba_rounds_per_frame;
  settings.local_mapping.ba_from_next_frame = opt.local_ba_from_next_frame == "on";
  settings.local_mapping.ba_iterations_per_frame = opt.local_ba_iterations_per_frame;
  settings.local_mapping.bundle.backend =
      opt.local_ba_solver == "schur_lm" ? BundleAdjustmentBackend::schur_lm : BundleAdjustmentBackend::ceres;
  settings.tracker.ransac_only_on_failure = opt.tracking_ransac == "on_failure";
  settings.tracker.ransac_solver =
      opt.tracking_ransac_solver == "rigid" ? slam::TrackingRansacSolver::rigid : slam::TrackingRansacSolver::epnp;
  settings.tracker.refinement.backend =
      opt.tracking_solver == "ceres" ? PoseRefinementBackend::ceres : PoseRefinementBackend::pose_lm;
  settings.loop_correction.bundle.backend =
      opt.global_ba_solver == "schur_lm" ? BundleAdjustmentBackend::schur_lm : BundleAdjustmentBackend::ceres;
  apply_map_maintenance(opt.map_maintenance, settings.local_mapping);
  settings.orbslam2_keyframes.min_frame_gap = opt.keyframe_min_gap;
  settings.keep_keyframe_images = opt.map;
  settings.loop_correction.enabled = opt.loop_correction != "none";
  settings.local_mapping.bundle_adjustment = opt.local_ba == "on";
  settings.local_mapping.covisible_keyframes = opt.local_ba_window;
  settings.local_mapping.fixed_keyframes = opt.local_ba_fixed;
  settings.loop_correction.bundle_adjustment = opt.loop_correction == "pgo+ba";
  return settings;
}

void check_run_options(SlamRunOptions& opt, slam::DynamicMode mode,
                       const std::function<void(const std::string&)>& warn) {
  if (opt.frames_given && opt.frames < 1) {
    throw std::invalid_argument("--frames must be at least 1, got " + std::to_string(opt.frames) +
                                " (omit it for every frame)");
  }
  if (!opt.dataset.empty() && opt.preset != kDefaultPreset) {
    throw std::invalid_argument("--preset renders a sequence: it cannot be combined with --dataset");
  }
  if (opt.dataset.empty()) {
    const std::vector<std::string> names = sim::preset_names();
    if (std::find(names.begin(), names.end(), opt.preset) == names.end()) {
      std::string known;
      for (const std::string& name : names) known += (known.empty() ? "" : ", ") + name;
      throw std::invalid_argument("--preset: unknown preset '" + opt.preset + "' (known: " + known + ")");
    }
    if (opt.frames_given && opt.frames > sim::kMaxPresetFrames) {
      throw std::invalid_argument("--frames must be at most " + std::to_string(sim::kMaxPresetFrames) +
                                  " (rendered: 10 minutes at 30 Hz), got " + std::to_string(opt.frames));
    }
  }
  // Options that only one source reads: say so instead of ignoring them in silence.
  if (!opt.model.empty() && opt.segmentation != "yolo") {
    warn("--model is used only with --segmentation yolo; ignored");
  }
  if (!opt.masks.empty() && opt.segmentation != "precomputed") {
    warn("--masks is used only with --segmentation precomputed; ignored");
  }
  if (opt.out.empty()) throw std::invalid_argument("--out must name a folder");
  if (opt.segmentation.empty()) opt.segmentation = mode == slam::DynamicMode::none ? "none" : "ground_truth";
  const std::set<std::string> kinds = {"none", "ground_truth", "yolo", "precomputed"};
  if (kinds.count(opt.segmentation) == 0) {
    throw std::invalid_argument("--segmentation: unknown source '" + opt.segmentation +
                                "' (expected none, ground_truth, yolo or precomputed)");
  }
  if (opt.segmentation == "yolo" && opt.model.empty()) {
    throw std::invalid_argument("--segmentation yolo needs --model ONNX");
  }
  if (opt.segmentation == "precomputed" && opt.masks.empty()) {
    throw std::invalid_argument("--segmentation precomputed needs --masks DIR");
  }
}

slam::LoopCloserSettings loop_closer_settings_from(const SlamRunOptions& opt) {
  slam::LoopCloserSettings loop;
  try {
    loop.scoring = slam::loop_scoring_from_string(opt.loop_scoring);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--loop-scoring: ") + e.what());
  }
  // The acceptance gate of the chosen scoring (step 3): S_sum for cge and combined, BoW for bow_only.
  if (opt.loop_min_score_given) {
    if (!std::isfinite(opt.loop_min_score)) throw std::invalid_argument("--loop-min-score must be a finite number");
    (loop.scoring == slam::LoopScoring::bow_only ? loop.min_bow_score : loop.min_cge_score) = opt.loop_min_score;
  }
  if (opt.cge_scaling == "raw") {
    loop.exponent_scaling = ScalingKind::raw;
  } else if (opt.cge_scaling == "normalised") {
    loop.exponent_scaling = ScalingKind::normalised_mean;
  } else if (!opt.cge_scaling.empty()) {
    throw std::invalid_argument("--cge-scaling: '" + opt.cge_scaling + "' is not raw or normalised");
  }
  loop.degree_entropy.ties = parse_tie_mode("--cge-ties", opt.cge_ties);
  loop.verified_members = opt.loop_verified_members;
  loop.verify_all_consistent_groups = opt.loop_verify_groups == "consistent";
  loop.min_group_total_ratio = opt.loop_min_group_ratio;
  try {
    loop.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("loop settings: ") + e.what());
  }
  return loop;
}

void apply_settings_file(const std::filesystem::path& file, PinholeIntrinsics<double>& intrinsics,
                         slam::SystemSettings& settings) {
  slam::apply_orbslam2_settings(dataset::read_orbslam2_settings(file), intrinsics, settings);
}

void check_first_image(const cv::Size& image, const std::optional<std::filesystem::path>& settings_file,
                       const slam::OrbSettings& orb) {
  const std::string size = std::to_string(image.width) + " x " + std::to_string(image.height);
  std::string where = "the settings";
  if (settings_file) {
    where = settings_file->string();
    const dataset::OrbSlam2Settings file = dataset::read_orbslam2_settings(*settings_file);
    if (file.width_px > 0 && (file.width_px != image.width || file.height_px != image.height)) {
      throw std::invalid_argument(where + ": Camera.width x Camera.height is " + std::to_string(file.width_px) +
                                  " x " + std::to_string(file.height_px) + ", but the images are " + size);
    }
  }
  dataset::OrbExtractorSettings pyramid;
  pyramid.levels = orb.levels;
  pyramid.scale_factor = orb.scale_factor;
  if (!dataset::coarsest_level_fits(pyramid, image.width, image.height)) {
    throw std::invalid_argument(where + ": ORBextractor.nLevels " + std::to_string(orb.levels) +
                                " is too many for " + size + " images at scaleFactor " +
                                short_number(orb.scale_factor) + " (the coarsest level keeps no pixel)");
  }
}

}  // namespace run
}  // namespace cge
