// cge::run's figures of a SLAM run (cge/run/run_summary.hpp) and its loop report
// (cge/run/loop_report.hpp), each against values worked out by hand from hand-made records.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/run/loop_report.hpp"
#include "cge/run/run_summary.hpp"

namespace {

cge::slam::FrameRecord record(int moving, int kept) {
  cge::slam::FrameRecord r;
  r.moving_keypoints = moving;
  r.moving_kept = kept;
  return r;
}

Eigen::Isometry3d pose_at(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

}  // namespace

TEST_CASE("run summary: median of odd, even and empty lists", "[run][summary]") {
  CHECK(cge::run::median({}) == 0.0);
  CHECK(cge::run::median({7.0}) == 7.0);
  CHECK(cge::run::median({5.0, 1.0, 3.0}) == 3.0);
  CHECK(cge::run::median({4.0, 1.0, 10.0, 2.0}) == 3.0);  // (2 + 4) / 2
}

TEST_CASE("run summary: the dynamic leak counts only frames with ground truth", "[run][summary]") {
  // Frames without a moving mask carry -1 and do not count.
  const std::vector<cge::slam::FrameRecord> frames = {record(10, 2), record(-1, -1), record(0, 0), record(30, 1)};
  const cge::run::DynamicLeak leak = cge::run::dynamic_leak(frames);
  CHECK(leak.frames_with_ground_truth == 3);
  CHECK(leak.moving_keypoints == 40);
  CHECK(leak.moving_kept == 3);
  REQUIRE(leak.rate);
  CHECK(*leak.rate == 3.0 / 40.0);

  CHECK_FALSE(cge::run::dynamic_leak({record(-1, -1)}).rate);  // no ground truth
  const cge::run::DynamicLeak none_moving = cge::run::dynamic_leak({record(0, 0), record(0, 0)});
  CHECK(none_moving.frames_with_ground_truth == 2);
  CHECK_FALSE(none_moving.rate);  // no keypoint on a moving body: no rate
}

TEST_CASE("run summary: mean and median time per stage", "[run][summary]") {
  std::vector<cge::slam::FrameRecord> frames(4);
  const double tracking[4] = {4, 1, 10, 2};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    frames[i].times_ms[static_cast<std::size_t>(cge::slam::Stage::tracking)] = tracking[i];
    frames[i].times_ms[static_cast<std::size_t>(cge::slam::Stage::total)] = 10.0 * static_cast<double>(i + 1);
  }
  const auto stages = cge::run::stage_times(frames);
  const cge::run::StageTime& t = stages[static_cast<std::size_t>(cge::slam::Stage::tracking)];
  CHECK(t.mean_ms == 17.0 / 4.0);
  CHECK(t.median_ms == 3.0);
  const cge::run::StageTime& total = stages[static_cast<std::size_t>(cge::slam::Stage::total)];
  CHECK(total.mean_ms == 25.0);
  CHECK(total.median_ms == 25.0);
  const cge::run::StageTime& unused = stages[static_cast<std::size_t>(cge::slam::Stage::loop_closing)];
  CHECK(unused.mean_ms == 0.0);
  CHECK(unused.median_ms == 0.0);
  for (const cge::run::StageTime& s : cge::run::stage_times({})) {
    CHECK(s.mean_ms == 0.0);
    CHECK(s.median_ms == 0.0);
  }
}

TEST_CASE("run summary: ATE and RPE of a shifted copy, and the reason when nothing associates",
          "[run][summary]") {
  cge::run::GroundTruthPoses truth, estimate;
  for (int i = 0; i < 40; ++i) {
    const double t = 0.1 * i;
    truth.emplace_back(t, pose_at(0.05 * i, 0.01 * i * i, 0));
    estimate.emplace_back(t, pose_at(0.05 * i + 3, 0.01 * i * i - 1, 2));  // a rigid shift: aligned away
  }
  const cge::run::TrajectoryErrors e = cge::run::trajectory_errors(truth, estimate);
  REQUIRE(e.ate_m);
  CHECK(e.ate_m->count == 40);
  CHECK(e.ate_m->rmse < 1e-9);
  REQUIRE(e.rpe_translation_m);
  CHECK(e.rpe_translation_m->rmse < 1e-9);
  CHECK(e.rpe_rotation_deg->rmse < 1e-6);
  CHECK(e.rpe_delta_s == 1.0);

  cge::run::GroundTruthPoses later;
  for (const auto& p : estimate) later.emplace_back(p.first + 100, p.second);  // no stamp associates
  const cge::run::TrajectoryErrors none = cge::run::trajectory_errors(truth, later);
  CHECK_FALSE(none.ate_m);
  CHECK_FALSE(none.ate_error.empty());
  CHECK_FALSE(none.rpe_translation_m);
}

TEST_CASE("loop report: loops.txt reads back as written", "[run][loop_report]") {
  std::vector<cge::metrics::GroundTruthLoop> loops(2);
  loops[0] = {12.5, 1.25, 375, 37, 0};
  loops[1] = {13.0, 2.0, 390, 60, 0};
  std::ostringstream text;
  cge::run::write_ground_truth_loops(text, loops);
  CHECK(text.str().find("\n12.500000 1.250000 375 37\n13.000000 2.000000 390 60\n") != std::string::npos);
  std::istringstream in(text.str());
  const std::vector<cge::metrics::GroundTruthLoop> back = cge::metrics::read_ground_truth_loops(in, "loops.txt");
  REQUIRE(back.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(back[i].query_timestamp_s == loops[i].query_timestamp_s);
    CHECK(back[i].match_timestamp_s == loops[i].match_timestamp_s);
    CHECK(back[i].query_index == loops[i].query_index);
    CHECK(back[i].match_index == loops[i].match_index);
  }
}

TEST_CASE("loop report: accepted loops marked against the ground truth, with how far apart they were",
          "[run][loop_report]") {
  std::vector<cge::slam::LoopRecord> loops(3);
  loops[0].query_keyframe = 9;  // accepted and a ground-truth pair
  loops[0].query_timestamp_s = 5.0;
  loops[0].match_keyframe = 1;
  loops[0].match_timestamp_s = 1.0;
  loops[0].matched_points = 80;
  loops[0].accepted = true;
  loops[1] = loops[0];  // rejected: not reported
  loops[1].accepted = false;
  loops[1].query_timestamp_s = 6.0;
  loops[2] = loops[0];  // accepted, wrong, and one stamp without a pose
  loops[2].query_keyframe = 12;
  loops[2].query_timestamp_s = 7.0;
  loops[2].match_timestamp_s = 2.0;
  loops[2].match_keyframe = 3;
  loops[2].matched_points = 41;

  std::vector<cge::metrics::GroundTruthLoop> truth(1);
  truth[0].query_timestamp_s = 5.0;
  truth[0].match_timestamp_s = 1.0;
  // Query camera 0.3 m and 0.4 m away, its optical axis turned by 90 degrees about y.
  Eigen::Isometry3d turned = pose_at(0.3, 0.4, 0);
  turned.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const cge::run::GroundTruthPoses poses = {{1.0, pose_at(0, 0, 0)}, {5.0, turned}, {7.0, pose_at(1, 0, 0)}};

  cge::metrics::LoopEvaluation e;
  e.ground_truth_pairs = 1;
  e.correct_detections = 1;
  e.precision = 0.5;
  e.loop_queries = 1;
  e.query_recall = 1;
  e.loop_events = 0;
  e.event_recall = std::numeric_limits<double>::quiet_NaN();
  CHECK(cge::run::loop_evaluation_report(loops, truth, poses, e) ==
        "loop_accepted query 5.000000 match 1.000000 keyframes 9 1 inliers 80 correct ground_truth_apart 0.500 m "
        "90.0 deg\n"
        "loop_accepted query 7.000000 match 2.000000 keyframes 12 3 inliers 41 wrong\n"
        "loop_ground_truth_pairs 1\nloop_correct 1\nloop_precision 0.5\nloop_queries_with_loop 1\n"
        "loop_query_recall 1\nloop_events 0\nloop_event_recall nan\n");
  CHECK(cge::run::queried_stamps(loops) == std::set<std::string>{"5.000000", "6.000000", "7.000000"});
}
