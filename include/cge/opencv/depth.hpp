#pragma once
// cv::Mat depth images as cge depth images (cge/core/depth_image.hpp).
//
// DepthView wraps a single-channel cv::Mat without copying its pixels:
// - CV_16UC1 with a scale in units per metre (TUM RGB-D and the synthetic sequences: 5000, Kinect
//   and RealSense raw: 1000); metres = value / units_per_metre, 0 = no measurement;
// - CV_32FC1 in metres (units_per_metre 1), 0 or NaN = no measurement.
// The view shares the Mat's buffer (cv::Mat reference counting): it stays valid while it lives,
// and sees later writes to the pixels.

#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "cge/core/depth_image.hpp"

namespace cge {
namespace opencv {

/// Depth units per metre of the TUM RGB-D benchmark's 16-bit depth PNGs.
constexpr double tum_depth_units_per_metre = 5000.0;

class DepthView {
 public:
  /// Throws std::invalid_argument when the Mat is empty, is not CV_16UC1 or CV_32FC1, or the scale
  /// is not finite and positive. A CV_32FC1 image in metres takes units_per_metre = 1.
  DepthView(const cv::Mat& depth, double units_per_metre) : depth_(depth), units_per_metre_(units_per_metre) {
    if (depth.empty()) throw std::invalid_argument("DepthView: the depth image is empty");
    if (depth.type() != CV_16UC1 && depth.type() != CV_32FC1) {
      std::ostringstream msg;
      msg << "DepthView: the depth image has type " << cv::typeToString(depth.type())
          << "; expected CV_16UC1 (with units per metre, TUM: 5000) or CV_32FC1 (metres)";
      throw std::invalid_argument(msg.str());
    }
    if (!(std::isfinite(units_per_metre) && units_per_metre > 0)) {
      std::ostringstream msg;
      msg << "DepthView: units_per_metre must be finite and positive, got " << units_per_metre;
      throw std::invalid_argument(msg.str());
    }
  }

  /// A CV_16UC1 image in units of 1 / units_per_metre metres (TUM: 5000).
  static DepthView from_u16(const cv::Mat& depth, double units_per_metre = tum_depth_units_per_metre) {
    if (!depth.empty() && depth.type() != CV_16UC1) {
      throw std::invalid_argument("DepthView::from_u16: the depth image has type " + cv::typeToString(depth.type()) +
                                  ", expected CV_16UC1");
    }
    return DepthView(depth, units_per_metre);
  }
  /// A CV_32FC1 image in metres.
  static DepthView from_metres(const cv::Mat& depth) {
    if (!depth.empty() && depth.type() != CV_32FC1) {
      throw std::invalid_argument("DepthView::from_metres: the depth image has type " + cv::typeToString(depth.type()) +
                                  ", expected CV_32FC1");
    }
    return DepthView(depth, 1.0);
  }

  int width() const { return depth_.cols; }
  int height() const { return depth_.rows; }
  double units_per_metre() const { return units_per_metre_; }
  const cv::Mat& mat() const { return depth_; }

  /// Metres at pixel (col, row); 0 or NaN where there is no measurement. Division, not
  /// multiplication by a reciprocal, so that value / 5000 is exactly what the dataset defines.
  double depth_m(int col, int row) const {
    if (depth_.type() == CV_16UC1) return depth_.ptr<std::uint16_t>(row)[col] / units_per_metre_;
    return depth_.ptr<float>(row)[col] / units_per_metre_;
  }

 private:
  cv::Mat depth_;
  double units_per_metre_;
};

}  // namespace opencv

namespace traits {

template <>
struct DepthImage<opencv::DepthView> {
  static int width(const opencv::DepthView& d) { return d.width(); }
  static int height(const opencv::DepthView& d) { return d.height(); }
  static double depth_m(const opencv::DepthView& d, int col, int row) { return d.depth_m(col, row); }
};

}  // namespace traits
}  // namespace cge
