#pragma once
// PoseRefiner: motion-only refinement of a camera pose from 3-D world points observed at pixels
// (docs/METHOD.md section 8: the PnP pose refined by minimising the reprojection error with a robust
// loss), in the manner of ORB-SLAM2's PoseOptimization:
//   - each observation's residual is whitened by its sigma_px (e.g. 1.2^octave for ORB), so the
//     squared residual is a chi-square statistic with 2 dof;
//   - `rounds` solves from the current pose; after each, every observation (outliers included, so
//     one can come back) is re-classified: outlier when chi2 > chi2_threshold_2dof or the point is not in
//     front of the camera; outliers are left out of the next round;
//   - the first `robust_rounds` rounds use a Huber loss of width huber_delta (in sigma units, i.e.
//     huber_delta * sigma_px pixels; 0: none), the later ones plain least squares on the inliers;
//   - an observation with a measured depth (RGB-D: the frame's depth at the keypoint) adds the
//     whitened depth residual (predicted z - measured z) / sigma_depth_m, making it a 3-dof chi2
//     (threshold chi2_threshold_3dof). Pixels alone leave a weak mode, a rotation about the scene's
//     centre with the matching sideways translation, that far points barely constrain; the depth
//     of points off the optical axis changes along it (ORB-SLAM2's RGB-D pose optimisation has a
//     depth term too).
// Two backends solve each round (PoseRefinementSettings::backend): cge's own 6x6
// Levenberg-Marquardt (pose_lm_solver.hpp, the default) or Ceres; the same problem, rounds,
// iterations and tolerances, the same minimum, different iterates (pose_lm_solver.hpp says how).
// Internally the pose is T_camera_world (see reprojection_cost.hpp); input and output are
// T_world_camera, metres. Deterministic: one thread, fixed options (solver_settings.hpp).
#include "cge/ceres/ceres_headers.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/ceres/pose_lm_solver.hpp"
#include "cge/ceres/reprojection_cost.hpp"
#include "cge/ceres/robust_rounds.hpp"
#include "cge/ceres/se3_parametrisation.hpp"
#include "cge/ceres/solver_settings.hpp"
#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {

/// One 3-D / 2-D correspondence.
struct PoseObservation {
  Eigen::Vector3d point_world_m = Eigen::Vector3d::Zero();  ///< the map point, world frame, metres
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();       ///< where it is observed, pixels
  double sigma_px = 1.0;  ///< standard deviation of the pixel position, pixels (> 0), e.g. 1.2^octave
  /// Measured depth of the point along the optical axis, metres; NaN = none (pixel-only observation).
  double depth_m = std::numeric_limits<double>::quiet_NaN();
  double sigma_depth_m = 0.0;  ///< depth standard deviation, metres (> 0 when depth_m is given)
};

/// Whitened pixel and depth residuals of a world point through T_camera_world (3 residuals).
struct PoseOnlyReprojectionDepthCost {
  PoseOnlyReprojectionCost pixel;
  double depth_m = 0;
  double inv_sigma_depth = 1;  ///< 1 / sigma_depth_m

  template <typename T>
  bool operator()(const T* q_camera_world, const T* t_camera_world, T* residual) const {
    if (!pixel(q_camera_world, t_camera_world, residual)) return false;
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_camera_world);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_camera_world);
    const Eigen::Matrix<T, 3, 1> p = q * pixel.point_world_m.cast<T>() + t;
    residual[2] = (p.z() - T(depth_m)) * T(inv_sigma_depth);
    return true;
  }

  static ceres::CostFunction* create(const PoseOnlyReprojectionDepthCost& cost) {
    return new ceres::AutoDiffCostFunction<PoseOnlyReprojectionDepthCost, 3, 4, 3>(
        new PoseOnlyReprojectionDepthCost(cost));
  }
};

/// Which solver a pose refinement's rounds run (PoseRefinementSettings::backend).
enum class PoseRefinementBackend { ceres, pose_lm };

/// "ceres" or "pose_lm": the backend's name on the command line and in summary.json.
inline const char* pose_refinement_backend_name(PoseRefinementBackend backend) {
  return backend == PoseRefinementBackend::pose_lm ? "pose_lm" : "ceres";
}

/// The rounds, loss and outlier test (RobustRoundsSettings: ORB-SLAM2's PoseOptimization runs 4
/// rounds, the first 2 with the Huber loss) and the inlier counts that stop the rounds early.
struct PoseRefinementSettings : RobustRoundsSettings {
  /// Fewer valid observations than this: refine() throws (ORB-SLAM2: 3), >= 3.
  int min_observations = 3;
  /// Stop before a round that would have fewer inliers than this (ORB-SLAM2: 10), >= 3.
  int min_inliers_to_continue = 10;
  /// Ceres iterations and tolerances per round (ORB-SLAM2: 10 iterations).
  CeresSolverSettings solver{10, 1e-8, 1e-10, 1e-10};
  /// Who solves each round: cge's own Levenberg-Marquardt (pose_lm_solver.hpp; 6.5-9x less time
  /// per refinement in BM_Ceres_PoseRefinement, the tracking stage 1.4-1.9x faster on the real
  /// slice, docs/REAL_DATA.md item 14) or Ceres.
  PoseRefinementBackend backend = PoseRefinementBackend::pose_lm;

  PoseRefinementSettings() {
    rounds = 4;         // ORB-SLAM2: 4
    robust_rounds = 2;  // ORB-SLAM2: 2
  }

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    const std::string owner = "PoseRefinementSettings";
    validate_rounds(owner);
    if (min_observations < 3) throw std::invalid_argument(owner + ": min_observations must be at least 3");
    if (min_inliers_to_continue < 3)
      throw std::invalid_argument(owner + ": min_inliers_to_continue must be at least 3");
    solver.validate(owner + ".solver");
  }
};

struct PoseRefinementResult {
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  ///< refined pose
  std::vector<bool> inliers;  ///< per observation, classification at the refined pose
  int inlier_count = 0;
  double initial_cost = 0;  ///< Ceres cost (0.5 * sum of robustified chi2) before the first round
  double final_cost = 0;    ///< Ceres cost after the last round (on that round's inliers and loss)
  double final_rms_px = 0;  ///< RMS reprojection error of the inliers at the refined pose, pixels
  int rounds = 0;           ///< rounds solved
  int iterations = 0;       ///< Ceres iterations over all rounds
  bool converged = false;   ///< the last round reached a convergence tolerance (or could not lower the cost at all)
};

class PoseRefiner {
 public:
  PoseRefinementSettings settings;

  PoseRefiner() = default;
  explicit PoseRefiner(const PoseRefinementSettings& s) : settings(s) {}

  /// Refines `T_world_camera_initial` (e.g. from PnP). Throws std::invalid_argument on invalid
  /// settings, intrinsics, pose or observations (naming the index), or fewer than
  /// settings.min_observations observations.
  PoseRefinementResult refine(const PinholeIntrinsics<double>& intrinsics,
                              const std::vector<PoseObservation>& observations,
                              const Eigen::Isometry3d& T_world_camera_initial) const {
    settings.validate();
    validate_input(intrinsics, observations, T_world_camera_initial);

    const std::size_t n = observations.size();
    SE3Block pose = SE3Block::from_isometry(T_world_camera_initial.inverse());
    PoseRefinementResult result;
    result.inliers.assign(n, true);
    // Points not in front of the starting pose cannot enter the first round.
    classify(intrinsics, observations, pose.to_isometry(), /*use_chi2=*/false, result);

    for (int round = 0; round < settings.rounds; ++round) {
      if (result.inlier_count < (round == 0 ? settings.min_observations : settings.min_inliers_to_continue)) {
        if (round == 0)
          throw std::invalid_argument("PoseRefiner: only " + std::to_string(result.inlier_count) +
                                      " observations in front of the initial pose, at least " +
                                      std::to_string(settings.min_observations) + " needed");
        break;
      }
      const RoundOutcome outcome = settings.backend == PoseRefinementBackend::pose_lm
                                       ? solve_round_pose_lm(intrinsics, observations, round, result.inliers, pose)
                                       : solve_round_ceres(intrinsics, observations, round, result.inliers, pose);
      if (round == 0) result.initial_cost = outcome.initial_cost;
      result.final_cost = outcome.final_cost;
      result.iterations += outcome.iterations;
      // A round that starts at a minimum to machine precision can run out of iterations rejecting
      // steps at the rounding floor: no decrease at all counts as converged too.
      result.converged =
          outcome.converged || (outcome.hit_iteration_limit && outcome.final_cost >= outcome.initial_cost);
      result.rounds = round + 1;
      classify(intrinsics, observations, pose.to_isometry(), /*use_chi2=*/true, result);
    }

    result.T_world_camera = pose.to_isometry().inverse();
    double sum_sq = 0;
    const Eigen::Isometry3d T_camera_world = pose.to_isometry();
    for (std::size_t i = 0; i < n; ++i)
      if (result.inliers[i])
        sum_sq += (intrinsics.project(T_camera_world * observations[i].point_world_m) - observations[i].pixel_px)
                      .squaredNorm();
    result.final_rms_px = result.inlier_count > 0 ? std::sqrt(sum_sq / result.inlier_count) : 0.0;
    return result;
  }

 private:
  struct RoundOutcome {
    double initial_cost = 0;
    double final_cost = 0;
    int iterations = 0;
    bool converged = false;            ///< a convergence tolerance was reached
    bool hit_iteration_limit = false;  ///< stopped by the iteration limit
  };

  RoundOutcome solve_round_ceres(const PinholeIntrinsics<double>& intrinsics,
                                 const std::vector<PoseObservation>& observations, int round,
                                 const std::vector<bool>& inliers, SE3Block& pose) const {
    // One loss shared by every residual; it outlives the problem, which does not own it.
    ceres::HuberLoss huber(settings.huber_delta > 0 ? settings.huber_delta : 1.0);  // any width when unused
    ceres::Problem problem(problem_options());
    pose.add_to(problem);
    const bool robust = settings.robust_in_round(round);
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (!inliers[i]) continue;
      const PoseObservation& o = observations[i];
      PoseOnlyReprojectionCost cost{intrinsics, o.point_world_m, o.pixel_px, 1.0 / o.sigma_px, settings.min_depth_m};
      ceres::CostFunction* function =
          std::isnan(o.depth_m) ? PoseOnlyReprojectionCost::create(cost)
                                : PoseOnlyReprojectionDepthCost::create({cost, o.depth_m, 1.0 / o.sigma_depth_m});
      problem.AddResidualBlock(function, robust ? &huber : nullptr, pose.q_xyzw.data(), pose.t.data());
    }
    ceres::Solver::Summary summary;
    ceres::Solve(settings.solver.options(/*sparse=*/false, /*schur=*/false), &problem, &summary);
    RoundOutcome out;
    out.initial_cost = summary.initial_cost;
    out.final_cost = summary.final_cost;
    out.iterations = static_cast<int>(summary.iterations.size()) - 1;
    out.converged = summary.termination_type == ceres::CONVERGENCE;
    out.hit_iteration_limit = summary.termination_type == ceres::NO_CONVERGENCE;
    return out;
  }

  RoundOutcome solve_round_pose_lm(const PinholeIntrinsics<double>& intrinsics,
                                   const std::vector<PoseObservation>& observations, int round,
                                   const std::vector<bool>& inliers, SE3Block& pose) const {
    std::vector<PoseLMObservation> residuals;
    residuals.reserve(observations.size());
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (!inliers[i]) continue;
      const PoseObservation& o = observations[i];
      PoseLMObservation r;
      r.point_world_m = o.point_world_m;
      r.pixel_px = o.pixel_px;
      r.inv_sigma_px = 1.0 / o.sigma_px;
      if (!std::isnan(o.depth_m)) {
        r.depth_m = o.depth_m;
        r.inv_sigma_depth = 1.0 / o.sigma_depth_m;
      }
      residuals.push_back(r);
    }
    const double huber = settings.robust_in_round(round) ? settings.huber_delta : 0.0;
    const PoseLMSolver solver(intrinsics, settings.solver, huber, settings.min_depth_m);
    const SchurLMSummary summary = solver.solve(pose, residuals, settings.solver.max_iterations);
    RoundOutcome out;
    out.initial_cost = summary.initial_cost;
    out.final_cost = summary.final_cost;
    out.iterations = summary.iterations;
    out.converged = summary.termination == SchurLMSummary::Termination::converged;
    out.hit_iteration_limit = summary.termination == SchurLMSummary::Termination::iteration_limit;
    return out;
  }

  void validate_input(const PinholeIntrinsics<double>& K, const std::vector<PoseObservation>& observations,
                      const Eigen::Isometry3d& T_world_camera_initial) const {
    if (!(std::isfinite(K.fx_px) && std::isfinite(K.fy_px) && std::isfinite(K.cx_px) && std::isfinite(K.cy_px) &&
          K.fx_px > 0 && K.fy_px > 0))
      throw std::invalid_argument("PoseRefiner: intrinsics must be finite with positive focal lengths");
    validate_rigid_transform(T_world_camera_initial, "PoseRefiner: T_world_camera_initial");
    if (observations.size() < static_cast<std::size_t>(settings.min_observations))
      throw std::invalid_argument("PoseRefiner: " + std::to_string(observations.size()) + " observations, at least " +
                                  std::to_string(settings.min_observations) + " needed (settings.min_observations)");
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const PoseObservation& o = observations[i];
      const std::string where = "PoseRefiner: observation " + std::to_string(i) + ": ";
      if (!o.point_world_m.allFinite()) throw std::invalid_argument(where + "point_world_m is not finite");
      if (!o.pixel_px.allFinite()) throw std::invalid_argument(where + "pixel_px is not finite");
      if (!(std::isfinite(o.sigma_px) && o.sigma_px > 0))
        throw std::invalid_argument(where + "sigma_px must be finite and positive");
      if (!std::isnan(o.depth_m)) {
        if (!(std::isfinite(o.depth_m) && o.depth_m > 0))
          throw std::invalid_argument(where + "depth_m must be positive and finite, or NaN for none");
        if (!(std::isfinite(o.sigma_depth_m) && o.sigma_depth_m > 0))
          throw std::invalid_argument(where + "sigma_depth_m must be finite and positive when depth_m is given");
      }
    }
  }

  /// Sets inliers / inlier_count at T_camera_world: in front of the camera and, when use_chi2,
  /// chi2 <= chi2_threshold_2dof.
  void classify(const PinholeIntrinsics<double>& K, const std::vector<PoseObservation>& observations,
                const Eigen::Isometry3d& T_camera_world, bool use_chi2, PoseRefinementResult& result) const {
    result.inlier_count = 0;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const PoseObservation& o = observations[i];
      bool in_front = false;
      double chi2 =
          reprojection_chi2(K, T_camera_world, o.point_world_m, o.pixel_px, o.sigma_px, settings.min_depth_m, in_front);
      const bool with_depth = !std::isnan(o.depth_m);
      if (with_depth) {
        const double e = ((T_camera_world * o.point_world_m).z() - o.depth_m) / o.sigma_depth_m;
        chi2 += e * e;
      }
      const bool inlier = in_front && (!use_chi2 || chi2 <= settings.chi2_threshold(with_depth));
      result.inliers[i] = inlier;
      result.inlier_count += inlier ? 1 : 0;
    }
  }
};

}  // namespace cge
