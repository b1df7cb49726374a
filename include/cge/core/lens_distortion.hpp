#pragma once
// Radial-tangential lens distortion, the model of OpenCV and of ORB-SLAM2's settings files
// (Camera.k1 k2 p1 p2 k3). TUM fr1 and fr2 images are distorted, fr3 and the synthetic ones are
// not. Undistorting keypoints (not whole images) is what ORB-SLAM2 does; the OpenCV adapter
// cge/opencv/undistort.hpp inverts this model.
#include <cmath>

#include <Eigen/Core>

namespace cge {

struct LensDistortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;  ///< unitless (normalised image coordinates)

  bool is_zero() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0; }
  bool is_finite() const {
    return std::isfinite(k1) && std::isfinite(k2) && std::isfinite(p1) && std::isfinite(p2) && std::isfinite(k3);
  }

  /// The forward model: where the lens puts the ideal normalised point xy = ((u - cx) / fx,
  /// (v - cy) / fy). r^2 = x^2 + y^2; radial = 1 + k1 r^2 + k2 r^4 + k3 r^6;
  /// x' = x radial + 2 p1 x y + p2 (r^2 + 2 x^2), y' = y radial + p1 (r^2 + 2 y^2) + 2 p2 x y.
  Eigen::Vector2d distort(const Eigen::Vector2d& xy) const {
    const double x = xy.x(), y = xy.y();
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x), y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
  }
};

}  // namespace cge
