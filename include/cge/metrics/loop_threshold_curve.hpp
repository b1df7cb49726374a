#pragma once
// Loop precision and recall as a function of an acceptance threshold on one score column of the
// loop closer's log (the P-R curves of paper Figure 18), computed from one loops.csv: an accepted
// row counts as a detection only when its score is >= the threshold; every other row stays a
// queried keyframe without a detection (so recall denominators do not change with the threshold).
//
// The curve has one point per distinct score among the accepted rows, ascending, each the
// evaluation of evaluate_loops at that threshold, after a first point at threshold -infinity (every
// accepted row counts: the log as written; equal to the lowest score's point whenever a row is
// accepted, and the only point when none is).

#include <algorithm>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/metrics/loop_precision_recall.hpp"

namespace cge {
namespace metrics {

/// Which score column of loops.csv a threshold applies to.
enum class LoopScoreColumn { bow_score, cge_score };

/// "bow_score", "cge_score": the loops.csv column names.
inline const char* to_string(LoopScoreColumn column) {
  return column == LoopScoreColumn::bow_score ? "bow_score" : "cge_score";
}

/// The inverse of to_string; throws std::invalid_argument naming the valid names.
inline LoopScoreColumn parse_loop_score_column(const std::string& name) {
  if (name == "bow_score") return LoopScoreColumn::bow_score;
  if (name == "cge_score") return LoopScoreColumn::cge_score;
  throw std::invalid_argument("score column '" + name + "' is not bow_score or cge_score");
}

/// The score of an accepted row in `column`. Throws std::invalid_argument "line <n>: ..." (the
/// row's line in its file) when the column is empty.
inline double accepted_row_score(const LoopQuery& row, LoopScoreColumn column) {
  const std::optional<double>& score = column == LoopScoreColumn::bow_score ? row.bow_score : row.cge_score;
  if (!score) {
    throw std::invalid_argument("line " + std::to_string(row.line) + ": an accepted row has no " + to_string(column));
  }
  return *score;
}

/// `rows` with every accepted row whose score is below `min_score` turned into a rejection
/// (accepted false, reason "below_threshold"). A NaN min_score is refused (std::invalid_argument);
/// -infinity keeps every row as it is.
inline std::vector<LoopQuery> apply_score_threshold(std::vector<LoopQuery> rows, LoopScoreColumn column,
                                                    double min_score) {
  if (min_score != min_score) throw std::invalid_argument("apply_score_threshold: the threshold is NaN");
  for (LoopQuery& row : rows) {
    if (row.accepted && !(accepted_row_score(row, column) >= min_score)) {
      row.accepted = false;
      row.reason = "below_threshold";
    }
  }
  return rows;
}

struct LoopCurvePoint {
  double threshold = 0;  ///< least score of a detection; -infinity for the first point
  LoopEvaluation evaluation;
};

/// The curve described at the top of this file.
inline std::vector<LoopCurvePoint> loop_threshold_curve(const std::vector<GroundTruthLoop>& ground_truth,
                                                        const std::vector<LoopQuery>& rows, LoopScoreColumn column,
                                                        const LoopEvaluationSettings& settings = {}) {
  std::vector<double> thresholds = {-std::numeric_limits<double>::infinity()};
  std::vector<double> scores;
  for (const LoopQuery& row : rows) {
    if (row.accepted) scores.push_back(accepted_row_score(row, column));
  }
  std::sort(scores.begin(), scores.end());
  scores.erase(std::unique(scores.begin(), scores.end()), scores.end());
  thresholds.insert(thresholds.end(), scores.begin(), scores.end());
  std::vector<LoopCurvePoint> curve;
  curve.reserve(thresholds.size());
  for (const double t : thresholds) {
    curve.push_back({t, evaluate_loops(ground_truth, apply_score_threshold(rows, column, t), settings)});
  }
  return curve;
}

}  // namespace metrics
}  // namespace cge
