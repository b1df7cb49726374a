#pragma once
// Keypoint undistortion through OpenCV (link cge::opencv): the pixels of the ideal pinhole camera
// (same intrinsics, no distortion) that distorted pixels correspond to, and the bounds of the
// undistorted image. Images are never remapped: keypoints are detected, masks tested and depth read
// in the image as it is, and only geometry (projection, PnP, bundle adjustment) uses the
// undistorted positions, as ORB-SLAM2 does.
#include <algorithm>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "cge/core/lens_distortion.hpp"
#include "cge/core/pinhole_intrinsics.hpp"

namespace cge {
namespace opencv {

/// cv::undistortPoints' fixed-point inversion of the distortion model.
struct UndistortSettings {
  /// Iterations, >= 1. OpenCV's own default (5) leaves about 0.1 px at the corners of a TUM fr1
  /// image (k1 = 0.26); 20 converge to well below 1e-3 px there.
  int max_iterations = 20;
  double epsilon = 1e-9;  ///< stops earlier when a step is below this, normalised units, >= 0

  void validate() const {
    if (max_iterations < 1 || !(epsilon >= 0)) {
      throw std::invalid_argument("UndistortSettings: max_iterations must be >= 1 and epsilon >= 0");
    }
  }
};

/// 1 x 5 CV_64F (k1, k2, p1, p2, k3), the order OpenCV takes.
inline cv::Mat distortion_coefficients(const LensDistortion& d) {
  return (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3);
}

/// The 3 x 3 camera matrix.
inline cv::Matx33d camera_matrix(const PinholeIntrinsics<double>& k) {
  return {k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1};
}

/// The undistorted pixels of `points_px`; returns them unchanged (bit for bit) when the distortion is zero.
inline std::vector<cv::Point2f> undistort_pixels(const std::vector<cv::Point2f>& points_px,
                                                 const PinholeIntrinsics<double>& intrinsics,
                                                 const LensDistortion& distortion, const UndistortSettings& settings = {}) {
  settings.validate();
  if (distortion.is_zero() || points_px.empty()) return points_px;
  if (!distortion.is_finite()) throw std::invalid_argument("undistort_pixels: the distortion coefficients must be finite");
  std::vector<cv::Point2f> out;
  const cv::Matx33d K = camera_matrix(intrinsics);
  cv::undistortPoints(points_px, out, K, distortion_coefficients(distortion), cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, settings.max_iterations,
                                       settings.epsilon));
  return out;
}

/// Where the image of `size` lies in the undistorted camera, pixels: the box spanned by its
/// undistorted corners (as ORB-SLAM2 bounds its keypoint grid). [0, width) x [0, height) when the
/// distortion is zero.
struct ImageBounds {
  double min_x_px = 0, min_y_px = 0, max_x_px = 0, max_y_px = 0;
  bool contains(double x, double y) const { return x >= min_x_px && x < max_x_px && y >= min_y_px && y < max_y_px; }
};

inline ImageBounds undistorted_image_bounds(cv::Size size, const PinholeIntrinsics<double>& intrinsics,
                                            const LensDistortion& distortion, const UndistortSettings& settings = {}) {
  const auto w = static_cast<float>(size.width), h = static_cast<float>(size.height);
  if (distortion.is_zero()) return {0, 0, w, h};
  const std::vector<cv::Point2f> c = undistort_pixels({{0, 0}, {w, 0}, {0, h}, {w, h}}, intrinsics, distortion, settings);
  return {std::min(c[0].x, c[2].x), std::min(c[0].y, c[1].y), std::max(c[1].x, c[3].x), std::max(c[2].y, c[3].y)};
}

}  // namespace opencv
}  // namespace cge
