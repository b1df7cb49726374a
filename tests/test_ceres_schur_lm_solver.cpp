// SchurLMSolver (cge/ceres/schur_lm_solver.hpp), the bundle adjuster's own Levenberg-Marquardt
// backend. Oracles: the cost's gradient by central differences of a cost written here (zero at the
// solver's optimum, Huber included), Ceres' optimum of the same problem (the BundleAdjuster tests
// run every case on both backends as well), the truth of noise-free data, and the iteration and
// failure contract.
#include "cge/ceres/bundle_adjustment.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "ceres_test_scene.hpp"

namespace {

using cge::SchurLMObservation;
using cge::SchurLMSolver;
using cge::SchurLMSummary;
using cge::SE3Block;
using cge_test::tight;
using cge_test::uniform;

struct Scene {
  cge::PinholeIntrinsics<double> K;
  std::vector<SE3Block> poses;  ///< T_camera_world
  std::vector<Eigen::Vector3d> points;
  std::vector<SchurLMObservation> observations;
};

/// Cameras along x looking at points 2..6 m ahead, every point seen by every camera that has it
/// in the image; half the observations carry depth (sigma 2 cm), the other half pixels only.
/// `pixel_noise` in sigma units; `outlier_every` > 0 moves every such observation 40 sigma off.
Scene make_scene(std::mt19937& rng, int cameras, int points, double pixel_noise, int outlier_every) {
  Scene s;
  std::vector<Eigen::Isometry3d> T_world_camera;
  for (int i = 0; i < cameras; ++i) {
    Eigen::Isometry3d T = cge_test::random_motion(rng, uniform(rng, 0, 0.06), 0.0);
    T.translation() = Eigen::Vector3d(0.25 * i, uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1));
    T_world_camera.push_back(T);
    s.poses.push_back(SE3Block::from_isometry(T.inverse()));
  }
  for (int j = 0; j < points; ++j)
    s.points.emplace_back(uniform(rng, -1.5, 0.25 * cameras + 1.5), uniform(rng, -1.2, 1.2), uniform(rng, 2, 6));
  std::normal_distribution<double> noise(0.0, 1.0);
  int n = 0;
  for (int i = 0; i < cameras; ++i) {
    for (int j = 0; j < points; ++j) {
      const Eigen::Vector3d p = T_world_camera[i].inverse() * s.points[j];
      const Eigen::Vector2d px = s.K.project(p);
      if (p.z() <= 0 || px.x() < 0 || px.x() > 640 || px.y() < 0 || px.y() > 480) continue;
      SchurLMObservation o;
      o.pose = i;
      o.point = j;
      o.inv_sigma_px = 1.0 / std::pow(1.2, std::uniform_int_distribution<int>(0, 3)(rng));
      o.pixel_px = px + pixel_noise / o.inv_sigma_px * Eigen::Vector2d(noise(rng), noise(rng));
      if (n % 2 == 0) {
        o.depth_m = p.z() + 0.02 * pixel_noise * noise(rng);
        o.inv_sigma_depth = 1.0 / 0.02;
      }
      if (outlier_every > 0 && n % outlier_every == 0) o.pixel_px += Eigen::Vector2d(40, -30) / o.inv_sigma_px;
      s.observations.push_back(o);
      ++n;
    }
  }
  return s;
}

/// Moves every pose but those fixed and every point a little off.
void perturb(std::mt19937& rng, Scene& s, const std::vector<bool>& fixed) {
  for (std::size_t i = 0; i < s.poses.size(); ++i) {
    if (fixed[i]) continue;
    const Eigen::Isometry3d T = cge_test::random_motion(rng, 0.01, 0.03) * s.poses[i].to_isometry();
    s.poses[i] = SE3Block::from_isometry(T);
  }
  for (Eigen::Vector3d& p : s.points) p += 0.05 * Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
}

/// 0.5 * sum of Huber(|r|^2) (delta <= 0: plain), written from the definitions, independent of the solver.
double oracle_cost(const Scene& s, const std::vector<Eigen::Isometry3d>& T_camera_world,
                   const std::vector<Eigen::Vector3d>& points, double delta) {
  double cost = 0;
  for (const SchurLMObservation& o : s.observations) {
    const Eigen::Vector3d p = T_camera_world[o.pose] * points[o.point];
    const Eigen::Vector2d e = (s.K.project(p) - o.pixel_px) * o.inv_sigma_px;
    const double ez = (p.z() - o.depth_m) * o.inv_sigma_depth;
    const double sq = e.squaredNorm() + ez * ez;
    cost += (delta <= 0 || sq <= delta * delta) ? sq : 2 * delta * std::sqrt(sq) - delta * delta;
  }
  return 0.5 * cost;
}

/// Largest central-difference derivative of oracle_cost over every free pose's 6 tangent
/// directions (rotation left-multiplied, translation added) and every point coordinate.
double gradient_max_norm(const Scene& s, const std::vector<bool>& fixed, double delta) {
  std::vector<Eigen::Isometry3d> T;
  for (const SE3Block& b : s.poses) T.push_back(b.to_isometry());
  std::vector<Eigen::Vector3d> X = s.points;
  const double h = 1e-6;
  double worst = 0;
  for (std::size_t i = 0; i < T.size(); ++i) {
    if (fixed[i]) continue;
    for (int a = 0; a < 6; ++a) {
      std::vector<Eigen::Isometry3d> Tp = T, Tm = T;
      Tp[i] = cge_test::tangent_step(T[i], a, h);
      Tm[i] = cge_test::tangent_step(T[i], a, -h);
      worst = std::max(worst, std::abs(oracle_cost(s, Tp, X, delta) - oracle_cost(s, Tm, X, delta)) / (2 * h));
    }
  }
  for (std::size_t j = 0; j < X.size(); ++j) {
    for (int a = 0; a < 3; ++a) {
      std::vector<Eigen::Vector3d> Xp = X, Xm = X;
      Xp[j](a) += h;
      Xm[j](a) -= h;
      worst = std::max(worst, std::abs(oracle_cost(s, T, Xp, delta) - oracle_cost(s, T, Xm, delta)) / (2 * h));
    }
  }
  return worst;
}

}  // namespace

TEST_CASE("SchurLMSolver: at its optimum the finite-difference gradient of the cost vanishes", "[ceres][schur_lm]") {
  const double delta = GENERATE(0.0, 2.4477);  // plain least squares and the Huber round
  CAPTURE(delta);
  std::mt19937 rng(51);
  Scene s = make_scene(rng, 5, 60, 1.0, delta > 0 ? 11 : 0);
  std::vector<Eigen::Isometry3d> T_truth;
  for (const SE3Block& b : s.poses) T_truth.push_back(b.to_isometry());
  const double truth_cost = oracle_cost(s, T_truth, s.points, delta);
  const std::vector<bool> fixed = {true, false, false, false, false};
  perturb(rng, s, fixed);
  const double start_gradient = gradient_max_norm(s, fixed, delta);
  std::vector<Eigen::Isometry3d> T_start;
  for (const SE3Block& b : s.poses) T_start.push_back(b.to_isometry());
  const double start_cost = oracle_cost(s, T_start, s.points, delta);

  SchurLMSolver solver(s.K, tight(200), delta, 1e-6);
  const SchurLMSummary summary = solver.solve(s.poses, fixed, s.points, s.observations, 200);
  CHECK(summary.termination == SchurLMSummary::Termination::converged);
  CHECK(summary.iterations > 2);
  CHECK(summary.initial_cost == Approx(start_cost).epsilon(1e-12));
  std::vector<Eigen::Isometry3d> T_end;
  for (const SE3Block& b : s.poses) T_end.push_back(b.to_isometry());
  CHECK(summary.final_cost == Approx(oracle_cost(s, T_end, s.points, delta)).epsilon(1e-12));
  CHECK(summary.final_cost <= truth_cost);  // the noisy data's optimum fits them at least as well
  CHECK(truth_cost < summary.initial_cost);
  CHECK(start_gradient > 1e4);
  // Central differences with h = 1e-6 on a cost of order 1e3 are good to about 1e-4.
  CHECK(gradient_max_norm(s, fixed, delta) < 1e-3);
  // The fixed pose is returned bit for bit.
  CHECK(cge_test::bit_identical(s.poses[0].to_isometry(), T_start[0]));
}

TEST_CASE("SchurLMSolver: noise-free data from a perturbed start gives back the truth, points alone too",
          "[ceres][schur_lm]") {
  const bool all_fixed = GENERATE(false, true);  // all fixed: a points-only problem (no reduced system)
  CAPTURE(all_fixed);
  std::mt19937 rng(52);
  Scene s = make_scene(rng, 4, 50, 0.0, 0);
  const Scene truth = s;
  const std::vector<bool> fixed = {true, all_fixed, all_fixed, all_fixed};
  perturb(rng, s, fixed);
  SchurLMSolver solver(s.K, tight(100), 0.0, 1e-6);
  const SchurLMSummary summary = solver.solve(s.poses, fixed, s.points, s.observations, 100);
  CHECK(summary.termination == SchurLMSummary::Termination::converged);
  for (std::size_t i = 0; i < s.poses.size(); ++i) {
    CAPTURE(i);
    CHECK(cge_test::rotation_error_rad(s.poses[i].to_isometry(), truth.poses[i].to_isometry()) < 1e-8);
    CHECK(cge_test::translation_error_m(s.poses[i].to_isometry(), truth.poses[i].to_isometry()) < 1e-8);
  }
  double worst = 0;
  for (std::size_t j = 0; j < s.points.size(); ++j) worst = std::max(worst, (s.points[j] - truth.points[j]).norm());
  CHECK(worst < 1e-8);
}

TEST_CASE("SchurLMSolver: the same optimum as Ceres on the bundle adjuster's rounds", "[ceres][schur_lm]") {
  std::mt19937 rng(53);
  const Scene s = make_scene(rng, 6, 80, 1.0, 13);
  Scene start = s;
  std::vector<bool> fixed(s.poses.size(), false);
  fixed[0] = true;
  perturb(rng, start, fixed);
  std::vector<Eigen::Isometry3d> T_world_camera;
  for (const SE3Block& b : start.poses) T_world_camera.push_back(b.to_isometry().inverse());
  std::vector<cge::BundleObservation> observations;
  for (const SchurLMObservation& o : s.observations) {
    cge::BundleObservation b;
    b.keyframe = o.pose;
    b.point = o.point;
    b.pixel_px = o.pixel_px;
    b.sigma_px = 1.0 / o.inv_sigma_px;
    if (o.inv_sigma_depth > 0) {
      b.depth_m = o.depth_m;
      b.sigma_depth_m = 1.0 / o.inv_sigma_depth;
    }
    observations.push_back(b);
  }
  cge::BundleAdjustmentSettings settings;  // two rounds, Huber in the first, outliers out of the second
  settings.solver = tight(100);
  const cge::BundleAdjustmentResult ceres =
      cge::BundleAdjuster(settings).adjust(s.K, T_world_camera, start.points, observations, {0});
  settings.backend = cge::BundleAdjustmentBackend::schur_lm;
  const cge::BundleAdjustmentResult own =
      cge::BundleAdjuster(settings).adjust(s.K, T_world_camera, start.points, observations, {0});
  CHECK(ceres.outlier_count > 10);
  CHECK(own.outliers == ceres.outliers);
  CHECK(own.converged);
  CHECK(own.initial_cost == Approx(ceres.initial_cost).epsilon(1e-12));
  CHECK(own.final_cost == Approx(ceres.final_cost).epsilon(1e-9));
  for (std::size_t i = 0; i < T_world_camera.size(); ++i) {
    CAPTURE(i);
    CHECK(cge_test::rotation_error_rad(own.T_world_camera[i], ceres.T_world_camera[i]) < 1e-8);
    CHECK(cge_test::translation_error_m(own.T_world_camera[i], ceres.T_world_camera[i]) < 1e-8);
  }
  double worst = 0;
  for (std::size_t j = 0; j < start.points.size(); ++j)
    worst = std::max(worst, (own.points_world_m[j] - ceres.points_world_m[j]).norm());
  CHECK(worst < 1e-7);
}

TEST_CASE("SchurLMSolver: the iteration limit, and a start behind a camera, are reported", "[ceres][schur_lm]") {
  std::mt19937 rng(54);
  Scene s = make_scene(rng, 4, 40, 1.0, 0);
  const std::vector<bool> fixed = {true, false, false, false};
  perturb(rng, s, fixed);
  cge::CeresSolverSettings no_tolerance = tight(100);
  no_tolerance.function_tolerance = no_tolerance.gradient_tolerance = no_tolerance.parameter_tolerance = 0;
  SchurLMSolver solver(s.K, no_tolerance, 0.0, 1e-6);
  Scene limited = s;
  const SchurLMSummary summary = solver.solve(limited.poses, fixed, limited.points, limited.observations, 2);
  CHECK(summary.iterations == 2);
  CHECK(summary.termination == SchurLMSummary::Termination::iteration_limit);
  CHECK(summary.final_cost < summary.initial_cost);

  // A point behind its camera at the start: nothing is touched.
  Scene behind = s;
  behind.points[static_cast<std::size_t>(behind.observations[3].point)] =
      behind.poses[behind.observations[3].pose].to_isometry().inverse() * Eigen::Vector3d(0, 0, -2);
  const Scene before = behind;
  const SchurLMSummary failed = solver.solve(behind.poses, fixed, behind.points, behind.observations, 10);
  CHECK(failed.termination == SchurLMSummary::Termination::failure);
  CHECK(failed.iterations == 0);
  bool untouched = true;
  for (std::size_t i = 0; i < behind.poses.size(); ++i)
    untouched = untouched && behind.poses[i].q_xyzw == before.poses[i].q_xyzw && behind.poses[i].t == before.poses[i].t;
  for (std::size_t j = 0; j < behind.points.size(); ++j) untouched = untouched && behind.points[j] == before.points[j];
  CHECK(untouched);
}
