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
#include <vector>

#include "cge/ceres/bundle_adjustment.hpp"
#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/keyframe.hpp"
#include "cge/slam/map.hpp"
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
/// orb_scale_factor^octave and, when the keypoint has depth z, that depth with sigma
/// depth_sigma_per_m * z^2; for the pose at index `pose` and the point at index `point` of a problem.
BundleObservation keyframe_bundle_observation(const Keyframe& kf, int keypoint_index, int pose, int point,
                                              double orb_scale_factor, double depth_sigma_per_m);

/// Optimises the window around `keyframe_id` in place (keyframe poses through Map::set_keyframe_pose,
/// points through Map::set_map_point_position). `orb_scale_factor` gives each keypoint its pixel sigma
/// (scale_factor^octave). Throws std::invalid_argument for an unknown keyframe.
LocalBundleAdjustmentReport local_bundle_adjustment(Map& map, int keyframe_id,
                                                    const PinholeIntrinsics<double>& intrinsics,
                                                    const LocalMappingSettings& settings, double orb_scale_factor);

}  // namespace slam
}  // namespace cge
