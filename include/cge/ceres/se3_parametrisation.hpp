#pragma once
// SE(3) parameter blocks for Ceres: a rigid transform is stored as a unit quaternion (Eigen's
// memory order x, y, z, w) on Ceres' EigenQuaternionManifold (3-dof rotation increments, so the
// normal equations stay well conditioned) and a separate translation block. Also the validation of
// rigid transforms that every optimiser applies to its input.
#include "cge/ceres/ceres_headers.hpp"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cge {

/// Maximum deviation of R^T R from the identity (entry-wise) accepted for a rotation, dimensionless.
inline constexpr double kRotationOrthonormalityTolerance = 1e-6;

/// Throws std::invalid_argument("<what> ...") unless T is finite with an orthonormal, right-handed
/// rotation part (within kRotationOrthonormalityTolerance).
inline void validate_rigid_transform(const Eigen::Isometry3d& T, const std::string& what) {
  if (!T.matrix().allFinite()) throw std::invalid_argument(what + " has non-finite entries");
  const Eigen::Matrix3d R = T.linear();
  const double deviation = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(deviation <= kRotationOrthonormalityTolerance) || R.determinant() <= 0)
    throw std::invalid_argument(what + " is not a rigid transform (rotation part not orthonormal)");
}

/// A rigid transform as two Ceres parameter blocks.
struct SE3Block {
  std::array<double, 4> q_xyzw{0, 0, 0, 1};  ///< unit quaternion, Eigen memory order
  std::array<double, 3> t{0, 0, 0};          ///< translation

  static SE3Block from_isometry(const Eigen::Isometry3d& T) {
    SE3Block b;
    Eigen::Quaterniond q(Eigen::Matrix3d(T.linear()));
    q.normalize();
    b.q_xyzw = {q.x(), q.y(), q.z(), q.w()};
    b.t = {T.translation().x(), T.translation().y(), T.translation().z()};
    return b;
  }

  Eigen::Isometry3d to_isometry() const {
    Eigen::Quaterniond q(q_xyzw[3], q_xyzw[0], q_xyzw[1], q_xyzw[2]);
    q.normalize();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.toRotationMatrix();
    T.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    return T;
  }

  /// Adds both blocks to `problem` (the quaternion on an EigenQuaternionManifold the problem owns);
  /// `constant` holds them fixed.
  void add_to(ceres::Problem& problem, bool constant = false) {
    problem.AddParameterBlock(q_xyzw.data(), 4, new ceres::EigenQuaternionManifold);
    problem.AddParameterBlock(t.data(), 3);
    if (constant) {
      problem.SetParameterBlockConstant(q_xyzw.data());
      problem.SetParameterBlockConstant(t.data());
    }
  }
};

}  // namespace cge
