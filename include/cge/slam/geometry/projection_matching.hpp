#pragma once
// Projection matching: 3-D points with descriptors projected into a frame at a pose and matched to
// the static keypoints near their projections (ORB-SLAM2's SearchByProjection, without its
// orientation and scale checks). The tracker matches its local map this way, and the previous
// frame's points when it falls back to frame-to-frame odometry.

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/slam/frame.hpp"

namespace cge {
namespace slam {

/// The static keypoints of a frame bucketed by undistorted pixel, for window queries.
class KeypointGrid {
 public:
  static constexpr int kCellPx = 16;  ///< bucket size, pixels (a window of 15 px spans 2 x 2 cells)

  explicit KeypointGrid(const Frame& frame);

  /// Calls f(i) for the static keypoints in the cells overlapping the square window of half-size
  /// radius around (u, v), by cell (row-major) then keypoint index: a fixed visiting order.
  template <typename F>
  void for_each_near(double u, double v, double radius, F&& f) const {
    const int c0 = cell_col(u - radius), c1 = cell_col(u + radius);
    const int r0 = cell_row(v - radius), r1 = cell_row(v + radius);
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        for (const int i : cells_[static_cast<std::size_t>(r * cols_ + c)]) f(i);
      }
    }
  }

 private:
  int cell_col(double x) const { return std::clamp(static_cast<int>(std::floor(x / kCellPx)), 0, cols_ - 1); }
  int cell_row(double y) const { return std::clamp(static_cast<int>(std::floor(y / kCellPx)), 0, rows_ - 1); }
  int cols_, rows_;
  std::vector<std::vector<int>> cells_;
};

struct KeypointMatch {
  int index = -1;          ///< keypoint, -1: none
  int distance = INT_MAX;  ///< Hamming distance, bits
};

/// The static keypoint within radius_px (Euclidean) of (u, v) whose descriptor is nearest to
/// `descriptor` (a 32-byte row); none when the nearest is farther than max_hamming bits or fails
/// the ratio test against the second nearest (NearestTwo::passes). Ties: the first visited.
KeypointMatch best_keypoint_near(const Frame& frame, const KeypointGrid& grid, double u, double v, double radius_px,
                                 const std::uint8_t* descriptor, int max_hamming, double ratio);

/// A point to project: its world position and its 32-byte descriptor (not owned).
struct PointToProject {
  Eigen::Vector3d position_world;
  const std::uint8_t* descriptor = nullptr;
};

/// Defaults: TrackerSettings' (search_radius_px, max_hamming, ratio); the caller passes its own.
struct ProjectionSearch {
  double radius_px = 15;      ///< search window radius around the projection, pixels
  int max_hamming = 64;       ///< largest descriptor distance of a match, bits of 256
  double ratio = 0.9;         ///< Lowe's ratio, best < ratio x second best
  double min_depth_m = 0.05;  ///< points nearer than this in front of the camera are not projected, metres (ours)
  /// Skip points projecting outside frame.undistorted_bounds (map points: they cannot be seen);
  /// false searches near every projection (the window is clamped to the image).
  bool require_in_image = true;
};

/// For every keypoint of `frame`, the index into `points` of the point matched to it, -1 for none.
/// Each point picks its best keypoint (best_keypoint_near); a keypoint picked by several points
/// keeps the one with the smallest distance, the earliest in `points` on ties. When `in_image` is
/// given, the indices of the points that passed the depth and image tests are appended to it in
/// order.
std::vector<int> match_by_projection(const Frame& frame, const KeypointGrid& grid,
                                     const PinholeIntrinsics<double>& intrinsics,
                                     const std::vector<PointToProject>& points, const Eigen::Isometry3d& T_world_camera,
                                     const ProjectionSearch& search, std::vector<int>* in_image = nullptr);

}  // namespace slam
}  // namespace cge
