#pragma once
// OpenCV keypoints and points as cge point types (cge/core/point_traits.hpp): a
// std::vector<cv::KeyPoint> from any OpenCV detector goes straight into the components.
// Coordinates are OpenCV's: pixel centres at integer coordinates.

#include <opencv2/core/types.hpp>

#include "cge/core/nearest_pixel.hpp"
#include "cge/core/point_traits.hpp"

namespace cge {
namespace traits {

/// cv::KeyPoint: its `pt`, in pixels of the image it was detected in (level 0 for ORB pyramids).
template <>
struct Point2<cv::KeyPoint> {
  static float x(const cv::KeyPoint& k) { return k.pt.x; }
  static float y(const cv::KeyPoint& k) { return k.pt.y; }
};

/// cv::Point_<T>: cv::Point2f, cv::Point2d, cv::Point (integers).
template <typename T>
struct Point2<cv::Point_<T>> {
  static T x(const cv::Point_<T>& p) { return p.x; }
  static T y(const cv::Point_<T>& p) { return p.y; }
};

}  // namespace traits

namespace opencv {

/// The pixel a keypoint falls on, as DepthMADFilter reads it (cge/core/nearest_pixel.hpp), clamped
/// into an image of `size` (cols = width, rows = height).
inline cv::Point nearest_pixel(const cv::Point2f& p, cv::Size size) {
  return {nearest_pixel_index(p.x, size.width), nearest_pixel_index(p.y, size.height)};
}

}  // namespace opencv
}  // namespace cge
