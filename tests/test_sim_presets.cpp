// Tests of the presets (cge/sim/presets.hpp), the ground-truth loops (cge/sim/loops.hpp) and the
// validation of sequence specs: hand-made trajectories with known loops, the loop scenes' events
// (a pedestrian at the revisit, objects added after the first lap), the motions' character, and
// the errors of bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/loops.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "test_support.hpp"

namespace {

using cge::sim::LoopPair;
using cge::sim::SequenceSpec;

constexpr double kPi = 3.14159265358979323846;

/// A camera at (x, 0, 1) looking along +x (forward = true) or -x.
Eigen::Isometry3d pose_on_line(double x, bool forward) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d z(forward ? 1.0 : -1.0, 0.0, 0.0);
  const Eigen::Vector3d y = -Eigen::Vector3d::UnitZ();
  T.linear().col(0) = y.cross(z);
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = Eigen::Vector3d(x, 0, 1);
  return T;
}

bool has_instance_of_class(const SequenceSpec& spec, const cv::Mat& labels, int class_id) {
  for (const auto& info : spec.instances) {
    if (info.class_id == class_id && cv::countNonZero(labels == info.id) > 0) return true;
  }
  return false;
}

/// Angle between the optical axes of two poses, degrees.
double axis_angle_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const double c = std::min(1.0, std::max(-1.0, a.linear().col(2).dot(b.linear().col(2))));
  return std::acos(c) * 180 / kPi;
}

}  // namespace

TEST_CASE("ground_truth_loops: a hand-made out-and-back-and-out trajectory", "[sim][loops]") {
  // x = 0 .. 9 m facing +x, back 9 .. 0 facing -x, then 0 .. 9 facing +x again.
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < 10; ++k) poses.push_back(pose_on_line(k, true));
  for (int k = 9; k >= 0; --k) poses.push_back(pose_on_line(k, false));
  for (int k = 0; k < 10; ++k) poses.push_back(pose_on_line(k, true));
  const std::vector<LoopPair> loops = cge::sim::ground_truth_loops(poses);
  // Only the third pass revisits the first with the same view; the way back faces the other way.
  REQUIRE(loops.size() == 10);
  for (int k = 0; k < 10; ++k) {
    CHECK(loops[static_cast<std::size_t>(k)].query_frame == 20 + k);
    CHECK(loops[static_cast<std::size_t>(k)].match_frame == k);
  }
  // With any viewing angle allowed, the way back also closes loops with the first pass, except
  // where the camera has not travelled min_travel_m since (around the turn at x = 9).
  cge::sim::LoopSettings any_angle;
  any_angle.max_angle_deg = 180;
  const std::vector<LoopPair> wide = cge::sim::ground_truth_loops(poses, any_angle);
  std::set<std::pair<int, int>> got;
  for (const LoopPair& l : wide) got.insert({l.query_frame, l.match_frame});
  std::set<std::pair<int, int>> expected;
  for (int q = 0; q < 30; ++q) {
    for (int m = 0; m < q; ++m) {
      double travel = 0;  // path length from m to q, summed step by step
      for (int i = m; i < q; ++i) travel += std::abs(poses[i + 1].translation().x() - poses[i].translation().x());
      if (poses[q].translation() == poses[m].translation() && travel >= 2) expected.insert({q, m});
    }
  }
  CHECK(expected.size() > 10);
  CHECK(got == expected);
}

TEST_CASE("ground_truth_loops: standing still never closes a loop; settings are checked", "[sim][loops]") {
  const std::vector<Eigen::Isometry3d> still(50, pose_on_line(1, true));
  CHECK(cge::sim::ground_truth_loops(still).empty());
  cge::sim::LoopSettings bad;
  bad.max_distance_m = 0;
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::ground_truth_loops(still, bad); }),
             Catch::Contains("max_distance_m"));
  bad = {};
  bad.max_angle_deg = 200;
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::ground_truth_loops(still, bad); }),
             Catch::Contains("max_angle_deg"));
  bad = {};
  bad.min_travel_m = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::ground_truth_loops(still, bad); }),
             Catch::Contains("min_travel_m"));
}

TEST_CASE("presets: every preset makes a valid spec with the requested frames", "[sim][presets]") {
  const std::vector<std::string> names = cge::sim::preset_names();
  CHECK(names == std::vector<std::string>{"walking_xyz", "walking_halfsphere", "walking_rpy", "walking_static",
                                          "sitting_xyz", "loop_dynamic", "loop_structure_change"});
  for (const std::string& name : names) {
    for (const int frames : {1, 37}) {
      const SequenceSpec spec = cge::sim::make_preset(name, frames, 4);
      INFO(name);
      CHECK(spec.name == name);
      CHECK(spec.T_world_camera.size() == static_cast<std::size_t>(frames));
      CHECK_NOTHROW(cge::sim::validate_sequence_spec(spec));
      // TUM fr3 camera at 640 x 480 and 30 Hz by default.
      CHECK(spec.camera.fx_px == 535.4);
      CHECK(spec.camera.width_px == 640);
      CHECK(spec.frame_rate_hz == 30);
      int people = 0;
      for (const auto& info : spec.instances) {
        people += info.class_id == cge::kCocoPerson ? 1 : 0;
        CHECK(info.moving == (info.class_id == cge::kCocoPerson));
      }
      CHECK(people == static_cast<int>(spec.people.size()));
      // loop_dynamic: the pedestrian, and the companion of its group revisits.
      CHECK(people == (name == "loop_structure_change" ? 0 : 2));
    }
  }
}

TEST_CASE("presets: camera motions have the character of their TUM namesakes", "[sim][presets]") {
  const int frames = 300;  // 10 s
  auto spread = [&](const std::string& name, double& max_translation_m, double& max_rotation_deg) {
    const SequenceSpec spec = cge::sim::make_preset(name, frames, 8);
    max_translation_m = 0;
    max_rotation_deg = 0;
    for (const auto& T : spec.T_world_camera) {
      max_translation_m = std::max(max_translation_m, (T.translation() - spec.T_world_camera[0].translation()).norm());
      const Eigen::AngleAxisd relative(spec.T_world_camera[0].linear().transpose() * T.linear());
      max_rotation_deg = std::max(max_rotation_deg, std::abs(relative.angle()) * 180 / kPi);
    }
  };
  double t = 0, r = 0;
  spread("walking_static", t, r);
  CHECK(t < 0.02);
  CHECK(r < 1.0);
  spread("walking_xyz", t, r);
  CHECK(t > 0.3);
  CHECK(r < 5.0);
  spread("walking_rpy", t, r);
  CHECK(t == 0);
  CHECK(r > 20);
  spread("walking_halfsphere", t, r);
  CHECK(t > 0.3);
  CHECK(t <= 1.0 + 1e-9);  // on a sphere of 1 m diameter
  CHECK(r > 5);
  // The people of sitting_xyz stay on their chairs; those of walking_xyz walk metres.
  for (const std::string name : {"sitting_xyz", "walking_xyz"}) {
    const SequenceSpec spec = cge::sim::make_preset(name, frames, 8);
    for (const auto& person : spec.people) {
      const auto a = cge::sim::person_state(person, 0);
      const auto b = cge::sim::person_state(person, 5.0);
      if (name == "sitting_xyz") {
        CHECK(person.posture == cge::sim::Posture::sitting);
        CHECK((a.xy_m - b.xy_m).norm() == 0);
      } else {
        CHECK(person.posture == cge::sim::Posture::walking);
      }
    }
  }
}

TEST_CASE("presets: the second walking person stands still pause_s at each stop, at walking_speed_mps between",
          "[sim][presets]") {
  for (const double pause : {0.0, 1.5, 4.0}) {
    for (const double speed : {0.35, 1.0}) {
      cge::sim::PresetSettings settings;
      settings.pause_s = pause;
      settings.walking_speed_mps = speed;
      const SequenceSpec spec = cge::sim::make_preset("walking_static", 1800, 4, settings);  // 60 s
      INFO("pause " << pause << " s, speed " << speed << " m/s");
      REQUIRE(spec.people.size() == 2);
      const auto& path = spec.people[1].path;
      REQUIRE(path.size() > 4);
      int stops = 0;
      for (std::size_t i = 1; i < path.size(); ++i) {
        const double dt = path[i].time_s - path[i - 1].time_s;
        const double step = (path[i].xy_m - path[i - 1].xy_m).norm();
        if (step == 0) {  // a stop: stands for exactly the pause
          CHECK(dt == Approx(pause).margin(1e-12));
          ++stops;
        } else {  // a walk between stops, at the walking speed
          CHECK(step / dt == Approx(speed).epsilon(1e-12));
        }
      }
      CHECK(stops >= 2);
      // The first person walks its loop at the same speed whatever the pause.
      const auto a = cge::sim::person_state(spec.people[0], 1.0);
      const auto b = cge::sim::person_state(spec.people[0], 1.5);
      CHECK((a.xy_m - b.xy_m).norm() == Approx(0.5 * speed).epsilon(0.05));
    }
  }
  // The defaults are the presets' documented motions.
  const cge::sim::PresetSettings defaults;
  CHECK(defaults.pause_s == 1.5);
  CHECK(defaults.walking_speed_mps == 1.0);
}

TEST_CASE("presets: repeated-room loop scenes circle the room and list loops that satisfy the thresholds",
          "[sim][presets][loops]") {
  const cge::sim::PresetSettings settings = cge::sim::repeated_room_loop_settings(3);
  const int frames = 240;
  for (const std::string name : {"loop_dynamic", "loop_structure_change"}) {
    const SequenceSpec spec = cge::sim::make_preset(name, frames, 6, settings);
    INFO(name);
    // Laps: the camera is back at the start every frames / laps frames.
    const int lap = frames / settings.loop_laps;
    CHECK((spec.T_world_camera[static_cast<std::size_t>(lap)].translation() - spec.T_world_camera[0].translation())
              .norm() < 1e-9);
    REQUIRE_FALSE(spec.loops.empty());
    std::set<int> queries;
    for (const LoopPair& l : spec.loops) {
      const auto& q = spec.T_world_camera[static_cast<std::size_t>(l.query_frame)];
      const auto& m = spec.T_world_camera[static_cast<std::size_t>(l.match_frame)];
      CHECK(l.match_frame < l.query_frame);
      CHECK((q.translation() - m.translation()).norm() <= settings.loops.max_distance_m);
      CHECK(axis_angle_deg(q, m) <= settings.loops.max_angle_deg + 1e-9);
      CHECK(l.query_frame - l.match_frame >= lap / 2);  // a revisit, never a neighbour
      queries.insert(l.query_frame);
    }
    // Every frame after the first lap revisits a place; none in the first lap does.
    CHECK(*queries.begin() >= lap - 5);
    CHECK(static_cast<int>(queries.size()) >= frames - lap - 5);
  }
}

TEST_CASE("make_preset: bad input names what is wrong", "[sim][presets][errors]") {
  const std::string unknown = cge_test::invalid_argument_message([] { cge::sim::make_preset("walking_fast", 10, 1); });
  CHECK_THAT(unknown, Catch::Contains("unknown preset 'walking_fast'"));
  for (const std::string& name : cge::sim::preset_names()) CHECK_THAT(unknown, Catch::Contains(name));

  for (const int frames : {0, -3}) {
    CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::make_preset("walking_xyz", frames, 1); }),
               Catch::Contains("frames must be >= 1 (got " + std::to_string(frames) + ")"));
  }

  struct BadCamera {
    void (*spoil)(cge::sim::PinholeCamera&);
    const char* field;
  };
  const BadCamera bad_cameras[] = {
      {[](cge::sim::PinholeCamera& c) { c.fx_px = 0; }, "camera.fx_px"},
      {[](cge::sim::PinholeCamera& c) { c.fy_px = -500; }, "camera.fy_px"},
      {[](cge::sim::PinholeCamera& c) { c.cx_px = std::numeric_limits<double>::quiet_NaN(); }, "camera.cx_px"},
      {[](cge::sim::PinholeCamera& c) { c.cy_px = std::numeric_limits<double>::infinity(); }, "camera.cy_px"},
      {[](cge::sim::PinholeCamera& c) { c.width_px = 0; }, "camera.width_px"},
      {[](cge::sim::PinholeCamera& c) { c.height_px = -480; }, "camera.height_px"},
      {[](cge::sim::PinholeCamera& c) { c.depth_units_per_metre = 0; }, "camera.depth_units_per_metre"},
  };
  for (const BadCamera& b : bad_cameras) {
    cge::sim::PresetSettings settings;
    b.spoil(settings.camera);
    CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::make_preset("walking_xyz", 5, 1, settings); }),
               Catch::Contains(b.field));
  }
  cge::sim::PresetSettings settings;
  settings.loop_laps = 1;
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::make_preset("loop_dynamic", 5, 1, settings); }),
             Catch::Contains("loop_laps"));
  for (const double pause : {-0.5, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    settings = {};
    settings.pause_s = pause;
    CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::make_preset("walking_xyz", 5, 1, settings); }),
               Catch::Contains("pause_s"));
  }
  settings = {};
  settings.render.depth.max_range_m = 0.1;
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::make_preset("walking_xyz", 5, 1, settings); }),
             Catch::Contains("max_range_m"));
}

TEST_CASE("SequenceRenderer: an invalid spec is refused with the offending field", "[sim][presets][errors]") {
  const SequenceSpec good = cge::sim::make_preset("walking_xyz", 3, 1);
  auto message = [](const SequenceSpec& s) {
    return cge_test::invalid_argument_message([&] { cge::sim::SequenceRenderer r(s); });
  };
  SequenceSpec s = good;
  s.T_world_camera.clear();
  CHECK_THAT(message(s), Catch::Contains("T_world_camera is empty"));
  s = good;
  s.T_world_camera[1].linear() *= 2.0;
  CHECK_THAT(message(s), Catch::Contains("T_world_camera[1]"));
  s = good;
  s.static_primitives[4].instance_id = 999;
  CHECK_THAT(message(s), Catch::Contains("static_primitives[4].instance_id 999 is not in SequenceSpec.instances"));
  s = good;
  s.static_primitives[2].size_m.x() = -1;
  CHECK_THAT(message(s), Catch::Contains("static_primitives[2]: size_m[0]"));
  s = good;
  s.instances.push_back(s.instances.front());
  CHECK_THAT(message(s), Catch::Contains("appears twice"));
  s = good;
  s.instances[0].class_id = 80;
  CHECK_THAT(message(s), Catch::Contains("COCO id"));
  s = good;
  s.people[0].path.clear();
  CHECK_THAT(message(s), Catch::Contains("people[0]: path is empty"));
  s = good;
  s.loops.push_back({1, 1});
  CHECK_THAT(message(s), Catch::Contains("loops[0]"));
  s = good;
  s.frame_rate_hz = 0;
  CHECK_THAT(message(s), Catch::Contains("frame_rate_hz"));
  s = good;
  s.render.depth.dropout_probability = 1.5;
  CHECK_THAT(message(s), Catch::Contains("dropout_probability"));
}
