#include "cge/mapping/map_dynamic_region.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "cge/opencv/disc_kernel.hpp"

namespace cge {
namespace mapping {

void check_settings(const DynamicRegionSettings& s) {
  const auto bad = [](const std::string& what) { throw std::invalid_argument("DynamicRegionSettings." + what); };
  if (s.edge_dilation_px < 0 || s.edge_dilation_px > 1000) bad("edge_dilation_px must be in 0 .. 1000");
  if (s.min_instance_px < 1) bad("min_instance_px must be >= 1");
  if (!(s.mad_scale >= 0 && std::isfinite(s.mad_scale))) bad("mad_scale must be finite and >= 0");
  if (!(s.min_band_half_width_m >= 0 && std::isfinite(s.min_band_half_width_m)))
    bad("min_band_half_width_m must be finite and >= 0");
  if (!(s.max_band_half_width_m >= s.min_band_half_width_m && std::isfinite(s.max_band_half_width_m)))
    bad("max_band_half_width_m must be finite and >= min_band_half_width_m");
  for (const double m : {s.box_margin_side, s.box_margin_top, s.box_margin_bottom}) {
    if (!(m >= 0 && m <= 100)) bad("box margins must be in [0, 100] box heights");
  }
}

namespace {

bool valid_depth(float z) { return z > 0 && std::isfinite(z); }

/// The lower median (element (n - 1) / 2 in ascending order); `values` is reordered. n > 0.
float lower_median(std::vector<float>& values) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>((values.size() - 1) / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

cv::Mat dynamic_region(const cv::Mat& dynamic_mask, const cv::Mat& depth_m, const DynamicRegionSettings& s) {
  check_settings(s);
  if (depth_m.type() != CV_32FC1) throw std::invalid_argument("dynamic_region: depth_m must be CV_32FC1");
  cv::Mat region = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  if (dynamic_mask.empty()) return region;
  if (dynamic_mask.type() != CV_8UC1 || dynamic_mask.size() != depth_m.size()) {
    throw std::invalid_argument("dynamic_region: dynamic_mask must be CV_8UC1 of the depth image's size");
  }
  const cv::Mat binary = dynamic_mask != 0;

  // 1. The mask and its rim: dilation by a Euclidean disc (pixels outside the image are ignored).
  if (s.edge_dilation_px > 0) {
    cv::dilate(binary, region, opencv::disc_kernel(s.edge_dilation_px));
  } else {
    binary.copyTo(region);
  }

  // 2. Per instance: pixels in the grown box whose depth lies in the instance's depth band.
  cv::Mat components, stats, centroids;
  const int n = cv::connectedComponentsWithStats(binary, components, stats, centroids, 8, CV_32S);
  std::vector<std::vector<float>> depths(static_cast<std::size_t>(n));
  for (int v = 0; v < depth_m.rows; ++v) {
    const int* c = components.ptr<int>(v);
    const float* z = depth_m.ptr<float>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (c[u] > 0 && valid_depth(z[u])) depths[static_cast<std::size_t>(c[u])].push_back(z[u]);
    }
  }
  for (int k = 1; k < n; ++k) {
    std::vector<float>& d = depths[static_cast<std::size_t>(k)];
    if (static_cast<int>(d.size()) < s.min_instance_px) continue;
    const float median = lower_median(d);
    for (float& x : d) x = std::abs(x - median);
    const double mad = lower_median(d);
    const double half = std::clamp(s.mad_scale * mad, s.min_band_half_width_m, s.max_band_half_width_m);
    const int left = stats.at<int>(k, cv::CC_STAT_LEFT), top = stats.at<int>(k, cv::CC_STAT_TOP);
    const int width = stats.at<int>(k, cv::CC_STAT_WIDTH), height = stats.at<int>(k, cv::CC_STAT_HEIGHT);
    const auto grow = [height](double fraction) { return static_cast<int>(std::ceil(fraction * height)); };
    const int u0 = std::max(0, left - grow(s.box_margin_side));
    const int u1 = std::min(depth_m.cols, left + width + grow(s.box_margin_side));
    const int v0 = std::max(0, top - grow(s.box_margin_top));
    const int v1 = std::min(depth_m.rows, top + height + grow(s.box_margin_bottom));
    for (int v = v0; v < v1; ++v) {
      const float* z = depth_m.ptr<float>(v);
      std::uint8_t* out = region.ptr<std::uint8_t>(v);
      for (int u = u0; u < u1; ++u) {
        if (valid_depth(z[u]) && std::abs(static_cast<double>(z[u]) - median) <= half) out[u] = 255;
      }
    }
  }
  return region;
}

}  // namespace mapping
}  // namespace cge
