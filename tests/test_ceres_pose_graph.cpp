// PoseGraphOptimiser and propagate_pose_correction (cge/ceres/pose_graph.hpp). Oracles: a graph
// whose edges are consistent with known poses has those poses as its zero-cost optimum; with exact
// rotations and dominant rotation weights the translation part is a linear least-squares problem,
// solved here independently with a dense QR; the correction helper is checked against its
// defining property (relative poses to the current keyframe unchanged).
#include "cge/ceres/pose_graph.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "ceres_test_scene.hpp"

namespace {

using cge::PoseGraphEdge;
using cge::PoseGraphOptimiser;
using cge::PoseGraphResult;
using cge_test::random_motion;
using cge_test::rotation_error_rad;
using cge_test::translation_error_m;

PoseGraphEdge exact_edge(const std::vector<Eigen::Isometry3d>& poses, int a, int b) {
  return PoseGraphEdge::weighted(a, b, poses[a].inverse() * poses[b], 1.0, 1.0);
}

/// A trajectory of n poses walking around a loop: each a random small motion from the previous.
std::vector<Eigen::Isometry3d> random_trajectory(std::mt19937& rng, int n) {
  std::vector<Eigen::Isometry3d> poses{cge_test::random_pose(rng)};
  for (int i = 1; i < n; ++i) poses.push_back(poses.back() * random_motion(rng, 0.2, 0.3));
  return poses;
}

}  // namespace

TEST_CASE("PoseGraphOptimiser recovers consistent poses exactly from perturbed starts", "[ceres]") {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 5; ++trial) {
    const int n = 12;
    const std::vector<Eigen::Isometry3d> truth = random_trajectory(rng, n);
    std::vector<PoseGraphEdge> edges;
    for (int i = 0; i + 1 < n; ++i) edges.push_back(exact_edge(truth, i, i + 1));     // sequential
    for (int i = 0; i + 3 < n; i += 2) edges.push_back(exact_edge(truth, i, i + 3));  // covisibility
    edges.push_back(exact_edge(truth, n - 1, 0));                                     // loop
    std::vector<Eigen::Isometry3d> start = truth;
    for (int i = 1; i < n; ++i) start[i] = truth[i] * random_motion(rng, 0.1, 0.1);
    const PoseGraphResult r = PoseGraphOptimiser().optimise(start, edges);
    CAPTURE(trial);
    REQUIRE(r.T_world_camera.size() == truth.size());
    CHECK(cge_test::bit_identical(r.T_world_camera[0], truth[0]));  // the fixed node is returned as given
    for (int i = 0; i < n; ++i) {
      CHECK(rotation_error_rad(r.T_world_camera[i], truth[i]) < 1e-6);
      CHECK(translation_error_m(r.T_world_camera[i], truth[i]) < 1e-6);
    }
    CHECK(r.final_cost < 1e-12);
    CHECK(r.initial_cost > r.final_cost);
    CHECK(r.converged);
  }
}

TEST_CASE("PoseGraphOptimiser: a drifted square loop is corrected as the linear least-squares oracle says", "[ceres]") {
  // A 2 m square walked in 8 steps of 1 m with a 90 degree turn at each corner; odometry reads every
  // step 2 cm long, 6 cm left and 3 cm down (exact rotations), the loop edge (7 -> 0) is exact.
  const int n = 8;
  std::vector<Eigen::Isometry3d> truth(n, Eigen::Isometry3d::Identity());
  for (int i = 1; i < n; ++i) {
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    step.translation() = Eigen::Vector3d(1, 0, 0);
    if (i % 2 == 0) step.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    truth[i] = truth[i - 1] * step;
  }
  const double rotation_weight = 1e8, translation_weight = 1.0;  // rotations held, translations free
  std::vector<PoseGraphEdge> edges;
  std::vector<Eigen::Isometry3d> odometry(n, Eigen::Isometry3d::Identity());
  for (int i = 0; i + 1 < n; ++i) {
    Eigen::Isometry3d measured = truth[i].inverse() * truth[i + 1];
    measured.translation() += Eigen::Vector3d(0.02, 0.06, 0.03);
    edges.push_back(PoseGraphEdge::weighted(i, i + 1, measured, rotation_weight, translation_weight));
    odometry[i + 1] = odometry[i] * measured;  // the drifted start: chained odometry
  }
  edges.push_back(
      PoseGraphEdge::weighted(n - 1, 0, truth[n - 1].inverse() * truth[0], rotation_weight, translation_weight));

  // Oracle: with R_i fixed at the truth, minimise sum |t_b - t_a - R_a t_ab|^2 over t_1..t_{n-1}, t_0 = 0.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * static_cast<int>(edges.size()), 3 * (n - 1));
  Eigen::VectorXd y = Eigen::VectorXd::Zero(A.rows());
  for (int k = 0; k < static_cast<int>(edges.size()); ++k) {
    const PoseGraphEdge& e = edges[k];
    if (e.to > 0) A.block<3, 3>(3 * k, 3 * (e.to - 1)) += Eigen::Matrix3d::Identity();
    if (e.from > 0) A.block<3, 3>(3 * k, 3 * (e.from - 1)) -= Eigen::Matrix3d::Identity();
    y.segment<3>(3 * k) = truth[e.from].linear() * e.T_from_to.translation();
  }
  const Eigen::VectorXd t_oracle = A.colPivHouseholderQr().solve(y);

  const PoseGraphResult r = PoseGraphOptimiser().optimise(odometry, edges);
  double drift_before = 0, drift_after = 0;
  for (int i = 1; i < n; ++i) {
    CAPTURE(i);
    CHECK((r.T_world_camera[i].translation() - t_oracle.segment<3>(3 * (i - 1))).norm() < 1e-6);
    CHECK(rotation_error_rad(r.T_world_camera[i], truth[i]) < 1e-6);
    drift_before = std::max(drift_before, translation_error_m(odometry[i], truth[i]));
    drift_after = std::max(drift_after, translation_error_m(r.T_world_camera[i], truth[i]));
  }
  // The loop edge spreads the accumulated drift over the loop: the worst error falls, and the last
  // keyframe (where the drift had accumulated, next to the exact loop edge) comes much closer.
  CHECK(drift_after < drift_before);
  const double last_before = translation_error_m(odometry[n - 1], truth[n - 1]);
  const double last_after = translation_error_m(r.T_world_camera[n - 1], truth[n - 1]);
  CHECK(last_after < 0.5 * last_before);
}

TEST_CASE("PoseGraphOptimiser honours several fixed nodes and information weights", "[ceres]") {
  std::mt19937 rng(22);
  const std::vector<Eigen::Isometry3d> truth = random_trajectory(rng, 3);
  // Two conflicting measurements of the same edge 0 -> 1 with weights 1 and 3: on translation alone
  // (rotations exact, node 0 fixed) the optimum is the weighted mean of the two.
  Eigen::Isometry3d m1 = truth[0].inverse() * truth[1], m2 = m1;
  m1.translation() += Eigen::Vector3d(0.4, 0, 0);
  m2.translation() -= Eigen::Vector3d(0, 0.4, 0);
  std::vector<PoseGraphEdge> edges{PoseGraphEdge::weighted(0, 1, m1, 1e8, 1.0),
                                   PoseGraphEdge::weighted(0, 1, m2, 1e8, 3.0), exact_edge(truth, 1, 2)};
  std::vector<Eigen::Isometry3d> start = truth;
  start[2] = truth[2] * random_motion(rng, 0.1, 0.1);
  const PoseGraphResult r = PoseGraphOptimiser().optimise(start, edges, {0, 2});
  const Eigen::Vector3d expected = truth[0] * ((1.0 * m1.translation() + 3.0 * m2.translation()) / 4.0);
  // Node 2 is fixed at a wrong pose, so edge 1 -> 2 pulls too; check only what the oracle covers
  // when that edge is removed.
  CHECK(cge_test::bit_identical(r.T_world_camera[2], start[2]));
  edges.pop_back();
  const PoseGraphResult r2 = PoseGraphOptimiser().optimise(start, edges, {0, 2});
  CHECK((r2.T_world_camera[1].translation() - expected).norm() < 1e-6);
  CHECK(rotation_error_rad(r2.T_world_camera[1], truth[1]) < 1e-6);
}

TEST_CASE("PoseGraphOptimiser is deterministic: two runs give bit-identical poses", "[ceres]") {
  std::mt19937 rng(23);
  const int n = 40;
  const std::vector<Eigen::Isometry3d> truth = random_trajectory(rng, n);
  std::vector<PoseGraphEdge> edges;
  for (int i = 0; i + 1 < n; ++i) {
    Eigen::Isometry3d m = truth[i].inverse() * truth[i + 1] * random_motion(rng, 0.01, 0.02);  // noisy
    edges.push_back(PoseGraphEdge::weighted(i, i + 1, m, 100.0, 10.0));
  }
  edges.push_back(exact_edge(truth, n - 1, 0));
  std::vector<Eigen::Isometry3d> start{truth[0]};
  for (int i = 0; i + 1 < n; ++i) start.push_back(start.back() * edges[i].T_from_to);
  const PoseGraphResult a = PoseGraphOptimiser().optimise(start, edges);
  const PoseGraphResult b = PoseGraphOptimiser().optimise(start, edges);
  for (int i = 0; i < n; ++i) CHECK(cge_test::bit_identical(a.T_world_camera[i], b.T_world_camera[i]));
  CHECK(a.final_cost == b.final_cost);
  CHECK(a.final_cost < a.initial_cost);
}

TEST_CASE("PoseGraphOptimiser rejects invalid input with a message naming it", "[ceres]") {
  std::mt19937 rng(24);
  const std::vector<Eigen::Isometry3d> poses = random_trajectory(rng, 4);
  const std::vector<PoseGraphEdge> good{exact_edge(poses, 0, 1), exact_edge(poses, 1, 2), exact_edge(poses, 2, 3)};
  const PoseGraphOptimiser opt;
  auto edges = good;
  edges[1].to = 4;
  CHECK_THROWS_WITH(opt.optimise(poses, edges), Catch::Contains("edge 1: node index out of range"));
  edges = good;
  edges[2].to = 2;
  CHECK_THROWS_WITH(opt.optimise(poses, edges), Catch::Contains("edge 2: joins node 2 to itself"));
  edges = good;
  edges[0].information(3, 3) = -1;
  CHECK_THROWS_WITH(opt.optimise(poses, edges), Catch::Contains("edge 0: information must be positive definite"));
  edges = good;
  edges[0].information(0, 5) = 0.5;
  CHECK_THROWS_WITH(opt.optimise(poses, edges), Catch::Contains("symmetric"));
  edges = good;
  edges[1].T_from_to.translation().z() = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(opt.optimise(poses, edges), Catch::Contains("edge 1: T_from_to"));
  auto bad_poses = poses;
  bad_poses[3].linear() *= 2.0;
  CHECK_THROWS_WITH(opt.optimise(bad_poses, good), Catch::Contains("pose 3"));
  CHECK_THROWS_WITH(opt.optimise(poses, good, {}), Catch::Contains("at least one fixed node"));
  CHECK_THROWS_WITH(opt.optimise(poses, good, {7}), Catch::Contains("fixed node 7 out of range"));
  cge::PoseGraphSettings bad;
  bad.huber_delta = -1;
  CHECK_THROWS_WITH(PoseGraphOptimiser(bad).optimise(poses, good), Catch::Contains("huber_delta"));
}

TEST_CASE("propagate_pose_correction moves connected keyframes rigidly with the current one", "[ceres]") {
  std::mt19937 rng(25);
  std::vector<Eigen::Isometry3d> poses = random_trajectory(rng, 6);
  const std::vector<Eigen::Isometry3d> before = poses;
  const Eigen::Isometry3d corrected = poses[4] * random_motion(rng, 0.3, 0.5);
  cge::propagate_pose_correction(poses, 4, corrected, {2, 3, 5});
  CHECK(poses[4].isApprox(corrected, 1e-12));
  for (int i : {2, 3, 5}) {  // relative pose to the current keyframe unchanged
    const Eigen::Isometry3d rel_before = before[4].inverse() * before[i];
    const Eigen::Isometry3d rel_after = poses[4].inverse() * poses[i];
    CHECK(rel_after.isApprox(rel_before, 1e-9));
    CHECK_FALSE(poses[i].isApprox(before[i], 1e-3));
  }
  for (int i : {0, 1}) CHECK(cge_test::bit_identical(poses[i], before[i]));  // not connected: untouched
  CHECK_THROWS_WITH(cge::propagate_pose_correction(poses, 6, corrected, {}), Catch::Contains("out of range"));
  CHECK_THROWS_WITH(cge::propagate_pose_correction(poses, 1, corrected, {9}), Catch::Contains("connected keyframe 9"));
}
