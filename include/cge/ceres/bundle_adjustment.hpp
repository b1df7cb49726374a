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
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/ceres/reprojection_cost.hpp"
#include "cge/ceres/robust_rounds.hpp"
#include "cge/ceres/rgbd_reprojection_cost.hpp"
#include "cge/ceres/schur_lm_solver.hpp"
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

/// Which solver a bundle adjustment runs (BundleAdjustmentSettings::backend).
enum class BundleAdjustmentBackend { ceres, schur_lm };

/// "ceres" or "schur_lm": the backend's name on the command line and in summary.json.
inline const char* bundle_adjustment_backend_name(BundleAdjustmentBackend backend) {
  return backend == BundleAdjustmentBackend::schur_lm ? "schur_lm" : "ceres";
}

/// The rounds, loss and outlier test (RobustRoundsSettings: ORB-SLAM2's local BA runs 2 rounds, the
/// first with the Huber loss) and the solver.
struct BundleAdjustmentSettings : RobustRoundsSettings {
  /// Ceres iterations and tolerances; sparse Schur (points eliminated) when Ceres has a sparse library.
  CeresSolverSettings solver{100, 1e-10, 1e-12, 1e-12};
  /// Reduced camera system: sparse (global BA, hundreds of keyframes) or dense Schur (a local
  /// window of a few dozen keyframes, whose reduced system of 6 unknowns per keyframe is small
  /// enough that a dense factorisation beats the sparse set-up).
  bool sparse_schur = true;
  /// The solver: Ceres (with solver's options and sparse_schur), or cge's own Schur-complement
  /// Levenberg-Marquardt (schur_lm_solver.hpp: the same problem, rounds, iteration budget and
  /// tolerances, dense reduced system; for local windows, where Ceres' per-block overhead dominates).
  BundleAdjustmentBackend backend = BundleAdjustmentBackend::ceres;
  /// With backend schur_lm: the most free poses a round gives cge's solver, count >= 1. Its
  /// reduced camera system is dense (6 unknowns a pose, factorised in O((6 n)^3)), so a round with
  /// more free poses goes to Ceres with sparse_schur as set. Ours, on the safe side: on
  /// loop_dynamic's global BAs the own solver was faster up to about 160 keyframes and slower from
  /// about 230 (docs/OPTIMISATION.md).
  int schur_lm_max_free_poses = 100;

  BundleAdjustmentSettings() {
    rounds = 2;         // ORB-SLAM2's local BA: 2 (1 = a single plain solve)
    robust_rounds = 1;  // ORB-SLAM2's local BA: 1
  }

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    validate_rounds("BundleAdjustmentSettings");
    solver.validate("BundleAdjustmentSettings.solver");
    if (schur_lm_max_free_poses < 1) {
      throw std::invalid_argument("BundleAdjustmentSettings: schur_lm_max_free_poses must be at least 1 (got " +
                                  std::to_string(schur_lm_max_free_poses) + ")");
    }
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

/// One bundle adjustment solved a round at a time, so that a caller can spread the rounds over
/// several calls (the SLAM pipeline runs one round per camera frame: a serial stand-in for
/// ORB-SLAM2's local-mapping thread, which optimises while tracking goes on). Running every round
/// and then taking result() is exactly BundleAdjuster::adjust.
class BundleAdjustmentRun {
 public:
  /// Validates as BundleAdjuster::adjust does (throws std::invalid_argument naming the problem)
  /// and takes the starting state; no round is solved yet.
  BundleAdjustmentRun(const BundleAdjustmentSettings& settings, const PinholeIntrinsics<double>& intrinsics,
                      const std::vector<Eigen::Isometry3d>& T_world_camera,
                      const std::vector<Eigen::Vector3d>& points_world_m,
                      const std::vector<BundleObservation>& observations, const std::vector<int>& fixed_keyframes);

  /// True when every round has been solved (or there was nothing left to optimise).
  bool done() const { return finished_; }
  /// Rounds solved so far.
  int rounds_solved() const { return result_.rounds; }
  /// Rounds still to solve (0 when done()).
  int rounds_left() const { return finished_ ? 0 : settings_.rounds - result_.rounds; }
  /// Solves the next round (what is left of it, when slices of it were solved); after each but the
  /// last, the observations over the chi2 threshold sit out the next round. Nothing to do when done().
  void solve_next_round();
  /// Solves at most `max_iterations` (>= 1) Levenberg-Marquardt iterations of the current round,
  /// from the current estimate (the damping starts afresh, as in a new solve). The round ends when
  /// Ceres stops before the slice's limit (converged, or no step found) or when the round has used
  /// settings.solver.max_iterations; then the outliers are classified as after a whole round.
  /// Returns the iterations used (0 when done()). Throws std::invalid_argument when max_iterations < 1.
  int solve_next_slice(int max_iterations);
  /// Iterations used so far by the current round's slices (0 at a round's start).
  int round_iterations() const { return round_iterations_; }
  /// Poses, points and outlier flags at the current state (after the rounds solved so far).
  BundleAdjustmentResult result() const;

 private:
  bool is_outlier(const BundleObservation& o, const Eigen::Isometry3d& T_camera_world,
                  const Eigen::Vector3d& point_world, double* pixel_sq) const;
  void classify(BundleAdjustmentResult& result) const;
  /// What one backend's solve of a slice gives the round bookkeeping.
  struct SliceOutcome {
    int iterations = 0;
    double initial_cost = 0, final_cost = 0;
    bool converged = false;            ///< a tolerance was reached (or no step could lower the cost)
    bool hit_iteration_limit = false;  ///< stopped by the slice's iteration limit
  };
  /// One slice of the current round over the active observations, at most `slice_limit` iterations.
  SliceOutcome solve_slice_ceres(bool robust, int slice_limit);
  SliceOutcome solve_slice_schur_lm(bool robust, int slice_limit);
  /// backend schur_lm, and the active observations' free poses within schur_lm_max_free_poses.
  bool solved_by_schur_lm() const;

  BundleAdjustmentSettings settings_;
  PinholeIntrinsics<double> intrinsics_;
  std::vector<Eigen::Isometry3d> T_world_camera_start_;
  std::vector<Eigen::Vector3d> points_start_;
  std::vector<BundleObservation> observations_;
  std::vector<SE3Block> poses_;  ///< T_camera_world, optimised in place
  std::vector<Eigen::Vector3d> points_;
  std::vector<bool> fixed_;
  std::vector<bool> active_;  ///< observations in the next round
  std::vector<bool> used_pose_, used_point_;
  BundleAdjustmentResult result_;  ///< costs, rounds, iterations, convergence so far
  bool finished_ = false;
  int round_iterations_ = 0;       ///< iterations of the current round's slices so far
  double round_initial_cost_ = 0;  ///< cost at the start of the current round's first slice
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
    BundleAdjustmentRun run(settings, intrinsics, T_world_camera, points_world_m, observations, fixed_keyframes);
    while (!run.done()) run.solve_next_round();
    return run.result();
  }

  /// Throws std::invalid_argument on invalid intrinsics, poses, points, observations or fixed
  /// keyframes, naming the index.
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


inline BundleAdjustmentRun::BundleAdjustmentRun(const BundleAdjustmentSettings& settings,
                                                const PinholeIntrinsics<double>& intrinsics,
                                                const std::vector<Eigen::Isometry3d>& T_world_camera,
                                                const std::vector<Eigen::Vector3d>& points_world_m,
                                                const std::vector<BundleObservation>& observations,
                                                const std::vector<int>& fixed_keyframes)
    : settings_(settings),
      intrinsics_(intrinsics),
      T_world_camera_start_(T_world_camera),
      points_start_(points_world_m),
      observations_(observations),
      points_(points_world_m) {
  settings_.validate();
  BundleAdjuster::validate_input(intrinsics, T_world_camera, points_world_m, observations, fixed_keyframes);
  const std::size_t n_poses = T_world_camera.size();
  poses_.reserve(n_poses);
  for (const Eigen::Isometry3d& T : T_world_camera) poses_.push_back(SE3Block::from_isometry(T.inverse()));
  fixed_.assign(n_poses, false);
  for (const int f : fixed_keyframes) fixed_[static_cast<std::size_t>(f)] = true;
  // Observations in the first round: those in front of their camera at the start.
  std::vector<Eigen::Isometry3d> T_camera_world_start;
  T_camera_world_start.reserve(n_poses);
  for (const SE3Block& b : poses_) T_camera_world_start.push_back(b.to_isometry());
  active_.resize(observations_.size());
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    const BundleObservation& o = observations_[k];
    active_[k] = (T_camera_world_start[o.keyframe] * points_[o.point]).z() > settings_.min_depth_m;
  }
  used_pose_.assign(n_poses, false);
  used_point_.assign(points_.size(), false);
}

inline void BundleAdjustmentRun::solve_next_round() {
  if (finished_) return;
  solve_next_slice(settings_.solver.max_iterations - round_iterations_);
}

inline int BundleAdjustmentRun::solve_next_slice(int max_iterations) {
  if (max_iterations < 1) throw std::invalid_argument("BundleAdjustmentRun: a slice needs at least 1 iteration");
  if (finished_) return 0;
  const int round = result_.rounds;
  const int budget_left = settings_.solver.max_iterations - round_iterations_;
  const int slice_limit = max_iterations < budget_left ? max_iterations : budget_left;
  bool any_active = false;
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    if (!active_[k]) continue;
    any_active = true;
    used_pose_[static_cast<std::size_t>(observations_[k].keyframe)] = true;
    used_point_[static_cast<std::size_t>(observations_[k].point)] = true;
  }
  if (!any_active) {
    if (round == 0) result_.converged = true;  // nothing to optimise
    finished_ = true;
    return 0;
  }
  const SliceOutcome outcome = solved_by_schur_lm()
                                   ? solve_slice_schur_lm(settings_.robust_in_round(round), slice_limit)
                                   : solve_slice_ceres(settings_.robust_in_round(round), slice_limit);
  const int used = outcome.iterations;
  if (round_iterations_ == 0) round_initial_cost_ = outcome.initial_cost;
  if (round == 0 && round_iterations_ == 0) result_.initial_cost = outcome.initial_cost;
  round_iterations_ += used;
  result_.final_cost = outcome.final_cost;
  result_.iterations += used;
  // A slice stopped by its own limit, with the round's budget not spent, leaves the round open.
  const bool hit_slice_limit = outcome.hit_iteration_limit && used >= slice_limit;
  if (hit_slice_limit && round_iterations_ < settings_.solver.max_iterations) return used;
  result_.rounds = round + 1;
  result_.converged =
      outcome.converged || (outcome.hit_iteration_limit && outcome.final_cost >= round_initial_cost_);
  round_iterations_ = 0;
  if (result_.rounds == settings_.rounds) {
    finished_ = true;
    return used;
  }
  // Outliers at this round's optimum sit out the next round (ORB-SLAM2's local BA).
  std::vector<Eigen::Isometry3d> T_camera_world;
  T_camera_world.reserve(poses_.size());
  for (const SE3Block& b : poses_) T_camera_world.push_back(b.to_isometry());
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    const BundleObservation& o = observations_[k];
    active_[k] = !is_outlier(o, T_camera_world[o.keyframe], points_[o.point], nullptr);
  }
  return used;
}

inline bool BundleAdjustmentRun::solved_by_schur_lm() const {
  if (settings_.backend != BundleAdjustmentBackend::schur_lm) return false;
  std::vector<bool> counted(poses_.size(), false);
  int free_poses = 0;
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    const std::size_t i = static_cast<std::size_t>(observations_[k].keyframe);
    if (!active_[k] || fixed_[i] || counted[i]) continue;
    counted[i] = true;
    ++free_poses;
  }
  return free_poses <= settings_.schur_lm_max_free_poses;
}

inline BundleAdjustmentRun::SliceOutcome BundleAdjustmentRun::solve_slice_ceres(bool robust, int slice_limit) {
  // One loss shared by every residual; it outlives the problem, which does not own it.
  ceres::HuberLoss huber(settings_.huber_delta > 0 ? settings_.huber_delta : 1.0);  // any width when unused
  ceres::Problem problem(problem_options());
  // Elimination order given, not searched for: points first (Schur complement), then poses.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  std::vector<bool> pose_in_problem(poses_.size(), false), point_in_problem(points_.size(), false);
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    if (!active_[k]) continue;
    const BundleObservation& o = observations_[k];
    SE3Block& pose = poses_[o.keyframe];
    if (!pose_in_problem[o.keyframe]) {
      pose.add_to(problem, fixed_[o.keyframe]);
      ordering->AddElementToGroup(pose.q_xyzw.data(), 1);
      ordering->AddElementToGroup(pose.t.data(), 1);
      pose_in_problem[o.keyframe] = true;
    }
    if (!point_in_problem[o.point]) {
      ordering->AddElementToGroup(points_[o.point].data(), 0);
      point_in_problem[o.point] = true;
    }
    const bool has_depth = !std::isnan(o.depth_m);
    problem.AddResidualBlock(new RgbdReprojectionCost(intrinsics_, o.pixel_px, 1.0 / o.sigma_px,
                                                      has_depth ? o.depth_m : 0.0,
                                                      has_depth ? 1.0 / o.sigma_depth_m : 0.0, settings_.min_depth_m),
                             robust ? &huber : nullptr, pose.q_xyzw.data(), pose.t.data(), points_[o.point].data());
  }
  ceres::Solver::Options options = settings_.solver.options(/*sparse=*/settings_.sparse_schur, /*schur=*/true);
  options.max_num_iterations = slice_limit;
  options.linear_solver_ordering = ordering;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  SliceOutcome outcome;
  outcome.iterations = std::max(0, static_cast<int>(summary.iterations.size()) - 1);
  outcome.initial_cost = summary.initial_cost;
  outcome.final_cost = summary.final_cost;
  outcome.converged = summary.termination_type == ceres::CONVERGENCE;
  outcome.hit_iteration_limit = summary.termination_type == ceres::NO_CONVERGENCE;
  return outcome;
}

inline BundleAdjustmentRun::SliceOutcome BundleAdjustmentRun::solve_slice_schur_lm(bool robust, int slice_limit) {
  std::vector<SchurLMObservation> residuals;
  residuals.reserve(observations_.size());
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    if (!active_[k]) continue;
    const BundleObservation& o = observations_[k];
    SchurLMObservation r;
    r.pose = o.keyframe;
    r.point = o.point;
    r.pixel_px = o.pixel_px;
    r.inv_sigma_px = 1.0 / o.sigma_px;
    const bool has_depth = !std::isnan(o.depth_m);
    r.depth_m = has_depth ? o.depth_m : 0.0;
    r.inv_sigma_depth = has_depth ? 1.0 / o.sigma_depth_m : 0.0;
    residuals.push_back(r);
  }
  SchurLMSolver solver(intrinsics_, settings_.solver, robust ? settings_.huber_delta : 0.0, settings_.min_depth_m);
  const SchurLMSummary summary = solver.solve(poses_, fixed_, points_, residuals, slice_limit);
  SliceOutcome outcome;
  outcome.iterations = summary.iterations;
  outcome.initial_cost = summary.initial_cost;
  outcome.final_cost = summary.final_cost;
  outcome.converged = summary.termination == SchurLMSummary::Termination::converged;
  outcome.hit_iteration_limit = summary.termination == SchurLMSummary::Termination::iteration_limit;
  return outcome;
}

inline BundleAdjustmentResult BundleAdjustmentRun::result() const {
  BundleAdjustmentResult result = result_;
  result.T_world_camera.reserve(poses_.size());
  for (std::size_t i = 0; i < poses_.size(); ++i) {
    result.T_world_camera.push_back(fixed_[i] || !used_pose_[i] ? T_world_camera_start_[i]
                                                                : poses_[i].to_isometry().inverse());
  }
  result.points_world_m = points_;
  for (std::size_t j = 0; j < points_.size(); ++j) {
    if (!used_point_[j]) result.points_world_m[j] = points_start_[j];
  }
  classify(result);
  return result;
}

/// chi2 test of one observation at T_camera_world; `pixel_sq` (if given) receives the squared pixel
/// error.
inline bool BundleAdjustmentRun::is_outlier(const BundleObservation& o, const Eigen::Isometry3d& T_camera_world,
                                            const Eigen::Vector3d& point_world, double* pixel_sq) const {
  const Eigen::Vector3d p = T_camera_world * point_world;
  if (!(p.z() > settings_.min_depth_m)) return true;
  const double e_sq = (intrinsics_.project(p) - o.pixel_px).squaredNorm();
  if (pixel_sq != nullptr) *pixel_sq = e_sq;
  double chi2 = e_sq / (o.sigma_px * o.sigma_px);
  const bool with_depth = !std::isnan(o.depth_m);
  if (with_depth) {
    const double e = (p.z() - o.depth_m) / o.sigma_depth_m;
    chi2 += e * e;
  }
  return !(chi2 <= settings_.chi2_threshold(with_depth));
}

inline void BundleAdjustmentRun::classify(BundleAdjustmentResult& result) const {
  result.outliers.assign(observations_.size(), false);
  result.outlier_count = 0;
  double sum_sq_px = 0;
  int inliers = 0;
  std::vector<Eigen::Isometry3d> T_camera_world;
  T_camera_world.reserve(result.T_world_camera.size());
  for (const Eigen::Isometry3d& T : result.T_world_camera) T_camera_world.push_back(T.inverse());
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    const BundleObservation& o = observations_[k];
    double pixel_sq = 0;
    const bool outlier = is_outlier(o, T_camera_world[o.keyframe], result.points_world_m[o.point], &pixel_sq);
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

}  // namespace cge
