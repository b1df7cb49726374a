// System-level test of loop correction: a short rendered loop (two laps of loop_dynamic), the
// System with a LoopCloser; an accepted loop must join the right places and its correction must
// bring the keyframes closer to the ground-truth poses. Oracle: the renderer's poses. Two
// invariants of the correction are checked too: a point seen by one keyframe moves with it, and
// a keyframe's frame stays on its keyframe in the trajectory.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/label_instances.hpp"
#include "cge/slam/loop_closer.hpp"
#include "cge/slam/system.hpp"
#include "cge/slam/vocabulary_training.hpp"

namespace {

// Two laps in 120 frames: 6 degrees and 5.8 cm a frame, as fast as the 181-frame render of the
// three-lap scene: the fast motion at which tracking is hardest to keep.
constexpr int kFrames = 120;
constexpr int kLaps = 2;
constexpr int kVocabularyFrames = 20;  // the first frames train the vocabulary (the pipeline's default)

cge::PinholeIntrinsics<double> intrinsics_of(const cge::sim::PinholeCamera& c) {
  return {c.fx_px, c.fy_px, c.cx_px, c.cy_px};
}

/// Position of keyframe pose T relative to the first keyframe's (the System's world).
Eigen::Vector3d relative_position(const Eigen::Isometry3d& T_first, const Eigen::Isometry3d& T) {
  return (T_first.inverse() * T).translation();
}

/// RMS distance of the keyframes' positions (relative to keyframe 0) from ground truth's.
double keyframe_error_m(const std::vector<Eigen::Isometry3d>& estimated, const std::vector<Eigen::Isometry3d>& truth) {
  double sum_sq = 0;
  for (std::size_t k = 0; k < estimated.size(); ++k) {
    sum_sq += (relative_position(estimated[0], estimated[k]) - relative_position(truth[0], truth[k])).squaredNorm();
  }
  return std::sqrt(sum_sq / static_cast<double>(estimated.size()));
}

}  // namespace

TEST_CASE("System with a loop closer: an accepted loop is corrected and the keyframe drift shrinks",
          "[slam][loop_correction]") {
  const cge::sim::SequenceRenderer renderer(
      cge::sim::make_preset("loop_dynamic", kFrames, 1, cge::sim::repeated_room_loop_settings(kLaps)));
  std::vector<cge::sim::RenderedFrame> frames;
  for (int i = 0; i < renderer.frame_count(); ++i) frames.push_back(renderer.render(i));
  std::vector<cv::Mat> training;
  for (int i = 0; i < kVocabularyFrames; ++i) training.push_back(frames[static_cast<std::size_t>(i)].rgb);
  cge::bow::Vocabulary vocabulary = cge::slam::train_vocabulary(training);

  cge::slam::SystemSettings settings;
  settings.mode = cge::slam::DynamicMode::YMK;
  // The loop correction alone: with local BA the keyframe error before the first correction is
  // 21 mm and the correction leaves 20.6 mm (little drift left to remove).
  settings.local_mapping.bundle_adjustment = false;
  // With cv::ORB's own keypoints (no spreading) the tracker leaves the drift this test corrects;
  // spread keypoints leave less (18.5 mm before, 17.2 mm after).
  settings.frame.orb.spread_oversampling = 1;
  // Nor the rest of local mapping (fusion and culling change which keyframes and points exist).
  settings.local_mapping.cull_map_points = false;
  settings.local_mapping.fuse_map_points = false;
  settings.local_mapping.cull_keyframes = false;
  // Nor the coverage guard: with it (0.2) the keyframes of the turns differ, the pose graph takes the
  // error before the first correction from 25.2 to 19.1 mm, and the global BA brings it back to 25.1
  // mm (the known problem of docs/LOOP_CLOSING.md, "The global BA undoes the loop correction").
  settings.patch_keyframes.use_coverage_guard = false;
  cge::slam::System system(settings, intrinsics_of(renderer.camera()));
  system.set_loop_closer(
      std::make_unique<cge::slam::LoopCloser>(std::move(vocabulary), intrinsics_of(renderer.camera()),
                                              renderer.camera().width_px, renderer.camera().height_px));
  std::map<int, int> classes;
  for (const auto& i : renderer.instances()) classes[i.id] = i.class_id;

  // Ground-truth loops by frame index; keyframe poses just before and after the first correction.
  std::set<std::pair<long long, long long>> true_loops;
  for (const auto& l : renderer.loops()) true_loops.emplace(l.query_frame, l.match_frame);
  std::vector<Eigen::Isometry3d> before, after, truth;
  // Map points seen by exactly one keyframe: their position in that keyframe's camera frame.
  struct SingleView {
    int keyframe = -1;
    Eigen::Vector3d p_camera;
  };
  const auto single_view_points = [&system] {
    std::map<std::int64_t, SingleView> out;
    for (const cge::slam::MapPoint& p : system.map().map_points()) {
      if (p.observations.size() != 1) continue;
      const int k = p.observations.front().keyframe_id;
      out[p.id] = {k, system.map().keyframe(k).T_world_camera.inverse() * p.position_world};
    }
    return out;
  };
  double worst_single_view_shift_m = 0;
  int single_view_checked = 0;
  for (const cge::sim::RenderedFrame& f : frames) {
    std::vector<Eigen::Isometry3d> poses;
    for (const cge::slam::Keyframe& kf : system.map().keyframes()) poses.push_back(kf.T_world_camera);
    const std::map<std::int64_t, SingleView> single_before = single_view_points();
    const int corrections = system.loop_corrections();
    cge::slam::FrameInput input;
    input.index = f.index;
    input.timestamp_s = f.timestamp_s;
    input.bgr = f.rgb;
    input.depth = f.depth;
    system.process(input, cge::slam::instances_from_label_image(f.instance_labels, classes, {cge::kCocoPerson}));
    if (system.loop_corrections() > corrections) {
      // The global BA moves keyframes but not the points it leaves out (those seen once): such a
      // point must follow its keyframe, or it sits off it by the BA's move.
      for (const auto& [id, now] : single_view_points()) {
        const auto was = single_before.find(id);
        if (was == single_before.end() || was->second.keyframe != now.keyframe) continue;
        worst_single_view_shift_m = std::max(worst_single_view_shift_m, (now.p_camera - was->second.p_camera).norm());
        ++single_view_checked;
      }
    }
    if (corrections == 0 && system.loop_corrections() == 1) {
      before = poses;
      for (std::size_t k = 0; k < poses.size(); ++k) {
        const cge::slam::Keyframe& kf = system.map().keyframe(static_cast<int>(k));
        after.push_back(kf.T_world_camera);
        truth.push_back(frames[static_cast<std::size_t>(kf.frame_index)].T_world_camera);
      }
    }
  }
  system.finish();

  int lost = 0;
  for (const cge::slam::FrameRecord& r : system.frames()) lost += r.state == cge::slam::TrackingState::lost;
  CHECK(lost == 0);

  // Every accepted loop joins frames that truly revisit each other.
  int accepted = 0;
  for (const cge::slam::LoopRecord& l : system.loops()) {
    if (!l.accepted) continue;
    ++accepted;
    const long long query = system.map().keyframe(l.query_keyframe).frame_index;
    const long long match = system.map().keyframe(l.match_keyframe).frame_index;
    INFO("accepted loop: frame " << query << " -> frame " << match);
    CHECK(true_loops.count({query, match}) == 1);
  }
  CHECK(accepted >= 1);
  REQUIRE(system.loop_corrections() >= 1);
  REQUIRE(!before.empty());

  INFO("single-view points checked across the corrections: " << single_view_checked);
  CHECK(single_view_checked > 100);
  CHECK(worst_single_view_shift_m < 1e-9);

  // A keyframe's own frame is reported at its keyframe's pose, after every correction (its pose is
  // kept relative to the keyframe as inserted, not as the correction left it).
  double worst_keyframe_frame_gap_m = 0;
  for (const cge::slam::FrameRecord& r : system.frames()) {
    if (r.keyframe_id < 0) continue;
    const Eigen::Isometry3d reported = system.pose_of(r);
    const Eigen::Isometry3d& keyframe = system.map().keyframe(r.keyframe_id).T_world_camera;
    worst_keyframe_frame_gap_m =
        std::max(worst_keyframe_frame_gap_m, (reported.translation() - keyframe.translation()).norm());
  }
  CHECK(worst_keyframe_frame_gap_m < 1e-9);

  // The correction moved the keyframes towards ground truth: the keyframes before the loop's query
  // (the ones that existed before the correction; the query was inserted by the correcting frame).
  before.resize(std::min(before.size(), after.size()));
  after.resize(before.size());
  truth.resize(before.size());
  const double error_before_m = keyframe_error_m(before, truth);
  const double error_after_m = keyframe_error_m(after, truth);
  INFO("keyframe RMS error before " << error_before_m << " m, after " << error_after_m << " m, keyframes "
                                    << before.size());
  // The tracker's depth term leaves little drift for the correction to remove: measured 26.3 mm
  // before, 20.4 mm after (0.78), so the bound is 0.9, not tighter.
  CHECK(error_after_m < 0.9 * error_before_m);
}
