#pragma once
// Synthetic scenes shared by the Ceres adapter tests: random points in front of known cameras,
// random rigid transforms and perturbations, all from a caller-seeded engine.
#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "cge/ceres/solver_settings.hpp"
#include "cge/core/pinhole_intrinsics.hpp"

namespace cge_test {

inline double uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

/// A rotation by a random axis and the given angle (radians) composed with a translation of the given length.
inline Eigen::Isometry3d random_motion(std::mt19937& rng, double angle_rad, double translation_m) {
  Eigen::Vector3d axis(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
  axis.normalize();
  Eigen::Vector3d dir(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
  dir.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, axis).toRotationMatrix();
  T.translation() = translation_m * dir;
  return T;
}

/// Any pose: random rotation (angle up to pi) and translation up to 2 m.
inline Eigen::Isometry3d random_pose(std::mt19937& rng) {
  return random_motion(rng, uniform(rng, 0, 3.1), uniform(rng, 0, 2));
}

/// A world point seen by T_world_camera inside the image (640 x 480 for the default intrinsics),
/// at depth 1..6 m.
inline Eigen::Vector3d random_visible_point(std::mt19937& rng, const cge::PinholeIntrinsics<double>& K,
                                            const Eigen::Isometry3d& T_world_camera) {
  const double u = uniform(rng, 10, 630), v = uniform(rng, 10, 470), z = uniform(rng, 1, 6);
  return T_world_camera * K.backproject(u, v, z);
}

inline double rotation_error_rad(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
  return Eigen::AngleAxisd(Eigen::Matrix3d(A.linear().transpose() * B.linear())).angle();
}

inline double translation_error_m(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
  return (A.translation() - B.translation()).norm();
}

inline bool bit_identical(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      if (std::memcmp(&A.matrix()(r, c), &B.matrix()(r, c), sizeof(double)) != 0) return false;
  return true;
}

/// T moved by +-h along tangent direction a of the optimisers' increment: a < 3 rotates about
/// axis a, left-multiplied (Exp(h e_a) R); a >= 3 adds h to translation coordinate a - 3.
inline Eigen::Isometry3d tangent_step(const Eigen::Isometry3d& T, int a, double h) {
  Eigen::Isometry3d moved = T;
  if (a < 3) {
    moved.linear() = Eigen::AngleAxisd(h, Eigen::Vector3d::Unit(a)).toRotationMatrix() * T.linear();
  } else {
    moved.translation()(a - 3) += h;
  }
  return moved;
}

/// Solver settings tight enough that a solve ends at the optimum to rounding, not at a tolerance.
inline cge::CeresSolverSettings tight(int iterations) {
  cge::CeresSolverSettings solver;
  solver.max_iterations = iterations;
  solver.function_tolerance = 1e-14;
  solver.gradient_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-14;
  return solver;
}

}  // namespace cge_test
