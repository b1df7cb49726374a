#pragma once
// A Euclidean disc as a structuring element for cv::dilate / cv::erode: the masks of people grow
// or shrink by the same distance in every direction (the segmentation error model, the maps'
// dynamic region).

#include <cstdint>
#include <stdexcept>

#include <opencv2/core/mat.hpp>

namespace cge {
namespace opencv {

/// (2r + 1) x (2r + 1) CV_8UC1, 1 where dx^2 + dy^2 <= r^2, else 0. Throws for r < 0.
inline cv::Mat disc_kernel(int radius_px) {
  if (radius_px < 0) throw std::invalid_argument("disc_kernel: radius_px must be >= 0");
  cv::Mat kernel(2 * radius_px + 1, 2 * radius_px + 1, CV_8UC1, cv::Scalar(0));
  for (int dy = -radius_px; dy <= radius_px; ++dy) {
    for (int dx = -radius_px; dx <= radius_px; ++dx) {
      if (dx * dx + dy * dy <= radius_px * radius_px) kernel.at<std::uint8_t>(dy + radius_px, dx + radius_px) = 1;
    }
  }
  return kernel;
}

}  // namespace opencv
}  // namespace cge
