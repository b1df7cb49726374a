#include "cge/slam/geometry/projection_matching.hpp"

#include "cge/bow/binary_descriptor.hpp"
#include "cge/slam/geometry/nearest_two.hpp"

namespace cge {
namespace slam {

KeypointGrid::KeypointGrid(const Frame& frame)
    : cols_((frame.image_size.width + kCellPx - 1) / kCellPx),
      rows_((frame.image_size.height + kCellPx - 1) / kCellPx),
      cells_(static_cast<std::size_t>(std::max(cols_ * rows_, 0))) {
  for (int i = 0; i < frame.size(); ++i) {
    if (!frame.is_static(i)) continue;
    const cv::Point2f& p = frame.undistorted_px[static_cast<std::size_t>(i)];
    cells_[static_cast<std::size_t>(cell_row(p.y) * cols_ + cell_col(p.x))].push_back(i);
  }
}

KeypointMatch best_keypoint_near(const Frame& frame, const KeypointGrid& grid, double u, double v, double radius_px,
                                 const std::uint8_t* descriptor, int max_hamming, double ratio) {
  const double radius_sq = radius_px * radius_px;
  NearestTwo nearest;
  grid.for_each_near(u, v, radius_px, [&](int i) {
    const cv::Point2f& kp = frame.undistorted_px[static_cast<std::size_t>(i)];
    const double du = kp.x - u, dv = kp.y - v;
    if (du * du + dv * dv > radius_sq) return;
    nearest.add(i, bow::hamming_distance_32_bytes(descriptor, frame.descriptors.ptr<std::uint8_t>(i)));
  });
  if (!nearest.passes(max_hamming, ratio)) return {};
  return {nearest.best_index, nearest.best};
}

std::vector<int> match_by_projection(const Frame& frame, const KeypointGrid& grid,
                                     const PinholeIntrinsics<double>& intrinsics,
                                     const std::vector<PointToProject>& points, const Eigen::Isometry3d& T_world_camera,
                                     const ProjectionSearch& search, std::vector<int>* in_image) {
  std::vector<int> source(static_cast<std::size_t>(frame.size()), -1);
  std::vector<int> best_distance(static_cast<std::size_t>(frame.size()), INT_MAX);
  const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d p_camera = T_camera_world * points[k].position_world;
    if (p_camera.z() < search.min_depth_m) continue;
    const Eigen::Vector2d uv = intrinsics.project(p_camera);
    if (search.require_in_image && !frame.undistorted_bounds.contains(uv.x(), uv.y())) continue;
    if (in_image != nullptr) in_image->push_back(static_cast<int>(k));
    const KeypointMatch m = best_keypoint_near(frame, grid, uv.x(), uv.y(), search.radius_px, points[k].descriptor,
                                               search.max_hamming, search.ratio);
    if (m.index < 0) continue;
    int& slot = best_distance[static_cast<std::size_t>(m.index)];
    if (m.distance < slot) {
      slot = m.distance;
      source[static_cast<std::size_t>(m.index)] = static_cast<int>(k);
    }
  }
  return source;
}

}  // namespace slam
}  // namespace cge
