// The reference pipeline on real frames: the first frames of TUM fr1/rpy in ../shared (skipped
// when it is absent). Keypoint undistortion against OpenCV and the forward model, bounded keyframe
// and map-point counts, and determinism.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/dataset/tum_sequence.hpp"
#include "cge/slam/frame.hpp"
#include "cge/slam/output_files.hpp"
#include "cge/slam/settings_from_orbslam2.hpp"
#include "cge/slam/system.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path kSlice = fs::path(CGE_SHARED_DIR) / "data" / "tum_fr1_rpy_300";
constexpr int kFrames = 40;  // 1.3 s of the rotating camera

bool slice_present() { return fs::is_regular_file(kSlice / "rgb.txt") && fs::is_regular_file(kSlice / "camera.yaml"); }

struct RealSetup {
  cge::PinholeIntrinsics<double> intrinsics;
  cge::slam::SystemSettings settings;
};

RealSetup real_setup(cge::slam::DynamicMode mode) {
  RealSetup s;
  s.settings.mode = mode;
  cge::slam::apply_orbslam2_settings(cge::dataset::read_orbslam2_settings(kSlice / "camera.yaml"), s.intrinsics,
                                     s.settings);
  return s;
}

/// trajectory.txt and keyframes.txt of a run over the first kFrames frames, and the System.
struct RunResult {
  std::string trajectory;
  int keyframes = 0;
  std::int64_t map_points = 0;
  int tracked = 0;
};

RunResult run(const cge::dataset::TumSequence& sequence, cge::slam::DynamicMode mode) {
  const RealSetup setup = real_setup(mode);
  cge::slam::System system(setup.settings, setup.intrinsics);
  for (int i = 0; i < kFrames; ++i) {
    const cge::dataset::TumFrame f = sequence.load(i);
    cge::slam::FrameInput in;
    in.index = i;
    in.timestamp_s = f.rgb_timestamp_s;
    in.bgr = f.bgr;
    in.depth = f.depth;
    in.stem = f.rgb_stem;
    system.process(in, {});
  }
  system.finish();
  RunResult r;
  std::ostringstream out;
  cge::slam::write_trajectory(out, system);
  r.trajectory = out.str();
  r.keyframes = system.map().keyframe_count();
  r.map_points = system.map().map_point_count();
  for (const auto& record : system.frames()) r.tracked += record.has_pose();
  return r;
}

}  // namespace

TEST_CASE("Real fr1/rpy: keypoints are undistorted as OpenCV and the forward model say (skipped without ../shared)",
          "[slam][real]") {
  if (!slice_present()) {
    WARN("skipped: " << kSlice.string() << " not found");
    return;
  }
  const cge::dataset::TumSequence sequence(kSlice);
  const RealSetup setup = real_setup(cge::slam::DynamicMode::none);
  const cge::LensDistortion& d = setup.settings.frame.distortion;
  REQUIRE_FALSE(d.is_zero());  // fr1 is distorted: k1 0.262383 ...
  cge::slam::FrameMaker maker(setup.settings, setup.intrinsics);
  const cge::dataset::TumFrame f = sequence.load(0);
  const cge::slam::Frame frame = maker.extract(0, f.rgb_timestamp_s, f.bgr, f.depth);
  REQUIRE(frame.size() > 500);
  REQUIRE(frame.undistorted_px.size() == frame.keypoints.size());

  // Oracle 1: cv::undistortPoints with a tight criterion of its own.
  std::vector<cv::Point2f> detected;
  for (const cv::KeyPoint& k : frame.keypoints) detected.push_back(k.pt);
  std::vector<cv::Point2f> opencv;
  const cv::Matx33d K = cge::opencv::camera_matrix(setup.intrinsics);
  cv::undistortPoints(detected, opencv, K, cge::opencv::distortion_coefficients(d), cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-14));
  // Oracle 2: the forward model takes each undistorted position back to where it was detected.
  const cge::PinholeIntrinsics<double>& k = setup.intrinsics;
  double largest_move = 0;
  for (std::size_t i = 0; i < detected.size(); ++i) {
    const cv::Point2f& u = frame.undistorted_px[i];
    CHECK(std::abs(u.x - opencv[i].x) < 1e-3);
    CHECK(std::abs(u.y - opencv[i].y) < 1e-3);
    const Eigen::Vector2d back = d.distort({(u.x - k.cx_px) / k.fx_px, (u.y - k.cy_px) / k.fy_px});
    CHECK(std::abs(back.x() * k.fx_px + k.cx_px - detected[i].x) < 1e-3);
    CHECK(std::abs(back.y() * k.fy_px + k.cy_px - detected[i].y) < 1e-3);
    largest_move = std::max(largest_move, static_cast<double>(std::hypot(u.x - detected[i].x, u.y - detected[i].y)));
    // The point from depth lies on the undistorted ray.
    const Eigen::Vector3d& p = frame.points_camera_m[i];
    if (std::isfinite(p.z())) {
      const Eigen::Vector2d uv = k.project(p);
      CHECK(std::abs(uv.x() - u.x) < 1e-3);
      CHECK(std::abs(uv.y() - u.y) < 1e-3);
    }
  }
  CHECK(largest_move > 5);  // fr1's distortion moves corner keypoints by pixels, not by rounding
  // The bounds are the undistorted corners: fr1's k1 > 0 moves them inwards by pixels.
  const std::vector<cv::Point2f> c = cge::opencv::undistort_pixels({{0, 0}, {640, 0}, {0, 480}, {640, 480}}, k, d);
  CHECK(frame.undistorted_bounds.min_x_px == std::min(c[0].x, c[2].x));
  CHECK(frame.undistorted_bounds.max_x_px == std::max(c[1].x, c[3].x));
  CHECK(frame.undistorted_bounds.min_y_px == std::min(c[0].y, c[1].y));
  CHECK(frame.undistorted_bounds.max_y_px == std::max(c[2].y, c[3].y));
  CHECK(frame.undistorted_bounds.min_x_px > 5);
  CHECK(frame.undistorted_bounds.max_x_px < 635);
}

TEST_CASE("Real fr1/rpy: bounded keyframes and map points, deterministic (skipped without ../shared)",
          "[slam][real]") {
  if (!slice_present()) {
    WARN("skipped: " << kSlice.string() << " not found");
    return;
  }
  const cge::dataset::TumSequence sequence(kSlice);
  for (const cge::slam::DynamicMode mode : {cge::slam::DynamicMode::none, cge::slam::DynamicMode::YMK}) {
    INFO("mode " << cge::slam::to_string(mode));
    const RunResult a = run(sequence, mode);
    CHECK(a.tracked == kFrames);
    // ORB-SLAM2 keeps about one keyframe in 7 frames on this sequence (41-43 of 300); every frame a
    // keyframe would be 40.
    CHECK(a.keyframes >= 2);
    CHECK(a.keyframes <= kFrames / 3);
    // At most 1000 keypoints per keyframe become points.
    CHECK(a.map_points <= 1000LL * a.keyframes);
    const RunResult b = run(sequence, mode);
    CHECK(a.trajectory == b.trajectory);
    CHECK(a.keyframes == b.keyframes);
    CHECK(a.map_points == b.map_points);
  }
}
