#pragma once
// RGB-D pose RANSAC: a camera pose from map points matched to keypoints, with hypotheses from three
// 3-D / 3-D pairs (the keypoint's back-projected depth against its map point) instead of PnP on
// pixels. Three pairs fix a rigid motion in closed form (the least-squares fit of Arun, Huang and
// Blostein 1987 with Umeyama's reflection fix), so a hypothesis costs a 3 x 3 SVD and the scoring;
// a sample of three is all-inlier far more often than EPnP's five, so fewer samples reach the same
// confidence. Every hypothesis is scored by the reprojection error of every pair, with or without
// depth, so the consensus is the same as a PnP RANSAC's: the largest set of matches that one rigid
// camera motion explains (on walking scenes without masks, the static background rather than a
// person who fills part of the view). Deterministic: samples come from a seeded splitmix64.

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {
namespace slam {

struct RigidPoseRansacSettings {
  /// Samples drawn at most, count >= 1 (fewer once the confidence is reached).
  int max_iterations = 100;
  /// Inlier threshold: reprojection error in pixels, > 0.
  double reprojection_px = 3.0;
  /// Stop once the chance that every sample drawn so far held an outlier, given the best inlier
  /// fraction among the pairs with depth, is below 1 - confidence; in (0, 1).
  double confidence = 0.99;
  /// Seed of the sample stream (the same input and seed give the same pose bit for bit).
  std::uint64_t seed = 0x5EEDC0DE;
  /// Three points closer to a line than this are not sampled: the triangle's area must exceed
  /// (min_triangle_side_m)^2 / 2, metres. Guards the SVD against a near-degenerate fit.
  double min_triangle_side_m = 0.01;
  /// The refit of the best hypothesis uses its inliers with depth whose 3-D residual
  /// |x_camera - T X| is at most refit_tolerance_m + refit_tolerance_per_m * z^2 (z: the
  /// keypoint's depth, metres): three standard deviations of Kinect-like depth noise 0.003 z^2
  /// (TrackerSettings' refinement default) plus 5 mm. Ours. Without the gate (every inlier with
  /// depth) one of the nine start offsets of the real fr1/rpy slice drifted to 47.6 mm in mode YMK
  /// (24.4 with EPnP; docs/REAL_DATA.md).
  double refit_tolerance_m = 0.005;        ///< metres, >= 0
  double refit_tolerance_per_m = 0.009;    ///< 1/m, >= 0

  /// Throws std::invalid_argument naming the first bad value.
  void validate() const;
};

struct RigidPoseRansacResult {
  /// A hypothesis with at least three inliers was found and its pose is finite.
  bool ok = false;
  /// Maps world points into the camera: x_camera = T_camera_world * X (valid when ok).
  Eigen::Isometry3d T_camera_world = Eigen::Isometry3d::Identity();
  /// Indices of the inlier pairs (ascending) under T_camera_world.
  std::vector<int> inliers;
  /// Samples drawn (degenerate ones included).
  int iterations = 0;
};

/// The rigid motion T minimising sum |q_i - T p_i|^2 over the pairs (p_i world, q_i camera),
/// without scale, a proper rotation (det +1): cge::metrics::align_rigid, the fit the ATE alignment
/// uses, restricted to at least three pairs. Not collinear; the result is unspecified (but finite)
/// for collinear ones. Throws std::invalid_argument for fewer than three pairs, lists of different
/// sizes or a non-finite point.
Eigen::Isometry3d fit_rigid_motion(const std::vector<Eigen::Vector3d>& points_world,
                                   const std::vector<Eigen::Vector3d>& points_camera);

/// RANSAC over pairs i of points_world[i] (a map point, metres) and pixels_px[i] (its matched
/// keypoint, undistorted pixels); points_camera_m[i] is the keypoint back-projected with its depth,
/// or non-finite when it has none (then the pair is scored but never sampled). The three vectors
/// have one size. After the samples, the best hypothesis is refitted in 3-D to its inliers with
/// depth (within the refit tolerance) and the refit kept when it explains at least as many pairs.
/// Throws std::invalid_argument for vectors of different sizes or invalid settings.
RigidPoseRansacResult solve_rigid_pose_ransac(const std::vector<Eigen::Vector3d>& points_world,
                                              const std::vector<Eigen::Vector2d>& pixels_px,
                                              const std::vector<Eigen::Vector3d>& points_camera_m,
                                              const PinholeIntrinsics<double>& camera,
                                              const RigidPoseRansacSettings& settings);

}  // namespace slam
}  // namespace cge
