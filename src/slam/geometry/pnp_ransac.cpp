#include "cge/slam/geometry/pnp_ransac.hpp"

#include <opencv2/calib3d.hpp>

namespace cge {
namespace slam {

cv::Matx33d camera_matrix(const PinholeIntrinsics<double>& camera) {
  return cv::Matx33d(camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
}

Eigen::Isometry3d isometry_from_rvec_tvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = R.at<double>(r, c);
    T.translation()(r) = tvec.at<double>(r);
  }
  return T;
}

PnpRansacResult solve_pnp_ransac(const std::vector<cv::Point3d>& object, const std::vector<cv::Point2d>& image,
                                 const PinholeIntrinsics<double>& camera, const PnpRansacSettings& settings) {
  PnpRansacResult result;
  cv::Mat rvec, tvec;
  bool solved = false;
  try {
    solved = cv::solvePnPRansac(object, image, camera_matrix(camera), cv::noArray(), rvec, tvec, false,
                                settings.iterations, static_cast<float>(settings.reprojection_px),
                                settings.confidence, result.inliers, cv::SOLVEPNP_EPNP);
  } catch (const cv::Exception&) {
    solved = false;  // degenerate configuration (e.g. too few or collinear points): no pose
  }
  if (!solved) return result;
  result.T_camera_object = isometry_from_rvec_tvec(rvec, tvec);
  result.ok = result.T_camera_object.matrix().allFinite();
  return result;
}

}  // namespace slam
}  // namespace cge
