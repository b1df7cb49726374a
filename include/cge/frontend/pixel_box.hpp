#pragma once
// Axis-aligned boxes of detected instances, and the pixels they cover.
//
// Coordinates of a box are *area* coordinates: pixel (col, row) is the unit square
// [col, col + 1) x [row, row + 1), so the image is [0, W] x [0, H]. This is the convention of
// cv::Rect (x, y, width, height cover pixels x .. x + width - 1) and of detector outputs
// (x1, y1, x2, y2 in [0, W] x [0, H]); both convert without offsets. A pixel belongs to a box when
// it overlaps the box: columns floor(x_min) .. ceil(x_max) - 1, likewise rows.
// (Keypoint coordinates are different: OpenCV puts pixel centres at integers, so a keypoint at
// (u, v) lies on pixel (round(u), round(v)); see cge/frontend/depth_mad_filter.hpp.)

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cge/core/mask.hpp"

namespace cge {

/// The half-open pixel range [col_begin, col_end) x [row_begin, row_end) a box overlaps.
struct PixelSpan {
  int col_begin = 0, col_end = 0;
  int row_begin = 0, row_end = 0;

  bool contains(int col, int row) const {
    return col >= col_begin && col < col_end && row >= row_begin && row < row_end;
  }
  int pixel_count() const { return (col_end - col_begin) * (row_end - row_begin); }
};

/// A box in area coordinates, pixels: [x_min, x_min + width) x [y_min, y_min + height).
struct PixelBox {
  double x_min_px = 0;   ///< left edge, pixels (area coordinates)
  double y_min_px = 0;   ///< top edge, pixels
  double width_px = 0;   ///< l_x in the paper, pixels, > 0
  double height_px = 0;  ///< l_y in the paper, pixels, > 0

  /// From the paper's form: centre (x_box, y_box) and size (l_x, l_y).
  static PixelBox from_centre(double centre_x_px, double centre_y_px, double width, double height) {
    return PixelBox{centre_x_px - width / 2, centre_y_px - height / 2, width, height};
  }
  /// From two corners (x1, y1) top-left and (x2, y2) bottom-right, as detectors report boxes.
  static PixelBox from_corners(double x1_px, double y1_px, double x2_px, double y2_px) {
    return PixelBox{x1_px, y1_px, x2_px - x1_px, y2_px - y1_px};
  }

  double x_max_px() const { return x_min_px + width_px; }
  double y_max_px() const { return y_min_px + height_px; }
  double centre_x_px() const { return x_min_px + width_px / 2; }
  double centre_y_px() const { return y_min_px + height_px / 2; }

  /// The pixels the box overlaps. Meaningful for a box that passes validate().
  PixelSpan pixels() const {
    return PixelSpan{static_cast<int>(std::floor(x_min_px)), static_cast<int>(std::ceil(x_max_px())),
                     static_cast<int>(std::floor(y_min_px)), static_cast<int>(std::ceil(y_max_px()))};
  }

  /// Throws std::invalid_argument, naming `which`, unless every field is finite, the box has a
  /// positive extent on both axes and lies inside the image [0, width] x [0, height].
  void validate(int image_width_px, int image_height_px, const char* which) const {
    const auto fail = [&](const char* what) {
      std::ostringstream msg;
      msg << which << " (x_min " << x_min_px << ", y_min " << y_min_px << ", width " << width_px << ", height "
          << height_px << " px) " << what << " (image " << image_width_px << " x " << image_height_px << ")";
      throw std::invalid_argument(msg.str());
    };
    if (!std::isfinite(x_min_px) || !std::isfinite(y_min_px) || !std::isfinite(width_px) || !std::isfinite(height_px)) {
      fail("is not finite");
    }
    // x_max > x_min, not just width > 0: a width below the spacing of doubles at x_min is no box.
    if (!(x_max_px() > x_min_px) || !(y_max_px() > y_min_px)) fail("has no positive width and height");
    if (x_min_px < 0 || y_min_px < 0 || x_max_px() > image_width_px || y_max_px() > image_height_px) {
      fail("reaches outside the image");
    }
  }
};

/// The smallest box holding every set pixel of the mask (pixel-aligned: integer edges), or nothing
/// when no pixel is set. Scans the whole mask.
template <typename M>
std::optional<PixelBox> bounding_box(const M& mask) {
  using T = traits::Mask<M>;
  if (T::empty(mask)) return std::nullopt;
  const int width = T::width(mask);
  const int height = T::height(mask);
  int col_min = width, col_max = -1, row_min = height, row_max = -1;
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      if (!T::is_set(mask, col, row)) continue;
      col_min = std::min(col_min, col);
      col_max = std::max(col_max, col);
      row_min = std::min(row_min, row);
      row_max = row;
    }
  }
  if (col_max < 0) return std::nullopt;
  return PixelBox{static_cast<double>(col_min), static_cast<double>(row_min),
                  static_cast<double>(col_max - col_min + 1), static_cast<double>(row_max - row_min + 1)};
}

}  // namespace cge
