// Loop closing: the choice among geometrically verified candidates (choose_verification),
// the extended loops.csv (tentative matches, checks run, connected keyframes), and the evaluation's
// breakdown of missed loop queries and open query recall. Oracles: hand-worked logs, and random logs
// against a brute-force count on frame numbers.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/features2d.hpp>

#include "cge/metrics/loop_precision_recall.hpp"
#include "cge/metrics/loop_queries_io.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/two_nearest_descriptors.hpp"
#include "loop_queries_text.hpp"
#include "test_support.hpp"

using cge::slam::LoopDecision;
using cge::slam::LoopReason;
using namespace cge::metrics;

namespace {

LoopDecision attempt(int match, LoopReason reason, int matched_points) {
  LoopDecision d;
  d.match_keyframe = match;
  d.reason = reason;
  d.accepted = reason == LoopReason::accepted;
  d.matched_points = matched_points;
  return d;
}

GroundTruthLoop gt_pair(double query_s, double match_s) {
  GroundTruthLoop l;
  l.query_timestamp_s = query_s;
  l.match_timestamp_s = match_s;
  return l;
}

LoopQuery row(double query_s, long long keyframe, const std::string& reason, std::vector<long long> connected,
              double match_s = -1) {
  LoopQuery q;
  q.query_timestamp_s = query_s;
  q.query_keyframe = keyframe;
  q.reason = reason;
  q.accepted = reason == "accepted";
  if (match_s >= 0) {
    q.match_timestamp_s = match_s;
    q.match_keyframe = 0;
  }
  q.connected_keyframes = std::move(connected);
  return q;
}

const std::string kExtendedHeader =
    "query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_points,accepted,"
    "reason,tentative_matches,verified_keyframes,connected_keyframes\n";

using cge_test::loops_csv_error;
using cge_test::read_loops_csv_text;

}  // namespace

TEST_CASE("choose_verification: the accepted check with the most inliers, else the closest failure", "[loops]") {
  CHECK(cge::slam::choose_verification({}) == -1);
  // Three accepted checks: 93 inliers (a neighbouring view), 140 (the closest view), 140 again (a
  // later tie): the first 140 is kept.
  CHECK(cge::slam::choose_verification({attempt(49, LoopReason::accepted, 93), attempt(51, LoopReason::accepted, 140),
                                        attempt(52, LoopReason::accepted, 140)}) == 1);
  // An accepted check beats failures with more matched points (tentative matches or inliers).
  CHECK(cge::slam::choose_verification({attempt(3, LoopReason::too_few_matches, 400),
                                        attempt(4, LoopReason::pose_not_robust, 300),
                                        attempt(5, LoopReason::accepted, 41)}) == 2);
  // No acceptance: a check that reached PnP beats one that did not, whatever the counts.
  CHECK(cge::slam::choose_verification(
            {attempt(3, LoopReason::too_few_matches, 40), attempt(4, LoopReason::pose_not_robust, 12)}) == 1);
  // Same stage: the most matched points, the earliest on ties.
  CHECK(cge::slam::choose_verification({attempt(3, LoopReason::too_few_matches, 10),
                                        attempt(4, LoopReason::too_few_matches, 30),
                                        attempt(5, LoopReason::too_few_matches, 30)}) == 1);
  CHECK(cge::slam::choose_verification({attempt(7, LoopReason::too_few_matches, 0)}) == 0);
}

TEST_CASE("LoopCloserSettings: verified_members and min_group_total_ratio are checked", "[loops]") {
  cge::slam::LoopCloserSettings s;
  s.verified_members = 0;
  CHECK_THAT(cge_test::invalid_argument_message([&] { s.validate(); }), Catch::Contains("verified_members"));
  cge::slam::LoopCloserSettings r;
  r.min_group_total_ratio = 1.5;
  CHECK_THAT(cge_test::invalid_argument_message([&] { r.validate(); }), Catch::Contains("min_group_total_ratio"));
  r.min_group_total_ratio = -0.1;
  CHECK_THAT(cge_test::invalid_argument_message([&] { r.validate(); }), Catch::Contains("min_group_total_ratio"));
}

TEST_CASE("loops.csv reader: the extended format's columns", "[loops]") {
  const std::vector<LoopQuery> rows =
      read_loops_csv_text(kExtendedHeader +
                          "1.000000,,3,,,,0,0,no_candidates,0,0,\n"
                          "2.000000,0.500000,4,1,0.5,0.9,12,0,too_few_matches,12,3,0 2 3\n"
                          "3.000000,0.600000,5,2,0.6,0.9,88,1,accepted,120,1,4\n");
  REQUIRE(rows.size() == 3);
  CHECK(*rows[0].tentative_matches == 0);
  CHECK(*rows[0].verified_keyframes == 0);
  CHECK(rows[0].connected_keyframes->empty());
  CHECK(*rows[1].tentative_matches == 12);
  CHECK(*rows[1].verified_keyframes == 3);
  CHECK(*rows[1].connected_keyframes == std::vector<long long>{0, 2, 3});
  CHECK(*rows[2].connected_keyframes == std::vector<long long>{4});
  // The original format leaves the new fields empty.
  const std::vector<LoopQuery> old = read_loops_csv_text(
      "query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_points,accepted,"
      "reason\n1.000000,,3,,,,0,0,no_candidates\n");
  REQUIRE(old.size() == 1);
  CHECK_FALSE(old[0].tentative_matches.has_value());
  CHECK_FALSE(old[0].connected_keyframes.has_value());

  CHECK_THAT(loops_csv_error(kExtendedHeader + "1,,3,,,,0,0,no_candidates\n"),
             Catch::Contains("loops.csv:2: expected 12 comma-separated fields, found 9"));
  CHECK_THAT(loops_csv_error(kExtendedHeader + "1,,3,,,,0,0,no_candidates,,0,\n"),
             Catch::Contains("loops.csv:2: tentative_matches and verified_keyframes must not be empty"));
  CHECK_THAT(loops_csv_error(kExtendedHeader + "1,,3,,,,0,0,no_candidates,0,0,1 x\n"),
             Catch::Contains("loops.csv:2: connected_keyframes '1 x' is not a list"));
  CHECK_THAT(loops_csv_error(kExtendedHeader + "1,,3,,,,0,0,no_candidates,0,0,1  2\n"),
             Catch::Contains("loops.csv:2: connected_keyframes '1  2' is not a list"));
  CHECK_THAT(loops_csv_error(kExtendedHeader + "1,,3,,,,0,0,no_candidates,0,0,2 1\n"),
             Catch::Contains("loops.csv:2: connected_keyframes '2 1' is not strictly ascending"));
  CHECK_THAT(
      loops_csv_error("query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_"
                      "points,accepted,reason,tentative_matches\n"),
      Catch::Contains("loops.csv:1: expected the header"));
}

TEST_CASE("loop evaluation: misses by reason, connected and open loop queries (hand-worked)", "[loops]") {
  // Keyframes 0, 1, 2 at 1, 2, 3 s; 3 .. 7 at 10 .. 14 s. Ground truth: 10 s revisits 1 and 2 s;
  // 11 s revisits 2 s and 2.5 s (no keyframe); 12 s revisits 3 s; 13 s only 4.5 s (no keyframe);
  // 14 s revisits 1 and 3 s.
  const std::vector<GroundTruthLoop> gt = {gt_pair(10, 1), gt_pair(10, 2),   gt_pair(11, 2), gt_pair(11, 2.5),
                                           gt_pair(12, 3), gt_pair(13, 4.5), gt_pair(14, 1), gt_pair(14, 3)};
  const std::vector<LoopQuery> rows = {
      row(1, 0, "no_candidates", {}),
      row(2, 1, "no_candidates", {0}),
      row(3, 2, "no_candidates", {1}),
      row(10, 3, "accepted", {}, 1),               // correct; partners 0, 1 open
      row(11, 4, "too_few_matches", {1, 3}, 0.5),  // partner 1 (t 2) connected: a connected query
      row(12, 5, "continuity", {0, 1, 4}, 1),      // partner 2 (t 3) not connected: open, missed
      row(13, 6, "no_candidates", {5}),            // no keyframe partner
      row(14, 7, "accepted", {0}, 2),              // wrong match; partner 2 open: missed
  };
  const LoopEvaluation e = evaluate_loops(gt, rows);
  CHECK(e.loop_queries == 5);
  CHECK(e.detected_loop_queries == 1);
  CHECK(e.missed_by_reason == std::map<std::string, std::size_t>{
                                  {"accepted", 1}, {"continuity", 1}, {"no_candidates", 1}, {"too_few_matches", 1}});
  REQUIRE(e.has_connectivity);
  CHECK(e.loop_queries_without_keyframe_partner == 1);
  CHECK(e.connected_loop_queries == 1);
  CHECK(e.open_loop_queries == 3);
  CHECK(e.detected_open_loop_queries == 1);
  CHECK(e.open_query_recall == Approx(1.0 / 3));
  CHECK(e.missed_open_by_reason == std::map<std::string, std::size_t>{{"accepted", 1}, {"continuity", 1}});
  // The old figures are unchanged by the new ones.
  CHECK(e.query_recall == Approx(0.2));
  CHECK(e.precision == Approx(0.5));

  // Without the connected column: no connectivity figures, the breakdown by reason stays.
  std::vector<LoopQuery> plain = rows;
  for (LoopQuery& r : plain) r.connected_keyframes.reset();
  const LoopEvaluation p = evaluate_loops(gt, plain);
  CHECK_FALSE(p.has_connectivity);
  CHECK(std::isnan(p.open_query_recall));
  CHECK(p.open_loop_queries == 0);
  CHECK(p.missed_by_reason == e.missed_by_reason);

  // A connected id that is no row's keyframe is refused.
  std::vector<LoopQuery> unknown = rows;
  unknown[4].connected_keyframes = std::vector<long long>{42};
  CHECK_THAT(cge_test::invalid_argument_message([&] { evaluate_loops(gt, unknown); }),
             Catch::Contains("connected keyframe 42"));
}

TEST_CASE("loop evaluation: open query recall of random logs agrees with a brute-force count", "[loops]") {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 200; ++trial) {
    // Frames k at 500 + k / 30 s; a random subset is queried (keyframe ids 0, 1, ... in order).
    const int frames = 50;
    auto stamp = [](int k) { return 500.0 + k / 30.0; };
    std::bernoulli_distribution coin(0.3), accept(0.4), right(0.5), connect(0.3), query(0.6);
    std::set<std::pair<int, int>> gt_set;
    std::vector<GroundTruthLoop> gt;
    for (int q = 1; q < frames; ++q) {
      for (int m = 0; m < q; ++m) {
        if (std::bernoulli_distribution(0.08)(rng)) {
          gt_set.insert({q, m});
          gt.push_back(gt_pair(stamp(q), stamp(m)));
        }
      }
    }
    std::vector<int> queried;  // frames; keyframe id = position
    std::map<int, long long> id_of;
    for (int k = 0; k < frames; ++k) {
      if (!query(rng)) continue;
      id_of[k] = static_cast<long long>(queried.size());
      queried.push_back(k);
    }
    std::vector<LoopQuery> rows;
    std::map<int, std::set<int>> connected;  // frame -> connected frames
    std::map<int, bool> detected;
    std::map<int, std::string> reason;
    const std::vector<std::string> reasons = {"no_candidates", "low_score", "continuity", "too_few_matches"};
    for (int k : queried) {
      std::vector<long long> ids;
      for (int j : queried) {
        if (j < k && connect(rng)) {
          connected[k].insert(j);
          ids.push_back(id_of[j]);
        }
      }
      LoopQuery r;
      r.query_timestamp_s = stamp(k);
      r.query_keyframe = id_of[k];
      r.connected_keyframes = ids;
      detected[k] = false;
      if (accept(rng)) {
        int m = std::uniform_int_distribution<int>(0, frames - 1)(rng);
        if (right(rng)) {
          for (const auto& p : gt_set) {
            if (p.first == k) m = p.second;
          }
        }
        r.accepted = true;
        r.reason = "accepted";
        r.match_timestamp_s = stamp(m);
        r.match_keyframe = 0;
        detected[k] = gt_set.count({k, m}) > 0;
      } else {
        r.reason = reasons[std::uniform_int_distribution<std::size_t>(0, reasons.size() - 1)(rng)];
      }
      reason[k] = r.reason;
      rows.push_back(r);
    }
    // Brute force over frame numbers.
    const std::set<int> queried_set(queried.begin(), queried.end());
    std::size_t loop_queries = 0, without = 0, connected_only = 0, open = 0, detected_open = 0;
    std::map<std::string, std::size_t> missed, missed_open;
    for (int k : queried) {
      std::vector<int> partners;
      bool loop = false;
      for (const auto& p : gt_set) {
        if (p.first != k) continue;
        loop = true;
        if (queried_set.count(p.second)) partners.push_back(p.second);
      }
      if (!loop) continue;
      ++loop_queries;
      if (!detected[k]) ++missed[reason[k]];
      const bool any_open =
          std::any_of(partners.begin(), partners.end(), [&](int m) { return connected[k].count(m) == 0; });
      if (partners.empty()) {
        ++without;
      } else if (!any_open) {
        ++connected_only;
      } else {
        ++open;
        if (detected[k]) ++detected_open;
        if (!detected[k]) ++missed_open[reason[k]];
      }
    }
    const LoopEvaluation e = evaluate_loops(gt, rows);
    INFO("trial " << trial);
    CHECK(e.loop_queries == loop_queries);
    CHECK(e.loop_queries_without_keyframe_partner == without);
    CHECK(e.connected_loop_queries == connected_only);
    CHECK(e.open_loop_queries == open);
    CHECK(e.detected_open_loop_queries == detected_open);
    CHECK(e.missed_by_reason == missed);
    CHECK(e.missed_open_by_reason == missed_open);
    if (open > 0) CHECK(e.open_query_recall == Approx(double(detected_open) / double(open)));
    if (open == 0) CHECK(std::isnan(e.open_query_recall));
  }
}

TEST_CASE("two_nearest_descriptors equals cv::BFMatcher's two nearest, ties included", "[loops]") {
  // Oracle: OpenCV's brute-force matcher. Few distinct byte values make equal distances common, so
  // the tie order (lower train index first) is exercised.
  std::mt19937 rng(31);
  for (const int train_rows : {0, 1, 2, 40, 300}) {
    CAPTURE(train_rows);
    cv::Mat query(60, 32, CV_8UC1), train(train_rows, 32, CV_8UC1);
    for (int r = 0; r < query.rows; ++r)
      for (int c = 0; c < 32; ++c) query.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(rng() % 4);
    for (int r = 0; r < train.rows; ++r)
      for (int c = 0; c < 32; ++c) train.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(rng() % 4);
    std::vector<std::vector<cv::DMatch>> expected;
    if (train_rows > 0) cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, train, expected, 2);
    const std::vector<std::vector<cv::DMatch>> got = cge::slam::two_nearest_descriptors(query, train);
    REQUIRE(got.size() == static_cast<std::size_t>(query.rows));
    for (int q = 0; q < query.rows; ++q) {
      CAPTURE(q);
      const auto& g = got[static_cast<std::size_t>(q)];
      REQUIRE(g.size() == static_cast<std::size_t>(std::min(train_rows, 2)));
      for (std::size_t k = 0; k < g.size(); ++k) {
        const cv::DMatch& e = expected[static_cast<std::size_t>(q)][k];
        CHECK(g[k].queryIdx == e.queryIdx);
        CHECK(g[k].trainIdx == e.trainIdx);
        CHECK(g[k].distance == e.distance);
      }
    }
  }
  CHECK_THROWS_AS(cge::slam::two_nearest_descriptors(cv::Mat::zeros(2, 16, CV_8UC1), cv::Mat::zeros(2, 32, CV_8UC1)),
                  std::invalid_argument);
}

TEST_CASE("two_nearest_descriptors: the POPCNT row scan finds what the portable one finds", "[loops]") {
  // Oracle: the portable scan (itself checked against cv::BFMatcher above, through whichever scan
  // this CPU runs). Full-range bytes give distances across 0 .. 256; the few-values rows give ties.
  if (!cge::slam::detail::nearest_two_popcnt_supported()) {
    WARN("this CPU has no POPCNT: only the portable scan runs here");
    return;
  }
#if CGE_NEAREST_TWO_HAVE_POPCNT
  std::mt19937 rng(32);
  for (const int values : {256, 3}) {
    CAPTURE(values);
    cv::Mat query(50, 32, CV_8UC1), train(500, 32, CV_8UC1);
    for (cv::Mat* m : {&query, &train})
      for (int r = 0; r < m->rows; ++r)
        for (int c = 0; c < 32; ++c) m->at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(rng() % values);
    for (int q = 0; q < query.rows; ++q) {
      CAPTURE(q);
      for (const int rows : {0, 1, 2, 500}) {
        const cv::Mat head = train.rowRange(0, rows);
        const cge::slam::NearestTwo portable = cge::slam::detail::nearest_two_rows_portable(query.ptr<std::uint8_t>(q), head);
        const cge::slam::NearestTwo popcnt = cge::slam::detail::nearest_two_rows_popcnt(query.ptr<std::uint8_t>(q), head);
        CHECK(popcnt.best == portable.best);
        CHECK(popcnt.best_index == portable.best_index);
        CHECK(popcnt.second == portable.second);
        CHECK(popcnt.second_index == portable.second_index);
      }
    }
  }
#endif
}
