#pragma once
// The associated pose pairs of an ATE computation after its alignment (ate.hpp): what a plot needs
// to draw the estimate against the ground truth with the error of each pair (paper Figures 8, 9).
//
// CSV (write_aligned_pairs_csv): header `timestamp,gt_x,gt_y,gt_z,est_x,est_y,est_z,error_m`, then
// one line per associated pair in ground-truth time order: the ground-truth timestamp (6 decimals),
// the ground-truth position, the estimated position mapped by T_groundtruth_estimate (both metres,
// in the ground truth's world frame) and their distance, 15 significant digits. The RMSE of
// error_m is the ATE's rmse.

#include <cstdio>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cge/metrics/ate.hpp"

namespace cge {
namespace metrics {

struct AlignedPair {
  double timestamp_s = 0;                                   ///< the ground-truth stamp, seconds
  Eigen::Vector3d groundtruth_m = Eigen::Vector3d::Zero();  ///< ground-truth position
  Eigen::Vector3d estimate_m = Eigen::Vector3d::Zero();     ///< aligned estimated position
  double error_m = 0;                                       ///< |estimate_m - groundtruth_m|, as AteResult::errors_m
};

/// The pairs of `result`, which compute_ate made from `ground_truth` and `estimate`. Throws
/// std::invalid_argument when a match indexes outside the trajectories (another pair of inputs).
inline std::vector<AlignedPair> aligned_pairs(const Trajectory& ground_truth, const Trajectory& estimate,
                                              const AteResult& result) {
  std::vector<AlignedPair> pairs;
  pairs.reserve(result.matches.size());
  for (std::size_t i = 0; i < result.matches.size(); ++i) {
    const TimestampMatch& m = result.matches[i];
    if (m.first >= ground_truth.size() || m.second >= estimate.size() || i >= result.errors_m.size()) {
      throw std::invalid_argument("aligned_pairs: the ATE result does not belong to these trajectories");
    }
    AlignedPair p;
    p.timestamp_s = ground_truth[m.first].timestamp_s;
    p.groundtruth_m = ground_truth[m.first].T_world_camera.translation();
    p.estimate_m = result.T_groundtruth_estimate * estimate[m.second].T_world_camera.translation();
    p.error_m = result.errors_m[i];
    pairs.push_back(p);
  }
  return pairs;
}

inline void write_aligned_pairs_csv(std::ostream& out, const std::vector<AlignedPair>& pairs) {
  const auto number = [](const char* format, double v) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, format, v);
    return std::string(buffer);
  };
  out << "timestamp,gt_x,gt_y,gt_z,est_x,est_y,est_z,error_m\n";
  for (const AlignedPair& p : pairs) {
    out << number("%.6f", p.timestamp_s);
    for (const double v : {p.groundtruth_m.x(), p.groundtruth_m.y(), p.groundtruth_m.z(), p.estimate_m.x(),
                           p.estimate_m.y(), p.estimate_m.z(), p.error_m}) {
      out << ',' << number("%.15g", v);
    }
    out << '\n';
  }
}

}  // namespace metrics
}  // namespace cge
