#pragma once
// PnP RANSAC and the pose conversions around it, shared by the tracker (map points to a frame) and
// the loop closer (a keyframe's 3-D points to the query's pixels).

#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {
namespace slam {

/// Defaults: LoopCloserSettings' pnp_* values; the tracker passes its own (TrackerSettings).
struct PnpRansacSettings {
  int iterations = 300;          ///< RANSAC iterations
  double reprojection_px = 4.0;  ///< inlier threshold, pixels of reprojection error
  double confidence = 0.999;     ///< RANSAC confidence, in (0, 1)
};

struct PnpRansacResult {
  /// OpenCV found a pose, did not throw, and the pose is finite.
  bool ok = false;
  /// Maps object-frame points into the camera: x_camera = T_camera_object * X (valid when ok).
  Eigen::Isometry3d T_camera_object = Eigen::Isometry3d::Identity();
  /// Indices of the inlier correspondences as OpenCV returns them (ascending); may be non-empty
  /// when ok is false (a non-finite pose).
  std::vector<int> inliers;
};

/// The 3 x 3 camera matrix K of `camera`.
cv::Matx33d camera_matrix(const PinholeIntrinsics<double>& camera);

/// The rigid transform of an OpenCV rotation vector (Rodrigues) and translation, both 3 x 1 CV_64F.
Eigen::Isometry3d isometry_from_rvec_tvec(const cv::Mat& rvec, const cv::Mat& tvec);

/// EPnP on minimal samples inside RANSAC, then EPnP on all inliers (no iterative refinement: the
/// callers refine with Ceres or need only the inlier count). `object` and `image` are paired by
/// index; no distortion (the pixels are undistorted). A degenerate configuration, for which OpenCV
/// throws cv::Exception, gives ok = false.
PnpRansacResult solve_pnp_ransac(const std::vector<cv::Point3d>& object, const std::vector<cv::Point2d>& image,
                                 const PinholeIntrinsics<double>& camera, const PnpRansacSettings& settings);

}  // namespace slam
}  // namespace cge
