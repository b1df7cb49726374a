// Tests of the scene helpers (cge/sim/scene.hpp) and the articulated people (cge/sim/bodies.hpp):
// timed paths against hand-worked positions, constant-speed walks against their definition, the
// posed body against simple physical expectations (feet on the floor, height, swinging legs), and
// the errors of bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cge/sim/bodies.hpp"
#include "cge/sim/scene.hpp"
#include "test_support.hpp"

namespace {

using cge::sim::Person;
using cge::sim::Primitive;
using cge::sim::Shape;
using cge::sim::TimedWaypoint;

constexpr double kPi = 3.14159265358979323846;

/// Half the vertical extent of a primitive (the support function of its shape along world z).
double half_height(const Primitive& p) {
  const Eigen::Matrix3d R = p.T_world_local.linear();
  const Eigen::Vector3d& s = p.size_m;
  switch (p.shape) {
    case Shape::box:
      return std::abs(R(2, 0)) * s.x() + std::abs(R(2, 1)) * s.y() + std::abs(R(2, 2)) * s.z();
    case Shape::ellipsoid:
      return Eigen::Vector3d(R(2, 0) * s.x(), R(2, 1) * s.y(), R(2, 2) * s.z()).norm();
    case Shape::capsule:
      return std::abs(R(2, 2)) * s.z() + s.x();
    case Shape::quad:
      return std::abs(R(2, 0)) * s.x() + std::abs(R(2, 1)) * s.y();
  }
  return 0;
}

double lowest_z(const Primitive& p) { return p.T_world_local.translation().z() - half_height(p); }
double highest_z(const Primitive& p) { return p.T_world_local.translation().z() + half_height(p); }

Person walker(std::vector<TimedWaypoint> path) {
  Person p;
  p.instance_id = 3;
  p.path = std::move(path);
  return p;
}

}  // namespace

TEST_CASE("person_state: positions, heading and distance along timed waypoints", "[sim][bodies]") {
  const Person p = walker({{1.0, {0, 0}}, {3.0, {2, 0}}, {4.0, {2, 0}}, {6.0, {2, 2}}});
  auto at = [&](double t) { return cge::sim::person_state(p, t); };
  CHECK(at(0.0).xy_m.isApprox(Eigen::Vector2d(0, 0)));  // before the first waypoint: standing there
  CHECK(at(0.0).speed_mps == 0);
  CHECK(at(2.0).xy_m.isApprox(Eigen::Vector2d(1, 0)));
  CHECK(at(2.0).speed_mps == Approx(1.0));
  CHECK(at(2.0).heading_rad == Approx(0.0).margin(1e-12));
  CHECK(at(2.0).distance_m == Approx(1.0));
  CHECK(at(3.5).xy_m.isApprox(Eigen::Vector2d(2, 0)));  // pausing: still, facing the way it came
  CHECK(at(3.5).speed_mps == 0);
  CHECK(at(3.5).heading_rad == Approx(0.0).margin(1e-12));
  CHECK(at(5.0).xy_m.isApprox(Eigen::Vector2d(2, 1)));
  CHECK(at(5.0).heading_rad == Approx(kPi / 2));
  CHECK(at(5.0).distance_m == Approx(3.0));
  CHECK(at(9.0).xy_m.isApprox(Eigen::Vector2d(2, 2)));
  CHECK(at(9.0).distance_m == Approx(4.0));
  // Turning is blended over turn_time_s around a waypoint: half-way at the waypoint itself.
  CHECK(at(4.0).heading_rad == Approx(kPi / 4));
  CHECK(at(4.0 + p.gait.turn_time_s / 2 + 1e-6).heading_rad == Approx(kPi / 2).margin(1e-4));
}

TEST_CASE("person_state: visibility windows", "[sim][bodies]") {
  Person p = walker({{0, {0, 0}}});
  p.visible_s = {{1.0, 2.0}, {5.0, 6.0}};
  for (const double t : {0.5, 2.0, 3.0, 6.0}) CHECK_FALSE(cge::sim::person_state(p, t).visible);
  for (const double t : {1.0, 1.5, 5.5}) CHECK(cge::sim::person_state(p, t).visible);
  std::vector<Primitive> parts;
  cge::sim::append_person_primitives(p, 3.0, parts);
  CHECK(parts.empty());
  cge::sim::append_person_primitives(p, 1.5, parts);
  CHECK_FALSE(parts.empty());
}

TEST_CASE("walk_at_constant_speed: round a closed square and back and forth along an open line", "[sim][bodies]") {
  const std::vector<Eigen::Vector2d> square = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const Person round = walker(cge::sim::walk_at_constant_speed(square, 0.5, true, 0.0, 20.0, 0.25));
  auto pos = [](const Person& p, double t) { return cge::sim::person_state(p, t).xy_m; };
  CHECK(pos(round, 0.0).isApprox(Eigen::Vector2d(0.25, 0)));
  CHECK(pos(round, 1.5).isApprox(Eigen::Vector2d(1, 0)));        // 0.25 + 0.75 m
  CHECK(pos(round, 4.0).isApprox(Eigen::Vector2d(0.75, 1)));     // 2.25 m: past the second corner
  CHECK(pos(round, 8.0 + 1.5).isApprox(Eigen::Vector2d(1, 0)));  // one lap (4 m) later, same place
  CHECK(cge::sim::person_state(round, 7.0).speed_mps == Approx(0.5));
  CHECK(cge::sim::person_state(round, 7.0).distance_m == Approx(3.5));

  const std::vector<Eigen::Vector2d> line = {{0, 0}, {2, 0}, {2, 3}};  // 5 m
  const Person forth = walker(cge::sim::walk_at_constant_speed(line, 1.0, false, 10.0, 30.0));
  CHECK(pos(forth, 10.0).isApprox(Eigen::Vector2d(0, 0)));
  CHECK(pos(forth, 14.0).isApprox(Eigen::Vector2d(2, 2)));
  CHECK(pos(forth, 16.0).isApprox(Eigen::Vector2d(2, 2)));  // on the way back
  CHECK(pos(forth, 20.0).isApprox(Eigen::Vector2d(0, 0)));  // back at the start after 10 m
  CHECK(forth.path.back().time_s == 30.0);

  CHECK_THAT(cge_test::invalid_argument_message([&] {
               cge::sim::walk_at_constant_speed({{0, 0}}, 1, true, 0, 1);
             }),
             Catch::Contains("at least 2 points"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::walk_at_constant_speed(line, 0, true, 0, 1); }),
             Catch::Contains("speed_mps"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::walk_at_constant_speed(line, 1, true, 2, 1); }),
             Catch::Contains("end_time_s > start_time_s"));
}

TEST_CASE("append_person_primitives: a walking person stands on the floor and swings the legs", "[sim][bodies]") {
  Person p = walker(cge::sim::walk_at_constant_speed({{0, 0}, {10, 0}}, 1.2, false, 0, 20));
  p.height_m = 1.8;
  double previous_left_foot_x = 0;
  double largest_stride_change = 0;
  for (double t = 0.05; t < 5; t += 0.1) {
    std::vector<Primitive> parts;
    cge::sim::append_person_primitives(p, t, parts);
    REQUIRE(!parts.empty());
    REQUIRE(parts.size() <= static_cast<std::size_t>(cge::sim::kMaxPrimitivesPerPerson));
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (const Primitive& part : parts) {
      CHECK(part.instance_id == 3);
      CHECK_NOTHROW(cge::sim::validate_primitive(part, "part"));
      low = std::min(low, lowest_z(part));
      high = std::max(high, highest_z(part));
    }
    CHECK(low == Approx(0.0).margin(1e-9));  // the stance foot rests on the floor
    CHECK(high == Approx(p.height_m).epsilon(0.05));
    // The feet are the boxes; the first is the left one. Relative to the body it moves to and fro.
    const Eigen::Vector2d body = cge::sim::person_state(p, t).xy_m;
    double left_foot_x = 0;
    for (const Primitive& part : parts) {
      if (part.shape == Shape::box) {
        left_foot_x = part.T_world_local.translation().x() - body.x();
        break;
      }
    }
    if (t > 0.1) largest_stride_change = std::max(largest_stride_change, std::abs(left_foot_x - previous_left_foot_x));
    previous_left_foot_x = left_foot_x;
  }
  CHECK(largest_stride_change > 0.03);
}

TEST_CASE("append_person_primitives: a sitting person stays on the seat with feet down", "[sim][bodies]") {
  Person p = walker({{0, {1, 2}}});
  p.posture = cge::sim::Posture::sitting;
  p.seat_height_m = 0.48;
  p.sitting_heading_rad = -kPi / 2;
  for (double t = 0; t < 10; t += 0.7) {
    std::vector<Primitive> parts;
    cge::sim::append_person_primitives(p, t, parts);
    double low = std::numeric_limits<double>::infinity(), high = -low;
    Eigen::Vector2d lowest_xy = Eigen::Vector2d::Zero();
    for (const Primitive& part : parts) {
      if (lowest_z(part) < low) {
        low = lowest_z(part);
        lowest_xy = part.T_world_local.translation().head<2>();
      }
      high = std::max(high, highest_z(part));
      // Nothing more than a leg's length from the seat.
      CHECK((part.T_world_local.translation().head<2>() - Eigen::Vector2d(1, 2)).norm() < 0.8);
    }
    CHECK(low == Approx(0.0).margin(1e-9));
    CHECK(lowest_xy.y() < 2.0);       // facing -y: the feet are in front of the seat, at smaller y
    CHECK(high < 0.85 * p.height_m);  // sitting is lower than standing
    CHECK(high > 0.6 * p.height_m);
  }
}

TEST_CASE("validate_person and validate_primitive: bad input names the field", "[sim][bodies][errors]") {
  auto person_message = [](const Person& p) {
    return cge_test::invalid_argument_message([&] { cge::sim::validate_person(p, "people[2]"); });
  };
  Person p = walker({{0, {0, 0}}, {1, {1, 0}}});
  CHECK_NOTHROW(cge::sim::validate_person(p, "people[2]"));
  Person bad = p;
  bad.path = {{1, {0, 0}}, {0.5, {1, 0}}};
  CHECK_THAT(person_message(bad), Catch::Contains("people[2]: path[1].time_s"));
  bad = p;
  bad.height_m = 3;
  CHECK_THAT(person_message(bad), Catch::Contains("height_m"));
  bad = p;
  bad.instance_id = 0;
  CHECK_THAT(person_message(bad), Catch::Contains("instance_id"));
  bad = p;
  bad.visible_s = {{2, 1}};
  CHECK_THAT(person_message(bad), Catch::Contains("visible_s[0]"));
  bad = p;
  bad.gait.stride_length_m = 0;
  CHECK_THAT(person_message(bad), Catch::Contains("gait"));
  bad = p;
  bad.path[0].xy_m.x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(person_message(bad), Catch::Contains("path[0] is not finite"));

  const cge::sim::Material m;
  auto primitive_message = [](const Primitive& q) {
    return cge_test::invalid_argument_message([&] { cge::sim::validate_primitive(q, "wall"); });
  };
  Primitive box = cge::sim::make_box({0, 0, 1}, {1, 1, 1}, 0.3, m);
  CHECK_NOTHROW(cge::sim::validate_primitive(box, "wall"));
  Primitive q = box;
  q.size_m.z() = 0;
  CHECK_THAT(primitive_message(q), Catch::Contains("wall: size_m[2]"));
  q = box;
  q.T_world_local.linear() *= 1.01;
  CHECK_THAT(primitive_message(q), Catch::Contains("not orthonormal"));
  q = box;
  q.material.scale_m = 0;
  CHECK_THAT(primitive_message(q), Catch::Contains("scale_m"));
  q = box;
  q.first_frame = -1;
  CHECK_THAT(primitive_message(q), Catch::Contains("first_frame"));
  q = box;
  q.first_frame = 5;
  q.last_frame = 5;  // one frame
  CHECK_NOTHROW(cge::sim::validate_primitive(q, "wall"));
  q.last_frame = 4;
  CHECK_THAT(primitive_message(q), Catch::Contains("last_frame"));
  // A quad needs no thickness.
  CHECK_NOTHROW(cge::sim::validate_primitive(
      cge::sim::make_quad({0, 0, 0}, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), 1, 2, m), "floor"));
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               cge::sim::make_capsule({1, 1, 1}, {1, 1, 1}, 0.1, m);
             }),
             Catch::Contains("coincide"));
}

TEST_CASE("scene helpers: frames of quads and capsules", "[sim][bodies]") {
  const cge::sim::Material m;
  const Primitive quad =
      cge::sim::make_quad({1, 2, 3}, Eigen::Vector3d(0, -2, 0), Eigen::Vector3d(1, 0.5, 0), 0.4, 0.3, m);
  const Eigen::Matrix3d R = quad.T_world_local.linear();
  CHECK(R.col(2).isApprox(Eigen::Vector3d(0, -1, 0)));  // the normal
  CHECK(R.col(0).isApprox(Eigen::Vector3d(1, 0, 0)));   // u: along_u made orthogonal to the normal
  CHECK(R.determinant() == Approx(1.0));
  CHECK(quad.size_m.isApprox(Eigen::Vector3d(0.4, 0.3, 0)));

  const Primitive cap = cge::sim::make_capsule({0, 0, 1}, {0, 2, 1}, 0.1, m, 5);
  CHECK(cap.T_world_local.translation().isApprox(Eigen::Vector3d(0, 1, 1)));
  CHECK(cap.T_world_local.linear().col(2).isApprox(Eigen::Vector3d(0, 1, 0)));
  CHECK(cap.T_world_local.linear().col(0).isApprox(Eigen::Vector3d(1, 0, 0)));  // the default side hint
  CHECK(cap.size_m.z() == Approx(1.0));
  CHECK(cap.size_m.x() == Approx(0.1));
  CHECK(cap.instance_id == 5);
}
