// LoopCloser's steps driven directly: a scripted BowModel (what each query returns is written in
// the test) and a hand-built keyframe database (keyframes and covisibility in plain vectors), no
// rendered sequence. Oracles: the scripted candidates, hand-placed 3-D points seen from a known
// relative pose, and the decision rules of docs/METHOD.md section 7 worked by hand.

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/slam/bow_model.hpp"
#include "cge/slam/keyframe_database_view.hpp"
#include "cge/slam/loop_closer.hpp"

using cge::slam::BowQueryMatch;
using cge::slam::Keyframe;
using cge::slam::LoopCloser;
using cge::slam::LoopCloserSettings;
using cge::slam::LoopDecision;
using cge::slam::LoopReason;
using cge::slam::LoopScoring;

namespace {

/// Answers query number n (the n-th keyframe processed) with script[n]; records what was added.
class ScriptedBow final : public cge::slam::BowModel {
 public:
  explicit ScriptedBow(std::map<int, std::vector<BowQueryMatch>> script, std::vector<int>* added_rows)
      : script_(std::move(script)), added_rows_(added_rows) {}
  void add(int, const cv::Mat& descriptors) override { added_rows_->push_back(descriptors.rows); }
  std::vector<BowQueryMatch> query(const cv::Mat&) const override {
    const auto it = script_.find(static_cast<int>(added_rows_->size()));
    return it == script_.end() ? std::vector<BowQueryMatch>{} : it->second;
  }
  void clear() override { added_rows_->clear(); }

 private:
  std::map<int, std::vector<BowQueryMatch>> script_;
  std::vector<int>* added_rows_;
};

/// Keyframes in a vector; covisibility as written by the test (already in the view's order).
class HandMap final : public cge::slam::KeyframeDatabaseView {
 public:
  int keyframe_count() const override { return static_cast<int>(keyframes.size()); }
  const Keyframe& keyframe(int id) const override { return keyframes.at(static_cast<std::size_t>(id)); }
  std::vector<int> covisible_keyframes(int id, int max_count) const override {
    const auto it = covisible.find(id);
    if (it == covisible.end()) return {};
    std::vector<int> out = it->second;
    if (max_count >= 0 && static_cast<int>(out.size()) > max_count) out.resize(static_cast<std::size_t>(max_count));
    return out;
  }
  std::vector<Keyframe> keyframes;
  std::map<int, std::vector<int>> covisible;
};

cge::PinholeIntrinsics<double> camera() {
  cge::PinholeIntrinsics<double> k;
  k.fx_px = 500;
  k.fy_px = 500;
  k.cx_px = 320;
  k.cy_px = 240;
  return k;
}

constexpr int kPoints = 60;  // more than min_matched_points = 40

/// A place: kPoints points 2 .. 4 m in front of its camera, each with its own descriptor.
struct Place {
  std::vector<Eigen::Vector3d> points_camera;
  cv::Mat descriptors;
};

Place make_place(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-0.8, 0.8), y(-0.6, 0.6), z(2, 4);  // in view after small_motion
  std::uniform_int_distribution<int> byte(0, 255);
  Place p;
  p.descriptors = cv::Mat(kPoints, 32, CV_8UC1);
  for (int i = 0; i < kPoints; ++i) {
    p.points_camera.emplace_back(x(rng), y(rng), z(rng));
    for (int c = 0; c < 32; ++c) p.descriptors.at<std::uint8_t>(i, c) = static_cast<std::uint8_t>(byte(rng));
  }
  return p;
}

/// The keyframe a camera at T_place_camera (its pose in the place camera's frame) makes of the
/// first `visible` points of `place`: keypoints at their projections, depth, the place's
/// descriptors; all static.
Keyframe view_of(const Place& place, int id, const Eigen::Isometry3d& T_place_camera, int visible = kPoints) {
  const cge::PinholeIntrinsics<double> K = camera();
  Keyframe kf;
  kf.id = id;
  kf.frame_index = id;
  kf.T_world_camera = T_place_camera;
  const Eigen::Isometry3d T_camera_place = T_place_camera.inverse();
  for (int i = 0; i < visible; ++i) {
    const Eigen::Vector3d p = T_camera_place * place.points_camera[static_cast<std::size_t>(i)];
    const Eigen::Vector2d uv = K.project(p);
    kf.keypoints.emplace_back(cv::Point2f(static_cast<float>(uv.x()), static_cast<float>(uv.y())), 8.f);
    kf.points_camera_m.push_back(p);
    kf.labels.push_back(cge::FeatureLabel::static_feature);
  }
  kf.descriptors = place.descriptors.rowRange(0, visible).clone();
  return kf;
}

/// A keyframe of unrelated points (another place), for ids that are only fillers.
Keyframe filler(int id) { return view_of(make_place(1000 + static_cast<unsigned>(id)), id, Eigen::Isometry3d::Identity()); }

Eigen::Isometry3d small_motion() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.06, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.12, -0.03, 0.05);
  return T;
}

/// Settings that take a single query's candidate to geometry: nothing recent excluded, no group
/// members, no continuity, BoW scoring.
LoopCloserSettings single_shot() {
  LoopCloserSettings s;
  s.scoring = LoopScoring::bow_only;
  s.recent_keyframes_excluded = 0;
  s.group_size = 0;
  s.consistent_keyframes = 1;
  return s;
}

/// Runs every keyframe of `map` through a LoopCloser with `script`; the decisions by id.
std::vector<LoopDecision> run(const HandMap& map, std::map<int, std::vector<BowQueryMatch>> script,
                              const LoopCloserSettings& settings, std::vector<int>* added_rows = nullptr) {
  std::vector<int> rows;
  LoopCloser closer(std::make_unique<ScriptedBow>(std::move(script), added_rows ? added_rows : &rows), camera(), 640,
                    480, settings);
  std::vector<LoopDecision> out;
  for (const Keyframe& kf : map.keyframes) out.push_back(closer.process(kf, map));
  return out;
}

}  // namespace

TEST_CASE("LoopCloser accepts a candidate seen again from a known pose and recovers the pose", "[loop_steps]") {
  const Place place = make_place(1);
  HandMap map;
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity()), filler(1),
                   view_of(place, 2, small_motion())};
  const auto d = run(map, {{2, {{0, 50, 0.3}, {1, 5, 0.01}}}}, single_shot());
  CHECK(d[0].reason == LoopReason::no_candidates);
  CHECK(d[1].reason == LoopReason::no_candidates);
  const LoopDecision& loop = d[2];
  CHECK(loop.candidates == 1);  // keyframe 1 has 5 common words, under 0.8 x 50
  REQUIRE(loop.accepted);
  CHECK(loop.reason == LoopReason::accepted);
  CHECK(loop.match_keyframe == 0);
  CHECK(loop.bow_score == 0.3);
  CHECK(loop.tentative_matches == kPoints);
  CHECK(loop.matched_points == kPoints);
  CHECK(loop.verified_keyframes == 1);
  CHECK((loop.T_match_query.matrix() - small_motion().matrix()).norm() < 1e-4);  // pixels held in float
  REQUIRE(loop.inlier_pairs.size() == static_cast<std::size_t>(kPoints));
  for (std::size_t i = 0; i < loop.inlier_pairs.size(); ++i) {
    CHECK(loop.inlier_pairs[i].first == static_cast<int>(i));  // keypoint i of the query is point i
    CHECK(loop.inlier_pairs[i].second == static_cast<int>(i));
  }
}

TEST_CASE("LoopCloser adds only the static features of each keyframe to the BoW model", "[loop_steps]") {
  const Place place = make_place(2);
  HandMap map;
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity()), view_of(place, 1, small_motion())};
  map.keyframes[1].labels[3] = cge::FeatureLabel::dynamic_by_mask;
  map.keyframes[1].labels[7] = cge::FeatureLabel::dynamic_by_mad;
  std::vector<int> added;
  run(map, {}, single_shot(), &added);
  CHECK(added == std::vector<int>{kPoints, kPoints - 2});
}

TEST_CASE("LoopCloser rejects a candidate under the BoW threshold in bow_only mode", "[loop_steps]") {
  const Place place = make_place(3);
  HandMap map;
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity()), view_of(place, 1, small_motion())};
  LoopCloserSettings s = single_shot();
  s.min_bow_score = 0.05;
  const auto low = run(map, {{1, {{0, 50, 0.049}}}}, s);
  CHECK_FALSE(low[1].accepted);
  CHECK(low[1].reason == LoopReason::low_score);
  CHECK(low[1].match_keyframe == 0);
  CHECK(low[1].verified_keyframes == 0);  // geometry never ran
  CHECK(low[1].tentative_matches == 0);
  const auto enough = run(map, {{1, {{0, 50, 0.05}}}}, s);
  CHECK(enough[1].accepted);  // the threshold itself passes
}

TEST_CASE("LoopCloser gates on S_sum in cge mode", "[loop_steps]") {
  const Place place = make_place(4);
  HandMap map;
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity()), view_of(place, 1, small_motion())};
  LoopCloserSettings s = single_shot();
  s.scoring = LoopScoring::cge;
  s.min_cge_score = -1e9;
  const auto open = run(map, {{1, {{0, 50, 0.3}}}}, s);
  REQUIRE(open[1].accepted);
  const double s_sum = open[1].cge_score;
  REQUIRE(std::isfinite(s_sum));
  s.min_cge_score = s_sum;  // S_sum reaches its own value
  CHECK(run(map, {{1, {{0, 50, 0.3}}}}, s)[1].accepted);
  s.min_cge_score = std::nextafter(s_sum, 1e300);
  const auto shut = run(map, {{1, {{0, 50, 0.3}}}}, s);
  CHECK(shut[1].reason == LoopReason::low_score);
  CHECK(shut[1].cge_score == s_sum);
  s.min_bow_score = 10;  // the BoW threshold plays no part in cge mode
  s.min_cge_score = s_sum;
  CHECK(run(map, {{1, {{0, 50, 0.3}}}}, s)[1].accepted);
}

TEST_CASE("LoopCloser needs consecutive consistent groups before geometry", "[loop_steps]") {
  const Place place = make_place(5);
  HandMap map;
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity())};
  for (int id = 1; id <= 4; ++id) map.keyframes.push_back(view_of(place, id, small_motion()));
  LoopCloserSettings s = single_shot();
  s.consistent_keyframes = 3;
  // Keyframes 1 .. 4 all see keyframe 0 (not covisible: the hand map has no covisibility).
  const std::vector<BowQueryMatch> zero = {{0, 50, 0.3}};
  const auto chained = run(map, {{1, zero}, {2, zero}, {3, zero}, {4, zero}}, s);
  CHECK(chained[1].reason == LoopReason::continuity);  // chain of 1
  CHECK(chained[2].reason == LoopReason::continuity);  // chain of 2
  CHECK(chained[3].accepted);                          // chain of 3
  CHECK(chained[4].accepted);
  // A query without candidates breaks the chain: keyframe 4 starts again at 1.
  const auto broken = run(map, {{1, zero}, {2, zero}, {4, zero}}, s);
  CHECK(broken[3].reason == LoopReason::no_candidates);
  CHECK(broken[4].reason == LoopReason::continuity);
  CHECK(broken[4].verified_keyframes == 0);
}

TEST_CASE("LoopCloser groups: a covisible member keeps the chain of its candidate", "[loop_steps]") {
  const Place place = make_place(6);
  HandMap map;
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity()), view_of(place, 1, Eigen::Isometry3d::Identity())};
  for (int id = 2; id <= 4; ++id) map.keyframes.push_back(view_of(place, id, small_motion()));
  map.covisible = {{0, {1}}, {1, {0}}};
  LoopCloserSettings s = single_shot();
  s.consistent_keyframes = 3;
  s.group_size = 10;
  // The candidate alternates between keyframes 0 and 1; their groups share both, so they chain.
  const auto d = run(map, {{2, {{0, 50, 0.3}}}, {3, {{1, 50, 0.3}}}, {4, {{0, 50, 0.3}}}}, s);
  CHECK(d[2].reason == LoopReason::continuity);
  CHECK(d[3].reason == LoopReason::continuity);
  REQUIRE(d[4].accepted);
  // Without the covisibility, 0 and 1 are separate groups and the chain never reaches 3.
  map.covisible.clear();
  const auto apart = run(map, {{2, {{0, 50, 0.3}}}, {3, {{1, 50, 0.3}}}, {4, {{0, 50, 0.3}}}}, s);
  CHECK(apart[4].reason == LoopReason::continuity);
}

TEST_CASE("LoopCloser excludes covisible and recent keyframes from the candidates", "[loop_steps]") {
  const Place place = make_place(7);
  HandMap map;
  for (int id = 0; id <= 3; ++id) map.keyframes.push_back(view_of(place, id, Eigen::Isometry3d::Identity()));
  map.covisible = {{3, {1}}, {1, {3}}};
  LoopCloserSettings s = single_shot();
  s.recent_keyframes_excluded = 1;  // keyframe 2 is too recent for 3
  const auto d = run(map, {{3, {{1, 80, 0.5}, {2, 80, 0.5}}}}, s);
  CHECK(d[3].reason == LoopReason::no_candidates);
  CHECK(d[3].candidates == 0);
  CHECK(d[3].connected_keyframes == std::vector<int>{1});
  // Keyframe 0 with fewer common words becomes the candidate once the others are excluded: the
  // ratio counts against the best keyframe that is not excluded.
  const auto e = run(map, {{3, {{0, 40, 0.2}, {1, 80, 0.5}, {2, 80, 0.5}}}}, s);
  CHECK(e[3].candidates == 1);
  CHECK(e[3].match_keyframe == 0);
}

TEST_CASE("LoopCloser rejects by geometry: too few matches, or no robust pose", "[loop_steps]") {
  const Place place = make_place(8);
  HandMap map;
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity()), view_of(place, 1, small_motion(), 30)};
  const auto few = run(map, {{1, {{0, 50, 0.3}}}}, single_shot());
  CHECK(few[1].reason == LoopReason::too_few_matches);
  CHECK(few[1].tentative_matches == 30);  // not more than 40
  CHECK(few[1].verified_keyframes == 1);
  CHECK(few[1].inlier_pairs.empty());

  // The same descriptors at shuffled pixels: 60 matches, but no pose explains them.
  Keyframe scrambled = view_of(place, 1, small_motion());
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> u(10, 630), v(10, 470);
  for (cv::KeyPoint& kp : scrambled.keypoints) kp.pt = cv::Point2f(u(rng), v(rng));
  map.keyframes[1] = scrambled;
  const auto bad = run(map, {{1, {{0, 50, 0.3}}}}, single_shot());
  CHECK(bad[1].reason == LoopReason::pose_not_robust);
  CHECK(bad[1].tentative_matches == kPoints);
  CHECK(bad[1].matched_points <= 40);
  CHECK_FALSE(bad[1].accepted);
}

TEST_CASE("LoopCloser keeps the verified member with the most inliers", "[loop_steps]") {
  const Place place = make_place(9);
  HandMap map;
  // Keyframes 0 and 1 see the place, 1 only 50 of its points; the query sees all 60.
  map.keyframes = {view_of(place, 0, Eigen::Isometry3d::Identity(), 50),
                   view_of(place, 1, Eigen::Isometry3d::Identity()), view_of(place, 2, small_motion())};
  LoopCloserSettings s = single_shot();
  s.verify_all_consistent_groups = true;
  s.min_group_total_ratio = 0;
  // Keyframe 0 has the higher BoW score, so it is ranked first; geometry prefers keyframe 1.
  const auto d = run(map, {{2, {{0, 50, 0.4}, {1, 50, 0.3}}}}, s);
  REQUIRE(d[2].accepted);
  CHECK(d[2].verified_keyframes == 2);
  CHECK(d[2].match_keyframe == 1);
  CHECK(d[2].matched_points == kPoints);
  CHECK(d[2].bow_score == 0.3);
}
