// Tests of the synthetic RGB-D renderer (cge/sim/renderer.hpp): depth of known planes against the
// plane equation, the sensor model's rules against their definitions, visibility and masks against
// an independent sphere tracer over signed distances, ground-truth poses against the projection of a
// marker, determinism, and ORB features on every preset.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/sim/scene.hpp"
#include "test_support.hpp"

namespace {

using cge::sim::Material;
using cge::sim::Pattern;
using cge::sim::PinholeCamera;
using cge::sim::Primitive;
using cge::sim::RenderedFrame;
using cge::sim::RenderWorkspace;
using cge::sim::SequenceRenderer;
using cge::sim::SequenceSpec;
using cge::sim::Shape;

const Material kTiles{Pattern::tiles, {0.7f, 0.7f, 0.7f}, {0.2f, 0.2f, 0.2f}, 0.1f, 7};

/// A one-frame spec with the camera at the world origin (camera frame = world frame) and an ideal
/// sensor: no noise, no dropout, no incidence or discontinuity rule, range 0 .. 20 m.
SequenceSpec ideal_spec() {
  SequenceSpec spec;
  spec.T_world_camera = {Eigen::Isometry3d::Identity()};
  auto& d = spec.render.depth;
  d.noise_enabled = false;
  d.dropout_probability = 0;
  d.max_incidence_deg = 90;
  d.discontinuity_jump_m = std::numeric_limits<double>::infinity();
  d.min_range_m = 0;
  d.max_range_m = 12;
  return spec;
}

/// Camera-frame ray direction (z = 1) through the centre of pixel (u, v).
Eigen::Vector3d ray(const PinholeCamera& c, double u, double v) {
  return Eigen::Vector3d((u - c.cx_px) / c.fx_px, (v - c.cy_px) / c.fy_px, 1.0);
}

// ---- an independent oracle: signed distances and sphere tracing ---------------------------------

/// Distance from a world point to the primitive's surface (exact for quads, boxes and capsules; a
/// lower bound for ellipsoids, exact on their surface), written from the shapes' definitions.
double surface_distance(const Primitive& p, const Eigen::Vector3d& x_world) {
  const Eigen::Vector3d q = p.T_world_local.inverse() * x_world;
  const Eigen::Vector3d& s = p.size_m;
  switch (p.shape) {
    case Shape::quad: {
      const double dx = std::max(std::abs(q.x()) - s.x(), 0.0);
      const double dy = std::max(std::abs(q.y()) - s.y(), 0.0);
      return std::sqrt(dx * dx + dy * dy + q.z() * q.z());
    }
    case Shape::box: {
      const Eigen::Vector3d d = q.cwiseAbs() - s;
      const double outside = d.cwiseMax(0.0).norm();
      const double inside = std::min(d.maxCoeff(), 0.0);
      return std::abs(outside + inside);
    }
    case Shape::ellipsoid:
      return std::abs(q.cwiseQuotient(s).norm() - 1.0) * s.minCoeff();
    case Shape::capsule: {
      const double along = std::min(std::max(q.z(), -s.z()), s.z());
      return std::abs((q - Eigen::Vector3d(0, 0, along)).norm() - s.x());
    }
  }
  return std::numeric_limits<double>::infinity();
}

struct TraceHit {
  bool hit = false;
  double z = 0;  // depth along the optical axis
  int primitive = -1;
};

/// Sphere tracing along the ray of pixel (u, v): steps by the distance to the nearest surface
/// until within `epsilon` of one. Independent of the renderer's analytic intersections.
TraceHit sphere_trace(const std::vector<Primitive>& prims, const Eigen::Isometry3d& T_world_camera,
                      const PinholeCamera& cam, int u, int v, double near_m, double far_m) {
  constexpr double kEpsilon = 1e-6;
  constexpr int kMaxSteps = 4000;
  const Eigen::Vector3d d_cam = ray(cam, u, v);
  const Eigen::Vector3d dir = T_world_camera.linear() * d_cam.normalized();
  const Eigen::Vector3d origin = T_world_camera.translation();
  double t = near_m * d_cam.norm();
  for (int step = 0; step < kMaxSteps && t < far_m * d_cam.norm(); ++step) {
    const Eigen::Vector3d x = origin + t * dir;
    double nearest = std::numeric_limits<double>::infinity();
    int which = -1;
    for (std::size_t i = 0; i < prims.size(); ++i) {
      const double dist = surface_distance(prims[i], x);
      if (dist < nearest) {
        nearest = dist;
        which = static_cast<int>(i);
      }
    }
    if (nearest < kEpsilon) return TraceHit{true, t / d_cam.norm(), which};
    t += nearest;
  }
  return {};
}

}  // namespace

TEST_CASE("SequenceRenderer: depth of a tilted plane is exact up to quantisation", "[sim][renderer]") {
  SequenceSpec spec = ideal_spec();
  const Eigen::Vector3d normal = Eigen::Vector3d(0.25, -0.3, -1.0).normalized();
  const Eigen::Vector3d point(0.1, -0.05, 2.3);
  spec.static_primitives.push_back(cge::sim::make_quad(point, normal, Eigen::Vector3d::UnitX(), 30, 30, kTiles));
  const SequenceRenderer renderer(spec);
  RenderedFrame frame;
  RenderWorkspace ws;
  renderer.render_into(0, frame, ws);
  const PinholeCamera& cam = renderer.camera();
  double worst_units = 0;
  int invalid = 0;
  for (int v = 0; v < cam.height_px; ++v) {
    for (int u = 0; u < cam.width_px; ++u) {
      const double z = normal.dot(point) / normal.dot(ray(cam, u, v));  // the plane equation
      const std::uint16_t d = frame.depth.at<std::uint16_t>(v, u);
      if (d == 0) ++invalid;
      worst_units = std::max(worst_units, std::abs(d - z * cam.depth_units_per_metre));
      REQUIRE(std::abs(ws.depth_exact_m.at<float>(v, u) - z) <= 1e-5 * z);
    }
  }
  CHECK(invalid == 0);
  CHECK(worst_units <= 0.5 + 1e-2);  // rounding to the nearest unit, float arithmetic aside
}

TEST_CASE("SequenceRenderer: range-dependent noise has the documented spread", "[sim][renderer]") {
  SequenceSpec spec = ideal_spec();
  spec.render.depth.noise_enabled = true;
  spec.T_world_camera.push_back(Eigen::Isometry3d::Identity());
  const double plane_z = 2.0;
  spec.static_primitives.push_back(
      cge::sim::make_quad({0, 0, plane_z}, -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), 10, 10, kTiles));
  spec.seed = 99;
  const SequenceRenderer renderer(spec);
  const auto& ds = spec.render.depth;
  const double dz = plane_z - ds.noise_reference_m;
  const double sigma = ds.noise_base_m + ds.noise_quadratic_per_m * dz * dz;  // the documented model

  const RenderedFrame a = renderer.render(0);
  const RenderedFrame b = renderer.render(1);
  double sum = 0, sum2 = 0, largest = 0, sum_ab = 0;
  const double n = static_cast<double>(a.depth.total());
  for (int v = 0; v < a.depth.rows; ++v) {
    for (int u = 0; u < a.depth.cols; ++u) {
      const double ra = a.depth.at<std::uint16_t>(v, u) / 5000.0 - plane_z;
      const double rb = b.depth.at<std::uint16_t>(v, u) / 5000.0 - plane_z;
      sum += ra;
      sum2 += ra * ra;
      sum_ab += ra * rb;
      largest = std::max(largest, std::abs(ra));
    }
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  CHECK(std::abs(mean) < 0.02 * sigma);
  CHECK(sd == Approx(sigma).epsilon(0.02));
  CHECK(largest <= 3.47 * sigma + 1.0 / 5000);         // four-uniform sum: tails end at sqrt(12) sigma
  CHECK(std::abs(sum_ab / n) < 0.02 * sigma * sigma);  // frames have independent noise
}

TEST_CASE("SequenceRenderer: no depth beyond the range limits", "[sim][renderer]") {
  for (const double plane_z : {0.3, 5.0}) {
    SequenceSpec spec = ideal_spec();
    spec.render.depth.min_range_m = 0.4;
    spec.render.depth.max_range_m = 4.5;
    spec.static_primitives.push_back(
        cge::sim::make_quad({0, 0, plane_z}, -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), 10, 10, kTiles));
    const RenderedFrame f = SequenceRenderer(spec).render(0);
    CHECK(cv::countNonZero(f.depth) == 0);
    CHECK(cv::countNonZero(f.instance_labels) == 0);
  }
}

TEST_CASE("SequenceRenderer: depth holes at discontinuities and grazing incidence, by their definitions",
          "[sim][renderer]") {
  SequenceSpec spec = ideal_spec();
  spec.render.depth.discontinuity_jump_m = 0.08;
  spec.render.depth.max_incidence_deg = 70;
  // A wall, and a box rotated about the vertical (its side faces are seen at many angles).
  spec.static_primitives.push_back(
      cge::sim::make_quad({0, 0, 3.0}, -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), 10, 10, kTiles));
  Primitive box = cge::sim::make_box({0.1, 0.05, 1.6}, {0.3, 0.25, 0.2}, 0, kTiles, 1);
  box.T_world_local.linear() = Eigen::AngleAxisd(0.9, Eigen::Vector3d::UnitY()).toRotationMatrix();
  spec.static_primitives.push_back(box);
  spec.instances.push_back({1, 56, false});
  const SequenceRenderer renderer(spec);
  RenderedFrame f;
  RenderWorkspace ws;
  renderer.render_into(0, f, ws);
  const PinholeCamera& cam = renderer.camera();
  const double cos_max = std::cos(70 * 3.14159265358979323846 / 180);
  int holes = 0, checked = 0;
  for (int v = 1; v + 1 < cam.height_px; ++v) {
    for (int u = 1; u + 1 < cam.width_px; ++u) {
      const float z = ws.depth_exact_m.at<float>(v, u);
      bool jump = false;
      for (const auto& o : {cv::Point(1, 0), cv::Point(-1, 0), cv::Point(0, 1), cv::Point(0, -1)}) {
        jump = jump || std::abs(ws.depth_exact_m.at<float>(v + o.y, u + o.x) - z) > 0.08f;
      }
      // The surface normal from the scene: the wall's, or the box face the point lies on.
      const Eigen::Vector3d x = z * ray(cam, u, v);
      Eigen::Vector3d n_world = Eigen::Vector3d::UnitZ();
      if (f.instance_labels.at<std::uint16_t>(v, u) == 1) {
        const Eigen::Vector3d q = box.T_world_local.inverse() * x;
        const Eigen::Vector3d r = q.cwiseAbs().cwiseQuotient(box.size_m);
        int k;
        r.maxCoeff(&k);
        n_world = box.T_world_local.linear().col(k);
      }
      const double cos_incidence = std::abs(n_world.dot(ray(cam, u, v).normalized()));
      if (std::abs(cos_incidence - cos_max) < 1e-4) continue;  // on the threshold: either answer
      const bool expect_hole = jump || cos_incidence < cos_max;
      CHECK((f.depth.at<std::uint16_t>(v, u) == 0) == expect_hole);
      holes += expect_hole ? 1 : 0;
      ++checked;
    }
  }
  CHECK(holes > 500);  // both rules did fire
  CHECK(checked > 300000);
}

TEST_CASE("SequenceRenderer: a box's mask is its analytic silhouette", "[sim][renderer]") {
  SequenceSpec spec = ideal_spec();
  spec.static_primitives.push_back(
      cge::sim::make_quad({0, 0, 4.0}, -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), 10, 10, kTiles));
  const Eigen::Vector3d centre(-0.2, 0.1, 2.0), half(0.4, 0.3, 0.25);
  spec.static_primitives.push_back(cge::sim::make_box(centre, half, 0, kTiles, 7));
  spec.instances.push_back({7, 62, false});
  const SequenceRenderer renderer(spec);
  const RenderedFrame f = renderer.render(0);
  const PinholeCamera& c = renderer.camera();
  // Axis-aligned box seen from the origin: its silhouette is the front face (z = 1.75) for rays
  // through the front face, which contains the projections of the back face's rim here.
  const double z_front = centre.z() - half.z();
  const double u_lo = c.cx_px + c.fx_px * (centre.x() - half.x()) / z_front;
  const double u_hi = c.cx_px + c.fx_px * (centre.x() + half.x()) / z_front;
  const double v_lo = c.cy_px + c.fy_px * (centre.y() - half.y()) / z_front;
  const double v_hi = c.cy_px + c.fy_px * (centre.y() + half.y()) / z_front;
  int inside = 0;
  for (int v = 0; v < c.height_px; ++v) {
    for (int u = 0; u < c.width_px; ++u) {
      const double margin = std::min({std::abs(u - u_lo), std::abs(u - u_hi), std::abs(v - v_lo), std::abs(v - v_hi)});
      if (margin < 1e-6) continue;
      const bool expected = u > u_lo && u < u_hi && v > v_lo && v < v_hi;
      REQUIRE((f.instance_labels.at<std::uint16_t>(v, u) == 7) == expected);
      if (expected) {
        ++inside;
        REQUIRE(std::abs(f.depth.at<std::uint16_t>(v, u) - z_front * 5000) <= 0.51);
      }
    }
  }
  CHECK(inside > 10000);
}

TEST_CASE("SequenceRenderer: depth and masks of presets agree with a sphere tracer", "[sim][renderer]") {
  struct Case {
    const char* preset;
    int frame;
  };
  for (const Case c : {Case{"walking_xyz", 30}, Case{"sitting_xyz", 20},
                       Case{"loop_dynamic", 42}}) {  // loop_dynamic: the first revisit
    const SequenceRenderer renderer(cge::sim::make_preset(c.preset, 300, 5));
    RenderedFrame f;
    RenderWorkspace ws;
    renderer.render_into(c.frame, f, ws);
    const std::vector<Primitive> prims = renderer.primitives_at(c.frame);
    const PinholeCamera& cam = renderer.camera();
    const double near_m = renderer.spec().render.near_plane_m;
    int traced = 0, interior = 0, person_pixels = 0;
    for (int v = 3; v < cam.height_px - 3; v += 23) {
      for (int u = 2; u < cam.width_px - 2; u += 17) {
        const std::uint16_t label = f.instance_labels.at<std::uint16_t>(v, u);
        // Interior pixels: the same label and a smooth depth all around (no silhouette nearby).
        bool is_interior = true;
        const float z = ws.depth_exact_m.at<float>(v, u);
        for (int dv = -2; dv <= 2; ++dv) {
          for (int du = -2; du <= 2; ++du) {
            is_interior = is_interior && f.instance_labels.at<std::uint16_t>(v + dv, u + du) == label &&
                          std::abs(ws.depth_exact_m.at<float>(v + dv, u + du) - z) < 0.05f * z;
          }
        }
        if (!is_interior) continue;
        ++interior;
        const TraceHit hit = sphere_trace(prims, f.T_world_camera, cam, u, v, near_m, 20.0);
        REQUIRE(hit.hit);
        ++traced;
        CHECK(std::abs(hit.z - z) < 1e-3);
        CHECK(prims[static_cast<std::size_t>(hit.primitive)].instance_id == label);
        for (const auto& info : renderer.instances()) {
          if (info.id == label && info.class_id == cge::kCocoPerson) ++person_pixels;
        }
      }
    }
    INFO(c.preset);
    CHECK(traced > 300);
    CHECK(person_pixels > 0);  // each of these frames shows a person
  }
}

TEST_CASE("SequenceRenderer: ground-truth poses project a static marker onto its rendered mask", "[sim][renderer]") {
  struct Case {
    const char* preset;
    Eigen::Vector3d marker;
  };
  for (const Case& c : {Case{"walking_halfsphere", {0.35, 2.1, 0.95}}, Case{"walking_rpy", {-0.3, 2.2, 1.1}},
                        Case{"walking_xyz", {0.6, 2.3, 0.9}}, Case{"loop_structure_change", {2.3, -0.3, 1.5}}}) {
    // The loop scene turns 8 1/3 times and shows the marker (through the screen's opening, above the
    // umbrella) only near the place: more frames, so that it is in view often enough.
    const bool loop_scene = std::string(c.preset).rfind("loop_", 0) == 0;
    SequenceSpec spec = cge::sim::make_preset(c.preset, loop_scene ? 480 : 120, 3);
    const double radius = 0.03;
    const auto id = static_cast<std::uint16_t>(spec.instances.size() + 1);
    spec.instances.push_back({id, 32, false});  // a sports ball
    spec.static_primitives.push_back(
        cge::sim::make_ellipsoid(c.marker, Eigen::Vector3d::Constant(radius), 0, kTiles, id));
    const SequenceRenderer renderer(spec);
    const PinholeCamera& cam = renderer.camera();
    int checked = 0;
    for (int i = 0; i < renderer.frame_count(); i += 2) {
      RenderedFrame f;
      RenderWorkspace ws;
      renderer.render_into(i, f, ws);
      const Eigen::Vector3d p = f.T_world_camera.inverse() * c.marker;  // camera frame
      if (p.z() < 0.3) continue;
      const double u = cam.cx_px + cam.fx_px * p.x() / p.z();
      const double v = cam.cy_px + cam.fy_px * p.y() / p.z();
      const double r_px = cam.fx_px * radius / p.z();
      if (u < r_px + 2 || v < r_px + 2 || u > cam.width_px - r_px - 3 || v > cam.height_px - r_px - 3) continue;
      double su = 0, sv = 0;
      int count = 0;
      for (int y = 0; y < cam.height_px; ++y) {
        for (int x = 0; x < cam.width_px; ++x) {
          if (f.instance_labels.at<std::uint16_t>(y, x) == id) {
            su += x;
            sv += y;
            ++count;
          }
        }
      }
      const double expected_area = 3.14159265358979323846 * r_px * r_px * cam.fy_px / cam.fx_px;
      if (count < 0.9 * expected_area) continue;  // partly hidden (a person in front)
      INFO(c.preset << " frame " << i);
      CHECK(std::abs(su / count - u) < 0.35);
      CHECK(std::abs(sv / count - v) < 0.35);
      const float z_centre =
          ws.depth_exact_m.at<float>(static_cast<int>(std::lround(v)), static_cast<int>(std::lround(u)));
      CHECK(std::abs(z_centre - (p.z() - radius)) < 0.01);
      ++checked;
    }
    INFO(c.preset);
    CHECK(checked >= 5);
  }
}

TEST_CASE("SequenceRenderer: same spec and seed give bit-identical frames in any order", "[sim][renderer]") {
  const SequenceRenderer a(cge::sim::make_preset("walking_xyz", 60, 11));
  const SequenceRenderer b(cge::sim::make_preset("walking_xyz", 60, 11));
  RenderedFrame reused;
  RenderWorkspace ws;
  for (const int i : {41, 3, 59, 3, 0}) {  // out of order, one twice, one workspace throughout
    const RenderedFrame fresh = b.render(i);
    a.render_into(i, reused, ws);
    CHECK(reused.index == i);
    CHECK(cv::norm(reused.rgb, fresh.rgb, cv::NORM_INF) == 0);
    CHECK(cv::norm(reused.depth, fresh.depth, cv::NORM_INF) == 0);
    CHECK(cv::norm(reused.instance_labels, fresh.instance_labels, cv::NORM_INF) == 0);
    CHECK(reused.T_world_camera.isApprox(fresh.T_world_camera, 0));
    CHECK(reused.timestamp_s == fresh.timestamp_s);
  }
  // Another seed: other textures, clothes and noise.
  const RenderedFrame other = SequenceRenderer(cge::sim::make_preset("walking_xyz", 60, 12)).render(3);
  CHECK(cv::norm(other.rgb, b.render(3).rgb, cv::NORM_INF) > 0);
}

TEST_CASE("SequenceRenderer: frame metadata and index errors", "[sim][renderer]") {
  cge::sim::PresetSettings settings;
  settings.start_timestamp_s = 1000.0;
  settings.frame_rate_hz = 20;
  const SequenceRenderer r(cge::sim::make_preset("walking_static", 10, 1, settings));
  CHECK(r.frame_count() == 10);
  CHECK(r.frame_rate_hz() == 20);
  const RenderedFrame f = r.render(4);
  CHECK(f.index == 4);
  CHECK(f.timestamp_s == Approx(1000.2).margin(1e-12));
  CHECK(f.T_world_camera.isApprox(r.spec().T_world_camera[4], 0));
  CHECK(f.rgb.type() == CV_8UC3);
  CHECK(f.depth.type() == CV_16UC1);
  CHECK(f.instance_labels.type() == CV_16UC1);
  CHECK(f.rgb.size() == cv::Size(640, 480));
  for (const int bad : {-1, 10, 1000}) {
    const std::string msg = cge_test::invalid_argument_message([&] { r.render(bad); });
    CHECK_THAT(msg, Catch::Contains("frame index " + std::to_string(bad)));
    CHECK_THAT(msg, Catch::Contains("0 .. 9"));
  }
}

TEST_CASE("SequenceRenderer: ORB finds hundreds of well-spread features on every preset", "[sim][renderer][orb]") {
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(1000);
  for (const std::string& name : cge::sim::preset_names()) {
    const SequenceRenderer renderer(cge::sim::make_preset(name, 90, 2));
    for (const int i : {0, 45, 89}) {
      cv::Mat gray;
      cv::cvtColor(renderer.render(i).rgb, gray, cv::COLOR_BGR2GRAY);
      std::vector<cv::KeyPoint> keypoints;
      orb->detect(gray, keypoints);
      // Spread: keypoints fall into most cells of a 4 x 4 grid.
      bool cell[4][4] = {};
      for (const cv::KeyPoint& k : keypoints) {
        cell[std::min(3, static_cast<int>(k.pt.y * 4 / static_cast<float>(gray.rows)))]
            [std::min(3, static_cast<int>(k.pt.x * 4 / static_cast<float>(gray.cols)))] = true;
      }
      int cells = 0;
      for (const auto& row : cell) cells += static_cast<int>(std::count(row, row + 4, true));
      INFO(name << " frame " << i << ": " << keypoints.size() << " keypoints in " << cells << " of 16 cells");
      CHECK(keypoints.size() >= 500);
      CHECK(cells >= 11);
    }
  }
}
