#include "cge/run/slam_run.hpp"

#include <algorithm>
#include <chrono>
#include <sstream>
#include <stdexcept>

#include "cge/dataset/tum_sequence.hpp"
#include "cge/mapping/map_image.hpp"
#include "cge/metrics/loop_queries_io.hpp"
#include "cge/run/dataset_frame_source.hpp"
#include "cge/run/default_vocabulary.hpp"
#include "cge/run/loop_report.hpp"
#include "cge/run/rendered_frame_source.hpp"
#include "cge/run/run_settings.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/output_files.hpp"

namespace cge {
namespace run {

namespace fs = std::filesystem;

namespace {
double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

const std::vector<std::string>& SlamRun::output_names() {
  static const std::vector<std::string> names = {"trajectory.txt", "keyframes.txt", "loops.csv",   "frames.csv",
                                                 "timings.csv",    "summary.json",  "groundtruth.txt", "map.ply",
                                                 "map.ot",         "map.bt",        "map_top.png",  "loops.txt"};
  return names;
}

SlamRun::SlamRun(SlamRunOptions options, const Message& warn) : options_(std::move(options)) {
  SlamRunOptions& opt = options_;
  settings_ = system_settings_from(opt);
  check_run_options(opt, settings_.mode, warn);
  loop_settings_ = loop_closer_settings_from(opt);
  const bool loops_off = opt.vocabulary == kNoVocabulary;
  vocabulary_source_ = loops_off ? "none: loop closing off (--vocabulary none)" : opt.vocabulary;
  if (!opt.vocabulary.empty() && !loops_off) {
    if (fs::is_directory(opt.vocabulary)) {
      throw std::invalid_argument("--vocabulary: '" + opt.vocabulary + "' is a directory, not a file");
    }
    vocabulary_ = std::make_unique<bow::Vocabulary>(bow::Vocabulary::load_file(opt.vocabulary));
  }
  if (opt.dataset.empty()) {
    open_rendered();
  } else {
    open_dataset();
  }
  // After the settings file, which sets the depth weight of tracking and BA (cge.DepthSigmaPerMetre or 1 / bf).
  if (opt.tracking_depth_sigma_given) settings_.tracker.refinement_depth_sigma_per_m = opt.tracking_depth_sigma;
  try {
    settings_.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("settings: ") + e.what());
  }
  // The images against the settings, before any work.
  if (source_->frame_count() > 0) check_first_image(source_->frame(0).bgr.size(), settings_file_, settings_.frame.orb);
}

SlamRun::~SlamRun() = default;

void SlamRun::open_rendered() {
  const SlamRunOptions& opt = options_;
  const int frames = opt.frames > 0 ? opt.frames : kDefaultPresetFrames;
  if (opt.segmentation == "precomputed") throw std::invalid_argument("--segmentation precomputed needs --dataset");
  auto rendered = std::make_unique<RenderedFrameSource>(opt.preset, frames, opt.seed, opt.segmentation == "ground_truth");
  const sim::PinholeCamera& cam = rendered->camera();
  intrinsics_ = {cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px};
  settings_.frame.depth_units_per_metre = cam.depth_units_per_metre;
  if (!opt.settings.empty()) {
    settings_file_ = opt.settings;
    apply_settings_file(opt.settings, intrinsics_, settings_);
  }
  if (opt.segmentation == "yolo" && slam::uses_masks(settings_.mode)) {
    dataset::SegmentationSourceSettings seg;
    seg.source = dataset::SegmentationSource::yolo;
    seg.yolo_model_path = opt.model;
    apply_temporal_filter(opt.temporal_filter, opt.temporal_overlap, seg);
    segmenter_ = dataset::make_segmenter(seg, "");
  }
  source_ = std::move(rendered);
  source_name_ = opt.preset + " rendered (" + std::to_string(frames) + " frames, seed " + std::to_string(opt.seed) + ")";
}

void SlamRun::open_dataset() {
  const SlamRunOptions& opt = options_;
  if (!fs::is_directory(opt.dataset)) throw std::invalid_argument("--dataset: '" + opt.dataset + "' is not a folder");
  auto sequence = std::make_unique<dataset::TumSequence>(opt.dataset, dataset::TumSequenceSettings{});
  if (!opt.settings.empty()) {
    settings_file_ = opt.settings;
  } else if (sequence->camera_settings_file()) {
    settings_file_ = *sequence->camera_settings_file();
  } else {
    throw std::invalid_argument("no settings: " + opt.dataset + " has no camera.yaml (give --settings YAML)");
  }
  apply_settings_file(*settings_file_, intrinsics_, settings_);
  const int frames = opt.frames > 0 ? std::min(opt.frames, sequence->frame_count()) : sequence->frame_count();
  // A synthetic sequence's exact masks give the leak count's ground truth; real data has none. A
  // cge_sim loop scene's loops.txt: the loop decisions are evaluated against it.
  std::unique_ptr<PrecomputedMaskReader> moving_masks = open_exact_masks(opt.dataset);
  source_ = std::make_unique<DatasetFrameSource>(std::move(sequence), frames, std::move(moving_masks),
                                                 loops_file_of(opt.dataset));
  source_name_ = opt.dataset;
  dataset::SegmentationSourceSettings seg;
  seg.source = dataset::parse_segmentation_source(opt.segmentation);
  seg.yolo_model_path = opt.model;
  seg.mask_folder = opt.masks;
  apply_temporal_filter(opt.temporal_filter, opt.temporal_overlap, seg);
  if (slam::uses_masks(settings_.mode)) segmenter_ = dataset::make_segmenter(seg, opt.dataset);
}

void SlamRun::prepare_vocabulary() {
  if (vocabulary_prepared_) return;
  vocabulary_prepared_ = true;
  if (options_.vocabulary.empty()) {
    if (rendered()) {
      const auto start = std::chrono::steady_clock::now();
      const std::uint64_t seed = options_.seed + 1;  // another scene: other textures, paths and phases
      const std::string trained_on = vocabulary_preset(options_.preset);
      vocabulary_ = std::make_unique<bow::Vocabulary>(train_default_vocabulary(trained_on, seed));
      vocabulary_training_s_ = seconds_since(start);
      vocabulary_source_ = default_vocabulary_description(trained_on, seed);
    } else {
      vocabulary_source_ = "none given: loop closing off (train one with cge_vocab, pass --vocabulary FILE)";
    }
  }
  loop_closing_ = vocabulary_ != nullptr;
  if (vocabulary_ != nullptr) vocabulary_words_ = vocabulary_->word_count();
}

void SlamRun::process(const std::function<void(int, int)>& progress) {
  prepare_vocabulary();
  system_ = std::make_unique<slam::System>(settings_, intrinsics_, std::move(segmenter_));
  const int n = source_->frame_count();
  const bool own_instances = source_->provides_instances() && slam::uses_masks(settings_.mode);
  for (int i = 0; i < n; ++i) {
    const slam::FrameInput input = source_->frame(i);
    if (i == 0 && vocabulary_ != nullptr) {
      system_->set_loop_closer(std::make_unique<slam::LoopCloser>(std::move(*vocabulary_), intrinsics_,
                                                                  input.bgr.cols, input.bgr.rows, loop_settings_));
    }
    if (own_instances) {
      const auto seg_start = std::chrono::steady_clock::now();
      const std::vector<SegmentedInstance> instances = source_->instances(i);
      system_->process(input, instances, 1000.0 * seconds_since(seg_start));
    } else {
      system_->process(input);
    }
    if (progress) progress(i + 1, n);
  }
  system_->finish();
}

bool SlamRun::every_frame_lost() const {
  const std::vector<slam::FrameRecord>& frames = system_->frames();
  return !frames.empty() &&
         std::none_of(frames.begin(), frames.end(), [](const slam::FrameRecord& r) { return r.has_pose(); });
}

void SlamRun::write_outputs(OutputFolder& out) {
  const slam::System& system = *system_;
  out.write("trajectory.txt", [&](std::ostream& f) { slam::write_trajectory(f, system); });
  out.write("keyframes.txt", [&](std::ostream& f) { slam::write_keyframes(f, system.map()); });
  std::ostringstream loops_csv;
  slam::write_loops_csv(loops_csv, system.loops());
  out.write("loops.csv", [&](std::ostream& f) { f << loops_csv.str(); });
  // The loop decisions against the ground-truth loops, read back from loops.csv as cge_eval loops
  // reads the file (same stamps, same numbers).
  ground_truth_loops_ = source_->ground_truth_loops(queried_stamps(system.loops()));
  if (ground_truth_loops_ && loop_closing_) {
    std::istringstream rows(loops_csv.str());
    loop_evaluation_ = metrics::evaluate_loops(*ground_truth_loops_, metrics::read_loop_queries(rows, "loops.csv"));
  }
  out.write("frames.csv", [&](std::ostream& f) { slam::write_frames_csv(f, system.frames()); });
  out.write("timings.csv", [&](std::ostream& f) { slam::write_timings_csv(f, system.frames()); });
  ground_truth_ = source_->ground_truth();
  summary_ = summarise_run(system, ground_truth_);
  if (options_.map) {
    // Semantic maps from the final (optimised) keyframes: dense cloud, octree, top view, scores.
    mapping::SemanticMapBuilder map(intrinsics_, {}, settings_.frame.distortion);
    map.rebuild(system.map().keyframes());
    map.write_ply(out.stage("map.ply"));
    map.write_octree(out.stage("map.ot"), out.stage("map.bt"));
    mapping::write_png(out.stage("map_top.png"), mapping::render_top_view(map.occupied_voxels()));
    map_figures_ = map.scores();
  }
  if (rendered() && !ground_truth_.empty()) {
    out.write("groundtruth.txt", [&](std::ostream& f) {
      f << "# ground truth trajectory of the rendered sequence: timestamp tx ty tz qx qy qz qw\n";
      for (const auto& p : ground_truth_) f << slam::tum_pose_line(p.first, p.second) << '\n';
    });
  }
  if (rendered() && ground_truth_loops_) {
    out.write("loops.txt", [&](std::ostream& f) { write_ground_truth_loops(f, *ground_truth_loops_); });
  }
}

}  // namespace run
}  // namespace cge
