#include "cge/slam/map.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace cge {
namespace slam {

void Map::check_keyframe(int id, const char* where) const {
  if (id < 0 || id >= keyframe_count()) {
    throw std::invalid_argument(std::string(where) + ": keyframe " + std::to_string(id) + " is not in 0 .. " +
                                std::to_string(keyframe_count() - 1));
  }
}

void Map::check_point(std::int64_t id, const char* where) const {
  if (id < 0 || id >= map_point_count()) {
    throw std::invalid_argument(std::string(where) + ": map point " + std::to_string(id) + " is not in 0 .. " +
                                std::to_string(map_point_count() - 1));
  }
}

const Keyframe& Map::keyframe(int id) const {
  check_keyframe(id, "Map::keyframe");
  return keyframes_[static_cast<std::size_t>(id)];
}

const MapPoint& Map::map_point(std::int64_t id) const {
  check_point(id, "Map::map_point");
  return points_[static_cast<std::size_t>(id)];
}

std::vector<int> Map::covisible_keyframes(int id, int max_count) const {
  check_keyframe(id, "Map::covisible_keyframes");
  std::vector<std::pair<int, int>> ranked;  // (shared, other id)
  for (const auto& entry : covisibility_[static_cast<std::size_t>(id)]) ranked.emplace_back(entry.second, entry.first);
  std::sort(ranked.begin(), ranked.end(), [](const std::pair<int, int>& a, const std::pair<int, int>& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  std::vector<int> ids;
  for (const auto& r : ranked) {
    if (max_count >= 0 && static_cast<int>(ids.size()) >= max_count) break;
    ids.push_back(r.second);
  }
  return ids;
}

int Map::add_keyframe(Keyframe keyframe) {
  const std::size_t n = keyframe.keypoints.size();
  if (keyframe.map_point_ids.empty()) keyframe.map_point_ids.assign(n, -1);
  if (static_cast<std::size_t>(keyframe.descriptors.rows) != n || keyframe.labels.size() != n ||
      keyframe.points_camera_m.size() != n || keyframe.map_point_ids.size() != n) {
    throw std::invalid_argument("Map::add_keyframe: the keyframe of frame " + std::to_string(keyframe.frame_index) +
                                " has per-keypoint vectors of different lengths");
  }
  if (std::any_of(keyframe.map_point_ids.begin(), keyframe.map_point_ids.end(),
                  [](std::int64_t p) { return p != -1; })) {
    throw std::invalid_argument("Map::add_keyframe: map_point_ids must be -1; use add_observation");
  }
  keyframe.id = keyframe_count();
  keyframes_.push_back(std::move(keyframe));
  covisibility_.emplace_back();
  return keyframes_.back().id;
}

std::int64_t Map::add_map_point(const Eigen::Vector3d& position_world, const cv::Mat& descriptor) {
  if (descriptor.rows != 1 || descriptor.type() != CV_8UC1) {
    throw std::invalid_argument("Map::add_map_point: the descriptor must be one CV_8UC1 row");
  }
  MapPoint p;
  p.id = map_point_count();
  p.position_world = position_world;
  p.descriptor = descriptor.clone();
  points_.push_back(std::move(p));
  return points_.back().id;
}

void Map::add_observation(std::int64_t point_id, int keyframe_id, int keypoint_index) {
  check_point(point_id, "Map::add_observation");
  check_keyframe(keyframe_id, "Map::add_observation");
  Keyframe& kf = keyframes_[static_cast<std::size_t>(keyframe_id)];
  if (keypoint_index < 0 || keypoint_index >= static_cast<int>(kf.keypoints.size())) {
    throw std::invalid_argument("Map::add_observation: keypoint " + std::to_string(keypoint_index) +
                                " is not in keyframe " + std::to_string(keyframe_id));
  }
  std::int64_t& slot = kf.map_point_ids[static_cast<std::size_t>(keypoint_index)];
  if (slot != -1) {
    throw std::invalid_argument("Map::add_observation: keypoint " + std::to_string(keypoint_index) + " of keyframe " +
                                std::to_string(keyframe_id) + " already observes map point " + std::to_string(slot));
  }
  MapPoint& p = points_[static_cast<std::size_t>(point_id)];
  for (const Observation& o : p.observations) {
    if (o.keyframe_id == keyframe_id) {
      throw std::invalid_argument("Map::add_observation: keyframe " + std::to_string(keyframe_id) +
                                  " already observes map point " + std::to_string(point_id));
    }
  }
  for (const Observation& o : p.observations) {
    ++covisibility_[static_cast<std::size_t>(keyframe_id)][o.keyframe_id];
    ++covisibility_[static_cast<std::size_t>(o.keyframe_id)][keyframe_id];
  }
  p.observations.push_back(Observation{keyframe_id, keypoint_index});
  slot = point_id;
}

void Map::set_keyframe_pose(int id, const Eigen::Isometry3d& T_world_camera) {
  check_keyframe(id, "Map::set_keyframe_pose");
  keyframes_[static_cast<std::size_t>(id)].T_world_camera = T_world_camera;
}

void Map::set_map_point_position(std::int64_t id, const Eigen::Vector3d& position_world) {
  check_point(id, "Map::set_map_point_position");
  points_[static_cast<std::size_t>(id)].position_world = position_world;
}

int Map::shared_points(int a, int b) const {
  check_keyframe(a, "Map::shared_points");
  check_keyframe(b, "Map::shared_points");
  const auto& row = covisibility_[static_cast<std::size_t>(a)];
  const auto it = row.find(b);
  return it == row.end() ? 0 : it->second;
}

int Map::observed_points(int id) const {
  check_keyframe(id, "Map::observed_points");
  const auto& ids = keyframes_[static_cast<std::size_t>(id)].map_point_ids;
  return static_cast<int>(std::count_if(ids.begin(), ids.end(), [](std::int64_t p) { return p >= 0; }));
}

}  // namespace slam
}  // namespace cge
