// cge_slam: the reference pipeline on an RGB-D sequence (TUM layout) or, without --dataset, on a
// synthetic preset rendered in memory (--preset, walking_xyz by default). Writes into --out:
//   trajectory.txt  every tracked frame, TUM format (T_world_camera)
//   keyframes.txt   the keyframes, TUM format
//   loops.csv       the loop closer's decisions (header only when loop closing is off)
//   loops.txt       (without --dataset, at most kMaxLoopTruthFrames frames) the ground-truth loops
//                   of the rendered sequence whose query is a keyframe the loop closer queried,
//                   for cge_eval loops
//   frames.csv      per frame: tracking state, features, dynamic labels, matches, keyframe, and the
//                   keypoints on moving bodies (with ground truth: synthetic masks/ or rendered)
//   timings.csv     per frame and stage, milliseconds
//   summary.json    counts, the run's settings (loop_settings), the dynamic-feature leak rate
//                   (dynamic_leak) and mean/median time per stage
//   groundtruth.txt (without --dataset) the rendered poses, for cge_eval
// Loop closing needs a vocabulary: --vocabulary FILE, or, without --dataset, one trained here on
// frames of another rendered preset (never the evaluated frames; --vocabulary none switches loop
// closing off). With ground-truth loops (rendered, or the dataset's loops.txt) the loop decisions
// are evaluated as cge_eval loops does (precision, query and event recall) and printed.
// trajectory.txt, keyframes.txt, loops.csv, frames.csv and groundtruth.txt are deterministic (same
// inputs and seed: same bytes); timings.csv and the `stages` object of summary.json are
// measurements and differ from run to run.
//
// Output folder: refused when not empty unless --force; with --force only the files above are
// replaced, nothing else is touched. Files are written into a hidden staging folder inside --out
// (.cge_slam.partial.<pid>) and renamed into place only when the run succeeded, after every
// destination was checked, so a failed run leaves --out as it was; so does SIGTERM or SIGINT,
// whose handler removes the staging folder. Staging folders of processes no longer alive are
// leftovers of a killed run: they do not make --out "not empty" and are removed. Missing folders
// on the way to --out are created (docs/CLI.md) and removed again when the run fails.
// Standard error: diagnostics and, on a terminal only, a progress bar.
// Exit codes: 0 success; 1 failure while running (a file that cannot be written); 2 bad usage or
// bad input (missing dataset, malformed list file, unreadable image, sizes that differ, ...).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <csignal>
#include <cerrno>
#include <cstring>

#include <signal.h>
#include <sys/types.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/dataset/segmentation_source.hpp"
#include "cge/dataset/tum_sequence.hpp"
#include "cge/mapping/map_image.hpp"
#include "cge/mapping/semantic_map_builder.hpp"
#include "cge/metrics/ate.hpp"
#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/metrics/loop_precision_recall.hpp"
#include "cge/metrics/loop_queries_io.hpp"
#include "cge/metrics/rpe.hpp"
#include "cge/segmentation/coco_classes.hpp"
#include "cge/segmentation/precomputed_mask_reader.hpp"
#include "cge/sim/frame_source.hpp"
#include "cge/sim/loops.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/sim/segmentation_error_model.hpp"
#include "cge/slam/label_instances.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/moving_keypoints.hpp"
#include "cge/slam/output_files.hpp"
#include "cge/slam/settings_from_orbslam2.hpp"
#include "cge/slam/system.hpp"
#include "cge/slam/vocabulary_training.hpp"

#include "tool_support.hpp"

#ifndef CGE_VERSION_STRING
#define CGE_VERSION_STRING "unknown"
#endif

namespace {

namespace fs = std::filesystem;

using cge_tool::kExitFailure;
using cge_tool::kExitOk;
constexpr const char* kProgram = "cge_slam";
constexpr const char* kDefaultPreset = "walking_xyz";
constexpr int kDefaultPresetFrames = 300;  // 10 s at 30 fps when --frames is not given
// The vocabulary of a rendered run without --vocabulary: another preset of the same room (another
// camera path, other walkers, another seed), so the evaluated frames never train it; 20 images
// spread over 10 s of it, k = 10, L = 4 (about 9 000 words, as cge_vocab's default).
constexpr const char* kVocabularyPreset = "walking_halfsphere";
constexpr const char* kVocabularyPresetOtherwise = "walking_xyz";  // when walking_halfsphere is evaluated
constexpr int kVocabularyPresetFrames = 300;
constexpr int kVocabularyImages = 20;
constexpr const char* kNoVocabulary = "none";  // --vocabulary none: loop closing off
// Rendered runs longer than this get no ground-truth loops (RenderedSource::ground_truth_loops).
constexpr int kMaxLoopTruthFrames = 1800;

cge_tool::ProgressBar progress_bar{kProgram};  // drawn only on a terminal

using cge_tool::UsageError;

/// The --temporal-filter default: "N/M" of the segmentation source's defaults.
std::string default_temporal_filter() {
  const cge::TemporalInstanceFilterSettings d;
  return std::to_string(d.min_frames_seen) + "/" + std::to_string(d.window_frames);
}

struct Options {
  std::string dataset;
  std::string preset = kDefaultPreset;  // rendered when there is no --dataset
  std::string mode = "YMK";
  std::string segmentation;  // default: ground_truth (rendered or synthetic folder)
  std::string model;
  std::string masks;
  // Temporal instance filter of the network sources: "N/M" (seen in N of the last M frames) or "off".
  std::string temporal_filter = default_temporal_filter();
  std::string temporal_overlap = cge::to_string(cge::TemporalInstanceFilterSettings{}.overlap);
  std::string depth_estimate = cge::to_string(cge::DepthMADSettings{}.depth_estimate);  // modes YM, YMK
  std::string settings;
  std::string vocabulary;
  std::uint64_t seed = 0;
  int frames = 0;  // not given: all (dataset) or kDefaultPresetFrames (rendered)
  bool frames_given = false;
  int reference_min_observations = cge::slam::MappingSettings{}.reference_min_observations;
  int keyframe_interval = cge::PatchKeyframeSettings<double>{}.interval_frames;  // mode YMK: k
  int orb_spread = cge::slam::OrbSettings{}.spread_oversampling;
  int local_ba_iterations = cge::slam::LocalMappingSettings{}.bundle.solver.max_iterations;
  int local_ba_rounds_per_frame = cge::slam::LocalMappingSettings{}.ba_rounds_per_frame;
  std::string map_maintenance = "all";
  int keyframe_min_gap = cge::slam::SystemSettings{}.orbslam2_keyframes.min_frame_gap;
  std::string loop_correction = "pgo+ba";                                        // none | pgo | pgo+ba
  // Depth term of the tracking refinement (0: pixels only) and local BA (on | off).
  double tracking_depth_sigma = cge::slam::TrackerSettings{}.refinement_depth_sigma_per_m;
  bool tracking_depth_sigma_given = false;  ///< wins over the settings file's depth weight
  std::string local_ba = cge::slam::LocalMappingSettings{}.bundle_adjustment ? "on" : "off";
  int local_ba_window = cge::slam::LocalMappingSettings{}.covisible_keyframes;
  int local_ba_fixed = cge::slam::LocalMappingSettings{}.fixed_keyframes;
  std::string loop_scoring = cge::slam::to_string(cge::slam::LoopCloserSettings{}.scoring);
  double loop_min_score = 0;  // used only when --loop-min-score is given (loop_min_score_given)
  bool loop_min_score_given = false;
  int loop_verified_members = cge::slam::LoopCloserSettings{}.verified_members;
  double loop_min_group_ratio = cge::slam::LoopCloserSettings{}.min_group_total_ratio;
  std::string loop_verify_groups =
      cge::slam::LoopCloserSettings{}.verify_all_consistent_groups ? "consistent" : "best";  // best | consistent
  std::string cge_scaling;  // raw | normalised; empty: the LoopCloserSettings default
  std::string cge_ties = "all";  // all | mean | min: TieMode of the loop closer's degree sums
  bool map = false;         // write map.ply, map.ot, map.bt, map_top.png
  std::string out;
  bool force = false;
};

/// --temporal-filter and --temporal-overlap into the segmentation source's settings.
void apply_temporal_filter(const std::string& text, const std::string& overlap,
                           cge::dataset::SegmentationSourceSettings& seg) {
  seg.temporal_filter.overlap = overlap == "mask" ? cge::TemporalOverlap::mask : cge::TemporalOverlap::box;
  if (text == "off") {
    seg.temporal_filter_sources.clear();
    return;
  }
  const std::size_t slash = text.find('/');
  int n = 0, m = 0;
  std::size_t used_n = 0, used_m = 0;
  try {
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    n = std::stoi(text.substr(0, slash), &used_n);
    m = std::stoi(text.substr(slash + 1), &used_m);
  } catch (const std::exception&) {
    throw UsageError("--temporal-filter: '" + text + "' is not N/M (e.g. 2/3) or off");
  }
  if (used_n != slash || used_m != text.size() - slash - 1) {
    throw UsageError("--temporal-filter: '" + text + "' is not N/M (e.g. 2/3) or off");
  }
  seg.temporal_filter.min_frames_seen = n;
  seg.temporal_filter.window_frames = m;
  try {
    seg.temporal_filter.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--temporal-filter: ") + e.what());
  }
}

/// A number as "%g" prints it (help texts).
std::string short_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

// ---- settings ------------------------------------------------------------------------------------

/// Camera, depth scale, depth weight, ORB extractor and keyframe gap from an ORB-SLAM2 TUM YAML file.
void apply_settings_file(const fs::path& file, cge::PinholeIntrinsics<double>& intrinsics,
                         cge::slam::SystemSettings& settings) {
  cge::slam::apply_orbslam2_settings(cge::dataset::read_orbslam2_settings(file), intrinsics, settings);
}

// ---- the output folder ---------------------------------------------------------------------------

/// Every file cge_slam may write into --out: each destination is checked before the run.
const std::vector<std::string>& output_names() {
  static const std::vector<std::string> names = {"trajectory.txt", "keyframes.txt", "loops.csv",   "frames.csv",
                                                 "timings.csv",    "summary.json",  "groundtruth.txt", "map.ply",
                                                 "map.ot",         "map.bt",        "map_top.png",  "loops.txt"};
  return names;
}

/// What the SIGTERM / SIGINT handler removes: the staging folder's possible files, the folder,
/// and --out when this run created it (rmdir: only when empty). Plain C strings, written before
/// the handler is installed, so that the handler only calls unlink, rmdir, signal and raise.
struct SignalCleanup {
  static constexpr std::size_t kPathBytes = 4096;
  char staged[16][kPathBytes] = {};
  int staged_count = 0;
  char staging[kPathBytes] = {};
  char created_out[kPathBytes] = {};
};
SignalCleanup signal_cleanup;
volatile std::sig_atomic_t cleanup_armed = 0;

extern "C" void remove_staging_and_die(int signal_number) {
  if (cleanup_armed != 0) {
    for (int i = 0; i < signal_cleanup.staged_count; ++i) ::unlink(signal_cleanup.staged[i]);
    ::rmdir(signal_cleanup.staging);
    if (signal_cleanup.created_out[0] != '\0') ::rmdir(signal_cleanup.created_out);
  }
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

bool copy_path(char* to, const fs::path& from) {
  const std::string text = from.string();
  if (text.size() + 1 > SignalCleanup::kPathBytes) return false;
  std::memcpy(to, text.c_str(), text.size() + 1);
  return true;
}

/// A staging folder ".cge_slam.partial.<pid>" whose process is gone (a killed run's leftover).
bool is_stale_staging(const fs::path& entry) {
  const std::string name = entry.filename().string();
  const std::string prefix = ".cge_slam.partial.";
  if (name.compare(0, prefix.size(), prefix) != 0 || name.size() == prefix.size()) return false;
  const std::string digits = name.substr(prefix.size());
  if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) return false;
  const long pid = std::stol(digits);
  if (pid == static_cast<long>(::getpid())) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

/// Writes files into a hidden staging folder inside `out` and moves them into `out` on commit();
/// without commit() (a failure) the staging folder is removed and `out` is as it was.
class OutputFolder {
 public:
  OutputFolder(const fs::path& out, bool force) : out_(out) {
    std::error_code ec;
    std::vector<fs::path> stale;
    if (fs::exists(out_, ec)) {
      if (!fs::is_directory(out_, ec)) throw UsageError("'" + out_.string() + "' exists and is not a folder");
      bool other_entries = false;
      for (const auto& entry : fs::directory_iterator(out_, ec)) {
        if (is_stale_staging(entry.path())) {
          stale.push_back(entry.path());
        } else {
          other_entries = true;
        }
      }
      if (other_entries && !force) {
        throw UsageError("'" + out_.string() +
                         "' exists and is not empty (use --force to replace cge_slam's files in it)");
      }
      // Replacing must not fail half-way: every destination must be a file or free.
      for (const std::string& name : output_names()) check_destination(name);
    } else {
      folders_.create(out_, "--out");
      created_out_ = true;
    }
    for (const fs::path& p : stale) fs::remove_all(p, ec);  // a killed run's files, never the user's
    staging_ = out_ / (".cge_slam.partial." + std::to_string(::getpid()));
    fs::create_directory(staging_, ec);
    if (ec) throw std::runtime_error("cannot create '" + staging_.string() + "': " + ec.message());
    arm_signal_cleanup();
  }
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder() {
    cleanup_armed = 0;
    if (committed_) return;
    std::error_code ec;
    fs::remove_all(staging_, ec);  // our own folder, holding only our files
    // folders_ (destroyed after this body) removes the folders this run created, when empty.
  }

  template <typename Writer>
  void write(const std::string& name, Writer&& writer) {
    const fs::path path = staging_ / name;
    std::ofstream file(path, std::ios::binary);
    if (!file) throw std::runtime_error("cannot write " + path.string());
    writer(file);
    file.flush();
    if (!file) throw std::runtime_error("cannot write " + path.string());
    names_.push_back(name);
  }

  /// A path in the staging folder for a writer that takes a file name (the map files); moved into
  /// `out` on commit() like the others.
  fs::path stage(const std::string& name) {
    names_.push_back(name);
    return staging_ / name;
  }

  /// Moves the files into `out`: every destination is checked first (it may have changed during
  /// the run), so that the renames do not stop half-way over a user's folder.
  void commit() {
    for (const std::string& name : names_) check_destination(name);
    for (const std::string& name : names_) {
      std::error_code ec;
      fs::rename(staging_ / name, out_ / name, ec);
      if (ec) throw std::runtime_error("cannot move " + name + " into '" + out_.string() + "': " + ec.message());
    }
    cleanup_armed = 0;
    std::error_code ec;
    fs::remove(staging_, ec);
    committed_ = true;
    folders_.keep();
  }

 private:
  void check_destination(const std::string& name) const {
    std::error_code ec;
    const fs::file_status st = fs::symlink_status(out_ / name, ec);
    if (fs::exists(st) && !fs::is_regular_file(st)) {
      throw UsageError("'" + (out_ / name).string() + "' exists and is not a file: cge_slam cannot replace it");
    }
  }

  void arm_signal_cleanup() {
    SignalCleanup& c = signal_cleanup;
    bool fits = copy_path(c.staging, staging_);
    c.staged_count = 0;
    for (const std::string& name : output_names()) fits = fits && copy_path(c.staged[c.staged_count++], staging_ / name);
    c.created_out[0] = '\0';
    if (created_out_) fits = fits && copy_path(c.created_out, out_);
    if (!fits) return;  // a path longer than the buffers: no cleanup on signals
    cleanup_armed = 1;
    struct sigaction action {};
    action.sa_handler = remove_staging_and_die;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGTERM, &action, nullptr);
    ::sigaction(SIGINT, &action, nullptr);
  }

  cge_tool::CreatedFolders folders_;  // first member: destroyed last, after the staging folder
  fs::path out_, staging_;
  std::vector<std::string> names_;
  bool created_out_ = false;
  bool committed_ = false;
};

// ---- frame sources -------------------------------------------------------------------------------

/// The frames the run processes: read from a dataset folder or rendered in memory.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual int frame_count() const = 0;
  virtual cge::slam::FrameInput frame(int index) = 0;
  /// The instances of the frame when the source segments itself (rendered ground truth); the
  /// System's segmenter is used otherwise.
  virtual bool provides_instances() const { return false; }
  virtual std::vector<cge::SegmentedInstance> instances(int /*index*/) { return {}; }
  /// Ground-truth poses (timestamp, T_world_camera), when known.
  virtual std::vector<std::pair<double, Eigen::Isometry3d>> ground_truth() const { return {}; }
  /// Ground-truth loops, when known (std::nullopt: none to evaluate against). `queries`: the stamps
  /// (as "%.6f") of the keyframes the loop closer queried; a source may keep only their loops.
  virtual std::optional<std::vector<cge::metrics::GroundTruthLoop>> ground_truth_loops(
      const std::set<std::string>& /*queries*/) const {
    return std::nullopt;
  }
};

class DatasetSource final : public FrameSource {
 public:
  /// `moving_masks`: the sequence's exact ground-truth mask folder (a synthetic sequence's masks/),
  /// or null when it has none (real data): the frames then carry no moving mask.
  /// `loops_file`: the sequence's loops.txt (a cge_sim loop scene), or empty when it has none.
  DatasetSource(const cge::dataset::TumSequence& sequence, int frames,
                std::unique_ptr<cge::PrecomputedMaskReader> moving_masks, const fs::path& loops_file)
      : sequence_(sequence), frames_(frames), moving_masks_(std::move(moving_masks)) {
    if (!loops_file.empty()) loops_ = cge::metrics::read_ground_truth_loops_file(loops_file.string());
  }
  std::optional<std::vector<cge::metrics::GroundTruthLoop>> ground_truth_loops(
      const std::set<std::string>& /*queries*/) const override {
    return loops_;  // the user's file as it is, as cge_eval loops reads it
  }
  std::vector<std::pair<double, Eigen::Isometry3d>> ground_truth() const override {
    std::vector<std::pair<double, Eigen::Isometry3d>> gt;
    for (const auto& p : sequence_.ground_truth()) gt.emplace_back(p.timestamp_s, p.T_world_camera);
    return gt;
  }
  int frame_count() const override { return frames_; }
  cge::slam::FrameInput frame(int index) override {
    const cge::dataset::TumFrame f = sequence_.load(index);
    cge::slam::FrameInput in;
    in.index = index;
    in.timestamp_s = f.rgb_timestamp_s;
    in.bgr = f.bgr;
    in.depth = f.depth;
    in.stem = f.rgb_stem;
    if (moving_masks_ != nullptr) {
      in.moving_mask = cge::slam::moving_mask_of(moving_masks_->read(in.stem, in.bgr.size()), in.bgr.size());
    }
    return in;
  }

 private:
  const cge::dataset::TumSequence& sequence_;
  int frames_;
  std::unique_ptr<cge::PrecomputedMaskReader> moving_masks_;
  std::optional<std::vector<cge::metrics::GroundTruthLoop>> loops_;
};

class RenderedSource final : public FrameSource {
 public:
  RenderedSource(const std::string& preset, int frames, std::uint64_t seed, bool segment)
      : renderer_(cge::sim::make_preset(preset, frames, seed)), model_(renderer_.instances(), seed), segment_(segment) {
    for (const cge::sim::InstanceInfo& i : renderer_.instances()) {
      class_of_id_[i.id] = i.class_id;
      if (i.moving) moving_ids_.push_back(i.id);
    }
  }
  int frame_count() const override { return renderer_.frame_count(); }
  const cge::sim::PinholeCamera& camera() const { return renderer_.camera(); }
  cge::slam::FrameInput frame(int index) override {
    last_ = renderer_.render(index);
    cge::slam::FrameInput in;
    in.index = index;
    in.timestamp_s = last_.timestamp_s;
    in.bgr = last_.rgb;
    in.depth = last_.depth;
    char stem[32];
    std::snprintf(stem, sizeof stem, "%.6f", last_.timestamp_s);
    in.stem = stem;
    // Ground truth of the leak count: the exact labels of the bodies that move.
    in.moving_mask = cv::Mat::zeros(last_.instance_labels.size(), CV_8UC1);
    for (const int id : moving_ids_) in.moving_mask.setTo(255, last_.instance_labels == id);
    return in;
  }
  bool provides_instances() const override { return segment_; }
  std::vector<cge::SegmentedInstance> instances(int index) override {
    const cge::sim::SegmentationResult seg = model_.apply(last_.instance_labels, index);
    std::map<int, int> classes = class_of_id_;
    for (const cge::sim::InstanceInfo& i : seg.instances) classes[i.id] = i.class_id;  // false positives
    return cge::slam::instances_from_label_image(seg.instance_labels, classes, {cge::kCocoPerson});
  }
  std::vector<std::pair<double, Eigen::Isometry3d>> ground_truth() const override {
    std::vector<std::pair<double, Eigen::Isometry3d>> gt;
    const cge::sim::SequenceSpec& spec = renderer_.spec();
    for (std::size_t i = 0; i < spec.T_world_camera.size(); ++i) {
      gt.emplace_back(spec.start_timestamp_s + static_cast<double>(i) / spec.frame_rate_hz, spec.T_world_camera[i]);
    }
    return gt;
  }
  /// The loop scenes' own ground truth; for the other presets the same rule (cge::sim::
  /// ground_truth_loops, its default settings: back within 0.3 m and 20 degrees after at least 2 m
  /// of travel) applied to the rendered poses. Only the loops of the queried keyframes are kept: on
  /// a camera that stays in one place (walking_xyz) almost every pair of distant frames is a loop.
  /// The pairs grow with the square of the length, so beyond kMaxLoopTruthFrames frames (at most
  /// 1.6 million pairs, 13 MB while they are filtered) there is no ground truth.
  std::optional<std::vector<cge::metrics::GroundTruthLoop>> ground_truth_loops(
      const std::set<std::string>& queries) const override {
    const cge::sim::SequenceSpec& spec = renderer_.spec();
    if (spec.T_world_camera.size() > static_cast<std::size_t>(kMaxLoopTruthFrames)) return std::nullopt;
    const auto stamp = [&spec](int i) { return spec.start_timestamp_s + static_cast<double>(i) / spec.frame_rate_hz; };
    const bool loop_scene = spec.name.rfind("loop_", 0) == 0;
    const std::vector<cge::sim::LoopPair> pairs =
        loop_scene ? spec.loops : cge::sim::ground_truth_loops(spec.T_world_camera);
    std::vector<cge::metrics::GroundTruthLoop> loops;
    char text[32];
    for (const cge::sim::LoopPair& p : pairs) {
      std::snprintf(text, sizeof text, "%.6f", stamp(p.query_frame));
      if (queries.count(text) == 0) continue;
      cge::metrics::GroundTruthLoop l;
      l.query_timestamp_s = stamp(p.query_frame);
      l.match_timestamp_s = stamp(p.match_frame);
      l.query_index = p.query_frame;
      l.match_index = p.match_frame;
      loops.push_back(l);
    }
    return loops;
  }

 private:
  cge::sim::SequenceRenderer renderer_;
  cge::sim::SegmentationErrorModel model_;
  bool segment_;
  std::map<int, int> class_of_id_;
  std::vector<int> moving_ids_;
  cge::sim::RenderedFrame last_;
};

/// The preset that trains the vocabulary of a rendered run of `evaluated` (never itself).
std::string vocabulary_preset(const std::string& evaluated) {
  return evaluated == kVocabularyPreset ? kVocabularyPresetOtherwise : kVocabularyPreset;
}

/// The vocabulary of a rendered run without --vocabulary (kVocabularyPreset, see there).
cge::bow::Vocabulary train_default_vocabulary(const std::string& preset_name, std::uint64_t seed) {
  const cge::sim::RendererFrameSource<cge::sim::SequenceRenderer> preset(
      cge::sim::SequenceRenderer(cge::sim::make_preset(preset_name, kVocabularyPresetFrames, seed)));
  cge::slam::VocabularyTrainingSettings training;  // cge_vocab's defaults: 1000 ORB, k = 10, L = 4, seed 1
  training.frame_step = kVocabularyPresetFrames / kVocabularyImages;
  return cge::slam::train_vocabulary(preset, kVocabularyPresetFrames, training);
}

// ---- summary ---------------------------------------------------------------------------------------

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The dynamic-feature leak over the frames with a moving mask: rate = kept / moving keypoints
/// (null when no frame had ground truth or no keypoint lay on a moving body).
nlohmann::ordered_json dynamic_leak(const std::vector<cge::slam::FrameRecord>& frames) {
  long long with_truth = 0, moving = 0, kept = 0;
  for (const auto& r : frames) {
    if (r.moving_keypoints < 0) continue;
    ++with_truth;
    moving += r.moving_keypoints;
    kept += r.moving_kept;
  }
  nlohmann::ordered_json j = {
      {"frames_with_ground_truth", with_truth}, {"moving_keypoints", moving}, {"moving_kept", kept}};
  j["rate"] = moving > 0 ? nlohmann::ordered_json(static_cast<double>(kept) / static_cast<double>(moving)) : nullptr;
  return j;
}

nlohmann::ordered_json make_summary(const cge::slam::System& system, const Options& opt, const std::string& source,
                                    const std::vector<std::pair<double, Eigen::Isometry3d>>& ground_truth,
                                    const nlohmann::ordered_json& loop_settings) {
  using cge::slam::TrackingState;
  nlohmann::ordered_json j;
  const auto& frames = system.frames();
  int tracked = 0, odometry = 0, relocalised = 0;
  for (const auto& r : frames) {
    tracked += r.has_pose();
    odometry += r.state == TrackingState::odometry;
    relocalised += r.state == TrackingState::relocalised;
  }
  j["frames"] = frames.size();
  j["tracked_frames"] = tracked;  // every frame with a pose, odometry and relocalised ones included
  j["lost_frames"] = static_cast<int>(frames.size()) - tracked;
  j["odometry_frames"] = odometry;
  j["relocalised_frames"] = relocalised;
  // Kept: after map maintenance culled keyframes and erased points (ORB-SLAM2's counts).
  j["keyframes"] = system.map().active_keyframe_count();
  j["keyframes_inserted"] = system.map().keyframe_count();
  j["map_points"] = system.map().active_map_point_count();
  j["map_points_created"] = system.map().map_point_count();
  int accepted = 0;
  for (const auto& l : system.loops()) accepted += l.accepted;
  j["loops"] = {
      {"candidates", system.loops().size()}, {"accepted", accepted}, {"corrections", system.loop_corrections()}};
  j["mode"] = cge::slam::to_string(system.settings().mode);
  j["segmentation"] = opt.segmentation;
  j["temporal_filter"] = opt.segmentation == "yolo" ? opt.temporal_filter : "off";
  if (opt.segmentation == "yolo" && opt.temporal_filter != "off") j["temporal_overlap"] = opt.temporal_overlap;
  j["depth_estimate"] = cge::to_string(system.settings().frame.mad.depth_estimate);
  j["source"] = source;
  j["seed"] = opt.seed;
  j["loop_settings"] = loop_settings;
  // The tracking and mapping settings the run used (the flags that change the trajectory).
  const cge::slam::SystemSettings& used = system.settings();
  j["mapping_settings"] = {{"tracking_depth_sigma", used.tracker.refinement_depth_sigma_per_m},
                           {"ba_depth_sigma", used.local_mapping.depth_sigma_per_m},
                           {"local_ba", used.local_mapping.bundle_adjustment ? "on" : "off"},
                           {"local_ba_window", used.local_mapping.covisible_keyframes},
                           {"local_ba_fixed", used.local_mapping.fixed_keyframes},
                           {"reference_min_observations", used.mapping.reference_min_observations},
                           {"keyframe_interval", used.patch_keyframes.interval_frames},
                           {"keyframe_min_gap", used.orbslam2_keyframes.min_frame_gap},
                           {"orb_spread", used.frame.orb.spread_oversampling},
                           {"local_ba_iterations", used.local_mapping.bundle.solver.max_iterations},
                           {"local_ba_rounds_per_frame", used.local_mapping.ba_rounds_per_frame},
                           {"map_maintenance", opt.map_maintenance},
                           {"loop_correction", opt.loop_correction}};
  j["dynamic_leak"] = dynamic_leak(frames);
  nlohmann::ordered_json stages;
  for (int s = 0; s < cge::slam::kStageCount; ++s) {
    std::vector<double> ms;
    double sum = 0;
    for (const auto& r : frames) {
      ms.push_back(r.times_ms[static_cast<std::size_t>(s)]);
      sum += ms.back();
    }
    stages[cge::slam::to_string(static_cast<cge::slam::Stage>(s))] = {
        {"mean_ms", frames.empty() ? 0.0 : sum / static_cast<double>(frames.size())}, {"median_ms", median(ms)}};
  }
  // ATE (cge::metrics, as cge_eval ate) when ground truth exists and a frame was tracked.
  cge::metrics::Trajectory gt, estimate;
  for (const auto& p : ground_truth) gt.push_back({p.first, p.second});
  for (const auto& r : frames) {
    if (r.has_pose()) estimate.push_back({r.timestamp_s, system.pose_of(r)});
  }
  if (!gt.empty() && !estimate.empty()) {
    try {
      const cge::metrics::AteResult ate = cge::metrics::compute_ate(gt, estimate);
      const cge::metrics::ErrorStatistics& t = ate.translation_m;
      j["ate"] = {{"pairs", t.count}, {"rmse_m", t.rmse}, {"mean_m", t.mean}, {"median_m", t.median},
                  {"std_m", t.std},   {"min_m", t.min},   {"max_m", t.max}};
    } catch (const std::invalid_argument& e) {
      j["ate"] = {{"error", e.what()}};
    }
    try {  // RPE over 1 s, as cge_eval rpe's default
      const cge::metrics::RpeResult rpe = cge::metrics::compute_rpe(gt, estimate);
      j["rpe"] = {{"delta_s", cge::metrics::RpeSettings{}.delta},
                  {"pairs", rpe.translation_m.count},
                  {"translation_rmse_m", rpe.translation_m.rmse},
                  {"rotation_rmse_deg", rpe.rotation_deg.rmse}};
    } catch (const std::invalid_argument& e) {
      j["rpe"] = {{"error", e.what()}};
    }
  }
  j["stages"] = stages;
  return j;
}

// ---- loops against the ground truth ------------------------------------------------------------------

/// loops.txt as cge_sim writes it (stamps as the rendered frames' stems).
void write_ground_truth_loops(std::ostream& f, const std::vector<cge::metrics::GroundTruthLoop>& loops) {
  f << "# ground-truth loops: the query frame revisits the place seen in the match frame (match < query)\n"
       "# indices count the frames from 0\n"
       "# query_timestamp match_timestamp query_index match_index\n";
  char line[128];
  for (const cge::metrics::GroundTruthLoop& l : loops) {
    std::snprintf(line, sizeof line, "%.6f %.6f %lld %lld\n", l.query_timestamp_s, l.match_timestamp_s, l.query_index,
                  l.match_index);
    f << line;
  }
}

nlohmann::ordered_json loop_evaluation_json(const cge::metrics::LoopEvaluation& e) {
  const auto number = [](double v) { return std::isnan(v) ? nlohmann::ordered_json() : nlohmann::ordered_json(v); };
  nlohmann::ordered_json j = {{"ground_truth_pairs", e.ground_truth_pairs},
                              {"queried_keyframes", e.queried_keyframes},
                              {"detections", e.detections},
                              {"correct_detections", e.correct_detections},
                              {"precision", number(e.precision)},
                              {"loop_queries", e.loop_queries},
                              {"detected_loop_queries", e.detected_loop_queries},
                              {"query_recall", number(e.query_recall)},
                              {"loop_events", e.loop_events},
                              {"detected_loop_events", e.detected_loop_events},
                              {"event_recall", number(e.event_recall)},
                              {"open_loop_queries", e.open_loop_queries},
                              {"open_query_recall", number(e.open_query_recall)}};
  j["missed_by_reason"] = nlohmann::ordered_json::object();
  for (const auto& [reason, count] : e.missed_by_reason) j["missed_by_reason"][reason] = count;
  return j;
}

/// The accepted loops, each marked correct or wrong against the ground-truth loops and, where the
/// ground-truth poses have both stamps, with how far apart the two cameras really were (centres,
/// metres; optical axes, degrees); then the figures (docs/EVALUATION.md); precision and recalls are
/// nan when their denominator is 0.
void print_loop_evaluation(const std::vector<cge::slam::LoopRecord>& loops,
                           const std::vector<cge::metrics::GroundTruthLoop>& ground_truth,
                           const std::vector<std::pair<double, Eigen::Isometry3d>>& poses,
                           const cge::metrics::LoopEvaluation& e) {
  const auto stamp = [](double t) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", t);
    return std::string(text);
  };
  std::set<std::pair<std::string, std::string>> pairs;
  for (const cge::metrics::GroundTruthLoop& l : ground_truth) {
    pairs.emplace(stamp(l.query_timestamp_s), stamp(l.match_timestamp_s));
  }
  std::map<std::string, Eigen::Isometry3d> pose_at;
  for (const auto& p : poses) pose_at.emplace(stamp(p.first), p.second);
  for (const cge::slam::LoopRecord& l : loops) {
    if (!l.accepted) continue;
    const std::string q = stamp(l.query_timestamp_s), m = stamp(l.match_timestamp_s);
    std::printf("loop_accepted query %s match %s keyframes %d %d inliers %d %s", q.c_str(), m.c_str(),
                l.query_keyframe, l.match_keyframe, l.matched_points, pairs.count({q, m}) > 0 ? "correct" : "wrong");
    const auto pq = pose_at.find(q), pm = pose_at.find(m);
    if (pq != pose_at.end() && pm != pose_at.end()) {
      const double distance_m = (pq->second.translation() - pm->second.translation()).norm();
      const double cosine = pq->second.linear().col(2).dot(pm->second.linear().col(2));
      const double angle_deg = std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI;
      std::printf(" ground_truth_apart %.3f m %.1f deg", distance_m, angle_deg);
    }
    std::printf("\n");
  }
  const auto print_line = [](const char* name, double value) { std::printf("%s %.6g\n", name, value); };
  print_line("loop_ground_truth_pairs", static_cast<double>(e.ground_truth_pairs));
  print_line("loop_correct", static_cast<double>(e.correct_detections));
  print_line("loop_precision", e.precision);
  print_line("loop_queries_with_loop", static_cast<double>(e.loop_queries));
  print_line("loop_query_recall", e.query_recall);
  print_line("loop_events", static_cast<double>(e.loop_events));
  print_line("loop_event_recall", e.event_recall);
}

// ---- the run ---------------------------------------------------------------------------------------

/// Compares the first image with the settings file (Camera.width x Camera.height) and with the ORB
/// pyramid; UsageError naming the file and key.
void check_first_image(const cv::Size& image, const std::optional<fs::path>& settings_file,
                       const cge::slam::OrbSettings& orb) {
  const std::string size = std::to_string(image.width) + " x " + std::to_string(image.height);
  std::string where = "the settings";
  if (settings_file) {
    where = settings_file->string();
    const cge::dataset::OrbSlam2Settings file = cge::dataset::read_orbslam2_settings(*settings_file);
    if (file.width_px > 0 && (file.width_px != image.width || file.height_px != image.height)) {
      throw UsageError(where + ": Camera.width x Camera.height is " + std::to_string(file.width_px) + " x " +
                       std::to_string(file.height_px) + ", but the images are " + size);
    }
  }
  cge::dataset::OrbExtractorSettings pyramid;
  pyramid.levels = orb.levels;
  pyramid.scale_factor = orb.scale_factor;
  if (!cge::dataset::coarsest_level_fits(pyramid, image.width, image.height)) {
    throw UsageError(where + ": ORBextractor.nLevels " + std::to_string(orb.levels) +
                     " is too many for " + size + " images at scaleFactor " + short_number(orb.scale_factor) +
                     " (the coarsest level keeps no pixel)");
  }
}

int run(Options opt) {
  cge::slam::SystemSettings settings;
  try {
    settings.mode = cge::slam::parse_dynamic_mode(opt.mode);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--mode: ") + e.what());
  }
  settings.seed = opt.seed;
  settings.frame.mad.depth_estimate =
      opt.depth_estimate == "mask_pixels" ? cge::DepthEstimate::mask_pixels : cge::DepthEstimate::box_samples;
  settings.mapping.reference_min_observations = opt.reference_min_observations;
  settings.patch_keyframes.interval_frames = opt.keyframe_interval;
  settings.frame.orb.spread_oversampling = opt.orb_spread;
  settings.local_mapping.bundle.solver.max_iterations = opt.local_ba_iterations;
  settings.local_mapping.ba_rounds_per_frame = opt.local_ba_rounds_per_frame;
  {
    cge::slam::LocalMappingSettings& lm = settings.local_mapping;
    const std::string& m = opt.map_maintenance;
    if (m != "all") {
      std::set<std::string> rules;
      std::stringstream list(m == "none" ? "" : m);
      for (std::string rule; std::getline(list, rule, ',');) {
        if (rule != "cull_points" && rule != "triangulate" && rule != "fuse" && rule != "cull_keyframes") {
          throw UsageError("--map-maintenance: unknown rule '" + rule +
                           "' (expected all, none or a comma list of cull_points, triangulate, fuse, cull_keyframes)");
        }
        rules.insert(rule);
      }
      lm.cull_map_points = rules.count("cull_points") > 0;
      lm.triangulate_points = rules.count("triangulate") > 0;
      lm.fuse_map_points = rules.count("fuse") > 0;
      lm.cull_keyframes = rules.count("cull_keyframes") > 0;
    }
  }
  settings.orbslam2_keyframes.min_frame_gap = opt.keyframe_min_gap;
  settings.keep_keyframe_images = opt.map;
  settings.loop_correction.enabled = opt.loop_correction != "none";
  settings.local_mapping.bundle_adjustment = opt.local_ba == "on";
  settings.local_mapping.covisible_keyframes = opt.local_ba_window;
  settings.local_mapping.fixed_keyframes = opt.local_ba_fixed;
  settings.loop_correction.bundle_adjustment = opt.loop_correction == "pgo+ba";
  if (opt.frames_given && opt.frames < 1) {
    throw UsageError("--frames must be at least 1, got " + std::to_string(opt.frames) + " (omit it for every frame)");
  }
  if (!opt.dataset.empty() && opt.preset != kDefaultPreset) {
    throw UsageError("--preset renders a sequence: it cannot be combined with --dataset");
  }
  if (opt.dataset.empty()) {
    const std::vector<std::string> names = cge::sim::preset_names();
    if (std::find(names.begin(), names.end(), opt.preset) == names.end()) {
      std::string known;
      for (const std::string& name : names) known += (known.empty() ? "" : ", ") + name;
      throw UsageError("--preset: unknown preset '" + opt.preset + "' (known: " + known + ")");
    }
  }
  if (opt.dataset.empty() && opt.frames_given) {
    cge_tool::require_at_most("--frames", opt.frames, cge::sim::kMaxPresetFrames, "rendered: 10 minutes at 30 Hz");
  }
  // Options that only one source reads: say so instead of ignoring them in silence.
  if (!opt.model.empty() && opt.segmentation != "yolo") {
    std::fprintf(stderr, "%s: warning: --model is used only with --segmentation yolo; ignored\n", kProgram);
  }
  if (!opt.masks.empty() && opt.segmentation != "precomputed") {
    std::fprintf(stderr, "%s: warning: --masks is used only with --segmentation precomputed; ignored\n", kProgram);
  }
  if (opt.out.empty()) throw UsageError("--out must name a folder");
  if (opt.segmentation.empty())
    opt.segmentation = settings.mode == cge::slam::DynamicMode::none ? "none" : "ground_truth";
  const std::set<std::string> kinds = {"none", "ground_truth", "yolo", "precomputed"};
  if (kinds.count(opt.segmentation) == 0) {
    throw UsageError("--segmentation: unknown source '" + opt.segmentation +
                     "' (expected none, ground_truth, yolo or precomputed)");
  }
  if (opt.segmentation == "yolo" && opt.model.empty()) throw UsageError("--segmentation yolo needs --model ONNX");
  if (opt.segmentation == "precomputed" && opt.masks.empty())
    throw UsageError("--segmentation precomputed needs --masks DIR");
  cge::slam::LoopCloserSettings loop_settings;
  try {
    loop_settings.scoring = cge::slam::loop_scoring_from_string(opt.loop_scoring);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--loop-scoring: ") + e.what());
  }
  // The acceptance gate of the chosen scoring (step 3): S_sum for cge and combined, BoW for bow_only.
  const bool bow_gate = loop_settings.scoring == cge::slam::LoopScoring::bow_only;
  double& min_score = bow_gate ? loop_settings.min_bow_score : loop_settings.min_cge_score;
  if (opt.loop_min_score_given) {
    if (!std::isfinite(opt.loop_min_score)) throw UsageError("--loop-min-score must be a finite number");
    min_score = opt.loop_min_score;
  }
  if (opt.cge_scaling == "raw") {
    loop_settings.exponent_scaling = cge::ScalingKind::raw;
  } else if (opt.cge_scaling == "normalised") {
    loop_settings.exponent_scaling = cge::ScalingKind::normalised_mean;
  } else if (!opt.cge_scaling.empty()) {
    throw UsageError("--cge-scaling: '" + opt.cge_scaling + "' is not raw or normalised");
  }
  if (opt.cge_ties == "mean") {
    loop_settings.degree_entropy.ties = cge::TieMode::mean;
  } else if (opt.cge_ties == "min") {
    loop_settings.degree_entropy.ties = cge::TieMode::min;
  } else if (opt.cge_ties != "all") {
    throw UsageError("--cge-ties: '" + opt.cge_ties + "' is not all, mean or min");
  }
  loop_settings.verified_members = opt.loop_verified_members;
  loop_settings.verify_all_consistent_groups = opt.loop_verify_groups == "consistent";
  loop_settings.min_group_total_ratio = opt.loop_min_group_ratio;
  try {
    loop_settings.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("loop settings: ") + e.what());
  }
  const bool loops_off = opt.vocabulary == kNoVocabulary;
  nlohmann::ordered_json loop_settings_json = {
      {"enabled", false},  // set below, once the vocabulary is known
      {"scoring", cge::slam::to_string(loop_settings.scoring)},
      {"min_score", min_score},
      {"min_score_setting", bow_gate ? "min_bow_score" : "min_cge_score"},
      {"cge_scaling", loop_settings.exponent_scaling == cge::ScalingKind::raw ? "raw" : "normalised"},
      {"cge_ties", opt.cge_ties},
      {"verified_members", loop_settings.verified_members},
      {"verify_groups", opt.loop_verify_groups},
      {"min_group_total_ratio", loop_settings.min_group_total_ratio}};
  std::unique_ptr<cge::bow::Vocabulary> vocabulary;
  std::string vocabulary_source = loops_off ? "none: loop closing off (--vocabulary none)" : opt.vocabulary;
  double vocabulary_training_s = 0;
  if (!opt.vocabulary.empty() && !loops_off && fs::is_directory(opt.vocabulary)) {
    throw UsageError("--vocabulary: '" + opt.vocabulary + "' is a directory, not a file");
  }
  if (!opt.vocabulary.empty() && !loops_off) {
    vocabulary = std::make_unique<cge::bow::Vocabulary>(cge::bow::Vocabulary::load_file(opt.vocabulary));
  }

  cge::PinholeIntrinsics<double> intrinsics;
  std::unique_ptr<cge::dataset::TumSequence> sequence;
  std::unique_ptr<FrameSource> source;
  std::unique_ptr<cge::InstanceSegmenter> segmenter;
  std::string source_name;
  if (opt.dataset.empty()) {
    const int frames = opt.frames > 0 ? opt.frames : kDefaultPresetFrames;
    if (opt.segmentation == "precomputed") throw UsageError("--segmentation precomputed needs --dataset");
    auto rendered =
        std::make_unique<RenderedSource>(opt.preset, frames, opt.seed, opt.segmentation == "ground_truth");
    const cge::sim::PinholeCamera& cam = rendered->camera();
    intrinsics = {cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px};
    settings.frame.depth_units_per_metre = cam.depth_units_per_metre;
    if (!opt.settings.empty()) apply_settings_file(opt.settings, intrinsics, settings);
    if (opt.segmentation == "yolo" && cge::slam::uses_masks(settings.mode)) {
      cge::dataset::SegmentationSourceSettings seg;
      seg.source = cge::dataset::SegmentationSource::yolo;
      seg.yolo_model_path = opt.model;
      apply_temporal_filter(opt.temporal_filter, opt.temporal_overlap, seg);
      segmenter = cge::dataset::make_segmenter(seg, "");
    }
    source = std::move(rendered);
    source_name = opt.preset + " rendered (" + std::to_string(frames) + " frames, seed " +
                  std::to_string(opt.seed) + ")";
  } else {
    if (!fs::is_directory(opt.dataset)) throw UsageError("--dataset: '" + opt.dataset + "' is not a folder");
    cge::dataset::TumSequenceSettings sequence_settings;
    sequence = std::make_unique<cge::dataset::TumSequence>(opt.dataset, sequence_settings);
    if (!opt.settings.empty()) {
      apply_settings_file(opt.settings, intrinsics, settings);
    } else if (sequence->camera_settings_file()) {
      apply_settings_file(*sequence->camera_settings_file(), intrinsics, settings);
    } else {
      throw UsageError("no settings: " + opt.dataset + " has no camera.yaml (give --settings YAML)");
    }
    const int frames = opt.frames > 0 ? std::min(opt.frames, sequence->frame_count()) : sequence->frame_count();
    // A synthetic sequence's exact masks give the leak count's ground truth; real data has none.
    std::unique_ptr<cge::PrecomputedMaskReader> moving_masks;
    const fs::path exact_masks =
        fs::path(opt.dataset) / cge::dataset::folder_name(cge::dataset::GroundTruthMasks::exact);
    if (fs::exists(exact_masks / "instances.csv")) {
      cge::PrecomputedMaskSettings mask_settings;
      mask_settings.require_every_frame = true;  // the simulator writes a PNG for every frame
      moving_masks = std::make_unique<cge::PrecomputedMaskReader>(exact_masks.string(), mask_settings);
    }
    // A cge_sim loop scene's loops.txt: the loop decisions are evaluated against it.
    const fs::path loops_file = fs::path(opt.dataset) / "loops.txt";
    source = std::make_unique<DatasetSource>(*sequence, frames, std::move(moving_masks),
                                             fs::is_regular_file(loops_file) ? loops_file : fs::path());
    source_name = opt.dataset;
    cge::dataset::SegmentationSourceSettings seg;
    seg.source = cge::dataset::parse_segmentation_source(opt.segmentation);
    seg.yolo_model_path = opt.model;
    seg.mask_folder = opt.masks;
    apply_temporal_filter(opt.temporal_filter, opt.temporal_overlap, seg);
    if (cge::slam::uses_masks(settings.mode)) segmenter = cge::dataset::make_segmenter(seg, opt.dataset);
  }
  // After the settings file, which sets the depth weight of tracking and BA (cge.DepthSigmaPerMetre or 1 / bf).
  if (opt.tracking_depth_sigma_given) settings.tracker.refinement_depth_sigma_per_m = opt.tracking_depth_sigma;
  try {
    settings.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("settings: ") + e.what());
  }
  // The images against the settings, before any work: the file's Camera.width and .height (when
  // it gives them) and the ORB pyramid, whose coarsest level must keep a pixel.
  const std::optional<fs::path> settings_path =
      !opt.settings.empty() ? std::optional<fs::path>(opt.settings)
                            : (sequence != nullptr ? sequence->camera_settings_file() : std::nullopt);
  if (source->frame_count() > 0) check_first_image(source->frame(0).bgr.size(), settings_path, settings.frame.orb);

  OutputFolder out(opt.out, opt.force);
  // Loop closing's vocabulary, when none was given: after every check, as it is the first work.
  if (opt.vocabulary.empty()) {
    if (opt.dataset.empty()) {
      const auto training_start = std::chrono::steady_clock::now();
      const std::uint64_t seed = opt.seed + 1;  // another scene: other textures, paths and phases
      const std::string trained_on = vocabulary_preset(opt.preset);
      vocabulary = std::make_unique<cge::bow::Vocabulary>(train_default_vocabulary(trained_on, seed));
      vocabulary_training_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - training_start).count();
      vocabulary_source = trained_on + " rendered, seed " + std::to_string(seed) + ", " +
                          std::to_string(kVocabularyImages) + " images over its " +
                          std::to_string(kVocabularyPresetFrames) + " frames (trained here; not the evaluated frames)";
    } else {
      vocabulary_source = "none given: loop closing off (train one with cge_vocab, pass --vocabulary FILE)";
    }
  }
  const bool loop_closing = vocabulary != nullptr;
  loop_settings_json["enabled"] = loop_closing;
  loop_settings_json["vocabulary"] = vocabulary_source;
  if (vocabulary != nullptr) loop_settings_json["vocabulary_words"] = vocabulary->word_count();
  cge::slam::System system(settings, intrinsics, std::move(segmenter));
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed_s = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const bool progress = ::isatty(::fileno(stderr)) != 0;
  const int n = source->frame_count();
  const bool own_instances = source->provides_instances() && cge::slam::uses_masks(settings.mode);
  for (int i = 0; i < n; ++i) {
    const cge::slam::FrameInput input = source->frame(i);
    if (i == 0 && vocabulary != nullptr) {
      system.set_loop_closer(std::make_unique<cge::slam::LoopCloser>(std::move(*vocabulary), intrinsics, input.bgr.cols,
                                                                     input.bgr.rows, loop_settings));
    }
    if (own_instances) {
      const auto seg_start = std::chrono::steady_clock::now();
      const std::vector<cge::SegmentedInstance> instances = source->instances(i);
      const double seg_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - seg_start).count();
      system.process(input, instances, seg_ms);
    } else {
      system.process(input);
    }
    if (progress) progress_bar.draw(i + 1, n, elapsed_s());
  }
  system.finish();
  if (n > 0 && std::none_of(system.frames().begin(), system.frames().end(),
                            [](const cge::slam::FrameRecord& r) { return r.has_pose(); })) {
    progress_bar.end_line();
    std::fprintf(stderr,
                 "%s: warning: every frame was lost (%d of %d): the trajectory is empty (wrong settings, "
                 "depth scale or images?)\n",
                 kProgram, n, n);
  }

  out.write("trajectory.txt", [&](std::ostream& f) { cge::slam::write_trajectory(f, system); });
  out.write("keyframes.txt", [&](std::ostream& f) { cge::slam::write_keyframes(f, system.map()); });
  std::ostringstream loops_csv;
  cge::slam::write_loops_csv(loops_csv, system.loops());
  out.write("loops.csv", [&](std::ostream& f) { f << loops_csv.str(); });
  // The loop decisions against the ground-truth loops, read back from loops.csv as cge_eval loops
  // reads the file (same stamps, same numbers).
  std::set<std::string> queried;
  for (const cge::slam::LoopRecord& l : system.loops()) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", l.query_timestamp_s);
    queried.insert(text);
  }
  const std::optional<std::vector<cge::metrics::GroundTruthLoop>> gt_loops = source->ground_truth_loops(queried);
  std::optional<cge::metrics::LoopEvaluation> loop_evaluation;
  if (gt_loops && loop_closing) {
    std::istringstream rows(loops_csv.str());
    loop_evaluation = cge::metrics::evaluate_loops(*gt_loops, cge::metrics::read_loop_queries(rows, "loops.csv"));
  }
  out.write("frames.csv", [&](std::ostream& f) { cge::slam::write_frames_csv(f, system.frames()); });
  out.write("timings.csv", [&](std::ostream& f) { cge::slam::write_timings_csv(f, system.frames()); });
  const auto gt = source->ground_truth();
  nlohmann::ordered_json summary = make_summary(system, opt, source_name, gt, loop_settings_json);
  if (vocabulary_training_s > 0) summary["vocabulary_training_s"] = vocabulary_training_s;
  if (loop_evaluation) summary["loop_evaluation"] = loop_evaluation_json(*loop_evaluation);
  if (opt.map) {
    // Semantic maps from the final (optimised) keyframes: dense cloud, octree, top view, scores.
    cge::mapping::SemanticMapBuilder map(intrinsics, {}, settings.frame.distortion);
    map.rebuild(system.map().keyframes());
    map.write_ply(out.stage("map.ply"));
    map.write_octree(out.stage("map.ot"), out.stage("map.bt"));
    cge::mapping::write_png(out.stage("map_top.png"), cge::mapping::render_top_view(map.occupied_voxels()));
    const cge::mapping::MapFigures f = map.scores();
    summary["map"] = {{"keyframes", f.keyframes},
                      {"cloud_points", f.cloud_points},
                      {"occupied_voxels", f.occupied_voxels},
                      {"integrity", f.integrity},
                      {"fluctuation", f.fluctuation},
                      {"entities", f.entities},
                      {"octree_memory_bytes", f.octree_memory_bytes}};
  }
  out.write("summary.json", [&](std::ostream& f) { f << summary.dump(2) << '\n'; });
  if (opt.dataset.empty() && !gt.empty()) {
    out.write("groundtruth.txt", [&](std::ostream& f) {
      f << "# ground truth trajectory of the rendered sequence: timestamp tx ty tz qx qy qz qw\n";
      for (const auto& p : gt) f << cge::slam::tum_pose_line(p.first, p.second) << '\n';
    });
  }
  if (opt.dataset.empty() && gt_loops) {
    out.write("loops.txt", [&](std::ostream& f) { write_ground_truth_loops(f, *gt_loops); });
  }
  out.commit();

  std::printf("%s: %d frames, %d tracked, %d lost, %d keyframes; wrote %s in %.1f s\n", kProgram, n,
              summary["tracked_frames"].get<int>(), summary["lost_frames"].get<int>(), system.map().active_keyframe_count(),
              opt.out.c_str(), elapsed_s());
  // The evaluation as `name value` lines (the figures of summary.json a reader looks for first).
  const auto print_line = [](const char* name, double value) { std::printf("%s %.6g\n", name, value); };
  print_line("keyframes", system.map().active_keyframe_count());
  std::printf("vocabulary %s\n", vocabulary_source.c_str());
  if (vocabulary_training_s > 0) print_line("vocabulary_training_s", vocabulary_training_s);
  print_line("loop_queries", static_cast<double>(system.loops().size()));
  print_line("loops_accepted", summary["loops"]["accepted"].get<double>());
  print_line("loop_corrections", system.loop_corrections());
  if (loop_evaluation) {
    print_loop_evaluation(system.loops(), *gt_loops, gt, *loop_evaluation);
  } else if (loop_closing && opt.dataset.empty()) {
    std::printf("loop_evaluation skipped: more than %d rendered frames (ground-truth loops grow with the square of "
                "the length)\n",
                kMaxLoopTruthFrames);
  }
  if (!summary["dynamic_leak"]["rate"].is_null()) {
    print_line("dynamic_leak_rate", summary["dynamic_leak"]["rate"].get<double>());
  }
  if (summary.contains("ate") && summary["ate"].contains("rmse_m")) {
    print_line("ate_rmse_m", summary["ate"]["rmse_m"].get<double>());
  }
  if (summary.contains("rpe") && summary["rpe"].contains("translation_rmse_m")) {
    print_line("rpe_translation_rmse_m", summary["rpe"]["translation_rmse_m"].get<double>());
    print_line("rpe_rotation_rmse_deg", summary["rpe"]["rotation_rmse_deg"].get<double>());
  }
  print_line("tracking_median_ms", summary["stages"]["tracking"]["median_ms"].get<double>());
  print_line("total_median_ms", summary["stages"]["total"]["median_ms"].get<double>());
  if (!cge_tool::standard_output_written(kProgram)) return kExitFailure;
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
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
                     short_number(cge::slam::LoopCloserSettings{}.min_cge_score) +
                     ") or BoW score (bow_only; default " +
                     short_number(cge::slam::LoopCloserSettings{}.min_bow_score) + ")")
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
                 "Ceres iterations per round of the local BA (its time budget per keyframe; 2 rounds)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--local-ba-rounds-per-frame", opt.local_ba_rounds_per_frame,
                 "local BA rounds solved per frame: 1 solves the first in the keyframe's frame and the second "
                 "in the next frame before it is tracked, 2 both in the keyframe's frame (same outputs, other times)")
      ->check(CLI::Range(1, 2));
  app.add_option("--orb-spread", opt.orb_spread,
                 "ORB candidates per kept keypoint, spread over the image cell by cell (1: cv::ORB's own choice)")
      ->check(CLI::Range(1, 8));
  app.add_option("--keyframe-interval", opt.keyframe_interval,
                 "mode YMK: frames per interval of the patch keyframe selector (k; its best candidate is inserted "
                 "at the end of each interval)")
      ->check(cge_tool::above_zero())
      ->capture_default_str();
  app.add_option("--out", opt.out, "output folder; must not exist or be empty, unless --force")->required();
  app.add_flag("--map", opt.map,
               "also build the semantic maps from the keyframes: map.ply (dense cloud), map.ot/map.bt (octree), "
               "map_top.png; their figures go to summary.json (docs/MAPS.md)");
  app.add_flag("--force", opt.force, "write into a non-empty folder: replace cge_slam's own files, delete nothing");

  if (const int exit_code = cge_tool::parse_command_line(app, argc, argv, kProgram); exit_code >= 0) return exit_code;
  // OpenCV's own warnings would come before the tool's message; its errors arrive as exceptions.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
  return cge_tool::run_reporting_errors(kProgram, &progress_bar, [&] { return run(opt); });
}
