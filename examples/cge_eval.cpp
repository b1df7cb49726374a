// cge_eval: trajectory and loop-closure metrics against ground truth (docs/EVALUATION.md).
//   cge_eval ate GT EST [--max-difference 0.02] [--offset 0]       absolute trajectory error
//                [--aligned-out CSV [--force]]                     and the aligned pairs, for plots
//   cge_eval rpe GT EST [--delta 1] [--delta-unit s|frames]        relative pose error
//   cge_eval loops GT_LOOPS LOOPS_CSV [--tolerance 0.001]          loop precision and recall
//                [--score cge_score|bow_score] [--min-score X]     detections need score >= X
//                [--curve CSV [--force]]                           P-R over every threshold
//   cge_eval map MAP.ot [--sequence DIR [--trajectory TXT]] [--image PNG]  semantic octree scores (docs/MAPS.md)
// GT and EST are TUM trajectories; ATE and RPE follow the TUM RGB-D benchmark tools.
//
// Output: one "name value" line per quantity on standard output (15 significant digits; "nan" for
// an undefined ratio), or with --json one JSON object (null for undefined). Diagnostics go to
// standard error. Exit codes: 0 success; 1 standard output could not be written; 2 bad usage or
// bad input (the message names the file and line). Files named by --aligned-out and --curve are
// never overwritten without --force, --image never; each is written beside its name and renamed
// into place when complete (a failed run leaves the old file); missing folders on the way are
// created (docs/CLI.md). One that cannot be written is exit code 1.
// A ground-truth or estimated trajectory repeating a timestamp keeps the later line, as the TUM
// tools do, with a warning naming the file and line; --duplicate-stamps error refuses such files.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "cge/metrics/ate.hpp"
#include "cge/metrics/ate_aligned_pairs.hpp"
#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/metrics/loop_precision_recall.hpp"
#include "cge/metrics/loop_queries_io.hpp"
#include "cge/metrics/loop_threshold_curve.hpp"
#include "cge/metrics/rpe.hpp"
#include "cge/metrics/tum_trajectory_io.hpp"

#ifdef CGE_EVAL_HAS_MAPS
#include "cge/mapping/ghost_voxels.hpp"
#include "cge/mapping/map_image.hpp"
#include "cge/voxels/semantic_integrity.hpp"
#include "cge/octomap/semantic_octree.hpp"
#endif

#include "tool_support.hpp"

#ifndef CGE_VERSION_STRING
#define CGE_VERSION_STRING "unknown"
#endif

namespace {

constexpr int kExitOk = 0;
constexpr int kExitOutput = 1;
constexpr int kExitUsage = 2;
constexpr const char* kProgram = "cge_eval";

namespace m = cge::metrics;

/// A bad flag value or an unusable input, reported on stderr with exit code 2.
using cge_tool::UsageError;

/// An output file that cannot be written: exit code 1.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string groundtruth;
  std::string estimate;
  std::string loops_txt;
  std::string loops_csv;
  bool json = false;
  std::string duplicate_stamps = "last";
  double max_difference_s = m::AssociationSettings{}.max_difference_s;
  double offset_s = m::AssociationSettings{}.offset_s;
  double delta = m::RpeSettings{}.delta;
  std::string delta_unit = "s";
  double tolerance_s = m::LoopEvaluationSettings{}.timestamp_tolerance_s;
  std::string score_column = "cge_score";
  double min_score = -std::numeric_limits<double>::infinity();  // no threshold unless --min-score
  bool min_score_given = false;
  std::string curve;
  std::string aligned_out;
  bool force = false;
  std::string map_ot;
  std::string map_sequence;
  std::string map_trajectory;  // the map's trajectory (TUM): aligns the ghost set to the map's frame
  std::string map_keyframes;   // the map's keyframe poses (TUM): the ghost set at those poses
  std::string map_image;
  std::size_t min_entity_voxels = 3;
};

/// One result: a name and a number (NaN for undefined); counts print as JSON integers.
struct Value {
  std::string name;
  double value;
  bool count;
};
using Values = std::vector<Value>;  // in print order

Value count(const std::string& name, std::size_t n) { return {name, static_cast<double>(n), true}; }
Value real(const std::string& name, double x) { return {name, x, false}; }

std::string number(double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.15g", value);
  return buf;
}

m::Trajectory read_trajectory(const std::string& path, const Options& opt) {
  m::TumReadSettings settings;
  settings.duplicate_timestamps =
      opt.duplicate_stamps == "last" ? m::DuplicateTimestamps::keep_last : m::DuplicateTimestamps::refuse;
  m::TumReadReport report;
  m::Trajectory t;
  try {
    t = m::read_tum_trajectory_file(path, settings, &report);
  } catch (const m::ParseError& e) {
    if (e.reason().find("repeats the one") != std::string::npos) {
      throw UsageError(e.source() + ":" + std::to_string(e.line()) + ": " +
                       e.reason().substr(0, e.reason().find(" (")) +
                       " (--duplicate-stamps error; the default, last, keeps the later line as the TUM tools do)");
    }
    throw;
  }
  for (const std::size_t line : report.replaced_lines) {
    std::fprintf(stderr,
                 "%s: warning: %s:%zu: pose replaced by the next line, which repeats its timestamp (the TUM tools "
                 "keep the later line; --duplicate-stamps error refuses the file)\n",
                 kProgram, path.c_str(), line);
  }
  if (t.empty()) throw UsageError(path + ": the file contains no poses");
  return t;
}

/// Refuses an existing `path` unless `force`, and a directory always (UsageError naming the flag).
void check_writable(const std::string& path, const char* flag, bool force) {
  cge_tool::check_output_file(path, flag, force);
}

/// Writes `path` through `writer`, all or nothing, creating missing folders on the way;
/// OutputError when the file cannot be written.
template <typename Writer>
void write_file(const std::string& path, const char* flag, Writer&& writer) {
  cge_tool::CreatedFolders folders;
  folders.create_parent_of(path, flag);
  try {
    cge_tool::replace_file_with_stream(path, writer);
  } catch (const std::runtime_error& e) {
    throw OutputError(std::string(flag) + ": " + e.what());
  }
  folders.keep();
}

void add_statistics(Values& v, const std::string& prefix, const std::string& unit, const m::ErrorStatistics& s) {
  v.push_back(real(prefix + "rmse" + unit, s.rmse));
  v.push_back(real(prefix + "mean" + unit, s.mean));
  v.push_back(real(prefix + "median" + unit, s.median));
  v.push_back(real(prefix + "std" + unit, s.std));
  v.push_back(real(prefix + "min" + unit, s.min));
  v.push_back(real(prefix + "max" + unit, s.max));
}

Values run_ate(const Options& opt, nlohmann::ordered_json& inputs) {
  if (!(std::isfinite(opt.max_difference_s) && opt.max_difference_s > 0)) {
    throw UsageError("--max-difference must be a finite positive number, got " + number(opt.max_difference_s));
  }
  if (!std::isfinite(opt.offset_s)) throw UsageError("--offset must be finite");
  if (!opt.aligned_out.empty()) check_writable(opt.aligned_out, "--aligned-out", opt.force);
  const m::Trajectory gt = read_trajectory(opt.groundtruth, opt);
  const m::Trajectory est = read_trajectory(opt.estimate, opt);
  m::AteSettings settings;
  settings.association.max_difference_s = opt.max_difference_s;
  settings.association.offset_s = opt.offset_s;
  const m::AteResult r = m::compute_ate(gt, est, settings);
  inputs = {{"groundtruth", opt.groundtruth},
            {"estimate", opt.estimate},
            {"max_difference_s", opt.max_difference_s},
            {"offset_s", opt.offset_s}};
  if (!opt.aligned_out.empty()) {
    write_file(opt.aligned_out, "--aligned-out", [&](std::ostream& f) { m::write_aligned_pairs_csv(f, m::aligned_pairs(gt, est, r)); });
    inputs["aligned_out"] = opt.aligned_out;
  }
  Values v = {count("groundtruth_poses", gt.size()), count("estimate_poses", est.size()),
              count("compared_pose_pairs", r.translation_m.count)};
  add_statistics(v, "ate_", "_m", r.translation_m);
  return v;
}

Values run_rpe(const Options& opt, nlohmann::ordered_json& inputs) {
  const m::RpeDeltaUnit unit = opt.delta_unit == "frames" ? m::RpeDeltaUnit::frames : m::RpeDeltaUnit::seconds;
  if (!(std::isfinite(opt.delta) && opt.delta > 0)) {
    throw UsageError("--delta must be a finite positive number, got " + number(opt.delta));
  }
  if (unit == m::RpeDeltaUnit::frames && opt.delta != std::floor(opt.delta)) {
    throw UsageError("--delta in frames must be a whole number, got " + number(opt.delta));
  }
  const m::Trajectory gt = read_trajectory(opt.groundtruth, opt);
  const m::Trajectory est = read_trajectory(opt.estimate, opt);
  m::RpeSettings settings;
  settings.delta = opt.delta;
  settings.delta_unit = unit;
  const m::RpeResult r = m::compute_rpe(gt, est, settings);
  inputs = {{"groundtruth", opt.groundtruth},
            {"estimate", opt.estimate},
            {"delta", opt.delta},
            {"delta_unit", opt.delta_unit}};
  Values v = {count("groundtruth_poses", gt.size()), count("estimate_poses", est.size()),
              count("compared_pose_pairs", r.pairs.size())};
  add_statistics(v, "rpe_trans_", "_m", r.translation_m);
  add_statistics(v, "rpe_rot_", "_deg", r.rotation_deg);
  return v;
}

#ifdef CGE_EVAL_HAS_MAPS
Values run_map(const Options& opt, nlohmann::ordered_json& inputs) {
  namespace mp = cge::mapping;
  if (!opt.map_keyframes.empty() && opt.map_sequence.empty()) throw UsageError("map: --keyframes needs --sequence");
  if (!opt.map_trajectory.empty() && opt.map_sequence.empty()) throw UsageError("map: --trajectory needs --sequence");
  if (!opt.map_image.empty()) check_writable(opt.map_image, "--image", false);
  const auto tree = cge::octomap_adapter::read_color_octree(opt.map_ot);
  inputs["map"] = opt.map_ot;
  const mp::OccupiedVoxels voxels = cge::octomap_adapter::occupied_voxels(*tree);
  const mp::IntegrityScores scores =
      mp::integrity_scores(voxels, mp::component_entities(voxels, opt.min_entity_voxels));
  Values v = {real("resolution_m", voxels.resolution_m),
              count("occupied_voxels", voxels.voxels.size()),
              count("entities", static_cast<std::size_t>(scores.entities)),
              real("integrity", scores.integrity),
              real("fluctuation", scores.fluctuation),
              count("memory_bytes", tree->memoryUsage())};
  if (!opt.map_sequence.empty()) {
    inputs["sequence"] = opt.map_sequence;
    mp::GhostVoxelSettings ghost_settings;
    if (!opt.map_trajectory.empty()) {
      // A SLAM map lives in the run's frame: place the ghost set there (the ATE alignment).
      inputs["trajectory"] = opt.map_trajectory;
      const m::Trajectory gt =
          read_trajectory((std::filesystem::path(opt.map_sequence) / "groundtruth.txt").string(), opt);
      const m::AteResult ate = m::compute_ate(gt, read_trajectory(opt.map_trajectory, opt));
      ghost_settings.T_map_world = ate.T_groundtruth_estimate.inverse();
      v.push_back(real("trajectory_ate_rmse_m", ate.translation_m.rmse));
    }
    const mp::GhostVoxels ghosts =
        mp::ghost_voxels_from_sequence(opt.map_sequence, voxels.resolution_m, ghost_settings);
    v.push_back(real("ghost_fraction", mp::ghost_fraction(voxels, ghosts)));
    v.push_back(count("ghost_set_voxels", ghosts.ghost.size()));
    v.push_back(count("ghost_voxels", mp::ghost_voxel_count(voxels, ghosts.ghost)));
    if (!opt.map_keyframes.empty()) {
      // The same measure over the keyframes only, each at the pose the map was built with.
      inputs["keyframes"] = opt.map_keyframes;
      mp::GhostVoxelSettings at_keyframes;
      at_keyframes.frame_poses = read_trajectory(opt.map_keyframes, opt);
      const mp::GhostVoxels kf = mp::ghost_voxels_from_sequence(opt.map_sequence, voxels.resolution_m, at_keyframes);
      v.push_back(real("ghost_fraction_keyframe_poses", mp::ghost_fraction(voxels, kf)));
      v.push_back(count("ghost_set_voxels_keyframe_poses", kf.ghost.size()));
      v.push_back(count("ghost_voxels_keyframe_poses", mp::ghost_voxel_count(voxels, kf.ghost)));
    }
  }
  if (!opt.map_image.empty()) {
    inputs["image"] = opt.map_image;
    const cv::Mat picture = mp::render_top_view(voxels);
    cge_tool::CreatedFolders folders;
    folders.create_parent_of(opt.map_image, "--image");
    try {
      cge_tool::replace_file(opt.map_image, [&picture](const std::filesystem::path& temporary) {
        mp::write_png(temporary, picture, true);
        return true;
      });
    } catch (const std::runtime_error& e) {
      throw OutputError(std::string("--image: ") + e.what());
    }
    folders.keep();
  }
  return v;
}
#endif

// Missed loop queries by the loops.csv reason: the known reasons always (in the loop closer's step
// order), any other word after them; "accepted" (a wrong match was accepted) as wrong_match.
void add_missed_loop_queries(Values& v, const std::string& prefix, std::size_t missed,
                             const std::map<std::string, std::size_t>& by_reason) {
  v.push_back(count(prefix + "missed_loop_queries", missed));
  const std::vector<std::string> known = {"no_candidates",   "low_score",       "continuity",
                                          "too_few_matches", "pose_not_robust", "accepted"};
  auto name = [&prefix](const std::string& reason) {
    return prefix + "missed_" + (reason == "accepted" ? std::string("wrong_match") : reason);
  };
  for (const std::string& reason : known) {
    const auto it = by_reason.find(reason);
    v.push_back(count(name(reason), it == by_reason.end() ? 0 : it->second));
  }
  for (const auto& kv : by_reason) {
    if (std::find(known.begin(), known.end(), kv.first) == known.end()) v.push_back(count(name(kv.first), kv.second));
  }
}

Values run_loops(const Options& opt, nlohmann::ordered_json& inputs) {
  if (!(std::isfinite(opt.tolerance_s) && opt.tolerance_s >= 0)) {
    throw UsageError("--tolerance must be a finite number >= 0, got " + number(opt.tolerance_s));
  }
  if (opt.min_score_given && !std::isfinite(opt.min_score)) {
    throw UsageError("--min-score must be a finite number, got " + number(opt.min_score));
  }
  const m::LoopScoreColumn column = m::parse_loop_score_column(opt.score_column);
  if (!opt.curve.empty()) check_writable(opt.curve, "--curve", opt.force);
  const std::vector<m::GroundTruthLoop> gt = m::read_ground_truth_loops_file(opt.loops_txt);
  const std::vector<m::LoopQuery> rows = m::read_loop_queries_file(opt.loops_csv);
  m::LoopEvaluationSettings settings;
  settings.timestamp_tolerance_s = opt.tolerance_s;
  const auto in_file = [&opt](auto&& compute) {  // names the file in "line <n>: ..." messages
    try {
      return compute();
    } catch (const std::invalid_argument& e) {
      throw UsageError(opt.loops_csv + ": " + e.what());
    }
  };
  const m::LoopEvaluation e = m::evaluate_loops(
      gt, opt.min_score_given ? in_file([&] { return m::apply_score_threshold(rows, column, opt.min_score); }) : rows,
      settings);
  if (!opt.curve.empty()) {
    // Thresholds read back as the same double (--min-score reproduces a row); the ratios as the
    // standard output prints them.
    const std::vector<m::LoopCurvePoint> curve =
        in_file([&] { return m::loop_threshold_curve(gt, rows, column, settings); });
    write_file(opt.curve, "--curve", [&](std::ostream& f) {
      f << "threshold,detections,correct_detections,precision,query_recall,event_recall\n";
      for (const m::LoopCurvePoint& p : curve) {
        f << cge_tool::round_trip_number(p.threshold) << ',' << p.evaluation.detections << ','
          << p.evaluation.correct_detections << ',' << number(p.evaluation.precision) << ','
          << number(p.evaluation.query_recall) << ',' << number(p.evaluation.event_recall) << '\n';
      }
    });
  }
  if (e.detections == 0) std::fprintf(stderr, "%s: note: no accepted loop: precision is undefined (nan)\n", kProgram);
  if (e.loop_queries == 0) {
    std::fprintf(stderr, "%s: note: no queried keyframe has a ground-truth loop: recall is undefined (nan)\n",
                 kProgram);
  }
  inputs = {{"ground_truth_loops", opt.loops_txt},
            {"loops_csv", opt.loops_csv},
            {"tolerance_s", opt.tolerance_s},
            {"score", m::to_string(column)}};
  if (opt.min_score_given) inputs["min_score"] = opt.min_score;
  if (!opt.curve.empty()) inputs["curve"] = opt.curve;
  Values v = {count("ground_truth_pairs", e.ground_truth_pairs),
              count("queried_keyframes", e.queried_keyframes),
              count("detections", e.detections),
              count("correct_detections", e.correct_detections),
              real("precision", e.precision),
              count("loop_queries", e.loop_queries),
              count("detected_loop_queries", e.detected_loop_queries),
              real("query_recall", e.query_recall),
              count("loop_events", e.loop_events),
              count("detected_loop_events", e.detected_loop_events),
              real("event_recall", e.event_recall)};
  add_missed_loop_queries(v, "", e.loop_queries - e.detected_loop_queries, e.missed_by_reason);
  if (e.has_connectivity) {
    v.push_back(count("loop_queries_without_keyframe_partner", e.loop_queries_without_keyframe_partner));
    v.push_back(count("connected_loop_queries", e.connected_loop_queries));
    v.push_back(count("open_loop_queries", e.open_loop_queries));
    v.push_back(count("detected_open_loop_queries", e.detected_open_loop_queries));
    v.push_back(real("open_query_recall", e.open_query_recall));
    add_missed_loop_queries(v, "open_", e.open_loop_queries - e.detected_open_loop_queries, e.missed_open_by_reason);
  } else {
    std::fprintf(stderr, "%s: note: %s has no connected_keyframes column: open query recall not computed\n", kProgram,
                 opt.loops_csv.c_str());
  }
  return v;
}

int print(const std::string& command, const Values& values, const nlohmann::ordered_json& inputs, bool json) {
  if (json) {
    nlohmann::ordered_json out;
    out["tool"] = kProgram;
    out["version"] = CGE_VERSION_STRING;
    out["command"] = command;
    out["inputs"] = inputs;
    for (const Value& v : values) {
      if (v.count) {
        out[v.name] = static_cast<unsigned long long>(v.value);
      } else if (std::isnan(v.value)) {
        out[v.name] = nullptr;  // undefined ratio
      } else {
        out[v.name] = v.value;
      }
    }
    std::cout << out.dump(2) << '\n';
  } else {
    for (const Value& v : values) std::cout << v.name << ' ' << number(v.value) << '\n';
  }
  if (!cge_tool::standard_output_written(kProgram)) return kExitOutput;
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"Trajectory and loop-closure metrics against ground truth (cge " CGE_VERSION_STRING
               ").\nATE and RPE as the TUM RGB-D benchmark tools compute them; loop precision and recall "
               "against\nthe synthetic sequences' loops.txt. See docs/EVALUATION.md.",
               kProgram};
  app.set_version_flag("--version", std::string(kProgram) + " " + CGE_VERSION_STRING);
  app.require_subcommand(1);

  auto add_common = [&opt](CLI::App* sub) {
    sub->add_flag("--json", opt.json, "print one JSON object instead of \"name value\" lines");
  };
  auto add_trajectories = [&opt](CLI::App* sub) {
    sub->add_option("GT", opt.groundtruth, "ground-truth trajectory (TUM format)")->required();
    sub->add_option("EST", opt.estimate, "estimated trajectory (TUM format)")->required();
    sub->add_option("--duplicate-stamps", opt.duplicate_stamps,
                    "a line repeating the previous timestamp: last (keep the later line with a warning, as the TUM "
                    "tools) or error (refuse the file)")
        ->check(CLI::IsMember({"error", "last"}))
        ->capture_default_str();
  };

  CLI::App* ate = app.add_subcommand("ate", "absolute trajectory error (evaluate_ate.py)");
  add_trajectories(ate);
  ate->add_option("--max-difference", opt.max_difference_s, "largest timestamp difference of an associated pair, s")
      ->capture_default_str();
  ate->add_option("--offset", opt.offset_s, "time offset added to the estimate's timestamps, s")->capture_default_str();
  ate->add_option("--aligned-out", opt.aligned_out,
                  "write the associated pairs after the alignment as CSV "
                  "(timestamp,gt_x,gt_y,gt_z,est_x,est_y,est_z,error_m)");
  ate->add_flag("--force", opt.force, "overwrite an existing --aligned-out file");
  add_common(ate);

  CLI::App* rpe = app.add_subcommand("rpe", "relative pose error over a fixed delta (evaluate_rpe.py --fixed_delta)");
  add_trajectories(rpe);
  rpe->add_option("--delta", opt.delta, "separation of the compared poses, in --delta-unit")->capture_default_str();
  rpe->add_option("--delta-unit", opt.delta_unit, "unit of --delta: s (seconds) or frames")
      ->check(CLI::IsMember({"s", "frames"}))
      ->capture_default_str();
  add_common(rpe);

  CLI::App* loops = app.add_subcommand("loops", "loop-closure precision and recall");
  loops->add_option("GT_LOOPS", opt.loops_txt, "ground-truth loops (the sequence's loops.txt)")->required();
  loops->add_option("LOOPS_CSV", opt.loops_csv, "the loop closer's log (cge_slam's loops.csv)")->required();
  loops->add_option("--tolerance", opt.tolerance_s, "two timestamps within this are the same frame, s")
      ->capture_default_str();
  loops->add_option("--score", opt.score_column, "the score column --min-score and --curve threshold")
      ->check(CLI::IsMember({"cge_score", "bow_score"}))
      ->capture_default_str();
  loops
      ->add_option("--min-score", opt.min_score,
                   "an accepted row is a detection only when its --score column is >= this (default: every "
                   "accepted row)")
      ->each([&opt](const std::string&) { opt.min_score_given = true; });
  loops->add_option("--curve", opt.curve,
                    "write precision and recall at every threshold as CSV "
                    "(threshold,detections,correct_detections,precision,query_recall,event_recall): a first row at "
                    "-inf, then one per distinct --score value among accepted rows, ascending");
  loops->add_flag("--force", opt.force, "overwrite an existing --curve file");
  add_common(loops);

#ifdef CGE_EVAL_HAS_MAPS
  CLI::App* map = app.add_subcommand("map", "semantic octree: occupied voxels, integrity, fluctuation, ghost voxels");
  map->add_option("MAP", opt.map_ot, "the semantic octree (.ot, a ColorOcTree)")->required();
  map->add_option(
      "--sequence", opt.map_sequence,
      "a synthetic sequence folder (cge_sim): also the fraction of occupied voxels on moving people's paths");
  map->add_option("--trajectory", opt.map_trajectory,
                  "with --sequence: the map's trajectory (TUM, e.g. cge_slam's trajectory.txt); the ghost set is "
                  "moved into the map's frame by the ATE alignment to the sequence's groundtruth.txt");
  map->add_option("--keyframes", opt.map_keyframes,
                  "with --sequence: the map's keyframe poses (TUM, e.g. cge_slam's keyframes.txt); also the ghost "
                  "figures with the ghost set made from those frames at those poses (*_keyframe_poses, docs/MAPS.md)");
  map->add_option("--image", opt.map_image, "write a top-view PNG of the occupied voxels (never overwritten)");
  map->add_option("--min-entity-voxels", opt.min_entity_voxels,
                  "smaller connected same-class parts are not integrity entities")
      ->capture_default_str();
  add_common(map);
#endif

  if (const int exit_code = cge_tool::parse_command_line(app, argc, argv, kProgram); exit_code >= 0) return exit_code;

  try {
    nlohmann::ordered_json inputs;
    if (ate->parsed()) {
      const Values v = run_ate(opt, inputs);
      return print("ate", v, inputs, opt.json);
    }
    if (rpe->parsed()) {
      const Values v = run_rpe(opt, inputs);
      return print("rpe", v, inputs, opt.json);
    }
#ifdef CGE_EVAL_HAS_MAPS
    if (map->parsed()) {
      const Values v = run_map(opt, inputs);
      return print("map", v, inputs, opt.json);
    }
#endif
    const Values v = run_loops(opt, inputs);
    return print("loops", v, inputs, opt.json);
  } catch (const std::invalid_argument& e) {  // malformed input (file:line) or unusable data
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitUsage;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitUsage;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitOutput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, e.what());
    return kExitUsage;
  }
}
