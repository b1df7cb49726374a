#pragma once
// The n x m grid of equal patches that keyframe selection lays over an image.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Core>

#include "cge/core/image_region.hpp"

namespace cge {

/// An image split into cols x rows equal patches, numbered row-major: patch = row * cols + col.
template <typename Scalar>
struct PatchGrid {
  using Point = Eigen::Matrix<Scalar, 2, 1>;

  ImageRegion<Scalar> image;  ///< the rectangle the grid covers
  int cols = 10;              ///< n, patches across, >= 1
  int rows = 10;              ///< m, patches down, >= 1

  int patch_count() const { return cols * rows; }
  Scalar patch_width_px() const { return image.width_px / static_cast<Scalar>(cols); }
  Scalar patch_height_px() const { return image.height_px / static_cast<Scalar>(rows); }

  /// Patch of a point inside the closed image rectangle (the caller checks that): column
  /// floor((x - x0) / patch width), clamped to the last column so that the far border belongs to
  /// the last patch; row likewise. The same rule as GraphBuilder's dense patches.
  int patch_of(const Point& p) const {
    const Point rel = p - image.origin_px;
    const int col = std::min(static_cast<int>(rel.x() / patch_width_px()), cols - 1);
    const int row = std::min(static_cast<int>(rel.y() / patch_height_px()), rows - 1);
    return row * cols + col;
  }

  /// Centre of a patch, in image pixels (origin included).
  Point patch_centre(int patch) const {
    const int col = patch % cols;
    const int row = patch / cols;
    return Point(image.origin_px.x() + (static_cast<Scalar>(col) + Scalar(0.5)) * patch_width_px(),
                 image.origin_px.y() + (static_cast<Scalar>(row) + Scalar(0.5)) * patch_height_px());
  }

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    image.validate();
    if (cols < 1 || rows < 1 ||
        static_cast<std::int64_t>(cols) * rows > static_cast<std::int64_t>(std::numeric_limits<int>::max())) {
      std::ostringstream msg;
      msg << "PatchGrid: cols and rows must be at least 1 and their product must fit an int, got " << cols << " x "
          << rows;
      throw std::invalid_argument(msg.str());
    }
  }

  bool operator==(const PatchGrid& o) const {
    return image.origin_px == o.image.origin_px && image.width_px == o.image.width_px &&
           image.height_px == o.image.height_px && cols == o.cols && rows == o.rows;
  }
  bool operator!=(const PatchGrid& o) const { return !(*this == o); }
};

}  // namespace cge
