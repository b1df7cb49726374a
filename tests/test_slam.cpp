// Tests of the tracking front of the reference pipeline (cge/slam/): Frame labels by mode, Map and
// covisibility invariants, tracking against rendered ground truth, determinism, output formats.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/frame.hpp"
#include "cge/slam/label_instances.hpp"
#include "cge/slam/map.hpp"
#include "cge/slam/output_files.hpp"
#include "cge/slam/system.hpp"
#include "cge/slam/tracker.hpp"

namespace {

using cge::FeatureLabel;
using cge::slam::DynamicMode;

cge::PinholeIntrinsics<double> intrinsics_of(const cge::sim::PinholeCamera& c) {
  return {c.fx_px, c.fy_px, c.cx_px, c.cy_px};
}

std::map<int, int> class_table(const cge::sim::SequenceRenderer& r) {
  std::map<int, int> table;
  for (const auto& i : r.instances()) table[i.id] = i.class_id;
  return table;
}

cge::slam::FrameInput input_of(const cge::sim::RenderedFrame& f) {
  cge::slam::FrameInput in;
  in.index = f.index;
  in.timestamp_s = f.timestamp_s;
  in.bgr = f.rgb;
  in.depth = f.depth;
  return in;
}

/// Runs a System with `settings` over the first `frames` frames of a renderer with exact
/// ground-truth instances.
cge::slam::System run_system(const cge::sim::SequenceRenderer& renderer, int frames,
                             const cge::slam::SystemSettings& settings) {
  cge::slam::System system(settings, intrinsics_of(renderer.camera()));
  const std::map<int, int> classes = class_table(renderer);
  for (int i = 0; i < frames; ++i) {
    const cge::sim::RenderedFrame f = renderer.render(i);
    system.process(input_of(f), cge::slam::instances_from_label_image(f.instance_labels, classes, {cge::kCocoPerson}));
  }
  system.finish();
  return system;
}

cge::slam::System run_system(const cge::sim::SequenceRenderer& renderer, int frames, DynamicMode mode) {
  cge::slam::SystemSettings settings;
  settings.mode = mode;
  return run_system(renderer, frames, settings);
}

/// The walking_xyz preset (seed 3) with its people removed: a static scene of `frames` frames.
cge::sim::SequenceSpec static_walking_xyz(int frames) {
  cge::sim::SequenceSpec spec = cge::sim::make_preset("walking_xyz", frames, 3);
  spec.people.clear();
  return spec;
}

/// Translation RMSE, metres, of the System's poses against the renderer's, both relative to frame 0.
double translation_rmse_m(const cge::slam::System& system, const cge::sim::SequenceSpec& spec) {
  const Eigen::Isometry3d gt0_inv = spec.T_world_camera[0].inverse();
  double sum_sq = 0;
  for (const cge::slam::FrameRecord& r : system.frames()) {
    const Eigen::Isometry3d gt = gt0_inv * spec.T_world_camera[static_cast<std::size_t>(r.index)];
    sum_sq += (system.pose_of(r).translation() - gt.translation()).squaredNorm();
  }
  return std::sqrt(sum_sq / static_cast<double>(system.frames().size()));
}

/// Pixel a keypoint is read at (nearest centre), as documented by the filter.
cv::Point pixel_of(const cv::KeyPoint& kp, cv::Size size) {
  return {std::clamp(static_cast<int>(std::lround(kp.pt.x)), 0, size.width - 1),
          std::clamp(static_cast<int>(std::lround(kp.pt.y)), 0, size.height - 1)};
}

}  // namespace

TEST_CASE("Frame labels by mode on a rendered walking frame", "[slam]") {
  const cge::sim::SequenceRenderer renderer(cge::sim::make_preset("walking_xyz", 20, 1));
  const cge::sim::RenderedFrame f = renderer.render(15);
  const std::map<int, int> classes = class_table(renderer);
  const std::vector<cge::SegmentedInstance> instances =
      cge::slam::instances_from_label_image(f.instance_labels, classes, {cge::kCocoPerson});
  // Oracle of the mask test: the person pixels of the label image.
  cv::Mat person(f.instance_labels.size(), CV_8UC1, cv::Scalar(0));
  for (const auto& [id, cls] : classes) {
    if (cls == cge::kCocoPerson) person.setTo(255, f.instance_labels == id);
  }
  REQUIRE(cv::countNonZero(person) > 1000);  // the frame shows people

  cge::slam::SystemSettings settings;
  const auto make = [&](DynamicMode mode, const std::vector<cge::SegmentedInstance>& inst) {
    settings.mode = mode;
    cge::slam::FrameMaker maker(settings, intrinsics_of(renderer.camera()));
    cge::slam::Frame frame = maker.extract(f.index, f.timestamp_s, f.rgb, f.depth);
    maker.label(frame, inst);
    return frame;
  };

  SECTION("none keeps every keypoint") {
    const cge::slam::Frame frame = make(DynamicMode::none, instances);
    CHECK(frame.count(FeatureLabel::static_feature) == frame.size());
  }
  SECTION("Y drops exactly the keypoints on person pixels, by mask") {
    const cge::slam::Frame frame = make(DynamicMode::Y, instances);
    int on_person = 0;
    for (int i = 0; i < frame.size(); ++i) {
      const bool expected =
          person.at<std::uint8_t>(pixel_of(frame.keypoints[static_cast<std::size_t>(i)], person.size())) != 0;
      on_person += expected;
      CHECK(frame.labels[static_cast<std::size_t>(i)] ==
            (expected ? FeatureLabel::dynamic_by_mask : FeatureLabel::static_feature));
    }
    CHECK(on_person > 20);
    CHECK(frame.count(FeatureLabel::dynamic_by_mad) == 0);
  }
  SECTION("YM with eroded masks: the mask labels stay, MAD catches edge keypoints inside person boxes") {
    // A network that misses a 5-pixel rim: erode every person mask.
    std::vector<cge::SegmentedInstance> eroded = instances;
    const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(11, 11));
    cv::Mat eroded_union(person.size(), CV_8UC1, cv::Scalar(0));
    for (auto& inst : eroded) {
      if (!inst.dynamic) continue;
      cv::erode(inst.mask, inst.mask, disc);
      eroded_union.setTo(255, inst.mask);
    }
    const cge::slam::Frame frame = make(DynamicMode::YM, eroded);
    const cge::slam::Frame again = make(DynamicMode::YM, eroded);
    CHECK(frame.labels == again.labels);  // seeded per frame
    int by_mad = 0;
    for (int i = 0; i < frame.size(); ++i) {
      const cv::KeyPoint& kp = frame.keypoints[static_cast<std::size_t>(i)];
      const cv::Point p = pixel_of(kp, person.size());
      const FeatureLabel label = frame.labels[static_cast<std::size_t>(i)];
      if (eroded_union.at<std::uint8_t>(p) != 0) {
        CHECK(label == FeatureLabel::dynamic_by_mask);
      } else if (label == FeatureLabel::dynamic_by_mad) {
        ++by_mad;
        bool in_box = false;
        for (const auto& inst : eroded) {
          const cv::Rect box = cv::boundingRect(inst.mask);
          in_box = in_box || (inst.dynamic && box.contains(p));
        }
        CHECK(in_box);
      } else {
        CHECK(label == FeatureLabel::static_feature);
      }
    }
    CHECK(by_mad > 0);
  }
}

TEST_CASE("Map: observations and covisibility", "[slam]") {
  cge::slam::Map map;
  const auto keyframe = [](int keypoints) {
    cge::slam::Keyframe kf;
    kf.keypoints.resize(static_cast<std::size_t>(keypoints));
    kf.descriptors = cv::Mat::zeros(keypoints, 32, CV_8UC1);
    kf.labels.assign(static_cast<std::size_t>(keypoints), FeatureLabel::static_feature);
    kf.points_camera_m.assign(static_cast<std::size_t>(keypoints), Eigen::Vector3d::Zero());
    return kf;
  };
  for (int k = 0; k < 4; ++k) CHECK(map.add_keyframe(keyframe(10)) == k);
  const cv::Mat d = cv::Mat::zeros(1, 32, CV_8UC1);
  // Points seen by: p0 {0,1,2}, p1 {0,1}, p2 {1,2}, p3 {0,3}, p4 {1,2}.
  const std::vector<std::vector<int>> seen = {{0, 1, 2}, {0, 1}, {1, 2}, {0, 3}, {1, 2}};
  for (std::size_t p = 0; p < seen.size(); ++p) {
    const std::int64_t id = map.add_map_point(Eigen::Vector3d::Zero(), d);
    CHECK(id == static_cast<std::int64_t>(p));
    for (const int k : seen[p]) map.add_observation(id, k, static_cast<int>(p));
  }
  // Hand count: shared(0,1) = p0 p1 = 2; shared(1,2) = p0 p2 p4 = 3; shared(0,2) = 1; shared(0,3) = 1.
  CHECK(map.shared_points(0, 1) == 2);
  CHECK(map.shared_points(1, 2) == 3);
  CHECK(map.shared_points(2, 1) == 3);
  CHECK(map.shared_points(0, 2) == 1);
  CHECK(map.shared_points(0, 3) == 1);
  CHECK(map.shared_points(1, 3) == 0);
  CHECK(map.covisible_keyframes(0, -1) == std::vector<int>{1, 2, 3});  // 2 shared, then ties by id
  CHECK(map.covisible_keyframes(1, -1) == std::vector<int>{2, 0});
  CHECK(map.covisible_keyframes(1, 1) == std::vector<int>{2});
  CHECK(map.covisible_keyframes(3, -1) == std::vector<int>{0});
  CHECK(map.observed_points(1) == 4);
  CHECK(map.keyframe(2).map_point_ids[4] == 4);

  CHECK_THROWS_AS(map.add_observation(0, 0, 7), std::invalid_argument);  // keyframe 0 already sees p0
  CHECK_THROWS_AS(map.add_observation(2, 0, 3), std::invalid_argument);  // keypoint 3 of keyframe 0 sees p3
  CHECK_THROWS_AS(map.add_observation(9, 0, 0), std::invalid_argument);  // no point 9
}

TEST_CASE("Map: invalid ids and keyframes are refused", "[slam]") {
  cge::slam::Map map;
  CHECK_THROWS_AS(map.keyframe(0), std::invalid_argument);
  CHECK_THROWS_AS(map.add_map_point(Eigen::Vector3d::Zero(), cv::Mat::zeros(2, 32, CV_8UC1)), std::invalid_argument);
  cge::slam::Keyframe bad;
  bad.keypoints.resize(3);
  bad.descriptors = cv::Mat::zeros(2, 32, CV_8UC1);
  CHECK_THROWS_AS(map.add_keyframe(bad), std::invalid_argument);
}

TEST_CASE("System tracks a rendered static scene close to ground truth, and its map is consistent", "[slam]") {
  const cge::sim::SequenceSpec spec = static_walking_xyz(40);
  const cge::sim::SequenceRenderer renderer(spec);
  const int frames = renderer.frame_count();
  const cge::slam::System system = run_system(renderer, frames, DynamicMode::none);
  REQUIRE(static_cast<int>(system.frames().size()) == frames);

  // Independent check: relative poses to frame 0 (the System's world is frame 0's camera).
  const Eigen::Isometry3d gt0_inv = spec.T_world_camera[0].inverse();
  double sum_sq = 0;
  double max_rot_deg = 0;
  for (const cge::slam::FrameRecord& r : system.frames()) {
    REQUIRE(r.has_pose());
    const Eigen::Isometry3d est = system.pose_of(r);
    const Eigen::Isometry3d gt = gt0_inv * spec.T_world_camera[static_cast<std::size_t>(r.index)];
    sum_sq += (est.translation() - gt.translation()).squaredNorm();
    const Eigen::AngleAxisd err(est.linear().transpose() * gt.linear());
    max_rot_deg = std::max(max_rot_deg, std::abs(err.angle()) * 180 / M_PI);
  }
  const double rmse_m = std::sqrt(sum_sq / frames);
  INFO("translation RMSE " << rmse_m << " m, largest rotation error " << max_rot_deg << " deg");
  CHECK(rmse_m < 0.01);
  CHECK(max_rot_deg < 0.5);
  // The camera moved: the check is not trivially met by standing still.
  CHECK((spec.T_world_camera.back().translation() - spec.T_world_camera[0].translation()).norm() > 0.05);

  // Map invariants against brute force.
  const cge::slam::Map& map = system.map();
  REQUIRE(map.keyframe_count() >= 1);
  for (const cge::slam::MapPoint& p : map.map_points()) {
    std::set<int> keyframes;
    for (const cge::slam::Observation& o : p.observations) {
      CHECK(keyframes.insert(o.keyframe_id).second);
      CHECK(map.keyframe(o.keyframe_id).map_point_ids[static_cast<std::size_t>(o.keypoint_index)] == p.id);
    }
  }
  for (int a = 0; a < map.keyframe_count(); ++a) {
    std::vector<std::pair<int, int>> expected;  // (-shared, id)
    for (int b = 0; b < map.keyframe_count(); ++b) {
      if (a == b) continue;
      const auto& ia = map.keyframe(a).map_point_ids;
      const auto& ib = map.keyframe(b).map_point_ids;
      std::set<std::int64_t> sa(ia.begin(), ia.end()), sb(ib.begin(), ib.end());
      sa.erase(-1);
      int shared = 0;
      for (const std::int64_t p : sa) shared += sb.count(p) > 0;
      CHECK(map.shared_points(a, b) == shared);
      if (shared > 0) expected.emplace_back(-shared, b);
    }
    std::sort(expected.begin(), expected.end());
    std::vector<int> ids;
    for (const auto& e : expected) ids.push_back(e.second);
    CHECK(map.covisible_keyframes(a, -1) == ids);
  }
}

TEST_CASE("System: same frames and settings give identical outputs", "[slam]") {
  const cge::sim::SequenceRenderer renderer(cge::sim::make_preset("walking_xyz", 12, 5));
  const auto outputs = [&] {
    const cge::slam::System system = run_system(renderer, renderer.frame_count(), DynamicMode::YMK);
    std::ostringstream out;
    cge::slam::write_trajectory(out, system);
    cge::slam::write_keyframes(out, system.map());
    cge::slam::write_frames_csv(out, system.frames());
    return out.str();
  };
  const std::string first = outputs();
  CHECK(first == outputs());
  CHECK(first.find("tracked") != std::string::npos);
}

TEST_CASE("System with the local BA in iteration slices: tracks, is deterministic, and is not whole rounds",
          "[slam][slices]") {
  const cge::sim::SequenceSpec spec = static_walking_xyz(30);
  const cge::sim::SequenceRenderer renderer(spec);
  cge::slam::SystemSettings whole;
  whole.mode = DynamicMode::none;
  cge::slam::SystemSettings sliced = whole;
  sliced.local_mapping.ba_iterations_per_frame = 1;
  const auto trajectory = [](const cge::slam::System& system) {
    std::ostringstream out;
    cge::slam::write_trajectory(out, system);
    return out.str();
  };
  const cge::slam::System a = run_system(renderer, renderer.frame_count(), sliced);
  const cge::slam::System b = run_system(renderer, renderer.frame_count(), sliced);
  const cge::slam::System w = run_system(renderer, renderer.frame_count(), whole);
  REQUIRE(a.map().keyframe_count() >= 3);  // several keyframes: BAs were pending across frames
  for (const cge::slam::FrameRecord& r : a.frames()) REQUIRE(r.has_pose());
  CHECK(trajectory(a) == trajectory(b));
  CHECK(trajectory(a) != trajectory(w));  // frames were tracked against a partly optimised window
  INFO("sliced " << translation_rmse_m(a, spec) << " m, whole rounds " << translation_rmse_m(w, spec) << " m");
  CHECK(translation_rmse_m(a, spec) < 0.01);
}

TEST_CASE("System: local-map tracking from the prediction (RANSAC only on failure) tracks like RANSAC first",
          "[slam]") {
  const cge::sim::SequenceSpec spec = static_walking_xyz(30);
  const cge::sim::SequenceRenderer renderer(spec);
  cge::slam::SystemSettings ransac_first;
  ransac_first.mode = DynamicMode::none;
  ransac_first.tracker.ransac_only_on_failure = false;
  cge::slam::SystemSettings from_prediction = ransac_first;
  from_prediction.tracker.ransac_only_on_failure = true;
  const cge::slam::System a = run_system(renderer, renderer.frame_count(), ransac_first);
  const cge::slam::System b = run_system(renderer, renderer.frame_count(), from_prediction);
  REQUIRE(a.frames().size() == b.frames().size());
  double largest_gap_m = 0;
  bool any_different = false;
  for (std::size_t i = 0; i < a.frames().size(); ++i) {
    REQUIRE(a.frames()[i].has_pose());
    REQUIRE(b.frames()[i].has_pose());
    const Eigen::Vector3d ta = a.pose_of(a.frames()[i]).translation();
    const Eigen::Vector3d tb = b.pose_of(b.frames()[i]).translation();
    largest_gap_m = std::max(largest_gap_m, (ta - tb).norm());
    any_different = any_different || ta != tb;
  }
  INFO("RANSAC first " << translation_rmse_m(a, spec) << " m, from the prediction " << translation_rmse_m(b, spec)
                       << " m, largest gap between them " << largest_gap_m << " m");
  CHECK(any_different);  // the setting changes the path the pose takes
  CHECK(largest_gap_m < 0.005);
  CHECK(translation_rmse_m(b, spec) < 0.01);
}

TEST_CASE("System: tracking's RANSAC from rigid or EPnP hypotheses keeps to the background with people walking "
          "and no masks",
          "[slam][slices]") {
  // People walk through the view and mode none filters nothing: the pose must come from the
  // consensus of the static background with either kind of hypothesis. The control, the refinement
  // from the prediction without RANSAC, follows the people.
  const cge::sim::SequenceSpec spec = cge::sim::make_preset("walking_xyz", 50, 1);
  REQUIRE_FALSE(spec.people.empty());
  const cge::sim::SequenceRenderer renderer(spec);
  cge::slam::SystemSettings rigid;
  rigid.mode = DynamicMode::none;
  rigid.tracker.ransac_solver = cge::slam::TrackingRansacSolver::rigid;
  cge::slam::SystemSettings epnp = rigid;
  epnp.tracker.ransac_solver = cge::slam::TrackingRansacSolver::epnp;
  cge::slam::SystemSettings no_ransac = rigid;
  no_ransac.tracker.ransac_only_on_failure = true;
  const cge::slam::System a = run_system(renderer, renderer.frame_count(), rigid);
  const cge::slam::System b = run_system(renderer, renderer.frame_count(), epnp);
  const cge::slam::System c = run_system(renderer, renderer.frame_count(), no_ransac);
  const double rigid_m = translation_rmse_m(a, spec);
  const double epnp_m = translation_rmse_m(b, spec);
  const double no_ransac_m = translation_rmse_m(c, spec);
  INFO("rigid " << rigid_m << " m, EPnP " << epnp_m << " m, no RANSAC " << no_ransac_m << " m");
  CHECK(rigid_m < 0.02);
  CHECK(epnp_m < 0.02);
  CHECK(no_ransac_m > 2 * std::max(rigid_m, epnp_m));
}

TEST_CASE("System: the local BA starts in the keyframe's frame or in the next one (ba_from_next_frame)",
          "[slam][slices]") {
  const cge::sim::SequenceSpec spec = static_walking_xyz(30);
  const cge::sim::SequenceRenderer renderer(spec);
  const std::map<int, int> classes = class_table(renderer);
  for (const bool from_next_frame : {true, false}) {
    cge::slam::SystemSettings settings;
    settings.mode = DynamicMode::none;
    settings.local_mapping.ba_from_next_frame = from_next_frame;
    cge::slam::System system(settings, intrinsics_of(renderer.camera()));
    // Per keyframe past the first two (the window then has poses to move besides the gauge): is it
    // where tracking put it once its own frame is processed, and has it moved once the next is?
    int checked = 0;
    int unmoved_after_own_frame = 0;
    int moved_after_next_frame = 0;
    int waiting = -1;  // keyframe inserted in the previous frame
    Eigen::Matrix4d tracked_pose;
    for (int i = 0; i < renderer.frame_count(); ++i) {
      const cge::sim::RenderedFrame f = renderer.render(i);
      const cge::slam::FrameRecord record =
          system.process(input_of(f), cge::slam::instances_from_label_image(f.instance_labels, classes, {}));
      if (waiting >= 0) {
        moved_after_next_frame += system.map().keyframe(waiting).T_world_camera.matrix() != tracked_pose;
        waiting = -1;
      }
      if (record.keyframe_id < 2) continue;
      ++checked;
      tracked_pose = record.T_world_camera.matrix();
      unmoved_after_own_frame += system.map().keyframe(record.keyframe_id).T_world_camera.matrix() == tracked_pose;
      waiting = record.keyframe_id;
    }
    INFO("from the next frame: " << from_next_frame << ", keyframes checked " << checked);
    REQUIRE(checked >= 3);
    if (from_next_frame) {
      CHECK(unmoved_after_own_frame == checked);
      CHECK(moved_after_next_frame >= checked - 1);  // the last keyframe may have no next frame
    } else {
      CHECK(unmoved_after_own_frame == 0);
    }
  }
}

TEST_CASE("System: a frame without texture is reported lost, not a crash", "[slam]") {
  cge::slam::SystemSettings settings;
  settings.mode = DynamicMode::none;
  cge::slam::System system(settings, cge::PinholeIntrinsics<double>{});
  cge::slam::FrameInput in;
  in.bgr = cv::Mat(480, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  in.depth = cv::Mat(480, 640, CV_16UC1, cv::Scalar(5000));
  for (int i = 0; i < 3; ++i) {
    in.index = i;
    in.timestamp_s = i / 30.0;
    CHECK(system.process(in).state == cge::slam::TrackingState::lost);
  }
  CHECK(system.map().keyframe_count() == 0);
  in.index = 1;  // not after the last
  CHECK_THROWS_AS(system.process(in), std::invalid_argument);
  in.index = 5;
  in.depth = cv::Mat(240, 320, CV_16UC1, cv::Scalar(5000));
  CHECK_THROWS_WITH(system.process(in), Catch::Contains("depth image is 320 x 240"));
}

TEST_CASE("Output files: TUM lines and CSV headers", "[slam]") {
  // Hand-worked: identity at t = 1.5; a quarter turn about z has q = (0, 0, sin 45, cos 45).
  CHECK(cge::slam::tum_pose_line(1.5, Eigen::Isometry3d::Identity()) == "1.500000 0 0 0 0 0 0 1");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1, -2, 0.25);
  CHECK(cge::slam::tum_pose_line(0, T) == "0.000000 1 -2 0.25 0 0 0.707106781 0.707106781");

  std::ostringstream loops;
  cge::slam::LoopRecord rejected;
  rejected.query_keyframe = 3;
  rejected.query_timestamp_s = 2;
  std::vector<cge::slam::LoopRecord> records{rejected};
  cge::slam::write_loops_csv(loops, records);
  CHECK(loops.str() ==
        "query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_points,accepted,"
        "reason,tentative_matches,verified_keyframes,connected_keyframes\n2.000000,,3,,,,0,0,no_candidates,0,0,\n");
  // The extended columns: checks run, tentative matches and the connected keyframes, space-separated.
  std::ostringstream extended;
  cge::slam::LoopRecord checked = rejected;
  checked.tentative_matches = 12;
  checked.verified_keyframes = 2;
  checked.connected_keyframes = {0, 4, 7};
  cge::slam::write_loops_csv(extended, {checked});
  CHECK(extended.str().substr(extended.str().find('\n') + 1) == "2.000000,,3,,,,0,0,no_candidates,12,2,0 4 7\n");

  std::ostringstream timings;
  cge::slam::write_timings_csv(timings, {});
  CHECK(timings.str() ==
        "frame,timestamp,segmentation_ms,features_ms,dynamic_filter_ms,tracking_ms,keyframe_ms,local_mapping_ms,"
        "loop_closing_ms,optimisation_ms,total_ms\n");
}

TEST_CASE("Settings: modes parse and bad values are refused", "[slam]") {
  CHECK(cge::slam::parse_dynamic_mode("YMK") == DynamicMode::YMK);
  CHECK(std::string(cge::slam::to_string(DynamicMode::Y)) == "Y");
  CHECK_THROWS_WITH(cge::slam::parse_dynamic_mode("ymk"), Catch::Contains("none, Y, YM or YMK"));
  cge::slam::SystemSettings s;
  CHECK_NOTHROW(s.validate());
  s.tracker.ratio = 0;
  CHECK_THROWS_WITH(s.validate(), Catch::Contains("tracker.ratio"));
  cge::slam::SystemSettings slices;
  slices.local_mapping.ba_iterations_per_frame = 3;
  CHECK_NOTHROW(slices.validate());
  slices.local_mapping.ba_iterations_per_frame = -1;
  CHECK_THROWS_WITH(slices.validate(), Catch::Contains("local_mapping.ba_iterations_per_frame"));
  CHECK(cge::slam::frame_seed(1, 0) != cge::slam::frame_seed(1, 1));
  CHECK(cge::slam::frame_seed(1, 0) != cge::slam::frame_seed(2, 0));
}

TEST_CASE("Tracker: when the local map fails, odometry against the previous frame keeps the pose and says so",
          "[slam]") {
  const cge::sim::SequenceSpec spec = static_walking_xyz(8);
  const cge::sim::SequenceRenderer renderer(spec);
  const cge::PinholeIntrinsics<double> K = intrinsics_of(renderer.camera());
  cge::slam::SystemSettings settings;
  settings.mode = DynamicMode::none;
  cge::slam::FrameMaker maker(settings, K);
  const auto make = [&](int i) {
    const cge::sim::RenderedFrame r = renderer.render(i);
    cge::slam::Frame f = maker.extract(r.index, r.timestamp_s, r.rgb, r.depth);
    maker.label(f, {});
    return f;
  };
  const cge::slam::Frame f0 = make(0), f2 = make(3);
  cge::slam::Tracker tracker(settings.tracker, K);
  cge::slam::Map map;
  REQUIRE(tracker.track(f0, map).state == cge::slam::TrackingState::initialised);
  // A map the local-map tracking cannot use: one keyframe whose 50 points lie behind the camera.
  cge::slam::Keyframe kf;
  for (int j = 0; j < 50; ++j) {
    kf.keypoints.emplace_back(10.f * static_cast<float>(j), 10.f, 31.f);
    kf.points_camera_m.emplace_back(0.01 * j, 0.0, -1.0);
    kf.labels.push_back(FeatureLabel::static_feature);
  }
  kf.descriptors = cv::Mat::zeros(50, 32, CV_8UC1);
  const int id = map.add_keyframe(kf);
  for (int j = 0; j < 50; ++j) {
    const std::int64_t p = map.add_map_point(Eigen::Vector3d(0.01 * j, 0.0, -1.0), kf.descriptors.row(j));
    map.add_observation(p, id, j);
  }
  const cge::slam::TrackResult result = tracker.track(f2, map);  // three frames on
  REQUIRE(result.state == cge::slam::TrackingState::odometry);
  CHECK(std::string(cge::slam::to_string(result.state)) == "odometry");
  CHECK(result.has_pose());
  // Oracle: the ground-truth motion from frame 0 (the tracker's world) to frame 3.
  const Eigen::Isometry3d truth = spec.T_world_camera[0].inverse() * spec.T_world_camera[3];
  const double error_m = (result.T_world_camera.translation() - truth.translation()).norm();
  INFO("moved " << truth.translation().norm() << " m, error " << error_m << " m");
  CHECK(error_m < 0.3 * truth.translation().norm());  // standing still would fail this

  // Descriptors that are not ORB's 32 bytes are refused, naming the frame.
  cge::slam::Frame bad = f2;
  bad.descriptors = f2.descriptors.colRange(0, 16).clone();
  CHECK_THROWS_WITH(tracker.track(bad, map), Catch::Contains("frame 3") && Catch::Contains("32-byte"));
}
