#pragma once
// SchurLMSolver: the bundle adjuster's second backend (BundleAdjustmentSettings::backend =
// schur_lm), a Levenberg-Marquardt solver written for the one residual shape of the RGB-D bundle
// adjustment (3 whitened rows: pixel u, v and depth, of one pose and one point). The points are
// eliminated by the Schur complement and the reduced camera system (6 unknowns per free keyframe,
// a few dozen keyframes in a local window) is factorised densely, as Ceres' DENSE_SCHUR does; what
// it saves is Ceres' general machinery per residual block (program evaluation, block-sparse
// bookkeeping, the manifold's plus and Jacobian), most of an iteration's time on a local window
// (docs/OPTIMISATION.md). It calls no Ceres code.
//
// The problem and the cost are the Ceres backend's: cost = 0.5 * sum of rho(|r|^2), rho the Huber
// loss of width delta on the whitened residual norm (or none), a point at or closer than
// min_depth_m in a camera makes a step invalid (rejected, more damping). Differences, by design:
// - Pose increment: T_camera_world <- (Exp(omega) R, t + tau), omega in radians (Ceres' quaternion
//   manifold takes half that angle); the point increment is additive in both.
// - Robust loss as g2o (ORB-SLAM2's optimiser): each observation's rows weighted by rho'(|r|^2) in
//   the normal equations (iteratively reweighted), instead of Ceres' second-order corrector. Both
//   have the same minimum; the iterates differ.
// - Damping as Ceres' LEVENBERG_MARQUARDT strategy: (H + diag(H) / radius) with diag(H) clamped to
//   [1e-6, 1e32], radius 1e4 at the start, shrunk on a rejected step (by 2, 4, 8, ...) and grown
//   on an accepted one by 1 / max(1/3, 1 - (2 rho - 1)^3), rho the ratio of actual to predicted
//   decrease; a step is accepted when rho > 1e-3.
// - Stopping, as CeresSolverSettings says: gradient max-norm <= gradient_tolerance, step norm <=
//   parameter_tolerance * (|x| + parameter_tolerance), |cost change| <= function_tolerance * cost
//   (converged; the step is kept when it lowers the cost), or max_iterations iterations, each
//   accepted or rejected step counting one.
// Deterministic: one thread, a fixed order of every sum.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "cge/ceres/rgbd_reprojection_cost.hpp"
#include "cge/ceres/se3_parametrisation.hpp"
#include "cge/ceres/solver_settings.hpp"
#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {

/// One residual block of the RGB-D bundle adjustment, whitened: pixel rows divided by sigma_px,
/// the depth row (p.z - depth) divided by sigma_depth (inv_sigma_depth 0: pixel only, the row is 0).
struct SchurLMObservation {
  int pose = -1;   ///< index into the poses
  int point = -1;  ///< index into the points
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();
  double inv_sigma_px = 1.0;
  double depth_m = 0.0;
  double inv_sigma_depth = 0.0;
};

struct SchurLMSummary {
  enum class Termination { converged, iteration_limit, failure };
  double initial_cost = 0;  ///< 0.5 * sum of rho(|r|^2) at the start
  double final_cost = 0;    ///< the same at the returned estimate
  int iterations = 0;       ///< accepted plus rejected steps
  Termination termination = Termination::failure;
};

class SchurLMSolver {
 public:
  /// `huber_delta` <= 0: no robust loss.
  SchurLMSolver(const PinholeIntrinsics<double>& intrinsics, const CeresSolverSettings& solver, double huber_delta,
                double min_depth_m)
      : K_(intrinsics), solver_(solver), huber_delta_(huber_delta), min_depth_m_(min_depth_m) {}

  /// Minimises over the poses not marked `fixed` and the points that the observations reference,
  /// in place, for at most `max_iterations` (>= 1) iterations. Poses are T_camera_world. Returns
  /// failure without touching anything when the start has a point at or behind min_depth_m.
  SchurLMSummary solve(std::vector<SE3Block>& poses, const std::vector<bool>& fixed,
                       std::vector<Eigen::Vector3d>& points, const std::vector<SchurLMObservation>& observations,
                       int max_iterations);

 private:
  struct Linearisation;

  /// Cost at the given state; false when a point is at or behind min_depth_m in its camera.
  bool cost(const std::vector<Eigen::Matrix3d>& R, const std::vector<SE3Block>& poses,
            const std::vector<Eigen::Vector3d>& points, const std::vector<SchurLMObservation>& observations,
            double* total) const;
  /// Residual of one observation at p = R X + t (camera frame), and d r / d p when J_p is given.
  Eigen::Vector3d residual(const SchurLMObservation& o, const Eigen::Vector3d& p,
                           Eigen::Matrix3d* J_p = nullptr) const {
    return rgbd_whitened_residual(K_, o.pixel_px, o.inv_sigma_px, o.depth_m, o.inv_sigma_depth, p, J_p);
  }
  /// rho(s) and rho'(s) of the squared residual norm s (Huber, or the identity without one).
  double rho(double s) const;
  double rho_prime(double s) const;

  PinholeIntrinsics<double> K_;
  CeresSolverSettings solver_;
  double huber_delta_;
  double min_depth_m_;
};

// ---------------------------------------------------------------------------------------------

namespace schur_lm_detail {

inline Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(),  //
      v.z(), 0.0, -v.x(),   //
      -v.y(), v.x(), 0.0;
  return m;
}

inline Eigen::Matrix3d rotation_of(const SE3Block& b) {
  return Eigen::Quaterniond(b.q_xyzw[3], b.q_xyzw[0], b.q_xyzw[1], b.q_xyzw[2]).normalized().toRotationMatrix();
}

/// Exp(omega) * q, normalised, into `out` (xyzw).
inline void rotate_left(const std::array<double, 4>& q_xyzw, const Eigen::Vector3d& omega,
                        std::array<double, 4>& out) {
  const double angle = omega.norm();
  Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
  if (angle > 0) dq = Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle));
  Eigen::Quaterniond q = dq * Eigen::Quaterniond(q_xyzw[3], q_xyzw[0], q_xyzw[1], q_xyzw[2]);
  q.normalize();
  out = {q.x(), q.y(), q.z(), q.w()};
}

/// Diagonal of the LM regulariser: diag(H) clamped as Ceres clamps it.
inline double clamp_diagonal(double d) { return std::min(std::max(d, 1e-6), 1e32); }

/// rho(s) of the squared residual norm s: Huber of width delta, or s itself when delta <= 0.
inline double huber_rho(double s, double delta) {
  if (delta <= 0 || s <= delta * delta) return s;
  return 2.0 * delta * std::sqrt(s) - delta * delta;
}
/// rho'(s): the weight of an observation's rows in the normal equations (g2o's robust weighting).
inline double huber_weight(double s, double delta) {
  if (delta <= 0 || s <= delta * delta) return 1.0;
  return delta / std::sqrt(s);
}

/// What a solver does with a candidate step (TrustRegion::judge).
struct StepVerdict {
  bool accept = false;     ///< the candidate becomes the estimate
  bool converged = false;  ///< stop: the cost-change tolerance is reached, or no step can lower the cost
};

/// Ceres' LEVENBERG_MARQUARDT trust region: the damping 1 / radius, its schedule and the step test
/// (SchurLMSolver and PoseLMSolver share it).
struct TrustRegion {
  double radius = 1e4;
  double decrease_factor = 2.0;

  double damping() const { return 1.0 / radius; }

  /// Judges a candidate step and updates the radius. `valid`: the candidate's cost could be
  /// evaluated (no point at or behind min_depth_m); `cost_change` = current cost - candidate's.
  /// Accepted when the cost fell by more than 1e-3 of the model's decrease (the radius grows), or
  /// fell at all within the cost-change tolerance |change| <= function_tolerance * cost, which also
  /// converges, as a rejected step within it does; any other rejection shrinks the radius, and
  /// converges when it falls under Ceres' min_trust_region_radius.
  StepVerdict judge(bool valid, double model_decrease, double cost_change, double current_cost,
                    double function_tolerance) {
    StepVerdict v;
    const bool tolerance_reached = valid && std::abs(cost_change) <= function_tolerance * current_cost;
    const bool successful = valid && model_decrease > 0 && cost_change / model_decrease > 1e-3;
    v.accept = successful || (tolerance_reached && cost_change > 0);
    if (tolerance_reached) {
      v.converged = true;
    } else if (v.accept) {
      grow(model_decrease > 0 ? cost_change / model_decrease : 0.0);
    } else {
      v.converged = !shrink();
    }
    return v;
  }

  /// After a rejected step (or a failed factorisation). False when the radius fell under Ceres'
  /// min_trust_region_radius: no step can lower the cost.
  bool shrink() {
    radius /= decrease_factor;
    decrease_factor *= 2.0;
    return radius >= 1e-32;
  }

 private:
  /// After an accepted step with gain ratio `ratio` (actual / predicted decrease).
  void grow(double ratio) {
    const double t = 2.0 * ratio - 1.0;
    radius = std::min(1e16, radius / std::max(1.0 / 3.0, 1.0 - t * t * t));
    decrease_factor = 2.0;
  }
};

}  // namespace schur_lm_detail

inline double SchurLMSolver::rho(double s) const { return schur_lm_detail::huber_rho(s, huber_delta_); }
inline double SchurLMSolver::rho_prime(double s) const { return schur_lm_detail::huber_weight(s, huber_delta_); }

/// The normal equations at one state: per free pose U (6x6), per point V (3x3), per observation
/// with a free pose W = J_pose^T w J_point (6x3), and the gradient.
struct SchurLMSolver::Linearisation {
  std::vector<Eigen::Matrix<double, 6, 6>> U;
  std::vector<Eigen::Matrix<double, 6, 1>> g_pose;
  std::vector<Eigen::Matrix3d> V;
  std::vector<Eigen::Vector3d> g_point;
  std::vector<Eigen::Matrix<double, 6, 3>> W;  ///< per observation (unused when its pose is fixed)
};

inline bool SchurLMSolver::cost(const std::vector<Eigen::Matrix3d>& R, const std::vector<SE3Block>& poses,
                                const std::vector<Eigen::Vector3d>& points,
                                const std::vector<SchurLMObservation>& observations, double* total) const {
  double sum = 0;
  for (const SchurLMObservation& o : observations) {
    const SE3Block& b = poses[static_cast<std::size_t>(o.pose)];
    const Eigen::Vector3d p =
        R[static_cast<std::size_t>(o.pose)] * points[static_cast<std::size_t>(o.point)] +
        Eigen::Vector3d(b.t[0], b.t[1], b.t[2]);
    if (!(p.z() > min_depth_m_)) return false;
    sum += rho(residual(o, p).squaredNorm());
  }
  *total = 0.5 * sum;
  return true;
}

inline SchurLMSummary SchurLMSolver::solve(std::vector<SE3Block>& poses, const std::vector<bool>& fixed,
                                           std::vector<Eigen::Vector3d>& points,
                                           const std::vector<SchurLMObservation>& observations,
                                           int max_iterations) {
  using schur_lm_detail::clamp_diagonal;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat63 = Eigen::Matrix<double, 6, 3>;
  SchurLMSummary summary;
  const std::size_t n_poses = poses.size(), n_points = points.size(), n_obs = observations.size();

  // Unknowns: the free poses and the points that some observation references, in index order.
  std::vector<int> pose_slot(n_poses, -1), point_slot(n_points, -1);
  std::vector<int> free_poses, used_points;
  for (const SchurLMObservation& o : observations) {
    if (!fixed[static_cast<std::size_t>(o.pose)]) pose_slot[static_cast<std::size_t>(o.pose)] = 0;
    point_slot[static_cast<std::size_t>(o.point)] = 0;
  }
  for (std::size_t i = 0; i < n_poses; ++i)
    if (pose_slot[i] == 0) {
      pose_slot[i] = static_cast<int>(free_poses.size());
      free_poses.push_back(static_cast<int>(i));
    }
  for (std::size_t j = 0; j < n_points; ++j)
    if (point_slot[j] == 0) {
      point_slot[j] = static_cast<int>(used_points.size());
      used_points.push_back(static_cast<int>(j));
    }
  const int nc = static_cast<int>(free_poses.size()), np = static_cast<int>(used_points.size());
  // Observations grouped by point (counting sort, stable: each point's in input order).
  std::vector<int> point_begin(static_cast<std::size_t>(np) + 1, 0), by_point(n_obs);
  for (const SchurLMObservation& o : observations) ++point_begin[static_cast<std::size_t>(point_slot[o.point]) + 1];
  for (int j = 0; j < np; ++j) point_begin[j + 1] += point_begin[j];
  {
    std::vector<int> fill(point_begin.begin(), point_begin.end() - 1);
    for (std::size_t k = 0; k < n_obs; ++k)
      by_point[static_cast<std::size_t>(fill[static_cast<std::size_t>(point_slot[observations[k].point])]++)] =
          static_cast<int>(k);
  }

  std::vector<Eigen::Matrix3d> R(n_poses);
  for (std::size_t i = 0; i < n_poses; ++i) R[i] = schur_lm_detail::rotation_of(poses[i]);
  double current_cost = 0;
  if (!cost(R, poses, points, observations, &current_cost)) return summary;  // failure: invalid start
  summary.initial_cost = summary.final_cost = current_cost;
  if (n_obs == 0 || (nc == 0 && np == 0)) {
    summary.termination = SchurLMSummary::Termination::converged;
    return summary;
  }

  Linearisation lin;
  lin.U.resize(static_cast<std::size_t>(nc));
  lin.g_pose.resize(static_cast<std::size_t>(nc));
  lin.V.resize(static_cast<std::size_t>(np));
  lin.g_point.resize(static_cast<std::size_t>(np));
  lin.W.resize(n_obs);
  const auto linearise = [&]() {
    for (auto& m : lin.U) m.setZero();
    for (auto& v : lin.g_pose) v.setZero();
    for (auto& m : lin.V) m.setZero();
    for (auto& v : lin.g_point) v.setZero();
    for (std::size_t k = 0; k < n_obs; ++k) {
      const SchurLMObservation& o = observations[k];
      const std::size_t i = static_cast<std::size_t>(o.pose);
      const Eigen::Vector3d p_rot = R[i] * points[static_cast<std::size_t>(o.point)];
      const Eigen::Vector3d p = p_rot + Eigen::Vector3d(poses[i].t[0], poses[i].t[1], poses[i].t[2]);
      Eigen::Matrix3d J_p;  // d r / d p, whitened
      const Eigen::Vector3d r = residual(o, p, &J_p);
      const double w = rho_prime(r.squaredNorm());
      const Eigen::Matrix3d J_X = J_p * R[i];
      const int j = point_slot[o.point];
      lin.V[static_cast<std::size_t>(j)].noalias() += w * J_X.transpose() * J_X;
      lin.g_point[static_cast<std::size_t>(j)].noalias() += w * J_X.transpose() * r;
      const int c = pose_slot[i];
      if (c < 0) continue;
      Eigen::Matrix<double, 3, 6> J_c;  // d r / d (omega, tau): dp/domega = -[R X]x, dp/dtau = I
      J_c.leftCols<3>().noalias() = -J_p * schur_lm_detail::hat(p_rot);
      J_c.rightCols<3>() = J_p;
      lin.U[static_cast<std::size_t>(c)].noalias() += w * J_c.transpose() * J_c;
      lin.g_pose[static_cast<std::size_t>(c)].noalias() += w * J_c.transpose() * r;
      lin.W[k].noalias() = w * J_c.transpose() * J_X;
    }
  };
  const auto gradient_max_norm = [&]() {
    double m = 0;
    for (const Vec6& g : lin.g_pose) m = std::max(m, g.cwiseAbs().maxCoeff());
    for (const Eigen::Vector3d& g : lin.g_point) m = std::max(m, g.cwiseAbs().maxCoeff());
    return m;
  };
  const auto parameter_norm = [&]() {
    double s = 0;
    for (const int i : free_poses) {
      const SE3Block& b = poses[static_cast<std::size_t>(i)];
      for (double v : b.q_xyzw) s += v * v;
      for (double v : b.t) s += v * v;
    }
    for (const int j : used_points) s += points[static_cast<std::size_t>(j)].squaredNorm();
    return std::sqrt(s);
  };

  linearise();
  if (gradient_max_norm() <= solver_.gradient_tolerance) {
    summary.termination = SchurLMSummary::Termination::converged;
    return summary;
  }

  schur_lm_detail::TrustRegion region;
  const int dim = 6 * nc;
  Eigen::MatrixXd S(dim, dim);
  Eigen::VectorXd rhs(dim), d_pose(dim);
  std::vector<Eigen::Vector3d> d_point(static_cast<std::size_t>(np));
  std::vector<Eigen::Matrix3d> V_inv(static_cast<std::size_t>(np));
  std::vector<Mat63> Y;  // W V^-1 of one point's observations
  std::vector<SE3Block> candidate_poses = poses;
  std::vector<Eigen::Vector3d> candidate_points = points;
  std::vector<Eigen::Matrix3d> candidate_R = R;
  summary.termination = SchurLMSummary::Termination::iteration_limit;

  while (summary.iterations < max_iterations) {
    ++summary.iterations;
    const double lambda = region.damping();
    // Reduced camera system S d_pose = rhs; (U + D) d_pose + W d_point = -g_pose,
    // W^T d_pose + (V + D) d_point = -g_point.
    S.setZero();
    rhs.setZero();
    bool factorised = true;
    for (int c = 0; c < nc; ++c) {
      Mat6 U = lin.U[static_cast<std::size_t>(c)];
      for (int a = 0; a < 6; ++a) U(a, a) += lambda * clamp_diagonal(U(a, a));
      S.block<6, 6>(6 * c, 6 * c) = U;
      rhs.segment<6>(6 * c) = -lin.g_pose[static_cast<std::size_t>(c)];
    }
    for (int j = 0; j < np && factorised; ++j) {
      Eigen::Matrix3d V = lin.V[static_cast<std::size_t>(j)];
      for (int a = 0; a < 3; ++a) V(a, a) += lambda * clamp_diagonal(V(a, a));
      const Eigen::LLT<Eigen::Matrix3d> llt(V);
      if (llt.info() != Eigen::Success) {
        factorised = false;
        break;
      }
      Eigen::Matrix3d& Vi = V_inv[static_cast<std::size_t>(j)];
      Vi = llt.solve(Eigen::Matrix3d::Identity());
      const int begin = point_begin[static_cast<std::size_t>(j)], end = point_begin[static_cast<std::size_t>(j) + 1];
      Y.resize(static_cast<std::size_t>(end - begin));
      const Eigen::Vector3d Vi_g = Vi * lin.g_point[static_cast<std::size_t>(j)];
      for (int a = begin; a < end; ++a) {
        const std::size_t ka = static_cast<std::size_t>(by_point[static_cast<std::size_t>(a)]);
        const int ca = pose_slot[observations[ka].pose];
        if (ca < 0) continue;
        Y[static_cast<std::size_t>(a - begin)].noalias() = lin.W[ka] * Vi;
        rhs.segment<6>(6 * ca).noalias() += lin.W[ka] * Vi_g;
      }
      for (int a = begin; a < end; ++a) {
        const std::size_t ka = static_cast<std::size_t>(by_point[static_cast<std::size_t>(a)]);
        const int ca = pose_slot[observations[ka].pose];
        if (ca < 0) continue;
        for (int b = a; b < end; ++b) {
          const std::size_t kb = static_cast<std::size_t>(by_point[static_cast<std::size_t>(b)]);
          const int cb = pose_slot[observations[kb].pose];
          if (cb < 0) continue;
          const Mat6 block = Y[static_cast<std::size_t>(a - begin)] * lin.W[kb].transpose();
          // Upper triangle only (the factorisation reads it); the pair's mirror lands there too.
          if (ca < cb) {
            S.block<6, 6>(6 * ca, 6 * cb) -= block;
          } else if (ca > cb) {
            S.block<6, 6>(6 * cb, 6 * ca) -= block.transpose();
          } else {
            S.block<6, 6>(6 * ca, 6 * ca) -= (a == b) ? block : Mat6(block + block.transpose());
          }
        }
      }
    }
    if (factorised && nc > 0) {
      const Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt(S);
      if (llt.info() != Eigen::Success) {
        factorised = false;
      } else {
        d_pose = llt.solve(rhs);
      }
    }
    if (!factorised) {
      region.shrink();
      continue;
    }
    // Back-substitution for the points, and the step's norm and predicted decrease.
    double step_sq = 0, model_decrease = 0;
    for (int c = 0; c < nc; ++c) {
      const Vec6 d = d_pose.segment<6>(6 * c);
      const Mat6& U = lin.U[static_cast<std::size_t>(c)];
      double damping = 0;
      for (int a = 0; a < 6; ++a) damping += clamp_diagonal(U(a, a)) * d(a) * d(a);
      model_decrease += -lin.g_pose[static_cast<std::size_t>(c)].dot(d) + lambda * damping;
      step_sq += d.squaredNorm();
    }
    for (int j = 0; j < np; ++j) {
      Eigen::Vector3d b = -lin.g_point[static_cast<std::size_t>(j)];
      for (int a = point_begin[static_cast<std::size_t>(j)]; a < point_begin[static_cast<std::size_t>(j) + 1]; ++a) {
        const std::size_t k = static_cast<std::size_t>(by_point[static_cast<std::size_t>(a)]);
        const int c = pose_slot[observations[k].pose];
        if (c >= 0) b.noalias() -= lin.W[k].transpose() * d_pose.segment<6>(6 * c);
      }
      const Eigen::Vector3d d = V_inv[static_cast<std::size_t>(j)] * b;
      d_point[static_cast<std::size_t>(j)] = d;
      const Eigen::Matrix3d& V = lin.V[static_cast<std::size_t>(j)];
      double damping = 0;
      for (int a = 0; a < 3; ++a) damping += clamp_diagonal(V(a, a)) * d(a) * d(a);
      model_decrease += -lin.g_point[static_cast<std::size_t>(j)].dot(d) + lambda * damping;
      step_sq += d.squaredNorm();
    }
    model_decrease *= 0.5;
    const double x_norm = parameter_norm();
    if (std::sqrt(step_sq) <= solver_.parameter_tolerance * (x_norm + solver_.parameter_tolerance)) {
      summary.termination = SchurLMSummary::Termination::converged;
      break;
    }
    // The candidate state.
    for (int c = 0; c < nc; ++c) {
      const std::size_t i = static_cast<std::size_t>(free_poses[static_cast<std::size_t>(c)]);
      const Vec6 d = d_pose.segment<6>(6 * c);
      schur_lm_detail::rotate_left(poses[i].q_xyzw, d.head<3>(), candidate_poses[i].q_xyzw);
      for (int a = 0; a < 3; ++a) candidate_poses[i].t[static_cast<std::size_t>(a)] = poses[i].t[static_cast<std::size_t>(a)] + d(3 + a);
      candidate_R[i] = schur_lm_detail::rotation_of(candidate_poses[i]);
    }
    for (int j = 0; j < np; ++j) {
      const std::size_t x = static_cast<std::size_t>(used_points[static_cast<std::size_t>(j)]);
      candidate_points[x] = points[x] + d_point[static_cast<std::size_t>(j)];
    }
    double candidate_cost = std::numeric_limits<double>::infinity();
    const bool valid = cost(candidate_R, candidate_poses, candidate_points, observations, &candidate_cost);
    const double cost_change = valid ? current_cost - candidate_cost : -std::numeric_limits<double>::infinity();
    const schur_lm_detail::StepVerdict verdict =
        region.judge(valid, model_decrease, cost_change, current_cost, solver_.function_tolerance);
    if (verdict.accept) {
      poses = candidate_poses;
      points = candidate_points;
      R = candidate_R;
      current_cost = candidate_cost;
      summary.final_cost = current_cost;
    }
    if (verdict.converged) {
      summary.termination = SchurLMSummary::Termination::converged;
      break;
    }
    if (verdict.accept) {
      linearise();
      if (gradient_max_norm() <= solver_.gradient_tolerance) {
        summary.termination = SchurLMSummary::Termination::converged;
        break;
      }
    }
  }
  return summary;
}

}  // namespace cge
