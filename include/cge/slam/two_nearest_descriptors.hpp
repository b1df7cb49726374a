#pragma once
// Brute-force two-nearest-neighbour matching of ORB descriptors (32-byte CV_8UC1 rows) by Hamming
// distance: what cv::BFMatcher(NORM_HAMMING).knnMatch(query, train, matches, 2) returns, without its
// per-pair call and tracing overhead (a third of a loop scene's run time went there).

#include <cstdint>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/bow/binary_descriptor.hpp"
#include "cge/slam/geometry/nearest_two.hpp"

namespace cge {
namespace slam {

/// For every query row, its nearest and second-nearest train rows (ascending distance; on equal
/// distances the lower train index first), as DMatch(queryIdx, trainIdx, distance); one match when
/// train has one row, none when it is empty. Throws std::invalid_argument unless both are CV_8UC1
/// with 32 columns (or empty).
inline std::vector<std::vector<cv::DMatch>> two_nearest_descriptors(const cv::Mat& query, const cv::Mat& train) {
  const auto check = [](const cv::Mat& m, const char* name) {
    if (!m.empty() && (m.type() != CV_8UC1 || m.cols != 32)) {
      throw std::invalid_argument(std::string("two_nearest_descriptors: ") + name + " must hold 32-byte CV_8UC1 rows");
    }
  };
  check(query, "query");
  check(train, "train");
  std::vector<std::vector<cv::DMatch>> out(static_cast<std::size_t>(query.rows));
  for (int q = 0; q < query.rows; ++q) {
    const std::uint8_t* a = query.ptr<std::uint8_t>(q);
    NearestTwo nearest;
    for (int t = 0; t < train.rows; ++t) nearest.add(t, bow::hamming_distance_32_bytes(a, train.ptr<std::uint8_t>(t)));
    auto& row = out[static_cast<std::size_t>(q)];
    if (nearest.best_index >= 0) row.emplace_back(q, nearest.best_index, static_cast<float>(nearest.best));
    if (nearest.second_index >= 0) row.emplace_back(q, nearest.second_index, static_cast<float>(nearest.second));
  }
  return out;
}

}  // namespace slam
}  // namespace cge
