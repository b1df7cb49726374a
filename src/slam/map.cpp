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

void Map::check_live_point(std::int64_t id, const char* where) const {
  check_point(id, where);
  if (points_[static_cast<std::size_t>(id)].bad) {
    throw std::invalid_argument(std::string(where) + ": map point " + std::to_string(id) + " is bad (erased)");
  }
}

void Map::check_live_keyframe(int id, const char* where) const {
  check_keyframe(id, where);
  if (keyframes_[static_cast<std::size_t>(id)].culled) {
    throw std::invalid_argument(std::string(where) + ": keyframe " + std::to_string(id) + " is culled");
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
  if (keyframe.undistorted_px.empty()) {
    keyframe.undistorted_px.reserve(n);
    for (const cv::KeyPoint& kp : keyframe.keypoints) keyframe.undistorted_px.push_back(kp.pt);
  }
  if (static_cast<std::size_t>(keyframe.descriptors.rows) != n || keyframe.labels.size() != n ||
      keyframe.points_camera_m.size() != n || keyframe.map_point_ids.size() != n ||
      keyframe.undistorted_px.size() != n) {
    throw std::invalid_argument("Map::add_keyframe: the keyframe of frame " + std::to_string(keyframe.frame_index) +
                                " has per-keypoint vectors of different lengths");
  }
  if (n > 0 && (keyframe.descriptors.cols != 32 || keyframe.descriptors.type() != CV_8UC1)) {
    throw std::invalid_argument("Map::add_keyframe: the keyframe of frame " + std::to_string(keyframe.frame_index) +
                                " needs one 32-byte CV_8UC1 descriptor row (ORB) per keypoint");
  }
  if (std::any_of(keyframe.map_point_ids.begin(), keyframe.map_point_ids.end(),
                  [](std::int64_t p) { return p != -1; })) {
    throw std::invalid_argument("Map::add_keyframe: map_point_ids must be -1; use add_observation");
  }
  if (keyframe.culled) {
    throw std::invalid_argument("Map::add_keyframe: the keyframe of frame " + std::to_string(keyframe.frame_index) +
                                " is marked culled; use cull_keyframe");
  }
  keyframe.id = keyframe_count();
  keyframe.parent = -1;
  keyframe.T_parent_camera = Eigen::Isometry3d::Identity();
  keyframes_.push_back(std::move(keyframe));
  covisibility_.emplace_back();
  culled_children_.emplace_back();
  return keyframes_.back().id;
}

std::int64_t Map::add_map_point(const Eigen::Vector3d& position_world, const cv::Mat& descriptor,
                                int created_by_keyframe) {
  if (descriptor.rows != 1 || descriptor.cols != 32 || descriptor.type() != CV_8UC1) {
    throw std::invalid_argument("Map::add_map_point: the descriptor must be one 32-byte CV_8UC1 row (ORB)");
  }
  if (created_by_keyframe != -1) check_keyframe(created_by_keyframe, "Map::add_map_point (created_by_keyframe)");
  MapPoint p;
  p.id = map_point_count();
  p.position_world = position_world;
  p.descriptor = descriptor.clone();
  p.created_by_keyframe = created_by_keyframe;
  points_.push_back(std::move(p));
  return points_.back().id;
}

void Map::add_observation(std::int64_t point_id, int keyframe_id, int keypoint_index) {
  check_live_point(point_id, "Map::add_observation");
  check_live_keyframe(keyframe_id, "Map::add_observation");
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

void Map::increase_visible(std::int64_t id, int n) {
  check_point(id, "Map::increase_visible");
  if (n < 0) throw std::invalid_argument("Map::increase_visible: n = " + std::to_string(n) + " is negative");
  points_[static_cast<std::size_t>(id)].visible += n;
}

void Map::increase_found(std::int64_t id, int n) {
  check_point(id, "Map::increase_found");
  if (n < 0) throw std::invalid_argument("Map::increase_found: n = " + std::to_string(n) + " is negative");
  points_[static_cast<std::size_t>(id)].found += n;
}

namespace {

/// One shared point fewer between a row's keyframe and `other`; the entry goes at 0.
void lower_covisibility(std::map<int, int>& row, int other) {
  const auto it = row.find(other);
  if (it == row.end() || it->second <= 0) throw std::logic_error("Map: covisibility out of step with observations");
  if (--it->second == 0) row.erase(it);
}

}  // namespace

void Map::unlink(const MapPoint& p, int k) {
  for (const Observation& o : p.observations) {
    if (o.keyframe_id == k) continue;
    lower_covisibility(covisibility_[static_cast<std::size_t>(k)], o.keyframe_id);
    lower_covisibility(covisibility_[static_cast<std::size_t>(o.keyframe_id)], k);
  }
}

void Map::erase_observation(std::int64_t point_id, int keyframe_id) {
  check_point(point_id, "Map::erase_observation");
  check_keyframe(keyframe_id, "Map::erase_observation");
  MapPoint& p = points_[static_cast<std::size_t>(point_id)];
  const auto it = std::find_if(p.observations.begin(), p.observations.end(),
                               [&](const Observation& o) { return o.keyframe_id == keyframe_id; });
  if (it == p.observations.end()) {
    throw std::invalid_argument("Map::erase_observation: keyframe " + std::to_string(keyframe_id) +
                                " does not observe map point " + std::to_string(point_id));
  }
  unlink(p, keyframe_id);
  keyframes_[static_cast<std::size_t>(keyframe_id)].map_point_ids[static_cast<std::size_t>(it->keypoint_index)] = -1;
  p.observations.erase(it);
  if (p.observations.empty() && !p.bad) {
    p.bad = true;
    ++bad_points_;
  }
}

void Map::erase_map_point(std::int64_t id) {
  check_point(id, "Map::erase_map_point");
  MapPoint& p = points_[static_cast<std::size_t>(id)];
  if (p.bad) return;
  // Last observation first: each erase is then a pop from the back.
  while (!p.observations.empty()) erase_observation(id, p.observations.back().keyframe_id);
  if (!p.bad) {  // a point that never had an observation
    p.bad = true;
    ++bad_points_;
  }
}

void Map::replace_map_point(std::int64_t old_id, std::int64_t keep_id) {
  check_live_point(old_id, "Map::replace_map_point");
  check_live_point(keep_id, "Map::replace_map_point");
  if (old_id == keep_id) {
    throw std::invalid_argument("Map::replace_map_point: map point " + std::to_string(old_id) +
                                " cannot replace itself");
  }
  const std::vector<Observation> moved = points_[static_cast<std::size_t>(old_id)].observations;
  for (const Observation& o : moved) {
    // Each step keeps covisibility exact on its own: the old point leaves the keyframe, then the kept
    // point enters it unless that keyframe sees it already.
    erase_observation(old_id, o.keyframe_id);
    const auto& keep_obs = points_[static_cast<std::size_t>(keep_id)].observations;
    const bool seen = std::any_of(keep_obs.begin(), keep_obs.end(),
                                  [&](const Observation& k) { return k.keyframe_id == o.keyframe_id; });
    if (!seen) add_observation(keep_id, o.keyframe_id, o.keypoint_index);
  }
  MapPoint& old_point = points_[static_cast<std::size_t>(old_id)];
  MapPoint& keep = points_[static_cast<std::size_t>(keep_id)];
  keep.visible += old_point.visible;
  keep.found += old_point.found;
  if (!old_point.bad) {  // an old point without observations
    old_point.bad = true;
    ++bad_points_;
  }
}

void Map::cull_keyframe(int id, int parent) {
  check_live_keyframe(id, "Map::cull_keyframe");
  check_live_keyframe(parent, "Map::cull_keyframe (parent)");
  if (id == 0) throw std::invalid_argument("Map::cull_keyframe: keyframe 0 fixes the world and is never culled");
  if (parent == id) {
    throw std::invalid_argument("Map::cull_keyframe: keyframe " + std::to_string(id) + " cannot be its own parent");
  }
  Keyframe& kf = keyframes_[static_cast<std::size_t>(id)];
  for (const std::int64_t p : std::vector<std::int64_t>(kf.map_point_ids)) {
    if (p >= 0) erase_observation(p, id);
  }
  const Keyframe& parent_kf = keyframes_[static_cast<std::size_t>(parent)];
  kf.culled = true;
  kf.parent = parent;
  kf.T_parent_camera = parent_kf.T_world_camera.inverse() * kf.T_world_camera;
  // From now on the stored pose is the resolved one (set_keyframe_pose keeps it so).
  kf.T_world_camera = parent_kf.T_world_camera * kf.T_parent_camera;
  culled_children_[static_cast<std::size_t>(parent)].push_back(id);
  ++culled_keyframes_;
  move_culled_children(id);
}

Eigen::Isometry3d Map::keyframe_pose(int id) const {
  check_keyframe(id, "Map::keyframe_pose");
  // Culled keyframes from `id` up to the first live ancestor; parents are live when assigned and
  // never revive, so the chain ends.
  std::vector<int> chain;
  int k = id;
  while (keyframes_[static_cast<std::size_t>(k)].culled) {
    chain.push_back(k);
    k = keyframes_[static_cast<std::size_t>(k)].parent;
  }
  Eigen::Isometry3d T = keyframes_[static_cast<std::size_t>(k)].T_world_camera;
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    T = T * keyframes_[static_cast<std::size_t>(*it)].T_parent_camera;
  }
  return T;
}

void Map::set_keyframe_pose(int id, const Eigen::Isometry3d& T_world_camera) {
  check_keyframe(id, "Map::set_keyframe_pose");
  if (keyframes_[static_cast<std::size_t>(id)].culled) {
    throw std::invalid_argument("Map::set_keyframe_pose: keyframe " + std::to_string(id) +
                                " is culled; its pose follows keyframe " +
                                std::to_string(keyframes_[static_cast<std::size_t>(id)].parent));
  }
  keyframes_[static_cast<std::size_t>(id)].T_world_camera = T_world_camera;
  move_culled_children(id);
}

void Map::move_culled_children(int id) {
  // The culled keyframes below `id`, parents before children (the products keyframe_pose forms).
  std::vector<int> stack(culled_children_[static_cast<std::size_t>(id)].rbegin(),
                         culled_children_[static_cast<std::size_t>(id)].rend());
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    Keyframe& child = keyframes_[static_cast<std::size_t>(c)];
    child.T_world_camera = keyframes_[static_cast<std::size_t>(child.parent)].T_world_camera * child.T_parent_camera;
    const auto& grandchildren = culled_children_[static_cast<std::size_t>(c)];
    stack.insert(stack.end(), grandchildren.rbegin(), grandchildren.rend());
  }
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
