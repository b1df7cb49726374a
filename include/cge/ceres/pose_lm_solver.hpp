#pragma once
// PoseLMSolver: the pose refiner's own backend (PoseRefinementSettings::backend = pose_lm), a
// Levenberg-Marquardt solver for one camera pose against fixed world points, each observed as a
// whitened pixel (and, with a measured depth, a whitened depth row): the residual of
// rgbd_reprojection_cost.hpp. The normal equations are one 6x6 system per iteration; what it saves
// against Ceres is the general machinery per residual block (automatic differentiation, program
// evaluation, the quaternion manifold), most of a tracking refinement's time (docs/OPTIMISATION.md).
// It calls no Ceres code.
//
// The problem and the cost are the Ceres backend's (pose_refinement.hpp): cost = 0.5 * sum of
// rho(|r|^2), rho the Huber loss of width delta on the whitened residual norm (or none); a point at
// or closer than min_depth_m in the camera makes a step invalid (rejected, more damping). The
// increment, the robust weighting, the damping and the stopping rules are SchurLMSolver's
// (schur_lm_solver.hpp), which documents how they differ from Ceres': T_camera_world <-
// (Exp(omega) R, t + tau); each observation weighted by rho'(|r|^2) (as g2o, ORB-SLAM2's
// optimiser); (H + diag(H) / radius) with Ceres' radius schedule; stop on the gradient, step or
// cost-change tolerance of CeresSolverSettings, or after max_iterations accepted or rejected steps.
// Deterministic: one thread, a fixed order of every sum.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "cge/ceres/rgbd_reprojection_cost.hpp"
#include "cge/ceres/schur_lm_solver.hpp"
#include "cge/ceres/se3_parametrisation.hpp"
#include "cge/ceres/solver_settings.hpp"
#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {

/// One whitened residual block of a pose-only problem: a fixed world point seen at a pixel, with
/// a depth row when inv_sigma_depth != 0 (0: pixel only, the row is 0).
struct PoseLMObservation {
  Eigen::Vector3d point_world_m = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();
  double inv_sigma_px = 1.0;
  double depth_m = 0.0;
  double inv_sigma_depth = 0.0;
};

class PoseLMSolver {
 public:
  /// `huber_delta` <= 0: no robust loss.
  PoseLMSolver(const PinholeIntrinsics<double>& intrinsics, const CeresSolverSettings& solver, double huber_delta,
               double min_depth_m)
      : K_(intrinsics), solver_(solver), huber_delta_(huber_delta), min_depth_m_(min_depth_m) {}

  /// Minimises over `pose` (T_camera_world) in place, for at most `max_iterations` (>= 1)
  /// iterations. Returns failure without touching the pose when the start has a point at or
  /// behind min_depth_m. The summary's termination and costs mean what SchurLMSolver's do.
  SchurLMSummary solve(SE3Block& pose, const std::vector<PoseLMObservation>& observations, int max_iterations) const;

 private:
  /// Cost at (R, t); false when a point is at or behind min_depth_m.
  bool cost(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const std::vector<PoseLMObservation>& observations,
            double* total) const {
    double sum = 0;
    for (const PoseLMObservation& o : observations) {
      const Eigen::Vector3d p = R * o.point_world_m + t;
      if (!(p.z() > min_depth_m_)) return false;
      sum += schur_lm_detail::huber_rho(
          rgbd_whitened_residual(K_, o.pixel_px, o.inv_sigma_px, o.depth_m, o.inv_sigma_depth, p).squaredNorm(),
          huber_delta_);
    }
    *total = 0.5 * sum;
    return true;
  }

  PinholeIntrinsics<double> K_;
  CeresSolverSettings solver_;
  double huber_delta_;
  double min_depth_m_;
};

inline SchurLMSummary PoseLMSolver::solve(SE3Block& pose, const std::vector<PoseLMObservation>& observations,
                                          int max_iterations) const {
  using schur_lm_detail::clamp_diagonal;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  SchurLMSummary summary;
  Eigen::Matrix3d R = schur_lm_detail::rotation_of(pose);
  Eigen::Vector3d t(pose.t[0], pose.t[1], pose.t[2]);
  double current_cost = 0;
  if (!cost(R, t, observations, &current_cost)) return summary;  // failure: invalid start
  summary.initial_cost = summary.final_cost = current_cost;
  if (observations.empty()) {
    summary.termination = SchurLMSummary::Termination::converged;
    return summary;
  }

  Mat6 H;
  Vec6 g;
  const auto linearise = [&]() {
    H.setZero();
    g.setZero();
    for (const PoseLMObservation& o : observations) {
      const Eigen::Vector3d p_rot = R * o.point_world_m;
      Eigen::Matrix3d J_p;  // d r / d p, whitened
      const Eigen::Vector3d r =
          rgbd_whitened_residual(K_, o.pixel_px, o.inv_sigma_px, o.depth_m, o.inv_sigma_depth, p_rot + t, &J_p);
      const double w = schur_lm_detail::huber_weight(r.squaredNorm(), huber_delta_);
      Eigen::Matrix<double, 3, 6> J;  // d r / d (omega, tau): dp/domega = -[R X]x, dp/dtau = I
      J.leftCols<3>().noalias() = -J_p * schur_lm_detail::hat(p_rot);
      J.rightCols<3>() = J_p;
      H.noalias() += w * J.transpose() * J;
      g.noalias() += w * J.transpose() * r;
    }
  };
  const auto parameter_norm = [&]() {
    double s = 0;
    for (double v : pose.q_xyzw) s += v * v;
    for (double v : pose.t) s += v * v;
    return std::sqrt(s);
  };

  linearise();
  if (g.cwiseAbs().maxCoeff() <= solver_.gradient_tolerance) {
    summary.termination = SchurLMSummary::Termination::converged;
    return summary;
  }

  schur_lm_detail::TrustRegion region;
  summary.termination = SchurLMSummary::Termination::iteration_limit;
  while (summary.iterations < max_iterations) {
    ++summary.iterations;
    const double lambda = region.damping();
    Mat6 A = H;
    for (int a = 0; a < 6; ++a) A(a, a) += lambda * clamp_diagonal(H(a, a));
    const Eigen::LLT<Mat6> llt(A);
    if (llt.info() != Eigen::Success) {
      region.shrink();
      continue;
    }
    const Vec6 d = llt.solve(-g);
    double damping = 0;
    for (int a = 0; a < 6; ++a) damping += clamp_diagonal(H(a, a)) * d(a) * d(a);
    const double model_decrease = 0.5 * (-g.dot(d) + lambda * damping);
    if (d.norm() <= solver_.parameter_tolerance * (parameter_norm() + solver_.parameter_tolerance)) {
      summary.termination = SchurLMSummary::Termination::converged;
      break;
    }
    SE3Block candidate;
    schur_lm_detail::rotate_left(pose.q_xyzw, d.head<3>(), candidate.q_xyzw);
    for (int a = 0; a < 3; ++a) candidate.t[static_cast<std::size_t>(a)] = t(a) + d(3 + a);
    const Eigen::Matrix3d candidate_R = schur_lm_detail::rotation_of(candidate);
    const Eigen::Vector3d candidate_t(candidate.t[0], candidate.t[1], candidate.t[2]);
    double candidate_cost = std::numeric_limits<double>::infinity();
    const bool valid = cost(candidate_R, candidate_t, observations, &candidate_cost);
    const double cost_change = valid ? current_cost - candidate_cost : -std::numeric_limits<double>::infinity();
    const schur_lm_detail::StepVerdict verdict =
        region.judge(valid, model_decrease, cost_change, current_cost, solver_.function_tolerance);
    if (verdict.accept) {
      pose = candidate;
      R = candidate_R;
      t = candidate_t;
      current_cost = candidate_cost;
      summary.final_cost = current_cost;
    }
    if (verdict.converged) {
      summary.termination = SchurLMSummary::Termination::converged;
      break;
    }
    if (verdict.accept) {
      linearise();
      if (g.cwiseAbs().maxCoeff() <= solver_.gradient_tolerance) {
        summary.termination = SchurLMSummary::Termination::converged;
        break;
      }
    }
  }
  return summary;
}

}  // namespace cge
