#pragma once
// Pinhole intrinsics without distortion, with the two maps every RGB-D component needs: projection
// of a camera-frame point and back-projection of a pixel with its depth. TUM fr3 images are
// undistorted; fr1/fr2 keypoints are undistorted first (cge/dataset/orbslam2_settings.hpp).
// Camera frame: x right, y down, z forward (OpenCV/TUM).
#include <Eigen/Core>

namespace cge {

template <typename Scalar = double>
struct PinholeIntrinsics {
  using Vector2 = Eigen::Matrix<Scalar, 2, 1>;
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;

  Scalar fx_px = Scalar(525);    ///< focal length along x, pixels
  Scalar fy_px = Scalar(525);    ///< focal length along y, pixels
  Scalar cx_px = Scalar(319.5);  ///< principal point x, pixels
  Scalar cy_px = Scalar(239.5);  ///< principal point y, pixels

  /// Pixel of a camera-frame point; the caller checks z > 0.
  Vector2 project(const Vector3& p_camera) const {
    return Vector2(fx_px * p_camera.x() / p_camera.z() + cx_px, fy_px * p_camera.y() / p_camera.z() + cy_px);
  }

  /// Camera-frame point seen at pixel (u, v) at depth z (metres along the optical axis).
  Vector3 backproject(Scalar u_px, Scalar v_px, Scalar depth_m) const {
    return Vector3((u_px - cx_px) * depth_m / fx_px, (v_px - cy_px) * depth_m / fy_px, depth_m);
  }
};

}  // namespace cge
