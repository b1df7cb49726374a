#pragma once
// cv::Mat masks as cge masks (cge/core/mask.hpp).
// - A CV_8UC1 cv::Mat is a binary mask: any non-zero byte is set (0/1 and 0/255 masks alike).
// - InstanceMask views one instance of an instance-label image (CV_16UC1 as the mask folders hold,
//   or CV_8UC1; 0 = background, k >= 1 = instance k): the pixels equal to its id are set.
// Neither copies pixels: they share the Mat's buffer (cv::Mat reference counting).
// An empty Mat is an empty mask (cge::traits::Mask::empty), whatever its type.

#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "cge/core/mask.hpp"

namespace cge {
namespace opencv {

/// Throws std::invalid_argument unless the Mat is empty or CV_8UC1.
inline void check_binary_mask_type(const cv::Mat& mask) {
  if (!mask.empty() && mask.type() != CV_8UC1) {
    throw std::invalid_argument("binary mask: the cv::Mat has type " + cv::typeToString(mask.type()) +
                                ", expected CV_8UC1 (non-zero = set); for an instance-label image use "
                                "cge::opencv::InstanceMask");
  }
}

/// The pixels of one instance in an instance-label image.
class InstanceMask {
 public:
  /// Throws std::invalid_argument when the labels are neither empty, CV_16UC1 nor CV_8UC1, or the
  /// id is not in 1 .. the type's largest value (0 is the background).
  InstanceMask(const cv::Mat& labels, int instance_id) : labels_(labels), id_(instance_id) {
    if (labels.empty()) return;
    if (labels.type() != CV_16UC1 && labels.type() != CV_8UC1) {
      throw std::invalid_argument("InstanceMask: the instance-label image has type " + cv::typeToString(labels.type()) +
                                  ", expected CV_16UC1 or CV_8UC1");
    }
    const int largest = labels.type() == CV_16UC1 ? 65535 : 255;
    if (instance_id < 1 || instance_id > largest) {
      std::ostringstream msg;
      msg << "InstanceMask: instance id " << instance_id << " is not in 1.." << largest << " ("
          << cv::typeToString(labels.type()) << " labels; 0 is the background)";
      throw std::invalid_argument(msg.str());
    }
  }

  int width() const { return labels_.cols; }
  int height() const { return labels_.rows; }
  bool empty() const { return labels_.empty(); }
  int instance_id() const { return id_; }
  const cv::Mat& labels() const { return labels_; }

  bool is_set(int col, int row) const {
    if (labels_.type() == CV_16UC1) return labels_.ptr<std::uint16_t>(row)[col] == id_;
    return labels_.ptr<std::uint8_t>(row)[col] == id_;
  }

 private:
  cv::Mat labels_;
  int id_;
};

}  // namespace opencv

namespace traits {

/// A CV_8UC1 cv::Mat; any other type throws std::invalid_argument on first use (width(), height()
/// or is_set()), so a label image passed by mistake is an error, never a silent misreading.
template <>
struct Mask<cv::Mat> {
  static int width(const cv::Mat& m) {
    opencv::check_binary_mask_type(m);
    return m.cols;
  }
  static int height(const cv::Mat& m) {
    opencv::check_binary_mask_type(m);
    return m.rows;
  }
  static bool is_set(const cv::Mat& m, int col, int row) {
    opencv::check_binary_mask_type(m);
    return m.ptr<std::uint8_t>(row)[col] != 0;
  }
  static bool empty(const cv::Mat& m) { return m.empty(); }
};

template <>
struct Mask<opencv::InstanceMask> {
  static int width(const opencv::InstanceMask& m) { return m.width(); }
  static int height(const opencv::InstanceMask& m) { return m.height(); }
  static bool is_set(const opencv::InstanceMask& m, int col, int row) { return m.is_set(col, row); }
  static bool empty(const opencv::InstanceMask& m) { return m.empty(); }
};

}  // namespace traits
}  // namespace cge
