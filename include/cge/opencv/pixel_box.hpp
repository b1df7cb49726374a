#pragma once
// cv::Rect boxes as cge::PixelBox (cge/frontend/pixel_box.hpp). Both use area coordinates
// (cv::Rect(x, y, w, h) covers pixels x .. x + w - 1), so the conversion is exact and offset-free.

#include <opencv2/core/types.hpp>

#include "cge/frontend/pixel_box.hpp"

namespace cge {
namespace opencv {

/// cv::Rect, cv::Rect2f or cv::Rect2d as a PixelBox.
template <typename T>
PixelBox to_pixel_box(const cv::Rect_<T>& rect) {
  return PixelBox{static_cast<double>(rect.x), static_cast<double>(rect.y), static_cast<double>(rect.width),
                  static_cast<double>(rect.height)};
}

/// A PixelBox as cv::Rect2d.
inline cv::Rect2d to_rect2d(const PixelBox& box) {
  return cv::Rect2d(box.x_min_px, box.y_min_px, box.width_px, box.height_px);
}

}  // namespace opencv
}  // namespace cge
