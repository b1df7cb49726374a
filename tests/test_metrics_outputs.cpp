// The evaluation outputs the results suite plots: the loop P-R curve over an acceptance threshold
// (cge/metrics/loop_threshold_curve.hpp) against hand-worked values, and the aligned ATE pairs
// (cge/metrics/ate_aligned_pairs.hpp) against a known rigid transform and the ATE's own RMSE.

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cge/metrics/ate_aligned_pairs.hpp"
#include "cge/metrics/loop_threshold_curve.hpp"

using namespace cge::metrics;

namespace {

GroundTruthLoop gt_pair(double query_s, double match_s) {
  GroundTruthLoop l;
  l.query_timestamp_s = query_s;
  l.match_timestamp_s = match_s;
  return l;
}

LoopQuery accepted_row(double query_s, double match_s, double cge, double bow) {
  LoopQuery q;
  q.query_timestamp_s = query_s;
  q.match_timestamp_s = match_s;
  q.match_keyframe = 0;
  q.cge_score = cge;
  q.bow_score = bow;
  q.accepted = true;
  q.reason = "accepted";
  return q;
}

LoopQuery rejected_row(double query_s) {
  LoopQuery q;
  q.query_timestamp_s = query_s;
  q.reason = "no_candidates";
  return q;
}

// Ground truth: 10, 11, 12 s revisit 1 and 2 s; 17 and 18 s revisit 5 s (two revisit events, since
// 14 s is queried in between and has no loop). Accepted: 10 (correct), 11 (wrong match),
// 12 (correct), 14 (no loop there), 17 (correct); cge scores tie at 0.6. The same log is
// tests/cli/eval/loops.txt and loops_curve.csv.
const std::vector<GroundTruthLoop> kGroundTruth = {gt_pair(10, 1), gt_pair(10, 2), gt_pair(11, 1), gt_pair(11, 2),
                                                   gt_pair(12, 2), gt_pair(17, 5), gt_pair(18, 5)};
const std::vector<LoopQuery> kRows = {rejected_row(4),
                                      accepted_row(10.0004, 1.0005, 0.8, 0.9),
                                      accepted_row(11, 3, 0.6, 0.7),
                                      accepted_row(12, 2, 0.6, 0.4),
                                      accepted_row(14, 2, 0.7, 0.8),
                                      accepted_row(17, 5, 0.9, 0.3),
                                      rejected_row(18),
                                      rejected_row(20)};

struct Expected {
  double threshold;
  std::size_t detections, correct;
  double precision, query_recall, event_recall;
};

void check_curve(const std::vector<LoopCurvePoint>& curve, const std::vector<Expected>& expected) {
  REQUIRE(curve.size() == expected.size());
  for (std::size_t i = 0; i < curve.size(); ++i) {
    INFO("point " << i << ", threshold " << expected[i].threshold);
    const LoopEvaluation& e = curve[i].evaluation;
    CHECK(curve[i].threshold == expected[i].threshold);
    CHECK(e.detections == expected[i].detections);
    CHECK(e.correct_detections == expected[i].correct);
    CHECK(e.precision == Approx(expected[i].precision));
    CHECK(e.query_recall == Approx(expected[i].query_recall));
    CHECK(e.event_recall == Approx(expected[i].event_recall));
    CHECK(e.loop_queries == 5);  // the denominators do not move with the threshold
    CHECK(e.loop_events == 2);
    CHECK(e.queried_keyframes == 8);
  }
}

}  // namespace

TEST_CASE("loop threshold curve: hand-worked points on cge_score and bow_score", "[metrics][loopcurve]") {
  const double inf = std::numeric_limits<double>::infinity();
  // cge: -inf and 0.6 keep all 5 (3 correct: 10, 12, 17); 0.7 keeps 10, 14, 17; 0.8 keeps 10, 17;
  // 0.9 keeps 17 (the second event alone).
  check_curve(loop_threshold_curve(kGroundTruth, kRows, LoopScoreColumn::cge_score), {{-inf, 5, 3, 0.6, 0.6, 1.0},
                                                                                      {0.6, 5, 3, 0.6, 0.6, 1.0},
                                                                                      {0.7, 3, 2, 2.0 / 3, 0.4, 1.0},
                                                                                      {0.8, 2, 2, 1.0, 0.4, 1.0},
                                                                                      {0.9, 1, 1, 1.0, 0.2, 0.5}});
  // bow: 0.4 drops 17; 0.7 keeps 10, 11, 14; 0.8 keeps 10, 14; 0.9 keeps 10.
  check_curve(loop_threshold_curve(kGroundTruth, kRows, LoopScoreColumn::bow_score), {{-inf, 5, 3, 0.6, 0.6, 1.0},
                                                                                      {0.3, 5, 3, 0.6, 0.6, 1.0},
                                                                                      {0.4, 4, 2, 0.5, 0.4, 0.5},
                                                                                      {0.7, 3, 1, 1.0 / 3, 0.2, 0.5},
                                                                                      {0.8, 2, 1, 0.5, 0.2, 0.5},
                                                                                      {0.9, 1, 1, 1.0, 0.2, 0.5}});
}

TEST_CASE("loop threshold: a gate between scores, above every score, and bad rows", "[metrics][loopcurve]") {
  // 0.65 on cge keeps what 0.7 keeps (scores are 0.6, 0.7, 0.8, 0.9).
  const LoopEvaluation between =
      evaluate_loops(kGroundTruth, apply_score_threshold(kRows, LoopScoreColumn::cge_score, 0.65));
  CHECK(between.detections == 3);
  CHECK(between.correct_detections == 2);
  const std::vector<LoopQuery> none = apply_score_threshold(kRows, LoopScoreColumn::cge_score, 0.95);
  const LoopEvaluation above = evaluate_loops(kGroundTruth, none);
  CHECK(above.detections == 0);
  CHECK(std::isnan(above.precision));
  CHECK(above.query_recall == 0);
  CHECK(none[1].reason == "below_threshold");
  CHECK(none[0].reason == "no_candidates");  // rejected rows stay as they were

  // No accepted row: the curve is the -inf point alone.
  const std::vector<LoopQuery> rejected = {rejected_row(10), rejected_row(11)};
  const std::vector<LoopCurvePoint> flat = loop_threshold_curve(kGroundTruth, rejected, LoopScoreColumn::cge_score);
  REQUIRE(flat.size() == 1);
  CHECK(flat[0].threshold == -std::numeric_limits<double>::infinity());
  CHECK(flat[0].evaluation.detections == 0);

  std::vector<LoopQuery> no_score = kRows;
  no_score[2].cge_score.reset();
  no_score[2].line = 4;
  CHECK_THROWS_WITH(apply_score_threshold(no_score, LoopScoreColumn::cge_score, 0.5),
                    Catch::Contains("line 4") && Catch::Contains("cge_score"));
  CHECK_NOTHROW(apply_score_threshold(no_score, LoopScoreColumn::bow_score, 0.5));
  CHECK_THROWS_AS(apply_score_threshold(kRows, LoopScoreColumn::cge_score, std::nan("")), std::invalid_argument);
  CHECK(parse_loop_score_column("bow_score") == LoopScoreColumn::bow_score);
  CHECK_THROWS_WITH(parse_loop_score_column("S_sum"), Catch::Contains("bow_score or cge_score"));
}

namespace {

Trajectory helix(std::size_t n) {
  Trajectory t(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = 0.1 * static_cast<double>(i);
    t[i].timestamp_s = 100 + s;
    t[i].T_world_camera.translation() = Eigen::Vector3d(std::cos(s), std::sin(s), 0.2 * s);
  }
  return t;
}

Eigen::Isometry3d known_transform() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  T.translation() = Eigen::Vector3d(4, -1, 2.5);
  return T;
}

/// The CSV's rows as numbers (8 columns), after checking its header.
std::vector<std::vector<double>> parse_aligned_csv(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  CHECK(line == "timestamp,gt_x,gt_y,gt_z,est_x,est_y,est_z,error_m");
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) row.push_back(std::stod(field));
    REQUIRE(row.size() == 8);
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

TEST_CASE("ATE aligned pairs: a rigid copy of the ground truth lands on it", "[metrics][alignedout]") {
  const Trajectory gt = helix(40);
  const Eigen::Isometry3d T = known_transform();
  Trajectory est = gt;
  for (StampedPose& p : est) p.T_world_camera = T * p.T_world_camera;
  est.erase(est.begin() + 5);  // an unmatched ground-truth pose: no row
  const AteResult r = compute_ate(gt, est);
  const std::vector<AlignedPair> pairs = aligned_pairs(gt, est, r);
  REQUIRE(pairs.size() == 39);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::size_t g = i < 5 ? i : i + 1;
    CHECK(pairs[i].timestamp_s == gt[g].timestamp_s);
    CHECK((pairs[i].groundtruth_m - gt[g].T_world_camera.translation()).norm() == 0);
    CHECK((pairs[i].estimate_m - gt[g].T_world_camera.translation()).norm() < 1e-9);
    CHECK(pairs[i].error_m < 1e-9);
  }
  std::ostringstream csv;
  write_aligned_pairs_csv(csv, pairs);
  const auto rows = parse_aligned_csv(csv.str());
  REQUIRE(rows.size() == 39);
  for (const auto& row : rows) {
    for (int k = 0; k < 3; ++k)
      CHECK(std::abs(row[static_cast<std::size_t>(4 + k)] - row[static_cast<std::size_t>(1 + k)]) < 1e-9);
  }
  CHECK_THROWS_AS(aligned_pairs(helix(3), est, r), std::invalid_argument);
}

TEST_CASE("ATE aligned pairs: the RMSE of error_m is the ATE RMSE, each error the distance of its row",
          "[metrics][alignedout]") {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.05);
  const Trajectory gt = helix(60);
  const Eigen::Isometry3d T = known_transform();
  Trajectory est = gt;
  for (StampedPose& p : est) {
    const Eigen::Vector3d noisy = p.T_world_camera.translation() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    p.T_world_camera.translation() = T * noisy;
    p.timestamp_s += 0.005;  // associated within 0.02 s
  }
  const AteResult r = compute_ate(gt, est);
  std::ostringstream csv;
  write_aligned_pairs_csv(csv, aligned_pairs(gt, est, r));
  const auto rows = parse_aligned_csv(csv.str());
  REQUIRE(rows.size() == 60);
  double sum_sq = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& row = rows[i];
    const double dx = row[4] - row[1], dy = row[5] - row[2], dz = row[6] - row[3];
    CHECK(row[7] == Approx(std::sqrt(dx * dx + dy * dy + dz * dz)).epsilon(1e-9));
    CHECK(row[0] == Approx(gt[i].timestamp_s).margin(5e-7));  // the ground-truth stamp, 6 decimals
    sum_sq += row[7] * row[7];
  }
  const double rmse = std::sqrt(sum_sq / static_cast<double>(rows.size()));
  CHECK(r.translation_m.rmse > 0.03);  // the noise is not aligned away
  CHECK(rmse == Approx(r.translation_m.rmse).epsilon(1e-12));
}
