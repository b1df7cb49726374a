// Map maintenance (cge/slam/map.hpp erase / replace / cull, cge/slam/map_maintenance.hpp rules) on
// maps built by hand: every expected erasure, fusion and cull is worked out in the comments from the
// rule's definition, and the covisibility the map keeps incrementally is compared, after every
// change, with a brute-force recount from the points' observations.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/map.hpp"
#include "cge/slam/map_maintenance.hpp"
#include "test_support.hpp"

namespace {

using cge::slam::Keyframe;
using cge::slam::Map;
using cge::slam::MapMaintenanceSettings;

const cge::PinholeIntrinsics<double> kIntrinsics{535.4, 539.2, 320.1, 247.6};
const cv::Size kImage(640, 480);
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

cv::Mat random_descriptor(std::mt19937& rng) {
  cv::Mat d(1, 32, CV_8UC1);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < 32; ++i) d.at<std::uint8_t>(0, i) = static_cast<std::uint8_t>(byte(rng));
  return d;
}

/// `d` with its first `bits` bits flipped: Hamming distance exactly `bits`.
cv::Mat flipped(const cv::Mat& d, int bits) {
  cv::Mat out = d.clone();
  for (int b = 0; b < bits; ++b) out.at<std::uint8_t>(0, b / 8) ^= static_cast<std::uint8_t>(1u << (b % 8));
  return out;
}

Eigen::Isometry3d at_x(double x) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, 0, 0);
  return T;
}

Eigen::Vector2d pixel_of(const Eigen::Isometry3d& T_world_camera, const Eigen::Vector3d& p_world) {
  return kIntrinsics.project(T_world_camera.inverse() * p_world);
}

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
        if (a.keyframe_id != b.keyframe_id)
          ++shared[static_cast<std::size_t>(a.keyframe_id)][static_cast<std::size_t>(b.keyframe_id)];
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
  Keyframe narrow = plain_keyframe(3);
  narrow.descriptors = cv::Mat::zeros(3, 16, CV_8UC1);  // the matching reads 32 bytes per row
  CHECK(cge_test::invalid_argument_message([&] { map.add_keyframe(narrow); }).find("32-byte") != std::string::npos);
  Keyframe culled = plain_keyframe(3);
  culled.culled = true;
  CHECK_THROWS_AS(map.add_keyframe(culled), std::invalid_argument);

  const std::int64_t a = map.add_map_point(Eigen::Vector3d(0, 0, 2), zero_descriptor());
  const std::int64_t b = map.add_map_point(Eigen::Vector3d(0, 0, 2), zero_descriptor(), 0);
  CHECK_THROWS_AS(map.add_map_point(Eigen::Vector3d(0, 0, 2), cv::Mat::zeros(1, 16, CV_8UC1)), std::invalid_argument);
  CHECK_THROWS_AS(map.add_map_point(Eigen::Vector3d(0, 0, 2), cv::Mat::zeros(1, 32, CV_32F)), std::invalid_argument);
  CHECK(map.map_point(a).created_by_keyframe == -1);
  CHECK(map.map_point(b).created_by_keyframe == 0);
  CHECK(map.map_point(a).visible == 1);
  CHECK(map.map_point(a).found == 1);
  CHECK_FALSE(map.map_point(a).bad);
  CHECK(cge_test::invalid_argument_message([&] {
          map.add_map_point(Eigen::Vector3d(0, 0, 2), zero_descriptor(), 1);
        }).find("keyframe 1") != std::string::npos);
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

// ---- map-point culling ------------------------------------------------------------------------------

TEST_CASE("cull_recent_map_points: found ratio, young points with few observations, maturity", "[maintenance][slam]") {
  Map map;
  // Keypoints 0..3 with depth (weight 2), 4..7 without (weight 1).
  for (int k = 0; k < 5; ++k) {
    std::vector<Kp> kps;
    for (int i = 0; i < 8; ++i) kps.push_back(kp_of(50.0 + 20 * i, 100, 0, i < 4 ? 2.0 : kNaN));
    map.add_keyframe(make_keyframe(Eigen::Isometry3d::Identity(), kps));
  }
  const auto point = [&](int created_by, std::vector<std::pair<int, int>> observations) {
    const std::int64_t id = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor(), created_by);
    for (const auto& [k, i] : observations) map.add_observation(id, k, i);
    return id;
  };
  // Current keyframe 4. Ages are 4 - created_by.
  const std::int64_t at_ratio = point(3, {{3, 0}, {4, 0}});  // found/visible = 1/4: not < 0.25, age 1: stays
  map.increase_visible(at_ratio, 3);
  const std::int64_t low_ratio = point(3, {{3, 1}, {4, 1}});  // 1/5 < 0.25: erased
  map.increase_visible(low_ratio, 4);
  const std::int64_t young_three = point(2, {{2, 0}, {3, 4}});   // age 2, weight 2 + 1 = 3 <= 3: erased
  const std::int64_t young_four = point(2, {{2, 1}, {3, 2}});    // age 2, weight 4 > 3: kept, stays recent
  const std::int64_t age_one_light = point(3, {{3, 5}});         // age 1, weight 1: too young to judge
  const std::int64_t mature = point(1, {{1, 0}, {2, 2}});        // age 3, weight 4: leaves the list, kept
  const std::int64_t mature_light = point(1, {{1, 4}, {4, 5}});  // age 3, weight 2 <= 3: erased (checked first)
  const std::int64_t already_bad = point(3, {{3, 3}});
  map.erase_map_point(already_bad);
  check_map_consistent(map);

  std::vector<std::int64_t> recent{at_ratio,      low_ratio, young_three,  young_four,
                                   age_one_light, mature,    mature_light, already_bad};
  const std::vector<std::int64_t> before = recent;
  MapMaintenanceSettings settings;
  // Errors leave the list and the map untouched.
  std::vector<std::int64_t> with_unknown = recent;
  with_unknown.push_back(99);
  CHECK_THROWS_AS(cge::slam::cull_recent_map_points(map, with_unknown, 4, settings), std::invalid_argument);
  const std::int64_t unrecorded = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor());
  std::vector<std::int64_t> with_unrecorded{low_ratio, unrecorded};
  CHECK(cge_test::invalid_argument_message([&] {
          cge::slam::cull_recent_map_points(map, with_unrecorded, 4, settings);
        }).find("created_by_keyframe") != std::string::npos);
  CHECK_FALSE(map.map_point(low_ratio).bad);
  CHECK_THROWS_AS(cge::slam::cull_recent_map_points(map, recent, 5, settings), std::invalid_argument);
  CHECK(recent == before);

  const cge::slam::MapPointCullingReport r = cge::slam::cull_recent_map_points(map, recent, 4, settings);
  CHECK(r.checked == 8);
  CHECK(r.dropped_bad == 1);
  CHECK(r.erased_low_found_ratio == 1);
  CHECK(r.erased_few_observations == 2);
  CHECK(r.matured == 1);
  CHECK(r.erased == std::vector<std::int64_t>{low_ratio, young_three, mature_light});
  CHECK(recent == std::vector<std::int64_t>{at_ratio, young_four, age_one_light});
  for (const std::int64_t id : {low_ratio, young_three, mature_light}) CHECK(map.map_point(id).bad);
  for (const std::int64_t id : {at_ratio, young_four, age_one_light, mature}) CHECK_FALSE(map.map_point(id).bad);
  check_map_consistent(map);
  CHECK(cge::slam::weighted_observations(map, map.map_point(young_four)) == 4);
  CHECK(cge::slam::weighted_observations(map, map.map_point(age_one_light)) == 1);
}

// ---- fusion ---------------------------------------------------------------------------------------------

TEST_CASE("fuse_map_points merges duplicates and adds observations within the chi2 and Hamming limits",
          "[maintenance][slam]") {
  std::mt19937 rng(3);
  // Five keyframes looking along +z from x = 0, 0.1, 0.2, 0.3, 0.4; keyframe 2 is the new one.
  std::vector<Eigen::Isometry3d> pose;
  for (int k = 0; k < 5; ++k) pose.push_back(at_x(0.1 * k));
  // Physical points, far apart in the images.
  const Eigen::Vector3d S(-0.8, -0.5, 3.5), A(-0.3, -0.4, 3.0), H(0.4, -0.4, 3.0), B(-0.6, 0.2, 2.5), C(-0.2, 0.2, 2.5),
      D(0.2, 0.2, 2.5), E(0.6, 0.2, 2.5), F(-0.6, 0.6, 2.5), G(-0.1, 0.6, 2.5), Q(0.9, 0.6, 3.0);
  const Eigen::Vector3d mm(0.001, 0, 0);  // the duplicates made by keyframe 2 sit 1 mm off
  std::map<char, cv::Mat> desc;
  for (const char c : std::string("SAHBCDEFGQ")) desc[c] = random_descriptor(rng);

  const auto kp_at = [&](int k, const Eigen::Vector3d& p, const cv::Mat& d, double depth, int octave = 0, double du = 0,
                         cge::FeatureLabel label = cge::FeatureLabel::static_feature) {
    const Eigen::Vector2d uv = pixel_of(pose[static_cast<std::size_t>(k)], p);
    return Kp{uv.x() + du, uv.y(), octave, depth, label, d};
  };
  Map map;
  // kf0: S, A.   kf1: S, A, B, C, D, E, F, G, H (all with depth), Q.   kf2 (new): see below.
  // kf3: Q only (a second neighbour of kf2, through kf1).   kf4: a keypoint where B projects, never a
  // target (it shares no point with anyone).
  map.add_keyframe(make_keyframe(pose[0], {kp_at(0, S, desc['S'], 3.5), kp_at(0, A, desc['A'], 3.0)}));
  map.add_keyframe(
      make_keyframe(pose[1], {kp_at(1, S, desc['S'], 3.5), kp_at(1, A, desc['A'], 3.0), kp_at(1, B, desc['B'], 2.5),
                              kp_at(1, C, desc['C'], 2.5), kp_at(1, D, desc['D'], 2.5), kp_at(1, E, desc['E'], 2.5),
                              kp_at(1, F, desc['F'], 2.5), kp_at(1, G, desc['G'], 2.5), kp_at(1, H, desc['H'], 3.0),
                              kp_at(1, Q, desc['Q'], 3.0)}));
  // kf2's keypoints, by index:
  //  0 S (observes S)     1 A' (observes its own duplicate of A, weight 2 vs A's 4: A stays)
  //  2 H' (own duplicate of H, weight 2 = H's 2: the projected H' stays, H is replaced)
  //  3 B, 10 bits off, no point: B gains it
  //  4 C, 2.5 px off at octave 0: chi2 6.25 >= 5.99, not fused
  //  5 D, 2.88 px off at octave 1: chi2 (2.88 / 1.2)^2 = 5.76 < 5.99, fused
  //  6 E at the projection, 51 bits off: over TH_LOW, not fused
  //  7 F at the projection, 50 bits off: fused
  //  8 G at the projection, same descriptor, but dynamic: never a candidate
  map.add_keyframe(
      make_keyframe(pose[2], {kp_at(2, S, desc['S'], 3.5), kp_at(2, A + mm, flipped(desc['A'], 5), 3.0),
                              kp_at(2, H + mm, flipped(desc['H'], 5), 3.0), kp_at(2, B, flipped(desc['B'], 10), 2.5),
                              kp_at(2, C, desc['C'], 2.5, 0, 2.5), kp_at(2, D, desc['D'], 2.5, 1, 2.88),
                              kp_at(2, E, flipped(desc['E'], 51), 2.5), kp_at(2, F, flipped(desc['F'], 50), 2.5),
                              kp_at(2, G, desc['G'], 2.5, 0, 0, cge::FeatureLabel::dynamic_by_mask)}));
  map.add_keyframe(make_keyframe(pose[3], {kp_at(3, Q, desc['Q'], 3.0)}));
  map.add_keyframe(make_keyframe(pose[4], {kp_at(4, B, desc['B'], 2.5)}));

  const auto add_point = [&](const Eigen::Vector3d& p, const cv::Mat& d, int created_by,
                             std::vector<std::pair<int, int>> observations) {
    const std::int64_t id = map.add_map_point(p, d, created_by);
    for (const auto& [k, i] : observations) map.add_observation(id, k, i);
    return id;
  };
  const std::int64_t pS = add_point(S, desc['S'], 0, {{0, 0}, {1, 0}, {2, 0}});
  const std::int64_t pA = add_point(A, desc['A'], 0, {{0, 1}, {1, 1}});
  const std::int64_t pB = add_point(B, desc['B'], 1, {{1, 2}});
  const std::int64_t pC = add_point(C, desc['C'], 1, {{1, 3}});
  const std::int64_t pD = add_point(D, desc['D'], 1, {{1, 4}});
  const std::int64_t pE = add_point(E, desc['E'], 1, {{1, 5}});
  const std::int64_t pF = add_point(F, desc['F'], 1, {{1, 6}});
  const std::int64_t pG = add_point(G, desc['G'], 1, {{1, 7}});
  const std::int64_t pH = add_point(H, desc['H'], 1, {{1, 8}});
  const std::int64_t pQ = add_point(Q, desc['Q'], 1, {{1, 9}, {3, 0}});
  const std::int64_t pA2 = add_point(A + mm, flipped(desc['A'], 5), 2, {{2, 1}});
  const std::int64_t pH2 = add_point(H + mm, flipped(desc['H'], 5), 2, {{2, 2}});
  check_map_consistent(map);

  MapMaintenanceSettings settings;
  CHECK_THROWS_AS(cge::slam::fuse_map_points(map, 5, kIntrinsics, kImage, 1.2, settings), std::invalid_argument);
  CHECK_THROWS_AS(cge::slam::fuse_map_points(map, 2, kIntrinsics, cv::Size(0, 480), 1.2, settings),
                  std::invalid_argument);
  CHECK_THROWS_AS(cge::slam::fuse_map_points(map, 2, kIntrinsics, kImage, 0.5, settings), std::invalid_argument);

  const cge::slam::FusionReport r = cge::slam::fuse_map_points(map, 2, kIntrinsics, kImage, 1.2, settings);
  check_map_consistent(map);
  CHECK(r.targets == std::vector<int>{0, 1, 3});
  CHECK(r.points_replaced == 2);
  CHECK(r.observations_added == 3);
  const Keyframe& kf2 = map.keyframe(2);
  CHECK(kf2.map_point_ids == std::vector<std::int64_t>{pS, pA, pH2, pB, -1, pD, -1, pF, -1});
  CHECK(map.map_point(pA2).bad);
  CHECK(map.map_point(pH).bad);
  CHECK_FALSE(map.map_point(pH2).bad);
  CHECK(map.keyframe(1).map_point_ids[8] == pH2);
  CHECK(map.map_point(pA).observations.size() == 3);
  for (const std::int64_t id : {pC, pE, pG}) CHECK(map.map_point(id).observations.size() == 1);
  CHECK(map.map_point(pQ).observations.size() == 2);
  CHECK(map.keyframe(4).map_point_ids[0] == -1);  // kf4 was never a target
  CHECK(map.map_point(pB).observations.size() == 2);
  CHECK(map.active_map_point_count() == map.map_point_count() - 2);

  // Fusing again finds nothing new: every match is made.
  const cge::slam::FusionReport again = cge::slam::fuse_map_points(map, 2, kIntrinsics, kImage, 1.2, settings);
  CHECK(again.points_replaced == 0);
  CHECK(again.observations_added == 0);
}

// ---- keyframe culling ------------------------------------------------------------------------------------

TEST_CASE("cull_redundant_keyframes culls keyframes whose close points three others see at a fine enough scale",
          "[maintenance][slam]") {
  // Keyframes 0..6; 6 is the new one. Each of 1..4 has a group of 10 close points (depth 2 m) that
  // the observers 0, 5 and 6 see too:
  //   kf1: at its octave 0, the observers at octave 2 (> 0 + 1): nothing redundant, kept;
  //   kf2: observers at octave 1 (= 0 + 1 counts), but one point lacks observer 6: 9 of 10 redundant,
  //        9 > 0.9 * 10 fails: kept (at the threshold);
  //   kf3: all 10 redundant: culled; it also shares 2 far points (4 m, not counted) with 5 only, so 5
  //        is its most covisible keyframe and becomes its parent;
  //   kf4: all 10 close points redundant, plus 5 far points (4 m) and 3 without depth seen by nobody
  //        else: neither kind counts, culled.
  //   kf5: sees every group (octave as its group's observers) plus 10 private close points: at most 40
  //        of 50 redundant: kept. Keyframe 0 would be redundant but is never culled; 6 is the new one.
  Map map;
  std::vector<std::vector<Kp>> kps(7);
  std::vector<std::vector<std::pair<int, int>>> points;  // per point: (keyframe, keypoint)
  const auto observe = [&](std::vector<std::pair<int, int>>& obs, int k, int octave, double depth) {
    std::vector<Kp>& list = kps[static_cast<std::size_t>(k)];
    const int n = static_cast<int>(list.size());
    list.push_back(kp_of(10.0 + 8 * (n % 70), 10.0 + 8 * (n / 70), octave, depth));
    obs.emplace_back(k, n);
  };
  for (int g = 1; g <= 4; ++g) {
    for (int j = 0; j < 10; ++j) {
      std::vector<std::pair<int, int>> obs;
      const int observer_octave = g == 1 ? 2 : g == 2 ? 1 : 0;
      observe(obs, g, 0, 2.0);
      observe(obs, 0, observer_octave, 2.0);
      observe(obs, 5, observer_octave, 2.0);
      if (!(g == 2 && j == 0)) observe(obs, 6, observer_octave, 2.0);
      points.push_back(obs);
    }
  }
  for (int j = 0; j < 2; ++j) {  // kf3's far points shared with 5
    std::vector<std::pair<int, int>> obs;
    observe(obs, 3, 0, 4.0);
    observe(obs, 5, 0, 4.0);
    points.push_back(obs);
  }
  for (int j = 0; j < 8; ++j) {  // kf4's far and depthless points
    std::vector<std::pair<int, int>> obs;
    observe(obs, 4, 0, j < 5 ? 4.0 : kNaN);
    points.push_back(obs);
  }
  for (int j = 0; j < 10; ++j) {  // kf5's private points
    std::vector<std::pair<int, int>> obs;
    observe(obs, 5, 0, 2.0);
    points.push_back(obs);
  }
  for (int k = 0; k < 7; ++k) {
    Keyframe kf = make_keyframe(at_x(0.05 * k), kps[static_cast<std::size_t>(k)]);
    map.add_keyframe(kf);
  }
  for (const auto& obs : points) {
    const std::int64_t id = map.add_map_point(Eigen::Vector3d::Zero(), zero_descriptor(), obs.front().first);
    for (const auto& [k, i] : obs) map.add_observation(id, k, i);
  }
  check_map_consistent(map);
  const Eigen::Isometry3d pose3 = map.keyframe(3).T_world_camera;
  const Eigen::Isometry3d pose5 = map.keyframe(5).T_world_camera;

  MapMaintenanceSettings settings;
  CHECK_THROWS_AS(cge::slam::cull_redundant_keyframes(map, 7, settings), std::invalid_argument);
  const cge::slam::KeyframeCullingReport r = cge::slam::cull_redundant_keyframes(map, 6, settings);
  check_map_consistent(map);
  CHECK(r.examined == std::vector<int>{1, 2, 3, 4, 5});
  CHECK(r.culled == std::vector<int>{3, 4});
  CHECK(map.keyframe(3).parent == 5);
  CHECK(map.keyframe(4).parent == 0);  // shares 10 with each of 0, 5, 6: ties go to the smaller id
  CHECK(map.active_keyframe_count() == 5);
  // kf3's close points keep three observers; its far points keep one (5); kf4's unshared points are gone.
  CHECK(map.active_map_point_count() == static_cast<std::int64_t>(points.size()) - 8);
  CHECK_THROWS_AS(cge::slam::cull_redundant_keyframes(map, 3, settings), std::invalid_argument);

  // The culled keyframe's pose follows its parent.
  const Eigen::Isometry3d moved5 = some_pose(0.2, Eigen::Vector3d(0.3, -0.1, 0.5));
  map.set_keyframe_pose(5, moved5);
  CHECK((map.keyframe_pose(3).matrix() - (moved5 * pose5.inverse() * pose3).matrix()).norm() < 1e-12);

  // A second pass culls nothing more.
  const cge::slam::KeyframeCullingReport again = cge::slam::cull_redundant_keyframes(map, 6, settings);
  CHECK(again.culled.empty());
  CHECK(again.examined == std::vector<int>{1, 2, 5});
}

// ---- triangulation -------------------------------------------------------------------------------

TEST_CASE("triangulate_new_points makes points for matched keypoints without depth", "[maintenance][slam]") {
  std::mt19937 rng(11);
  // Keyframe 1 is the new one; keyframe 0 is its neighbour, where the epipolar band is measured.
  const Eigen::Isometry3d pose0 = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d pose1 = some_pose(0.05, Eigen::Vector3d(0.3, 0.02, 0.05));
  // Shared points with depth make the keyframes covisible (and give keyframe 0 its median depth).
  std::vector<Eigen::Vector3d> anchors;
  for (int j = 0; j < 5; ++j) anchors.emplace_back(-0.8 + 0.4 * j, -0.7, 3.0);
  // Points seen without depth, keyframe 1's descriptor 3 bits off keyframe 0's unless said:
  //   0..4 triangulated; 5 is 50 bits off (TH_LOW, still matched) and triangulated; 6 is 51 bits off:
  //   no match; 7 is 2000 m away: matched, but the rays are nearly parallel (cosine >= 0.9998);
  //   8 has keyframe 0's keypoint 2.1 px off the epipolar line (chi2 ~4.4 >= 3.84): no match;
  //   9 is 1.8 px off (chi2 ~3.2): matched and triangulated, a few millimetres off.
  std::vector<Eigen::Vector3d> targets;
  for (int j = 0; j < 6; ++j) targets.emplace_back(-0.9 + 0.35 * j, 0.1 * (j % 3), 2.5 + 0.3 * j);
  targets.emplace_back(0.2, 0.5, 2.8);
  targets.emplace_back(120.0, 0.1 * 2000 / 3, 2000.0);
  targets.emplace_back(-0.4, 0.6, 3.2);
  targets.emplace_back(0.5, 0.35, 2.7);
  std::vector<cv::Mat> desc;
  for (std::size_t j = 0; j < targets.size(); ++j) desc.push_back(random_descriptor(rng));
  std::vector<Kp> kps0, kps1;
  for (const Eigen::Vector3d& a : anchors) {
    const Eigen::Vector2d u0 = pixel_of(pose0, a), u1 = pixel_of(pose1, a);
    kps0.push_back(kp_of(u0.x(), u0.y(), 0, (pose0.inverse() * a).z()));
    kps1.push_back(kp_of(u1.x(), u1.y(), 0, (pose1.inverse() * a).z()));
  }
  for (std::size_t j = 0; j < targets.size(); ++j) {
    const Eigen::Vector2d u0 = pixel_of(pose0, targets[j]), u1 = pixel_of(pose1, targets[j]);
    REQUIRE((u0.x() > 0 && u0.x() < 640 && u0.y() > 0 && u0.y() < 480));
    REQUIRE((u1.x() > 0 && u1.x() < 640 && u1.y() > 0 && u1.y() < 480));
    const int octave = j >= 8 ? 0 : static_cast<int>(j % 2);
    const double off = j == 8 ? 2.1 : j == 9 ? 1.8 : 0.0;  // across the nearly horizontal epipolar lines
    const int bits = j == 5 ? 50 : j == 6 ? 51 : 3;
    kps0.push_back(Kp{u0.x(), u0.y() + off, octave, kNaN, cge::FeatureLabel::static_feature, desc[j]});
    kps1.push_back(Kp{u1.x(), u1.y(), octave, kNaN, cge::FeatureLabel::static_feature, flipped(desc[j], bits)});
  }
  // A keypoint with depth in keyframe 0 is never used (it had its chance to make a point at insertion).
  const Eigen::Vector3d with_depth(0.7, -0.3, 2.6);
  const cv::Mat d_depth = random_descriptor(rng);
  kps0.push_back(Kp{pixel_of(pose0, with_depth).x(), pixel_of(pose0, with_depth).y(), 0, 2.6,
                    cge::FeatureLabel::static_feature, d_depth});
  kps1.push_back(Kp{pixel_of(pose1, with_depth).x(), pixel_of(pose1, with_depth).y(), 0, kNaN,
                    cge::FeatureLabel::static_feature, d_depth});
  Map map;
  map.add_keyframe(make_keyframe(pose0, kps0));
  map.add_keyframe(make_keyframe(pose1, kps1));
  for (std::size_t j = 0; j < anchors.size(); ++j) {
    const std::int64_t id = map.add_map_point(anchors[j], zero_descriptor(), 0);
    map.add_observation(id, 0, static_cast<int>(j));
    map.add_observation(id, 1, static_cast<int>(j));
  }
  const std::int64_t before = map.map_point_count();

  MapMaintenanceSettings settings;
  CHECK_THROWS_AS(cge::slam::triangulate_new_points(map, 2, kIntrinsics, 1.2, settings), std::invalid_argument);
  CHECK_THROWS_AS(cge::slam::triangulate_new_points(map, 1, kIntrinsics, 0.9, settings), std::invalid_argument);
  const cge::slam::TriangulationReport r = cge::slam::triangulate_new_points(map, 1, kIntrinsics, 1.2, settings);
  check_map_consistent(map);
  CHECK(r.neighbours == std::vector<int>{0});
  CHECK(r.matches == 8);  // 0..5, 7 and 9
  const std::vector<std::size_t> made{0, 1, 2, 3, 4, 5, 9};
  REQUIRE(r.created.size() == made.size());
  const std::size_t first = anchors.size();
  for (std::size_t m = 0; m < made.size(); ++m) {
    const std::size_t j = made[m];
    CAPTURE(j);
    const cge::slam::MapPoint& p = map.map_point(r.created[m]);
    CHECK(p.id == before + static_cast<std::int64_t>(m));
    CHECK(p.created_by_keyframe == 1);
    // Exact pixels (stored as float) give the point to micrometres; 1.8 px of disagreement to millimetres.
    CHECK((p.position_world - targets[j]).norm() < (j == 9 ? 0.02 : 1e-4));
    CHECK(map.keyframe(0).map_point_ids[first + j] == p.id);
    CHECK(map.keyframe(1).map_point_ids[first + j] == p.id);
    CHECK(cv::norm(p.descriptor, map.keyframe(1).descriptors.row(static_cast<int>(first + j)), cv::NORM_HAMMING) == 0);
  }
  for (const std::size_t j : {6u, 7u, 8u, 10u}) {
    CAPTURE(j);
    CHECK(map.keyframe(0).map_point_ids[first + j] == -1);
    CHECK(map.keyframe(1).map_point_ids[first + j] == -1);
  }
  CHECK(map.shared_points(0, 1) == 5 + 7);
  // Matched keypoints observe their points now: a second run makes nothing.
  CHECK(cge::slam::triangulate_new_points(map, 1, kIntrinsics, 1.2, settings).created.empty());
}

TEST_CASE("MapMaintenanceSettings::validate names the field", "[maintenance][slam]") {
  MapMaintenanceSettings s;
  CHECK_NOTHROW(s.validate());
  s.min_found_ratio = 1.5;
  CHECK(cge_test::invalid_argument_message([&] { s.validate(); }).find("min_found_ratio") != std::string::npos);
  s = MapMaintenanceSettings{};
  s.close_depth_m = 0;
  CHECK(cge_test::invalid_argument_message([&] { s.validate(); }).find("close_depth_m") != std::string::npos);
  s = MapMaintenanceSettings{};
  s.fuse_max_hamming = 300;
  CHECK(cge_test::invalid_argument_message([&] { s.validate(); }).find("fuse_max_hamming") != std::string::npos);
}
