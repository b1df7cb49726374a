#include "cge/slam/loop_correction.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "cge/ceres/bundle_adjustment.hpp"
#include "cge/ceres/pose_graph.hpp"
#include "cge/slam/local_mapping.hpp"

namespace cge {
namespace slam {

namespace {

/// A keyframe's nearest live ancestor (itself when live).
int live_ancestor(const Map& map, int k) {
  while (map.keyframe(k).culled) k = map.keyframe(k).parent;
  return k;
}

}  // namespace

LoopCorrection::LoopCorrection(const LoopCorrectionSettings& settings, const PinholeIntrinsics<double>& intrinsics,
                               double orb_scale_factor)
    : settings_(settings), intrinsics_(intrinsics), orb_scale_factor_(orb_scale_factor) {
  settings_.validate();
  if (!(intrinsics.fx_px > 0 && intrinsics.fy_px > 0 && std::isfinite(intrinsics.cx_px) && std::isfinite(intrinsics.cy_px))) {
    throw std::invalid_argument("LoopCorrection: the intrinsics need fx, fy > 0 and finite cx, cy");
  }
  if (!(std::isfinite(orb_scale_factor) && orb_scale_factor >= 1)) {
    throw std::invalid_argument("LoopCorrection: orb_scale_factor must be finite and at least 1");
  }
}

void LoopCorrection::add_loop(const LoopEdge& edge) {
  if (edge.match_keyframe < 0 || edge.query_keyframe < 0 || edge.match_keyframe == edge.query_keyframe) {
    throw std::invalid_argument("LoopCorrection::add_loop: keyframes " + std::to_string(edge.match_keyframe) +
                                " and " + std::to_string(edge.query_keyframe) +
                                " are not two distinct keyframe ids");
  }
  loop_edges_.push_back(edge);
}

bool LoopCorrection::due(int query_keyframe) const {
  return last_correction_keyframe_ < 0 ||
         query_keyframe - last_correction_keyframe_ > settings_.min_keyframes_between;
}

LoopCorrection::Nodes LoopCorrection::live_keyframes(const Map& map) {
  Nodes nodes;
  nodes.node_of.assign(static_cast<std::size_t>(map.keyframe_count()), -1);
  for (int k = 0; k < map.keyframe_count(); ++k) {
    if (map.keyframe(k).culled) continue;
    nodes.node_of[static_cast<std::size_t>(k)] = static_cast<int>(nodes.keyframes.size());
    nodes.keyframes.push_back(k);
  }
  return nodes;
}

std::vector<PoseGraphEdge> LoopCorrection::pose_graph_edges(const Map& map, const Nodes& node,
                                                            LoopCorrectionReport& report) const {
  const LoopCorrectionSettings& lc = settings_;
  const std::vector<int>& live = node.keyframes;
  const auto pose = [&](int k) { return map.keyframe(k).T_world_camera; };
  std::vector<PoseGraphEdge> edges;
  const auto add_edge = [&](int a, int b, const Eigen::Isometry3d& T_a_b) {
    edges.push_back(PoseGraphEdge::weighted(node(a), node(b), T_a_b, lc.rotation_weight, lc.translation_weight));
  };
  for (std::size_t i = 1; i < live.size(); ++i) {
    add_edge(live[i - 1], live[i], pose(live[i - 1]).inverse() * pose(live[i]));
    ++report.sequential_edges;
  }
  for (const int a : live) {
    for (int b : map.covisible_keyframes(a, -1)) {  // most shared points first
      if (map.shared_points(a, b) < lc.covisibility_min_shared_points) break;
      if (b > a && node(b) != node(a) + 1) {
        add_edge(a, b, pose(a).inverse() * pose(b));
        ++report.covisibility_edges;
      }
    }
  }
  for (const LoopEdge& e : loop_edges_) {
    // An end culled since: the edge moves to its live ancestor, through the current relative pose.
    const int match = live_ancestor(map, e.match_keyframe), query = live_ancestor(map, e.query_keyframe);
    if (match == query) {  // both ends culled into one keyframe: the edge no longer constrains anything
      ++report.collapsed_loop_edges;
      continue;
    }
    if (match == e.match_keyframe && query == e.query_keyframe) {
      add_edge(match, query, e.T_match_query);
    } else {
      add_edge(match, query,
               pose(match).inverse() * pose(e.match_keyframe) * e.T_match_query *
                   pose(e.query_keyframe).inverse() * pose(query));
    }
    ++report.loop_edges;
  }
  return edges;
}

namespace {

/// Moves every point whose first keyframe has node i from pose from[i] to pose to[i], rigidly;
/// only the points seen by exactly one keyframe when `single_observation_only`. Bad points (no
/// observations) stay.
template <typename NodeOf>
void move_points_with_first_keyframe(Map& map, const NodeOf& node, const std::vector<Eigen::Isometry3d>& from,
                                     const std::vector<Eigen::Isometry3d>& to, bool single_observation_only) {
  for (const MapPoint& p : map.map_points()) {
    if (p.observations.empty() || (single_observation_only && p.observations.size() != 1)) continue;
    const auto i = static_cast<std::size_t>(node(p.observations.front().keyframe_id));
    map.set_map_point_position(p.id, to[i] * (from[i].inverse() * p.position_world));
  }
}

}  // namespace

void LoopCorrection::global_bundle_adjustment(Map& map, const Nodes& node,
                                              std::vector<Eigen::Isometry3d>& T_world_camera,
                                              LoopCorrectionReport& report) const {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::int64_t> point_ids;
  std::vector<BundleObservation> observations;
  const OctaveScales octave_scales(orb_scale_factor_);
  for (const MapPoint& p : map.map_points()) {
    if (p.observations.size() < 2) continue;
    const int index = static_cast<int>(points.size());
    points.push_back(p.position_world);
    point_ids.push_back(p.id);
    for (const Observation& o : p.observations) {
      observations.push_back(keyframe_bundle_observation(map.keyframe(o.keyframe_id), o.keypoint_index,
                                                         node(o.keyframe_id), index, octave_scales,
                                                         settings_.depth_sigma_per_m));
    }
  }
  if (points.empty()) return;
  const BundleAdjustmentResult ba =
      BundleAdjuster{settings_.bundle}.adjust(intrinsics_, T_world_camera, points, observations, {0});
  // A point seen by one keyframe took no part: it follows that keyframe's move, as in ORB-SLAM2,
  // or it would sit where the pose graph put it, off its own keyframe's new pose (the newest
  // keyframes, whose points mostly have one observation, moved most).
  move_points_with_first_keyframe(map, node, T_world_camera, ba.T_world_camera, true);
  for (std::size_t i = 0; i < node.keyframes.size(); ++i) map.set_keyframe_pose(node.keyframes[i], ba.T_world_camera[i]);
  for (std::size_t i = 0; i < point_ids.size(); ++i) map.set_map_point_position(point_ids[i], ba.points_world_m[i]);
  T_world_camera = ba.T_world_camera;
  report.bundle_adjusted = true;
  report.bundle_points = static_cast<int>(points.size());
}

LoopCorrectionReport LoopCorrection::correct(Map& map, int query_keyframe) {
  if (query_keyframe < 0 || query_keyframe >= map.keyframe_count()) {
    throw std::invalid_argument("LoopCorrection::correct: no keyframe " + std::to_string(query_keyframe) +
                                " in a map of " + std::to_string(map.keyframe_count()));
  }
  for (const LoopEdge& e : loop_edges_) {
    if (e.match_keyframe >= map.keyframe_count() || e.query_keyframe >= map.keyframe_count()) {
      throw std::invalid_argument("LoopCorrection::correct: the loop between keyframes " +
                                  std::to_string(e.match_keyframe) + " and " + std::to_string(e.query_keyframe) +
                                  " is not in a map of " + std::to_string(map.keyframe_count()) + " keyframes");
    }
  }
  LoopCorrectionReport report;
  const Nodes node = live_keyframes(map);
  report.live_keyframes = static_cast<int>(node.keyframes.size());
  std::vector<Eigen::Isometry3d> before;
  for (const int k : node.keyframes) before.push_back(map.keyframe(k).T_world_camera);

  const std::vector<PoseGraphEdge> edges = pose_graph_edges(map, node, report);
  std::vector<Eigen::Isometry3d> after = PoseGraphOptimiser{settings_.pose_graph}.optimise(before, edges, {0}).T_world_camera;
  move_points_with_first_keyframe(map, node, before, after, false);
  for (std::size_t i = 0; i < node.keyframes.size(); ++i) map.set_keyframe_pose(node.keyframes[i], after[i]);

  if (settings_.bundle_adjustment) global_bundle_adjustment(map, node, after, report);

  const int q = live_ancestor(map, query_keyframe);
  report.T_corrected_old = map.keyframe(q).T_world_camera * before[static_cast<std::size_t>(node(q))].inverse();
  last_correction_keyframe_ = query_keyframe;
  ++corrections_;
  return report;
}

}  // namespace slam
}  // namespace cge
