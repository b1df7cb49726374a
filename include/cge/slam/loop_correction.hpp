#pragma once
// Correction of accepted loops (docs/METHOD.md section 7, step 5), beside local mapping as
// ORB-SLAM2's loop correction is beside its local mapping. Settings: LoopCorrectionSettings
// (cge/slam/settings.hpp).
//
// One correction, in named steps:
//   1. live_keyframes: the pose-graph nodes are the keyframes not culled (culled ones follow their
//      parents when Map::set_keyframe_pose moves those);
//   2. pose_graph_edges: relative poses as currently estimated between consecutive live keyframes
//      and between covisible ones (covisibility_min_shared_points), plus every accepted loop's
//      measured relative pose; keyframe 0 fixes the gauge;
//   3. the pose graph is optimised and every map point moves rigidly with its first keyframe;
//   4. global_bundle_adjustment (optional): the points seen by at least two keyframes and every
//      live pose; a point seen by one keyframe follows that keyframe's move, as in ORB-SLAM2.
// The report carries the move of the query keyframe, which the tracker's last pose follows.
//
// Deterministic: keyframes and points in id order, one-threaded Ceres.
#include <vector>

#include <Eigen/Geometry>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/map.hpp"
#include "cge/slam/settings.hpp"

namespace cge {
namespace slam {

/// One accepted loop as the loop closer measured it.
struct LoopEdge {
  int match_keyframe = -1;  ///< the earlier keyframe of the loop
  int query_keyframe = -1;  ///< the keyframe that closed it
  /// The query keyframe's camera in the match keyframe's camera, metres.
  Eigen::Isometry3d T_match_query = Eigen::Isometry3d::Identity();
};

/// What one correction did (for tests and logs).
struct LoopCorrectionReport {
  int live_keyframes = 0;      ///< pose-graph nodes
  int sequential_edges = 0;    ///< between consecutive live keyframes
  int covisibility_edges = 0;  ///< between covisible, non-consecutive live keyframes
  int loop_edges = 0;          ///< every accepted loop so far whose ends are still two live keyframes
  /// Accepted loops left out because keyframe culling merged both ends into one live keyframe.
  int collapsed_loop_edges = 0;
  bool bundle_adjusted = false;  ///< the global BA ran (enabled and some point seen twice)
  int bundle_points = 0;         ///< points in the global BA
  /// Old world coordinates to corrected ones, as the query keyframe (its live ancestor when culled)
  /// moved: T_world_query(after) * T_world_query(before)^-1.
  Eigen::Isometry3d T_corrected_old = Eigen::Isometry3d::Identity();
};

class LoopCorrection {
 public:
  /// Throws std::invalid_argument for bad settings (LoopCorrectionSettings fields) or intrinsics.
  LoopCorrection(const LoopCorrectionSettings& settings, const PinholeIntrinsics<double>& intrinsics,
                 double orb_scale_factor);

  /// Keeps an accepted loop's edge for this and every later correction. Throws
  /// std::invalid_argument when an id is negative or the two are equal.
  void add_loop(const LoopEdge& edge);
  /// True when a correction at `query_keyframe` is due: none yet, or the last one is more than
  /// min_keyframes_between keyframes older (one revisit is accepted at many consecutive keyframes;
  /// the loops between only add their edges).
  bool due(int query_keyframe) const;
  /// Corrects `map` with every loop edge added so far (steps above) and records the correction at
  /// `query_keyframe`. Throws std::invalid_argument for an unknown query keyframe or a loop edge
  /// whose keyframes are not in the map.
  LoopCorrectionReport correct(Map& map, int query_keyframe);

  int corrections() const { return corrections_; }
  const std::vector<LoopEdge>& loop_edges() const { return loop_edges_; }
  const LoopCorrectionSettings& settings() const { return settings_; }

 private:
  /// Pose-graph nodes: node i is keyframe keyframes[i]; node_of[k] is -1 for a culled keyframe.
  struct Nodes {
    std::vector<int> keyframes;
    std::vector<int> node_of;
    int operator()(int keyframe_id) const { return node_of[static_cast<std::size_t>(keyframe_id)]; }
  };
  static Nodes live_keyframes(const Map& map);
  std::vector<PoseGraphEdge> pose_graph_edges(const Map& map, const Nodes& nodes, LoopCorrectionReport& report) const;
  /// Points seen by two or more keyframes and every live pose, starting from `T_world_camera`
  /// (node-indexed, updated); the map gets the result.
  void global_bundle_adjustment(Map& map, const Nodes& nodes, std::vector<Eigen::Isometry3d>& T_world_camera,
                                LoopCorrectionReport& report) const;

  LoopCorrectionSettings settings_;
  PinholeIntrinsics<double> intrinsics_;
  double orb_scale_factor_ = 1.2;
  std::vector<LoopEdge> loop_edges_;
  int last_correction_keyframe_ = -1;
  int corrections_ = 0;
};

}  // namespace slam
}  // namespace cge
