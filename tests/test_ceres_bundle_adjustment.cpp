// BundleAdjuster (cge/ceres/bundle_adjustment.hpp). Oracles: synthetic scenes with known poses and
// points (noise-free data from a perturbed start must give back the truth), the cost at the truth
// computed here independently (the optimum of noisy data must not be worse, and its RMS must sit at
// the noise level), injected gross errors (flagged, nothing else), bit-identical repeated runs, and
// invalid input naming what is wrong.
#include "cge/ceres/bundle_adjustment.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include "ceres_test_scene.hpp"

namespace {

using cge::BundleAdjuster;
using cge::BundleAdjustmentResult;
using cge::BundleAdjustmentSettings;
using cge::BundleObservation;
using cge_test::random_motion;
using cge_test::rotation_error_rad;
using cge_test::translation_error_m;
using cge_test::uniform;

struct BAScene {
  cge::PinholeIntrinsics<double> K;
  std::vector<Eigen::Isometry3d> T_world_camera;
  std::vector<Eigen::Vector3d> points;
  std::vector<BundleObservation> observations;
};

/// Keyframes strung along x (0.3 m apart, small random rotations) looking at points 3..8 m ahead;
/// every point observed (exactly) by every keyframe that sees it inside the image. With depth, every
/// observation also carries its exact depth (sigma 1 cm).
BAScene make_ba_scene(std::mt19937& rng, int keyframes, int points, bool with_depth) {
  BAScene s;
  for (int i = 0; i < keyframes; ++i) {
    Eigen::Isometry3d T = random_motion(rng, uniform(rng, 0, 0.08), 0.0);
    T.translation() = Eigen::Vector3d(0.3 * i, uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1));
    s.T_world_camera.push_back(T);
  }
  const double span = 0.3 * (keyframes - 1);
  for (int j = 0; j < points; ++j)
    s.points.emplace_back(uniform(rng, -2, span + 2), uniform(rng, -1.5, 1.5), uniform(rng, 3, 8));
  for (int i = 0; i < keyframes; ++i) {
    const Eigen::Isometry3d T_camera_world = s.T_world_camera[i].inverse();
    for (int j = 0; j < points; ++j) {
      const Eigen::Vector3d p = T_camera_world * s.points[j];
      const Eigen::Vector2d px = s.K.project(p);
      if (p.z() <= 0 || px.x() < 0 || px.x() > 640 || px.y() < 0 || px.y() > 480) continue;
      BundleObservation o;
      o.keyframe = i;
      o.point = j;
      o.pixel_px = px;
      o.sigma_px = std::pow(1.2, std::uniform_int_distribution<int>(0, 3)(rng));
      if (with_depth) {
        o.depth_m = p.z();
        o.sigma_depth_m = 0.01;
      }
      s.observations.push_back(o);
    }
  }
  return s;
}

/// 0.5 * sum chi2 at the given poses and points, without a robust loss (the test's own oracle).
double plain_cost(const BAScene& s, const std::vector<Eigen::Isometry3d>& poses,
                  const std::vector<Eigen::Vector3d>& points) {
  double cost = 0;
  for (const BundleObservation& o : s.observations) {
    const Eigen::Vector3d p = poses[o.keyframe].inverse() * points[o.point];
    cost += 0.5 * ((s.K.project(p) - o.pixel_px) / o.sigma_px).squaredNorm();
    if (!std::isnan(o.depth_m)) cost += 0.5 * std::pow((p.z() - o.depth_m) / o.sigma_depth_m, 2);
  }
  return cost;
}

void perturb(std::mt19937& rng, BAScene& s, std::vector<Eigen::Isometry3d>& poses, std::vector<Eigen::Vector3d>& points,
             const std::vector<int>& fixed) {
  poses = s.T_world_camera;
  points = s.points;
  for (std::size_t i = 0; i < poses.size(); ++i)
    if (std::find(fixed.begin(), fixed.end(), static_cast<int>(i)) == fixed.end())
      poses[i] = poses[i] * random_motion(rng, 0.01, 0.03);
  for (Eigen::Vector3d& p : points)
    p += Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)) * 0.05;
}

/// Six keyframes over 200 points with depth, 1 px of pixel noise, keyframe 0 fixed and the other
/// poses and the points perturbed: the start of the bit-for-bit comparisons.
struct NoisyStart {
  BAScene scene;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
};
NoisyStart noisy_start(unsigned seed) {
  std::mt19937 rng(seed);
  NoisyStart start{make_ba_scene(rng, 6, 200, true), {}, {}};
  std::normal_distribution<double> noise(0.0, 1.0);
  for (BundleObservation& o : start.scene.observations) o.pixel_px += Eigen::Vector2d(noise(rng), noise(rng));
  perturb(rng, start.scene, start.poses, start.points, {0});
  return start;
}

/// Poses, points, outliers, iterations and final cost all the same to the bit.
bool bit_identical_results(const BundleAdjustmentResult& a, const BundleAdjustmentResult& b) {
  bool identical = a.final_cost == b.final_cost && a.iterations == b.iterations && a.outliers == b.outliers &&
                   a.T_world_camera.size() == b.T_world_camera.size() &&
                   a.points_world_m.size() == b.points_world_m.size();
  for (std::size_t i = 0; identical && i < a.T_world_camera.size(); ++i)
    identical = cge_test::bit_identical(a.T_world_camera[i], b.T_world_camera[i]);
  for (std::size_t j = 0; identical && j < a.points_world_m.size(); ++j)
    identical = std::memcmp(a.points_world_m[j].data(), b.points_world_m[j].data(), 3 * sizeof(double)) == 0;
  return identical;
}

/// Default settings with the given solver; every BundleAdjuster test below runs on both backends.
BundleAdjustmentSettings with_backend(cge::BundleAdjustmentBackend backend) {
  BundleAdjustmentSettings settings;
  settings.backend = backend;
  return settings;
}

}  // namespace

TEST_CASE("BundleAdjuster recovers poses and points from noise-free pixels (two keyframes fixed)", "[ceres]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(31);
  BAScene s = make_ba_scene(rng, 6, 150, false);
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
  perturb(rng, s, poses, points, {0, 1});  // pixels alone leave the scale free: two fixed poses fix it
  const BundleAdjustmentResult r = BundleAdjuster(with_backend(backend)).adjust(s.K, poses, points, s.observations, {0, 1});
  for (std::size_t i = 0; i < poses.size(); ++i) {
    CAPTURE(i);
    CHECK(rotation_error_rad(r.T_world_camera[i], s.T_world_camera[i]) < 1e-6);
    CHECK(translation_error_m(r.T_world_camera[i], s.T_world_camera[i]) < 1e-6);
  }
  double worst_point_m = 0;
  for (std::size_t j = 0; j < points.size(); ++j)
    worst_point_m = std::max(worst_point_m, (r.points_world_m[j] - s.points[j]).norm());
  CHECK(worst_point_m < 1e-6);
  CHECK(r.outlier_count == 0);
  CHECK(r.final_rms_px < 1e-6);
  CHECK(r.initial_cost > r.final_cost);
  CHECK(r.converged);
  CHECK(cge_test::bit_identical(r.T_world_camera[0], poses[0]));
}

TEST_CASE("BundleAdjuster with depth observations recovers the truth with only the first keyframe fixed", "[ceres]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(32);
  BAScene s = make_ba_scene(rng, 5, 120, true);
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
  perturb(rng, s, poses, points, {0});
  const BundleAdjustmentResult r = BundleAdjuster(with_backend(backend)).adjust(s.K, poses, points, s.observations);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    CAPTURE(i);
    CHECK(rotation_error_rad(r.T_world_camera[i], s.T_world_camera[i]) < 1e-6);
    CHECK(translation_error_m(r.T_world_camera[i], s.T_world_camera[i]) < 1e-6);
  }
  for (std::size_t j = 0; j < points.size(); ++j) CHECK((r.points_world_m[j] - s.points[j]).norm() < 1e-6);
  CHECK(r.outlier_count == 0);
}

TEST_CASE("BundleAdjuster on noisy pixels: cost no worse than the truth's, RMS at the noise level", "[ceres]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(33);
  BAScene s = make_ba_scene(rng, 8, 300, false);
  std::normal_distribution<double> noise(0.0, 1.0);
  double noise_sq = 0;
  for (BundleObservation& o : s.observations) {
    const Eigen::Vector2d e = o.sigma_px * Eigen::Vector2d(noise(rng), noise(rng));
    o.pixel_px += e;
    noise_sq += e.squaredNorm();
  }
  const double noise_rms_px = std::sqrt(noise_sq / static_cast<double>(s.observations.size()));
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
  perturb(rng, s, poses, points, {0, 1});
  BundleAdjustmentSettings settings = with_backend(backend);
  settings.rounds = 1;         // one plain least-squares solve over every observation, so that the optimum's
  settings.robust_rounds = 0;  // cost is comparable with the truth's
  const BundleAdjustmentResult r = BundleAdjuster(settings).adjust(s.K, poses, points, s.observations, {0, 1});
  const double truth_cost = plain_cost(s, s.T_world_camera, s.points);
  const double start_cost = plain_cost(s, poses, points);
  CHECK(plain_cost(s, r.T_world_camera, r.points_world_m) <= truth_cost);
  CHECK(r.final_cost == Approx(plain_cost(s, r.T_world_camera, r.points_world_m)).epsilon(1e-9));
  CHECK(r.initial_cost == Approx(start_cost).epsilon(1e-9));
  // Fitting 3 parameters per point and 6 per free pose absorbs a little noise: RMS slightly below it.
  // (final_rms_px counts inliers only, so compare the all-observation figure.)
  double sq = 0;
  for (const BundleObservation& o : s.observations)
    sq += (s.K.project(r.T_world_camera[o.keyframe].inverse() * r.points_world_m[o.point]) - o.pixel_px).squaredNorm();
  const double rms_px = std::sqrt(sq / static_cast<double>(s.observations.size()));
  CHECK(rms_px < noise_rms_px);
  CHECK(rms_px > 0.7 * noise_rms_px);
  // Scale is fixed by the 0.3 m between keyframes 0 and 1 only: the far keyframes move by centimetres.
  for (std::size_t i = 2; i < poses.size(); ++i)
    CHECK(translation_error_m(r.T_world_camera[i], s.T_world_camera[i]) < 0.05);
}

TEST_CASE("BundleAdjuster flags exactly the injected gross errors on otherwise exact data", "[ceres]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(34);
  BAScene s = make_ba_scene(rng, 6, 200, true);
  // One observation of every third point seen by at least 4 keyframes (with fewer, the point itself
  // could absorb a gross error), 30..60 sigma off.
  std::vector<int> seen(s.points.size(), 0);
  for (const BundleObservation& o : s.observations) ++seen[o.point];
  std::vector<bool> corrupted(s.observations.size(), false), point_done(s.points.size(), false);
  for (std::size_t k = 0; k < s.observations.size(); ++k) {
    const int j = s.observations[k].point;
    if (seen[j] < 4 || j % 3 != 0 || point_done[j]) continue;
    point_done[j] = true;
    const double angle = uniform(rng, 0, 6.28);
    s.observations[k].pixel_px +=
        uniform(rng, 30, 60) * s.observations[k].sigma_px * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    corrupted[k] = true;
  }
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
  perturb(rng, s, poses, points, {0});
  const BundleAdjustmentResult r = BundleAdjuster(with_backend(backend)).adjust(s.K, poses, points, s.observations);
  REQUIRE(r.outliers.size() == s.observations.size());
  int expected = 0;
  for (std::size_t k = 0; k < corrupted.size(); ++k) {
    CHECK(r.outliers[k] == corrupted[k]);
    expected += corrupted[k] ? 1 : 0;
  }
  CHECK(r.outlier_count == expected);
  CHECK(expected > 20);
  // The second round, without the flagged observations, is exact again.
  for (std::size_t i = 0; i < poses.size(); ++i)
    CHECK(translation_error_m(r.T_world_camera[i], s.T_world_camera[i]) < 1e-6);
  CHECK(r.rounds == 2);
}

TEST_CASE("BundleAdjuster leaves out and flags observations behind their camera at the start", "[ceres]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(35);
  BAScene s = make_ba_scene(rng, 4, 60, true);
  std::vector<Eigen::Vector3d> points = s.points;
  // Add a point behind keyframe 0 with a (bogus) observation: it must not break the solve.
  points.emplace_back(0.0, 0.0, -3.0);
  s.observations.push_back({0, static_cast<int>(points.size()) - 1, Eigen::Vector2d(320, 240), 1.0,
                            std::numeric_limits<double>::quiet_NaN(), 0.0});
  const BundleAdjustmentResult r = BundleAdjuster(with_backend(backend)).adjust(s.K, s.T_world_camera, points, s.observations);
  CHECK(r.outliers.back());
  CHECK(r.outlier_count == 1);
  CHECK(r.points_world_m.back() == points.back());  // unobserved in the solve: returned as given
}

TEST_CASE("BundleAdjuster is deterministic: two runs give bit-identical results", "[ceres]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  const NoisyStart start = noisy_start(36);
  const BAScene& s = start.scene;
  const BundleAdjustmentResult a =
      BundleAdjuster(with_backend(backend)).adjust(s.K, start.poses, start.points, s.observations);
  const BundleAdjustmentResult b =
      BundleAdjuster(with_backend(backend)).adjust(s.K, start.poses, start.points, s.observations);
  CHECK(bit_identical_results(a, b));
}

TEST_CASE("BundleAdjuster schur_lm: more free poses than schur_lm_max_free_poses go to Ceres, bit for bit", "[ceres]") {
  const NoisyStart start = noisy_start(37);  // 5 free poses
  const BAScene& s = start.scene;
  const std::vector<Eigen::Isometry3d>& poses = start.poses;
  const std::vector<Eigen::Vector3d>& points = start.points;
  const auto same = bit_identical_results;
  const BundleAdjustmentResult by_ceres =
      BundleAdjuster(with_backend(cge::BundleAdjustmentBackend::ceres)).adjust(s.K, poses, points, s.observations);
  const BundleAdjustmentResult by_schur_lm =
      BundleAdjuster(with_backend(cge::BundleAdjustmentBackend::schur_lm)).adjust(s.K, poses, points, s.observations);
  REQUIRE_FALSE(same(by_ceres, by_schur_lm));  // the two solvers' iterates differ, so the test can tell them apart

  BundleAdjustmentSettings limited = with_backend(cge::BundleAdjustmentBackend::schur_lm);
  limited.schur_lm_max_free_poses = 4;
  CHECK(same(BundleAdjuster(limited).adjust(s.K, poses, points, s.observations), by_ceres));
  limited.schur_lm_max_free_poses = 5;
  CHECK(same(BundleAdjuster(limited).adjust(s.K, poses, points, s.observations), by_schur_lm));

  limited.schur_lm_max_free_poses = 0;
  CHECK_THROWS_WITH(limited.validate(), Catch::Contains("schur_lm_max_free_poses must be at least 1"));
}

TEST_CASE("BundleAdjuster rejects invalid input with a message naming it", "[ceres]") {
  std::mt19937 rng(37);
  const BAScene s = make_ba_scene(rng, 3, 30, false);
  const BundleAdjuster ba;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto obs = s.observations;
  obs[4].keyframe = 3;
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, obs),
                    Catch::Contains("observation 4: keyframe 3 out of range"));
  obs = s.observations;
  obs[2].point = -1;
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, obs),
                    Catch::Contains("observation 2: point -1 out of range"));
  obs = s.observations;
  obs[1].pixel_px.y() = nan;
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, obs), Catch::Contains("observation 1: pixel_px"));
  obs = s.observations;
  obs[0].sigma_px = -2;
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, obs), Catch::Contains("observation 0: sigma_px"));
  obs = s.observations;
  obs[3].depth_m = 2.0;  // sigma_depth_m left at 0
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, obs), Catch::Contains("observation 3: sigma_depth_m"));
  obs[3].depth_m = -1.0;
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, obs), Catch::Contains("observation 3: depth_m"));
  auto points = s.points;
  points[5].x() = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, points, s.observations), Catch::Contains("point 5 is not finite"));
  auto poses = s.T_world_camera;
  poses[1].linear()(0, 1) += 0.1;
  CHECK_THROWS_WITH(ba.adjust(s.K, poses, s.points, s.observations), Catch::Contains("pose 1"));
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, s.observations, {}),
                    Catch::Contains("at least one fixed"));
  CHECK_THROWS_WITH(ba.adjust(s.K, s.T_world_camera, s.points, s.observations, {3}),
                    Catch::Contains("fixed keyframe 3"));
  cge::PinholeIntrinsics<double> K = s.K;
  K.fy_px = 0;
  CHECK_THROWS_WITH(ba.adjust(K, s.T_world_camera, s.points, s.observations), Catch::Contains("intrinsics"));
  BundleAdjustmentSettings bad;
  bad.chi2_threshold_3dof = 0;
  CHECK_THROWS_WITH(BundleAdjuster(bad).adjust(s.K, s.T_world_camera, s.points, s.observations),
                    Catch::Contains("chi2_threshold_3dof"));
}

TEST_CASE("RgbdReprojectionCost equals the autodiff residuals and Jacobians", "[ceres]") {
  // Oracle: Ceres autodiff of ReprojectionCost (pixel only) and ReprojectionDepthCost (pixel + depth),
  // on random poses (also quaternions off the unit sphere, which Ceres' manifold never produces but
  // the ambient Jacobian must still match) and random points in front of the camera.
  std::mt19937 rng(21);
  const cge::PinholeIntrinsics<double> K{535.4, 539.2, 320.1, 247.6};
  for (int trial = 0; trial < 200; ++trial) {
    CAPTURE(trial);
    Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
    const double scale = trial % 4 == 0 ? uniform(rng, 0.9, 1.1) : 1.0;
    double q_xyzw[4] = {scale * q.x(), scale * q.y(), scale * q.z(), scale * q.w()};
    const Eigen::Vector3d t(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    // A point 1..6 m in front of the (unit) camera, taken back to the world.
    const Eigen::Vector3d p_camera(uniform(rng, -2, 2), uniform(rng, -1.5, 1.5), uniform(rng, 1, 6));
    const Eigen::Vector3d X = q.conjugate() * (p_camera - t);
    const Eigen::Vector2d pixel(uniform(rng, 0, 640), uniform(rng, 0, 480));
    const double inv_sigma = 1.0 / uniform(rng, 0.5, 3.0);
    const bool with_depth = trial % 2 == 0;
    const double depth = uniform(rng, 1, 6), inv_sigma_depth = with_depth ? 1.0 / uniform(rng, 0.005, 0.1) : 0.0;

    const cge::RgbdReprojectionCost analytic(K, pixel, inv_sigma, depth, inv_sigma_depth, 1e-6);
    const cge::ReprojectionCost pixel_cost{K, pixel, inv_sigma, 1e-6};
    std::unique_ptr<ceres::CostFunction> autodiff(
        with_depth ? cge::ReprojectionDepthCost::create({pixel_cost, {depth, inv_sigma_depth}})
                   : cge::ReprojectionCost::create(pixel_cost));
    const int rows = with_depth ? 3 : 2;

    double t_arr[3] = {t.x(), t.y(), t.z()}, X_arr[3] = {X.x(), X.y(), X.z()};
    const double* params[3] = {q_xyzw, t_arr, X_arr};
    double r_a[3], J_a0[12], J_a1[9], J_a2[9];
    double r_b[3] = {0, 0, 0}, J_b0[12] = {}, J_b1[9] = {}, J_b2[9] = {};
    double* J_a[3] = {J_a0, J_a1, J_a2};
    double* J_b[3] = {J_b0, J_b1, J_b2};
    REQUIRE(analytic.Evaluate(params, r_a, J_a));
    REQUIRE(autodiff->Evaluate(params, r_b, J_b));
    const auto close = [](double a, double b) { return std::abs(a - b) <= 1e-9 * (1.0 + std::abs(b)); };
    for (int r = 0; r < rows; ++r) {
      CAPTURE(r);
      CHECK(close(r_a[r], r_b[r]));
      for (int c = 0; c < 4; ++c) CHECK(close(J_a0[r * 4 + c], J_b0[r * 4 + c]));
      for (int c = 0; c < 3; ++c) CHECK(close(J_a1[r * 3 + c], J_b1[r * 3 + c]));
      for (int c = 0; c < 3; ++c) CHECK(close(J_a2[r * 3 + c], J_b2[r * 3 + c]));
    }
    if (!with_depth) {  // the pixel-only depth row is identically zero
      CHECK(r_a[2] == 0.0);
      for (int c = 0; c < 4; ++c) CHECK(J_a0[8 + c] == 0.0);
      for (int c = 0; c < 3; ++c) CHECK((J_a1[6 + c] == 0.0 && J_a2[6 + c] == 0.0));
    }
  }
  // Behind the camera: no residual, as the autodiff cost.
  const cge::RgbdReprojectionCost analytic(K, Eigen::Vector2d(320, 240), 1.0, 2.0, 10.0, 1e-6);
  double q_id[4] = {0, 0, 0, 1}, t0[3] = {0, 0, 0}, behind[3] = {0, 0, -1};
  const double* params[3] = {q_id, t0, behind};
  double r[3];
  CHECK_FALSE(analytic.Evaluate(params, r, nullptr));
}

TEST_CASE("BundleAdjustmentRun: rounds solved one at a time give exactly what adjust gives", "[ceres]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(41);
  BAScene s = make_ba_scene(rng, 6, 150, true);
  // Gross pixel errors, so that the first round's outliers sit out the second.
  for (std::size_t k = 0; k < s.observations.size(); k += 17) s.observations[k].pixel_px += Eigen::Vector2d(40, -25);
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
  perturb(rng, s, poses, points, {0});
  const BundleAdjustmentSettings settings = with_backend(backend);  // two rounds, the first robust
  const BundleAdjustmentResult whole = BundleAdjuster(settings).adjust(s.K, poses, points, s.observations, {0});

  cge::BundleAdjustmentRun run(settings, s.K, poses, points, s.observations, {0});
  CHECK_FALSE(run.done());
  CHECK(run.rounds_left() == 2);
  const BundleAdjustmentResult start = run.result();  // nothing solved: the input back
  CHECK(cge_test::bit_identical(start.T_world_camera[3], poses[3]));
  CHECK(start.points_world_m[7] == points[7]);
  run.solve_next_round();
  CHECK(run.rounds_solved() == 1);
  CHECK(run.rounds_left() == 1);
  const BundleAdjustmentResult first = run.result();
  // The first round alone brings the poses most of the way (the oracle: the true poses).
  for (std::size_t i = 1; i < poses.size(); ++i) {
    CAPTURE(i);
    CHECK(translation_error_m(first.T_world_camera[i], s.T_world_camera[i]) <
          translation_error_m(poses[i], s.T_world_camera[i]));
  }
  run.solve_next_round();
  CHECK(run.done());
  CHECK(run.rounds_left() == 0);
  run.solve_next_round();  // nothing left: no change
  const BundleAdjustmentResult stepwise = run.result();
  REQUIRE(stepwise.T_world_camera.size() == whole.T_world_camera.size());
  for (std::size_t i = 0; i < poses.size(); ++i) CHECK(cge_test::bit_identical(stepwise.T_world_camera[i], whole.T_world_camera[i]));
  for (std::size_t j = 0; j < points.size(); ++j) CHECK(stepwise.points_world_m[j] == whole.points_world_m[j]);
  CHECK(stepwise.outliers == whole.outliers);
  CHECK(stepwise.outlier_count > 0);
  CHECK(stepwise.iterations == whole.iterations);
  CHECK(stepwise.final_cost == whole.final_cost);
}

TEST_CASE("BundleAdjustmentRun in slices: no slice over its limit, a round within its budget, the same optimum",
          "[ceres][slices]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(43);
  BAScene s = make_ba_scene(rng, 6, 150, true);
  for (std::size_t k = 0; k < s.observations.size(); k += 17) s.observations[k].pixel_px += Eigen::Vector2d(40, -25);
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
  perturb(rng, s, poses, points, {0});
  BundleAdjustmentSettings settings = with_backend(backend);  // two rounds, the first robust, 100 iterations each
  const BundleAdjustmentResult whole = BundleAdjuster(settings).adjust(s.K, poses, points, s.observations, {0});
  REQUIRE(whole.converged);

  cge::BundleAdjustmentRun run(settings, s.K, poses, points, s.observations, {0});
  CHECK_THROWS_AS(run.solve_next_slice(0), std::invalid_argument);
  constexpr int kSlice = 2;
  int slices = 0, total = 0;
  while (!run.done()) {
    const int rounds_before = run.rounds_solved();
    const int used = run.solve_next_slice(kSlice);
    CHECK(used <= kSlice);
    // A slice that used all its iterations leaves the round open unless the round converged there.
    if (used < kSlice) CHECK(run.rounds_solved() == rounds_before + 1);
    CHECK(run.round_iterations() <= settings.solver.max_iterations);
    total += used;
    REQUIRE(++slices < 200);
  }
  CHECK(slices > 2);  // the rounds really were cut
  const BundleAdjustmentResult sliced = run.result();
  CHECK(sliced.iterations == total);
  CHECK(sliced.rounds == 2);
  CHECK(sliced.converged);
  // The same optimum as the whole solve (each slice restarts the damping, so not bit for bit):
  // the plain cost computed here, the poses against the whole solve's, the same outliers.
  const double cost_whole = plain_cost(s, whole.T_world_camera, whole.points_world_m);
  const double cost_sliced = plain_cost(s, sliced.T_world_camera, sliced.points_world_m);
  CHECK(cost_sliced == Approx(cost_whole).epsilon(1e-6));
  for (std::size_t i = 0; i < poses.size(); ++i) {
    CAPTURE(i);
    CHECK(translation_error_m(sliced.T_world_camera[i], whole.T_world_camera[i]) < 1e-7);
    CHECK(rotation_error_rad(sliced.T_world_camera[i], whole.T_world_camera[i]) < 1e-7);
  }
  CHECK(sliced.outliers == whole.outliers);
  CHECK(sliced.outlier_count > 0);
}

TEST_CASE("BundleAdjustmentRun in slices: a round ends at its iteration budget; a slice past it is cut",
          "[ceres][slices]") {
  const cge::BundleAdjustmentBackend backend = GENERATE(cge::BundleAdjustmentBackend::ceres, cge::BundleAdjustmentBackend::schur_lm);
  CAPTURE(cge::bundle_adjustment_backend_name(backend));
  std::mt19937 rng(44);
  BAScene s = make_ba_scene(rng, 5, 120, true);
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> points;
  perturb(rng, s, poses, points, {0});
  BundleAdjustmentSettings settings = with_backend(backend);
  settings.solver.max_iterations = 3;
  settings.solver.function_tolerance = 0;  // no early convergence: every round spends its budget
  settings.solver.gradient_tolerance = 0;
  settings.solver.parameter_tolerance = 0;
  const BundleAdjustmentResult whole = BundleAdjuster(settings).adjust(s.K, poses, points, s.observations, {0});

  cge::BundleAdjustmentRun run(settings, s.K, poses, points, s.observations, {0});
  CHECK(run.solve_next_slice(2) == 2);
  CHECK(run.rounds_solved() == 0);
  CHECK(run.round_iterations() == 2);
  CHECK(run.solve_next_slice(2) == 1);  // the round's third and last iteration
  CHECK(run.rounds_solved() == 1);
  CHECK(run.round_iterations() == 0);
  // A slice as large as the round's budget is the whole round, bit for bit.
  CHECK(run.solve_next_slice(1000) == 3);
  CHECK(run.done());
  CHECK(run.solve_next_slice(5) == 0);
  const BundleAdjustmentResult sliced = run.result();
  CHECK(sliced.iterations == 6);
  CHECK(whole.iterations == 6);
  // Sliced, the first round differs from the whole solve only by the restarted damping: the end
  // is near it, and both are far nearer the truth than the start.
  for (std::size_t i = 1; i < poses.size(); ++i) {
    CAPTURE(i);
    CHECK(translation_error_m(sliced.T_world_camera[i], s.T_world_camera[i]) <
          0.1 * translation_error_m(poses[i], s.T_world_camera[i]));
  }
}
