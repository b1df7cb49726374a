#pragma once
// Reprojection residuals for Ceres autodiff. The pose is T_camera_world (p_camera = q * p_world + t,
// see se3_parametrisation.hpp): its Jacobians are simpler and better conditioned than those of
// T_world_camera for this residual. The residual is whitened: (projected - observed) / sigma_px, so
// its squared norm is the chi-square statistic of the observation (2 dof) and a robust loss on it
// acts in units of sigma.
#include "cge/ceres/ceres_headers.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {

/// Whitened reprojection residual of a world point through T_camera_world; false when the point is
/// not in front of the camera (depth <= min_depth_m), which makes Ceres reject the step.
template <typename T>
bool whitened_reprojection_residual(const PinholeIntrinsics<double>& intrinsics, const Eigen::Vector2d& pixel_px,
                                    double inv_sigma, double min_depth_m, const T* q_camera_world,
                                    const T* t_camera_world, const T* point_world, T* residual) {
  const Eigen::Map<const Eigen::Quaternion<T>> q(q_camera_world);
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_camera_world);
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_world(point_world);
  const Eigen::Matrix<T, 3, 1> p = q * p_world + t;
  if (!(p.z() > T(min_depth_m))) return false;
  const T u = T(intrinsics.fx_px) * p.x() / p.z() + T(intrinsics.cx_px);
  const T v = T(intrinsics.fy_px) * p.y() / p.z() + T(intrinsics.cy_px);
  residual[0] = (u - T(pixel_px.x())) * T(inv_sigma);
  residual[1] = (v - T(pixel_px.y())) * T(inv_sigma);
  return true;
}

/// Motion-only residual: the world point is a constant. Parameters: q_camera_world[4], t_camera_world[3].
struct PoseOnlyReprojectionCost {
  PinholeIntrinsics<double> intrinsics;
  Eigen::Vector3d point_world_m;
  Eigen::Vector2d pixel_px;
  double inv_sigma = 1;    ///< 1 / sigma_px
  double min_depth_m = 0;  ///< points at or behind this depth are invalid

  template <typename T>
  bool operator()(const T* q_camera_world, const T* t_camera_world, T* residual) const {
    const T p[3] = {T(point_world_m.x()), T(point_world_m.y()), T(point_world_m.z())};
    return whitened_reprojection_residual(intrinsics, pixel_px, inv_sigma, min_depth_m, q_camera_world, t_camera_world,
                                          p, residual);
  }

  static ceres::CostFunction* create(const PoseOnlyReprojectionCost& cost) {
    return new ceres::AutoDiffCostFunction<PoseOnlyReprojectionCost, 2, 4, 3>(new PoseOnlyReprojectionCost(cost));
  }
};

/// Full residual (bundle adjustment). Parameters: q_camera_world[4], t_camera_world[3], point_world[3].
struct ReprojectionCost {
  PinholeIntrinsics<double> intrinsics;
  Eigen::Vector2d pixel_px;
  double inv_sigma = 1;    ///< 1 / sigma_px
  double min_depth_m = 0;  ///< points at or behind this depth are invalid

  template <typename T>
  bool operator()(const T* q_camera_world, const T* t_camera_world, const T* point_world, T* residual) const {
    return whitened_reprojection_residual(intrinsics, pixel_px, inv_sigma, min_depth_m, q_camera_world, t_camera_world,
                                          point_world, residual);
  }

  static ceres::CostFunction* create(const ReprojectionCost& cost) {
    return new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 4, 3, 3>(new ReprojectionCost(cost));
  }
};

/// Chi-square (squared whitened error) of an observation for a pose T_camera_world, in double;
/// `in_front` reports whether the point lies deeper than min_depth_m.
inline double reprojection_chi2(const PinholeIntrinsics<double>& intrinsics, const Eigen::Isometry3d& T_camera_world,
                                const Eigen::Vector3d& point_world_m, const Eigen::Vector2d& pixel_px, double sigma_px,
                                double min_depth_m, bool& in_front) {
  const Eigen::Vector3d p = T_camera_world * point_world_m;
  in_front = p.z() > min_depth_m;
  if (!in_front) return 0;
  const Eigen::Vector2d e = (intrinsics.project(p) - pixel_px) / sigma_px;
  return e.squaredNorm();
}

}  // namespace cge
