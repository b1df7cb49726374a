#pragma once
// The SE(3) relative-pose residual of a pose-graph edge for Ceres autodiff. Poses are
// T_world_camera blocks (se3_parametrisation.hpp); the edge measures T_a_b. The error transform
//   E = T_a_b_measured^-1 * T_world_a^-1 * T_world_b
// is the identity for a consistent edge; the residual is [2 * vec(q_E); t_E] (rotation first;
// 2 vec(q) equals the rotation vector to first order), multiplied by the upper-triangular square
// root of the 6x6 information matrix, so its squared norm is r^T * information * r.
#include "cge/ceres/ceres_headers.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cge {

struct RelativePoseCost {
  Eigen::Quaterniond q_a_b_measured = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t_a_b_measured = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 6> sqrt_information = Eigen::Matrix<double, 6, 6>::Identity();

  template <typename T>
  bool operator()(const T* q_world_a_ptr, const T* t_world_a_ptr, const T* q_world_b_ptr, const T* t_world_b_ptr,
                  T* residual_ptr) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_world_a(q_world_a_ptr), q_world_b(q_world_b_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_world_a(t_world_a_ptr), t_world_b(t_world_b_ptr);
    const Eigen::Quaternion<T> q_a_world = q_world_a.conjugate();
    // Estimated T_a_b = T_world_a^-1 * T_world_b.
    const Eigen::Quaternion<T> q_a_b = q_a_world * q_world_b;
    const Eigen::Matrix<T, 3, 1> t_a_b = q_a_world * (t_world_b - t_world_a);
    // E = T_a_b_measured^-1 * T_a_b.
    const Eigen::Quaternion<T> q_measured_inverse = q_a_b_measured.conjugate().template cast<T>();
    const Eigen::Quaternion<T> q_error = q_measured_inverse * q_a_b;
    const Eigen::Matrix<T, 3, 1> t_error = q_measured_inverse * (t_a_b - t_a_b_measured.template cast<T>());
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residual_ptr);
    residual.template head<3>() = T(2) * q_error.vec();
    residual.template tail<3>() = t_error;
    residual.applyOnTheLeft(sqrt_information.template cast<T>());
    return true;
  }

  static ceres::CostFunction* create(const RelativePoseCost& cost) {
    return new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 4, 3, 4, 3>(new RelativePoseCost(cost));
  }
};

}  // namespace cge
