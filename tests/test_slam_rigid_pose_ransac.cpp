// The RGB-D pose RANSAC (cge/slam/geometry/rigid_pose_ransac.hpp). Oracles: Eigen::umeyama for the
// closed-form fit, hand-built scenes with a known camera pose, a static background and a second,
// coherent rigid motion (a walking person) or depth errors along the ray.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "cge/slam/geometry/rigid_pose_ransac.hpp"

using cge::slam::RigidPoseRansacResult;
using cge::slam::RigidPoseRansacSettings;
using cge::slam::fit_rigid_motion;
using cge::slam::solve_rigid_pose_ransac;

namespace {

cge::PinholeIntrinsics<double> test_camera() {
  cge::PinholeIntrinsics<double> k;
  k.fx_px = 520;
  k.fy_px = 515;
  k.cx_px = 320;
  k.cy_px = 240;
  return k;
}

Eigen::Isometry3d make_pose(double angle_rad, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

/// Pairs of a RANSAC input: world points, their pixels, their camera points (NaN: no depth).
struct Pairs {
  std::vector<Eigen::Vector3d> world;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<Eigen::Vector3d> camera;

  void add(const Eigen::Vector3d& X, const Eigen::Vector3d& p_camera, const cge::PinholeIntrinsics<double>& K,
           bool with_depth) {
    world.push_back(X);
    pixels.push_back(K.project(p_camera));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    camera.push_back(with_depth ? p_camera : Eigen::Vector3d(nan, nan, nan));
  }
  RigidPoseRansacResult solve(const cge::PinholeIntrinsics<double>& K, const RigidPoseRansacSettings& s = {}) const {
    return solve_rigid_pose_ransac(world, pixels, camera, K, s);
  }
};

/// A camera at T_camera_world seeing `count` points 1.5-4 m ahead; the first `moving` of them
/// belong to a body that moved by `motion` after the map saw them (their world points are where
/// they were), every seventh has no depth.
Pairs scene(const Eigen::Isometry3d& T_camera_world, int count, int moving, const Eigen::Isometry3d& motion,
            unsigned seed) {
  const cge::PinholeIntrinsics<double> K = test_camera();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-1.2, 1.2), z(1.5, 4.0);
  Pairs pairs;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p_camera(xy(rng), xy(rng), z(rng));
    const Eigen::Vector3d X_now = T_camera_world.inverse() * p_camera;
    const Eigen::Vector3d X_mapped = i < moving ? motion.inverse() * X_now : X_now;
    pairs.add(X_mapped, p_camera, K, i % 7 != 3);
  }
  return pairs;
}

double pose_gap(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) { return (a.matrix() - b.matrix()).norm(); }

}  // namespace

TEST_CASE("fit_rigid_motion is Umeyama's fit without scale", "[slam_geometry][rigid_ransac]") {
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0, 0.02);
  std::uniform_real_distribution<double> coord(-2, 2);
  const Eigen::Isometry3d T = make_pose(0.7, Eigen::Vector3d(0.3, -1, 0.5), Eigen::Vector3d(0.4, 1.1, -0.6));
  for (const int n : {3, 4, 10, 200}) {
    std::vector<Eigen::Vector3d> world, camera;
    Eigen::Matrix3Xd W(3, n), C(3, n);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d X(coord(rng), coord(rng), coord(rng));
      const Eigen::Vector3d x = T * X + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      world.push_back(X);
      camera.push_back(x);
      W.col(i) = X;
      C.col(i) = x;
    }
    const Eigen::Matrix4d oracle = Eigen::umeyama(W, C, false);
    const Eigen::Isometry3d fitted = fit_rigid_motion(world, camera);
    INFO("pairs " << n);
    CHECK((fitted.matrix() - oracle).norm() < 1e-9);
    CHECK(fitted.linear().determinant() == Approx(1).margin(1e-12));
  }
  // Without noise the fit is the motion itself.
  std::vector<Eigen::Vector3d> world = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0.5, 0.5, 1}};
  std::vector<Eigen::Vector3d> camera;
  for (const Eigen::Vector3d& X : world) camera.push_back(T * X);
  CHECK(pose_gap(fit_rigid_motion(world, camera), T) < 1e-12);
}

TEST_CASE("fit_rigid_motion refuses too few or unpaired points", "[slam_geometry][rigid_ransac]") {
  const std::vector<Eigen::Vector3d> two = {{0, 0, 0}, {1, 0, 0}};
  const std::vector<Eigen::Vector3d> three = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  CHECK_THROWS_AS(fit_rigid_motion(two, two), std::invalid_argument);
  CHECK_THROWS_AS(fit_rigid_motion(three, two), std::invalid_argument);
}

TEST_CASE("solve_rigid_pose_ransac recovers the pose of the static majority, not the moving group",
          "[slam_geometry][rigid_ransac]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  const Eigen::Isometry3d T_camera_world =
      make_pose(0.3, Eigen::Vector3d(0.2, 1, -0.1), Eigen::Vector3d(0.1, -0.2, 0.3));
  // 40 % of the points moved together by 25 cm (a person): a rigid motion of its own, so samples
  // drawn inside the group agree with each other, and only the consensus can tell them apart.
  const Eigen::Isometry3d person = make_pose(0.05, Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0.25, 0, 0.05));
  const int count = 150, moving = 60;
  const Pairs pairs = scene(T_camera_world, count, moving, person, 11);
  const RigidPoseRansacResult r = pairs.solve(K);
  REQUIRE(r.ok);
  CHECK(pose_gap(r.T_camera_world, T_camera_world) < 1e-9);
  // Inliers: exactly the static points, those without depth included (scored by their pixels).
  std::vector<int> expected;
  for (int i = moving; i < count; ++i) expected.push_back(i);
  CHECK(r.inliers == expected);
  CHECK(r.iterations >= 1);
  CHECK(r.iterations <= RigidPoseRansacSettings{}.max_iterations);
}

TEST_CASE("solve_rigid_pose_ransac: same input and seed give the same pose bit for bit; another seed finds the same pose",
          "[slam_geometry][rigid_ransac]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  const Eigen::Isometry3d T_camera_world = make_pose(0.2, Eigen::Vector3d(1, 0.2, 0), Eigen::Vector3d(0, 0.1, -0.2));
  Pairs pairs = scene(T_camera_world, 120, 50, make_pose(0.1, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.3, 0.1, 0)),
                      5);
  // Noise on every camera point, so that poses from different samples differ in their last bits.
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0, 0.004);
  for (Eigen::Vector3d& x : pairs.camera) x += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const RigidPoseRansacResult a = pairs.solve(K);
  const RigidPoseRansacResult b = pairs.solve(K);
  REQUIRE(a.ok);
  CHECK(a.T_camera_world.matrix() == b.T_camera_world.matrix());
  CHECK(a.inliers == b.inliers);
  CHECK(a.iterations == b.iterations);
  // Another seed: another sample stream, still the static pose within the noise.
  RigidPoseRansacSettings other;
  other.seed = 12345;
  const RigidPoseRansacResult c = pairs.solve(K, other);
  REQUIRE(c.ok);
  CHECK((c.T_camera_world.translation() - T_camera_world.translation()).norm() < 0.01);
  CHECK((a.T_camera_world.translation() - T_camera_world.translation()).norm() < 0.01);
}

TEST_CASE("solve_rigid_pose_ransac: the refit leaves out pairs whose depth is wrong along the ray",
          "[slam_geometry][rigid_ransac]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  const Eigen::Isometry3d T_camera_world = make_pose(0.25, Eigen::Vector3d(0, 1, 0.3), Eigen::Vector3d(0.2, 0, 0.1));
  Pairs pairs = scene(T_camera_world, 100, 0, Eigen::Isometry3d::Identity(), 21);
  // A few keypoints read a depth 16 cm too far (an edge seeing the background): their pixels stay
  // exact, so they are reprojection inliers, but a 3-D fit through them is pulled off the pose.
  int edge_points = 0;
  for (std::size_t i = 0; i < pairs.camera.size(); i += 20) {
    if (!pairs.camera[i].allFinite()) continue;
    pairs.camera[i] *= (pairs.camera[i].z() + 0.16) / pairs.camera[i].z();
    ++edge_points;
  }
  REQUIRE(edge_points >= 3);
  const RigidPoseRansacResult gated = pairs.solve(K);
  REQUIRE(gated.ok);
  CHECK(gated.inliers.size() == pairs.world.size());
  CHECK(pose_gap(gated.T_camera_world, T_camera_world) < 1e-9);
  // The control: with a tolerance that admits them, the refit goes through them and, still within
  // the 3-pixel threshold everywhere, is kept: the gate is what keeps the pose exact above.
  RigidPoseRansacSettings open;
  open.refit_tolerance_m = 10;
  const RigidPoseRansacResult ungated = pairs.solve(K, open);
  REQUIRE(ungated.ok);
  CHECK(ungated.inliers.size() == pairs.world.size());
  CHECK(pose_gap(ungated.T_camera_world, T_camera_world) > 1e-6);
}

TEST_CASE("solve_rigid_pose_ransac stops early when every pair agrees", "[slam_geometry][rigid_ransac]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  const Eigen::Isometry3d T_camera_world = make_pose(0.1, Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 0, 0.2));
  const Pairs pairs = scene(T_camera_world, 60, 0, Eigen::Isometry3d::Identity(), 2);
  const RigidPoseRansacResult r = pairs.solve(K);
  REQUIRE(r.ok);
  CHECK(r.iterations == 1);  // all-inlier fraction 1: the confidence is reached at once
  CHECK(r.inliers.size() == 60);
}

TEST_CASE("solve_rigid_pose_ransac: unusable input gives no pose or a clear error", "[slam_geometry][rigid_ransac]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  const Eigen::Isometry3d T = make_pose(0.1, Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, 0, 0));
  Pairs pairs = scene(T, 30, 0, Eigen::Isometry3d::Identity(), 3);
  // Two pairs with depth: nothing to sample.
  Pairs sparse = pairs;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 2; i < sparse.camera.size(); ++i) sparse.camera[i] = Eigen::Vector3d(nan, nan, nan);
  CHECK_FALSE(sparse.solve(K).ok);
  // Every point on one line: every sample is degenerate.
  Pairs line;
  for (int i = 0; i < 20; ++i) line.add(Eigen::Vector3d(0.1 * i, 0, 2), Eigen::Vector3d(0.1 * i, 0, 2), K, true);
  const RigidPoseRansacResult on_line = line.solve(K);
  CHECK_FALSE(on_line.ok);
  CHECK(on_line.iterations == RigidPoseRansacSettings{}.max_iterations);
  // Unpaired vectors and bad settings: std::invalid_argument naming the problem.
  Pairs unpaired = pairs;
  unpaired.pixels.pop_back();
  CHECK_THROWS_WITH(unpaired.solve(K), Catch::Contains("differ in size"));
  RigidPoseRansacSettings bad;
  bad.confidence = 1;
  CHECK_THROWS_WITH(pairs.solve(K, bad), Catch::Contains("confidence"));
  bad = {};
  bad.max_iterations = 0;
  CHECK_THROWS_WITH(pairs.solve(K, bad), Catch::Contains("max_iterations"));
  bad = {};
  bad.reprojection_px = -1;
  CHECK_THROWS_WITH(pairs.solve(K, bad), Catch::Contains("reprojection_px"));
  bad = {};
  bad.refit_tolerance_per_m = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(pairs.solve(K, bad), Catch::Contains("refit_tolerance_per_m"));
}
