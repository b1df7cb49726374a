#pragma once
// PoseGraphOptimiser: pose-graph optimisation over keyframe poses (docs/METHOD.md section 7.5:
// sequential, covisibility and loop edges), with Ceres. Nodes are T_world_camera (metres), edges
// measured relative poses T_a_b = T_world_a^-1 * T_world_b with a 6x6 information matrix (rotation
// first, then translation; see pose_graph_cost.hpp). The caller names the fixed nodes (at least one:
// the graph is otherwise free to move as a whole). Also propagate_pose_correction(), the step
// ORB-SLAM runs before the graph: the current keyframe's loop correction carried rigidly to its
// connected keyframes. Deterministic: one thread, fixed options.
#include "cge/ceres/ceres_headers.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/ceres/pose_graph_cost.hpp"
#include "cge/ceres/se3_parametrisation.hpp"
#include "cge/ceres/solver_settings.hpp"

namespace cge {

struct PoseGraphEdge {
  int from = -1;                                                ///< node a
  int to = -1;                                                  ///< node b
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();  ///< measured T_a_b, metres
  /// Symmetric positive definite, order (rotation x y z [rad], translation x y z [m]); 1/variance.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();

  /// An edge with diagonal information: rotation_weight (1/rad^2) and translation_weight (1/m^2).
  static PoseGraphEdge weighted(int a, int b, const Eigen::Isometry3d& T_a_b, double rotation_weight,
                                double translation_weight) {
    PoseGraphEdge e;
    e.from = a;
    e.to = b;
    e.T_from_to = T_a_b;
    e.information.setZero();
    e.information.diagonal() << rotation_weight, rotation_weight, rotation_weight, translation_weight,
        translation_weight, translation_weight;
    return e;
  }
};

struct PoseGraphSettings {
  /// Huber width on the whitened edge residual norm, sqrt of information units; 0 = no robust loss.
  double huber_delta = 0;
  /// Ceres iterations and tolerances (ORB-SLAM2's essential graph: 20 iterations; ours more, the
  /// problem is small).
  CeresSolverSettings solver{100, 1e-10, 1e-12, 1e-12};

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    if (!(std::isfinite(huber_delta) && huber_delta >= 0))
      throw std::invalid_argument("PoseGraphSettings: huber_delta must be finite and not negative");
    solver.validate("PoseGraphSettings.solver");
  }
};

struct PoseGraphResult {
  std::vector<Eigen::Isometry3d> T_world_camera;  ///< optimised poses, one per input node
  double initial_cost = 0;                        ///< Ceres cost 0.5 * sum r^T information r (robustified) at the start
  double final_cost = 0;                          ///< the same at the optimum
  int iterations = 0;                             ///< Ceres iterations
  bool converged = false;  ///< a convergence tolerance was reached (or the start was already optimal)
};

class PoseGraphOptimiser {
 public:
  PoseGraphSettings settings;

  PoseGraphOptimiser() = default;
  explicit PoseGraphOptimiser(const PoseGraphSettings& s) : settings(s) {}

  /// Optimises the poses; the nodes listed in `fixed_nodes` keep their input pose exactly.
  /// Throws std::invalid_argument on invalid settings, poses, edges (naming the index) or fixed nodes.
  PoseGraphResult optimise(const std::vector<Eigen::Isometry3d>& T_world_camera,
                           const std::vector<PoseGraphEdge>& edges, const std::vector<int>& fixed_nodes = {0}) const {
    settings.validate();
    const int n = static_cast<int>(T_world_camera.size());
    validate_input(T_world_camera, edges, fixed_nodes);

    std::vector<SE3Block> blocks;
    blocks.reserve(T_world_camera.size());
    for (const Eigen::Isometry3d& T : T_world_camera) blocks.push_back(SE3Block::from_isometry(T));
    std::vector<bool> fixed(T_world_camera.size(), false);
    for (int f : fixed_nodes) fixed[f] = true;

    // One loss shared by every residual; it outlives the problem, which does not own it.
    ceres::HuberLoss huber(settings.huber_delta > 0 ? settings.huber_delta : 1.0);  // any width when unused
    ceres::Problem problem(problem_options());
    for (int i = 0; i < n; ++i) blocks[i].add_to(problem, fixed[i]);
    for (const PoseGraphEdge& e : edges) {
      RelativePoseCost cost;
      cost.q_a_b_measured = Eigen::Quaterniond(Eigen::Matrix3d(e.T_from_to.linear())).normalized();
      cost.t_a_b_measured = e.T_from_to.translation();
      cost.sqrt_information = Eigen::LLT<Eigen::Matrix<double, 6, 6>>(e.information).matrixU();
      problem.AddResidualBlock(RelativePoseCost::create(cost), settings.huber_delta > 0 ? &huber : nullptr,
                               blocks[e.from].q_xyzw.data(), blocks[e.from].t.data(), blocks[e.to].q_xyzw.data(),
                               blocks[e.to].t.data());
    }

    PoseGraphResult result;
    ceres::Solver::Summary summary;
    if (problem.NumResidualBlocks() > 0) {
      ceres::Solve(settings.solver.options(/*sparse=*/true, /*schur=*/false), &problem, &summary);
      result.initial_cost = summary.initial_cost;
      result.final_cost = summary.final_cost;
      result.iterations = static_cast<int>(summary.iterations.size()) - 1;
      result.converged =
          summary.termination_type == ceres::CONVERGENCE ||
          (summary.termination_type == ceres::NO_CONVERGENCE && summary.final_cost >= summary.initial_cost);
    } else {
      result.converged = true;  // nothing to optimise
    }
    result.T_world_camera.reserve(T_world_camera.size());
    for (int i = 0; i < n; ++i) result.T_world_camera.push_back(fixed[i] ? T_world_camera[i] : blocks[i].to_isometry());
    return result;
  }

 private:
  static void validate_input(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                             const std::vector<int>& fixed_nodes) {
    const int n = static_cast<int>(poses.size());
    for (int i = 0; i < n; ++i) validate_rigid_transform(poses[i], "PoseGraphOptimiser: pose " + std::to_string(i));
    if (fixed_nodes.empty())
      throw std::invalid_argument("PoseGraphOptimiser: at least one fixed node is needed (the gauge)");
    for (int f : fixed_nodes)
      if (f < 0 || f >= n)
        throw std::invalid_argument("PoseGraphOptimiser: fixed node " + std::to_string(f) + " out of range [0, " +
                                    std::to_string(n) + ")");
    for (std::size_t k = 0; k < edges.size(); ++k) {
      const PoseGraphEdge& e = edges[k];
      const std::string where = "PoseGraphOptimiser: edge " + std::to_string(k) + ": ";
      if (e.from < 0 || e.from >= n || e.to < 0 || e.to >= n)
        throw std::invalid_argument(where + "node index out of range [0, " + std::to_string(n) + ")");
      if (e.from == e.to) throw std::invalid_argument(where + "joins node " + std::to_string(e.from) + " to itself");
      validate_rigid_transform(e.T_from_to, where + "T_from_to");
      if (!e.information.allFinite() || !e.information.isApprox(e.information.transpose()))
        throw std::invalid_argument(where + "information must be finite and symmetric");
      Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(e.information);
      if (llt.info() != Eigen::Success) throw std::invalid_argument(where + "information must be positive definite");
    }
  }
};

/// ORB-SLAM-style loop correction before the pose graph: keyframe `current` moves to
/// T_world_current_corrected, and every keyframe in `connected` moves rigidly with it (keeping its
/// pose relative to `current`): T_world_i <- T_world_current_corrected * T_world_current^-1 * T_world_i.
/// Throws std::invalid_argument on an index out of range or a non-rigid correction.
inline void propagate_pose_correction(std::vector<Eigen::Isometry3d>& T_world_camera, int current,
                                      const Eigen::Isometry3d& T_world_current_corrected,
                                      const std::vector<int>& connected) {
  const int n = static_cast<int>(T_world_camera.size());
  if (current < 0 || current >= n)
    throw std::invalid_argument("propagate_pose_correction: current keyframe " + std::to_string(current) +
                                " out of range");
  validate_rigid_transform(T_world_current_corrected, "propagate_pose_correction: T_world_current_corrected");
  for (int i : connected)
    if (i < 0 || i >= n)
      throw std::invalid_argument("propagate_pose_correction: connected keyframe " + std::to_string(i) +
                                  " out of range");
  const Eigen::Isometry3d correction = T_world_current_corrected * T_world_camera[current].inverse();
  for (int i : connected)
    if (i != current) T_world_camera[i] = correction * T_world_camera[i];
  T_world_camera[current] = T_world_current_corrected;
}

}  // namespace cge
