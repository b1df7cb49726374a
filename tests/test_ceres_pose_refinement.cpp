// PoseRefiner (cge/ceres/pose_refinement.hpp): synthetic scenes with a known pose are the oracle:
// noise-free observations from a perturbed start must give back the true pose, injected gross
// errors must be flagged and nothing else, sigma_px must scale the outlier test, and bad input must
// throw naming what is wrong. The cases that recover a pose run on both backends (the own
// Levenberg-Marquardt, the default, and Ceres).
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "ceres_test_scene.hpp"
#include "cge/ceres/pose_refinement.hpp"

namespace {

using cge::PoseObservation;
using cge::PoseRefinementResult;
using cge::PoseRefinementSettings;
using cge::PoseRefiner;
using cge_test::random_motion;
using cge_test::rotation_error_rad;
using cge_test::translation_error_m;

struct Scene {
  cge::PinholeIntrinsics<double> K;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  std::vector<PoseObservation> observations;
};

/// n exact observations of random points by a random camera; sigma_px drawn from the ORB scale
/// pyramid (1.2^octave, octave 0..7).
Scene make_scene(std::mt19937& rng, int n) {
  Scene s;
  s.T_world_camera = cge_test::random_pose(rng);
  const Eigen::Isometry3d T_camera_world = s.T_world_camera.inverse();
  for (int i = 0; i < n; ++i) {
    PoseObservation o;
    o.point_world_m = cge_test::random_visible_point(rng, s.K, s.T_world_camera);
    o.pixel_px = s.K.project(T_camera_world * o.point_world_m);
    o.sigma_px = std::pow(1.2, std::uniform_int_distribution<int>(0, 7)(rng));
    s.observations.push_back(o);
  }
  return s;
}

/// Default settings on the given backend.
PoseRefinementSettings on(cge::PoseRefinementBackend backend) {
  PoseRefinementSettings settings;
  settings.backend = backend;
  return settings;
}

}  // namespace

TEST_CASE("PoseRefiner recovers the true pose from noise-free observations and a perturbed start", "[ceres]") {
  const auto backend = GENERATE(cge::PoseRefinementBackend::pose_lm, cge::PoseRefinementBackend::ceres);
  CAPTURE(cge::pose_refinement_backend_name(backend));
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    const Scene s = make_scene(rng, 60);
    const Eigen::Isometry3d start = s.T_world_camera * random_motion(rng, 0.1, 0.15);
    const PoseRefinementResult r = PoseRefiner(on(backend)).refine(s.K, s.observations, start);
    CAPTURE(trial);
    CHECK(rotation_error_rad(r.T_world_camera, s.T_world_camera) < 1e-6);
    CHECK(translation_error_m(r.T_world_camera, s.T_world_camera) < 1e-6);
    CHECK(r.inlier_count == 60);
    CHECK(r.rounds == 4);
    CHECK(r.final_rms_px < 1e-6);
    CHECK(r.initial_cost > r.final_cost);
    CHECK(r.final_cost < 1e-12);
    CHECK(r.converged);
  }
}

TEST_CASE("PoseRefiner flags exactly the injected gross errors on otherwise exact data", "[ceres]") {
  const auto backend = GENERATE(cge::PoseRefinementBackend::pose_lm, cge::PoseRefinementBackend::ceres);
  CAPTURE(cge::pose_refinement_backend_name(backend));
  std::mt19937 rng(12);
  for (int trial = 0; trial < 5; ++trial) {
    Scene s = make_scene(rng, 200);
    std::vector<bool> corrupted(s.observations.size(), false);
    for (std::size_t i = 0; i < s.observations.size(); i += 4) {  // 25 % outliers, 20..60 sigma off
      const double angle = cge_test::uniform(rng, 0, 6.28);
      const double length = cge_test::uniform(rng, 20, 60) * s.observations[i].sigma_px;
      s.observations[i].pixel_px += length * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      corrupted[i] = true;
    }
    const Eigen::Isometry3d start = s.T_world_camera * random_motion(rng, 0.05, 0.05);
    const PoseRefinementResult r = PoseRefiner(on(backend)).refine(s.K, s.observations, start);
    CAPTURE(trial);
    CHECK(rotation_error_rad(r.T_world_camera, s.T_world_camera) < 1e-6);
    CHECK(translation_error_m(r.T_world_camera, s.T_world_camera) < 1e-6);
    REQUIRE(r.inliers.size() == s.observations.size());
    for (std::size_t i = 0; i < corrupted.size(); ++i) CHECK(r.inliers[i] == !corrupted[i]);
    CHECK(r.inlier_count == 150);
  }
}

TEST_CASE("PoseRefiner with pixel noise: error at the noise level and about 5 % chi2 rejections", "[ceres]") {
  const auto backend = GENERATE(cge::PoseRefinementBackend::pose_lm, cge::PoseRefinementBackend::ceres);
  CAPTURE(cge::pose_refinement_backend_name(backend));
  std::mt19937 rng(13);
  Scene s = make_scene(rng, 1000);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (PoseObservation& o : s.observations) o.pixel_px += o.sigma_px * Eigen::Vector2d(noise(rng), noise(rng));
  const PoseRefinementResult r =
      PoseRefiner(on(backend)).refine(s.K, s.observations, s.T_world_camera * random_motion(rng, 0.05, 0.1));
  // 1000 points at 1..6 m with ~2 px noise: the pose is determined to well under a centimetre.
  CHECK(translation_error_m(r.T_world_camera, s.T_world_camera) < 0.01);
  CHECK(rotation_error_rad(r.T_world_camera, s.T_world_camera) < 0.002);
  // chi2(2) > 5.991 has probability 0.05: 50 expected; binomial sd ~7.
  CHECK(r.inlier_count > 1000 - 80);
  CHECK(r.inlier_count < 1000 - 25);
}

TEST_CASE("PoseRefiner scales the outlier test by each observation's sigma_px", "[ceres]") {
  std::mt19937 rng(14);
  Scene s = make_scene(rng, 100);
  for (PoseObservation& o : s.observations) o.sigma_px = 1.0;
  // 5 px off: chi2 = 25 / sigma^2, an outlier at sigma 1 and 2 (6.25 > 5.991), an inlier at sigma 3.
  s.observations[0].pixel_px.x() += 5.0;
  for (double sigma : {1.0, 2.0, 3.0}) {
    s.observations[0].sigma_px = sigma;
    const PoseRefinementResult r = PoseRefiner().refine(s.K, s.observations, s.T_world_camera);
    CAPTURE(sigma);
    CHECK(r.inliers[0] == (sigma > 2.5));
    for (std::size_t i = 1; i < s.observations.size(); ++i) CHECK(r.inliers[i]);
  }
}

TEST_CASE("PoseRefiner is deterministic: two runs give bit-identical results", "[ceres]") {
  const auto backend = GENERATE(cge::PoseRefinementBackend::pose_lm, cge::PoseRefinementBackend::ceres);
  CAPTURE(cge::pose_refinement_backend_name(backend));
  std::mt19937 rng(15);
  Scene s = make_scene(rng, 300);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (PoseObservation& o : s.observations) o.pixel_px += o.sigma_px * Eigen::Vector2d(noise(rng), noise(rng));
  const Eigen::Isometry3d start = s.T_world_camera * random_motion(rng, 0.05, 0.1);
  const PoseRefinementResult a = PoseRefiner(on(backend)).refine(s.K, s.observations, start);
  const PoseRefinementResult b = PoseRefiner(on(backend)).refine(s.K, s.observations, start);
  CHECK(cge_test::bit_identical(a.T_world_camera, b.T_world_camera));
  CHECK(a.inliers == b.inliers);
  CHECK(a.final_cost == b.final_cost);
  CHECK(a.iterations == b.iterations);
}

TEST_CASE("PoseRefiner stops early when too few inliers remain, and rounds follow the settings", "[ceres]") {
  std::mt19937 rng(16);
  const Scene s = make_scene(rng, 9);
  PoseRefinementSettings settings;
  // 9 inliers < min_inliers_to_continue (10): one round only.
  PoseRefinementResult r = PoseRefiner(settings).refine(s.K, s.observations, s.T_world_camera);
  CHECK(r.rounds == 1);
  CHECK(r.inlier_count == 9);
  settings.min_inliers_to_continue = 9;
  settings.rounds = 3;
  settings.robust_rounds = 0;
  r = PoseRefiner(settings).refine(s.K, s.observations, s.T_world_camera);
  CHECK(r.rounds == 3);
  settings.min_observations = 10;
  CHECK_THROWS_WITH(PoseRefiner(settings).refine(s.K, s.observations, s.T_world_camera),
                    Catch::Contains("at least 10"));
}

TEST_CASE("PoseRefiner with huber_delta 0 runs no robust round: as robust_rounds 0", "[ceres]") {
  // RobustRoundsSettings: 0 = no robust loss (the bundle adjuster's meaning too). With gross
  // outliers in the data a Huber round changes the path, so the comparison can tell the two apart.
  std::mt19937 rng(18);
  Scene s = make_scene(rng, 200);
  for (std::size_t i = 0; i < s.observations.size(); i += 7) s.observations[i].pixel_px += Eigen::Vector2d(25, -18);
  const Eigen::Isometry3d start = s.T_world_camera * random_motion(rng, 0.03, 0.06);
  PoseRefinementSettings no_width;
  no_width.huber_delta = 0;
  PoseRefinementSettings no_robust_round;
  no_robust_round.robust_rounds = 0;
  const PoseRefinementResult a = PoseRefiner(no_width).refine(s.K, s.observations, start);
  const PoseRefinementResult b = PoseRefiner(no_robust_round).refine(s.K, s.observations, start);
  CHECK(cge_test::bit_identical(a.T_world_camera, b.T_world_camera));
  CHECK(a.inliers == b.inliers);
  CHECK(a.initial_cost == b.initial_cost);
  const PoseRefinementResult robust = PoseRefiner().refine(s.K, s.observations, start);
  CHECK(robust.initial_cost != a.initial_cost);  // the Huber loss was in play by default
}

TEST_CASE("PoseRefiner rejects invalid input with a message naming it", "[ceres]") {
  std::mt19937 rng(17);
  const Scene s = make_scene(rng, 20);
  const PoseRefiner refiner;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto throws_with = [&](std::vector<PoseObservation> obs, const Eigen::Isometry3d& T, const std::string& text,
                               const cge::PinholeIntrinsics<double>& K) {
    CHECK_THROWS_WITH(refiner.refine(K, obs, T), Catch::Contains(text));
  };
  SECTION("too few observations") {
    throws_with({s.observations.begin(), s.observations.begin() + 2}, s.T_world_camera, "at least 3", s.K);
  }
  SECTION("non-finite values") {
    std::vector<PoseObservation> obs = s.observations;
    obs[7].point_world_m.y() = nan;
    throws_with(obs, s.T_world_camera, "observation 7: point_world_m", s.K);
    obs = s.observations;
    obs[3].pixel_px.x() = std::numeric_limits<double>::infinity();
    throws_with(obs, s.T_world_camera, "observation 3: pixel_px", s.K);
    obs = s.observations;
    obs[5].sigma_px = 0;
    throws_with(obs, s.T_world_camera, "observation 5: sigma_px", s.K);
    Eigen::Isometry3d T = s.T_world_camera;
    T.translation().x() = nan;
    throws_with(s.observations, T, "T_world_camera_initial", s.K);
  }
  SECTION("not a rigid transform") {
    Eigen::Isometry3d T = s.T_world_camera;
    T.linear() *= 1.01;
    throws_with(s.observations, T, "not a rigid transform", s.K);
  }
  SECTION("bad intrinsics") {
    cge::PinholeIntrinsics<double> K = s.K;
    K.fx_px = -1;
    throws_with(s.observations, s.T_world_camera, "intrinsics", K);
  }
  SECTION("every point behind the initial pose") {
    Eigen::Isometry3d T = s.T_world_camera;
    T.linear() = T.linear() * Eigen::AngleAxisd(3.14159265358979, Eigen::Vector3d::UnitX()).toRotationMatrix();
    throws_with(s.observations, T, "in front of the initial pose", s.K);
  }
  SECTION("bad settings") {
    PoseRefinementSettings bad;
    bad.robust_rounds = 5;
    CHECK_THROWS_WITH(PoseRefiner(bad).refine(s.K, s.observations, s.T_world_camera), Catch::Contains("robust_rounds"));
    bad = {};
    bad.chi2_threshold_2dof = nan;
    CHECK_THROWS_WITH(PoseRefiner(bad).refine(s.K, s.observations, s.T_world_camera),
                      Catch::Contains("chi2_threshold_2dof"));
    bad = {};
    bad.huber_delta = -1;
    CHECK_THROWS_WITH(PoseRefiner(bad).refine(s.K, s.observations, s.T_world_camera), Catch::Contains("huber_delta"));
    bad = {};
    bad.solver.max_iterations = 0;
    CHECK_THROWS_WITH(PoseRefiner(bad).refine(s.K, s.observations, s.T_world_camera),
                      Catch::Contains("max_iterations"));
  }
}

// Ceres' headers include glog, whose CHECK would silently replace Catch2's (this file includes
// catch.hpp first); cge/ceres/ceres_headers.hpp restores it. Catch's CHECK reports through
// Catch::AssertionHandler, glog's aborts through google::LogMessageFatal.
#define CGE_TEST_STRINGIZE_EXPANDED(...) CGE_TEST_STRINGIZE(__VA_ARGS__)
#define CGE_TEST_STRINGIZE(...) #__VA_ARGS__
TEST_CASE("Including the Ceres adapters after catch.hpp keeps Catch2's CHECK", "[ceres]") {
  const std::string expansion = CGE_TEST_STRINGIZE_EXPANDED(CHECK(true));
  CHECK(expansion.find("AssertionHandler") != std::string::npos);
  CHECK(expansion.find("google") == std::string::npos);
}
