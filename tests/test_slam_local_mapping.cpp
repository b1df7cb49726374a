// Local bundle adjustment (cge/slam/local_mapping.hpp) and the depth term of the pose refinement
// (cge/ceres/pose_refinement.hpp): synthetic scenes with known truth are the oracle. A map whose
// keyframes see exact projections and depths of true points, with perturbed poses and points, must
// come back to the truth inside the window and stay put outside it; the depth term must pull a pose
// along the direction pixels alone leave free, and flag a depth outlier by its 3-dof chi2.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "ceres_test_scene.hpp"
#include "cge/ceres/pose_refinement.hpp"
#include "cge/slam/local_mapping.hpp"
#include "cge/slam/map.hpp"

namespace {

using cge_test::random_motion;
using cge_test::rotation_error_rad;
using cge_test::translation_error_m;

const cge::PinholeIntrinsics<double> kIntrinsics{535.4, 539.2, 320.1, 247.6};

/// Camera k looks along +z from x = 0.15 k (a sideways dolly), so every camera sees the points.
Eigen::Isometry3d camera_pose(int k) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.15 * k, 0.02 * k, 0.0);
  return T;
}

struct TruthMap {
  cge::slam::Map map;
  std::vector<Eigen::Isometry3d> true_poses;
  std::vector<Eigen::Vector3d> true_points;
};

/// `keyframes` keyframes observing `points` points at 2..4 m with exact pixels and depths (but for
/// the points in `depth_off_by_1m`, whose measured depth is 1 m too far in every keyframe); the map
/// holds the keyframe poses (keyframe 0 exact, others perturbed) and perturbed points.
TruthMap make_map(int keyframes, int points, std::mt19937& rng, const std::vector<int>& depth_off_by_1m = {}) {
  TruthMap t;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int j = 0; j < points; ++j) t.true_points.emplace_back(0.3 + 1.2 * u(rng), 0.9 * u(rng), 3.0 + u(rng));
  for (int k = 0; k < keyframes; ++k) {
    t.true_poses.push_back(camera_pose(k));
    cge::slam::Keyframe kf;
    kf.T_world_camera = k == 0 ? t.true_poses[0] : t.true_poses[k] * random_motion(rng, 0.01, 0.02);
    const Eigen::Isometry3d T_camera_world = t.true_poses[k].inverse();
    for (int j = 0; j < points; ++j) {
      const Eigen::Vector3d p = T_camera_world * t.true_points[static_cast<std::size_t>(j)];
      const Eigen::Vector2d uv = kIntrinsics.project(p);
      kf.keypoints.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f);
      kf.keypoints.back().octave = 0;
      // Pixels are stored as float: the depth stays exact, the pixel is off by < 1e-4 px.
      const bool off = std::find(depth_off_by_1m.begin(), depth_off_by_1m.end(), j) != depth_off_by_1m.end();
      kf.points_camera_m.push_back(off ? Eigen::Vector3d(p.x(), p.y(), p.z() + 1.0) : p);
      kf.labels.push_back(cge::FeatureLabel::static_feature);
    }
    kf.descriptors = cv::Mat::zeros(points, 32, CV_8UC1);
    t.map.add_keyframe(kf);
  }
  for (int j = 0; j < points; ++j) {
    const Eigen::Vector3d noisy =
        t.true_points[static_cast<std::size_t>(j)] + 0.02 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const std::int64_t id = t.map.add_map_point(noisy, cv::Mat::zeros(1, 32, CV_8UC1));
    for (int k = 0; k < keyframes; ++k) t.map.add_observation(id, k, j);
  }
  return t;
}

/// One keyframe seeing one keypoint at (u, v) pixels with depth z: a map with nothing to adjust.
cge::slam::Map one_keyframe_map(float u_px, float v_px, double z_m) {
  cge::slam::Map map;
  cge::slam::Keyframe kf;
  kf.keypoints.emplace_back(u_px, v_px, 31.f);
  kf.points_camera_m.emplace_back(0, 0, z_m);
  kf.labels.push_back(cge::FeatureLabel::static_feature);
  kf.descriptors = cv::Mat::zeros(1, 32, CV_8UC1);
  map.add_keyframe(kf);
  return map;
}

}  // namespace

TEST_CASE("local_bundle_adjustment recovers perturbed poses and points of its window", "[slam]") {
  std::mt19937 rng(5);
  TruthMap t = make_map(4, 80, rng);
  cge::slam::LocalMappingSettings settings;  // window: keyframe 3 and its 10 most covisible (all)
  const cge::slam::LocalBundleAdjustmentReport report =
      cge::slam::local_bundle_adjustment(t.map, 3, kIntrinsics, settings, 1.2);
  REQUIRE(report.ran);
  CHECK(report.window_keyframes == 4);
  CHECK(report.fixed_keyframes == 1);  // keyframe 0, the gauge
  CHECK(report.points == 80);
  CHECK(report.observations == 320);
  CHECK(report.outliers == 0);
  // Keyframe 0 is the world: untouched, bit for bit.
  CHECK(t.map.keyframe(0).T_world_camera.matrix() == t.true_poses[0].matrix());
  for (int k = 1; k < 4; ++k) {
    CAPTURE(k);
    CHECK(rotation_error_rad(t.map.keyframe(k).T_world_camera, t.true_poses[static_cast<std::size_t>(k)]) < 1e-5);
    CHECK(translation_error_m(t.map.keyframe(k).T_world_camera, t.true_poses[static_cast<std::size_t>(k)]) < 1e-5);
  }
  for (int j = 0; j < 80; ++j) {
    CAPTURE(j);
    CHECK((t.map.map_point(j).position_world - t.true_points[static_cast<std::size_t>(j)]).norm() < 1e-4);
  }
}

TEST_CASE("local_bundle_adjustment keeps keyframes outside the window fixed and uses them as the gauge", "[slam]") {
  std::mt19937 rng(9);
  TruthMap t = make_map(5, 60, rng);
  // Keyframe 1 outside the window is exact (as if already optimised); the window is keyframe 4 and
  // its 2 most covisible keyframes (ties by smaller id: 0 and 1), so 2 and 3 observe as fixed.
  t.map.set_keyframe_pose(1, t.true_poses[1]);
  const Eigen::Isometry3d kf2_before = t.map.keyframe(2).T_world_camera;
  const Eigen::Isometry3d kf3_before = t.map.keyframe(3).T_world_camera;
  const double error_before = translation_error_m(t.map.keyframe(4).T_world_camera, t.true_poses[4]);
  cge::slam::LocalMappingSettings settings;
  settings.covisible_keyframes = 2;
  const cge::slam::LocalBundleAdjustmentReport report =
      cge::slam::local_bundle_adjustment(t.map, 4, kIntrinsics, settings, 1.2);
  REQUIRE(report.ran);
  CHECK(report.window_keyframes == 3);
  CHECK(report.fixed_keyframes == 3);  // keyframe 0 (gauge) and the outside observers 2 and 3
  CHECK(t.map.keyframe(2).T_world_camera.matrix() == kf2_before.matrix());
  CHECK(t.map.keyframe(3).T_world_camera.matrix() == kf3_before.matrix());
  // The wrong fixed poses of 2 and 3 pull against the exact 0 and 1: keyframe 4 moves towards its
  // truth without reaching it.
  const double error_after = translation_error_m(t.map.keyframe(4).T_world_camera, t.true_poses[4]);
  CHECK(error_after < error_before);
  CHECK(error_after > 1e-5);
}

TEST_CASE("local_bundle_adjustment fixes the outside keyframes that observe most of the window's points", "[slam]") {
  std::mt19937 rng(13);
  TruthMap t = make_map(6, 60, rng);
  // Keyframe 2 sees points 0..29 only, none of which keyframe 5 sees (5 sees 30..59): it is not
  // covisible with 5 but observes 30 of the window's points. Keyframe 3 sees points 50..59 only.
  for (int j = 0; j < 30; ++j) t.map.erase_observation(j, 5);
  for (int j = 30; j < 60; ++j) t.map.erase_observation(j, 2);
  for (int j = 0; j < 50; ++j) t.map.erase_observation(j, 3);
  cge::slam::LocalMappingSettings settings;
  settings.covisible_keyframes = 2;  // keyframe 5 shares 30 points with 0, 1 and 4, 10 with 3: window 5, 0, 1
  settings.fixed_keyframes = 2;
  const cge::slam::LocalBundleAdjustmentReport report =
      cge::slam::local_bundle_adjustment(t.map, 5, kIntrinsics, settings, 1.2);
  REQUIRE(report.ran);
  CHECK(report.window_keyframes == 3);
  // Outside observers of the window's 60 points: 4 (60), 2 (30), 3 (10); the two first are fixed,
  // with keyframe 0 (the gauge). Ranked by covisibility with keyframe 5, 3 would have come before 2.
  CHECK(report.fixed_keyframe_ids == std::vector<int>{0, 2, 4});
  CHECK(report.fixed_keyframes == 3);
  // Observations of 0, 1, 5 (window), 2 and 4 take part; 3's are left out.
  CHECK(report.observations == 60 + 60 + 30 + 30 + 60);
  settings.fixed_keyframes = 3;
  TruthMap again = make_map(6, 60, rng);
  for (int j = 0; j < 30; ++j) again.map.erase_observation(j, 5);
  for (int j = 30; j < 60; ++j) again.map.erase_observation(j, 2);
  for (int j = 0; j < 50; ++j) again.map.erase_observation(j, 3);
  const cge::slam::LocalBundleAdjustmentReport all =
      cge::slam::local_bundle_adjustment(again.map, 5, kIntrinsics, settings, 1.2);
  CHECK(all.fixed_keyframe_ids == std::vector<int>{0, 2, 3, 4});
  CHECK(all.observations == 60 + 60 + 30 + 30 + 60 + 10);
}

TEST_CASE("local_bundle_adjustment without a point seen twice does nothing; unknown keyframes throw", "[slam]") {
  cge::slam::Map map = one_keyframe_map(100.f, 100.f, 2);
  const std::int64_t p = map.add_map_point(Eigen::Vector3d(0, 0, 2), cv::Mat::zeros(1, 32, CV_8UC1));
  map.add_observation(p, 0, 0);
  const cge::slam::LocalBundleAdjustmentReport report =
      cge::slam::local_bundle_adjustment(map, 0, kIntrinsics, cge::slam::LocalMappingSettings{}, 1.2);
  CHECK_FALSE(report.ran);
  CHECK(map.map_point(p).position_world == Eigen::Vector3d(0, 0, 2));
  CHECK_THROWS_AS(cge::slam::local_bundle_adjustment(map, 1, kIntrinsics, cge::slam::LocalMappingSettings{}, 1.2),
                  std::invalid_argument);
}

TEST_CASE("keyframe_bundle_observation: pixel sigma by octave, depth sigma growing with z squared", "[slam]") {
  cge::slam::Keyframe kf;
  kf.keypoints.emplace_back(10.f, 20.f, 31.f);
  kf.keypoints.back().octave = 2;
  kf.keypoints.emplace_back(30.f, 40.f, 31.f);
  kf.points_camera_m.emplace_back(0.1, 0.2, 2.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  kf.points_camera_m.emplace_back(nan, nan, nan);
  const cge::BundleObservation a = cge::slam::keyframe_bundle_observation(kf, 0, 3, 7, cge::slam::OctaveScales(1.2), 0.003);
  CHECK(a.keyframe == 3);
  CHECK(a.point == 7);
  CHECK(a.pixel_px == Eigen::Vector2d(10, 20));
  CHECK(a.sigma_px == Approx(1.44));
  CHECK(a.depth_m == 2.0);
  CHECK(a.sigma_depth_m == Approx(0.012));  // 0.003 * 2^2
  const cge::BundleObservation b = cge::slam::keyframe_bundle_observation(kf, 1, 0, 0, cge::slam::OctaveScales(1.2), 0.003);
  CHECK(std::isnan(b.depth_m));
}

TEST_CASE("PoseRefiner depth term: recovers the pose, constrains the weak mode, flags a depth outlier", "[slam]") {
  std::mt19937 rng(21);
  // Far points in a narrow depth band: the rotation about the scene centre with the matching
  // sideways translation is the weakest pixel mode.
  const Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<cge::PoseObservation> pixels_only, with_depth;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(1.5 * u(rng), 1.1 * u(rng), 3.5 + 0.2 * u(rng));
    cge::PoseObservation o;
    o.point_world_m = p;
    o.pixel_px = kIntrinsics.project(p);
    pixels_only.push_back(o);
    o.depth_m = p.z();
    o.sigma_depth_m = 0.003 * p.z() * p.z();
    with_depth.push_back(o);
  }
  const Eigen::Isometry3d start = T_world_camera * random_motion(rng, 0.01, 0.03);
  SECTION("exact data: both recover the truth") {
    const cge::PoseRefinementResult r = cge::PoseRefiner().refine(kIntrinsics, with_depth, start);
    CHECK(r.inlier_count == 200);
    CHECK(rotation_error_rad(r.T_world_camera, T_world_camera) < 1e-6);
    CHECK(translation_error_m(r.T_world_camera, T_world_camera) < 1e-6);
  }
  SECTION("noisy pixels, exact depths: the depth term shrinks the error over many trials") {
    double sum_pixels = 0, sum_depth = 0;
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<cge::PoseObservation> a = pixels_only, b = with_depth;
      for (std::size_t i = 0; i < a.size(); ++i) {
        const Eigen::Vector2d e(noise(rng), noise(rng));
        a[i].pixel_px += e;
        b[i].pixel_px += e;
      }
      sum_pixels +=
          translation_error_m(cge::PoseRefiner().refine(kIntrinsics, a, start).T_world_camera, T_world_camera);
      sum_depth += translation_error_m(cge::PoseRefiner().refine(kIntrinsics, b, start).T_world_camera, T_world_camera);
    }
    // Depth sigma here is 0.003 * 3.5^2 = 37 mm: a weak constraint per point, so the gain is modest
    // (about a quarter on this scene) but must be there on average.
    CHECK(sum_depth < sum_pixels);
  }
  SECTION("a depth 10 sigma off with an exact pixel is an outlier (3-dof chi2), the rest inliers") {
    std::vector<cge::PoseObservation> o = with_depth;
    o[17].depth_m += 10 * o[17].sigma_depth_m;
    const cge::PoseRefinementResult r = cge::PoseRefiner().refine(kIntrinsics, o, start);
    CHECK_FALSE(r.inliers[17]);
    CHECK(r.inlier_count == 199);
  }
  SECTION("a depth without a positive sigma is rejected naming the observation") {
    std::vector<cge::PoseObservation> o = with_depth;
    o[3].sigma_depth_m = 0;
    CHECK_THROWS_WITH(cge::PoseRefiner().refine(kIntrinsics, o, start), Catch::Contains("observation 3"));
  }
}

TEST_CASE("local_bundle_adjustment leaves out points without a depth observation", "[slam]") {
  // A camera turning in place (walking_rpy): no baseline between the keyframes, so a point seen
  // only in pixels is free along its ray. Points 0..9 have no depth in any keyframe.
  std::mt19937 rng(13);
  TruthMap t = make_map(4, 60, rng);
  for (int k = 0; k < 4; ++k) {
    Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
    turned.linear() = Eigen::AngleAxisd(0.05 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
    t.true_poses[static_cast<std::size_t>(k)] = turned;
  }
  // Rebuild the observations for the turned cameras: exact pixels, depth only for points 10..59.
  cge::slam::Map map;
  for (int k = 0; k < 4; ++k) {
    cge::slam::Keyframe kf;
    kf.T_world_camera =
        k == 0 ? t.true_poses[0] : t.true_poses[static_cast<std::size_t>(k)] * random_motion(rng, 0.005, 0.01);
    const Eigen::Isometry3d T_camera_world = t.true_poses[static_cast<std::size_t>(k)].inverse();
    for (int j = 0; j < 60; ++j) {
      const Eigen::Vector3d p = T_camera_world * t.true_points[static_cast<std::size_t>(j)];
      const Eigen::Vector2d uv = kIntrinsics.project(p);
      kf.keypoints.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f);
      kf.keypoints.back().octave = 0;
      const double nan = std::numeric_limits<double>::quiet_NaN();
      kf.points_camera_m.push_back(j < 10 ? Eigen::Vector3d(nan, nan, nan) : p);
      kf.labels.push_back(cge::FeatureLabel::static_feature);
    }
    kf.descriptors = cv::Mat::zeros(60, 32, CV_8UC1);
    map.add_keyframe(kf);
  }
  std::vector<Eigen::Vector3d> before;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int j = 0; j < 60; ++j) {
    before.push_back(t.true_points[static_cast<std::size_t>(j)] + 0.02 * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const std::int64_t id = map.add_map_point(before.back(), cv::Mat::zeros(1, 32, CV_8UC1));
    for (int k = 0; k < 4; ++k) map.add_observation(id, k, j);
  }
  const cge::slam::LocalBundleAdjustmentReport report =
      cge::slam::local_bundle_adjustment(map, 3, kIntrinsics, cge::slam::LocalMappingSettings{}, 1.2);
  REQUIRE(report.ran);
  CHECK(report.points_without_depth == 10);
  CHECK(report.points == 50);
  CHECK(report.observations == 200);
  CHECK(report.points_kept == 0);
  for (int j = 0; j < 10; ++j) {
    CAPTURE(j);
    CHECK(map.map_point(j).position_world == before[static_cast<std::size_t>(j)]);  // untouched, bit for bit
  }
  for (int j = 10; j < 60; ++j) {
    CAPTURE(j);
    CHECK((map.map_point(j).position_world - t.true_points[static_cast<std::size_t>(j)]).norm() < 1e-4);
  }
  for (int k = 1; k < 4; ++k) {
    CAPTURE(k);
    CHECK(rotation_error_rad(map.keyframe(k).T_world_camera, t.true_poses[static_cast<std::size_t>(k)]) < 1e-5);
    CHECK(translation_error_m(map.keyframe(k).T_world_camera, t.true_poses[static_cast<std::size_t>(k)]) < 1e-5);
  }
}

TEST_CASE("local_bundle_adjustment keeps a point whose depth observations all end as outliers", "[slam]") {
  // Point 0's measured depth is 1 m off in every keyframe (a chi2 far beyond the 3-dof threshold):
  // at the optimum only its pixels agree, which do not fix it well, so its position is not written.
  std::mt19937 rng(17);
  TruthMap t = make_map(4, 40, rng, {0});
  const Eigen::Vector3d before = t.map.map_point(0).position_world;
  const cge::slam::LocalBundleAdjustmentReport report =
      cge::slam::local_bundle_adjustment(t.map, 3, kIntrinsics, cge::slam::LocalMappingSettings{}, 1.2);
  REQUIRE(report.ran);
  CHECK(report.points == 40);
  CHECK(report.points_kept == 1);
  CHECK(t.map.map_point(0).position_world == before);  // untouched, bit for bit
  for (int j = 1; j < 40; ++j) {
    CAPTURE(j);
    CHECK((t.map.map_point(j).position_world - t.true_points[static_cast<std::size_t>(j)]).norm() < 1e-3);
  }
}

TEST_CASE("LocalBundleAdjustment round by round: each round lands in the map, the end equals the whole BA", "[slam]") {
  std::mt19937 rng_a(9), rng_b(9);
  TruthMap whole = make_map(4, 80, rng_a);
  TruthMap stepwise = make_map(4, 80, rng_b);
  const cge::slam::LocalMappingSettings settings;
  cge::slam::local_bundle_adjustment(whole.map, 3, kIntrinsics, settings, 1.2);

  const Eigen::Isometry3d start = stepwise.map.keyframe(3).T_world_camera;
  cge::slam::LocalBundleAdjustment adjustment(stepwise.map, 3, kIntrinsics, settings, 1.2);
  CHECK(adjustment.keyframe_id() == 3);
  CHECK(adjustment.rounds_left() == 2);
  CHECK(adjustment.report().points == 80);
  CHECK_FALSE(adjustment.report().ran);
  CHECK(cge_test::bit_identical(stepwise.map.keyframe(3).T_world_camera, start));  // nothing solved yet
  adjustment.solve_next_round(stepwise.map);
  CHECK(adjustment.rounds_left() == 1);
  CHECK(adjustment.report().ran);
  // The first round is in the map already, nearer the truth than the start.
  CHECK(translation_error_m(stepwise.map.keyframe(3).T_world_camera, stepwise.true_poses[3]) <
        0.1 * translation_error_m(start, stepwise.true_poses[3]));
  adjustment.solve_next_round(stepwise.map);
  CHECK(adjustment.done());
  for (int k = 0; k < 4; ++k) {
    CAPTURE(k);
    CHECK(cge_test::bit_identical(stepwise.map.keyframe(k).T_world_camera, whole.map.keyframe(k).T_world_camera));
  }
  for (int j = 0; j < 80; ++j) CHECK(stepwise.map.map_point(j).position_world == whole.map.map_point(j).position_world);
}

TEST_CASE("LocalBundleAdjustment in slices: each slice lands in the map within its iterations, the end near the whole BA",
          "[slam][slices]") {
  std::mt19937 rng_a(9), rng_b(9);
  TruthMap whole = make_map(4, 80, rng_a);
  TruthMap sliced = make_map(4, 80, rng_b);
  const cge::slam::LocalMappingSettings settings;
  cge::slam::local_bundle_adjustment(whole.map, 3, kIntrinsics, settings, 1.2);

  const Eigen::Isometry3d start = sliced.map.keyframe(3).T_world_camera;
  cge::slam::LocalBundleAdjustment adjustment(sliced.map, 3, kIntrinsics, settings, 1.2);
  CHECK(adjustment.solve_next_slice(sliced.map, 1) == 1);
  CHECK(adjustment.report().ran);
  // One iteration is in the map already: nearer the truth than the start.
  CHECK(translation_error_m(sliced.map.keyframe(3).T_world_camera, sliced.true_poses[3]) <
        translation_error_m(start, sliced.true_poses[3]));
  int slices = 1;
  while (!adjustment.done()) {
    CHECK(adjustment.solve_next_slice(sliced.map, 1) <= 1);
    REQUIRE(++slices < 100);
  }
  CHECK(adjustment.solve_next_slice(sliced.map, 1) == 0);
  for (int k = 0; k < 4; ++k) {
    CAPTURE(k);
    CHECK(translation_error_m(sliced.map.keyframe(k).T_world_camera, whole.map.keyframe(k).T_world_camera) < 1e-4);
  }
}

TEST_CASE("LocalBundleAdjustment with nothing to optimise is done at once", "[slam]") {
  cge::slam::Map map = one_keyframe_map(10.f, 10.f, 1);
  cge::slam::LocalBundleAdjustment adjustment(map, 0, kIntrinsics, cge::slam::LocalMappingSettings{}, 1.2);
  CHECK(adjustment.done());
  CHECK(adjustment.rounds_left() == 0);
  adjustment.solve_next_round(map);
  CHECK_FALSE(adjustment.report().ran);
  CHECK_THROWS_AS(cge::slam::LocalBundleAdjustment(map, 1, kIntrinsics, cge::slam::LocalMappingSettings{}, 1.2),
                  std::invalid_argument);
}
