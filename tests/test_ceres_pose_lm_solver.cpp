// PoseLMSolver (cge/ceres/pose_lm_solver.hpp), the pose refiner's own Levenberg-Marquardt backend.
// Oracles: the cost's gradient by central differences of a cost written here (zero at the solver's
// optimum, Huber included), the truth of noise-free data, Ceres' optimum of the same refinement
// (PoseRefiner on both backends), and the iteration and failure contract.
#include "cge/ceres/pose_refinement.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "ceres_test_scene.hpp"

namespace {

using cge::PoseLMObservation;
using cge::PoseLMSolver;
using cge::SchurLMSummary;
using cge::SE3Block;
using cge_test::tight;

struct Scene {
  cge::PinholeIntrinsics<double> K;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  std::vector<PoseLMObservation> observations;
};

/// n observations of random visible points; every other one carries depth (sigma 2 cm), the rest
/// pixels only. `pixel_noise` in sigma units; `outlier_every` > 0 moves every such one 40 sigma off.
Scene make_scene(std::mt19937& rng, int n, double pixel_noise, int outlier_every) {
  Scene s;
  s.T_world_camera = cge_test::random_pose(rng);
  const Eigen::Isometry3d T_camera_world = s.T_world_camera.inverse();
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    PoseLMObservation o;
    o.point_world_m = cge_test::random_visible_point(rng, s.K, s.T_world_camera);
    const Eigen::Vector3d p = T_camera_world * o.point_world_m;
    o.inv_sigma_px = 1.0 / std::pow(1.2, std::uniform_int_distribution<int>(0, 7)(rng));
    o.pixel_px = s.K.project(p) + pixel_noise / o.inv_sigma_px * Eigen::Vector2d(noise(rng), noise(rng));
    if (i % 2 == 0) {
      o.depth_m = p.z() + 0.02 * pixel_noise * noise(rng);
      o.inv_sigma_depth = 1.0 / 0.02;
    }
    if (outlier_every > 0 && i % outlier_every == 0) o.pixel_px += Eigen::Vector2d(40, -30) / o.inv_sigma_px;
    s.observations.push_back(o);
  }
  return s;
}

/// 0.5 * sum of Huber(|r|^2) (delta <= 0: plain), written from the definitions, independent of the solver.
double oracle_cost(const Scene& s, const Eigen::Isometry3d& T_camera_world, double delta) {
  double cost = 0;
  for (const PoseLMObservation& o : s.observations) {
    const Eigen::Vector3d p = T_camera_world * o.point_world_m;
    const Eigen::Vector2d e = (s.K.project(p) - o.pixel_px) * o.inv_sigma_px;
    const double ez = (p.z() - o.depth_m) * o.inv_sigma_depth;
    const double sq = e.squaredNorm() + ez * ez;
    cost += (delta <= 0 || sq <= delta * delta) ? sq : 2 * delta * std::sqrt(sq) - delta * delta;
  }
  return 0.5 * cost;
}

/// Largest central-difference derivative of oracle_cost over the pose's 6 tangent directions
/// (rotation left-multiplied, translation added).
double gradient_max_norm(const Scene& s, const Eigen::Isometry3d& T, double delta) {
  const double h = 1e-6;
  double worst = 0;
  for (int a = 0; a < 6; ++a) {
    const double plus = oracle_cost(s, cge_test::tangent_step(T, a, h), delta);
    const double minus = oracle_cost(s, cge_test::tangent_step(T, a, -h), delta);
    worst = std::max(worst, std::abs(plus - minus) / (2 * h));
  }
  return worst;
}

}  // namespace

TEST_CASE("PoseLMSolver: at its optimum the finite-difference gradient of the cost vanishes", "[ceres][pose_lm]") {
  const double delta = GENERATE(0.0, 2.4477);  // plain least squares and the Huber round
  CAPTURE(delta);
  std::mt19937 rng(61);
  const Scene s = make_scene(rng, 150, 1.0, delta > 0 ? 9 : 0);
  const Eigen::Isometry3d truth = s.T_world_camera.inverse();
  const Eigen::Isometry3d start = cge_test::random_motion(rng, 0.02, 0.05) * truth;
  SE3Block pose = SE3Block::from_isometry(start);
  const double start_cost = oracle_cost(s, start, delta);

  // No cost-change tolerance: with Huber weights the last steps change a cost of 2e3 by less than
  // 1e-14 of it while the gradient is still 1e-3; the step and gradient tolerances stop it.
  cge::CeresSolverSettings solver = tight(100);
  solver.function_tolerance = 0;
  const SchurLMSummary summary = PoseLMSolver(s.K, solver, delta, 1e-6).solve(pose, s.observations, 100);
  CHECK(summary.termination == SchurLMSummary::Termination::converged);
  CHECK(summary.iterations > 2);
  CHECK(summary.initial_cost == Approx(start_cost).epsilon(1e-12));
  CHECK(summary.final_cost == Approx(oracle_cost(s, pose.to_isometry(), delta)).epsilon(1e-12));
  CHECK(summary.final_cost <= oracle_cost(s, truth, delta));  // the noisy data's optimum fits at least as well
  CHECK(gradient_max_norm(s, start, delta) > 1e3);
  // Central differences with h = 1e-6 on a cost of order 1e2 are good to about 1e-5.
  CAPTURE(summary.iterations, summary.final_cost);
  CHECK(gradient_max_norm(s, pose.to_isometry(), delta) < 1e-3);
}

TEST_CASE("PoseLMSolver: noise-free data from a perturbed start give back the truth, with and without depth",
          "[ceres][pose_lm]") {
  const bool with_depth = GENERATE(true, false);
  CAPTURE(with_depth);
  std::mt19937 rng(62);
  Scene s = make_scene(rng, 60, 0.0, 0);
  if (!with_depth)
    for (PoseLMObservation& o : s.observations) o.inv_sigma_depth = 0.0;
  const Eigen::Isometry3d truth = s.T_world_camera.inverse();
  for (int trial = 0; trial < 5; ++trial) {
    CAPTURE(trial);
    SE3Block pose = SE3Block::from_isometry(cge_test::random_motion(rng, 0.1, 0.15) * truth);
    const SchurLMSummary summary = PoseLMSolver(s.K, tight(100), 0.0, 1e-6).solve(pose, s.observations, 100);
    CHECK(summary.termination == SchurLMSummary::Termination::converged);
    CHECK(cge_test::rotation_error_rad(pose.to_isometry(), truth) < 1e-9);
    CHECK(cge_test::translation_error_m(pose.to_isometry(), truth) < 1e-9);
  }
}

TEST_CASE("PoseRefiner: the own backend reaches Ceres' optimum and inliers on noisy data with outliers",
          "[ceres][pose_lm]") {
  std::mt19937 rng(63);
  for (int trial = 0; trial < 5; ++trial) {
    CAPTURE(trial);
    const Scene s = make_scene(rng, 300, 1.0, 7);
    std::vector<cge::PoseObservation> observations;
    for (const PoseLMObservation& o : s.observations) {
      cge::PoseObservation p;
      p.point_world_m = o.point_world_m;
      p.pixel_px = o.pixel_px;
      p.sigma_px = 1.0 / o.inv_sigma_px;
      if (o.inv_sigma_depth != 0.0) {
        p.depth_m = o.depth_m;
        p.sigma_depth_m = 1.0 / o.inv_sigma_depth;
      }
      observations.push_back(p);
    }
    const Eigen::Isometry3d start = s.T_world_camera * cge_test::random_motion(rng, 0.03, 0.05);
    cge::PoseRefinementSettings settings;
    settings.solver = tight(50);
    settings.backend = cge::PoseRefinementBackend::pose_lm;
    const cge::PoseRefinementResult own = cge::PoseRefiner(settings).refine(s.K, observations, start);
    settings.backend = cge::PoseRefinementBackend::ceres;
    const cge::PoseRefinementResult ceres = cge::PoseRefiner(settings).refine(s.K, observations, start);
    CHECK(own.rounds == ceres.rounds);
    CHECK(own.inliers == ceres.inliers);
    CHECK(own.inlier_count < 300 - 300 / 7);  // the 43 outliers are out, and some noise
    CHECK(cge_test::rotation_error_rad(own.T_world_camera, ceres.T_world_camera) < 1e-9);
    CHECK(cge_test::translation_error_m(own.T_world_camera, ceres.T_world_camera) < 1e-9);
    CHECK(own.final_cost == Approx(ceres.final_cost).epsilon(1e-9));
    CHECK(own.converged);
  }
}

TEST_CASE("PoseLMSolver: the iteration limit, and a start with a point behind the camera, are reported",
          "[ceres][pose_lm]") {
  std::mt19937 rng(64);
  Scene s = make_scene(rng, 50, 1.0, 0);
  const Eigen::Isometry3d start = cge_test::random_motion(rng, 0.03, 0.05) * s.T_world_camera.inverse();
  cge::CeresSolverSettings no_tolerance = tight(100);
  no_tolerance.function_tolerance = no_tolerance.gradient_tolerance = no_tolerance.parameter_tolerance = 0;
  const PoseLMSolver solver(s.K, no_tolerance, 0.0, 1e-6);
  SE3Block limited = SE3Block::from_isometry(start);
  const SchurLMSummary summary = solver.solve(limited, s.observations, 2);
  CHECK(summary.iterations == 2);
  CHECK(summary.termination == SchurLMSummary::Termination::iteration_limit);
  CHECK(summary.final_cost < summary.initial_cost);

  // A point behind the camera at the start: the pose is not touched.
  s.observations[3].point_world_m = start.inverse() * Eigen::Vector3d(0, 0, -2);
  SE3Block behind = SE3Block::from_isometry(start);
  const SE3Block before = behind;
  const SchurLMSummary failed = solver.solve(behind, s.observations, 10);
  CHECK(failed.termination == SchurLMSummary::Termination::failure);
  CHECK(failed.iterations == 0);
  CHECK(behind.q_xyzw == before.q_xyzw);
  CHECK(behind.t == before.t);
}
