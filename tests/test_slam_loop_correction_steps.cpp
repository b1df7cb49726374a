// LoopCorrection (cge/slam/loop_correction.hpp) on hand-built maps with known truth.
// Oracles: (1) with every rotation the identity and rotation held by a far larger weight, the pose
// graph is linear least squares on positions, and on one cycle of n equally weighted edges the
// closure error spreads evenly: keyframe k moves by k (L - D) / n, D the drifted chain's end-to-end
// translation and L the loop's measured one (derived in the test, computed here from D and L);
// (2) with exact pixels and depths of true points, pose graph + global BA returns the true poses
// and points. Invariant: a point seen by one keyframe keeps its place in that keyframe's camera.
#include <catch2/catch.hpp>

#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "ceres_test_scene.hpp"
#include "cge/slam/loop_correction.hpp"
#include "cge/slam/map.hpp"

namespace {

using cge_test::rotation_error_rad;
using cge_test::translation_error_m;

const cge::PinholeIntrinsics<double> kIntrinsics{535.4, 539.2, 320.1, 247.6};
constexpr double kOrbScale = 1.2;

Eigen::Isometry3d translation(const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = t;
  return T;
}

/// Appends keypoint `p_camera` (exact pixel and depth) to a keyframe under construction.
void add_keypoint(cge::slam::Keyframe& kf, const Eigen::Vector3d& p_camera) {
  const Eigen::Vector2d uv = kIntrinsics.project(p_camera);
  kf.keypoints.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f);
  kf.keypoints.back().octave = 0;
  kf.points_camera_m.push_back(p_camera);
  kf.labels.push_back(cge::FeatureLabel::static_feature);
}

/// A loop of keyframes (identity rotations, true positions `truth`), the map's poses drifted by
/// k * drift; each keyframe sees `own_points` points of its own (one observation each), placed
/// where its drifted pose puts them. Returns the ids of keyframe k's points in points[k].
struct LoopMap {
  cge::slam::Map map;
  std::vector<std::vector<std::int64_t>> points;
};

LoopMap drifted_loop(const std::vector<Eigen::Vector3d>& truth, const Eigen::Vector3d& drift, int own_points) {
  LoopMap m;
  m.points.resize(truth.size());
  for (std::size_t k = 0; k < truth.size(); ++k) {
    cge::slam::Keyframe kf;
    kf.T_world_camera = translation(truth[k] + static_cast<double>(k) * drift);
    for (int j = 0; j < own_points; ++j) add_keypoint(kf, Eigen::Vector3d(0.3 * j - 0.3, 0.1 * j - 0.1, 2.0 + j));
    kf.descriptors = cv::Mat::zeros(own_points, 32, CV_8UC1);
    const int id = m.map.add_keyframe(kf);
    for (int j = 0; j < own_points; ++j) {
      const Eigen::Vector3d p_world = kf.T_world_camera * kf.points_camera_m[static_cast<std::size_t>(j)];
      const std::int64_t p = m.map.add_map_point(p_world, cv::Mat::zeros(1, 32, CV_8UC1), id);
      m.map.add_observation(p, id, j);
      m.points[k].push_back(p);
    }
  }
  return m;
}

/// Pose graph only, rotation held far stiffer than translation (so positions are the linear
/// least-squares problem of the oracle).
cge::slam::LoopCorrectionSettings translation_only_pose_graph() {
  cge::slam::LoopCorrectionSettings s;
  s.bundle_adjustment = false;
  s.rotation_weight = 1e8;
  s.translation_weight = 1;
  return s;
}

/// Positions after spreading the closure error of a cycle of `edges` equally weighted edges over
/// the chain `before` (positions of the cycle's keyframes in chain order; the loop joins the first
/// and the last): keyframe k moves by k (L - D) / edges.
std::vector<Eigen::Vector3d> spread_closure_error(const std::vector<Eigen::Vector3d>& before,
                                                  const Eigen::Vector3d& loop_translation, int edges) {
  const Eigen::Vector3d D = before.back() - before.front();
  std::vector<Eigen::Vector3d> after;
  for (std::size_t k = 0; k < before.size(); ++k) {
    after.push_back(before[k] + static_cast<double>(k) * (loop_translation - D) / edges);
  }
  return after;
}

const std::vector<Eigen::Vector3d> kLoopTruth = {{0, 0, 0},   {1.0, 0, 0},  {2.0, 0.1, 0.5},
                                                 {2.0, 0.1, 1.5}, {1.0, 0, 2.0}, {0.1, 0, 0.3}};
const Eigen::Vector3d kDrift(0.02, -0.01, 0.03);

}  // namespace

TEST_CASE("LoopCorrection spreads a translation drift evenly around the loop", "[slam][loop_correction]") {
  LoopMap m = drifted_loop(kLoopTruth, kDrift, 3);
  const int last = static_cast<int>(kLoopTruth.size()) - 1;
  std::vector<Eigen::Isometry3d> before;
  std::vector<Eigen::Vector3d> before_positions;
  for (const cge::slam::Keyframe& kf : m.map.keyframes()) {
    before.push_back(kf.T_world_camera);
    before_positions.push_back(kf.T_world_camera.translation());
  }
  std::vector<Eigen::Vector3d> point_in_camera_before;
  for (const cge::slam::MapPoint& p : m.map.map_points()) {
    point_in_camera_before.push_back(before[static_cast<std::size_t>(p.observations.front().keyframe_id)].inverse() *
                                     p.position_world);
  }

  cge::slam::LoopCorrection correction(translation_only_pose_graph(), kIntrinsics, kOrbScale);
  const Eigen::Isometry3d T_match_query = translation(kLoopTruth[0]).inverse() * translation(kLoopTruth.back());
  correction.add_loop({0, last, T_match_query});
  CHECK(correction.due(last));
  const cge::slam::LoopCorrectionReport report = correction.correct(m.map, last);

  CHECK(report.live_keyframes == 6);
  CHECK(report.sequential_edges == 5);
  CHECK(report.covisibility_edges == 0);  // no shared points
  CHECK(report.loop_edges == 1);
  CHECK_FALSE(report.bundle_adjusted);
  CHECK(correction.corrections() == 1);

  const std::vector<Eigen::Vector3d> expected =
      spread_closure_error(before_positions, T_match_query.translation(), 6);
  CHECK(m.map.keyframe(0).T_world_camera.matrix() == before[0].matrix());  // the gauge
  for (int k = 0; k <= last; ++k) {
    CAPTURE(k);
    const Eigen::Isometry3d& T = m.map.keyframe(k).T_world_camera;
    CHECK((T.translation() - expected[static_cast<std::size_t>(k)]).norm() < 1e-6);
    CHECK(rotation_error_rad(T, Eigen::Isometry3d::Identity()) < 1e-6);
  }
  // The loop's keyframes: their relative pose misses the measured one by a sixth of the drift.
  const Eigen::Isometry3d T_match_query_after =
      m.map.keyframe(0).T_world_camera.inverse() * m.map.keyframe(last).T_world_camera;
  const double error_before = translation_error_m(before[0].inverse() * before[static_cast<std::size_t>(last)], T_match_query);
  const double error_after = translation_error_m(T_match_query_after, T_match_query);
  CHECK(error_before == Approx(5 * kDrift.norm()).epsilon(1e-12));
  CHECK(error_after == Approx(error_before / 6).epsilon(1e-5));
  // Points move with their keyframes.
  for (const cge::slam::MapPoint& p : m.map.map_points()) {
    CAPTURE(p.id);
    const int k = p.observations.front().keyframe_id;
    CHECK((m.map.keyframe(k).T_world_camera.inverse() * p.position_world -
           point_in_camera_before[static_cast<std::size_t>(p.id)])
              .norm() < 1e-9);
  }
  // What the tracker's last pose follows: the query keyframe's move.
  CHECK((report.T_corrected_old.matrix() -
         (m.map.keyframe(last).T_world_camera * before[static_cast<std::size_t>(last)].inverse()).matrix())
            .norm() < 1e-12);
}

TEST_CASE("LoopCorrection is due again only more than min_keyframes_between keyframes later",
          "[slam][loop_correction]") {
  LoopMap m = drifted_loop(kLoopTruth, kDrift, 1);
  cge::slam::LoopCorrectionSettings settings = translation_only_pose_graph();
  settings.min_keyframes_between = 10;
  cge::slam::LoopCorrection correction(settings, kIntrinsics, kOrbScale);
  CHECK(correction.due(0));
  correction.add_loop({0, 5, Eigen::Isometry3d::Identity()});
  correction.correct(m.map, 5);
  CHECK_FALSE(correction.due(15));
  CHECK(correction.due(16));
  correction.add_loop({1, 4, Eigen::Isometry3d::Identity()});
  CHECK(correction.loop_edges().size() == 2);
  CHECK(correction.correct(m.map, 5).loop_edges == 2);  // every loop so far joins every later graph
  CHECK(correction.corrections() == 2);
}

TEST_CASE("LoopCorrection moves a loop edge off a culled keyframe to its live parent", "[slam][loop_correction]") {
  LoopMap m = drifted_loop(kLoopTruth, kDrift, 2);
  const Eigen::Isometry3d T_match_query = translation(kLoopTruth[0]).inverse() * translation(kLoopTruth[5]);
  m.map.cull_keyframe(5, 4);  // its points lose their only observation and turn bad
  const Eigen::Isometry3d T_4_5 = m.map.keyframe(4).T_world_camera.inverse() * m.map.keyframe(5).T_world_camera;
  std::vector<Eigen::Vector3d> before_positions;
  for (int k = 0; k <= 4; ++k) before_positions.push_back(m.map.keyframe(k).T_world_camera.translation());
  const Eigen::Vector3d bad_point_before = m.map.map_point(m.points[5][0]).position_world;
  const Eigen::Isometry3d T_4_before = m.map.keyframe(4).T_world_camera;

  cge::slam::LoopCorrection correction(translation_only_pose_graph(), kIntrinsics, kOrbScale);
  correction.add_loop({0, 5, T_match_query});
  const cge::slam::LoopCorrectionReport report = correction.correct(m.map, 5);

  CHECK(report.live_keyframes == 5);
  CHECK(report.sequential_edges == 4);
  // The edge 0 -> 5 becomes 0 -> 4 through 5's pose relative to 4: L = t_05 - t_45 (no rotation).
  const std::vector<Eigen::Vector3d> expected =
      spread_closure_error(before_positions, T_match_query.translation() - T_4_5.translation(), 5);
  for (int k = 0; k <= 4; ++k) {
    CAPTURE(k);
    CHECK((m.map.keyframe(k).T_world_camera.translation() - expected[static_cast<std::size_t>(k)]).norm() < 1e-6);
  }
  // The culled keyframe follows its parent; the correction it reports is its parent's move.
  const Eigen::Isometry3d T_4 = m.map.keyframe(4).T_world_camera;
  CHECK(((T_4 * T_4_5).matrix() - m.map.keyframe(5).T_world_camera.matrix()).norm() < 1e-12);
  CHECK(((T_4 * T_4_before.inverse()).matrix() - report.T_corrected_old.matrix()).norm() < 1e-12);
  CHECK(m.map.map_point(m.points[5][0]).position_world == bad_point_before);
}

TEST_CASE("LoopCorrection leaves out a loop whose ends were culled into one keyframe", "[slam][loop_correction]") {
  LoopMap m = drifted_loop(kLoopTruth, kDrift, 2);
  const Eigen::Isometry3d T_3_5 = translation(kLoopTruth[3]).inverse() * translation(kLoopTruth[5]);
  const Eigen::Isometry3d T_0_5 = translation(kLoopTruth[0]).inverse() * translation(kLoopTruth[5]);
  m.map.cull_keyframe(5, 4);
  m.map.cull_keyframe(3, 4);  // the loop 3 -> 5 now joins keyframe 4 to itself
  cge::slam::LoopCorrection correction(translation_only_pose_graph(), kIntrinsics, kOrbScale);
  correction.add_loop({3, 5, T_3_5});
  correction.add_loop({0, 5, T_0_5});
  const cge::slam::LoopCorrectionReport report = correction.correct(m.map, 5);
  CHECK(report.live_keyframes == 4);
  CHECK(report.loop_edges == 1);  // 0 -> 5, moved to 0 -> 4
  CHECK(report.collapsed_loop_edges == 1);
  for (int k : {0, 1, 2, 4}) CHECK(m.map.keyframe(k).T_world_camera.matrix().allFinite());
}

TEST_CASE("LoopCorrection with global BA returns drifted keyframes and points to the truth",
          "[slam][loop_correction]") {
  // Five cameras on a sideways dolly, all seeing 40 shared points (exact pixels and depths); each
  // also sees 2 points of its own. The map's poses drift by k * 2 cm; shared points are perturbed.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr int kKeyframes = 5, kShared = 40, kOwn = 2;
  std::vector<Eigen::Isometry3d> truth;
  for (int k = 0; k < kKeyframes; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d(Eigen::AngleAxisd(0.03 * k, Eigen::Vector3d::UnitY()));
    T.translation() = Eigen::Vector3d(0.15 * k, 0.02 * k, 0.0);
    truth.push_back(T);
  }
  std::vector<Eigen::Vector3d> shared_truth;
  for (int j = 0; j < kShared; ++j) shared_truth.emplace_back(0.3 + 1.2 * u(rng), 0.9 * u(rng), 3.0 + u(rng));

  cge::slam::Map map;
  std::vector<Eigen::Isometry3d> before;
  for (int k = 0; k < kKeyframes; ++k) {
    cge::slam::Keyframe kf;
    kf.T_world_camera = k == 0 ? truth[0] : truth[static_cast<std::size_t>(k)] * cge_test::random_motion(rng, 0.005, 0.02 * k);
    before.push_back(kf.T_world_camera);
    const Eigen::Isometry3d T_camera_world = truth[static_cast<std::size_t>(k)].inverse();
    for (const Eigen::Vector3d& p : shared_truth) add_keypoint(kf, T_camera_world * p);
    for (int j = 0; j < kOwn; ++j) add_keypoint(kf, Eigen::Vector3d(0.2 * j, -0.1, 2.5));
    kf.descriptors = cv::Mat::zeros(kShared + kOwn, 32, CV_8UC1);
    map.add_keyframe(kf);
  }
  for (int j = 0; j < kShared; ++j) {
    const Eigen::Vector3d noisy = shared_truth[static_cast<std::size_t>(j)] + 0.02 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const std::int64_t id = map.add_map_point(noisy, cv::Mat::zeros(1, 32, CV_8UC1));
    for (int k = 0; k < kKeyframes; ++k) map.add_observation(id, k, j);
  }
  std::vector<std::int64_t> own_points;
  std::vector<Eigen::Vector3d> own_in_camera;
  for (int k = 0; k < kKeyframes; ++k) {
    for (int j = 0; j < kOwn; ++j) {
      const Eigen::Vector3d p_camera = map.keyframe(k).points_camera_m[static_cast<std::size_t>(kShared + j)];
      const std::int64_t id = map.add_map_point(before[static_cast<std::size_t>(k)] * p_camera, cv::Mat::zeros(1, 32, CV_8UC1));
      map.add_observation(id, k, kShared + j);
      own_points.push_back(id);
      own_in_camera.push_back(p_camera);
    }
  }

  cge::slam::LoopCorrectionSettings settings;
  settings.covisibility_min_shared_points = kShared;  // every pair is covisible
  cge::slam::LoopCorrection correction(settings, kIntrinsics, kOrbScale);
  correction.add_loop({0, kKeyframes - 1, truth[0].inverse() * truth[kKeyframes - 1]});
  const cge::slam::LoopCorrectionReport report = correction.correct(map, kKeyframes - 1);

  CHECK(report.sequential_edges == kKeyframes - 1);
  CHECK(report.covisibility_edges == 6);  // pairs (0,2) (0,3) (0,4) (1,3) (1,4) (2,4)
  CHECK(report.loop_edges == 1);
  REQUIRE(report.bundle_adjusted);
  CHECK(report.bundle_points == kShared);  // own points are seen once: not in the BA
  for (int k = 0; k < kKeyframes; ++k) {
    CAPTURE(k);
    CHECK(rotation_error_rad(map.keyframe(k).T_world_camera, truth[static_cast<std::size_t>(k)]) < 1e-5);
    CHECK(translation_error_m(map.keyframe(k).T_world_camera, truth[static_cast<std::size_t>(k)]) < 1e-5);
  }
  for (int j = 0; j < kShared; ++j) {
    CAPTURE(j);
    CHECK((map.map_point(j).position_world - shared_truth[static_cast<std::size_t>(j)]).norm() < 1e-4);
  }
  for (std::size_t i = 0; i < own_points.size(); ++i) {
    CAPTURE(i);
    const cge::slam::MapPoint& p = map.map_point(own_points[i]);
    const Eigen::Isometry3d& T = map.keyframe(p.observations.front().keyframe_id).T_world_camera;
    CHECK((T.inverse() * p.position_world - own_in_camera[i]).norm() < 1e-9);
  }
}

TEST_CASE("LoopCorrection refuses bad settings, loops and keyframes with a message", "[slam][loop_correction]") {
  cge::slam::LoopCorrectionSettings bad;
  bad.min_keyframes_between = -1;
  CHECK_THROWS_WITH(cge::slam::LoopCorrection(bad, kIntrinsics, kOrbScale),
                    Catch::Contains("min_keyframes_between"));
  bad = cge::slam::LoopCorrectionSettings{};
  bad.translation_weight = 0;
  CHECK_THROWS_WITH(cge::slam::LoopCorrection(bad, kIntrinsics, kOrbScale), Catch::Contains("translation_weight"));
  CHECK_THROWS_WITH(cge::slam::LoopCorrection({}, kIntrinsics, 0.5), Catch::Contains("orb_scale_factor"));

  LoopMap m = drifted_loop(kLoopTruth, kDrift, 1);
  cge::slam::LoopCorrection correction({}, kIntrinsics, kOrbScale);
  CHECK_THROWS_AS(correction.add_loop({-1, 3, Eigen::Isometry3d::Identity()}), std::invalid_argument);
  CHECK_THROWS_AS(correction.add_loop({2, 2, Eigen::Isometry3d::Identity()}), std::invalid_argument);
  CHECK_THROWS_WITH(correction.correct(m.map, 6), Catch::Contains("no keyframe 6"));
  correction.add_loop({0, 9, Eigen::Isometry3d::Identity()});
  const Eigen::Isometry3d pose_before = m.map.keyframe(5).T_world_camera;
  CHECK_THROWS_WITH(correction.correct(m.map, 5), Catch::Contains("keyframes 0 and 9"));
  CHECK(m.map.keyframe(5).T_world_camera.matrix() == pose_before.matrix());  // refused before any change
  CHECK(correction.corrections() == 0);
}
