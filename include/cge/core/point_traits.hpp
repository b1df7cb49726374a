#pragma once
// Adapting foreign 2-D point types (keypoints, pixels) to the toolkit.
//
// Contract (the only thing a component asks of a point type P):
//   cge::traits::Point2<P>::x(const P&)  -> a value convertible to the component's Scalar, in pixels
//   cge::traits::Point2<P>::y(const P&)  -> likewise
// Specialise cge::traits::Point2 for your type in namespace cge::traits, or rely on the
// specialisations below (Eigen 2-vectors, std::array<T, 2>, std::pair<T, T>). Components read points
// only through the free functions cge::point_x / cge::point_y, never through members, so a type
// you cannot change (a cv::KeyPoint, your own Keypoint struct) adapts without wrappers.
// The OpenCV specialisations live in cge/opencv/ so that this header needs no OpenCV.

#include <array>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

namespace cge {
namespace traits {

/// Primary template: deliberately undefined, so a missing specialisation fails at compile time
/// with the type's name in the message.
template <typename Point, typename Enable = void>
struct Point2;

template <typename T, int Options, int MaxRows, int MaxCols>
struct Point2<Eigen::Matrix<T, 2, 1, Options, MaxRows, MaxCols>> {
  using Point = Eigen::Matrix<T, 2, 1, Options, MaxRows, MaxCols>;
  static T x(const Point& p) { return p.x(); }
  static T y(const Point& p) { return p.y(); }
};

template <typename T>
struct Point2<std::array<T, 2>> {
  static T x(const std::array<T, 2>& p) { return p[0]; }
  static T y(const std::array<T, 2>& p) { return p[1]; }
};

template <typename T>
struct Point2<std::pair<T, T>> {
  static T x(const std::pair<T, T>& p) { return p.first; }
  static T y(const std::pair<T, T>& p) { return p.second; }
};

}  // namespace traits

/// x coordinate of any adapted point type, in pixels.
template <typename Point>
auto point_x(const Point& p) -> decltype(traits::Point2<Point>::x(p)) {
  return traits::Point2<Point>::x(p);
}

/// y coordinate of any adapted point type, in pixels.
template <typename Point>
auto point_y(const Point& p) -> decltype(traits::Point2<Point>::y(p)) {
  return traits::Point2<Point>::y(p);
}

}  // namespace cge
