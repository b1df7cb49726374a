#pragma once
// People-like articulated bodies: a walking or sitting person made of about 16 primitives
// (ellipsoids for head, torso and pelvis, capsules for the limbs, boxes for the feet), posed by a
// simple forward-kinematics gait from the time alone.
//
// Body frame: origin on the floor under the pelvis, x to the person's right, y forward (the
// heading), z up. A walking person follows timed waypoints on the floor; legs and arms swing with
// the distance walked (phase = 2 pi distance / stride length), so a person that stands still
// stands straight. A sitting person stays on a seat and fidgets (turns the head, raises an arm,
// sways). Posing is a pure function of (Person, time): frames can be rendered in any order.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cge/sim/scene.hpp"

namespace cge {
namespace sim {

/// Where a person's body-frame origin is at a given time, on the floor (world x, y).
struct TimedWaypoint {
  double time_s = 0;
  Eigen::Vector2d xy_m = Eigen::Vector2d::Zero();
};

enum class Posture : std::uint8_t { walking, sitting };

/// Walking gait; angles in degrees, amplitudes at full walking speed.
struct GaitSettings {
  double stride_length_m = 1.3;       ///< distance of one full gait cycle (two steps), metres
  double full_swing_speed_mps = 0.6;  ///< at or above this speed the limbs swing fully; slower, less
  double hip_swing_deg = 24;          ///< hip flexion amplitude
  double knee_bend_deg = 45;          ///< peak knee flexion during the swing phase
  double arm_swing_deg = 18;          ///< shoulder swing amplitude (opposite to the legs)
  double elbow_bend_deg = 18;         ///< mean elbow flexion while walking
  double turn_time_s = 0.4;           ///< heading changes are blended over this time at waypoints
};

/// Small motions of a sitting person; periods in seconds, angles in degrees.
struct FidgetSettings {
  double head_yaw_deg = 30;    ///< head turning amplitude
  double head_period_s = 4.5;  ///< head turning period
  double arm_raise_deg = 40;   ///< right upper arm raised by up to this much (gesturing)
  double arm_period_s = 6.0;   ///< gesture period
  double sway_deg = 5;         ///< torso sway amplitude (about the vertical axis)
  double sway_period_s = 7.0;  ///< torso sway period
};

/// Colours and patterns of a person (each limb's texture moves with the limb).
struct PersonAppearance {
  Material shirt{Pattern::checks, {0.25f, 0.45f, 0.3f}, {0.85f, 0.85f, 0.8f}, 0.06f, 1};
  Material trousers{Pattern::noise, {0.22f, 0.27f, 0.4f}, {0.4f, 0.45f, 0.55f}, 0.02f, 2};
  Material skin{Pattern::plain, {0.86f, 0.67f, 0.55f}, {0.7f, 0.5f, 0.4f}, 0.03f, 3};
  Material hair{Pattern::noise, {0.25f, 0.17f, 0.1f}, {0.1f, 0.07f, 0.05f}, 0.01f, 4};
  Material shoes{Pattern::plain, {0.12f, 0.12f, 0.12f}, {0.05f, 0.05f, 0.05f}, 0.03f, 5};
  bool short_sleeves = false;  ///< forearms show skin
};

struct Person {
  std::uint16_t instance_id = 1;  ///< >= 1; its InstanceInfo should be class 0 (person), moving
  Posture posture = Posture::walking;
  double height_m = 1.75;  ///< standing height; every segment scales with it (0.5 .. 2.5)
  /// Walking: the position over time, piecewise linear between waypoints of non-decreasing time;
  /// before the first and after the last the person stands at that waypoint. Sitting: path[0].xy_m
  /// is the seat centre. Never empty.
  std::vector<TimedWaypoint> path;
  double sitting_heading_rad = 0;  ///< sitting: direction faced, from world x towards world y
  double seat_height_m = 0.46;     ///< sitting: height of the seat surface
  double fidget_phase_s = 0;       ///< sitting: time offset of the fidgeting, so two people differ
  /// Time windows [from, until) in seconds in which the person is in the scene; empty = always.
  std::vector<std::pair<double, double>> visible_s;
  GaitSettings gait;
  FidgetSettings fidget;
  PersonAppearance appearance;
};

/// Where a person is and how far into the gait, at one time.
struct PersonState {
  bool visible = true;
  Eigen::Vector2d xy_m = Eigen::Vector2d::Zero();  ///< body-frame origin on the floor
  double heading_rad = 0;                          ///< forward direction, from world x towards world y
  double speed_mps = 0;                            ///< current walking speed
  double distance_m = 0;                           ///< distance walked since the first waypoint
};

/// Throws std::invalid_argument naming `where` for an empty path, waypoints out of time order,
/// non-finite values, a height outside 0.5 .. 2.5 m, non-positive stride or periods, or an empty
/// or reversed visibility window.
void validate_person(const Person& person, const std::string& where);

/// The state of a person at time_s (any finite time).
PersonState person_state(const Person& person, double time_s);

/// Appends the person's primitives posed at time_s, in world coordinates and with the person's
/// instance id; appends nothing when the person is not visible then.
void append_person_primitives(const Person& person, double time_s, std::vector<Primitive>& out);

/// Upper bound of the number of primitives append_person_primitives adds.
constexpr int kMaxPrimitivesPerPerson = 18;

/// Timed waypoints for walking through `points` at a constant speed from start_time_s until
/// end_time_s, starting start_offset_m along the polyline; a closed polyline is walked round and
/// round, an open one back and forth. Needs >= 2 points, a positive speed, end > start.
std::vector<TimedWaypoint> walk_at_constant_speed(const std::vector<Eigen::Vector2d>& points, double speed_mps,
                                                  bool closed, double start_time_s, double end_time_s,
                                                  double start_offset_m = 0);

}  // namespace sim
}  // namespace cge
