#pragma once
// Brute-force two-nearest-neighbour matching of ORB descriptors (32-byte CV_8UC1 rows) by Hamming
// distance: what cv::BFMatcher(NORM_HAMMING).knnMatch(query, train, matches, 2) returns, without its
// per-pair call and tracing overhead (a third of a loop scene's run time went there).
// On x86-64 CPUs with the POPCNT instruction the row scan is compiled for it and chosen at run time
// (the build targets baseline x86-64, where a popcount takes a dozen operations); distances are
// whole bit counts, so both scans return the same matches.

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/bow/binary_descriptor.hpp"
#include "cge/slam/geometry/nearest_two.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CGE_NEAREST_TWO_HAVE_POPCNT 1
#else
#define CGE_NEAREST_TWO_HAVE_POPCNT 0
#endif

namespace cge {
namespace slam {
namespace detail {

/// The nearest two rows of `train` to the 32 bytes at `a`, in NearestTwo's visiting order (portable).
inline NearestTwo nearest_two_rows_portable(const std::uint8_t* a, const cv::Mat& train) {
  NearestTwo nearest;
  for (int t = 0; t < train.rows; ++t) nearest.add(t, bow::hamming_distance_32_bytes(a, train.ptr<std::uint8_t>(t)));
  return nearest;
}

/// True when this CPU runs nearest_two_rows_popcnt.
inline bool nearest_two_popcnt_supported() {
#if CGE_NEAREST_TWO_HAVE_POPCNT
  static const bool supported = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("popcnt") != 0;
  }();
  return supported;
#else
  return false;
#endif
}

#if CGE_NEAREST_TWO_HAVE_POPCNT
/// The same scan compiled for the POPCNT instruction; call only when nearest_two_popcnt_supported().
__attribute__((target("popcnt"))) inline NearestTwo nearest_two_rows_popcnt(const std::uint8_t* a,
                                                                             const cv::Mat& train) {
  std::uint64_t x[4];
  std::memcpy(x, a, sizeof x);
  NearestTwo nearest;
  for (int t = 0; t < train.rows; ++t) {
    std::uint64_t y[4];
    std::memcpy(y, train.ptr<std::uint8_t>(t), sizeof y);
    nearest.add(t, __builtin_popcountll(x[0] ^ y[0]) + __builtin_popcountll(x[1] ^ y[1]) +
                       __builtin_popcountll(x[2] ^ y[2]) + __builtin_popcountll(x[3] ^ y[3]));
  }
  return nearest;
}
#endif

/// The scan this CPU runs fastest.
inline NearestTwo nearest_two_rows(const std::uint8_t* a, const cv::Mat& train) {
#if CGE_NEAREST_TWO_HAVE_POPCNT
  if (nearest_two_popcnt_supported()) return nearest_two_rows_popcnt(a, train);
#endif
  return nearest_two_rows_portable(a, train);
}

}  // namespace detail

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
    const NearestTwo nearest = detail::nearest_two_rows(query.ptr<std::uint8_t>(q), train);
    auto& row = out[static_cast<std::size_t>(q)];
    if (nearest.best_index >= 0) row.emplace_back(q, nearest.best_index, static_cast<float>(nearest.best));
    if (nearest.second_index >= 0) row.emplace_back(q, nearest.second_index, static_cast<float>(nearest.second));
  }
  return out;
}

}  // namespace slam
}  // namespace cge
