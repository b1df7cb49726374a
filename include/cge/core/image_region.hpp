#pragma once
// The rectangle of image plane a frame's points live in.

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Core>

namespace cge {

/// Axis-aligned image rectangle in pixels: [origin.x, origin.x + width) x [origin.y, origin.y + height).
/// The origin is (0, 0) for an ordinary image; it is a field so that a frame and its points can be
/// translated together (a property the graph construction must respect).
template <typename Scalar>
struct ImageRegion {
  using Point = Eigen::Matrix<Scalar, 2, 1>;

  Point origin_px = Point::Zero();  ///< top-left corner, pixels
  Scalar width_px = Scalar(640);    ///< pixels, > 0 (TUM RGB-D default)
  Scalar height_px = Scalar(480);   ///< pixels, > 0

  Point centre() const { return origin_px + Point(width_px / 2, height_px / 2); }
  Scalar diagonal() const { return std::sqrt(width_px * width_px + height_px * height_px); }

  /// True when p lies in the closed rectangle (a keypoint exactly on the far border is accepted).
  bool contains(const Point& p) const {
    return p.x() >= origin_px.x() && p.y() >= origin_px.y() && p.x() <= origin_px.x() + width_px &&
           p.y() <= origin_px.y() + height_px;
  }

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    if (!std::isfinite(origin_px.x()) || !std::isfinite(origin_px.y())) {
      throw std::invalid_argument("ImageRegion: origin_px is not finite");
    }
    if (!(std::isfinite(width_px) && width_px > 0) || !(std::isfinite(height_px) && height_px > 0)) {
      std::ostringstream msg;
      msg << "ImageRegion: width_px and height_px must be finite and positive, got " << width_px << " x " << height_px;
      throw std::invalid_argument(msg.str());
    }
  }
};

}  // namespace cge
