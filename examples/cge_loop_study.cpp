// cge_loop_study: the study of the entropy measures on a synthetic loop sequence.
//
//   cge_loop_study --dataset DIR --out DIR [--force] [--step 3] [--min-gap-frames 30] [--alpha 0.5]
//                  [--collapse-tolerance-bits 1] [--mode YMK] [--seed 0] [--ties all|mean|min]
//
// For every step-th frame of DIR (a cge_sim folder: rgb/, depth/, masks/ with instances.csv,
// camera.yaml, loops.txt) it makes what the loop closer sees of a keyframe: ORB features and
// static labels from cge::slam::FrameMaker (the run's --mode and --seed, as cge_slam), with the
// exact ground-truth masks of masks/ and their `moving` flag as the dynamic instances; the graph
// the LoopCloser builds (own_mask_graph) and the degree-degree entropy with raw and with normalised
// exponent scaling at --alpha, tied shortest paths counted by --ties (TieMode; all, the default, is the
// LoopCloser's; min is closest to the paper's rule), the LoopCloser's other settings at their
// defaults. Writes into --out:
//   frames.csv  frame,timestamp,vertices,edges,entropy_raw_bits,entropy_normalised_bits,
//               log2_vertices,collapsed_raw,collapsed_normalised
//   pairs.csv   query,match,revisit,s_sum_raw,s_sum_normalised (every pair of studied frames at
//               least --min-gap-frames apart; revisit 1 when (query, match) is in loops.txt)
//   summary.json the settings and the figures below
// and prints `name value` lines: frames, pairs, revisit_pairs, collapse_fraction_raw,
// collapse_fraction_normalised, auc_raw, auc_normalised, average_precision_raw,
// average_precision_normalised (cge/metrics/binary_classifier.hpp; nan when the pairs lack a class).
//
// Collapse: with alpha = 0.5 and raw exponents of 1e3..1e5 the functional puts its mass on one or
// two nodes, H ~ 0 and the information index I = log2|V| - H ~ log2|V| (docs/METHOD.md section 4).
// A frame is `collapsed` when |I - log2|V|| = H <= T bits (lambda = 1, the default): H <= 1 bit
// means the distribution's perplexity 2^H is at most 2, i.e. effectively one or two nodes.
// --out is filled all or nothing, as cge_slam's (cge/run/output_folder.hpp): a failed run leaves it
// as it was. Same inputs, same bytes. Exit codes: 0 success, 1 failure while writing, 2 bad usage or input.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "cge/dataset/tum_sequence.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/metrics/binary_classifier.hpp"
#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/run/output_folder.hpp"
#include "cge/run/run_settings.hpp"
#include "cge/segmentation/precomputed_mask_reader.hpp"
#include "cge/slam/frame.hpp"
#include "cge/slam/keyframe.hpp"
#include "cge/slam/loop_closer.hpp"

#include "tool_support.hpp"

#ifndef CGE_VERSION_STRING
#define CGE_VERSION_STRING "unknown"
#endif

namespace {

namespace fs = std::filesystem;

using cge_tool::kExitFailure;
using cge_tool::kExitOk;
constexpr const char* kProgram = "cge_loop_study";
constexpr const char* kFramesFile = "frames.csv";
constexpr const char* kPairsFile = "pairs.csv";
constexpr const char* kSummaryFile = "summary.json";

cge_tool::ProgressBar progress_bar{kProgram};  // drawn only on a terminal

using cge_tool::UsageError;

struct Options {
  std::string dataset;
  std::string out;
  bool force = false;
  int step = 3;                        ///< study every step-th frame
  int min_gap_frames = 30;             ///< pairs at least this many frames apart
  double alpha = 0.5;                  ///< base of the functional alpha^E (DegreeDegreeSettings' default)
  double collapse_tolerance_bits = 1;  ///< collapsed when H <= this (perplexity <= 2 at 1 bit)
  std::string mode = "YMK";            ///< dynamic handling of the labels, as cge_slam
  std::uint64_t seed = 0;              ///< seed of the MAD samples, as cge_slam
  std::string ties = "all";            ///< TieMode of the degree sums: all, mean or min
};

/// One studied frame: its graph's size and entropies under both scalings (computed once).
struct StudiedFrame {
  int index = 0;
  double timestamp_s = 0;
  int vertices = 0;
  int edges = 0;
  double entropy_raw_bits = std::numeric_limits<double>::quiet_NaN();
  double entropy_normalised_bits = std::numeric_limits<double>::quiet_NaN();
  double log2_vertices = std::numeric_limits<double>::quiet_NaN();
  bool collapsed_raw = false;
  bool collapsed_normalised = false;
  cge::GraphEntropies<double> raw;
  cge::GraphEntropies<double> normalised;
  std::vector<cge::SemanticInstance<double>> instances;
};

struct StudiedPair {
  int query = 0;
  int match = 0;
  bool revisit = false;
  double s_sum_raw = 0;
  double s_sum_normalised = 0;
};

/// Doubles in the CSV files: 17 significant digits read back exactly (ties stay ties).
std::string exact(double v) {
  if (std::isnan(v)) return "nan";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

void check_options(const Options& opt) {
  if (opt.dataset.empty()) throw UsageError("--dataset must name a folder");
  if (opt.out.empty()) throw UsageError("--out must name a folder");
  if (opt.step < 1) throw UsageError("--step must be at least 1, got " + std::to_string(opt.step));
  if (opt.min_gap_frames < 1) {
    throw UsageError("--min-gap-frames must be at least 1, got " + std::to_string(opt.min_gap_frames));
  }
  if (!(std::isfinite(opt.alpha) && opt.alpha > 0)) throw UsageError("--alpha must be a finite positive number");
  if (!(std::isfinite(opt.collapse_tolerance_bits) && opt.collapse_tolerance_bits >= 0)) {
    throw UsageError("--collapse-tolerance-bits must be a finite number >= 0");
  }
}

double area_or_nan(const std::vector<cge::metrics::LabelledScore>& examples, bool average_precision) {
  bool pos = false, neg = false;
  for (const auto& e : examples) (e.positive ? pos : neg) = true;
  if (!pos || !neg) return std::numeric_limits<double>::quiet_NaN();
  return average_precision ? cge::metrics::average_precision(examples) : cge::metrics::roc_auc(examples);
}

int run(const Options& opt) {
  check_options(opt);
  cge::slam::SystemSettings settings;
  settings.mode = cge::run::parse_mode_option(opt.mode);
  settings.seed = opt.seed;

  // ---- the dataset ----------------------------------------------------------------------------
  const fs::path dataset(opt.dataset);
  if (!fs::is_directory(dataset)) throw UsageError("--dataset: '" + opt.dataset + "' is not a folder");
  const cge::dataset::TumSequence sequence(dataset);
  if (!sequence.camera_settings_file()) throw UsageError("'" + opt.dataset + "' has no camera.yaml");
  cge::PinholeIntrinsics<double> intrinsics;
  cge::run::apply_settings_file(*sequence.camera_settings_file(), intrinsics, settings);
  try {
    settings.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("settings: ") + e.what());
  }
  const fs::path masks = dataset / "masks";
  if (!fs::is_regular_file(masks / "instances.csv")) {
    throw UsageError("'" + masks.string() + "' has no instances.csv (the ground-truth masks of a cge_sim folder)");
  }
  cge::PrecomputedMaskSettings mask_settings;
  mask_settings.require_every_frame = true;
  const cge::PrecomputedMaskReader mask_reader(masks.string(), mask_settings);
  const fs::path loops_path = dataset / "loops.txt";
  if (!fs::is_regular_file(loops_path)) throw UsageError("'" + opt.dataset + "' has no loops.txt");
  const std::vector<cge::metrics::GroundTruthLoop> loops =
      cge::metrics::read_ground_truth_loops_file(loops_path.string());
  const int n = sequence.frame_count();
  std::set<std::pair<long long, long long>> revisits;  // (query, match) frame indices
  for (const cge::metrics::GroundTruthLoop& l : loops) {
    if (l.query_index >= n) {
      throw UsageError(loops_path.string() + ":" + std::to_string(l.line) + ": query_index " +
                       std::to_string(l.query_index) + " is beyond the sequence's " + std::to_string(n) + " frames");
    }
    revisits.emplace(l.query_index, l.match_index);
  }

  // ---- per frame: the LoopCloser's graph and both entropies (each frame once) ------------------
  cge::slam::LoopCloserSettings raw_settings;
  raw_settings.degree_entropy.alpha = opt.alpha;
  raw_settings.degree_entropy.ties = cge::run::parse_tie_mode("--ties", opt.ties);
  raw_settings.exponent_scaling = cge::ScalingKind::raw;
  cge::slam::LoopCloserSettings normalised_settings = raw_settings;
  normalised_settings.exponent_scaling = cge::ScalingKind::normalised_mean;
  const cge::CGESimilarity<double> raw_similarity = cge::slam::loop_similarity(raw_settings);
  const cge::CGESimilarity<double> normalised_similarity = cge::slam::loop_similarity(normalised_settings);
  const double lambda = raw_settings.degree_entropy.lambda;

  cge::run::OutputFolder out(opt.out, opt.force, kProgram, {kFramesFile, kPairsFile, kSummaryFile});
  cge::slam::FrameMaker maker(settings, intrinsics);
  const auto start = std::chrono::steady_clock::now();
  const bool progress = ::isatty(::fileno(stderr)) != 0;
  std::vector<StudiedFrame> frames;
  for (int i = 0; i < n; i += opt.step) {
    const cge::dataset::TumFrame tf = sequence.load(i);
    cge::slam::Frame frame = maker.extract(i, tf.rgb_timestamp_s, tf.bgr, tf.depth);
    std::vector<cge::SegmentedInstance> instances = mask_reader.read(tf.rgb_stem, tf.bgr.size());
    for (cge::SegmentedInstance& inst : instances) inst.dynamic = inst.moving.value_or(inst.dynamic);
    maker.label(frame, instances);

    cge::slam::Keyframe kf;  // the fields the LoopCloser's graph reads
    kf.keypoints = frame.keypoints;
    kf.labels = frame.labels;
    kf.instances = frame.instances;
    kf.dynamic_mask = frame.dynamic_mask;
    cge::ImageRegion<double> image;
    image.width_px = frame.image_size.width;
    image.height_px = frame.image_size.height;
    const cge::Graph<double> g = cge::slam::own_mask_graph(kf, image, raw_similarity.graph_builder);

    StudiedFrame s;
    s.index = i;
    s.timestamp_s = tf.rgb_timestamp_s;
    s.vertices = g.num_nodes();
    s.edges = g.num_edges();
    s.instances = frame.instances;
    if (s.vertices > 0) {
      // One Delta table for both scalings: the O(|V||E|) part of information_index(g), done once.
      const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, raw_similarity.degree_entropy.settings.ties);
      const auto raw = raw_similarity.degree_entropy.from_table(table);
      const auto normalised = normalised_similarity.degree_entropy.from_table(table);
      const double edge_bits = raw_similarity.edge_entropy.compute(g);
      s.raw = {raw.information_index, edge_bits, s.vertices, s.edges};
      s.normalised = {normalised.information_index, edge_bits, s.vertices, s.edges};
      s.entropy_raw_bits = raw.entropy_bits;
      s.entropy_normalised_bits = normalised.entropy_bits;
      s.log2_vertices = std::log2(static_cast<double>(s.vertices));
      // |I - lambda log2|V|| = lambda H.
      s.collapsed_raw = std::fabs(raw.information_index - lambda * s.log2_vertices) <= opt.collapse_tolerance_bits;
      s.collapsed_normalised =
          std::fabs(normalised.information_index - lambda * s.log2_vertices) <= opt.collapse_tolerance_bits;
    }
    frames.push_back(std::move(s));
    if (progress) {
      progress_bar.draw(i / opt.step + 1, (n + opt.step - 1) / opt.step,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  }

  // ---- pairs: S_sum from the cached entropies, as LoopCloser::cge_score in own_mask mode ---------
  std::vector<StudiedPair> pairs;
  for (const StudiedFrame& q : frames) {
    for (const StudiedFrame& m : frames) {
      if (q.index - m.index < opt.min_gap_frames) break;  // frames ascend: the rest are closer
      StudiedPair p;
      p.query = q.index;
      p.match = m.index;
      p.revisit = revisits.count({q.index, m.index}) > 0;
      if (q.vertices > 0 && m.vertices > 0) {  // no node: no evidence of a loop, S_sum 0
        const cge::SemanticComparison sem = cge::compare_semantics(q.instances, m.instances);
        p.s_sum_raw = raw_similarity.combine(q.raw, m.raw, sem).similarity;
        p.s_sum_normalised = normalised_similarity.combine(q.normalised, m.normalised, sem).similarity;
      }
      pairs.push_back(p);
    }
  }

  // ---- figures ---------------------------------------------------------------------------------
  int with_graph = 0, collapsed_raw = 0, collapsed_normalised = 0;
  for (const StudiedFrame& f : frames) {
    with_graph += f.vertices > 0;
    collapsed_raw += f.collapsed_raw;
    collapsed_normalised += f.collapsed_normalised;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double fraction_raw = with_graph > 0 ? static_cast<double>(collapsed_raw) / with_graph : nan;
  const double fraction_normalised = with_graph > 0 ? static_cast<double>(collapsed_normalised) / with_graph : nan;
  std::vector<cge::metrics::LabelledScore> by_raw, by_normalised;
  int revisit_pairs = 0;
  for (const StudiedPair& p : pairs) {
    by_raw.push_back({p.s_sum_raw, p.revisit});
    by_normalised.push_back({p.s_sum_normalised, p.revisit});
    revisit_pairs += p.revisit;
  }
  const double auc_raw = area_or_nan(by_raw, false);
  const double auc_normalised = area_or_nan(by_normalised, false);
  const double ap_raw = area_or_nan(by_raw, true);
  const double ap_normalised = area_or_nan(by_normalised, true);
  if (std::isnan(auc_raw)) {
    std::fprintf(stderr,
                 "%s: warning: the pairs are all revisits or all non-revisits (%d of %zu): AUC and AP are nan\n",
                 kProgram, revisit_pairs, pairs.size());
  }

  // ---- output ----------------------------------------------------------------------------------
  out.write(kFramesFile, [&](std::ostream& f) {
    f << "frame,timestamp,vertices,edges,entropy_raw_bits,entropy_normalised_bits,log2_vertices,collapsed_raw,"
         "collapsed_normalised\n";
    char stamp[40];
    for (const StudiedFrame& s : frames) {
      std::snprintf(stamp, sizeof stamp, "%.6f", s.timestamp_s);
      f << s.index << ',' << stamp << ',' << s.vertices << ',' << s.edges << ',' << exact(s.entropy_raw_bits) << ','
        << exact(s.entropy_normalised_bits) << ',' << exact(s.log2_vertices) << ',' << int(s.collapsed_raw) << ','
        << int(s.collapsed_normalised) << '\n';
    }
  });
  out.write(kPairsFile, [&](std::ostream& f) {
    f << "query,match,revisit,s_sum_raw,s_sum_normalised\n";
    for (const StudiedPair& p : pairs) {
      f << p.query << ',' << p.match << ',' << int(p.revisit) << ',' << exact(p.s_sum_raw) << ','
        << exact(p.s_sum_normalised) << '\n';
    }
  });
  const auto number = [](double v) { return std::isnan(v) ? nlohmann::ordered_json() : nlohmann::ordered_json(v); };
  nlohmann::ordered_json summary;
  summary["tool"] = kProgram;
  summary["settings"] = {{"step", opt.step},    {"min_gap_frames", opt.min_gap_frames},
                         {"alpha", opt.alpha},  {"collapse_tolerance_bits", opt.collapse_tolerance_bits},
                         {"mode", opt.mode},    {"seed", opt.seed},
                         {"ties", opt.ties},    {"sequence_frames", n}};
  summary["frames"] = frames.size();
  summary["frames_with_graph"] = with_graph;
  summary["pairs"] = pairs.size();
  summary["revisit_pairs"] = revisit_pairs;
  summary["collapse_fraction_raw"] = number(fraction_raw);
  summary["collapse_fraction_normalised"] = number(fraction_normalised);
  summary["auc_raw"] = number(auc_raw);
  summary["auc_normalised"] = number(auc_normalised);
  summary["average_precision_raw"] = number(ap_raw);
  summary["average_precision_normalised"] = number(ap_normalised);
  out.write(kSummaryFile, [&](std::ostream& f) { f << summary.dump(2) << '\n'; });
  out.commit();

  const auto print_line = [](const char* name, double value) { std::printf("%s %.12g\n", name, value); };
  print_line("frames", static_cast<double>(frames.size()));
  print_line("pairs", static_cast<double>(pairs.size()));
  print_line("revisit_pairs", revisit_pairs);
  print_line("collapse_fraction_raw", fraction_raw);
  print_line("collapse_fraction_normalised", fraction_normalised);
  print_line("auc_raw", auc_raw);
  print_line("auc_normalised", auc_normalised);
  print_line("average_precision_raw", ap_raw);
  print_line("average_precision_normalised", ap_normalised);
  if (!cge_tool::standard_output_written(kProgram)) return kExitFailure;
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"Studies the degree-degree entropy on a synthetic loop sequence (cge " CGE_VERSION_STRING
               "): how often the raw\nindex collapses to log2|V|, and how well S_sum with raw and with "
               "normalised exponents separates\nrevisits from other frame pairs. Writes frames.csv, pairs.csv "
               "and summary.json into --out.",
               kProgram};
  app.set_version_flag("--version", std::string(kProgram) + " " + CGE_VERSION_STRING);
  app.add_option("--dataset", opt.dataset, "cge_sim folder (rgb/, depth/, masks/, camera.yaml, loops.txt)")->required();
  app.add_option("--out", opt.out, "output folder; must not exist or be empty, unless --force")->required();
  app.add_flag("--force", opt.force, "write into a non-empty folder: replace this tool's files, delete nothing");
  app.add_option("--step", opt.step, "study every step-th frame")->capture_default_str();
  app.add_option("--min-gap-frames", opt.min_gap_frames, "pairs of studied frames at least this many frames apart")
      ->capture_default_str();
  app.add_option("--alpha", opt.alpha, "base of the functional alpha^E, > 0")->capture_default_str();
  app.add_option("--collapse-tolerance-bits", opt.collapse_tolerance_bits,
                 "a frame is collapsed when |I - log2|V|| = H <= this many bits (1: perplexity <= 2)")
      ->capture_default_str();
  app.add_option("--mode", opt.mode, "dynamic labelling as cge_slam: none, Y, YM, YMK")->capture_default_str();
  app.add_option("--seed", opt.seed, "seed of the MAD samples (as cge_slam --seed)")
      ->check(cge_tool::seed_check())
      ->capture_default_str();
  app.add_option("--ties", opt.ties,
                 "tied shortest paths in the degree sums: all (every path, the LoopCloser's default), mean (one "
                 "averaged path per node) or min (the path with the smallest sum, closest to the paper's rule)")
      ->check(CLI::IsMember({"all", "mean", "min"}))
      ->capture_default_str();
  if (const int exit_code = cge_tool::parse_command_line(app, argc, argv, kProgram); exit_code >= 0) return exit_code;
  return cge_tool::run_reporting_errors(kProgram, &progress_bar, [&] { return run(opt); });
}
