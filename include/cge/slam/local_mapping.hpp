#pragma once
// Local bundle adjustment after a keyframe insertion (ORB-SLAM2's local mapping; settings in
// LocalMappingSettings). Map points are made from one keyframe's depth, so each carries that
// keyframe's depth noise and pose error; refining them with every keyframe that observes them, and the
// window's poses with them, is what keeps the map (and the frames tracked against it) consistent.
//
// The window: the new keyframe and its `covisible_keyframes` most covisible keyframes. The points:
// those the window observes that at least two keyframes see and that keep a depth observation in the
// problem. Observations from keyframes outside the window take part with their poses fixed: as in
// ORB-SLAM2, the keyframes that observe the window's points, here at most fixed_keyframes of them,
// those with most such observations. Keyframe 0 is always fixed (the world is its camera). Pixel +
// depth observations through cge::BundleAdjuster.
//
// Deterministic: keyframes and points in id order, one-threaded Ceres.
#include <cstdint>
#include <memory>
#include <vector>

#include "cge/ceres/bundle_adjustment.hpp"
#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/keyframe.hpp"
#include "cge/slam/map.hpp"
#include "cge/slam/octave_scales.hpp"
#include "cge/slam/settings.hpp"

namespace cge {
namespace slam {

/// What one local bundle adjustment did (for tests and logs).
struct LocalBundleAdjustmentReport {
  bool ran = false;          ///< false: no point seen twice, or no fixed keyframe for the gauge
  int window_keyframes = 0;  ///< keyframes in the window (keyframe 0 counted when in it)
  int fixed_keyframes = 0;   ///< keyframes held fixed (outside observers and keyframe 0)
  std::vector<int> fixed_keyframe_ids;  ///< their ids, ascending
  int points = 0;            ///< map points optimised
  /// Points the window observes, left out: no observation taking part has depth (pixels alone do not
  /// fix a point along its ray when the keyframes have little baseline).
  int points_without_depth = 0;
  /// Optimised points whose depth observations all ended as outliers: their positions are not written.
  int points_kept = 0;
  int observations = 0;      ///< observations in the problem
  int outliers = 0;          ///< observations over the chi2 threshold at the optimum
  int iterations = 0;        ///< Ceres iterations over all rounds
  bool converged = false;    ///< the last round reached a convergence tolerance
};

/// The bundle-adjustment observation of keypoint `keypoint_index` of `kf`: its pixel with sigma
/// scale_factor^octave (`octave_scales`) and, when the keypoint has depth z, that depth with sigma
/// depth_sigma_per_m * z^2; for the pose at index `pose` and the point at index `point` of a problem.
BundleObservation keyframe_bundle_observation(const Keyframe& kf, int keypoint_index, int pose, int point,
                                              const OctaveScales& octave_scales, double depth_sigma_per_m);

/// The local bundle adjustment of one keyframe's window, solved a round at a time so that the
/// pipeline can spread its rounds over frames (LocalMappingSettings::ba_rounds_per_frame and
/// ba_from_next_frame). Between rounds the map must not change structurally (no keyframe inserted
/// or culled, no point erased or fused). Every round writes the window's poses and points into the
/// map.
class LocalBundleAdjustment {
 public:
  /// Collects the window, its fixed observers, points and observations from the map (nothing is
  /// solved yet). Throws std::invalid_argument for an unknown keyframe.
  LocalBundleAdjustment(const Map& map, int keyframe_id, const PinholeIntrinsics<double>& intrinsics,
                        const LocalMappingSettings& settings, double orb_scale_factor);
  ~LocalBundleAdjustment();
  LocalBundleAdjustment(LocalBundleAdjustment&&) noexcept;
  LocalBundleAdjustment& operator=(LocalBundleAdjustment&&) noexcept;

  int keyframe_id() const { return keyframe_id_; }
  /// True when every round is solved, or there was nothing to optimise.
  bool done() const;
  /// Rounds not solved yet (0 when done()).
  int rounds_left() const;
  /// Solves the next round and writes the optimised poses and points into `map`.
  void solve_next_round(Map& map);
  /// Solves at most `max_iterations` (>= 1) iterations of the current round
  /// (BundleAdjustmentRun::solve_next_slice) and writes the estimate into `map`; returns the
  /// iterations used (0 when done()).
  int solve_next_slice(Map& map, int max_iterations);
  /// Solves every round left, then writes the result into `map` once.
  void solve_remaining_rounds(Map& map);
  /// What was done so far (complete once done()).
  const LocalBundleAdjustmentReport& report() const { return report_; }

 private:
  void write_back(Map& map);

  int keyframe_id_ = -1;
  std::vector<int> keyframe_of_;             ///< pose index -> keyframe id
  std::vector<int> fixed_;                   ///< fixed pose indices
  std::vector<std::int64_t> optimised_ids_;  ///< point index -> map point id
  std::vector<Eigen::Vector3d> points_start_;
  std::vector<BundleObservation> observations_;
  std::unique_ptr<BundleAdjustmentRun> run_;  ///< null: nothing to optimise
  LocalBundleAdjustmentReport report_;
};

/// Optimises the window around `keyframe_id` in place, every round at once (keyframe poses through Map::set_keyframe_pose,
/// points through Map::set_map_point_position). `orb_scale_factor` gives each keypoint its pixel sigma
/// (scale_factor^octave). Throws std::invalid_argument for an unknown keyframe.
LocalBundleAdjustmentReport local_bundle_adjustment(Map& map, int keyframe_id,
                                                    const PinholeIntrinsics<double>& intrinsics,
                                                    const LocalMappingSettings& settings, double orb_scale_factor);

}  // namespace slam
}  // namespace cge
