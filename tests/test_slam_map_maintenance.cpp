// Map maintenance (cge/slam/map.hpp erase / replace / cull) on maps built by hand: every expected
// erasure and cull is worked out in the comments, and the covisibility the map keeps incrementally is
// compared, after every change, with a brute-force recount from the points' observations.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/map.hpp"
#include "test_support.hpp"

namespace {

using cge::slam::Keyframe;
using cge::slam::Map;

const cge::PinholeIntrinsics<double> kIntrinsics{535.4, 539.2, 320.1, 247.6};
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A keypoint for the hand-built keyframes: undistorted pixel, octave, depth (NaN: none), label.
struct Kp {
  double u = 0, v = 0;
  int octave = 0;
  double depth_m = kNaN;
  cge::FeatureLabel label = cge::FeatureLabel::static_feature;
  cv::Mat descriptor;  // 1 x 32; zeros when empty
};

Kp kp_of(double u, double v, int octave, double depth_m) {
  Kp k;
  k.u = u;
  k.v = v;
  k.octave = octave;
  k.depth_m = depth_m;
  return k;
}

Keyframe make_keyframe(const Eigen::Isometry3d& T_world_camera, const std::vector<Kp>& kps) {
  Keyframe kf;
  kf.T_world_camera = T_world_camera;
  kf.descriptors = cv::Mat::zeros(static_cast<int>(kps.size()), 32, CV_8UC1);
  for (std::size_t i = 0; i < kps.size(); ++i) {
    const Kp& k = kps[i];
    cv::KeyPoint kp(static_cast<float>(k.u), static_cast<float>(k.v), 31.f);
    kp.octave = k.octave;
    kf.keypoints.push_back(kp);
    kf.undistorted_px.emplace_back(static_cast<float>(k.u), static_cast<float>(k.v));
    kf.labels.push_back(k.label);
    kf.points_camera_m.push_back(std::isnan(k.depth_m) ? Eigen::Vector3d(kNaN, kNaN, kNaN)
                                                       : kIntrinsics.backproject(k.u, k.v, k.depth_m));
    if (!k.descriptor.empty()) k.descriptor.copyTo(kf.descriptors.row(static_cast<int>(i)));
  }
  return kf;
}

/// `n` keypoints with depth 2 m (octave 0) on a grid, for maps where only the structure matters.
Keyframe plain_keyframe(int n, double depth_m = 2.0, int octave = 0) {
  std::vector<Kp> kps;
  for (int i = 0; i < n; ++i) kps.push_back(kp_of(20.0 + 10 * (i % 60), 20.0 + 10 * (i / 60), octave, depth_m));
  return make_keyframe(Eigen::Isometry3d::Identity(), kps);
}

cv::Mat zero_descriptor() { return cv::Mat::zeros(1, 32, CV_8UC1); }

/// Recounts covisibility from the points' observations and checks the map's against it, and that
/// the keyframes' slots and the points' observations agree both ways; bad points have no
/// observations, culled keyframes observe nothing and are nobody's covisible keyframe.
void check_map_consistent(const Map& map) {
  const int n = map.keyframe_count();
  std::vector<std::vector<int>> shared(static_cast<std::size_t>(n), std::vector<int>(static_cast<std::size_t>(n), 0));
  std::int64_t bad = 0;
  for (const cge::slam::MapPoint& p : map.map_points()) {
    bad += p.bad;
    if (p.bad) CHECK(p.observations.empty());
    for (const auto& a : p.observations) {
      CHECK(map.keyframe(a.keyframe_id).map_point_ids[static_cast<std::size_t>(a.keypoint_index)] == p.id);
      for (const auto& b : p.observations) {
        if (a.keyframe_id != b.keyframe_id) ++shared[static_cast<std::size_t>(a.keyframe_id)][static_cast<std::size_t>(b.keyframe_id)];
      }
    }
  }
  CHECK(map.active_map_point_count() == map.map_point_count() - bad);
  int culled = 0;
  for (int a = 0; a < n; ++a) {
    const Keyframe& kf = map.keyframe(a);
    culled += kf.culled;
    if (kf.culled) CHECK(map.observed_points(a) == 0);
    for (std::size_t i = 0; i < kf.map_point_ids.size(); ++i) {
      const std::int64_t id = kf.map_point_ids[i];
      if (id < 0) continue;
      const auto& obs = map.map_point(id).observations;
      CHECK(std::count_if(obs.begin(), obs.end(), [&](const cge::slam::Observation& o) {
              return o.keyframe_id == a && o.keypoint_index == static_cast<int>(i);
            }) == 1);
    }
    std::vector<int> expected_covisible;
    for (int b = 0; b < n; ++b) {
      const int s = shared[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)];
      CHECK(map.shared_points(a, b) == s);
      if (s > 0) expected_covisible.push_back(b);
    }
    std::vector<int> covisible = map.covisible_keyframes(a, -1);
    std::sort(covisible.begin(), covisible.end());
    CHECK(covisible == expected_covisible);
    for (const int b : covisible) CHECK_FALSE(map.keyframe(b).culled);
    CHECK((map.keyframe_pose(a).matrix() == kf.T_world_camera.matrix()));
  }
  CHECK(map.active_keyframe_count() == n - culled);
}

Eigen::Isometry3d some_pose(double angle, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

}  // namespace

// ---- Map API -------------------------------------------------------------------------------------

TEST_CASE("Map keeps undistorted pixels, creation keyframes and found/visible counters", "[maintenance][slam]") {
  Map map;
  Keyframe kf = plain_keyframe(3);
  kf.undistorted_px.clear();
  map.add_keyframe(kf);  // undistorted_px filled from the keypoints
  REQUIRE(map.keyframe(0).undistorted_px.size() == 3);
  CHECK(map.keyframe(0).undistorted_px[2] == map.keyframe(0).keypoints[2].pt);
  Keyframe wrong = plain_keyframe(3);
  wrong.undistorted_px.pop_back();
  CHECK_THROWS_AS(map.add_keyframe(wrong), std::invalid_argument);
  Keyframe culled = plain_keyframe(3);
  culled.culled = true;
  CHECK_THROWS_AS(map.add_keyframe(culled), std::invalid_argument);

  const std::int64_t a = map.add_map_point(Eigen::Vector3d(0, 0, 2), zero_descriptor());
  const std::int64_t b = map.add_map_point(Eigen::Vector3d(0, 0, 2), zero_descriptor(), 0);
  CHECK(map.map_point(a).created_by_keyframe == -1);
  CHECK(map.map_point(b).created_by_keyframe == 0);
  CHECK(map.map_point(a).visible == 1);
  CHECK(map.map_point(a).found == 1);
  CHECK_FALSE(map.map_point(a).bad);
  CHECK(cge_test::invalid_argument_message([&] { map.add_map_point(Eigen::Vector3d(0, 0, 2), zero_descriptor(), 1); })
            .find("keyframe 1") != std::string::npos);
  map.increase_visible(a, 3);
  map.increase_found(a);
  CHECK(map.map_point(a).visible == 4);
  CHECK(map.map_point(a).found == 2);
  CHECK_THROWS_AS(map.increase_visible(a, -1), std::invalid_argument);
  CHECK_THROWS_AS(map.increase_found(7, 1), std::invalid_argument);
  CHECK(map.active_map_point_count() == 2);
  CHECK(map.active_keyframe_count() == 1);
}

TEST_CASE("Map::erase_observation and erase_map_point keep covisibility exact", "[maintenance][slam]") {
  Map map;
  for (int k = 0; k < 3; ++k) map.add_keyframe(plain_keyframe(4));
  // p0 seen by 0, 1, 2; p1 by 0, 1; p2 by 1, 2.
  const std::int64_t p0 = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  const std::int64_t p1 = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  const std::int64_t p2 = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  for (int k = 0; k < 3; ++k) map.add_observation(p0, k, 0);
  map.add_observation(p1, 0, 1);
  map.add_observation(p1, 1, 1);
  map.add_observation(p2, 1, 2);
  map.add_observation(p2, 2, 2);
  check_map_consistent(map);
  CHECK(map.shared_points(0, 1) == 2);
  CHECK(map.shared_points(0, 2) == 1);

  map.erase_observation(p0, 2);  // 0-2 share nothing now: 2 is no longer covisible with 0
  check_map_consistent(map);
  CHECK(map.shared_points(0, 2) == 0);
  CHECK(map.covisible_keyframes(0, -1) == std::vector<int>{1});
  CHECK(map.covisible_keyframes(2, -1) == std::vector<int>{1});
  CHECK(map.keyframe(2).map_point_ids[0] == -1);
  CHECK_FALSE(map.map_point(p0).bad);
  CHECK(cge_test::invalid_argument_message([&] { map.erase_observation(p0, 2); }).find("does not observe") !=
        std::string::npos);
  CHECK_THROWS_AS(map.erase_observation(9, 0), std::invalid_argument);
  CHECK_THROWS_AS(map.erase_observation(p0, 5), std::invalid_argument);

  map.erase_observation(p1, 0);
  CHECK_FALSE(map.map_point(p1).bad);  // one observation left
  map.erase_observation(p1, 1);
  CHECK(map.map_point(p1).bad);  // none left
  CHECK(map.active_map_point_count() == 2);
  check_map_consistent(map);
  // A bad point takes no observation; the freed slot takes another point.
  CHECK(cge_test::invalid_argument_message([&] { map.add_observation(p1, 0, 1); }).find("bad") != std::string::npos);
  map.add_observation(p2, 0, 1);
  check_map_consistent(map);

  map.erase_map_point(p0);
  CHECK(map.map_point(p0).bad);
  CHECK(map.map_point(p0).observations.empty());
  map.erase_map_point(p0);  // already bad: nothing happens
  check_map_consistent(map);
  CHECK(map.shared_points(0, 1) == 1);  // p2 only
  CHECK(map.active_map_point_count() == 1);
}

TEST_CASE("Map::replace_map_point moves observations, drops duplicates and sums the counters", "[maintenance][slam]") {
  Map map;
  for (int k = 0; k < 4; ++k) map.add_keyframe(plain_keyframe(4));
  // old seen by 0 (kp 0), 1 (kp 0), 2 (kp 0); keep seen by 2 (kp 1), 3 (kp 1).
  const std::int64_t old_id = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  const std::int64_t keep = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  for (int k = 0; k < 3; ++k) map.add_observation(old_id, k, 0);
  map.add_observation(keep, 2, 1);
  map.add_observation(keep, 3, 1);
  map.increase_visible(old_id, 4);  // 5
  map.increase_found(old_id, 2);    // 3
  map.increase_visible(keep, 1);    // 2
  check_map_consistent(map);

  map.replace_map_point(old_id, keep);
  check_map_consistent(map);
  const cge::slam::MapPoint& k = map.map_point(keep);
  CHECK(map.map_point(old_id).bad);
  CHECK(map.map_point(old_id).observations.empty());
  // 0 and 1 move over with their keypoints; 2 saw keep already: its old observation is dropped.
  REQUIRE(k.observations.size() == 4);
  CHECK(map.keyframe(0).map_point_ids[0] == keep);
  CHECK(map.keyframe(1).map_point_ids[0] == keep);
  CHECK(map.keyframe(2).map_point_ids[0] == -1);
  CHECK(map.keyframe(2).map_point_ids[1] == keep);
  CHECK(k.visible == 5 + 2);
  CHECK(k.found == 3 + 1);
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) CHECK(map.shared_points(a, b) == (a == b ? 0 : 1));
  }
  CHECK_THROWS_AS(map.replace_map_point(keep, keep), std::invalid_argument);
  CHECK(cge_test::invalid_argument_message([&] { map.replace_map_point(old_id, keep); }).find("bad") !=
        std::string::npos);
  CHECK_THROWS_AS(map.replace_map_point(keep, 99), std::invalid_argument);
}

TEST_CASE("Map::cull_keyframe: the culled keyframe observes nothing and its pose follows its parent",
          "[maintenance][slam]") {
  Map map;
  for (int k = 0; k < 4; ++k) {
    Keyframe kf = plain_keyframe(2);
    kf.T_world_camera = some_pose(0.1 * k, Eigen::Vector3d(0.2 * k, 0.05 * k, -0.1 * k));
    map.add_keyframe(kf);
  }
  // p seen by all four; q by 1 and 2 only.
  const std::int64_t p = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  const std::int64_t q = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  for (int k = 0; k < 4; ++k) map.add_observation(p, k, 0);
  map.add_observation(q, 1, 1);
  map.add_observation(q, 2, 1);
  const Eigen::Isometry3d pose1 = map.keyframe(1).T_world_camera;
  const Eigen::Isometry3d pose2 = map.keyframe(2).T_world_camera;
  const Eigen::Isometry3d pose3 = map.keyframe(3).T_world_camera;

  CHECK(cge_test::invalid_argument_message([&] { map.cull_keyframe(0, 1); }).find("keyframe 0") != std::string::npos);
  CHECK_THROWS_AS(map.cull_keyframe(2, 2), std::invalid_argument);
  CHECK_THROWS_AS(map.cull_keyframe(4, 1), std::invalid_argument);
  CHECK_THROWS_AS(map.cull_keyframe(2, -1), std::invalid_argument);

  map.cull_keyframe(2, 3);
  check_map_consistent(map);
  CHECK(map.keyframe(2).culled);
  CHECK(map.keyframe(2).parent == 3);
  CHECK(map.observed_points(2) == 0);
  CHECK(map.map_point(q).observations.size() == 1);  // q keeps keyframe 1
  CHECK_FALSE(map.map_point(q).bad);
  CHECK(map.active_keyframe_count() == 3);
  CHECK(map.covisible_keyframes(2, -1).empty());
  for (int k : {0, 1, 3}) {
    const auto c = map.covisible_keyframes(k, -1);
    CHECK(std::find(c.begin(), c.end(), 2) == c.end());
  }
  CHECK((map.keyframe_pose(2).matrix() - pose2.matrix()).norm() < 1e-12);
  CHECK(cge_test::invalid_argument_message([&] { map.cull_keyframe(1, 2); }).find("culled") != std::string::npos);
  CHECK_THROWS_AS(map.cull_keyframe(2, 1), std::invalid_argument);  // culled twice
  CHECK_THROWS_AS(map.add_observation(p, 2, 1), std::invalid_argument);
  CHECK(cge_test::invalid_argument_message([&] { map.set_keyframe_pose(2, pose1); }).find("follows keyframe 3") !=
        std::string::npos);

  // The parent moves: the culled keyframe keeps its pose relative to it.
  const Eigen::Isometry3d moved3 = some_pose(-0.4, Eigen::Vector3d(1, 2, 3));
  map.set_keyframe_pose(3, moved3);
  const Eigen::Isometry3d expected2 = moved3 * (pose3.inverse() * pose2);
  CHECK((map.keyframe_pose(2).matrix() - expected2.matrix()).norm() < 1e-12);
  check_map_consistent(map);  // keyframe(2).T_world_camera == keyframe_pose(2) bit for bit

  // A chain: 3 is culled too, under 1; moving 1 moves 3 and, through 3, 2.
  map.cull_keyframe(3, 1);
  check_map_consistent(map);
  CHECK(map.map_point(p).observations.size() == 2);  // 0 and 1 remain
  const Eigen::Isometry3d moved1 = some_pose(0.7, Eigen::Vector3d(-1, 0.5, 0));
  map.set_keyframe_pose(1, moved1);
  const Eigen::Isometry3d expected3 = moved1 * (pose1.inverse() * moved3);
  CHECK((map.keyframe_pose(3).matrix() - expected3.matrix()).norm() < 1e-12);
  CHECK((map.keyframe_pose(2).matrix() - (expected3 * (pose3.inverse() * pose2)).matrix()).norm() < 1e-12);
  check_map_consistent(map);
  CHECK(map.active_keyframe_count() == 2);
}

TEST_CASE("Map covisibility stays exact through random erase, replace and cull sequences", "[maintenance][slam]") {
  std::mt19937 rng(17);
  for (int round = 0; round < 20; ++round) {
    CAPTURE(round);
    Map map;
    const int keyframes = 6, keypoints = 12;
    for (int k = 0; k < keyframes; ++k) map.add_keyframe(plain_keyframe(keypoints));
    std::uniform_int_distribution<int> kf_of(0, keyframes - 1), kp_of(0, keypoints - 1), op_of(0, 9);
    for (int j = 0; j < 30; ++j) {
      const std::int64_t id = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
      for (int t = 0; t < 4; ++t) {
        const int k = kf_of(rng), i = kp_of(rng);
        if (map.keyframe(k).map_point_ids[static_cast<std::size_t>(i)] >= 0) continue;
        const auto& obs = map.map_point(id).observations;
        if (std::any_of(obs.begin(), obs.end(), [&](const cge::slam::Observation& o) { return o.keyframe_id == k; }))
          continue;
        map.add_observation(id, k, i);
      }
    }
    std::uniform_int_distribution<std::int64_t> point_of(0, map.map_point_count() - 1);
    for (int step = 0; step < 25; ++step) {
      const int op = op_of(rng);
      const std::int64_t a = point_of(rng), b = point_of(rng);
      const int k = kf_of(rng);
      if (op < 4 && !map.map_point(a).observations.empty()) {
        map.erase_observation(a, map.map_point(a).observations.front().keyframe_id);
      } else if (op < 6) {
        map.erase_map_point(a);
      } else if (op < 9 && a != b && !map.map_point(a).bad && !map.map_point(b).bad) {
        map.replace_map_point(a, b);
      } else if (op == 9 && k != 0 && !map.keyframe(k).culled && !map.keyframe(0).culled) {
        map.cull_keyframe(k, 0);
      }
      check_map_consistent(map);
    }
  }
}
