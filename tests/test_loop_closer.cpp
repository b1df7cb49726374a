// Tests of the LoopCloser on rendered loop sequences (cge::sim presets loop_dynamic and
// loop_structure_change) with keyframes from ground-truth poses and masks, and of vocabulary
// training from images. Oracles: the sequences' ground-truth loop pairs and poses.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "cge/sim/frame_source.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/vocabulary_training.hpp"
#include "loop_test_support.hpp"
#include "test_support.hpp"

using cge::slam::Keyframe;
using cge::slam::LoopCloser;
using cge::slam::LoopCloserSettings;
using cge::slam::LoopDecision;
using cge::slam::LoopReason;
using cge::slam::LoopScoring;

namespace {

constexpr int kFrames =
    85;  // two laps of 42.5 frames (8.5 degrees per frame): lap 2 sees no frame of lap 1 again exactly
constexpr int kLaps = 2;
constexpr int kVocabularyFrames = 20;  // the first half lap trains the vocabulary, as the pipeline's default does

struct LoopScene {
  cge::sim::SequenceSpec spec;
  std::vector<Keyframe> keyframes;
  std::vector<cv::Mat> images;
  std::set<std::pair<int, int>> loops;  // (query frame, match frame)
  cge::bow::Vocabulary vocabulary;
};

const LoopScene& scene(const std::string& preset) {
  static std::map<std::string, std::unique_ptr<LoopScene>> cache;
  auto it = cache.find(preset);
  if (it != cache.end()) return *it->second;
  auto s = std::make_unique<LoopScene>();
  // The whole room repeats on every lap: every frame of lap 2 revisits a place.
  s->spec = cge::sim::make_preset(preset, kFrames, 5, cge::sim::repeated_room_loop_settings(kLaps));
  const cge::sim::SequenceRenderer renderer(s->spec);
  for (int i = 0; i < renderer.frame_count(); ++i) {
    const cge::sim::RenderedFrame f = renderer.render(i);
    s->keyframes.push_back(cge_test::keyframe_from_frame(f, s->spec.camera, s->spec.instances, i));
    s->images.push_back(f.rgb);
  }
  for (const auto& l : s->spec.loops) s->loops.emplace(l.query_frame, l.match_frame);
  cge::slam::VocabularyTrainingSettings vs;
  s->vocabulary =
      cge::slam::train_vocabulary(std::vector<cv::Mat>(s->images.begin(), s->images.begin() + kVocabularyFrames), vs);
  return *cache.emplace(preset, std::move(s)).first->second;
}

std::vector<LoopDecision> run(const LoopScene& s, const LoopCloserSettings& settings) {
  LoopCloser closer(s.vocabulary, cge_test::intrinsics_of(s.spec.camera), s.spec.camera.width_px,
                    s.spec.camera.height_px, settings);
  cge_test::PoseCovisibilityView view(s.keyframes, 5, 60.0);
  std::vector<LoopDecision> out;
  for (const Keyframe& kf : s.keyframes) {
    view.set_count(kf.id + 1);
    out.push_back(closer.process(kf, view));
  }
  return out;
}

}  // namespace

TEST_CASE("LoopCloser experiment: print decisions", "[.loopexp]") {
  const bool verbose = std::getenv("CGE_LOOP_VERBOSE") != nullptr;
  for (const std::string preset : {"loop_dynamic", "loop_structure_change"}) {
    const LoopScene& s = scene(preset);
    std::set<int> gt_queries;
    for (const auto& l : s.loops) gt_queries.insert(l.first);
    const char* only = std::getenv("CGE_LOOP_THRESHOLDS");
    if (only != nullptr) {
      for (LoopScoring mode : {LoopScoring::cge, LoopScoring::combined}) {
        for (double th : {0.0, 0.5, 0.8, 0.9, 0.95}) {
          LoopCloserSettings settings;
          settings.scoring = mode;
          settings.exponent_scaling = cge::ScalingKind::normalised_mean;
          settings.min_cge_score = th;
          const auto d = run(s, settings);
          int accepted = 0, correct = 0;
          std::set<int> found;
          for (const auto& x : d) {
            if (!x.accepted) continue;
            ++accepted;
            if (s.loops.count({x.query_keyframe, x.match_keyframe}) > 0) {
              ++correct;
              found.insert(x.query_keyframe);
            }
          }
          std::printf("%-22s %-8s th %.2f accepted %2d correct %2d queries_found %2zu/%zu\n", preset.c_str(),
                      to_string(mode), th, accepted, correct, found.size(), gt_queries.size());
        }
      }
      continue;
    }
    for (int variant = 0; variant < 12; ++variant) {
      const LoopScoring mode = variant % 3 == 0   ? LoopScoring::cge
                               : variant % 3 == 1 ? LoopScoring::bow_only
                                                  : LoopScoring::combined;
      const bool open = (variant / 3) % 2 == 0;
      const bool normalised = variant >= 6;
      LoopCloserSettings settings;
      settings.scoring = mode;
      if (normalised) settings.exponent_scaling = cge::ScalingKind::normalised_mean;
      if (open) {
        settings.min_cge_score = 0;
        settings.min_bow_score = 0;
        settings.consistent_keyframes = 1;
      }
      const auto d = run(s, settings);
      int accepted = 0, correct = 0, gt_cge_low = 0, chosen_gt = 0;
      std::set<int> found;
      double gt_cge = 0, other_cge = 0;
      int n_other = 0;
      for (const auto& x : d) {
        const bool gt = s.loops.count({x.query_keyframe, x.match_keyframe}) > 0;
        if (x.match_keyframe >= 0) {
          if (gt) {
            ++chosen_gt;
            gt_cge += x.cge_score;
            if (x.cge_score < settings.min_cge_score) ++gt_cge_low;
          } else {
            other_cge += x.cge_score;
            ++n_other;
          }
        }
        if (x.accepted) {
          ++accepted;
          if (gt) {
            ++correct;
            found.insert(x.query_keyframe);
          }
        }
        if (verbose) {
          std::printf("q %2d m %2d gt %d cand %2d bow %.4f cge %.4f tent %3d inl %3d %s\n", x.query_keyframe,
                      x.match_keyframe, gt ? 1 : 0, x.candidates, x.bow_score, x.cge_score, x.tentative_matches,
                      x.matched_points, to_string(x.reason));
        }
      }
      std::printf(
          "%-22s %-8s %-8s %-10s accepted %2d correct %2d queries_found %2zu/%zu chosen_gt %2d mean_cge gt %.3f other "
          "%.3f\n",
          preset.c_str(), to_string(mode), open ? "open" : "defaults", normalised ? "normalised" : "raw", accepted,
          correct, found.size(), gt_queries.size(), chosen_gt, chosen_gt ? gt_cge / chosen_gt : 0.0,
          n_other ? other_cge / n_other : 0.0);
    }
  }
}

namespace {

double rotation_error_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::AngleAxisd d(a.linear().transpose() * b.linear());
  return std::fabs(d.angle()) * 180.0 / M_PI;
}

/// The checks every mode must pass on a loop scene; returns the query frames found.
/// strict: every accepted pair must be a ground-truth pair (within 20 degrees); otherwise the query
/// must be a ground-truth query frame (a revisit) and the pose must agree, but the match may be a
/// neighbour of the listed ones (the cge ranking picks such frames: docs/LOOP_CLOSING.md).
std::set<int> check_decisions(const LoopScene& s, const std::vector<LoopDecision>& decisions,
                              const LoopCloserSettings& settings, bool strict = true) {
  std::set<int> queries;
  for (const auto& l : s.loops) queries.insert(l.first);
  int first_query = kFrames;
  for (const auto& l : s.loops) first_query = std::min(first_query, l.first);
  REQUIRE(first_query > kFrames / kLaps - 5);  // the ground truth has no loop in the first lap
  std::set<int> found;
  for (const LoopDecision& d : decisions) {
    const std::string reason = to_string(d.reason);
    CHECK((reason == "accepted" || reason == "no_candidates" || reason == "low_score" || reason == "continuity" ||
           reason == "too_few_matches" || reason == "pose_not_robust"));
    CHECK(d.accepted == (d.reason == LoopReason::accepted));
    if (d.reason == LoopReason::no_candidates) CHECK(d.match_keyframe == -1);
    if (!d.accepted) continue;
    INFO("query " << d.query_keyframe << " match " << d.match_keyframe);
    // A non-revisit is never accepted: every accepted pair is a ground-truth loop.
    if (strict) {
      CHECK(s.loops.count({d.query_keyframe, d.match_keyframe}) == 1);
    } else {
      CHECK(queries.count(d.query_keyframe) == 1);
    }
    CHECK(d.match_keyframe <= d.query_keyframe - settings.recent_keyframes_excluded);
    CHECK(d.matched_points > settings.min_matched_points);
    CHECK(static_cast<int>(d.inlier_pairs.size()) == d.matched_points);
    // The geometric check's relative pose agrees with the ground truth.
    const Eigen::Isometry3d truth = s.keyframes[static_cast<std::size_t>(d.match_keyframe)].T_world_camera.inverse() *
                                    s.keyframes[static_cast<std::size_t>(d.query_keyframe)].T_world_camera;
    // EPnP inside RANSAC without refinement: a few cm and degrees (every consistent group's best
    // members are verified, some far from the query: 6.5 cm / 1.7 degrees measured on loop_structure_change).
    CHECK((d.T_match_query.translation() - truth.translation()).norm() < 0.1);
    CHECK(rotation_error_deg(d.T_match_query, truth) < 3.0);
    // Inlier pairs are static features, the match's with depth.
    for (const auto& p : d.inlier_pairs) {
      CHECK(s.keyframes[static_cast<std::size_t>(d.query_keyframe)].labels[static_cast<std::size_t>(p.first)] ==
            cge::FeatureLabel::static_feature);
      CHECK(s.keyframes[static_cast<std::size_t>(d.match_keyframe)]
                .points_camera_m[static_cast<std::size_t>(p.second)]
                .allFinite());
    }
    if (s.loops.count({d.query_keyframe, d.match_keyframe}) == 1) found.insert(d.query_keyframe);
  }
  return found;
}

std::size_t ground_truth_queries(const LoopScene& s) {
  std::set<int> q;
  for (const auto& l : s.loops) q.insert(l.first);
  return q.size();
}

}  // namespace

TEST_CASE("LoopCloser: loop_dynamic revisits accepted, non-revisits rejected, poses as ground truth", "[loop]") {
  const LoopScene& s = scene("loop_dynamic");
  for (LoopScoring mode : {LoopScoring::combined, LoopScoring::cge, LoopScoring::bow_only}) {
    INFO("scoring " << to_string(mode));
    LoopCloserSettings settings;
    settings.scoring = mode;
    const auto decisions = run(s, settings);
    REQUIRE(decisions.size() == s.keyframes.size());
    const std::set<int> found = check_decisions(s, decisions, settings, mode != LoopScoring::cge);
    // Recall over the query frames of the ground truth (measured 43/44 combined and bow_only,
    // 30/44 cge; docs/LOOP_CLOSING.md): the bounds leave room for other platforms' ORB.
    const double recall = static_cast<double>(found.size()) / static_cast<double>(ground_truth_queries(s));
    CHECK(recall >= (mode == LoopScoring::cge ? 0.4 : 0.8));
  }
}

TEST_CASE("LoopCloser: loop_structure_change revisits accepted despite the new objects", "[loop]") {
  const LoopScene& s = scene("loop_structure_change");
  LoopCloserSettings settings;
  const auto decisions = run(s, settings);
  const std::set<int> found = check_decisions(s, decisions, settings);
  CHECK(static_cast<double>(found.size()) / static_cast<double>(ground_truth_queries(s)) >= 0.8);
}

TEST_CASE("LoopCloser: the gates reject what they should", "[loop]") {
  const LoopScene& s = scene("loop_dynamic");
  SECTION("an impossible S_sum threshold: low_score, never accepted") {
    LoopCloserSettings settings;
    settings.min_cge_score = 1.5;
    for (const auto& d : run(s, settings)) {
      CHECK_FALSE(d.accepted);
      if (d.match_keyframe >= 0) CHECK(d.reason == LoopReason::low_score);
    }
  }
  SECTION("more matches than features: too_few_matches") {
    LoopCloserSettings settings;
    settings.min_matched_points = 5000;
    int geometric = 0;
    for (const auto& d : run(s, settings)) {
      CHECK_FALSE(d.accepted);
      if (d.reason == LoopReason::too_few_matches) ++geometric;
    }
    CHECK(geometric > 10);
  }
  SECTION("continuity: a detection needs the previous keyframes' consistent groups") {
    LoopCloserSettings one, three;
    one.consistent_keyframes = 1;
    const auto a = run(s, one);
    const auto b = run(s, three);
    int continuity = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (b[i].reason == LoopReason::continuity) ++continuity;
      // A decision that reached the geometric check with 3 keyframes did so with 1 too.
      if (b[i].accepted) CHECK(a[i].accepted);
    }
    CHECK(continuity > 0);
    // The first detection of a loop can never pass the 3-keyframe check.
    for (std::size_t i = 0; i < b.size(); ++i) {
      if (b[i].accepted) {
        REQUIRE(i >= 2);
        CHECK(b[i - 1].match_keyframe >= 0);
        CHECK(b[i - 2].match_keyframe >= 0);
        break;
      }
    }
  }
}

TEST_CASE("LoopCloser: deterministic, and both graph-stability modes run", "[loop]") {
  const LoopScene& s = scene("loop_dynamic");
  LoopCloserSettings settings;
  const auto a = run(s, settings);
  const auto b = run(s, settings);
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].match_keyframe == b[i].match_keyframe);
    CHECK(a[i].bow_score == b[i].bow_score);
    CHECK(a[i].cge_score == b[i].cge_score);
    CHECK(a[i].matched_points == b[i].matched_points);
    CHECK(a[i].reason == b[i].reason);
    CHECK(a[i].T_match_query.matrix() == b[i].T_match_query.matrix());
    CHECK(a[i].inlier_pairs == b[i].inlier_pairs);
  }
  settings.graph_stability = cge::slam::GraphStability::both_masks;
  const auto c = run(s, settings);
  CHECK(static_cast<double>(check_decisions(s, c, settings).size()) >=
        0.8 * static_cast<double>(ground_truth_queries(s)));
}

namespace {
/// A BoW policy of the test's own that shares no word with anything: shows the LoopCloser takes
/// any model honouring the contract (and calls add() once per keyframe).
class ScriptedBowModel final : public cge::slam::BowModel {
 public:
  int adds = 0;
  void add(int, const cv::Mat&) override { ++adds; }
  std::vector<cge::slam::BowQueryMatch> query(const cv::Mat&) const override { return {}; }
  void clear() override { adds = 0; }
};
}  // namespace

TEST_CASE("LoopCloser: a host's BoW model plugs in; bad input is refused", "[loop]") {
  const LoopScene& s = scene("loop_dynamic");
  auto model = std::make_unique<ScriptedBowModel>();
  ScriptedBowModel* raw = model.get();
  LoopCloser closer(std::move(model), cge_test::intrinsics_of(s.spec.camera), s.spec.camera.width_px,
                    s.spec.camera.height_px);
  cge_test::PoseCovisibilityView view(s.keyframes, 5, 60.0);
  for (int i = 0; i < 15; ++i) {
    view.set_count(i + 1);
    const LoopDecision d = closer.process(s.keyframes[static_cast<std::size_t>(i)], view);
    CHECK(d.reason == LoopReason::no_candidates);  // the model shares no word with anything
  }
  CHECK(raw->adds == 15);
  CHECK(closer.processed_count() == 15);

  // Out of order.
  CHECK_THAT(cge_test::invalid_argument_message([&] { closer.process(s.keyframes[20], view); }),
             Catch::Contains("keyframe id 20") && Catch::Contains("expected 15"));
  // Per-keypoint vectors of different sizes.
  Keyframe broken = s.keyframes[15];
  broken.labels.pop_back();
  view.set_count(16);
  CHECK_THAT(cge_test::invalid_argument_message([&] { closer.process(broken, view); }),
             Catch::Contains("keyframe 15") && Catch::Contains("labels"));
  broken = s.keyframes[15];
  broken.descriptors = cv::Mat(broken.descriptors.rows, 16, CV_8UC1, cv::Scalar(0));
  CHECK_THAT(cge_test::invalid_argument_message([&] { closer.process(broken, view); }), Catch::Contains("32 bytes"));
  broken = s.keyframes[15];
  broken.dynamic_mask = cv::Mat(10, 10, CV_8UC1, cv::Scalar(0));
  CHECK_THAT(cge_test::invalid_argument_message([&] { closer.process(broken, view); }),
             Catch::Contains("dynamic_mask"));
  CHECK(closer.processed_count() == 15);  // nothing was added by the refused calls

  LoopCloserSettings bad;
  bad.min_matched_points = 2;
  CHECK_THAT(cge_test::invalid_argument_message(
                 [&] { LoopCloser(s.vocabulary, cge_test::intrinsics_of(s.spec.camera), 640, 480, bad); }),
             Catch::Contains("min_matched_points"));
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               LoopCloser(std::unique_ptr<cge::slam::BowModel>(), cge_test::intrinsics_of(s.spec.camera), 640, 480);
             }),
             Catch::Contains("null"));
  CHECK_THAT(cge_test::invalid_argument_message([] { cge::slam::loop_scoring_from_string("dbow"); }),
             Catch::Contains("cge, bow_only, combined"));
  CHECK(cge::slam::loop_scoring_from_string("bow_only") == LoopScoring::bow_only);
}

TEST_CASE("train_vocabulary: from a sequence's first frames, deterministic", "[bow][loop]") {
  const LoopScene& s = scene("loop_dynamic");
  const cge::sim::RendererFrameSource<cge::sim::SequenceRenderer> source{cge::sim::SequenceRenderer(s.spec)};
  cge::slam::VocabularyTrainingSettings vs;
  vs.vocabulary.depth = 3;
  const cge::bow::Vocabulary a = cge::slam::train_vocabulary(source, 4, vs);
  const cge::bow::Vocabulary b =
      cge::slam::train_vocabulary(std::vector<cv::Mat>(s.images.begin(), s.images.begin() + 4), vs);
  CHECK(a == b);
  CHECK(a.training_images() == 4);
  CHECK(a.word_count() > 100);
  // Every training image's descriptors land on words with positive weight somewhere.
  CHECK_FALSE(a.transform(cge::slam::orb_descriptors(s.images[0], 500)).empty());
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::slam::train_vocabulary(source, 0, vs); }),
             Catch::Contains("first_frames"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::slam::train_vocabulary({cv::Mat()}, vs); }),
             Catch::Contains("image 0"));
}

TEST_CASE("LoopCloser: verifying more members and groups keeps the check with the most inliers", "[loop][loops]") {
  // Checks with verified_members = 1 on the best group (the former step 5) are a subset of those
  // with 3 members, which are a subset of those over every consistent group; the continuity state
  // does not depend on step 5, so decision i of each run sees the same groups. The most-inliers
  // choice can then only keep or gain acceptances and inliers.
  const LoopScene& s = scene("loop_dynamic");
  LoopCloserSettings one, members, all;
  one.verified_members = 1;
  one.verify_all_consistent_groups = false;
  members.verify_all_consistent_groups = false;
  REQUIRE(members.verified_members == 3);
  REQUIRE(all.verify_all_consistent_groups);
  const auto a = run(s, one);
  const auto b = run(s, members);
  const auto c = run(s, all);
  REQUIRE(a.size() == c.size());
  REQUIRE(b.size() == c.size());
  int more_checks = 0;
  cge_test::PoseCovisibilityView view(s.keyframes, 5, 60.0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    INFO("keyframe " << i);
    CHECK(a[i].verified_keyframes <= 1);
    CHECK(b[i].verified_keyframes <= 3);
    CHECK(b[i].verified_keyframes >= a[i].verified_keyframes);
    CHECK(c[i].verified_keyframes >= b[i].verified_keyframes);
    if (c[i].verified_keyframes > a[i].verified_keyframes) ++more_checks;
    if (a[i].accepted) {
      CHECK(b[i].accepted);
      CHECK(b[i].matched_points >= a[i].matched_points);
    }
    if (b[i].accepted) {
      CHECK(c[i].accepted);
      CHECK(c[i].matched_points >= b[i].matched_points);
    }
    // Connected keyframes: the earlier keyframes covisible with the query, never the match.
    view.set_count(static_cast<int>(i) + 1);
    std::vector<int> expected;
    for (int id : view.covisible_keyframes(static_cast<int>(i), -1)) {
      if (id < static_cast<int>(i)) expected.push_back(id);
    }
    std::sort(expected.begin(), expected.end());
    CHECK(c[i].connected_keyframes == expected);
    CHECK(std::find(expected.begin(), expected.end(), c[i].match_keyframe) == expected.end());
  }
  CHECK(more_checks > 0);
  // Every acceptance is still a ground-truth pair with a pose as ground truth.
  check_decisions(s, c, all);
}
