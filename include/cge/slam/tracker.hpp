#pragma once
// Tracker: the camera pose of each frame against the map (docs/METHOD.md section 8). Per frame:
// constant-velocity prediction; projection of the local map's points (those seen by the last
// keyframes and by the reference keyframe's covisible ones) into the frame and matching to its
// static keypoints by descriptor in a window; a first pose by RANSAC on those matches (hypotheses
// from three matches with depth fitted in 3-D, or EPnP: TrackerSettings::ransac_solver; or, with
// ransac_only_on_failure, refined from the prediction and RANSAC only when that fails); a
// second search from that pose and refinement by minimising reprojection error; a quality check.
// A failure at the normal search radius is retried once with the wide radius (a wrong prediction
// gives enough matches, most of them wrong, so the count alone does not reveal it). When both fail, odometry against the previous
// frame (its static keypoints with depth as temporary points, as ORB-SLAM2's RGB-D motion model):
// on a fast turn the view leaves the keyframes' map within a frame or two, and the few map points
// the odometry pose still matches trigger the keyframe policy's tracking guard. When that fails too: relocalisation
// against candidate keyframes (descriptor matching + PnP, then the local map around the candidate): the last keyframes
// and, when a candidate source is set (the System's bag-of-words database), the keyframes most alike anywhere in the
// map, as ORB-SLAM2 does; else the frame is reported lost. The first frame (empty map) is reported `initialised` at the
// identity pose: the System makes it the first keyframe with map points from depth (RGB-D needs no two-view
// initialisation).
//
// Refinement: PoseRefiner (cge/ceres/pose_refinement.hpp) on every match from the first pose; its
// chi2 classification gives the inliers.
//
// Deterministic: the rigid RANSAC draws from a seeded splitmix64 and cv::solvePnPRansac from its own
// fixed-seed generator, matching visits map points and keypoints in id order, Ceres runs
// single-threaded.
#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Geometry>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/frame.hpp"
#include "cge/slam/geometry/projection_matching.hpp"
#include "cge/slam/map.hpp"
#include "cge/slam/settings.hpp"

namespace cge {
namespace slam {

enum class TrackingState : std::uint8_t {
  initialised,  ///< first frame: the map starts here
  tracked,      ///< pose from the local map
  odometry,     ///< the local map failed: pose from the previous frame's points (frame-to-frame odometry)
  relocalised,  ///< pose from relocalisation after a failure
  lost,         ///< no pose
};

/// "initialised", "tracked", "odometry", "relocalised" or "lost".
const char* to_string(TrackingState state);

struct TrackResult {
  TrackingState state = TrackingState::lost;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  ///< meaningful unless lost
  int matches = 0;                                                   ///< map points matched before PnP
  int inliers = 0;  ///< matches consistent with the final pose (the tracked map points)
  /// Per keypoint of the frame: the map point it was matched to (inliers only), -1 otherwise.
  std::vector<std::int64_t> map_point_ids;
  /// The keyframe sharing most tracked points (the local map's centre); -1 when lost or initialised.
  int reference_keyframe = -1;
  /// The local map's points that the final pose puts inside the image (the last projection search),
  /// ascending id: map-point culling's "visible" count (found / visible).
  std::vector<std::int64_t> visible_map_points;

  bool has_pose() const { return state != TrackingState::lost; }
};

class Tracker {
 public:
  /// orb_scale_factor: the ORB pyramid's scale between levels (a keypoint of octave o has a pixel
  /// sigma of orb_scale_factor^o in the refinement).
  Tracker(const TrackerSettings& settings, const PinholeIntrinsics<double>& intrinsics, double orb_scale_factor = 1.2);

  /// The pose of `frame` (its static keypoints only are used) against `map`.
  TrackResult track(const Frame& frame, const Map& map);

  /// Tells the tracker about a keyframe just inserted from the frame it last tracked: it becomes
  /// the reference of the local map.
  void set_reference_keyframe(int keyframe_id) { reference_keyframe_ = keyframe_id; }
  int reference_keyframe() const { return reference_keyframe_; }

  /// Relocalisation candidates beyond the last keyframes: keyframe ids, most promising first
  /// (e.g. by bag-of-words score over all keyframes). Called only when tracking has failed.
  using CandidateSource = std::function<std::vector<int>(const Frame& frame)>;
  void set_relocalisation_candidates(CandidateSource source) { candidate_source_ = std::move(source); }

  /// The map was corrected (loop closure): the last tracked pose moves with it, so the next
  /// prediction lands in the corrected map. T_corrected_old maps old world coordinates to new ones.
  void apply_map_correction(const Eigen::Isometry3d& T_corrected_old) {
    T_world_last_ = T_corrected_old * T_world_last_;
  }

  const TrackerSettings& settings() const { return settings_; }

 private:
  struct Attempt;
  bool track_local_map(const Frame& frame, const Map& map, const Eigen::Isometry3d& prediction, Attempt& out) const;
  bool relocalise(const Frame& frame, const Map& map, Attempt& out) const;
  /// Odometry against the previous frame's static keypoints with depth; the map points agreeing
  /// with the resulting pose are the tracked ones.
  bool track_last_frame(const Frame& frame, const Map& map, const Eigen::Isometry3d& prediction, Attempt& out) const;
  void remember_last_frame(const Frame& frame);
  bool ransac_pose(const Frame& frame, const std::vector<int>& keypoints,
                   const std::vector<Eigen::Vector3d>& points_world, int min_inliers,
                   Eigen::Isometry3d& T_world_camera) const;
  /// ransac_pose with TrackingRansacSolver::rigid.
  bool rigid_ransac_pose(const Frame& frame, const std::vector<int>& keypoints,
                         const std::vector<Eigen::Vector3d>& points_world, int min_inliers,
                         Eigen::Isometry3d& T_world_camera) const;
  /// The projection search at radius_px with the tracker's descriptor tests.
  ProjectionSearch projection_search(double radius_px, bool require_in_image) const;
  /// `visible`, when given, receives the points that project into the image (ascending id).
  int match_by_projection(const Frame& frame, const Map& map, const std::vector<std::int64_t>& points,
                          const Eigen::Isometry3d& T_world_camera, double radius_px,
                          std::vector<std::int64_t>& matches, std::vector<std::int64_t>* visible = nullptr) const;
  bool ransac_pose(const Frame& frame, const Map& map, const std::vector<std::int64_t>& matches, int min_inliers,
                   Eigen::Isometry3d& T_world_camera) const;
  /// The keypoint's depth as a term of its refinement observation (refinement_depth_sigma_per_m).
  void add_depth(const Frame& frame, int keypoint, PoseObservation& o) const;
  bool refine_pose(const Frame& frame, const Map& map, const std::vector<std::int64_t>& matches,
                   const Eigen::Isometry3d& T_initial, int min_inliers, Attempt& out) const;
  bool refine_with_local_map(const Frame& frame, const Map& map, const std::vector<std::int64_t>& points,
                             const Eigen::Isometry3d& T_initial, Attempt& out) const;
  /// Points of the local map around keyframe `centre` (-1: none): the last keyframes, the centre
  /// and its most covisible keyframes.
  std::vector<std::int64_t> local_map_points(const Map& map, int centre) const;
  bool track_with_radius(const Frame& frame, const Map& map, const std::vector<std::int64_t>& points,
                         const Eigen::Isometry3d& prediction, double radius_px, Attempt& out) const;

  TrackerSettings settings_;
  PinholeIntrinsics<double> intrinsics_;
  double orb_scale_factor_;
  PoseRefiner refiner_;
  CandidateSource candidate_source_;
  /// The previous frame had a pose: the frame-to-frame motion is known (else the last pose is stale).
  bool last_has_pose_ = false;
  // The previous frame's static keypoints with depth (odometry fallback): camera-frame point (its
  // world position is T_world_last_ * point, so a map correction moves it too) and descriptor row.
  std::vector<Eigen::Vector3d> last_points_camera_m_;
  cv::Mat last_descriptors_;
  Eigen::Isometry3d T_world_last_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_last_current_velocity_ = Eigen::Isometry3d::Identity();  ///< last frame-to-frame motion
  int reference_keyframe_ = -1;
};

}  // namespace slam
}  // namespace cge
