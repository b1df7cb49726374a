#pragma once
// Relative pose error with a fixed delta, as evaluate_rpe.py of the TUM RGB-D tools computes it
// with --fixed_delta (docs/EVALUATION.md lists the one deviation):
//   1. overlap check: for every estimated stamp, the closest ground-truth stamp and back its
//      closest estimated stamp; fewer than two distinct stamps found this way is an error;
//   2. pairs (i, j) of estimated poses: j = closest index to index_i + delta, where the index is
//      the stamp (unit seconds) or the position in the file (unit frames); pairs whose j is the
//      last pose are dropped, as the tool does (so is a pair whose j is legitimately the last);
//   3. each estimated stamp takes the closest ground-truth stamp (no time limit in the search);
//      a pair is skipped when either ground-truth stamp is more than twice the median
//      ground-truth interval away from its estimated stamp;
//   4. error E = (E_i^-1 E_j) (G_i^-1 G_j)^-1 for estimated poses E and ground-truth poses G
//      (T_world_camera), which is the tool's ominus(ominus(E_j, E_i), ominus(G_j, G_i)) with
//      ominus(a, b) = a^-1 b (the paper writes (G_i^-1 G_j)^-1 (E_i^-1 E_j) instead: same angle,
//      a different translation in general; the code is followed). Translational error
//      |trans(E)| in metres, rotational error acos(clamp((trace(rot(E)) - 1) / 2, -1, 1)) in degrees;
//   5. fewer than two errors is an error; statistics as error_statistics.hpp.
// "Closest" is the tool's own binary search (find_closest_index), reproduced below so that ties
// between two equally close stamps resolve the same way. No alignment is applied (RPE is
// invariant to a rigid change of the world frame).
// Deviation: the tool randomly subsamples to 10000 pairs when there are more (--max_pairs); this
// code always uses every pair, so results agree for up to 10000 pairs and stay deterministic.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cge/metrics/error_statistics.hpp"
#include "cge/metrics/trajectory.hpp"

namespace cge {
namespace metrics {

enum class RpeDeltaUnit {
  seconds,  ///< delta in seconds of estimated timestamps (TUM unit "s")
  frames,   ///< delta in poses of the estimated trajectory (TUM unit "f")
};

struct RpeSettings {
  double delta = 1.0;                               ///< pair separation in delta_unit, > 0 (TUM default 1)
  RpeDeltaUnit delta_unit = RpeDeltaUnit::seconds;  ///< unit of delta
  /// A ground-truth stamp may lie at most this many median ground-truth intervals from its
  /// estimated stamp (evaluate_rpe.py: 2), > 0.
  double max_gt_gap_intervals = 2.0;
};

/// One evaluated pair: indices into the estimate and the ground truth, and its errors.
struct RpePair {
  std::size_t estimate_first = 0;
  std::size_t estimate_second = 0;
  std::size_t groundtruth_first = 0;
  std::size_t groundtruth_second = 0;
  double translation_error_m = 0.0;
  double rotation_error_deg = 0.0;
};

struct RpeResult {
  std::vector<RpePair> pairs;     ///< in the order of their first estimated pose
  ErrorStatistics translation_m;  ///< statistics of translation_error_m, metres
  ErrorStatistics rotation_deg;   ///< statistics of rotation_error_deg, degrees
};

namespace detail {

constexpr double kDegreesPerRadian = 57.295779513082320876798154814105;  // 180 / pi

/// evaluate_rpe.py's find_closest_index: a binary search for t in the sorted list that remembers
/// the closest element among those it visits (ties: the first visited wins; an exact hit returns
/// at once). The list must not be empty.
inline std::size_t tum_closest_index(const std::vector<double>& sorted, double t) {
  std::size_t beginning = 0, end = sorted.size(), best = 0;
  double difference = std::abs(sorted[0] - t);
  while (beginning < end) {
    const std::size_t middle = (beginning + end) / 2;
    if (std::abs(sorted[middle] - t) < difference) {
      difference = std::abs(sorted[middle] - t);
      best = middle;
    }
    if (t == sorted[middle]) return middle;
    if (sorted[middle] > t) {
      end = middle;
    } else {
      beginning = middle + 1;
    }
  }
  return best;
}

/// numpy.median of a non-empty list.
inline double median_of(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t mid = values.size() / 2;
  return values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

/// Rotation angle of a rotation matrix from its trace, as the TUM tool computes it, radians.
inline double rotation_angle_rad(const Eigen::Matrix3d& R) {
  return std::acos(std::min(1.0, std::max(-1.0, (R.trace() - 1.0) / 2.0)));
}

}  // namespace detail

/// Throws std::invalid_argument for invalid settings or trajectories (ground truth with fewer than
/// two poses included), a delta not shorter than the estimate's span, too little timestamp
/// overlap, or fewer than two evaluable pairs.
inline RpeResult compute_rpe(const Trajectory& ground_truth, const Trajectory& estimate,
                             const RpeSettings& settings = {}) {
  if (!(std::isfinite(settings.delta) && settings.delta > 0)) {
    throw std::invalid_argument("RPE: delta must be finite and > 0");
  }
  if (settings.delta_unit == RpeDeltaUnit::frames && settings.delta != std::floor(settings.delta)) {
    throw std::invalid_argument("RPE: a delta in frames must be a whole number");
  }
  if (!(std::isfinite(settings.max_gt_gap_intervals) && settings.max_gt_gap_intervals > 0)) {
    throw std::invalid_argument("RPE: max_gt_gap_intervals must be finite and > 0");
  }
  require_valid_trajectory(ground_truth, "RPE ground truth");
  require_valid_trajectory(estimate, "RPE estimate");
  if (ground_truth.size() < 2) throw std::invalid_argument("RPE: the ground truth needs at least two poses");
  if (estimate.size() < 2) throw std::invalid_argument("RPE: the estimate needs at least two poses");

  const std::vector<double> stamps_gt = timestamps(ground_truth);
  const std::vector<double> stamps_est = timestamps(estimate);
  // A delta as long as the estimate pairs nothing (the pair ending on the last pose is dropped);
  // a far longer one would make every distance to index + delta round to the same double, and the
  // closest-index search would then pair poses with the first one: refuse it before the search.
  const bool in_seconds = settings.delta_unit == RpeDeltaUnit::seconds;
  const double span = in_seconds ? stamps_est.back() - stamps_est.front() : static_cast<double>(estimate.size() - 1);
  if (!(settings.delta < span)) {
    std::ostringstream message;
    message.precision(15);
    message << "RPE: fewer than two pose pairs: delta " << settings.delta << (in_seconds ? " s" : " frames")
            << " is not shorter than the estimate's span of " << span << (in_seconds ? " s" : " frames");
    throw std::invalid_argument(message.str());
  }

  // 1. Overlap: distinct estimated stamps reached by estimate -> closest gt -> closest estimate.
  std::vector<std::size_t> returned;
  for (const double t_est : stamps_est) {
    const double t_gt = stamps_gt[detail::tum_closest_index(stamps_gt, t_est)];
    returned.push_back(detail::tum_closest_index(stamps_est, t_gt));
  }
  std::sort(returned.begin(), returned.end());
  if (std::unique(returned.begin(), returned.end()) - returned.begin() < 2) {
    throw std::invalid_argument(
        "RPE: the timestamps of the estimate and the ground truth hardly overlap "
        "(wrong files?)");
  }

  // 2. Pairs by the fixed delta.
  std::vector<double> index_est(stamps_est.size());
  for (std::size_t i = 0; i < index_est.size(); ++i) {
    index_est[i] = settings.delta_unit == RpeDeltaUnit::seconds ? stamps_est[i] : static_cast<double>(i);
  }
  const std::size_t last = estimate.size() - 1;

  // 3. Ground-truth time limit.
  std::vector<double> gt_intervals(stamps_gt.size() - 1);
  for (std::size_t k = 0; k + 1 < stamps_gt.size(); ++k) gt_intervals[k] = stamps_gt[k + 1] - stamps_gt[k];
  const double max_gt_gap_s = settings.max_gt_gap_intervals * detail::median_of(gt_intervals);

  RpeResult result;
  std::vector<double> translation_errors, rotation_errors;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    const std::size_t j = detail::tum_closest_index(index_est, index_est[i] + settings.delta);
    if (j == last) continue;
    const std::size_t g0 = detail::tum_closest_index(stamps_gt, stamps_est[i]);
    const std::size_t g1 = detail::tum_closest_index(stamps_gt, stamps_est[j]);
    if (std::abs(stamps_gt[g0] - stamps_est[i]) > max_gt_gap_s ||
        std::abs(stamps_gt[g1] - stamps_est[j]) > max_gt_gap_s) {
      continue;
    }
    // 4. E = (E_i^-1 E_j) (G_i^-1 G_j)^-1.
    const Eigen::Isometry3d motion_est = estimate[i].T_world_camera.inverse() * estimate[j].T_world_camera;
    const Eigen::Isometry3d motion_gt = ground_truth[g0].T_world_camera.inverse() * ground_truth[g1].T_world_camera;
    const Eigen::Isometry3d error = motion_est * motion_gt.inverse();
    RpePair pair;
    pair.estimate_first = i;
    pair.estimate_second = j;
    pair.groundtruth_first = g0;
    pair.groundtruth_second = g1;
    pair.translation_error_m = error.translation().norm();
    pair.rotation_error_deg = detail::rotation_angle_rad(error.linear()) * detail::kDegreesPerRadian;
    result.pairs.push_back(pair);
    translation_errors.push_back(pair.translation_error_m);
    rotation_errors.push_back(pair.rotation_error_deg);
  }
  // 5.
  if (result.pairs.size() < 2) {
    throw std::invalid_argument("RPE: fewer than two pose pairs " + std::to_string(settings.delta) +
                                (settings.delta_unit == RpeDeltaUnit::seconds ? " s" : " frames") +
                                " apart have ground truth (trajectory too short for the delta?)");
  }
  result.translation_m = error_statistics(translation_errors);
  result.rotation_deg = error_statistics(rotation_errors);
  return result;
}

}  // namespace metrics
}  // namespace cge
