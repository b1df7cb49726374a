#pragma once
// Map: the keyframes and map points of the reference pipeline, with covisibility (keyframes that
// observe common map points). It implements KeyframeDatabaseView for the loop closer.
//
// Ids: keyframe ids are 0, 1, 2, ... in insertion order (the index in keyframes()); map point ids
// likewise (the index in map_points()). Nothing is ever removed from the containers, so ids stay
// valid and every container is ordered by id (deterministic iteration). Map maintenance
// (cge/slam/map_maintenance.hpp) retires entries in place instead: an erased map point is marked
// `bad` and has no observations; a culled keyframe observes no map point and its pose follows its
// parent keyframe (keyframe_pose). Neither ever shows up in covisible_keyframes.
//
// Covisibility is exact at all times: shared_points(a, b) is the number of map points that both a
// and b observe, whatever sequence of add / erase / replace / cull led there.
#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/slam/keyframe.hpp"
#include "cge/slam/keyframe_database_view.hpp"

namespace cge {
namespace slam {

/// One keyframe's observation of a map point: the keypoint that sees it.
struct Observation {
  int keyframe_id = -1;
  int keypoint_index = -1;
};

struct MapPoint {
  std::int64_t id = -1;
  Eigen::Vector3d position_world = Eigen::Vector3d::Zero();  ///< metres
  cv::Mat descriptor;                     ///< 1 x 32 CV_8UC1: the descriptor of the keypoint that created the point
  std::vector<Observation> observations;  ///< in insertion order
  int created_by_keyframe = -1;           ///< the keyframe whose insertion made the point, -1: not recorded
  /// Frames in whose view the point was predicted (ORB-SLAM2's mnVisible), count >= 1.
  int visible = 1;
  /// Frames in which it was matched as an inlier (ORB-SLAM2's mnFound), count >= 1.
  int found = 1;
  bool bad = false;  ///< erased: no observations, never observed again
};

class Map final : public KeyframeDatabaseView {
 public:
  // ---- KeyframeDatabaseView -------------------------------------------------------------------------
  int keyframe_count() const override { return static_cast<int>(keyframes_.size()); }
  const Keyframe& keyframe(int id) const override;
  /// Keyframes sharing at least one map point with `id`, most shared first, ties by smaller id.
  /// Never lists a culled keyframe (it shares nothing); a culled `id` has none.
  std::vector<int> covisible_keyframes(int id, int max_count) const override;

  // ---- building ---------------------------------------------------------------------------------
  /// Adds a keyframe, assigning its id (returned) and checking that its per-keypoint vectors agree
  /// and that its descriptors are 32-byte CV_8UC1 rows (ORB).
  /// Its map_point_ids must be all -1 (observations are added with add_observation); they are
  /// resized to the keypoint count when empty. undistorted_px, when empty, is filled from the
  /// keypoints' positions (a camera without distortion). It must not be culled (its parent and
  /// T_parent_camera are reset). Throws std::invalid_argument otherwise.
  int add_keyframe(Keyframe keyframe);
  /// A new map point (without observations); returns its id. The descriptor must be one 32-byte
  /// CV_8UC1 row (ORB), as the matching reads it. `created_by_keyframe` is -1 or an
  /// existing keyframe (the one whose insertion made it: the age used by map-point culling).
  std::int64_t add_map_point(const Eigen::Vector3d& position_world, const cv::Mat& descriptor,
                             int created_by_keyframe = -1);
  /// Records that keypoint `keypoint_index` of keyframe `keyframe_id` sees map point `point_id`
  /// (sets the keyframe's map_point_ids entry, updates covisibility). Throws std::invalid_argument
  /// for unknown ids, a bad point, a culled keyframe, a keypoint that already observes a point, or a
  /// point the keyframe already observes through another keypoint.
  void add_observation(std::int64_t point_id, int keyframe_id, int keypoint_index);

  /// Counters of the found ratio (found / visible) used by map-point culling; n >= 0.
  void increase_visible(std::int64_t id, int n = 1);
  void increase_found(std::int64_t id, int n = 1);

  // ---- maintenance (ids stay: points are marked bad, keyframes culled) -----------------------------
  /// Removes keyframe `keyframe_id`'s observation of `point_id`: frees the keyframe's slot and lowers
  /// covisibility (a pair that shares no point any more is no longer covisible). A point left without
  /// observations is bad. Throws std::invalid_argument when the keyframe does not observe the point.
  void erase_observation(std::int64_t point_id, int keyframe_id);
  /// Erases every observation of the point and marks it bad (nothing to do for a bad point).
  void erase_map_point(std::int64_t id);
  /// Fusion of duplicates: every observation of `old_id` moves to `keep_id`, except where that
  /// keyframe already observes `keep_id` (that observation is dropped); visible and found are summed
  /// into `keep_id`; `old_id` ends bad. Throws std::invalid_argument for equal ids or a bad point.
  void replace_map_point(std::int64_t old_id, std::int64_t keep_id);
  /// Culls keyframe `id` as redundant: erases all its observations (points left with none become
  /// bad), marks it culled and keeps its pose relative to `parent` (T_parent_camera =
  /// pose(parent)^-1 * pose(id)). Throws std::invalid_argument for keyframe 0, an unknown or culled
  /// `id`, an unknown or culled `parent`, or parent == id.
  void cull_keyframe(int id, int parent);

  // ---- optimisation (pose-graph optimisation and bundle adjustment move these) --------------------
  /// Moves a live keyframe; the culled keyframes hanging from it (directly or through other culled
  /// ones) move with it, so keyframe(k).T_world_camera equals keyframe_pose(k) for every k. Throws
  /// std::invalid_argument for a culled keyframe (its pose follows its parent).
  void set_keyframe_pose(int id, const Eigen::Isometry3d& T_world_camera);
  void set_map_point_position(std::int64_t id, const Eigen::Vector3d& position_world);

  // ---- reading ----------------------------------------------------------------------------------
  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  const std::vector<MapPoint>& map_points() const { return points_; }
  const MapPoint& map_point(std::int64_t id) const;
  /// All map points ever made, bad ones included (the id range).
  std::int64_t map_point_count() const { return static_cast<std::int64_t>(points_.size()); }
  /// Map points that are not bad.
  std::int64_t active_map_point_count() const { return map_point_count() - bad_points_; }
  /// Keyframes that are not culled.
  int active_keyframe_count() const { return keyframe_count() - culled_keyframes_; }
  /// T_world_camera of keyframe `id`: its own pose when live; for a culled one, its parent's
  /// keyframe_pose times T_parent_camera (resolved along the chain of parents).
  Eigen::Isometry3d keyframe_pose(int id) const;
  /// Map points shared by keyframes a and b (0 for a == b or no common point).
  int shared_points(int a, int b) const;
  /// Map points a keyframe observes.
  int observed_points(int id) const;

 private:
  void check_keyframe(int id, const char* where) const;
  void check_point(std::int64_t id, const char* where) const;
  void check_live_point(std::int64_t id, const char* where) const;
  void check_live_keyframe(int id, const char* where) const;
  /// Lowers the covisibility of keyframe k with every other observer of p by one.
  void unlink(const MapPoint& p, int k);
  /// Recomputes the stored poses of the culled keyframes hanging from `id` (parent pose * T_parent_camera).
  void move_culled_children(int id);

  std::vector<Keyframe> keyframes_;
  std::vector<MapPoint> points_;
  std::vector<std::map<int, int>> covisibility_;   // per keyframe: other keyframe id -> shared points (> 0)
  std::vector<std::vector<int>> culled_children_;  // per keyframe: culled keyframes whose parent it is
  int culled_keyframes_ = 0;
  std::int64_t bad_points_ = 0;
};

}  // namespace slam
}  // namespace cge
