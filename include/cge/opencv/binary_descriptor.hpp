#pragma once
// OpenCV ORB descriptors (CV_8UC1, 32 bytes per row) as cge::bow::BinaryDescriptor values.

#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/bow/binary_descriptor.hpp"

namespace cge {
namespace opencv {

/// Throws std::invalid_argument unless the Mat is empty or CV_8UC1 with 32 columns.
inline void check_orb_descriptors(const cv::Mat& descriptors, const char* what = "descriptors") {
  if (descriptors.empty()) return;
  if (descriptors.type() != CV_8UC1 || descriptors.cols != 32) {
    throw std::invalid_argument(std::string(what) + ": expected CV_8UC1 rows of 32 bytes (ORB), got " +
                                cv::typeToString(descriptors.type()) + " with " + std::to_string(descriptors.cols) +
                                " columns");
  }
}

/// Row `row` of a CV_8UC1 32-column Mat.
inline bow::BinaryDescriptor to_binary_descriptor(const cv::Mat& descriptors, int row) {
  return bow::descriptor_from_bytes(descriptors.ptr<std::uint8_t>(row));
}

/// Every row, in order.
inline std::vector<bow::BinaryDescriptor> to_binary_descriptors(const cv::Mat& descriptors) {
  check_orb_descriptors(descriptors);
  std::vector<bow::BinaryDescriptor> out;
  out.reserve(static_cast<std::size_t>(descriptors.rows));
  for (int r = 0; r < descriptors.rows; ++r) out.push_back(to_binary_descriptor(descriptors, r));
  return out;
}

/// The rows listed in `rows`, in that order (each must be in 0 .. rows - 1).
inline std::vector<bow::BinaryDescriptor> to_binary_descriptors(const cv::Mat& descriptors,
                                                                const std::vector<int>& rows) {
  check_orb_descriptors(descriptors);
  std::vector<bow::BinaryDescriptor> out;
  out.reserve(rows.size());
  for (int r : rows) {
    if (r < 0 || r >= descriptors.rows) {
      throw std::invalid_argument("to_binary_descriptors: row " + std::to_string(r) + " is not in 0 .. " +
                                  std::to_string(descriptors.rows - 1));
    }
    out.push_back(to_binary_descriptor(descriptors, r));
  }
  return out;
}

}  // namespace opencv
}  // namespace cge
