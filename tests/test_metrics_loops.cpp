// Loop precision / recall against ground-truth loops: a hand-worked log, and random logs against a
// brute-force oracle that works on frame numbers instead of timestamps.

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cge/metrics/loop_precision_recall.hpp"
#include "test_support.hpp"

using namespace cge::metrics;

namespace {

GroundTruthLoop gt_pair(double query_s, double match_s) {
  GroundTruthLoop l;
  l.query_timestamp_s = query_s;
  l.match_timestamp_s = match_s;
  return l;
}

LoopQuery row(double query_s, bool accepted, double match_s = -1) {
  LoopQuery q;
  q.query_timestamp_s = query_s;
  q.accepted = accepted;
  q.reason = accepted ? "accepted" : "low_score";
  if (match_s >= 0) q.match_timestamp_s = match_s;
  return q;
}

}  // namespace

TEST_CASE("loop P/R: hand-worked log", "[metrics]") {
  // Ground truth: keyframes at 10, 11, 12 s revisit 1 and 2 s; 17 and 18 s revisit 5 s.
  const std::vector<GroundTruthLoop> gt = {gt_pair(10, 1), gt_pair(10, 2), gt_pair(11, 1), gt_pair(11, 2),
                                           gt_pair(12, 2), gt_pair(17, 5), gt_pair(18, 5)};
  // Queried: 4, 10 (correct, match 0.5 ms off), 11 (wrong match), 12, 14 (no loop there), 17, 18, 20.
  const std::vector<LoopQuery> rows = {row(4, false),    row(10.0004, true, 1.0005), row(11, true, 3), row(12, false),
                                       row(14, true, 2), row(17, false, 5),          row(18, false),   row(20, false)};
  const LoopEvaluation e = evaluate_loops(gt, rows);
  CHECK(e.ground_truth_pairs == 7);
  CHECK(e.queried_keyframes == 8);
  CHECK(e.detections == 3);
  CHECK(e.correct_detections == 1);
  CHECK(e.precision == Approx(1.0 / 3));
  CHECK(e.loop_queries == 5);  // 10, 11, 12, 17, 18
  CHECK(e.detected_loop_queries == 1);
  CHECK(e.query_recall == Approx(0.2));
  CHECK(e.loop_events == 2);  // {10, 11, 12} and {17, 18}: 14 is queried and has no loop
  CHECK(e.detected_loop_events == 1);
  CHECK(e.event_recall == Approx(0.5));

  // 2 ms off is another frame; a tolerance of 3 ms accepts it.
  const std::vector<LoopQuery> off = {row(10, true, 1.002), row(17, true, 5)};
  const LoopEvaluation e2 = evaluate_loops(gt, off);
  CHECK(e2.correct_detections == 1);
  CHECK(e2.loop_events == 1);  // only 10 and 17 were queried: consecutive queries, one event
  LoopEvaluationSettings wide;
  wide.timestamp_tolerance_s = 0.003;
  CHECK(evaluate_loops(gt, off, wide).correct_detections == 2);
}

TEST_CASE("loop P/R: direction matters, repeated query rows are one keyframe, undefined ratios are NaN", "[metrics]") {
  const std::vector<GroundTruthLoop> gt = {gt_pair(10, 1)};
  // (1, 10) reversed is not the ground-truth pair (10, 1).
  const LoopEvaluation reversed = evaluate_loops(gt, {row(1, true, 10)});
  CHECK(reversed.detections == 1);
  CHECK(reversed.correct_detections == 0);
  CHECK(reversed.loop_queries == 0);
  CHECK(std::isnan(reversed.query_recall));
  CHECK(std::isnan(reversed.event_recall));
  // Two rows for keyframe 10: one keyframe, two detections.
  const LoopEvaluation twice = evaluate_loops(gt, {row(10, true, 1), row(10, true, 7)});
  CHECK(twice.queried_keyframes == 1);
  CHECK(twice.detections == 2);
  CHECK(twice.correct_detections == 1);
  CHECK(twice.precision == Approx(0.5));
  CHECK(twice.query_recall == 1.0);
  CHECK(twice.event_recall == 1.0);
  // Nothing accepted: precision undefined, recall 0.
  const LoopEvaluation none = evaluate_loops(gt, {row(10, false)});
  CHECK(std::isnan(none.precision));
  CHECK(none.query_recall == 0.0);
  CHECK(none.event_recall == 0.0);
  LoopEvaluationSettings bad;
  bad.timestamp_tolerance_s = -1;
  CHECK_THAT(cge_test::invalid_argument_message([&] { evaluate_loops(gt, {}, bad); }),
             Catch::Contains("timestamp_tolerance_s"));
}

TEST_CASE("loop P/R: random logs agree with a brute-force oracle on frame numbers", "[metrics]") {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 200; ++trial) {
    // Frames k at 1000 + k / 30 s; the loop closer queries a random subset of frames in order.
    const int frames = 60;
    auto stamp = [](int k) { return 1000.0 + k / 30.0; };
    std::bernoulli_distribution coin(0.3), accept(0.4), right(0.5);
    std::uniform_int_distribution<int> frame(0, frames - 1);
    std::set<std::pair<int, int>> gt_set;
    std::vector<GroundTruthLoop> gt;
    for (int q = 1; q < frames; ++q) {
      if (!coin(rng)) continue;
      const int m = std::uniform_int_distribution<int>(0, q - 1)(rng);
      gt_set.insert({q, m});
      gt.push_back(gt_pair(stamp(q), stamp(m)));
      if (coin(rng) && m + 1 < q) {
        gt_set.insert({q, m + 1});
        gt.push_back(gt_pair(stamp(q), stamp(m + 1)));
      }
    }
    std::vector<int> queried;
    std::vector<LoopQuery> rows;
    std::map<int, bool> detected;  // queried frame -> some correct detection
    int detections = 0, correct = 0;
    for (int k = 0; k < frames; ++k) {
      if (!coin(rng) && !coin(rng)) continue;
      queried.push_back(k);
      detected[k] = false;
      if (accept(rng)) {
        int m = frame(rng);
        if (right(rng)) {  // pick a true match when there is one
          for (const auto& p : gt_set) {
            if (p.first == k) m = p.second;
          }
        }
        rows.push_back(row(stamp(k), true, stamp(m)));
        ++detections;
        if (gt_set.count({k, m})) {
          ++correct;
          detected[k] = true;
        }
      } else {
        rows.push_back(row(stamp(k), false));
      }
    }
    // Oracle recall: loop frames, and runs of consecutive queried loop frames.
    auto has_loop = [&](int k) {
      for (const auto& p : gt_set) {
        if (p.first == k) return true;
      }
      return false;
    };
    int loop_queries = 0, detected_queries = 0, events = 0, detected_events = 0;
    for (std::size_t i = 0; i < queried.size(); ++i) {
      if (!has_loop(queried[i])) continue;
      ++loop_queries;
      if (detected[queried[i]]) ++detected_queries;
      if (i == 0 || !has_loop(queried[i - 1])) {
        ++events;
        bool any = false;
        for (std::size_t j = i; j < queried.size() && has_loop(queried[j]); ++j) any = any || detected[queried[j]];
        if (any) ++detected_events;
      }
    }
    const LoopEvaluation e = evaluate_loops(gt, rows);
    INFO("trial " << trial);
    CHECK(e.queried_keyframes == queried.size());
    CHECK(e.detections == std::size_t(detections));
    CHECK(e.correct_detections == std::size_t(correct));
    CHECK(e.loop_queries == std::size_t(loop_queries));
    CHECK(e.detected_loop_queries == std::size_t(detected_queries));
    CHECK(e.loop_events == std::size_t(events));
    CHECK(e.detected_loop_events == std::size_t(detected_events));
    if (detections > 0) CHECK(e.precision == Approx(double(correct) / detections));
    if (loop_queries > 0) CHECK(e.query_recall == Approx(double(detected_queries) / loop_queries));
    if (events > 0) CHECK(e.event_recall == Approx(double(detected_events) / events));
  }
}
