#pragma once
// Precision and recall of loop detections against ground-truth loops (docs/EVALUATION.md).
//
// Inputs: the ground-truth loop pairs (every revisiting frame pair, ground_truth_loops_io.hpp) and
// the loop closer's rows (loop_queries_io.hpp): every row names a queried keyframe; accepted rows
// are the detections. Timestamps identify frames; two stamps are the same frame when they differ
// by at most LoopEvaluationSettings::timestamp_tolerance_s.
//   - A detection (q, m) is correct when (q, m) is a ground-truth pair (query to query, match to
//     match; the direction matters, ground truth has match earlier than query).
//   - precision = correct detections / detections.
//   - A queried keyframe "has a loop" when it is the query of some ground-truth pair.
//   - query recall = queried keyframes with a loop that have a correct detection / queried
//     keyframes with a loop.
//   - A revisit event is a maximal run of consecutive queried keyframes (in time order) that all
//     have a loop; event recall = events holding at least one correct detection / events.
// Event recall asks "was each revisit noticed at least once", which is what a SLAM system needs to
// close the loop; query recall asks "how many of the revisiting keyframes were recognised".
// A ratio whose denominator is 0 is NaN (undefined), never a silent 0 or 1.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <vector>

#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/metrics/loop_queries_io.hpp"

namespace cge {
namespace metrics {

struct LoopEvaluationSettings {
  double timestamp_tolerance_s = 1e-3;  ///< two stamps within this are one frame, seconds, >= 0
};

struct LoopEvaluation {
  std::size_t ground_truth_pairs = 0;     ///< lines of the ground truth
  std::size_t queried_keyframes = 0;      ///< distinct query stamps in loops.csv
  std::size_t detections = 0;             ///< accepted rows
  std::size_t correct_detections = 0;     ///< accepted rows that are ground-truth pairs
  double precision = 0.0;                 ///< correct_detections / detections (NaN when none)
  std::size_t loop_queries = 0;           ///< queried keyframes that have a ground-truth loop
  std::size_t detected_loop_queries = 0;  ///< of those, with a correct detection
  double query_recall = 0.0;              ///< detected_loop_queries / loop_queries (NaN when none)
  std::size_t loop_events = 0;            ///< maximal runs of consecutive queried keyframes with a loop
  std::size_t detected_loop_events = 0;   ///< of those, holding a correct detection
  double event_recall = 0.0;              ///< detected_loop_events / loop_events (NaN when none)
};

/// Throws std::invalid_argument for a negative or non-finite tolerance.
inline LoopEvaluation evaluate_loops(const std::vector<GroundTruthLoop>& ground_truth,
                                     const std::vector<LoopQuery>& queries,
                                     const LoopEvaluationSettings& settings = {}) {
  const double tol = settings.timestamp_tolerance_s;
  if (!(std::isfinite(tol) && tol >= 0))
    throw std::invalid_argument("evaluate_loops: timestamp_tolerance_s must be >= 0");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto ratio = [nan](std::size_t num, std::size_t den) {
    return den == 0 ? nan : static_cast<double>(num) / static_cast<double>(den);
  };

  // Ground truth sorted by query stamp, for a window search.
  std::vector<GroundTruthLoop> gt = ground_truth;
  std::sort(gt.begin(), gt.end(), [](const GroundTruthLoop& l, const GroundTruthLoop& r) {
    if (l.query_timestamp_s != r.query_timestamp_s) return l.query_timestamp_s < r.query_timestamp_s;
    return l.match_timestamp_s < r.match_timestamp_s;
  });
  auto first_candidate = [&gt, tol](double query_s) {
    return std::lower_bound(gt.begin(), gt.end(), query_s - tol,
                            [](const GroundTruthLoop& l, double t) { return l.query_timestamp_s < t; });
  };
  auto has_loop = [&](double query_s) {
    const auto it = first_candidate(query_s);
    return it != gt.end() && std::abs(it->query_timestamp_s - query_s) <= tol;
  };
  auto is_correct = [&](double query_s, double match_s) {
    for (auto it = first_candidate(query_s); it != gt.end() && it->query_timestamp_s <= query_s + tol; ++it) {
      if (std::abs(it->query_timestamp_s - query_s) <= tol && std::abs(it->match_timestamp_s - match_s) <= tol) {
        return true;
      }
    }
    return false;
  };

  // Queried keyframes in time order; rows with the same query stamp are one keyframe.
  struct Queried {
    double stamp_s;
    bool detected;  // some accepted row of it is correct
  };
  std::vector<Queried> queried;
  std::vector<LoopQuery> rows = queries;
  std::stable_sort(rows.begin(), rows.end(),
                   [](const LoopQuery& l, const LoopQuery& r) { return l.query_timestamp_s < r.query_timestamp_s; });
  LoopEvaluation e;
  e.ground_truth_pairs = ground_truth.size();
  for (const LoopQuery& row : rows) {
    if (!std::isfinite(row.query_timestamp_s))
      throw std::invalid_argument("evaluate_loops: a query stamp is not finite");
    bool correct = false;
    if (row.accepted) {
      if (!row.match_timestamp_s) throw std::invalid_argument("evaluate_loops: an accepted row has no match");
      ++e.detections;
      correct = is_correct(row.query_timestamp_s, *row.match_timestamp_s);
      if (correct) ++e.correct_detections;
    }
    if (queried.empty() || queried.back().stamp_s != row.query_timestamp_s) {
      queried.push_back({row.query_timestamp_s, correct});
    } else {
      queried.back().detected = queried.back().detected || correct;
    }
  }
  e.queried_keyframes = queried.size();
  e.precision = ratio(e.correct_detections, e.detections);

  bool in_event = false, event_detected = false;
  for (const Queried& k : queried) {
    if (has_loop(k.stamp_s)) {
      ++e.loop_queries;
      if (k.detected) ++e.detected_loop_queries;
      if (!in_event) {
        in_event = true;
        event_detected = false;
        ++e.loop_events;
      }
      if (k.detected && !event_detected) {
        event_detected = true;
        ++e.detected_loop_events;
      }
    } else {
      in_event = false;
    }
  }
  e.query_recall = ratio(e.detected_loop_queries, e.loop_queries);
  e.event_recall = ratio(e.detected_loop_events, e.loop_events);
  return e;
}

}  // namespace metrics
}  // namespace cge
