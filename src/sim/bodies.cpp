#include "cge/sim/bodies.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cge {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;

// Body proportions for a standing height of kReferenceHeightM; everything scales with the height.
constexpr double kReferenceHeightM = 1.75;
struct Proportions {
  double hip_half_width = 0.095;  // hip joint from the body's mid-plane
  double thigh = 0.44, shin = 0.43, ankle_height = 0.075;
  double thigh_radius = 0.07, shin_radius = 0.052;
  double foot_half[3] = {0.045, 0.12, 0.035};  // half sizes: width, length, height
  double foot_forward = 0.05;                  // foot centre ahead of the ankle
  double pelvis_above_hip = 0.05;
  double pelvis_radii[3] = {0.17, 0.11, 0.12};
  double torso_above_hip = 0.31;
  double torso_radii[3] = {0.19, 0.115, 0.26};
  double shoulder_above_hip = 0.5, shoulder_half_width = 0.19;
  double upper_arm = 0.29, forearm = 0.26, upper_arm_radius = 0.045, forearm_radius = 0.038;
  double arm_splay = 0.12;  // arms hang this much outwards (lateral component of their direction)
  double hand_radius = 0.048;
  double neck_above_hip = 0.53, neck_length = 0.1, neck_radius = 0.05;
  double head_above_hip = 0.715;
  double head_radii[3] = {0.085, 0.1, 0.115};
  double hair_radii[3] = {0.092, 0.106, 0.09};
  double hair_offset[2] = {-0.018, 0.04};  // backwards, upwards from the head centre
  double sitting_hip_above_seat = 0.085;   // thigh thickness under the hip joint
  double sitting_hip_back = 0.05;          // hip joint behind the seat centre
  double sitting_upper_arm_deg = 25, sitting_elbow_deg = 70;
  double standing_knee_deg = 4;  // slight knee flexion in stance
};

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

std::string str(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

double wrap_angle(double a) {
  a = std::fmod(a + kPi, 2 * kPi);
  if (a < 0) a += 2 * kPi;
  return a - kPi;
}

bool is_visible(const Person& person, double t) {
  if (person.visible_s.empty()) return true;
  for (const auto& w : person.visible_s) {
    if (t >= w.first && t < w.second) return true;
  }
  return false;
}

/// Heading of the motion along segment k (waypoints k -> k+1), or of the nearest moving segment
/// before it, or after it; 0 when the person never moves.
double segment_heading(const std::vector<TimedWaypoint>& path, std::size_t k) {
  auto heading_of = [&](std::size_t j, double& out) {
    const Eigen::Vector2d d = path[j + 1].xy_m - path[j].xy_m;
    if (d.norm() <= 1e-9) return false;
    out = std::atan2(d.y(), d.x());
    return true;
  };
  double h = 0;
  for (std::size_t j = k + 1; j-- > 0;) {
    if (heading_of(j, h)) return h;
  }
  for (std::size_t j = k + 1; j + 1 < path.size(); ++j) {
    if (heading_of(j, h)) return h;
  }
  return 0;
}

// ---- posing ----------------------------------------------------------------------------------------

/// Points of the body frame placed in the world.
struct BodyPlacement {
  Eigen::Isometry3d T_world_body;
  Eigen::Vector3d to_world(const Eigen::Vector3d& p) const { return T_world_body * p; }
};

struct LegPose {
  double hip_flexion_rad;   // forwards swing of the thigh from vertical
  double knee_flexion_rad;  // backwards bend of the shin relative to the thigh
};

Eigen::Vector3d sagittal(double angle_rad, double splay = 0) {
  // Direction hanging down from a joint, swung forwards by angle (body frame: y forward, z up).
  return Eigen::Vector3d(splay, std::sin(angle_rad), -std::cos(angle_rad)).normalized();
}

}  // namespace

void validate_person(const Person& person, const std::string& where) {
  if (person.instance_id == 0) fail(where, "instance_id must be >= 1");
  if (!std::isfinite(person.height_m) || person.height_m < 0.5 || person.height_m > 2.5) {
    fail(where, "height_m must be in 0.5 .. 2.5 (got " + str(person.height_m) + ")");
  }
  if (person.path.empty()) fail(where, "path is empty (a person needs at least one waypoint)");
  for (std::size_t i = 0; i < person.path.size(); ++i) {
    const TimedWaypoint& w = person.path[i];
    if (!std::isfinite(w.time_s) || !w.xy_m.allFinite()) fail(where, "path[" + std::to_string(i) + "] is not finite");
    if (i > 0 && w.time_s < person.path[i - 1].time_s) {
      fail(where, "path[" + std::to_string(i) + "].time_s (" + str(w.time_s) + ") is before the previous waypoint's");
    }
  }
  if (!std::isfinite(person.sitting_heading_rad)) fail(where, "sitting_heading_rad must be finite");
  if (!std::isfinite(person.seat_height_m) || person.seat_height_m < 0)
    fail(where, "seat_height_m must be finite and >= 0");
  if (!std::isfinite(person.fidget_phase_s)) fail(where, "fidget_phase_s must be finite");
  for (std::size_t i = 0; i < person.visible_s.size(); ++i) {
    const auto& w = person.visible_s[i];
    if (std::isnan(w.first) || std::isnan(w.second) || !(w.first < w.second)) {
      fail(where, "visible_s[" + std::to_string(i) + "] must be a window [from, until) with from < until");
    }
  }
  const GaitSettings& g = person.gait;
  const double gait_values[] = {g.stride_length_m, g.full_swing_speed_mps, g.turn_time_s};
  for (const double v : gait_values) {
    if (!std::isfinite(v) || !(v > 0)) fail(where, "gait lengths, speeds and times must be finite and > 0");
  }
  const double angles[] = {g.hip_swing_deg,
                           g.knee_bend_deg,
                           g.arm_swing_deg,
                           g.elbow_bend_deg,
                           person.fidget.head_yaw_deg,
                           person.fidget.arm_raise_deg,
                           person.fidget.sway_deg};
  for (const double a : angles) {
    if (!std::isfinite(a) || std::abs(a) > 180)
      fail(where, "gait and fidget angles must be finite, within +-180 degrees");
  }
  const FidgetSettings& f = person.fidget;
  const double periods[] = {f.head_period_s, f.arm_period_s, f.sway_period_s};
  for (const double v : periods) {
    if (!std::isfinite(v) || !(v > 0)) fail(where, "fidget periods must be finite and > 0");
  }
}

PersonState person_state(const Person& person, double t) {
  PersonState s;
  s.visible = is_visible(person, t);
  const std::vector<TimedWaypoint>& path = person.path;
  if (person.posture == Posture::sitting) {
    s.xy_m = path.front().xy_m;
    s.heading_rad = person.sitting_heading_rad;
    return s;
  }
  // Distance walked up to the start of each segment is summed on the way.
  double walked = 0;
  if (path.size() == 1 || t <= path.front().time_s) {
    s.xy_m = path.front().xy_m;
    s.heading_rad = path.size() > 1 ? segment_heading(path, 0) : 0.0;
    return s;
  }
  std::size_t k = 0;
  while (k + 1 < path.size() && path[k + 1].time_s <= t) {
    walked += (path[k + 1].xy_m - path[k].xy_m).norm();
    ++k;
  }
  if (k + 1 == path.size()) {  // after the last waypoint
    s.xy_m = path.back().xy_m;
    s.distance_m = walked;
    s.heading_rad = segment_heading(path, k - 1);
    return s;
  }
  const TimedWaypoint& a = path[k];
  const TimedWaypoint& b = path[k + 1];
  const double dt = b.time_s - a.time_s;  // > 0: equal times are skipped by the loop above
  const double f = (t - a.time_s) / dt;
  const double length = (b.xy_m - a.xy_m).norm();
  s.xy_m = a.xy_m + f * (b.xy_m - a.xy_m);
  s.speed_mps = length / dt;
  s.distance_m = walked + f * length;

  // Heading: the segment's, blended with the neighbours' over turn_time_s around each waypoint.
  const double half_turn = 0.5 * person.gait.turn_time_s;
  double heading = segment_heading(path, k);
  if (k > 0 && t - a.time_s < half_turn) {
    const double before = segment_heading(path, k - 1);
    const double w = 0.5 + (t - a.time_s) / (2 * half_turn);
    heading = before + w * wrap_angle(heading - before);
  } else if (k + 2 < path.size() && b.time_s - t < half_turn) {
    const double after = segment_heading(path, k + 1);
    const double w = 0.5 - (b.time_s - t) / (2 * half_turn);
    heading = heading + w * wrap_angle(after - heading);
  }
  s.heading_rad = wrap_angle(heading);
  return s;
}

void append_person_primitives(const Person& person, double t, std::vector<Primitive>& out) {
  const PersonState state = person_state(person, t);
  if (!state.visible) return;
  const Proportions P;
  const double k = person.height_m / kReferenceHeightM;
  const PersonAppearance& look = person.appearance;
  const std::uint16_t id = person.instance_id;
  const bool sitting = person.posture == Posture::sitting;

  BodyPlacement place;
  place.T_world_body = Eigen::Isometry3d::Identity();
  place.T_world_body.linear() =
      Eigen::AngleAxisd(state.heading_rad - 0.5 * kPi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  place.T_world_body.translation() = Eigen::Vector3d(state.xy_m.x(), state.xy_m.y(), 0);
  const Eigen::Vector3d lateral_world = place.T_world_body.linear() * Eigen::Vector3d::UnitX();

  // ---- legs -----------------------------------------------------------------------------------------
  LegPose legs[2];   // 0 left, 1 right
  double swing = 0;  // 0 .. 1: how much the limbs swing
  double phase = 0;
  const GaitSettings& g = person.gait;
  if (!sitting) {
    swing = std::min(1.0, state.speed_mps / g.full_swing_speed_mps);
    phase = 2 * kPi * state.distance_m / g.stride_length_m;
    for (int side = 0; side < 2; ++side) {
      const double ph = phase + side * kPi;
      legs[side].hip_flexion_rad = swing * g.hip_swing_deg * kDegToRad * std::sin(ph);
      legs[side].knee_flexion_rad =
          P.standing_knee_deg * kDegToRad + swing * g.knee_bend_deg * kDegToRad * std::max(0.0, std::cos(ph));
    }
  }
  double hip_z = 0;
  Eigen::Vector3d hip_centre;
  if (sitting) {
    hip_z = person.seat_height_m + P.sitting_hip_above_seat * k;
    hip_centre = Eigen::Vector3d(0, -P.sitting_hip_back * k, hip_z);
  } else {
    for (const LegPose& leg : legs) {
      const double drop = P.thigh * std::cos(leg.hip_flexion_rad) +
                          P.shin * std::cos(leg.hip_flexion_rad - leg.knee_flexion_rad) + P.ankle_height;
      hip_z = std::max(hip_z, drop * k);
    }
    hip_centre = Eigen::Vector3d(0, 0, hip_z);
  }
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? -1.0 : 1.0;  // left is -x
    const Eigen::Vector3d hip = hip_centre + Eigen::Vector3d(sign * P.hip_half_width * k, 0, 0);
    Eigen::Vector3d knee, ankle;
    if (sitting) {
      // Thighs forwards, sloping down if the seat is high, so that a vertical shin puts the foot
      // on the floor; on a low seat the shin leans forwards instead.
      const double knee_z = std::min(hip.z(), (P.ankle_height + P.shin) * k);
      const double slope = std::asin(std::min(1.0, (hip.z() - knee_z) / (P.thigh * k)));
      knee = hip + P.thigh * k * Eigen::Vector3d(0, std::cos(slope), -std::sin(slope));
      const double reach = (knee.z() - P.ankle_height * k) / (P.shin * k);
      const double tilt = std::acos(std::min(1.0, std::max(-1.0, reach)));
      ankle = knee + P.shin * k * sagittal(tilt);
    } else {
      knee = hip + P.thigh * k * sagittal(legs[side].hip_flexion_rad);
      ankle = knee + P.shin * k * sagittal(legs[side].hip_flexion_rad - legs[side].knee_flexion_rad);
    }
    out.push_back(
        make_capsule(place.to_world(hip), place.to_world(knee), P.thigh_radius * k, look.trousers, id, lateral_world));
    out.push_back(
        make_capsule(place.to_world(knee), place.to_world(ankle), P.shin_radius * k, look.trousers, id, lateral_world));
    const Eigen::Vector3d foot_centre =
        ankle + Eigen::Vector3d(0, P.foot_forward * k, -(P.ankle_height - P.foot_half[2]) * k);
    Primitive foot = make_box(place.to_world(foot_centre),
                              Eigen::Vector3d(P.foot_half[0], P.foot_half[1], P.foot_half[2]) * k, 0, look.shoes, id);
    foot.T_world_local.linear() = place.T_world_body.linear();
    out.push_back(foot);
  }

  // ---- upper body (turned by the sway of a sitting person about the pelvis) ---------------------------
  double sway = 0, head_yaw = 0, arm_raise = 0;
  if (sitting) {
    const FidgetSettings& f = person.fidget;
    const double tf = t + person.fidget_phase_s;
    sway = f.sway_deg * kDegToRad * std::sin(2 * kPi * tf / f.sway_period_s);
    head_yaw = f.head_yaw_deg * kDegToRad * std::sin(2 * kPi * tf / f.head_period_s);
    arm_raise = f.arm_raise_deg * kDegToRad * 0.5 * (1 - std::cos(2 * kPi * tf / f.arm_period_s));
  }
  const Eigen::Matrix3d R_sway = Eigen::AngleAxisd(sway, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto upper = [&](const Eigen::Vector3d& p) { return place.to_world(hip_centre + R_sway * (p - hip_centre)); };
  const Eigen::Matrix3d R_world_upper = place.T_world_body.linear() * R_sway;
  const Eigen::Vector3d up_lateral_world = R_world_upper * Eigen::Vector3d::UnitX();

  auto ellipsoid = [&](const Eigen::Vector3d& centre_body, const double radii[3], const Material& m,
                       const Eigen::Matrix3d& R_world_local) {
    Primitive e = make_ellipsoid(upper(centre_body), Eigen::Vector3d(radii[0], radii[1], radii[2]) * k, 0, m, id);
    e.T_world_local.linear() = R_world_local;
    out.push_back(e);
  };
  ellipsoid(hip_centre + Eigen::Vector3d(0, 0, P.pelvis_above_hip * k), P.pelvis_radii, look.trousers, R_world_upper);
  ellipsoid(hip_centre + Eigen::Vector3d(0, 0, P.torso_above_hip * k), P.torso_radii, look.shirt, R_world_upper);

  const Eigen::Vector3d neck_base = hip_centre + Eigen::Vector3d(0, 0, P.neck_above_hip * k);
  out.push_back(make_capsule(upper(neck_base), upper(neck_base + Eigen::Vector3d(0, 0, P.neck_length * k)),
                             P.neck_radius * k, look.skin, id, up_lateral_world));
  const Eigen::Matrix3d R_world_head = R_world_upper * Eigen::AngleAxisd(head_yaw, Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d head_centre = hip_centre + Eigen::Vector3d(0, 0, P.head_above_hip * k);
  ellipsoid(head_centre, P.head_radii, look.skin, R_world_head);
  {
    const Eigen::Vector3d hair_offset_head(0, P.hair_offset[0] * k, P.hair_offset[1] * k);
    const Eigen::Matrix3d R_head_in_upper = Eigen::AngleAxisd(head_yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    ellipsoid(head_centre + R_head_in_upper * hair_offset_head, P.hair_radii, look.hair, R_world_head);
  }

  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? -1.0 : 1.0;
    double shoulder_angle, elbow_angle;
    if (sitting) {
      shoulder_angle = P.sitting_upper_arm_deg * kDegToRad + (side == 1 ? arm_raise : 0.0);
      elbow_angle = P.sitting_elbow_deg * kDegToRad;
    } else {
      // Each arm swings with the opposite leg.
      shoulder_angle = -swing * g.arm_swing_deg * kDegToRad * std::sin(phase + side * kPi);
      elbow_angle = g.elbow_bend_deg * kDegToRad * (0.6 + 0.4 * swing);
    }
    const Eigen::Vector3d shoulder =
        hip_centre + Eigen::Vector3d(sign * P.shoulder_half_width * k, 0, P.shoulder_above_hip * k);
    const Eigen::Vector3d elbow = shoulder + P.upper_arm * k * sagittal(shoulder_angle, sign * P.arm_splay);
    const Eigen::Vector3d wrist = elbow + P.forearm * k * sagittal(shoulder_angle + elbow_angle, sign * P.arm_splay);
    const Eigen::Vector3d hand = wrist + P.hand_radius * k * sagittal(shoulder_angle + elbow_angle);
    out.push_back(
        make_capsule(upper(shoulder), upper(elbow), P.upper_arm_radius * k, look.shirt, id, up_lateral_world));
    out.push_back(make_capsule(upper(elbow), upper(wrist), P.forearm_radius * k,
                               look.short_sleeves ? look.skin : look.shirt, id, up_lateral_world));
    const double hand_radii[3] = {P.hand_radius, P.hand_radius, P.hand_radius};
    ellipsoid(hand, hand_radii, look.skin, R_world_upper);
  }
}

std::vector<TimedWaypoint> walk_at_constant_speed(const std::vector<Eigen::Vector2d>& points, double speed_mps,
                                                  bool closed, double start_time_s, double end_time_s,
                                                  double start_offset_m) {
  const std::string where = "walk_at_constant_speed";
  if (points.size() < 2) fail(where, "needs at least 2 points");
  if (!std::isfinite(speed_mps) || !(speed_mps > 0)) fail(where, "speed_mps must be finite and > 0");
  if (!std::isfinite(start_time_s) || !std::isfinite(end_time_s) || !(end_time_s > start_time_s)) {
    fail(where, "needs finite times with end_time_s > start_time_s");
  }
  if (!std::isfinite(start_offset_m) || start_offset_m < 0) fail(where, "start_offset_m must be finite and >= 0");
  // The vertices of one period of the walk, with their distance from its start.
  std::vector<Eigen::Vector2d> vertices;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite()) fail(where, "points must be finite");
    if (vertices.empty() || (p - vertices.back()).norm() > 1e-9) vertices.push_back(p);
  }
  if (closed) {
    if ((vertices.back() - vertices.front()).norm() > 1e-9) vertices.push_back(vertices.front());
  } else {
    for (std::size_t i = vertices.size() - 1; i-- > 0;) vertices.push_back(vertices[i]);
  }
  if (vertices.size() < 2) fail(where, "the points must not all coincide");
  std::vector<double> at(vertices.size(), 0.0);
  for (std::size_t i = 1; i < vertices.size(); ++i) at[i] = at[i - 1] + (vertices[i] - vertices[i - 1]).norm();
  const double period = at.back();

  auto position = [&](double s) -> Eigen::Vector2d {
    s = std::fmod(s, period);
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(at.begin(), at.end(), s) - at.begin());
    const std::size_t j = std::min(std::max<std::size_t>(i, 1), at.size() - 1);
    const double f = (s - at[j - 1]) / (at[j] - at[j - 1]);
    return vertices[j - 1] + f * (vertices[j] - vertices[j - 1]);
  };

  std::vector<TimedWaypoint> out;
  double s = start_offset_m;
  double t = start_time_s;
  out.push_back({t, position(s)});
  while (t < end_time_s) {
    // The next vertex strictly ahead of s.
    const double laps = std::floor(s / period);
    const double within = s - laps * period;
    std::size_t i = static_cast<std::size_t>(std::upper_bound(at.begin(), at.end(), within + 1e-12) - at.begin());
    const double next = laps * period + (i < at.size() ? at[i] : period + at[1]);
    const double t_next = t + (next - s) / speed_mps;
    if (t_next >= end_time_s) {
      out.push_back({end_time_s, position(s + (end_time_s - t) * speed_mps)});
      break;
    }
    t = t_next;
    s = next;
    out.push_back({t, i < at.size() ? vertices[i] : vertices[1]});
  }
  return out;
}

}  // namespace sim
}  // namespace cge
