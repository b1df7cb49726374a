#include "cge/slam/local_mapping.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/slam/frame.hpp"

namespace cge {
namespace slam {

BundleObservation keyframe_bundle_observation(const Keyframe& kf, int keypoint_index, int pose, int point,
                                              const OctaveScales& octave_scales, double depth_sigma_per_m) {
  const cv::KeyPoint& kp = kf.keypoints[static_cast<std::size_t>(keypoint_index)];
  BundleObservation b;
  b.keyframe = pose;
  b.point = point;
  const cv::Point2f pixel = undistorted_position(kf, static_cast<std::size_t>(keypoint_index));
  b.pixel_px = Eigen::Vector2d(pixel.x, pixel.y);
  b.sigma_px = octave_scales(kp.octave);
  const double z = kf.points_camera_m[static_cast<std::size_t>(keypoint_index)].z();
  if (std::isfinite(z) && z > 0) {
    b.depth_m = z;
    b.sigma_depth_m = depth_sigma_per_m * z * z;
  }
  return b;
}

LocalBundleAdjustment::LocalBundleAdjustment(const Map& map, int keyframe_id,
                                             const PinholeIntrinsics<double>& intrinsics,
                                             const LocalMappingSettings& lm, double orb_scale_factor)
    : keyframe_id_(keyframe_id) {
  if (keyframe_id < 0 || keyframe_id >= map.keyframe_count()) {
    throw std::invalid_argument("local_bundle_adjustment: unknown keyframe " + std::to_string(keyframe_id));
  }
  LocalBundleAdjustmentReport& report = report_;
  // The window: the new keyframe and its most covisible ones; keyframe 0 stays fixed (the gauge).
  std::vector<int> window{keyframe_id};
  for (const int id : map.covisible_keyframes(keyframe_id, lm.covisible_keyframes)) window.push_back(id);
  std::sort(window.begin(), window.end());
  const auto in_window = [&](int k) { return std::binary_search(window.begin(), window.end(), k); };
  // Points: those the window observes and at least two keyframes see (one view constrains nothing).
  std::vector<std::int64_t> point_ids;
  for (const int k : window) {
    for (const std::int64_t p : map.keyframe(k).map_point_ids) {
      if (p >= 0 && map.map_point(p).observations.size() >= 2) point_ids.push_back(p);
    }
  }
  std::sort(point_ids.begin(), point_ids.end());
  point_ids.erase(std::unique(point_ids.begin(), point_ids.end()), point_ids.end());
  if (point_ids.empty()) return;
  // Fixed observers, as in ORB-SLAM2's local BA: the keyframes outside the window that observe its
  // points, here the fixed_keyframes of them with most such observations (ties: smaller id). They
  // hold the gauge; ranked by covisibility with the new keyframe alone, a window that already took
  // every covisible keyframe was left one weakly connected anchor, and a few wrong matches to it
  // moved the whole window (decimetres on the real fr1/rpy frames, docs/REAL_DATA.md).
  std::map<int, int> outside_observations;
  for (const std::int64_t id : point_ids) {
    for (const Observation& o : map.map_point(id).observations) {
      if (!in_window(o.keyframe_id)) ++outside_observations[o.keyframe_id];
    }
  }
  std::vector<std::pair<int, int>> ranked;  // (-observations, keyframe)
  for (const auto& [k, n] : outside_observations) ranked.emplace_back(-n, k);
  std::sort(ranked.begin(), ranked.end());
  std::vector<int> observers;
  for (std::size_t i = 0; i < ranked.size() && static_cast<int>(i) < lm.fixed_keyframes; ++i) {
    observers.push_back(ranked[i].second);
  }
  std::sort(observers.begin(), observers.end());
  const auto takes_part = [&](int k) {
    return in_window(k) || std::binary_search(observers.begin(), observers.end(), k);
  };
  // Poses: the window, then the fixed observers that see a point, each indexed once.
  std::map<int, int> pose_index;
  std::vector<int>& keyframe_of = keyframe_of_;
  std::vector<int>& fixed = fixed_;
  const auto index_of = [&](int k) {
    const auto it = pose_index.find(k);
    if (it != pose_index.end()) return it->second;
    const int index = static_cast<int>(keyframe_of.size());
    pose_index.emplace(k, index);
    keyframe_of.push_back(k);
    if (!in_window(k) || k == 0) fixed.push_back(index);
    return index;
  };
  for (const int k : window) index_of(k);
  // A point enters only with at least one depth observation among those taking part: pixels alone
  // from keyframes with little baseline between them (a camera turning in place) do not fix the
  // point along its ray, and it slides to kilometres (walking_rpy: points 300 m to 7 km out, which
  // then pulled tracked poses 17 cm off). Its observation that had depth may belong to a keyframe
  // left out of the problem.
  std::vector<std::int64_t>& optimised_ids = optimised_ids_;
  std::vector<Eigen::Vector3d> points;
  std::vector<BundleObservation>& observations = observations_;
  std::vector<BundleObservation> of_point;   // the point's observations taking part, pose index unset
  std::vector<int> keyframe_of_observation;  // their keyframes
  const OctaveScales octave_scales(orb_scale_factor);
  for (const std::int64_t id : point_ids) {
    const MapPoint& p = map.map_point(id);
    of_point.clear();
    keyframe_of_observation.clear();
    for (const Observation& o : p.observations) {
      if (!takes_part(o.keyframe_id)) continue;
      of_point.push_back(keyframe_bundle_observation(map.keyframe(o.keyframe_id), o.keypoint_index, -1,
                                                     static_cast<int>(points.size()), octave_scales,
                                                     lm.depth_sigma_per_m));
      keyframe_of_observation.push_back(o.keyframe_id);
    }
    const bool anchored = std::any_of(of_point.begin(), of_point.end(),
                                      [](const BundleObservation& b) { return !std::isnan(b.depth_m); });
    if (!anchored) {
      ++report.points_without_depth;
      continue;
    }
    optimised_ids.push_back(id);
    points.push_back(p.position_world);
    for (std::size_t k = 0; k < of_point.size(); ++k) {
      of_point[k].keyframe = index_of(keyframe_of_observation[k]);
      observations.push_back(of_point[k]);
    }
  }
  if (points.empty() || fixed.empty()) return;  // no gauge: no keyframe 0, no outside observers
  std::vector<Eigen::Isometry3d> poses;
  for (const int k : keyframe_of) poses.push_back(map.keyframe(k).T_world_camera);
  points_start_ = points;
  run_ = std::make_unique<BundleAdjustmentRun>(lm.bundle, intrinsics, poses, points, observations, fixed);
  report.window_keyframes = static_cast<int>(window.size());
  report.fixed_keyframes = static_cast<int>(fixed.size());
  for (const int index : fixed) report.fixed_keyframe_ids.push_back(keyframe_of[static_cast<std::size_t>(index)]);
  std::sort(report.fixed_keyframe_ids.begin(), report.fixed_keyframe_ids.end());
  report.points = static_cast<int>(points.size());
  report.observations = static_cast<int>(observations.size());
}

LocalBundleAdjustment::~LocalBundleAdjustment() = default;
LocalBundleAdjustment::LocalBundleAdjustment(LocalBundleAdjustment&&) noexcept = default;
LocalBundleAdjustment& LocalBundleAdjustment::operator=(LocalBundleAdjustment&&) noexcept = default;

bool LocalBundleAdjustment::done() const { return run_ == nullptr || run_->done(); }

int LocalBundleAdjustment::rounds_left() const { return done() ? 0 : run_->rounds_left(); }

void LocalBundleAdjustment::solve_next_round(Map& map) {
  if (done()) return;
  run_->solve_next_round();
  write_back(map);
}

int LocalBundleAdjustment::solve_next_slice(Map& map, int max_iterations) {
  if (done()) return 0;
  const int used = run_->solve_next_slice(max_iterations);
  write_back(map);
  return used;
}

void LocalBundleAdjustment::solve_remaining_rounds(Map& map) {
  if (done()) return;
  while (!run_->done()) run_->solve_next_round();
  write_back(map);
}

void LocalBundleAdjustment::write_back(Map& map) {
  const BundleAdjustmentResult ba = run_->result();
  for (std::size_t i = 0; i < keyframe_of_.size(); ++i) {
    if (std::find(fixed_.begin(), fixed_.end(), static_cast<int>(i)) == fixed_.end()) {
      map.set_keyframe_pose(keyframe_of_[i], ba.T_world_camera[i]);
    }
  }
  // The same holds at the optimum: a point whose depth observations all ended as outliers was fixed
  // by pixels alone in the last round, so it keeps its position from before the adjustment.
  std::vector<char> anchored_at_optimum(points_start_.size(), 0);
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    if (!ba.outliers[k] && !std::isnan(observations_[k].depth_m))
      anchored_at_optimum[static_cast<std::size_t>(observations_[k].point)] = 1;
  }
  report_.points_kept = 0;
  for (std::size_t j = 0; j < optimised_ids_.size(); ++j) {
    if (anchored_at_optimum[j]) {
      map.set_map_point_position(optimised_ids_[j], ba.points_world_m[j]);
    } else {
      map.set_map_point_position(optimised_ids_[j], points_start_[j]);
      ++report_.points_kept;
    }
  }
  report_.ran = true;
  report_.outliers = ba.outlier_count;
  report_.iterations = ba.iterations;
  report_.converged = ba.converged;
}

LocalBundleAdjustmentReport local_bundle_adjustment(Map& map, int keyframe_id,
                                                    const PinholeIntrinsics<double>& intrinsics,
                                                    const LocalMappingSettings& lm, double orb_scale_factor) {
  LocalBundleAdjustment adjustment(map, keyframe_id, intrinsics, lm, orb_scale_factor);
  adjustment.solve_remaining_rounds(map);
  return adjustment.report();
}

}  // namespace slam
}  // namespace cge
