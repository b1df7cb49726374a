#include "cge/sim/presets.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "cge/core/splitmix64.hpp"
#include "cge/segmentation/coco_classes.hpp"

namespace cge {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;

// The names, in the documented order.
const char* const kPresetNames[] = {"walking_xyz", "walking_halfsphere", "walking_rpy",          "walking_static",
                                    "sitting_xyz", "loop_dynamic",       "loop_structure_change"};

// ---- the room (metres, world z up): x in [-kHalfX, kHalfX], y in [-kHalfY, kHalfY] ------------------
constexpr double kHalfX = 3.5;
constexpr double kHalfY = 3.0;
constexpr double kRoomHeight = 2.7;
constexpr double kDeskTopZ = 0.74;
constexpr double kSeatZ = 0.46;
constexpr double kChairY = 1.75;  // the desk chairs, in front of the desks along the north wall

// ---- the TUM-like views: the camera looks north at the desks ----------------------------------------
const Eigen::Vector3d kDeskViewEye(0.0, -0.6, 1.4);
const Eigen::Vector3d kDeskViewTarget(0.0, 2.5, 0.9);

// ---- loop scenes --------------------------------------------------------------------------------------
constexpr double kLoopEyeHeight = 1.2;
constexpr double kLoopPitchDeg = 8;    // camera looks this much down
constexpr double kRevisitAngle = 0.0;  // the revisited place: the camera at (r, 0) looking east
// Glances: their centres spread evenly over this arc of the circle, away from the place (degrees).
constexpr double kGlanceArcFromDeg = 75;
constexpr double kGlanceArcToDeg = 285;
// The screen: flat panels of at most this angle at the centre; each lap's screen stands this much
// inside the previous one (so the newest hides the older), metres.
constexpr double kScreenPanelDeg = 20;
constexpr double kScreenLapStepM = 0.003;
// loop_dynamic's pair of people is in view from this much of the circle before the place to as much
// after it, degrees: the place shows through the opening within about 26 of it at the defaults.
constexpr double kGroupArcDeg = 35;
// loop_dynamic's counters: depth of the box (metres) and the least gap between its back and the
// pair's centres (a torso's half depth and a little more), so that the pair stops behind it.
constexpr double kCounterDepthM = 0.08;
constexpr double kCounterToPairM = 0.15;

/// Deterministic random numbers for scene variation (splitmix64; portable, unlike std distributions).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : stream_(seed) {}
  std::uint64_t next() { return stream_.next(); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * stream_.next_unit(); }
  std::size_t index(std::size_t n) { return static_cast<std::size_t>(next() % n); }
  std::uint32_t salt() { return static_cast<std::uint32_t>(next() >> 32); }

 private:
  SplitMix64 stream_;
};

Eigen::Vector3f rgb(double r, double g, double b) {
  return Eigen::Vector3f(static_cast<float>(r), static_cast<float>(g), static_cast<float>(b));
}

/// A colour with each channel uniform in [lo, hi], drawn blue, green, red. One statement per draw:
/// the order of draws inside one call's arguments is unspecified in C++, so a compiler could render
/// another scene from the same seed. This order (and the one of the draws around each call below)
/// is the one GCC took when the draws were still arguments, so the presets keep their bytes.
Eigen::Vector3f random_rgb(Rng& r, double lo, double hi) {
  const double blue = r.uniform(lo, hi);
  const double green = r.uniform(lo, hi);
  const double red = r.uniform(lo, hi);
  return rgb(red, green, blue);
}

/// A two-colour pattern of random colours: colour a in [a_lo, a_hi], colour b in [b_lo, b_hi] per
/// channel, cell size uniform in [scale_lo, scale_hi]; drawn scale, b, a (see random_rgb).
struct RandomColours {
  Eigen::Vector3f a, b;
  double scale;
};
RandomColours random_colours(Rng& r, double a_lo, double a_hi, double b_lo, double b_hi, double scale_lo,
                             double scale_hi) {
  RandomColours c;
  c.scale = r.uniform(scale_lo, scale_hi);
  c.b = random_rgb(r, b_lo, b_hi);
  c.a = random_rgb(r, a_lo, a_hi);
  return c;
}

/// Camera pose looking along `forward` (world), x to the right and y down with no roll.
Eigen::Isometry3d look_along(const Eigen::Vector3d& eye, const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = forward.normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (x.norm() < 1e-9) x = Eigen::Vector3d::UnitX();
  x.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

/// Rotation about the camera's own axes: yaw about y (down), pitch about x (right), roll about z.
Eigen::Matrix3d camera_rotation(double yaw_rad, double pitch_rad, double roll_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

class SceneBuilder {
 public:
  SceneBuilder(SequenceSpec& spec, Rng& rng) : spec_(spec), rng_(rng) {}

  std::uint16_t instance(int class_id, bool moving) {
    const auto id = static_cast<std::uint16_t>(spec_.instances.size() + 1);
    spec_.instances.push_back(InstanceInfo{id, class_id, moving});
    return id;
  }
  std::uint16_t object(const char* coco_name) { return instance(*coco_class_id(coco_name), false); }

  Material material(Pattern pattern, const Eigen::Vector3f& a, const Eigen::Vector3f& b, double scale_m) {
    return Material{pattern, a, b, static_cast<float>(scale_m), rng_.salt()};
  }

  void add(Primitive p, int first_frame = 0) {
    p.first_frame = first_frame;
    spec_.static_primitives.push_back(p);
  }
  void box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double yaw, const Material& m,
           std::uint16_t id = 0, int first_frame = 0) {
    add(make_box(centre, half, yaw, m, id), first_frame);
  }
  /// A quad on a vertical wall: `normal` horizontal, u horizontal, v up.
  void wall_quad(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal, double half_u, double half_v,
                 const Material& m, std::uint16_t id = 0) {
    add(make_quad(centre, normal, Eigen::Vector3d::UnitZ().cross(normal), half_u, half_v, m, id));
  }

  Rng& rng() { return rng_; }

 private:
  SequenceSpec& spec_;
  Rng& rng_;
};

// ---- furniture and objects ------------------------------------------------------------------------------

/// A point offset in a frame yawed by `yaw` about z and placed at `at`.
Eigen::Vector3d place(const Eigen::Vector3d& at, double yaw, double x, double y, double z) {
  return at + Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(x, y, z);
}

void add_table(SceneBuilder& b, const Eigen::Vector2d& centre, double half_x, double half_y, const Material& top) {
  const std::uint16_t id = b.object("dining table");
  const Material metal = b.material(Pattern::plain, rgb(0.55, 0.56, 0.58), rgb(0.3, 0.3, 0.3), 0.05);
  b.box({centre.x(), centre.y(), kDeskTopZ - 0.02}, {half_x, half_y, 0.02}, 0, top, id);
  const double leg_half = 0.5 * (kDeskTopZ - 0.04);
  for (int i = 0; i < 4; ++i) {
    const double sx = (i & 1) ? 1 : -1, sy = (i & 2) ? 1 : -1;
    b.box({centre.x() + sx * (half_x - 0.05), centre.y() + sy * (half_y - 0.05), leg_half}, {0.025, 0.025, leg_half}, 0,
          metal, id);
  }
}

/// A desk chair whose sitter faces `yaw` + 90 degrees from world x (yaw 0: faces +y).
void add_chair(SceneBuilder& b, const Eigen::Vector2d& at_xy, double yaw, int first_frame = 0) {
  const std::uint16_t id = b.object("chair");
  const Eigen::Vector3d at(at_xy.x(), at_xy.y(), 0);
  const Material wood = b.material(Pattern::planks, rgb(0.78, 0.6, 0.3), rgb(0.45, 0.32, 0.15), 0.07);
  const Material metal = b.material(Pattern::plain, rgb(0.15, 0.15, 0.16), rgb(0.1, 0.1, 0.1), 0.05);
  b.box(place(at, yaw, 0, 0, kSeatZ), {0.23, 0.23, 0.035}, yaw, wood, id, first_frame);
  b.box(place(at, yaw, 0, -0.22, kSeatZ + 0.32), {0.22, 0.025, 0.2}, yaw, wood, id, first_frame);
  b.box(place(at, yaw, 0, -0.21, kSeatZ + 0.1), {0.02, 0.02, 0.1}, yaw, metal, id, first_frame);
  b.add(make_capsule(place(at, yaw, 0, 0, 0.1), place(at, yaw, 0, 0, kSeatZ - 0.04), 0.025, metal, id), first_frame);
  b.box(place(at, yaw, 0, 0, 0.05), {0.28, 0.03, 0.02}, yaw + 0.4, metal, id, first_frame);
  b.box(place(at, yaw, 0, 0, 0.05), {0.28, 0.03, 0.02}, yaw + 0.4 + kPi / 2, metal, id, first_frame);
}

void add_monitor(SceneBuilder& b, const Eigen::Vector2d& at_xy, double yaw, const char* coco = "tv",
                 double base_z = kDeskTopZ, double half_w = 0.28, double half_h = 0.18) {
  const std::uint16_t id = b.object(coco);
  const Eigen::Vector3d at(at_xy.x(), at_xy.y(), base_z);
  const Material plastic = b.material(Pattern::plain, rgb(0.12, 0.12, 0.13), rgb(0.1, 0.1, 0.1), 0.05);
  const Material display =
      b.material(Pattern::screen, rgb(0.2, 0.35, 0.7), rgb(0.1 + 0.2 * b.rng().uniform(0, 1), 0.4, 0.55), 0.07);
  const double centre_z = 0.11 + half_h;
  b.box(place(at, yaw, 0, 0, 0.008), {0.11, 0.08, 0.008}, yaw, plastic, id);
  b.box(place(at, yaw, 0, 0.01, 0.06), {0.03, 0.015, 0.06}, yaw, plastic, id);
  b.box(place(at, yaw, 0, 0, centre_z), {half_w, 0.025, half_h}, yaw, plastic, id);
  // The display faces -y of the monitor's frame (towards the user).
  const Eigen::Vector3d normal = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(0, -1, 0);
  b.wall_quad(place(at, yaw, 0, -0.0265, centre_z), normal, half_w - 0.02, half_h - 0.02, display, id);
}

/// A 40-inch tv (0.9 m x 0.55 m, its centre 1.15 m high) on a pole stand, its display facing -x
/// with its front at x = front_x, the pole at y; it appears at first_frame.
void add_tv_on_stand(SceneBuilder& b, double front_x, double y, int first_frame) {
  const std::uint16_t id = b.object("tv");
  const Material plastic = b.material(Pattern::plain, rgb(0.12, 0.12, 0.13), rgb(0.1, 0.1, 0.1), 0.05);
  const Material display = b.material(Pattern::screen, rgb(0.25, 0.3, 0.65), rgb(0.7, 0.45, 0.3), 0.07);
  const double centre_z = 1.15, half_w = 0.45, half_h = 0.275, half_depth = 0.025;
  const double x = front_x + half_depth;
  b.box({x, y, centre_z}, {half_depth, half_w, half_h}, 0, plastic, id, first_frame);
  b.add(make_quad({front_x - 0.0015, y, centre_z}, -Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitY(), half_w - 0.02,
                  half_h - 0.02, display, id),
        first_frame);
  b.add(make_capsule({x + 0.05, y, 0.03}, {x + 0.05, y, centre_z - half_h}, 0.025, plastic, id), first_frame);
  b.box({x + 0.05, y, 0.015}, {0.2, 0.04, 0.015}, 0, plastic, id, first_frame);
}

void add_keyboard(SceneBuilder& b, const Eigen::Vector2d& at, double yaw) {
  const std::uint16_t id = b.object("keyboard");
  b.box({at.x(), at.y(), kDeskTopZ + 0.012}, {0.22, 0.07, 0.012}, yaw,
        b.material(Pattern::tiles, rgb(0.8, 0.8, 0.78), rgb(0.15, 0.15, 0.15), 0.019), id);
}

void add_books(SceneBuilder& b, const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double yaw,
               int first_frame = 0) {
  const std::uint16_t id = b.object("book");
  b.box(centre, half, yaw, b.material(Pattern::spines, rgb(0.7, 0.6, 0.5), rgb(0.2, 0.2, 0.2), 0.045), id, first_frame);
}

void add_plant(SceneBuilder& b, const Eigen::Vector2d& at, double scale, int first_frame = 0) {
  const std::uint16_t id = b.object("potted plant");
  const Material pot = b.material(Pattern::bricks, rgb(0.7, 0.35, 0.2), rgb(0.5, 0.25, 0.15), 0.12);
  const Material leaves = b.material(Pattern::leaves, rgb(0.25, 0.6, 0.18), rgb(0.05, 0.15, 0.05), 0.05);
  b.box({at.x(), at.y(), 0.2 * scale}, Eigen::Vector3d(0.16, 0.16, 0.2) * scale, 0.3, pot, id, first_frame);
  b.add(make_ellipsoid({at.x(), at.y(), 0.7 * scale}, Eigen::Vector3d(0.32, 0.3, 0.36) * scale, 0.2, leaves, id),
        first_frame);
  b.add(make_ellipsoid({at.x() + 0.1 * scale, at.y() - 0.08 * scale, 1.05 * scale},
                       Eigen::Vector3d(0.22, 0.24, 0.3) * scale, 1.1, leaves, id),
        first_frame);
}

/// Posters: random-shape patterns on a vertical wall.
void add_poster(SceneBuilder& b, const Eigen::Vector3d& centre, const Eigen::Vector3d& normal, double half_u,
                double half_v) {
  const RandomColours c = random_colours(b.rng(), 0.6, 0.95, 0.1, 0.5, 0.08, 0.16);
  b.wall_quad(centre, normal, half_u, half_v, b.material(Pattern::blocks, c.a, c.b, c.scale));
}

void build_room(SceneBuilder& b) {
  Rng& r = b.rng();
  // Floor, rug, ceiling with lamps.
  b.add(make_quad({0, 0, 0}, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), kHalfX, kHalfY,
                  b.material(Pattern::planks, rgb(0.55, 0.38, 0.22), rgb(0.2, 0.13, 0.08), 0.16)));
  b.add(make_quad({0.2, -0.3, 0.004}, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), 1.3, 0.9,
                  b.material(Pattern::checks, rgb(0.6, 0.15, 0.12), rgb(0.85, 0.8, 0.65), 0.35)));
  b.add(make_quad({0, 0, kRoomHeight}, -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), kHalfX, kHalfY,
                  b.material(Pattern::tiles, rgb(0.88, 0.88, 0.85), rgb(0.55, 0.55, 0.55), 0.6)));
  const Material lamp = b.material(Pattern::plain, rgb(1.0, 1.0, 0.97), rgb(1, 1, 1), 0.2);
  for (const double x : {-1.8, 0.0, 1.8}) {
    for (const double y : {-1.5, 1.5}) {
      b.add(
          make_quad({x, y, kRoomHeight - 0.005}, -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), 0.6, 0.3, lamp));
    }
  }
  // Walls: north plaster, east bricks, south and west painted plaster; skirting boards.
  b.wall_quad({0, kHalfY, kRoomHeight / 2}, -Eigen::Vector3d::UnitY(), kHalfX, kRoomHeight / 2,
              b.material(Pattern::noise, rgb(0.85, 0.83, 0.76), rgb(0.62, 0.6, 0.52), 0.25));
  b.wall_quad({kHalfX, 0, kRoomHeight / 2}, -Eigen::Vector3d::UnitX(), kHalfY, kRoomHeight / 2,
              b.material(Pattern::bricks, rgb(0.62, 0.3, 0.2), rgb(0.82, 0.8, 0.74), 0.25));
  b.wall_quad({0, -kHalfY, kRoomHeight / 2}, Eigen::Vector3d::UnitY(), kHalfX, kRoomHeight / 2,
              b.material(Pattern::noise, rgb(0.72, 0.8, 0.75), rgb(0.5, 0.6, 0.55), 0.3));
  b.wall_quad({-kHalfX, 0, kRoomHeight / 2}, Eigen::Vector3d::UnitX(), kHalfY, kRoomHeight / 2,
              b.material(Pattern::noise, rgb(0.78, 0.8, 0.86), rgb(0.55, 0.58, 0.66), 0.3));
  const Material skirting = b.material(Pattern::planks, rgb(0.35, 0.25, 0.16), rgb(0.15, 0.1, 0.06), 0.08);
  b.box({0, kHalfY - 0.01, 0.05}, {kHalfX, 0.01, 0.05}, 0, skirting);
  b.box({0, -kHalfY + 0.01, 0.05}, {kHalfX, 0.01, 0.05}, 0, skirting);
  b.box({kHalfX - 0.01, 0, 0.05}, {0.01, kHalfY, 0.05}, 0, skirting);
  b.box({-kHalfX + 0.01, 0, 0.05}, {0.01, kHalfY, 0.05}, 0, skirting);

  // North: partition behind two desks, monitors, keyboards, books, cup, bottle, chairs, plant, clock.
  b.box({0, 2.85, 0.75}, {2.0, 0.03, 0.75}, 0,
        b.material(Pattern::noise, rgb(0.55, 0.6, 0.68), rgb(0.3, 0.34, 0.42), 0.1));
  for (int i = 0; i < 6; ++i) {
    const double half_v = r.uniform(0.12, 0.2);
    const double half_u = r.uniform(0.12, 0.2);
    const double x = -1.7 + i * 0.68 + r.uniform(-0.1, 0.1);
    const double z = 1.1 + r.uniform(-0.15, 0.15);
    add_poster(b, {x, 2.815, z}, -Eigen::Vector3d::UnitY(), half_u, half_v);
  }
  add_poster(b, {-1.3, kHalfY - 0.005, 2.0}, -Eigen::Vector3d::UnitY(), 0.45, 0.3);
  add_poster(b, {0.2, kHalfY - 0.005, 1.95}, -Eigen::Vector3d::UnitY(), 0.25, 0.32);
  // A wall shelf with books above the partition.
  b.box({2.4, kHalfY - 0.13, 1.75}, {0.6, 0.12, 0.015}, 0,
        b.material(Pattern::planks, rgb(0.6, 0.45, 0.3), rgb(0.3, 0.2, 0.1), 0.1));
  add_books(b, {2.3, kHalfY - 0.13, 1.765 + 0.12}, {0.4, 0.1, 0.12}, 0);
  {
    const std::uint16_t clock = b.object("clock");
    Primitive face = make_ellipsoid({1.6, kHalfY - 0.02, 2.0}, {0.16, 0.02, 0.16}, 0,
                                    b.material(Pattern::tiles, rgb(0.95, 0.95, 0.92), rgb(0.1, 0.1, 0.1), 0.07), clock);
    b.add(face);
  }
  const Material desk_top = b.material(Pattern::planks, rgb(0.85, 0.72, 0.5), rgb(0.5, 0.4, 0.25), 0.2);
  add_table(b, {-0.85, 2.45}, 0.8, 0.4, desk_top);
  add_table(b, {0.85, 2.45}, 0.8, 0.4, desk_top);
  add_monitor(b, {-0.75, 2.62}, r.uniform(-0.15, 0.15));
  add_monitor(b, {0.95, 2.62}, r.uniform(-0.15, 0.15));
  add_keyboard(b, {-0.75, 2.28}, r.uniform(-0.1, 0.1));
  add_keyboard(b, {0.95, 2.28}, r.uniform(-0.1, 0.1));
  {
    const std::uint16_t mouse = b.object("mouse");
    b.add(make_ellipsoid({-0.4, 2.3, kDeskTopZ + 0.015}, {0.03, 0.05, 0.018}, 0,
                         b.material(Pattern::plain, rgb(0.2, 0.2, 0.22), rgb(0, 0, 0), 0.05), mouse));
  }
  add_books(b, {-1.4, 2.55, kDeskTopZ + 0.05}, {0.16, 0.12, 0.05}, 0.3);
  add_books(b, {1.5, 2.6, kDeskTopZ + 0.12}, {0.14, 0.1, 0.12}, 0);
  {
    const std::uint16_t cup = b.object("cup");
    b.add(make_capsule({0.35, 2.3, kDeskTopZ + 0.04}, {0.35, 2.3, kDeskTopZ + 0.08}, 0.04,
                       b.material(Pattern::blocks, rgb(0.95, 0.95, 0.95), rgb(0.9, 0.9, 0.9), 0.05), cup));
    const std::uint16_t bottle = b.object("bottle");
    b.add(make_capsule({1.35, 2.35, kDeskTopZ + 0.04}, {1.35, 2.35, kDeskTopZ + 0.2}, 0.035,
                       b.material(Pattern::noise, rgb(0.3, 0.7, 0.35), rgb(0.8, 0.9, 0.8), 0.03), bottle));
  }
  add_chair(b, {-0.7, kChairY}, kPi + r.uniform(-0.3, 0.3));
  add_chair(b, {0.9, kChairY}, kPi + r.uniform(-0.3, 0.3));
  add_plant(b, {-2.9, 2.5}, 1.0);
  b.box({2.9, 2.55, 0.55}, {0.3, 0.3, 0.55}, 0,
        b.material(Pattern::tiles, rgb(0.6, 0.62, 0.65), rgb(0.25, 0.25, 0.28), 0.3));

  // East: bookshelf with four rows of books (the loop scenes' revisited place), posters.
  const Material shelf_wood = b.material(Pattern::planks, rgb(0.45, 0.3, 0.18), rgb(0.2, 0.12, 0.07), 0.1);
  b.box({kHalfX - 0.03, 0, 1.0}, {0.02, 1.0, 1.0}, 0, shelf_wood);
  for (const double y : {-1.0, 1.0}) b.box({kHalfX - 0.2, y, 1.0}, {0.16, 0.02, 1.0}, 0, shelf_wood);
  for (int i = 0; i < 5; ++i) b.box({kHalfX - 0.2, 0, 0.02 + 0.48 * i}, {0.16, 1.0, 0.015}, 0, shelf_wood);
  for (int i = 0; i < 4; ++i) {
    const double half_len = r.uniform(0.55, 0.95);
    const double offset = r.uniform(-(0.97 - half_len), 0.97 - half_len);
    const double half_h = r.uniform(0.13, 0.19);
    add_books(b, {kHalfX - 0.2, offset, 0.035 + 0.48 * i + half_h}, {0.12, half_len, half_h}, 0);
  }
  add_poster(b, {kHalfX - 0.005, -2.0, 1.5}, -Eigen::Vector3d::UnitX(), 0.35, 0.45);
  add_poster(b, {kHalfX - 0.005, 2.0, 1.6}, -Eigen::Vector3d::UnitX(), 0.3, 0.3);
  add_plant(b, {3.0, -1.4}, 0.8);

  // South: couch with cushions, low cabinet with a tv, door, window, poster.
  {
    const std::uint16_t couch = b.object("couch");
    const Material fabric = b.material(Pattern::checks, rgb(0.55, 0.2, 0.18), rgb(0.35, 0.35, 0.38), 0.14);
    b.box({-1.2, -2.5, 0.22}, {1.0, 0.42, 0.2}, 0, fabric, couch);
    b.box({-1.2, -2.86, 0.6}, {1.0, 0.12, 0.32}, 0, fabric, couch);
    for (const double dx : {-1.0, 1.0}) b.box({-1.2 + dx, -2.5, 0.5}, {0.1, 0.42, 0.1}, 0, fabric, couch);
    for (const double dx : {-0.45, 0.45}) {
      b.add(make_ellipsoid({-1.2 + dx, -2.65, 0.62}, {0.25, 0.08, 0.2}, 0,
                           b.material(Pattern::blocks, rgb(0.9, 0.85, 0.6), rgb(0.4, 0.5, 0.6), 0.1), couch));
    }
  }
  b.box({1.4, -2.75, 0.25}, {0.65, 0.22, 0.25}, 0,
        b.material(Pattern::planks, rgb(0.6, 0.45, 0.3), rgb(0.25, 0.18, 0.1), 0.12));
  add_monitor(b, {1.4, -2.75}, kPi, "tv", 0.5, 0.45, 0.27);
  add_poster(b, {-1.2, -kHalfY + 0.005, 1.7}, Eigen::Vector3d::UnitY(), 0.7, 0.4);
  b.add(make_quad({2.8, -kHalfY + 0.004, 1.0}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), 1.0, 0.45,
                  b.material(Pattern::planks, rgb(0.7, 0.55, 0.38), rgb(0.35, 0.25, 0.15), 0.15)));
  add_poster(b, {0.3, -kHalfY + 0.005, 1.5}, Eigen::Vector3d::UnitY(), 0.25, 0.35);

  // West: whiteboard, window, second table with a laptop and a vase, two chairs, posters.
  b.box({-kHalfX + 0.02, 0.4, 1.45}, {0.015, 1.0, 0.6}, 0,
        b.material(Pattern::blocks, rgb(0.95, 0.95, 0.95), rgb(0.88, 0.9, 0.92), 0.22));
  b.wall_quad({-kHalfX + 0.004, 2.1, 1.6}, Eigen::Vector3d::UnitX(), 0.6, 0.45,
              b.material(Pattern::noise, rgb(0.85, 0.92, 0.98), rgb(0.55, 0.7, 0.9), 0.4));
  {
    const Material frame = b.material(Pattern::plain, rgb(0.95, 0.95, 0.95), rgb(1, 1, 1), 0.1);
    b.box({-kHalfX + 0.02, 2.1, 1.6}, {0.02, 0.6, 0.025}, 0, frame);
    b.box({-kHalfX + 0.02, 2.1, 1.6}, {0.02, 0.025, 0.45}, 0, frame);
  }
  add_table(b, {-2.6, -1.2}, 0.5, 0.7, b.material(Pattern::planks, rgb(0.5, 0.33, 0.2), rgb(0.25, 0.15, 0.08), 0.15));
  {
    const std::uint16_t laptop = b.object("laptop");
    const Material grey = b.material(Pattern::tiles, rgb(0.6, 0.6, 0.62), rgb(0.2, 0.2, 0.2), 0.018);
    b.box({-2.55, -0.95, kDeskTopZ + 0.01}, {0.13, 0.17, 0.01}, 0, grey, laptop);
    Primitive lid = make_box({-2.7, -0.95, kDeskTopZ + 0.13}, {0.01, 0.17, 0.12}, 0,
                             b.material(Pattern::plain, rgb(0.2, 0.2, 0.22), rgb(0, 0, 0), 0.1), laptop);
    lid.T_world_local.linear() = Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
    b.add(lid);
    Primitive display = make_quad({0, 0, 0}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 0.15, 0.1,
                                  b.material(Pattern::screen, rgb(0.7, 0.3, 0.2), rgb(0.2, 0.3, 0.45), 0.05), laptop);
    Eigen::Isometry3d T_lid_display = Eigen::Isometry3d::Identity();  // just in front of the lid's +x face
    T_lid_display.linear() = display.T_world_local.linear();
    T_lid_display.translation() = Eigen::Vector3d(0.0105, 0, 0);
    display.T_world_local = lid.T_world_local * T_lid_display;
    b.add(display);
    const std::uint16_t vase = b.object("vase");
    b.add(make_ellipsoid({-2.45, -1.6, kDeskTopZ + 0.12}, {0.06, 0.06, 0.12}, 0,
                         b.material(Pattern::blocks, rgb(0.3, 0.45, 0.75), rgb(0.9, 0.9, 0.85), 0.04), vase));
  }
  add_chair(b, {-1.85, -1.3}, kPi / 2 + r.uniform(-0.3, 0.3));
  add_chair(b, {-2.6, -2.3}, 0 + r.uniform(-0.3, 0.3));
  add_poster(b, {-kHalfX + 0.005, -2.2, 1.6}, Eigen::Vector3d::UnitX(), 0.3, 0.4);
  add_poster(b, {-kHalfX + 0.005, -0.3, 2.35}, Eigen::Vector3d::UnitX(), 0.5, 0.15);
}

// ---- people -----------------------------------------------------------------------------------------------

PersonAppearance random_appearance(Rng& r) {
  static const Eigen::Vector3f kShirts[] = {rgb(0.25, 0.45, 0.3), rgb(0.7, 0.15, 0.15), rgb(0.2, 0.3, 0.6),
                                            rgb(0.85, 0.75, 0.3), rgb(0.3, 0.3, 0.32),  rgb(0.9, 0.9, 0.88)};
  static const Eigen::Vector3f kTrousers[] = {rgb(0.22, 0.27, 0.4), rgb(0.12, 0.12, 0.13), rgb(0.55, 0.48, 0.35),
                                              rgb(0.35, 0.38, 0.3)};
  static const Eigen::Vector3f kSkins[] = {rgb(0.87, 0.68, 0.56), rgb(0.7, 0.5, 0.36), rgb(0.45, 0.3, 0.2),
                                           rgb(0.95, 0.78, 0.66)};
  static const Eigen::Vector3f kHair[] = {rgb(0.25, 0.17, 0.1), rgb(0.08, 0.06, 0.05), rgb(0.7, 0.55, 0.3),
                                          rgb(0.45, 0.25, 0.12)};
  static const Pattern kShirtPatterns[] = {Pattern::checks, Pattern::checks, Pattern::blocks, Pattern::bricks};
  PersonAppearance a;
  const Eigen::Vector3f shirt = kShirts[r.index(6)];
  const Eigen::Vector3f shirt_b = kShirts[r.index(6)] * 0.5f + Eigen::Vector3f::Constant(0.45f);
  const Pattern pattern = kShirtPatterns[r.index(4)];
  a.shirt = Material{pattern, shirt, shirt_b,
                     static_cast<float>(pattern == Pattern::checks ? r.uniform(0.05, 0.09) : 0.12), r.salt()};
  const Eigen::Vector3f trousers = kTrousers[r.index(4)];
  a.trousers = Material{Pattern::noise, trousers, trousers * 1.6f, 0.025f, r.salt()};
  const Eigen::Vector3f skin = kSkins[r.index(4)];
  a.skin = Material{Pattern::plain, skin, skin, 0.03f, r.salt()};
  const Eigen::Vector3f hair = kHair[r.index(4)];
  a.hair = Material{Pattern::noise, hair, hair * 0.5f, 0.012f, r.salt()};
  a.shoes = Material{Pattern::plain, rgb(0.12, 0.11, 0.1), rgb(0.05, 0.05, 0.05), 0.03f, r.salt()};
  a.short_sleeves = r.uniform(0, 1) < 0.5;
  return a;
}

Person make_person(SceneBuilder& b, Posture posture) {
  Person p;
  p.instance_id = b.instance(kCocoPerson, true);
  p.posture = posture;
  p.height_m = b.rng().uniform(1.62, 1.88);
  p.appearance = random_appearance(b.rng());
  return p;
}

/// Two people walking in front of the desks: one round a loop, one back and forth with pauses.
void add_walking_people(SceneBuilder& b, SequenceSpec& spec, double duration_s, double speed, double pause_s) {
  Rng& r = b.rng();
  Person first = make_person(b, Posture::walking);
  const std::vector<Eigen::Vector2d> loop = {{-1.9, 0.6}, {1.7, 0.6}, {1.9, 1.25}, {-1.7, 1.3}};
  first.path = walk_at_constant_speed(loop, speed, true, 0, duration_s + 1, r.uniform(0, 8));
  spec.people.push_back(first);

  // The second person walks to the desks, stops, walks on, stops, and back, pausing at each stop.
  Person second = make_person(b, Posture::walking);
  const std::vector<Eigen::Vector2d> stops = {{2.2, 1.0}, {0.1, 1.45}, {-1.2, 0.4}, {-2.3, 1.5}};
  double t = -r.uniform(0, 10);
  std::size_t i = 0;
  int direction = 1;
  second.path.push_back({t, stops[0]});
  while (t < duration_s + 1) {
    if ((i == 0 && direction < 0) || (i + 1 == stops.size() && direction > 0)) direction = -direction;
    const std::size_t next = static_cast<std::size_t>(static_cast<int>(i) + direction);
    t += (stops[next] - stops[i]).norm() / speed;
    second.path.push_back({t, stops[next]});
    t += pause_s;
    second.path.push_back({t, stops[next]});
    i = next;
  }
  spec.people.push_back(second);
}

/// Two people sitting on the desk chairs, facing the camera, fidgeting.
void add_sitting_people(SceneBuilder& b, SequenceSpec& spec) {
  const double xs[] = {-0.7, 0.9};
  for (int k = 0; k < 2; ++k) {
    Person p = make_person(b, Posture::sitting);
    p.path = {{0, Eigen::Vector2d(xs[k], kChairY)}};
    p.sitting_heading_rad = -kPi / 2 + b.rng().uniform(-0.35, 0.35);
    p.seat_height_m = kSeatZ + 0.035;
    p.fidget_phase_s = b.rng().uniform(0, 10);
    spec.people.push_back(p);
  }
}

// ---- camera trajectories (t in seconds, T the duration) -----------------------------------------------------

Eigen::Isometry3d desk_view() { return look_along(kDeskViewEye, kDeskViewTarget - kDeskViewEye); }

double wave(double t, double period_s, double phase) { return std::sin(2 * kPi * t / period_s + phase); }

struct Phases {
  double p[6];
};

Phases random_phases(Rng& r) {
  Phases ph;
  for (double& x : ph.p) x = r.uniform(0, 2 * kPi);
  return ph;
}

/// Translation along the world axes (lateral, forwards, up), rotation within 1.5 degrees.
Eigen::Isometry3d xyz_pose(double t, const Phases& ph) {
  Eigen::Isometry3d T = desk_view();
  T.translation() +=
      Eigen::Vector3d(0.35 * wave(t, 7.3, ph.p[0]), 0.25 * wave(t, 9.7, ph.p[1]), 0.15 * wave(t, 5.9, ph.p[2]));
  T.linear() =
      T.linear() * camera_rotation(1.5 * kDegToRad * wave(t, 6.7, ph.p[3]), 1.5 * kDegToRad * wave(t, 8.3, ph.p[4]),
                                   1.0 * kDegToRad * wave(t, 7.7, ph.p[5]));
  return T;
}

/// On a half sphere of 1 m diameter (the half towards the camera's back), looking at the desks.
Eigen::Isometry3d halfsphere_pose(double t, const Phases& ph) {
  const Eigen::Vector3d centre(0.0, -0.2, 1.1);
  const double radius = 0.5;
  const double azimuth = 60 * kDegToRad * wave(t, 11.0, ph.p[0]);
  const double elevation = (35 + 30 * wave(t, 7.0, ph.p[1])) * kDegToRad;
  const Eigen::Vector3d eye =
      centre + radius * Eigen::Vector3d(std::sin(azimuth) * std::cos(elevation),
                                        -std::cos(azimuth) * std::cos(elevation), std::sin(elevation));
  return look_along(eye, kDeskViewTarget - eye);
}

/// In place: yaw 25, pitch 15, roll 20 degrees amplitudes.
Eigen::Isometry3d rpy_pose(double t, const Phases& ph) {
  Eigen::Isometry3d T = desk_view();
  T.linear() =
      T.linear() * camera_rotation(25 * kDegToRad * wave(t, 6.1, ph.p[0]), 15 * kDegToRad * wave(t, 4.3, ph.p[1]),
                                   20 * kDegToRad * wave(t, 5.3, ph.p[2]));
  return T;
}

/// Almost still: millimetres and tenths of a degree of hand tremor.
Eigen::Isometry3d static_pose(double t, const Phases& ph) {
  Eigen::Isometry3d T = desk_view();
  T.translation() +=
      Eigen::Vector3d(0.004 * wave(t, 3.1, ph.p[0]), 0.004 * wave(t, 4.7, ph.p[1]), 0.003 * wave(t, 2.3, ph.p[2]));
  T.linear() =
      T.linear() * camera_rotation(0.3 * kDegToRad * wave(t, 3.7, ph.p[3]), 0.3 * kDegToRad * wave(t, 2.9, ph.p[4]),
                                   0.2 * kDegToRad * wave(t, 4.1, ph.p[5]));
  return T;
}

/// Circling the room counter-clockwise, looking outwards (up by glance_deg); angle 0 is the revisited place.
Eigen::Isometry3d loop_pose(double angle_rad, double radius_m, double glance_deg = 0) {
  const Eigen::Vector3d eye(radius_m * std::cos(angle_rad), radius_m * std::sin(angle_rad), kLoopEyeHeight);
  const double pitch = (kLoopPitchDeg - glance_deg) * kDegToRad;
  const Eigen::Vector3d forward(std::cos(angle_rad) * std::cos(pitch), std::sin(angle_rad) * std::cos(pitch),
                                -std::sin(pitch));
  return look_along(eye, forward);
}

/// Returns to the place the camera films: without a margin the last return is not filmed.
int loop_revisits(const PresetSettings& s) { return s.loop_margin_deg > 0 ? s.loop_laps : s.loop_laps - 1; }

void validate_preset_settings(const PresetSettings& s) {
  validate_camera(s.camera, "PresetSettings.camera");
  validate_render_settings(s.render);
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(s.frame_rate_hz)) throw std::invalid_argument("PresetSettings.frame_rate_hz must be finite and > 0");
  if (!std::isfinite(s.start_timestamp_s))
    throw std::invalid_argument("PresetSettings.start_timestamp_s must be finite");
  if (!(positive(s.walking_speed_mps) && s.walking_speed_mps <= kMaxWalkingSpeedMps))
    throw std::invalid_argument("PresetSettings.walking_speed_mps must be > 0 and at most " +
                                std::to_string(kMaxWalkingSpeedMps) + " m/s");
  if (!(std::isfinite(s.pause_s) && s.pause_s >= 0))
    throw std::invalid_argument("PresetSettings.pause_s must be finite and >= 0");
  if (s.loop_laps < 2) {
    throw std::invalid_argument("PresetSettings.loop_laps must be >= 2 (got " + std::to_string(s.loop_laps) + ")");
  }
  if (!positive(s.loop_radius_m) || s.loop_radius_m > 1.6) {
    throw std::invalid_argument("PresetSettings.loop_radius_m must be in (0, 1.6]");
  }
  if (!positive(s.crossing_time_s))
    throw std::invalid_argument("PresetSettings.crossing_time_s must be finite and > 0");
  if (!(std::isfinite(s.crossing_distance_m) && s.crossing_distance_m > 0.4 && s.crossing_distance_m < 2.2))
    throw std::invalid_argument("PresetSettings.crossing_distance_m must be in (0.4, 2.2) metres");
  if (!positive(s.crossing_half_length_m) || s.crossing_half_length_m > 3)
    throw std::invalid_argument("PresetSettings.crossing_half_length_m must be in (0, 3] metres");
  if (!(std::isfinite(s.crossing_angle_deg) && s.crossing_angle_deg >= 0 && s.crossing_angle_deg <= 80))
    throw std::invalid_argument("PresetSettings.crossing_angle_deg must be in [0, 80]");
  if (!(std::isfinite(s.added_objects_distance_m) && s.added_objects_distance_m >= 0.5 &&
        s.added_objects_distance_m <= 2))
    throw std::invalid_argument("PresetSettings.added_objects_distance_m must be in [0.5, 2] metres");
  if (!(std::isfinite(s.crossing_jitter_s) && s.crossing_jitter_s >= 0))
    throw std::invalid_argument("PresetSettings.crossing_jitter_s must be finite and >= 0");
  if (!(s.loop_screen_radius_m == 0 ||
        (std::isfinite(s.loop_screen_radius_m) && s.loop_screen_radius_m > s.loop_radius_m + 0.4 &&
         s.loop_screen_radius_m <= 2.9)))
    throw std::invalid_argument("PresetSettings.loop_screen_radius_m must be 0 or in (loop_radius_m + 0.4, 2.9]");
  if (!(positive(s.loop_screen_opening_deg) && s.loop_screen_opening_deg < 90))
    throw std::invalid_argument("PresetSettings.loop_screen_opening_deg must be in (0, 90)");
  if (!(std::isfinite(s.loop_glance_pitch_deg) && s.loop_glance_pitch_deg >= 0 && s.loop_glance_pitch_deg <= 60))
    throw std::invalid_argument("PresetSettings.loop_glance_pitch_deg must be in [0, 60]");
  if (!(std::isfinite(s.loop_margin_deg) && s.loop_margin_deg >= 0 && s.loop_margin_deg <= 180))
    throw std::invalid_argument("PresetSettings.loop_margin_deg must be in [0, 180]");
  if (!(positive(s.loop_glance_half_arc_deg) && s.loop_glance_half_arc_deg <= 90))
    throw std::invalid_argument("PresetSettings.loop_glance_half_arc_deg must be in (0, 90]");
  const int revisits = loop_revisits(s);
  for (std::size_t k = 0; k < s.group_revisits.size(); ++k) {
    const int r = s.group_revisits[k];
    if (r < 1 || r > revisits || (k > 0 && r <= s.group_revisits[k - 1]))
      throw std::invalid_argument("PresetSettings.group_revisits must be strictly increasing, each in [1, " +
                                  std::to_string(revisits) + "] (got " + std::to_string(r) + ")");
  }
  if (!(std::isfinite(s.group_distance_m) && s.group_distance_m >= 0.5 && s.group_distance_m <= 2.2))
    throw std::invalid_argument("PresetSettings.group_distance_m must be in [0.5, 2.2] metres");
  if (!(positive(s.group_speed_mps) && s.group_speed_mps <= 1))
    throw std::invalid_argument("PresetSettings.group_speed_mps must be in (0, 1] m/s");
  if (!(std::isfinite(s.group_spacing_m) && s.group_spacing_m >= 0.4 && s.group_spacing_m <= 1.2))
    throw std::invalid_argument("PresetSettings.group_spacing_m must be in [0.4, 1.2] metres");
  if (!(s.group_counter_distance_m == 0 ||
        (std::isfinite(s.group_counter_distance_m) && s.group_counter_distance_m >= 0.42 &&
         s.group_counter_distance_m <= s.group_distance_m - 0.25)))
    throw std::invalid_argument(
        "PresetSettings.group_counter_distance_m must be 0 or in [0.42, group_distance_m - 0.25] metres");
  if (!(std::isfinite(s.group_counter_height_m) && s.group_counter_height_m >= 0.9 && s.group_counter_height_m <= 1.15))
    throw std::invalid_argument("PresetSettings.group_counter_height_m must be in [0.9, 1.15] metres");
  if (!(std::isfinite(s.tv_distance_m) && s.tv_distance_m >= 0.41 && s.tv_distance_m <= 0.45))
    throw std::invalid_argument("PresetSettings.tv_distance_m must be in [0.41, 0.45] metres");
  if (s.restock_revisit != 0 && (s.restock_revisit < 2 || s.restock_revisit > s.loop_laps))
    throw std::invalid_argument("PresetSettings.restock_revisit must be 0 or in [2, loop_laps] (got " +
                                std::to_string(s.restock_revisit) + ")");
}

/// Circle angle of frame i, radians: from margin before the place to margin after the laps-th
/// return to it, at constant speed (margin 0: exactly laps turns from the place).
double loop_angle_rad(int i, int frames, int laps, double margin_deg) {
  const double turns = laps + 2 * margin_deg / 360.0;
  return kRevisitAngle + 2 * kPi * turns * static_cast<double>(i) / frames - margin_deg * kDegToRad;
}

/// The frame at which the camera passes the place for the pass-th time (0: the first visit): the
/// first frame at or past it.
int pass_frame(int pass, int frames, int laps, double margin_deg) {
  const double fraction = (margin_deg + 360.0 * pass) / (360.0 * laps + 2 * margin_deg);
  return static_cast<int>(std::ceil(fraction * frames - 1e-9));
}

/// The frame nearest to where the camera is `angle_deg` of the circle past its first visit of the
/// place (360: the first return).
int frame_at_angle(double angle_deg, int frames, int laps, double margin_deg) {
  return static_cast<int>(std::lround(frames * (margin_deg + angle_deg) / (360.0 * laps + 2 * margin_deg)));
}

/// How far up the camera looks at circle angle `angle_deg` on lap `lap` (lap k runs from pass k-1
/// to pass k), degrees. Laps 2 .. laps glance once, each at a centre of its own; a raised cosine over
/// +-half_arc around it.
double glance_deg(const PresetSettings& s, int lap, double angle_deg) {
  const int laps = s.loop_laps;
  if (lap < 2 || lap > laps || s.loop_glance_pitch_deg == 0) return 0;
  const double centre = laps == 2 ? 0.5 * (kGlanceArcFromDeg + kGlanceArcToDeg)
                                  : kGlanceArcFromDeg + (kGlanceArcToDeg - kGlanceArcFromDeg) * (lap - 2) / (laps - 2);
  const double offset = std::abs(std::remainder(angle_deg - centre, 360.0));
  if (offset >= s.loop_glance_half_arc_deg) return 0;
  const double c = std::cos(0.5 * kPi * offset / s.loop_glance_half_arc_deg);
  return s.loop_glance_pitch_deg * c * c;
}

/// The screen of lap `lap`: floor-to-ceiling panels on a circle round the centre, leaving the
/// opening towards the place; it exists from the lap's first frame, a little inside the last one.
void add_lap_screen(SceneBuilder& b, const PresetSettings& s, int lap, int first_frame) {
  const double radius = s.loop_screen_radius_m - kScreenLapStepM * lap;
  const double from = s.loop_screen_opening_deg * kDegToRad, to = 2 * kPi - from;
  const int panels = static_cast<int>(std::ceil((to - from) / (kScreenPanelDeg * kDegToRad)));
  const double step = (to - from) / panels;
  Rng& r = b.rng();
  for (int j = 0; j < panels; ++j) {
    const double mid = from + (j + 0.5) * step;
    const Eigen::Vector3d inward(-std::cos(mid), -std::sin(mid), 0);
    const Eigen::Vector3d centre = -inward * radius * std::cos(0.5 * step);
    // Small cells: texture to track at 0.6 m.
    const RandomColours c = random_colours(r, 0.5, 0.95, 0.05, 0.45, 0.04, 0.06);
    const Material m = b.material(Pattern::blocks, c.a, c.b, c.scale);
    // Half width a little over the chord's so neighbouring panels meet without a gap.
    Primitive p =
        make_quad(centre + Eigen::Vector3d(0, 0, kRoomHeight / 2), inward, Eigen::Vector3d::UnitZ().cross(inward),
                  radius * std::sin(0.5 * step) + 0.01, kRoomHeight / 2 - 0.002, m);
    b.add(p, first_frame);
  }
}

/// loop_dynamic's counter of one group revisit: a thin box across the screen's opening, its front
/// group_counter_distance_m from the camera at the place, as wide as the opening there (seen from
/// the circle it covers the opening's whole width), with a new poster on its front. It exists from
/// first_frame to last_frame only.
void add_group_counter(SceneBuilder& b, const PresetSettings& s, int first_frame, int last_frame) {
  const double front = s.loop_radius_m + s.group_counter_distance_m;
  const double half_y = front * std::tan(s.loop_screen_opening_deg * kDegToRad);
  const double top = s.group_counter_height_m;
  Rng& r = b.rng();
  Primitive body = make_box({front + 0.5 * kCounterDepthM, 0, 0.5 * top}, {0.5 * kCounterDepthM, half_y, 0.5 * top}, 0,
                            b.material(Pattern::noise, rgb(0.55, 0.45, 0.35), rgb(0.35, 0.28, 0.2), 0.03));
  const RandomColours colours = random_colours(r, 0.6, 0.95, 0.05, 0.45, 0.03, 0.045);
  const Material poster = b.material(Pattern::blocks, colours.a, colours.b, colours.scale);
  Primitive front_poster = make_quad({front - 0.0015, 0, 0.5 * top}, -Eigen::Vector3d::UnitX(),
                                     -Eigen::Vector3d::UnitY(), half_y - 0.01, 0.5 * top - 0.01, poster);
  for (Primitive* p : {&body, &front_poster}) {
    p->last_frame = last_frame;
    b.add(*p, first_frame);
  }
}

}  // namespace

PresetSettings repeated_room_loop_settings(int laps) {
  PresetSettings s;
  s.loop_laps = laps;
  s.loop_margin_deg = 0;
  s.loop_screen_radius_m = 0;
  s.loop_glance_pitch_deg = 0;
  s.crossing_time_s = 3.0;
  s.crossing_distance_m = 1.0;
  s.crossing_half_length_m = 1.5;
  s.crossing_angle_deg = 0;
  s.crossing_jitter_s = 0;
  s.group_revisits.clear();
  s.restock_revisit = 0;
  return s;
}

std::vector<std::string> preset_names() {
  return std::vector<std::string>(std::begin(kPresetNames), std::end(kPresetNames));
}

SequenceSpec make_preset(const std::string& name, int frames, std::uint64_t seed, const PresetSettings& settings) {
  bool known = false;
  for (const char* n : kPresetNames) known = known || name == n;
  if (!known) {
    std::ostringstream msg;
    msg << "unknown preset '" << name << "'; known presets:";
    for (const char* n : kPresetNames) msg << ' ' << n;
    throw std::invalid_argument(msg.str());
  }
  if (frames < 1) {
    throw std::invalid_argument("make_preset(" + name + "): frames must be >= 1 (got " + std::to_string(frames) + ")");
  }
  if (frames > kMaxPresetFrames) {
    throw std::invalid_argument("make_preset(" + name + "): frames must be at most kMaxPresetFrames = " +
                                std::to_string(kMaxPresetFrames) + " (got " + std::to_string(frames) + ")");
  }
  validate_preset_settings(settings);

  SequenceSpec spec;
  spec.name = name;
  spec.camera = settings.camera;
  spec.frame_rate_hz = settings.frame_rate_hz;
  spec.start_timestamp_s = settings.start_timestamp_s;
  spec.render = settings.render;
  spec.seed = seed;
  Rng rng(seed);
  SceneBuilder builder(spec, rng);
  build_room(builder);

  const double duration_s = frames / settings.frame_rate_hz;
  const Phases phases = random_phases(rng);
  spec.T_world_camera.reserve(static_cast<std::size_t>(frames));
  const bool loop_scene = name.rfind("loop_", 0) == 0;
  if (!loop_scene) {
    for (int i = 0; i < frames; ++i) {
      const double t = i / settings.frame_rate_hz;
      if (name == "walking_halfsphere") {
        spec.T_world_camera.push_back(halfsphere_pose(t, phases));
      } else if (name == "walking_rpy") {
        spec.T_world_camera.push_back(rpy_pose(t, phases));
      } else if (name == "walking_static") {
        spec.T_world_camera.push_back(static_pose(t, phases));
      } else {
        spec.T_world_camera.push_back(xyz_pose(t, phases));
      }
    }
    if (name == "sitting_xyz") {
      add_sitting_people(builder, spec);
    } else {
      add_walking_people(builder, spec, duration_s, settings.walking_speed_mps, settings.pause_s);
    }
  } else {
    const int laps = settings.loop_laps;
    const double margin = settings.loop_margin_deg;
    for (int i = 0; i < frames; ++i) {
      const double angle = loop_angle_rad(i, frames, laps, margin);
      const double angle_deg = (angle - kRevisitAngle) / kDegToRad;
      const int lap = static_cast<int>(std::floor(angle_deg / 360.0)) + 1;  // 0 before the first visit
      spec.T_world_camera.push_back(loop_pose(angle, settings.loop_radius_m, glance_deg(settings, lap, angle_deg)));
    }
    if (settings.loop_screen_radius_m > 0) {
      // A new screen at every pass of the place (while the camera looks through the opening).
      for (int pass = 0; pass <= laps; ++pass) {
        add_lap_screen(builder, settings, pass, pass == 0 ? 0 : pass_frame(pass, frames, laps, margin));
      }
    }
    const double lap_s = duration_s * 360.0 / (360.0 * laps + 2 * margin);
    if (name == "loop_dynamic") {
      // A pedestrian crosses close in front of the camera each time it comes back to the place.
      Person walker = make_person(builder, Posture::walking);
      const double crossing_s = std::min(settings.crossing_time_s, 0.5 * lap_s);
      const Eigen::Vector2d middle(settings.loop_radius_m + settings.crossing_distance_m, 0);
      const double a = settings.crossing_angle_deg * kDegToRad;
      const Eigen::Vector2d half = settings.crossing_half_length_m * Eigen::Vector2d(std::sin(a), std::cos(a));
      const int revisits = loop_revisits(settings);
      // On the group revisits the pedestrian and a companion walk side by side towards the camera,
      // radially, passing group_distance_m in front of it when it passes the place; they are in view
      // from kGroupArcDeg before the place to as much after it (the place shows over less).
      const double group_half_s = lap_s * kGroupArcDeg / 360.0;
      const double group_walk_m = settings.group_speed_mps * group_half_s;
      const double group_x = settings.loop_radius_m + settings.group_distance_m;
      // Where the pair's walk ends: behind the counter when there is one.
      const double group_near_x =
          settings.group_counter_distance_m > 0
              ? std::max(group_x - group_walk_m,
                         settings.loop_radius_m + settings.group_counter_distance_m + kCounterDepthM + kCounterToPairM)
              : group_x - group_walk_m;
      std::vector<double> group_at;
      for (int lap = 1; lap <= revisits; ++lap) {
        const double sign = (lap % 2 == 1) ? 1.0 : -1.0;
        // Crossings of neighbouring revisits never overlap in short sequences: the jitter is at most
        // a quarter lap, the crossing at most half a lap.
        const double pass_s = duration_s * (margin + 360.0 * lap) / (360.0 * laps + 2 * margin);
        const double at = pass_s + rng.uniform(-1, 1) * std::min(settings.crossing_jitter_s, 0.2 * lap_s);
        if (std::find(settings.group_revisits.begin(), settings.group_revisits.end(), lap) !=
            settings.group_revisits.end()) {
          // Centred on the pass itself: the pair is in view the whole time the place is.
          const double side = 0.5 * settings.group_spacing_m;
          walker.path.push_back({pass_s - group_half_s, {group_x + group_walk_m, -side}});
          walker.path.push_back({pass_s + group_half_s, {group_near_x, -side}});
          walker.visible_s.emplace_back(pass_s - group_half_s, pass_s + group_half_s);
          group_at.push_back(pass_s);
          continue;
        }
        const Eigen::Vector2d along(half.x(), sign * half.y());  // always away from the camera
        walker.path.push_back({at - crossing_s / 2, middle - along});
        walker.path.push_back({at + crossing_s / 2, middle + along});
        walker.visible_s.emplace_back(at - crossing_s / 2, at + crossing_s / 2);
      }
      spec.people.push_back(walker);
      if (!group_at.empty()) {
        Person companion = make_person(builder, Posture::walking);
        const double side = 0.5 * settings.group_spacing_m;
        for (const double pass_s : group_at) {
          companion.path.push_back({pass_s - group_half_s, {group_x + group_walk_m, side}});
          companion.path.push_back({pass_s + group_half_s, {group_near_x, side}});
          companion.visible_s.emplace_back(pass_s - group_half_s, pass_s + group_half_s);
        }
        spec.people.push_back(companion);
      }
      // Drawn last, so that the counters change nothing else of the scene. Each is put up and taken
      // away half a lap before and after its revisit, while the camera looks the other way.
      if (settings.group_counter_distance_m > 0) {
        for (const int lap : settings.group_revisits) {
          add_group_counter(builder, settings, frame_at_angle(360.0 * lap - 180.0, frames, laps, margin),
                            frame_at_angle(360.0 * lap + 180.0, frames, laps, margin));
        }
      }
    } else {
      // As in the paper's experiment: two chairs, a laptop and an umbrella appear at the place half a
      // lap in, while the camera looks the other way.
      const int appear = frame_at_angle(180.0, frames, laps, margin);
      const double x0 = settings.loop_radius_m + settings.added_objects_distance_m;  // the chairs' line
      add_chair(builder, {x0, -0.35}, kPi / 2 + rng.uniform(-0.3, 0.3), appear);     // facing the camera
      add_chair(builder, {x0 + 0.05, 0.4}, kPi / 2 + rng.uniform(-0.3, 0.3), appear);
      {
        const std::uint16_t laptop = builder.object("laptop");  // open, on the first chair's seat
        const double seat = kSeatZ + 0.035;
        builder.box({x0, -0.35, seat + 0.01}, {0.12, 0.16, 0.01}, 0,
                    builder.material(Pattern::tiles, rgb(0.7, 0.7, 0.72), rgb(0.2, 0.2, 0.2), 0.018), laptop, appear);
        builder.box({x0 + 0.13, -0.35, seat + 0.13}, {0.01, 0.16, 0.11}, 0,
                    builder.material(Pattern::screen, rgb(0.2, 0.5, 0.3), rgb(0.6, 0.3, 0.5), 0.05), laptop, appear);
      }
      {
        // Open, standing on its handle behind the chairs: a canopy of 0.5 m radius at 1.1 m height.
        const std::uint16_t umbrella = builder.object("umbrella");
        const Material cloth = builder.material(Pattern::checks, rgb(0.15, 0.2, 0.55), rgb(0.8, 0.75, 0.2), 0.06);
        builder.add(make_capsule({x0 + 0.35, 0.0, 0.05}, {x0 + 0.35, 0.0, 1.1}, 0.015, cloth, umbrella), appear);
        builder.add(make_ellipsoid({x0 + 0.35, 0.0, 1.1}, {0.5, 0.5, 0.18}, 0, cloth, umbrella), appear);
      }
      if (settings.restock_revisit > 0) {
        // Other books on every row of the shelf, a little larger than the old ones and just in front
        // of them, half a lap before the restock revisit (the camera looks the other way).
        const int restock = frame_at_angle(360.0 * (settings.restock_revisit - 1) + 180.0, frames, laps, margin);
        for (int row = 0; row < 4; ++row) {
          const double half_h = builder.rng().uniform(0.19, 0.21);
          add_books(builder, {kHalfX - 0.205, 0, 0.035 + 0.48 * row + half_h}, {0.125, 0.975, half_h}, 0, restock);
        }
        add_tv_on_stand(builder, settings.loop_radius_m + settings.tv_distance_m, 0.5 * (-0.35 + 0.4), restock);
      }
    }
    spec.loops = ground_truth_loops(spec.T_world_camera, settings.loops);
  }
  validate_sequence_spec(spec);
  return spec;
}

}  // namespace sim
}  // namespace cge
