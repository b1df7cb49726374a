#pragma once
// Absolute trajectory error as evaluate_ate.py of the TUM RGB-D tools computes it:
//   1. associate ground-truth and estimated stamps (association.hpp; ground truth first);
//   2. align the associated estimated positions to the ground-truth positions with the closed-form
//      rigid transform without scale (rigid_alignment.hpp);
//   3. the error of each pair is the distance between the aligned estimated position and the
//      ground-truth position; report rmse, mean, median, std, min, max (error_statistics.hpp).
// Only positions enter: the estimated orientations do not change the ATE.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cge/metrics/association.hpp"
#include "cge/metrics/error_statistics.hpp"
#include "cge/metrics/rigid_alignment.hpp"
#include "cge/metrics/trajectory.hpp"

namespace cge {
namespace metrics {

struct AteSettings {
  AssociationSettings association;  ///< offset 0 s, max difference 0.02 s, as evaluate_ate.py
  /// Fewest associated pairs the ATE is computed from, >= 1. A rigid alignment fits one or two
  /// positions exactly, so with fewer than three pairs the ATE is 0 whatever the estimate (a
  /// silent wrong number); evaluate_ate.py has no such check. Default 3, the fewest points that
  /// determine a rigid transform in 3-D.
  std::size_t min_pairs = 3;
};

struct AteResult {
  std::vector<TimestampMatch> matches;  ///< (ground-truth index, estimate index), by ground-truth stamp
  Eigen::Isometry3d T_groundtruth_estimate = Eigen::Isometry3d::Identity();  ///< the alignment
  std::vector<double> errors_m;                                              ///< per match, metres, parallel to matches
  ErrorStatistics translation_m;                                             ///< statistics of errors_m, metres
};

/// Throws std::invalid_argument for invalid trajectories, when no timestamp associates, or when
/// fewer than settings.min_pairs pairs associate.
inline AteResult compute_ate(const Trajectory& ground_truth, const Trajectory& estimate,
                             const AteSettings& settings = {}) {
  require_valid_trajectory(ground_truth, "ATE ground truth");
  require_valid_trajectory(estimate, "ATE estimate");
  AteResult result;
  result.matches = associate(ground_truth, estimate, settings.association);
  if (result.matches.empty()) {
    throw std::invalid_argument(
        "ATE: no timestamp of the estimate lies within the maximum difference of a "
        "ground-truth timestamp (wrong files, or a time offset?)");
  }
  if (result.matches.size() < settings.min_pairs) {
    throw std::invalid_argument("ATE: only " + std::to_string(result.matches.size()) +
                                " pose pair(s) associate; at least " + std::to_string(settings.min_pairs) +
                                " are needed (the rigid alignment fits fewer exactly, so their ATE would be 0)");
  }
  std::vector<Eigen::Vector3d> p_estimate, p_groundtruth;
  p_estimate.reserve(result.matches.size());
  p_groundtruth.reserve(result.matches.size());
  for (const TimestampMatch& m : result.matches) {
    p_groundtruth.push_back(ground_truth[m.first].T_world_camera.translation());
    p_estimate.push_back(estimate[m.second].T_world_camera.translation());
  }
  result.T_groundtruth_estimate = align_rigid(p_estimate, p_groundtruth);
  result.errors_m.reserve(result.matches.size());
  for (std::size_t i = 0; i < p_estimate.size(); ++i) {
    result.errors_m.push_back((result.T_groundtruth_estimate * p_estimate[i] - p_groundtruth[i]).norm());
  }
  result.translation_m = error_statistics(result.errors_m);
  return result;
}

}  // namespace metrics
}  // namespace cge
