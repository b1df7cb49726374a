#pragma once
// Map: the keyframes and map points of the reference pipeline, with covisibility (keyframes that
// observe common map points). It implements KeyframeDatabaseView for the loop closer.
//
// Ids: keyframe ids are 0, 1, 2, ... in insertion order (the index in keyframes()); map point ids
// likewise (the index in map_points()). Nothing is ever removed, so ids stay valid and every
// container is ordered by id (deterministic iteration).
#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Core>
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
};

class Map final : public KeyframeDatabaseView {
 public:
  // ---- KeyframeDatabaseView -------------------------------------------------------------------------
  int keyframe_count() const override { return static_cast<int>(keyframes_.size()); }
  const Keyframe& keyframe(int id) const override;
  /// Keyframes sharing at least one map point with `id`, most shared first, ties by smaller id.
  std::vector<int> covisible_keyframes(int id, int max_count) const override;

  // ---- building ---------------------------------------------------------------------------------
  /// Adds a keyframe, assigning its id (returned) and checking that its per-keypoint vectors agree.
  /// Its map_point_ids must be all -1 (observations are added with add_observation); they are
  /// resized to the keypoint count when empty. Throws std::invalid_argument otherwise.
  int add_keyframe(Keyframe keyframe);
  /// A new map point (without observations); returns its id.
  std::int64_t add_map_point(const Eigen::Vector3d& position_world, const cv::Mat& descriptor);
  /// Records that keypoint `keypoint_index` of keyframe `keyframe_id` sees map point `point_id`
  /// (sets the keyframe's map_point_ids entry, updates covisibility). Throws std::invalid_argument
  /// for unknown ids, a keypoint that already observes a point, or a point the keyframe already
  /// observes through another keypoint.
  void add_observation(std::int64_t point_id, int keyframe_id, int keypoint_index);

  // ---- optimisation (pose-graph optimisation and bundle adjustment move these) --------------------
  void set_keyframe_pose(int id, const Eigen::Isometry3d& T_world_camera);
  void set_map_point_position(std::int64_t id, const Eigen::Vector3d& position_world);

  // ---- reading ----------------------------------------------------------------------------------
  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  const std::vector<MapPoint>& map_points() const { return points_; }
  const MapPoint& map_point(std::int64_t id) const;
  std::int64_t map_point_count() const { return static_cast<std::int64_t>(points_.size()); }
  /// Map points shared by keyframes a and b (0 for a == b or no common point).
  int shared_points(int a, int b) const;
  /// Map points a keyframe observes.
  int observed_points(int id) const;

 private:
  void check_keyframe(int id, const char* where) const;
  void check_point(std::int64_t id, const char* where) const;

  std::vector<Keyframe> keyframes_;
  std::vector<MapPoint> points_;
  std::vector<std::map<int, int>> covisibility_;  // per keyframe: other keyframe id -> shared points
};

}  // namespace slam
}  // namespace cge
