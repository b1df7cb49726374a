#pragma once
// BundleAdjuster: global bundle adjustment over keyframe poses and 3-D points (docs/METHOD.md
// section 7.5, after the pose graph), with Ceres. Each observation is a pixel (whitened by its
// sigma_px, 2 dof) and, for RGB-D, optionally the measured depth (whitened by its sigma_depth_m; 3
// dof with the pixel), which also fixes the scale that pixels alone leave free. As ORB-SLAM2's local
// BA: a first round with a Huber loss on the whitened residual, then observations over the chi2
// threshold are left out and a second round runs without the robust loss (settings.rounds,
// robust_rounds). The keyframes in `fixed_keyframes` (at least one, by default the first; it should
// have observations, else it fixes nothing) keep their poses. At the end every observation is
// flagged an outlier when its chi2 exceeds the threshold for its dof or its point is not in front of
// the camera. Poses in and out are
// T_world_camera, metres; internally T_camera_world (reprojection_cost.hpp). Deterministic: one
// thread, fixed options.
#include "cge/ceres/ceres_headers.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/ceres/reprojection_cost.hpp"
#include "cge/ceres/rgbd_reprojection_cost.hpp"
#include "cge/ceres/se3_parametrisation.hpp"
#include "cge/ceres/solver_settings.hpp"
#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {

struct BundleObservation {
  int keyframe = -1;                                   ///< index into the poses
  int point = -1;                                      ///< index into the points
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();  ///< where the keyframe sees the point, pixels
  double sigma_px = 1.0;                               ///< pixel standard deviation, pixels (> 0)
  /// Measured depth along the optical axis, metres; NaN = none (pixel-only observation).
  double depth_m = std::numeric_limits<double>::quiet_NaN();
  double sigma_depth_m = 0.0;  ///< depth standard deviation, metres (> 0 when depth_m is given)
};

// The autodiff pair below is the reference that RgbdReprojectionCost (used by BundleAdjuster) is
// tested against.

/// Whitened depth residual (predicted - measured) / sigma of a world point through T_camera_world.
struct DepthCost {
  double depth_m = 0;
  double inv_sigma = 1;  ///< 1 / sigma_depth_m

  template <typename T>
  bool operator()(const T* q_camera_world, const T* t_camera_world, const T* point_world, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_camera_world);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_camera_world);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_world(point_world);
    const Eigen::Matrix<T, 3, 1> p = q * p_world + t;
    residual[0] = (p.z() - T(depth_m)) * T(inv_sigma);
    return true;
  }
};

/// Pixel and depth residuals of one RGB-D observation (3 residuals).
struct ReprojectionDepthCost {
  ReprojectionCost pixel;
  DepthCost depth;

  template <typename T>
  bool operator()(const T* q_camera_world, const T* t_camera_world, const T* point_world, T* residual) const {
    return pixel(q_camera_world, t_camera_world, point_world, residual) &&
           depth(q_camera_world, t_camera_world, point_world, residual + 2);
  }

  static ceres::CostFunction* create(const ReprojectionDepthCost& cost) {
    return new ceres::AutoDiffCostFunction<ReprojectionDepthCost, 3, 4, 3, 3>(new ReprojectionDepthCost(cost));
  }
};

struct BundleAdjustmentSettings {
  /// Optimise / re-classify rounds: after each but the last, observations over the chi2 threshold
  /// sit out the next round (ORB-SLAM2's local BA: 2; 1 = a single plain solve), >= 1.
  int rounds = 2;
  /// The first this many rounds use the Huber loss, the rest none (ORB-SLAM2's local BA: 1), 0..rounds.
  int robust_rounds = 1;
  /// Huber width on the whitened residual norm, sigma units (ORB-SLAM2: sqrt(5.991)); 0 = none.
  double huber_delta = 2.4477;
  /// Pixel-only observation: outlier when chi2 (2 dof) exceeds this after the solve (95 %: 5.991).
  double chi2_threshold_2dof = 5.991;
  /// Pixel + depth observation: outlier when chi2 (3 dof) exceeds this (95 %: 7.815).
  double chi2_threshold_3dof = 7.815;
  /// A point at or closer than this depth in a camera frame is an outlier there, metres, >= 0.
  double min_depth_m = 1e-6;
  /// Ceres iterations and tolerances; sparse Schur (points eliminated) when Ceres has a sparse library.
  CeresSolverSettings solver{100, 1e-10, 1e-12, 1e-12};
  /// Reduced camera system: sparse (global BA, hundreds of keyframes) or dense Schur (a local
  /// window of a few dozen keyframes, whose reduced system of 6 unknowns per keyframe is small
  /// enough that a dense factorisation beats the sparse set-up).
  bool sparse_schur = true;

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    const auto fail = [](const std::string& what) { throw std::invalid_argument("BundleAdjustmentSettings: " + what); };
    if (rounds < 1) fail("rounds must be at least 1");
    if (robust_rounds < 0 || robust_rounds > rounds) fail("robust_rounds must be in [0, rounds]");
    if (!(std::isfinite(huber_delta) && huber_delta >= 0)) fail("huber_delta must be finite and not negative");
    if (!(std::isfinite(chi2_threshold_2dof) && chi2_threshold_2dof > 0))
      fail("chi2_threshold_2dof must be finite and positive");
    if (!(std::isfinite(chi2_threshold_3dof) && chi2_threshold_3dof > 0))
      fail("chi2_threshold_3dof must be finite and positive");
    if (!(std::isfinite(min_depth_m) && min_depth_m >= 0)) fail("min_depth_m must be finite and not negative");
    solver.validate("BundleAdjustmentSettings.solver");
  }
};

struct BundleAdjustmentResult {
  std::vector<Eigen::Isometry3d> T_world_camera;  ///< optimised poses (fixed ones exactly as given)
  std::vector<Eigen::Vector3d> points_world_m;    ///< optimised points (unobserved ones as given)
  std::vector<bool> outliers;  ///< per observation, at the optimum (also those left out: behind the start pose)
  int outlier_count = 0;
  double initial_cost = 0;  ///< Ceres cost 0.5 * sum of (robustified) chi2 at the start of the first round
  double final_cost = 0;    ///< the same at the end of the last round (on that round's observations)
  double final_rms_px = 0;  ///< RMS pixel error of the inlier observations at the optimum, pixels
  int rounds = 0;           ///< rounds solved
  int iterations = 0;       ///< Ceres iterations over all rounds
  bool converged = false;   ///< the last round reached a convergence tolerance (or could not lower the cost)
};

class BundleAdjuster {
 public:
  BundleAdjustmentSettings settings;

  BundleAdjuster() = default;
  explicit BundleAdjuster(const BundleAdjustmentSettings& s) : settings(s) {}

  /// Optimises poses and points. Observations whose point is not in front of their camera at the
  /// start are left out of the solve (and flagged). Throws std::invalid_argument on invalid settings,
  /// intrinsics, poses, points or observations (naming the index) or fixed keyframes.
  BundleAdjustmentResult adjust(const PinholeIntrinsics<double>& intrinsics,
                                const std::vector<Eigen::Isometry3d>& T_world_camera,
                                const std::vector<Eigen::Vector3d>& points_world_m,
                                const std::vector<BundleObservation>& observations,
                                const std::vector<int>& fixed_keyframes = {0}) const {
    settings.validate();
    validate_input(intrinsics, T_world_camera, points_world_m, observations, fixed_keyframes);
    const std::size_t n_poses = T_world_camera.size(), n_points = points_world_m.size();

    std::vector<SE3Block> poses;
    poses.reserve(n_poses);
    for (const Eigen::Isometry3d& T : T_world_camera) poses.push_back(SE3Block::from_isometry(T.inverse()));
    std::vector<Eigen::Vector3d> points = points_world_m;
    std::vector<bool> fixed(n_poses, false);
    for (int f : fixed_keyframes) fixed[f] = true;

    std::vector<Eigen::Isometry3d> T_camera_world_start;
    T_camera_world_start.reserve(n_poses);
    for (const SE3Block& b : poses) T_camera_world_start.push_back(b.to_isometry());

    BundleAdjustmentResult result;
    // Observations in the next round: those in front of their camera at the start.
    std::vector<bool> active(observations.size());
    for (std::size_t k = 0; k < observations.size(); ++k)
      active[k] =
          (T_camera_world_start[observations[k].keyframe] * points[observations[k].point]).z() > settings.min_depth_m;
    std::vector<bool> used_pose(n_poses, false), used_point(n_points, false);
    for (int round = 0; round < settings.rounds; ++round) {
      // One loss shared by every residual; it outlives the problem, which does not own it.
      ceres::HuberLoss huber(settings.huber_delta > 0 ? settings.huber_delta : 1.0);  // any width when unused
      ceres::Problem problem(problem_options());
      // Elimination order given, not searched for: points first (Schur complement), then poses.
      auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
      std::vector<bool> in_problem(n_poses, false), point_in_problem(n_points, false);
      const bool robust = round < settings.robust_rounds && settings.huber_delta > 0;
      for (std::size_t k = 0; k < observations.size(); ++k) {
        if (!active[k]) continue;
        const BundleObservation& o = observations[k];
        SE3Block& pose = poses[o.keyframe];
        if (!in_problem[o.keyframe]) {
          pose.add_to(problem, fixed[o.keyframe]);
          ordering->AddElementToGroup(pose.q_xyzw.data(), 1);
          ordering->AddElementToGroup(pose.t.data(), 1);
          in_problem[o.keyframe] = true;
          used_pose[o.keyframe] = true;
        }
        if (!point_in_problem[o.point]) {
          ordering->AddElementToGroup(points[o.point].data(), 0);
          point_in_problem[o.point] = true;
        }
        used_point[o.point] = true;
        const bool has_depth = !std::isnan(o.depth_m);
        problem.AddResidualBlock(new RgbdReprojectionCost(intrinsics, o.pixel_px, 1.0 / o.sigma_px,
                                                          has_depth ? o.depth_m : 0.0,
                                                          has_depth ? 1.0 / o.sigma_depth_m : 0.0, settings.min_depth_m),
                                 robust ? &huber : nullptr, pose.q_xyzw.data(), pose.t.data(), points[o.point].data());
      }
      ceres::Solver::Options options = settings.solver.options(/*sparse=*/settings.sparse_schur, /*schur=*/true);
      options.linear_solver_ordering = ordering;
      if (problem.NumResidualBlocks() == 0) {
        if (round == 0) result.converged = true;  // nothing to optimise
        break;
      }
      ceres::Solver::Summary summary;
      ceres::Solve(options, &problem, &summary);
      if (round == 0) result.initial_cost = summary.initial_cost;
      result.final_cost = summary.final_cost;
      result.iterations += static_cast<int>(summary.iterations.size()) - 1;
      result.rounds = round + 1;
      result.converged =
          summary.termination_type == ceres::CONVERGENCE ||
          (summary.termination_type == ceres::NO_CONVERGENCE && summary.final_cost >= summary.initial_cost);
      if (round + 1 < settings.rounds) {
        // Outliers at this round's optimum sit out the next round (ORB-SLAM2's local BA).
        std::vector<Eigen::Isometry3d> T_camera_world;
        for (const SE3Block& b : poses) T_camera_world.push_back(b.to_isometry());
        for (std::size_t k = 0; k < observations.size(); ++k)
          active[k] = !is_outlier(intrinsics, observations[k], T_camera_world[observations[k].keyframe],
                                  points[observations[k].point], nullptr);
      }
    }

    result.T_world_camera.reserve(n_poses);
    for (std::size_t i = 0; i < n_poses; ++i)
      result.T_world_camera.push_back(fixed[i] || !used_pose[i] ? T_world_camera[i] : poses[i].to_isometry().inverse());
    result.points_world_m = std::move(points);
    for (std::size_t j = 0; j < n_points; ++j)
      if (!used_point[j]) result.points_world_m[j] = points_world_m[j];
    classify(intrinsics, observations, result);
    return result;
  }

 private:
  /// chi2 test of one observation at T_camera_world; `pixel_sq` (if given) receives the squared
  /// pixel error.
  bool is_outlier(const PinholeIntrinsics<double>& K, const BundleObservation& o,
                  const Eigen::Isometry3d& T_camera_world, const Eigen::Vector3d& point_world, double* pixel_sq) const {
    const Eigen::Vector3d p = T_camera_world * point_world;
    if (!(p.z() > settings.min_depth_m)) return true;
    const double e_sq = (K.project(p) - o.pixel_px).squaredNorm();
    if (pixel_sq != nullptr) *pixel_sq = e_sq;
    double chi2 = e_sq / (o.sigma_px * o.sigma_px);
    double threshold = settings.chi2_threshold_2dof;
    if (!std::isnan(o.depth_m)) {
      const double e = (p.z() - o.depth_m) / o.sigma_depth_m;
      chi2 += e * e;
      threshold = settings.chi2_threshold_3dof;
    }
    return !(chi2 <= threshold);
  }

  void classify(const PinholeIntrinsics<double>& K, const std::vector<BundleObservation>& observations,
                BundleAdjustmentResult& result) const {
    result.outliers.assign(observations.size(), false);
    result.outlier_count = 0;
    double sum_sq_px = 0;
    int inliers = 0;
    std::vector<Eigen::Isometry3d> T_camera_world;
    T_camera_world.reserve(result.T_world_camera.size());
    for (const Eigen::Isometry3d& T : result.T_world_camera) T_camera_world.push_back(T.inverse());
    for (std::size_t k = 0; k < observations.size(); ++k) {
      const BundleObservation& o = observations[k];
      double pixel_sq = 0;
      const bool outlier = is_outlier(K, o, T_camera_world[o.keyframe], result.points_world_m[o.point], &pixel_sq);
      result.outliers[k] = outlier;
      if (outlier) {
        ++result.outlier_count;
      } else {
        sum_sq_px += pixel_sq;
        ++inliers;
      }
    }
    result.final_rms_px = inliers > 0 ? std::sqrt(sum_sq_px / inliers) : 0.0;
  }

  static void validate_input(const PinholeIntrinsics<double>& K, const std::vector<Eigen::Isometry3d>& poses,
                             const std::vector<Eigen::Vector3d>& points,
                             const std::vector<BundleObservation>& observations, const std::vector<int>& fixed) {
    const std::string who = "BundleAdjuster: ";
    if (!(std::isfinite(K.fx_px) && std::isfinite(K.fy_px) && std::isfinite(K.cx_px) && std::isfinite(K.cy_px) &&
          K.fx_px > 0 && K.fy_px > 0))
      throw std::invalid_argument(who + "intrinsics must be finite with positive focal lengths");
    const int n_poses = static_cast<int>(poses.size()), n_points = static_cast<int>(points.size());
    for (int i = 0; i < n_poses; ++i) validate_rigid_transform(poses[i], who + "pose " + std::to_string(i));
    for (int j = 0; j < n_points; ++j)
      if (!points[j].allFinite()) throw std::invalid_argument(who + "point " + std::to_string(j) + " is not finite");
    if (fixed.empty()) throw std::invalid_argument(who + "at least one fixed keyframe is needed (the gauge)");
    for (int f : fixed)
      if (f < 0 || f >= n_poses)
        throw std::invalid_argument(who + "fixed keyframe " + std::to_string(f) + " out of range [0, " +
                                    std::to_string(n_poses) + ")");
    for (std::size_t k = 0; k < observations.size(); ++k) {
      const BundleObservation& o = observations[k];
      const std::string where = who + "observation " + std::to_string(k) + ": ";
      if (o.keyframe < 0 || o.keyframe >= n_poses)
        throw std::invalid_argument(where + "keyframe " + std::to_string(o.keyframe) + " out of range [0, " +
                                    std::to_string(n_poses) + ")");
      if (o.point < 0 || o.point >= n_points)
        throw std::invalid_argument(where + "point " + std::to_string(o.point) + " out of range [0, " +
                                    std::to_string(n_points) + ")");
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
};

}  // namespace cge
