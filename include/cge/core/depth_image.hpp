#pragma once
// Depth images as the front-end components read them.
//
// Contract for a depth image type D (specialise cge::traits::DepthImage<D>):
//   static int width(const D&), height(const D&)        size in pixels; 0 x 0 means "no depth image"
//   static double depth_m(const D&, int col, int row)    depth in metres along the optical axis at
//                                                        pixel (col, row), 0 <= col < width,
//                                                        0 <= row < height; the return type need
//                                                        only convert to double
// 0 and NaN mean "no measurement" (the TUM convention and the float convention). More generally a
// value is a valid measurement exactly when it is finite and positive (is_valid_depth_m): negative
// values and infinities are treated as missing, never as an error, because a depth image is sensor
// data, not a setting.
// One type comes with the core: FloatDepthImage (owning, row-major float metres). cv::Mat depth
// (CV_16U with a scale, CV_32F metres) is adapted in cge/opencv/depth.hpp.

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace cge {

/// True when a depth value is a measurement: finite and positive.
inline bool is_valid_depth_m(double depth_m) { return std::isfinite(depth_m) && depth_m > 0.0; }

/// Row-major depth image in metres, single precision (what a 16-bit sensor resolves, and half the
/// memory of double).
struct FloatDepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth_m;  ///< width * height values, row-major, metres; 0 or NaN = invalid

  FloatDepthImage() = default;
  FloatDepthImage(int width_px, int height_px, float fill_m = 0.0f) : width(width_px), height(height_px) {
    if (width_px < 0 || height_px < 0) throw std::invalid_argument("FloatDepthImage: negative size");
    depth_m.assign(static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px), fill_m);
  }

  float& at(int col, int row) { return depth_m[static_cast<std::size_t>(row) * width + col]; }
  float at(int col, int row) const { return depth_m[static_cast<std::size_t>(row) * width + col]; }
};

namespace traits {

/// Primary template: deliberately undefined, so a missing specialisation fails at compile time
/// with the type's name in the message.
template <typename D, typename Enable = void>
struct DepthImage;

template <>
struct DepthImage<FloatDepthImage> {
  static int width(const FloatDepthImage& d) { return d.width; }
  static int height(const FloatDepthImage& d) { return d.height; }
  static float depth_m(const FloatDepthImage& d, int col, int row) { return d.at(col, row); }
};

}  // namespace traits

}  // namespace cge
