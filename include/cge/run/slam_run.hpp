#pragma once
// SlamRun: one run of the reference pipeline as cge_slam makes it (docs/CLI.md, docs/SLAM.md): the
// frames of a TUM folder or of a synthetic preset rendered in memory, the settings from the
// options and the ORB-SLAM2 settings file, loop closing with the given vocabulary (or, for a
// rendered run, one trained on another preset: cge/run/default_vocabulary.hpp), then the output
// files and the evaluation against the ground truth the source knows.
//
// Steps, in this order: the constructor checks every option and opens every input (bad input:
// std::invalid_argument naming it, before any work); prepare_vocabulary() trains the default
// vocabulary when needed (the first work); process() tracks every frame; write_outputs() writes
//   trajectory.txt, keyframes.txt  every tracked frame and the keyframes, TUM format
//   loops.csv                      the loop closer's decisions (header only when loop closing is off)
//   frames.csv, timings.csv        per frame: tracking state, features, labels, leak; stage times
//   groundtruth.txt, loops.txt     (rendered) the poses and the ground-truth loops of the queried keyframes
//   map.ply, map.ot, map.bt, map_top.png  (options.map) the semantic maps of the keyframes
// into an OutputFolder and computes the summary; summary.json is the caller's (its spelling is the
// tool's). Same inputs and seed: the same bytes in every file but timings.csv.
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cge/bow/vocabulary.hpp"
#include "cge/mapping/semantic_map_builder.hpp"
#include "cge/metrics/loop_precision_recall.hpp"
#include "cge/run/frame_source.hpp"
#include "cge/run/output_folder.hpp"
#include "cge/run/run_summary.hpp"
#include "cge/run/slam_run_options.hpp"
#include "cge/segmentation/instance_segmenter.hpp"
#include "cge/slam/system.hpp"

namespace cge {
namespace run {

class SlamRun {
 public:
  using Message = std::function<void(const std::string&)>;

  /// `warn` receives the options that are given but not used.
  SlamRun(SlamRunOptions options, const Message& warn);
  ~SlamRun();
  SlamRun(const SlamRun&) = delete;
  SlamRun& operator=(const SlamRun&) = delete;

  /// Every file a run may write into its output folder.
  static const std::vector<std::string>& output_names();

  /// Trains the default vocabulary of a rendered run given none (once).
  void prepare_vocabulary();
  /// Tracks every frame in order (after prepare_vocabulary()); `progress(done, total)` after each.
  void process(const std::function<void(int, int)>& progress);
  /// Writes the run's files into `out` (not committed) and computes the summary and loop evaluation.
  void write_outputs(OutputFolder& out);

  /// The options as used (the default segmentation filled in).
  const SlamRunOptions& options() const { return options_; }
  bool rendered() const { return options_.dataset.empty(); }
  int frame_count() const { return source_->frame_count(); }
  /// "<dataset>" or "<preset> rendered (<n> frames, seed <s>)".
  const std::string& source_name() const { return source_name_; }
  const slam::LoopCloserSettings& loop_settings() const { return loop_settings_; }
  bool loop_closing() const { return loop_closing_; }
  const std::string& vocabulary_source() const { return vocabulary_source_; }
  std::optional<std::size_t> vocabulary_words() const { return vocabulary_words_; }
  double vocabulary_training_s() const { return vocabulary_training_s_; }  ///< 0 when none was trained
  /// After process().
  const slam::System& system() const { return *system_; }
  bool every_frame_lost() const;
  /// After write_outputs().
  const RunSummary& summary() const { return summary_; }
  const GroundTruthPoses& ground_truth() const { return ground_truth_; }
  const std::optional<std::vector<metrics::GroundTruthLoop>>& ground_truth_loops() const { return ground_truth_loops_; }
  const std::optional<metrics::LoopEvaluation>& loop_evaluation() const { return loop_evaluation_; }
  const std::optional<mapping::MapFigures>& map_figures() const { return map_figures_; }

 private:
  void open_rendered();
  void open_dataset();

  SlamRunOptions options_;
  slam::SystemSettings settings_;
  slam::LoopCloserSettings loop_settings_;
  PinholeIntrinsics<double> intrinsics_;
  std::optional<std::filesystem::path> settings_file_;
  std::unique_ptr<FrameSource> source_;
  std::unique_ptr<InstanceSegmenter> segmenter_;
  std::string source_name_;
  std::unique_ptr<bow::Vocabulary> vocabulary_;
  bool vocabulary_prepared_ = false;
  bool loop_closing_ = false;
  std::string vocabulary_source_;
  std::optional<std::size_t> vocabulary_words_;
  double vocabulary_training_s_ = 0;
  std::unique_ptr<slam::System> system_;
  RunSummary summary_;
  GroundTruthPoses ground_truth_;
  std::optional<std::vector<metrics::GroundTruthLoop>> ground_truth_loops_;
  std::optional<metrics::LoopEvaluation> loop_evaluation_;
  std::optional<mapping::MapFigures> map_figures_;
};

}  // namespace run
}  // namespace cge
