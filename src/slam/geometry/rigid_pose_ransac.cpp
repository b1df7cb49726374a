#include "cge/slam/geometry/rigid_pose_ransac.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "cge/core/splitmix64.hpp"
#include "cge/metrics/rigid_alignment.hpp"

namespace cge {
namespace slam {

void RigidPoseRansacSettings::validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("RigidPoseRansacSettings: " + what);
  };
  if (max_iterations < 1) fail("max_iterations must be at least 1");
  if (!(reprojection_px > 0) || !std::isfinite(reprojection_px)) fail("reprojection_px must be finite and > 0");
  if (!(confidence > 0 && confidence < 1)) fail("confidence must be in (0, 1)");
  const auto non_negative = [](double v) { return v >= 0 && std::isfinite(v); };
  if (!non_negative(min_triangle_side_m)) fail("min_triangle_side_m must be finite and >= 0");
  if (!non_negative(refit_tolerance_m)) fail("refit_tolerance_m must be finite and >= 0");
  if (!non_negative(refit_tolerance_per_m)) fail("refit_tolerance_per_m must be finite and >= 0");
}

namespace {

bool spans_a_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      double min_cross_norm) {
  const double cross = (b - a).cross(c - a).norm();
  return std::isfinite(cross) && cross > min_cross_norm;
}

/// The pairs whose point, moved by T, lies in front of the camera and reprojects within the threshold.
struct Scorer {
  const std::vector<Eigen::Vector3d>& world;
  const std::vector<Eigen::Vector2d>& pixels;
  const PinholeIntrinsics<double>& camera;
  double threshold_sq_px;

  bool inlier(const Eigen::Isometry3d& T, std::size_t i) const {
    const Eigen::Vector3d p = T.linear() * world[i] + T.translation();
    if (!(p.z() > 0)) return false;
    const double du = camera.fx_px * p.x() / p.z() + camera.cx_px - pixels[i].x();
    const double dv = camera.fy_px * p.y() / p.z() + camera.cy_px - pixels[i].y();
    return du * du + dv * dv < threshold_sq_px;
  }
  /// Inliers of T, all and those with depth, in one pass over the pairs.
  struct Count {
    int all = 0;
    int with_depth = 0;
  };
  Count count(const Eigen::Isometry3d& T, const std::vector<char>& has_depth) const {
    Count n;
    for (std::size_t i = 0; i < world.size(); ++i) {
      if (!inlier(T, i)) continue;
      ++n.all;
      n.with_depth += has_depth[i] ? 1 : 0;
    }
    return n;
  }
  std::vector<int> inliers(const Eigen::Isometry3d& T) const {
    std::vector<int> out;
    for (std::size_t i = 0; i < world.size(); ++i) {
      if (inlier(T, i)) out.push_back(static_cast<int>(i));
    }
    return out;
  }
};

}  // namespace

Eigen::Isometry3d fit_rigid_motion(const std::vector<Eigen::Vector3d>& points_world,
                                   const std::vector<Eigen::Vector3d>& points_camera) {
  if (points_world.size() != points_camera.size() || points_world.size() < 3) {
    throw std::invalid_argument("fit_rigid_motion: needs at least three pairs of equal-sized point lists");
  }
  return metrics::align_rigid(points_world, points_camera);
}

RigidPoseRansacResult solve_rigid_pose_ransac(const std::vector<Eigen::Vector3d>& points_world,
                                              const std::vector<Eigen::Vector2d>& pixels_px,
                                              const std::vector<Eigen::Vector3d>& points_camera_m,
                                              const PinholeIntrinsics<double>& camera,
                                              const RigidPoseRansacSettings& settings) {
  settings.validate();
  if (points_world.size() != pixels_px.size() || points_world.size() != points_camera_m.size()) {
    throw std::invalid_argument("solve_rigid_pose_ransac: points_world, pixels_px and points_camera_m differ in size");
  }
  RigidPoseRansacResult result;
  std::vector<int> with_depth;
  std::vector<char> has_depth(points_world.size(), 0);
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    if (points_camera_m[i].allFinite() && points_world[i].allFinite()) {
      with_depth.push_back(static_cast<int>(i));
      has_depth[i] = 1;
    }
  }
  const auto m = static_cast<std::uint64_t>(with_depth.size());
  if (m < 3) return result;

  const Scorer scorer{points_world, pixels_px, camera, settings.reprojection_px * settings.reprojection_px};
  const double min_cross = settings.min_triangle_side_m * settings.min_triangle_side_m;
  const double log_miss = std::log(1.0 - settings.confidence);
  SplitMix64 rng(settings.seed);
  Eigen::Isometry3d best = Eigen::Isometry3d::Identity();
  int best_count = -1;
  double needed = static_cast<double>(settings.max_iterations);
  while (result.iterations < settings.max_iterations && result.iterations < needed) {
    ++result.iterations;
    const std::uint64_t a = rng.next() % m;
    std::uint64_t b = rng.next() % (m - 1);
    b += b >= a ? 1 : 0;
    std::uint64_t c = rng.next() % (m - 2);
    // The third index skips the two taken, in ascending order.
    const std::uint64_t lo = a < b ? a : b;
    const std::uint64_t hi = a < b ? b : a;
    c += c >= lo ? 1 : 0;
    c += c >= hi ? 1 : 0;
    const std::array<int, 3> sample = {with_depth[a], with_depth[b], with_depth[c]};
    const auto x = static_cast<std::size_t>(sample[0]);
    const auto y = static_cast<std::size_t>(sample[1]);
    const auto z = static_cast<std::size_t>(sample[2]);
    if (!spans_a_triangle(points_world[x], points_world[y], points_world[z], min_cross) ||
        !spans_a_triangle(points_camera_m[x], points_camera_m[y], points_camera_m[z], min_cross)) {
      continue;
    }
    const Eigen::Isometry3d T = metrics::align_rigid(points_world, points_camera_m, sample.data(), sample.size());
    if (!T.matrix().allFinite()) continue;
    const Scorer::Count count = scorer.count(T, has_depth);
    if (count.all <= best_count) continue;
    best_count = count.all;
    best = T;
    const double w = static_cast<double>(count.with_depth) / static_cast<double>(m);
    const double all_inlier = w * w * w;
    if (all_inlier >= 1) {
      needed = 0;
    } else if (all_inlier > 0) {
      needed = log_miss / std::log(1.0 - all_inlier);
    }
  }
  if (best_count < 3) return result;

  // The refit takes the inliers whose 3-D residual, too, is within the depth noise: reprojection
  // barely sees a depth error along the ray (a keypoint on an edge reads the background's depth),
  // while a least-squares fit in 3-D follows it.
  std::vector<int> inliers = scorer.inliers(best);
  std::vector<int> refit_pairs;
  for (const int i : inliers) {
    const auto k = static_cast<std::size_t>(i);
    if (!has_depth[k]) continue;
    const double z = points_camera_m[k].z();
    const double tolerance_m = settings.refit_tolerance_m + settings.refit_tolerance_per_m * z * z;
    if ((points_camera_m[k] - best * points_world[k]).norm() <= tolerance_m) refit_pairs.push_back(i);
  }
  if (refit_pairs.size() >= 3) {
    const Eigen::Isometry3d refit =
        metrics::align_rigid(points_world, points_camera_m, refit_pairs.data(), refit_pairs.size());
    if (refit.matrix().allFinite()) {
      std::vector<int> refit_inliers = scorer.inliers(refit);
      if (refit_inliers.size() >= inliers.size()) {
        best = refit;
        inliers = std::move(refit_inliers);
      }
    }
  }
  result.T_camera_world = best;
  result.inliers = std::move(inliers);
  result.ok = result.inliers.size() >= 3 && best.matrix().allFinite();
  return result;
}

}  // namespace slam
}  // namespace cge
