// Tracking's pose RANSAC on a synthetic frame of the real fr1/rpy slice's size: N matches (300:
// a typical local-map match count there, 1000: a full frame), 25 % of them wrong (a random map
// point), the rest with 1 px pixel noise and Kinect-like depth noise (sigma 0.003 z^2), every tenth
// without depth. Rigid: cge's hypotheses from three matches with depth (solve_rigid_pose_ransac);
// EPnP: cv::solvePnPRansac as the tracker calls it (solve_pnp_ransac). Both with the tracker's
// settings (100 samples at most, 3 px, confidence 0.99). Scene generation is outside the timed loop.
#include <benchmark/benchmark.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/slam/geometry/pnp_ransac.hpp"
#include "cge/slam/geometry/rigid_pose_ransac.hpp"
#include "cge/slam/settings.hpp"

namespace {

struct RansacScene {
  cge::PinholeIntrinsics<double> camera;
  std::vector<Eigen::Vector3d> world;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<Eigen::Vector3d> points_camera;
};

RansacScene make_scene(int matches) {
  RansacScene s;
  s.camera.fx_px = 517.3;
  s.camera.fy_px = 516.5;
  s.camera.cx_px = 318.6;
  s.camera.cy_px = 255.3;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 640), v(0, 480), z(0.8, 3.5), unit(0, 1);
  std::normal_distribution<double> noise(0, 1);
  Eigen::Isometry3d T_camera_world = Eigen::Isometry3d::Identity();
  T_camera_world.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  T_camera_world.translation() = Eigen::Vector3d(0.2, -0.1, 0.4);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < matches; ++i) {
    const double depth = z(rng);
    const Eigen::Vector3d p = s.camera.backproject(u(rng), v(rng), depth);
    Eigen::Vector3d X = T_camera_world.inverse() * p;
    if (unit(rng) < 0.25) X = T_camera_world.inverse() * s.camera.backproject(u(rng), v(rng), z(rng));
    s.world.push_back(X);
    s.pixels.push_back(s.camera.project(p) + Eigen::Vector2d(noise(rng), noise(rng)));
    const double sigma_z = 0.003 * depth * depth;
    const Eigen::Vector3d measured = p * ((depth + sigma_z * noise(rng)) / depth);
    s.points_camera.push_back(i % 10 == 9 ? Eigen::Vector3d(nan, nan, nan) : measured);
  }
  return s;
}

void BM_PoseRansac_Rigid(benchmark::State& state) {
  const RansacScene s = make_scene(static_cast<int>(state.range(0)));
  const cge::slam::TrackerSettings tracker;
  cge::slam::RigidPoseRansacSettings settings;
  settings.max_iterations = tracker.pnp_iterations;
  settings.reprojection_px = tracker.pnp_reprojection_px;
  settings.confidence = tracker.pnp_confidence;
  int inliers = 0;
  for (auto _ : state) {
    const auto r = cge::slam::solve_rigid_pose_ransac(s.world, s.pixels, s.points_camera, s.camera, settings);
    inliers = static_cast<int>(r.inliers.size());
    benchmark::DoNotOptimize(r.T_camera_world);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_PoseRansac_Rigid)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_PoseRansac_EPnP(benchmark::State& state) {
  const RansacScene s = make_scene(static_cast<int>(state.range(0)));
  const cge::slam::TrackerSettings tracker;
  cge::slam::PnpRansacSettings settings;
  settings.iterations = tracker.pnp_iterations;
  settings.reprojection_px = tracker.pnp_reprojection_px;
  settings.confidence = tracker.pnp_confidence;
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (std::size_t i = 0; i < s.world.size(); ++i) {
    object.emplace_back(s.world[i].x(), s.world[i].y(), s.world[i].z());
    image.emplace_back(s.pixels[i].x(), s.pixels[i].y());
  }
  int inliers = 0;
  for (auto _ : state) {
    const auto r = cge::slam::solve_pnp_ransac(object, image, s.camera, settings);
    inliers = static_cast<int>(r.inliers.size());
    benchmark::DoNotOptimize(r.T_camera_object);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_PoseRansac_EPnP)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);

}  // namespace
