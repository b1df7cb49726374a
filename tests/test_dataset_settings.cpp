// Tests of the ORB-SLAM2 settings reader: the synthetic sequences' camera.yaml, hand-written
// TUM1-style files, every error naming file and key, and keypoint undistortion against a forward
// distortion model written out here.

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/slam/settings_from_orbslam2.hpp"
#include "cge/sim/tum_writer.hpp"
#include "temp_dir.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using cge::dataset::OrbSlam2Settings;
using cge::dataset::read_orbslam2_settings;
using cge_test::invalid_argument_message;
using cge_test::TempDir;

namespace {

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// Our own RGB-D file in the layout of ORB-SLAM2's TUM1.yaml, with the TUM fr1 calibration
// (published by TUM) and a few keys left out to exercise the defaults.
const char* const kTum1Style = R"(%YAML:1.0

#--------------------------------------------------------------------------------------------
# Camera Parameters. Adjust them!
#--------------------------------------------------------------------------------------------

# Camera calibration and distortion parameters (OpenCV)
Camera.fx: 517.306408
Camera.fy: 516.469215
Camera.cx: 318.643040
Camera.cy: 255.313989

Camera.k1: 0.262383
Camera.k2: -0.953104
Camera.p1: -0.005358
Camera.p2: 0.002628
Camera.k3: 1.163314

Camera.fps: 30.0

# IR projector baseline times fx (aprox.)
Camera.bf: 40.0

# Color order of the images (0: BGR, 1: RGB. It is ignored if images are grayscale)
Camera.RGB: 1

# Close/Far threshold. Baseline times.
ThDepth: 40.0

# Deptmap values factor
DepthMapFactor: 5000.0

ORBextractor.nFeatures: 1000
ORBextractor.scaleFactor: 1.2
ORBextractor.nLevels: 8
ORBextractor.iniThFAST: 20
ORBextractor.minThFAST: 7

Viewer.KeyFrameSize: 0.05
Viewer.PointSize: 2
)";

/// A minimal valid file with one line replaced or added.
std::string minimal(const std::string& extra = "") {
  return "%YAML:1.0\nCamera.fx: 500.0\nCamera.fy: 501.0\nCamera.cx: 320.0\nCamera.cy: 240.0\n"
         "Camera.k1: 0.0\nCamera.k2: 0.0\nCamera.p1: 0.0\nCamera.p2: 0.0\nDepthMapFactor: 1000.0\n" +
         extra;
}

/// OpenCV's radial-tangential model, forward: ideal normalised (x, y) -> distorted pixel.
cv::Point2d distort(const OrbSlam2Settings& s, double x, double y) {
  const auto& d = s.distortion;
  const double r2 = x * x + y * y;
  const double radial = 1 + d.k1 * r2 + d.k2 * r2 * r2 + d.k3 * r2 * r2 * r2;
  const double xd = x * radial + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x);
  const double yd = y * radial + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y;
  return {s.camera.fx_px * xd + s.camera.cx_px, s.camera.fy_px * yd + s.camera.cy_px};
}

}  // namespace

TEST_CASE("ORB-SLAM2 settings: the synthetic sequences' camera.yaml", "[dataset][settings]") {
  cge::sim::PinholeCamera camera;
  camera.fx_px = 512.25;
  camera.fy_px = 513.5;
  camera.cx_px = 300.75;
  camera.cy_px = 200.125;
  camera.width_px = 600;
  camera.height_px = 400;
  camera.depth_units_per_metre = 1000;
  cge::sim::TumWriterSettings ws;
  ws.orb_features = 1500;
  ws.orb_scale_factor = 1.25;
  ws.orb_levels = 6;
  ws.orb_initial_fast_threshold = 18;
  ws.orb_min_fast_threshold = 5;
  ws.orb_baseline_times_fx = 35;
  ws.orb_close_depth_baselines = 45;
  ws.depth_sigma_per_m = 0.004;
  TempDir tmp{"cge_test_dataset_settings"};
  const fs::path file = tmp.path() / "camera.yaml";
  write_text(file, cge::sim::format_camera_yaml(camera, 25.0, ws));

  const OrbSlam2Settings s = read_orbslam2_settings(file);
  CHECK(s.camera.fx_px == 512.25);
  CHECK(s.camera.fy_px == 513.5);
  CHECK(s.camera.cx_px == 300.75);
  CHECK(s.camera.cy_px == 200.125);
  CHECK(s.distortion.is_zero());
  CHECK(s.width_px == 600);
  CHECK(s.height_px == 400);
  CHECK(s.fps_hz == 25.0);
  CHECK(s.bf_px_m == 35.0);
  CHECK(s.th_depth_baselines == 45.0);
  CHECK(s.depth_map_factor == 1000.0);
  REQUIRE(s.rgb_order.has_value());
  CHECK(*s.rgb_order);
  CHECK(s.orb.features == 1500);
  CHECK(s.orb.scale_factor == 1.25);
  CHECK(s.orb.levels == 6);
  CHECK(s.orb.initial_fast_threshold == 18);
  CHECK(s.orb.min_fast_threshold == 5);
  CHECK(s.defaulted_keys.empty());
  CHECK(s.notes.empty());
  CHECK(s.source == file.string());
  CHECK(s.baseline_m() == Approx(35.0 / 512.25));
  CHECK(s.close_depth_threshold_m() == Approx(45.0 * 35.0 / 512.25));
  REQUIRE(s.depth_sigma_per_m_key.has_value());
  CHECK(*s.depth_sigma_per_m_key == 0.004);
  CHECK(s.depth_sigma_per_m() == 0.004);
}

TEST_CASE("ORB-SLAM2 settings: a TUM1-style file with distortion and defaults", "[dataset][settings]") {
  TempDir tmp{"cge_test_dataset_settings"};
  const fs::path file = tmp.path() / "TUM1.yaml";
  write_text(file, kTum1Style);
  const OrbSlam2Settings s = read_orbslam2_settings(file);
  CHECK(s.camera.fx_px == 517.306408);
  CHECK(s.camera.cy_px == 255.313989);
  CHECK(s.distortion.k1 == 0.262383);
  CHECK(s.distortion.k2 == -0.953104);
  CHECK(s.distortion.p1 == -0.005358);
  CHECK(s.distortion.p2 == 0.002628);
  CHECK(s.distortion.k3 == 1.163314);
  CHECK_FALSE(s.distortion.is_zero());
  CHECK(s.width_px == 0);  // not in the file
  CHECK(s.height_px == 0);
  CHECK(s.defaulted_keys == std::vector<std::string>{"Camera.width", "Camera.height", "cge.DepthSigmaPerMetre"});
  REQUIRE(s.notes.size() == 1);
  CHECK_THAT(s.notes[0], Contains("distortion"));
  CHECK(s.depth_map_factor == 5000.0);
  CHECK(s.orb.features == 1000);
  const cv::Mat K = s.camera_matrix();
  CHECK(K.at<double>(0, 0) == 517.306408);
  CHECK(K.at<double>(1, 2) == 255.313989);
  CHECK(K.at<double>(2, 2) == 1.0);

  // Only the required keys: every optional one takes ORB-SLAM2's TUM default.
  write_text(file, minimal());
  const OrbSlam2Settings m = read_orbslam2_settings(file);
  // k3, width, height, fps, bf, RGB, ThDepth, cge.DepthSigmaPerMetre, five ORBextractor keys
  CHECK(m.defaulted_keys.size() == 13);
  CHECK(m.fps_hz == 30);
  CHECK(m.bf_px_m == 40);
  // Without our key, ORB-SLAM2's depth weight: sigma_z = z^2 / bf at a one-pixel sigma.
  CHECK_FALSE(m.depth_sigma_per_m_key.has_value());
  CHECK(m.depth_sigma_per_m() == 1.0 / 40);
  CHECK(m.th_depth_baselines == 40);
  CHECK_FALSE(m.rgb_order.has_value());
  CHECK(m.orb.features == 1000);
  CHECK(m.orb.scale_factor == 1.2);
  CHECK(m.orb.levels == 8);
  CHECK(m.orb.initial_fast_threshold == 20);
  CHECK(m.orb.min_fast_threshold == 7);
  CHECK(m.depth_map_factor == 1000);
  // An integer written for a real key, and an integral real for an integer key, are accepted.
  write_text(file, minimal("Camera.fps: 15\nORBextractor.nFeatures: 2000.0\n"));
  const OrbSlam2Settings n = read_orbslam2_settings(file);
  CHECK(n.fps_hz == 15.0);
  CHECK(n.orb.features == 2000);
}

TEST_CASE("ORB-SLAM2 settings: errors name the file, the key and its line", "[dataset][settings][errors]") {
  TempDir tmp{"cge_test_dataset_settings"};
  const fs::path file = tmp.path() / "bad.yaml";
  const std::string f = file.string();
  const auto message = [&](const std::string& text) {
    write_text(file, text);
    return invalid_argument_message([&] { read_orbslam2_settings(file); });
  };
  CHECK_THAT(invalid_argument_message([&] { read_orbslam2_settings(tmp.path() / "none.yaml"); }),
             Contains("none.yaml") && Contains("does not exist"));
  CHECK_THAT(message("%YAML:1.0\nCamera.fx: [1, 2\n"), Contains(f));
  CHECK_THAT(message("just some words\n"), Contains(f));
  // Missing required keys.
  std::string no_fy = minimal();
  no_fy.erase(no_fy.find("Camera.fy"), std::string("Camera.fy: 501.0\n").size());
  CHECK_THAT(message(no_fy), Contains(f) && Contains("Camera.fy") && Contains("missing"));
  std::string no_factor = minimal();
  no_factor.erase(no_factor.find("DepthMapFactor"));
  CHECK_THAT(message(no_factor), Contains(f) && Contains("DepthMapFactor") && Contains("missing"));
  // Wrong types, with the line of the key.
  std::string fx_string = minimal();
  fx_string.replace(fx_string.find("500.0"), 5, "fast");
  CHECK_THAT(message(fx_string), Contains(f + ":2: key Camera.fx") && Contains("'fast'"));
  CHECK_THAT(message(minimal("ThDepth: [1, 2]\n")), Contains(f + ":11: key ThDepth") && Contains("sequence"));
  CHECK_THAT(message(minimal("ORBextractor.nLevels: 7.5\n")),
             Contains(f + ":11: key ORBextractor.nLevels") && Contains("integer"));
  // Out of range.
  std::string fx_negative = minimal();
  fx_negative.replace(fx_negative.find("500.0"), 5, "-500.0");
  CHECK_THAT(message(fx_negative), Contains(f + ":2: key Camera.fx") && Contains("out of range"));
  CHECK_THAT(message(minimal("ORBextractor.scaleFactor: 1.0\n")), Contains(f + ":11: key ORBextractor.scaleFactor"));
  CHECK_THAT(message(minimal("ORBextractor.iniThFAST: 300\n")), Contains("ORBextractor.iniThFAST"));
  CHECK_THAT(message(minimal("Camera.RGB: 2\n")), Contains("Camera.RGB"));
  CHECK_THAT(message(minimal("Camera.width: 640\n")), Contains(f + ":11: key Camera.width") && Contains("together"));
  CHECK_THAT(message(minimal("cge.DepthSigmaPerMetre: 0\n")),
             Contains(f + ":11: key cge.DepthSigmaPerMetre") && Contains("out of range"));
}

TEST_CASE("ORB-SLAM2 settings onto the pipeline's settings", "[dataset][settings]") {
  TempDir tmp{"cge_test_dataset_settings"};
  const fs::path file = tmp.path() / "camera.yaml";
  write_text(file, minimal("Camera.bf: 50.0\nThDepth: 30.0\nCamera.fps: 15.0\n"));
  const OrbSlam2Settings s = read_orbslam2_settings(file);
  cge::slam::SystemSettings settings;
  cge::PinholeIntrinsics<double> intrinsics;
  cge::slam::apply_orbslam2_settings(s, intrinsics, settings);
  CHECK(intrinsics.fx_px == 500.0);
  CHECK(settings.frame.depth_units_per_metre == 1000.0);
  CHECK(settings.frame.close_depth_m == Approx(30.0 * 50.0 / 500.0));
  CHECK(settings.orbslam2_keyframes.max_frame_gap == 15);
  // The depth weight of tracking, local BA and loop correction alike: 1 / bf without our key.
  CHECK(settings.tracker.refinement_depth_sigma_per_m == 1.0 / 50);
  CHECK(settings.local_mapping.depth_sigma_per_m == 1.0 / 50);
  CHECK(settings.loop_correction.depth_sigma_per_m == 1.0 / 50);
  write_text(file, minimal("cge.DepthSigmaPerMetre: 0.002\n"));
  cge::slam::apply_orbslam2_settings(read_orbslam2_settings(file), intrinsics, settings);
  CHECK(settings.tracker.refinement_depth_sigma_per_m == 0.002);
  CHECK(settings.local_mapping.depth_sigma_per_m == 0.002);
  CHECK(settings.loop_correction.depth_sigma_per_m == 0.002);
  CHECK_NOTHROW(settings.validate());
}

TEST_CASE("ORB-SLAM2 settings: keypoint undistortion inverts the distortion model", "[dataset][settings][undistort]") {
  TempDir tmp{"cge_test_dataset_settings"};
  const fs::path file = tmp.path() / "TUM1.yaml";
  write_text(file, kTum1Style);
  const OrbSlam2Settings s = read_orbslam2_settings(file);
  // Ideal pixels on a grid over the image; their distorted positions by the model above.
  std::vector<cv::Point2d> ideal;
  std::vector<cv::KeyPoint> distorted;
  for (int v = 20; v < 480; v += 40) {
    for (int u = 20; u < 640; u += 40) {
      ideal.emplace_back(u, v);
      const cv::Point2d d = distort(s, (u - s.camera.cx_px) / s.camera.fx_px, (v - s.camera.cy_px) / s.camera.fy_px);
      distorted.emplace_back(cv::Point2f(static_cast<float>(d.x), static_cast<float>(d.y)), 7.0f, 30.0f, 0.5f, 2, 9);
    }
  }
  const std::vector<cv::KeyPoint> out = cge::dataset::undistort_keypoints(distorted, s);
  REQUIRE(out.size() == ideal.size());
  double worst_px = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    worst_px = std::max(worst_px, std::hypot(out[i].pt.x - ideal[i].x, out[i].pt.y - ideal[i].y));
    CHECK(out[i].size == 7.0f);
    CHECK(out[i].angle == 30.0f);
    CHECK(out[i].octave == 2);
    CHECK(out[i].class_id == 9);
  }
  CAPTURE(worst_px);
  CHECK(worst_px < 0.01);  // float keypoints: the input itself is rounded to ~3e-5 px

  // No distortion: the points come back as they are.
  OrbSlam2Settings plain = s;
  plain.distortion = {};
  const std::vector<cv::Point2f> points = {{1.25f, 2.5f}, {600.5f, 470.25f}};
  CHECK(cge::dataset::undistort_points(points, plain) == points);
}
