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
//   - Misses: loop queries without a correct detection, counted by the reason of their row
//     ("accepted" there means a wrong match was accepted; with several rows per keyframe, the last).
// With the extended loops.csv (connected_keyframes logged by the loop closer) also:
//   - A keyframe partner of a loop query is a queried keyframe whose stamp is a ground-truth match
//     of it. The query is "connected" when it has keyframe partners and every one of them is in its
//     connected_keyframes (covisible with it when it was processed: the loop there is closed
//     already, and a loop closer never proposes such keyframes); it is "open" when some keyframe
//     partner is not connected: the loop closer could still have found it.
//   - open query recall = open loop queries with a correct detection / open loop queries.
// A ratio whose denominator is 0 is NaN (undefined), never a silent 0 or 1.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
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
  /// Loop queries without a correct detection by the reason of their row ("accepted": wrong match).
  std::map<std::string, std::size_t> missed_by_reason;

  // Extended loops.csv only (every row has connected_keyframes); otherwise counts 0 and recall NaN.
  bool has_connectivity = false;
  std::size_t loop_queries_without_keyframe_partner = 0;                ///< no ground-truth match is a queried keyframe
  std::size_t connected_loop_queries = 0;                               ///< every keyframe partner already connected
  std::size_t open_loop_queries = 0;                                    ///< some keyframe partner not connected
  std::size_t detected_open_loop_queries = 0;                           ///< of those, with a correct detection
  double open_query_recall = std::numeric_limits<double>::quiet_NaN();  ///< detected_open / open
  /// Open loop queries without a correct detection, by the reason of their row.
  std::map<std::string, std::size_t> missed_open_by_reason;
};

/// Throws std::invalid_argument for a negative or non-finite tolerance, and (extended format) for a
/// connected keyframe id that is no row's query_keyframe.
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
    bool detected;       // some accepted row of it is correct
    std::string reason;  // of its last row
    std::vector<long long> connected;
  };
  std::vector<Queried> queried;
  std::vector<LoopQuery> rows = queries;
  std::stable_sort(rows.begin(), rows.end(),
                   [](const LoopQuery& l, const LoopQuery& r) { return l.query_timestamp_s < r.query_timestamp_s; });
  LoopEvaluation e;
  e.ground_truth_pairs = ground_truth.size();
  e.has_connectivity = !rows.empty();
  for (const LoopQuery& row : rows) {
    if (!std::isfinite(row.query_timestamp_s))
      throw std::invalid_argument("evaluate_loops: a query stamp is not finite");
    if (!row.connected_keyframes) e.has_connectivity = false;
    bool correct = false;
    if (row.accepted) {
      if (!row.match_timestamp_s) throw std::invalid_argument("evaluate_loops: an accepted row has no match");
      ++e.detections;
      correct = is_correct(row.query_timestamp_s, *row.match_timestamp_s);
      if (correct) ++e.correct_detections;
    }
    if (queried.empty() || queried.back().stamp_s != row.query_timestamp_s) {
      queried.push_back({row.query_timestamp_s, correct, row.reason, {}});
    } else {
      queried.back().detected = queried.back().detected || correct;
      queried.back().reason = row.reason;
    }
    if (row.connected_keyframes) {
      std::vector<long long>& c = queried.back().connected;
      c.insert(c.end(), row.connected_keyframes->begin(), row.connected_keyframes->end());
    }
  }
  e.queried_keyframes = queried.size();
  e.precision = ratio(e.correct_detections, e.detections);

  // Keyframe stamps by id (each row's query), and the stamps sorted for the partner search.
  std::map<long long, double> keyframe_stamp;
  std::vector<std::pair<double, long long>> keyframes_by_stamp;
  for (const LoopQuery& row : rows) {
    if (keyframe_stamp.emplace(row.query_keyframe, row.query_timestamp_s).second) {
      keyframes_by_stamp.emplace_back(row.query_timestamp_s, row.query_keyframe);
    }
  }
  std::sort(keyframes_by_stamp.begin(), keyframes_by_stamp.end());
  // Keyframe partners of a loop query: the queried keyframes at its ground-truth match stamps.
  auto keyframe_partners = [&](double query_s) {
    std::vector<long long> ids;
    for (auto it = first_candidate(query_s); it != gt.end() && it->query_timestamp_s <= query_s + tol; ++it) {
      if (std::abs(it->query_timestamp_s - query_s) > tol) continue;
      const double m = it->match_timestamp_s;
      auto k = std::lower_bound(keyframes_by_stamp.begin(), keyframes_by_stamp.end(),
                                std::make_pair(m - tol, std::numeric_limits<long long>::min()));
      for (; k != keyframes_by_stamp.end() && k->first <= m + tol; ++k) ids.push_back(k->second);
    }
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    return ids;
  };
  if (e.has_connectivity) {
    for (const Queried& k : queried) {
      for (long long id : k.connected) {
        if (keyframe_stamp.count(id) == 0) {
          throw std::invalid_argument("evaluate_loops: connected keyframe " + std::to_string(id) +
                                      " is no row's query_keyframe");
        }
      }
    }
  }

  bool in_event = false, event_detected = false;
  for (const Queried& k : queried) {
    if (has_loop(k.stamp_s)) {
      ++e.loop_queries;
      if (k.detected) ++e.detected_loop_queries;
      if (!k.detected) ++e.missed_by_reason[k.reason];
      if (e.has_connectivity) {
        const std::vector<long long> partners = keyframe_partners(k.stamp_s);
        bool open = false;
        for (long long id : partners) {
          if (std::find(k.connected.begin(), k.connected.end(), id) == k.connected.end()) open = true;
        }
        if (partners.empty()) {
          ++e.loop_queries_without_keyframe_partner;
        } else if (!open) {
          ++e.connected_loop_queries;
        } else {
          ++e.open_loop_queries;
          if (k.detected) ++e.detected_open_loop_queries;
          if (!k.detected) ++e.missed_open_by_reason[k.reason];
        }
      }
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
  if (e.has_connectivity) e.open_query_recall = ratio(e.detected_open_loop_queries, e.open_loop_queries);
  return e;
}

}  // namespace metrics
}  // namespace cge
