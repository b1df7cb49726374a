#pragma once
// Map maintenance after a keyframe insertion, the rules of ORB-SLAM2's local mapping for the RGB-D
// case, serial and deterministic (keyframes and points in id order, no threads):
//   - cull_recent_map_points: recently created points that tracking rarely finds, or that too few
//     keyframes observe once they are two keyframes old, are erased (MapPointCulling);
//   - fuse_map_points: duplicates of one physical point in the new keyframe and its neighbours are
//     merged, and missing observations added (SearchInNeighbors + ORBmatcher::Fuse);
//   - cull_redundant_keyframes: a keyframe whose close points are nearly all seen by three other
//     keyframes at the same or a finer scale is culled (KeyFrameCulling);
//   - triangulate_new_points: points for keypoints without depth, from two keyframes' views
//     (CreateNewMapPoints).
// Every geometric step uses the keyframes' undistorted_px and T_world_camera; a keypoint "has depth"
// when its points_camera_m entry has a finite z > 0. Only static keypoints (FeatureLabel) are matched.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/map.hpp"

namespace cge {
namespace slam {

/// Thresholds of the maintenance rules. Defaults are ORB-SLAM2's for RGB-D (the source is named at
/// each); validate() throws std::invalid_argument naming the field.
struct MapMaintenanceSettings {
  // ---- map-point culling (LocalMapping.cc, MapPointCulling) --------------------------------------
  /// A recent point with found / visible under this is erased, ratio (ORB-SLAM2: 0.25).
  double min_found_ratio = 0.25;
  /// From this many keyframes after its creating keyframe on, a recent point needs more weighted
  /// observations than young_point_max_weighted_observations, keyframes (ORB-SLAM2: 2).
  int young_point_age_keyframes = 2;
  /// Weighted observations (2 per keypoint with depth, 1 without) at or under which an old enough recent
  /// point is erased, count (ORB-SLAM2 cnThObs: 3 for stereo/RGB-D, 2 for monocular).
  int young_point_max_weighted_observations = 3;
  /// A recent point this many keyframes old leaves the recent list (it is mature), keyframes (ORB-SLAM2: 3).
  int mature_point_age_keyframes = 3;

  // ---- fusion (LocalMapping.cc SearchInNeighbors, ORBmatcher.cc Fuse) -----------------------------
  int fuse_covisible_keyframes = 10;  ///< first neighbours: most covisible, count (ORB-SLAM2 nn: 10 stereo/RGB-D)
  int fuse_second_neighbours = 5;     ///< second neighbours per first neighbour, count (ORB-SLAM2: 5)
  /// Search radius around the projection: this times scale_factor^octave of the candidate keypoint,
  /// pixels (ORBmatcher::Fuse th: 3).
  double fuse_radius_px = 3.0;
  /// Reprojection test: squared pixel error / (scale_factor^octave)^2 under this, chi2 2 dof 95%
  /// (ORBmatcher::Fuse: 5.99 for a keypoint without a right-image coordinate, which ours never carry).
  double fuse_chi2 = 5.99;
  int fuse_max_hamming = 50;  ///< largest descriptor distance of a fusion, bits (ORBmatcher TH_LOW: 50)

  // ---- keyframe culling (LocalMapping.cc KeyFrameCulling) ------------------------------------------
  /// Only points whose keypoint depth is in (0, close_depth_m] count, metres. ORB-SLAM2: ThDepth = 40
  /// baselines of bf = 40 px m, i.e. 40 * 40 / fx = 2.99 m for TUM fr3 (fx 535.4), 3.09 m for fr1.
  double close_depth_m = 3.0;
  /// Other keyframes that must see a point for it to be redundant, count (ORB-SLAM2 thObs: 3).
  int redundant_min_observers = 3;
  /// Those observers must see it at octave <= the keyframe's octave + this (ORB-SLAM2: 1).
  int redundant_octave_tolerance = 1;
  /// Culled when more than this fraction of its counted points are redundant (ORB-SLAM2: 0.9).
  double redundant_fraction = 0.9;

  // ---- triangulation (LocalMapping.cc CreateNewMapPoints, ORBmatcher.cc SearchForTriangulation) ----
  int triangulation_neighbours = 10;   ///< most covisible keyframes paired with the new one (ORB-SLAM2 nn: 10)
  int triangulation_max_hamming = 50;  ///< bits (ORBmatcher TH_LOW: 50)
  /// Best distance < ratio * second best among the candidates on the epipolar line (ORB-SLAM2 builds
  /// this matcher with nnratio 0.6; its search restricts candidates by vocabulary node instead).
  double triangulation_ratio = 0.6;
  /// Distance to the epipolar line: squared / sigma^2 of the second keypoint under this, chi2 1 dof
  /// 95% (ORBmatcher::CheckDistEpipolarLine: 3.84).
  double triangulation_epipolar_chi2 = 3.84;
  /// A keypoint within this times scale_factor^octave pixels of the epipole is skipped, pixels
  /// (SearchForTriangulation: squared distance < 100 * scale factor of the level).
  double triangulation_epipole_px = 10.0;
  double triangulation_chi2 = 5.991;  ///< reprojection in both views, chi2 2 dof 95% (CreateNewMapPoints: 5.991)
  /// Rays closer than this cosine give no point: too little parallax (CreateNewMapPoints: 0.9998).
  double triangulation_max_parallax_cos = 0.9998;
  /// Distance ratio vs octave ratio tolerance, times scale_factor (CreateNewMapPoints ratioFactor: 1.5).
  double triangulation_scale_tolerance = 1.5;
  /// A neighbour whose baseline is under this fraction of its median point depth is skipped
  /// (CreateNewMapPoints, monocular case: 0.01).
  double triangulation_min_baseline_ratio = 0.01;

  void validate() const;
};

/// Weighted observation count as ORB-SLAM2 counts it for RGB-D: 2 for an observation whose keypoint
/// has depth, 1 for one without.
int weighted_observations(const Map& map, const MapPoint& point);

/// What cull_recent_map_points did.
struct MapPointCullingReport {
  int checked = 0;                   ///< entries of the recent list examined
  int dropped_bad = 0;               ///< already bad: left the list
  int erased_low_found_ratio = 0;    ///< found / visible < min_found_ratio
  int erased_few_observations = 0;   ///< old enough, too few weighted observations
  int matured = 0;                   ///< old enough and kept: left the list
  std::vector<std::int64_t> erased;  ///< in list order
};

/// ORB-SLAM2's MapPointCulling over `recent` (ids of recently created points, in the caller's order),
/// seen from the keyframe just inserted (`current_keyframe`). Per entry: bad -> leaves the list;
/// found / visible < min_found_ratio -> erased; else (current_keyframe - created_by_keyframe) >=
/// young_point_age_keyframes and weighted_observations <= young_point_max_weighted_observations ->
/// erased; else >= mature_point_age_keyframes keyframes old -> leaves the list; else stays. Erased
/// points leave the list too; the rest keep their order. Throws std::invalid_argument (before
/// changing anything) for an unknown keyframe, an unknown point or a point without created_by_keyframe.
MapPointCullingReport cull_recent_map_points(Map& map, std::vector<std::int64_t>& recent, int current_keyframe,
                                             const MapMaintenanceSettings& settings);

/// What fuse_map_points did.
struct FusionReport {
  std::vector<int> targets;    ///< the neighbour keyframes, ascending id
  int projections = 0;         ///< points projected inside a keyframe's image (both directions)
  int observations_added = 0;  ///< a point gained a keypoint that saw no point
  int points_replaced = 0;     ///< duplicates merged by replace_map_point
};

/// ORB-SLAM2's SearchInNeighbors, serial. Targets: the keyframe's fuse_covisible_keyframes most
/// covisible keyframes plus each one's fuse_second_neighbours most covisible, without the keyframe
/// itself, each once, ascending id. First the keyframe's points (as they were on entry, skipping
/// those gone bad) are projected into each target in turn, then the targets' points (ascending id,
/// not bad, not yet observed by the keyframe) into the keyframe. A projection needs z > 0 and a pixel
/// inside `image_size`; candidates are static keypoints within fuse_radius_px * s^octave of it with
/// chi2 = d^2 / s^(2 octave) < fuse_chi2 (s = orb_scale_factor), and the nearest descriptor wins
/// (ties: smaller keypoint index) if within fuse_max_hamming. When the winner already observes a
/// point, the one with more weighted observations stays (ties: the projected point, as ORB-SLAM2)
/// and the other is replaced; otherwise the projected point gains the observation. No distance or
/// viewing-angle check (the points carry no scale range or normal). Throws std::invalid_argument for
/// an unknown or culled keyframe, an empty image size or orb_scale_factor < 1.
FusionReport fuse_map_points(Map& map, int keyframe_id, const PinholeIntrinsics<double>& intrinsics,
                             const cv::Size& image_size, double orb_scale_factor,
                             const MapMaintenanceSettings& settings);

/// What cull_redundant_keyframes did.
struct KeyframeCullingReport {
  std::vector<int> examined;  ///< covisible keyframes examined, ascending id
  std::vector<int> culled;    ///< culled, ascending id
};

/// ORB-SLAM2's KeyFrameCulling for the covisible keyframes of `keyframe_id` (never keyframe 0 nor
/// keyframe_id), ascending id, each judged on the map as the culls before it left it. Of a keyframe's
/// points whose keypoint depth is in (0, close_depth_m], those observed by at least
/// redundant_min_observers other keyframes at octave <= its octave + redundant_octave_tolerance are
/// redundant; with more than redundant_fraction of them redundant, the keyframe is culled with its
/// most covisible keyframe as parent. Throws std::invalid_argument for an unknown or culled keyframe.
KeyframeCullingReport cull_redundant_keyframes(Map& map, int keyframe_id, const MapMaintenanceSettings& settings);

/// What triangulate_new_points did.
struct TriangulationReport {
  std::vector<int> neighbours;        ///< keyframes paired with the new one, ascending id
  int matches = 0;                    ///< descriptor matches passing the epipolar and ratio tests
  std::vector<std::int64_t> created;  ///< new map points, in creation order (add them to the recent list)
};

/// ORB-SLAM2's CreateNewMapPoints for keypoints without depth: between the keyframe and each of its
/// triangulation_neighbours most covisible keyframes (ascending id; skipped when the baseline is
/// under triangulation_min_baseline_ratio of the neighbour's median point depth), static keypoints
/// that observe no point and have no depth are matched by descriptor (nearest within
/// triangulation_max_hamming among those within the epipolar band and away from the epipole, best <
/// triangulation_ratio * second best, each neighbour keypoint used once, keyframe keypoints in index
/// order), triangulated linearly (DLT) and kept when in front of both cameras, with enough parallax
/// (cosine < triangulation_max_parallax_cos), a reprojection chi2 < triangulation_chi2 in both views
/// and distances consistent with the octaves. Each new point (descriptor of the keyframe's keypoint,
/// created_by_keyframe = keyframe_id) is observed by both keypoints. Deviation from ORB-SLAM2: it
/// matches within vocabulary nodes; this searches all candidates of the neighbour with the ratio test
/// (no vocabulary needed). Throws std::invalid_argument for an unknown or culled keyframe or
/// orb_scale_factor < 1.
TriangulationReport triangulate_new_points(Map& map, int keyframe_id, const PinholeIntrinsics<double>& intrinsics,
                                           double orb_scale_factor, const MapMaintenanceSettings& settings);

}  // namespace slam
}  // namespace cge
