#pragma once
// The per-frame quantities of patch keyframe selection (docs/METHOD.md section 2): features per
// patch, the distribution vector Z, its cosine similarity, the dense-patch mean and the semantic
// centroid. Pure functions; PatchKeyframeSelector composes them.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iterator>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "cge/core/point_traits.hpp"
#include "cge/frontend/patch_grid.hpp"

namespace cge {

/// Z has 11 bins of width 2 (the paper's definition, not a tuning knob): bin i < 10 holds the
/// patches with 2i < c <= 2(i+1) features, bin 10 those with c > 20; empty patches are in no bin.
/// The bins fit a load of about 10 features per patch (1000 features on 10 x 10 patches).
constexpr int kPatchHistogramBins = 11;
constexpr int kPatchHistogramBinWidth = 2;
using PatchHistogram = std::array<int, kPatchHistogramBins>;

/// Bin of a patch holding `count` features, or -1 for an empty patch.
constexpr int patch_histogram_bin(int count) {
  if (count <= 0) return -1;
  if (count > kPatchHistogramBinWidth * (kPatchHistogramBins - 1)) return kPatchHistogramBins - 1;
  return (count - 1) / kPatchHistogramBinWidth;
}

/// Features per patch of `grid`, row-major. `keypoints` is any range of points adapted by
/// cge::traits::Point2. Throws std::invalid_argument for a bad grid or for a keypoint that is not
/// finite or lies outside the closed image rectangle (naming its index).
template <typename Scalar, typename Keypoints>
std::vector<int> count_patch_features(const PatchGrid<Scalar>& grid, const Keypoints& keypoints) {
  using Point = typename PatchGrid<Scalar>::Point;
  grid.validate();
  std::vector<int> counts(static_cast<std::size_t>(grid.patch_count()), 0);
  std::size_t index = 0;
  for (const auto& kp : keypoints) {
    const Point p(static_cast<Scalar>(point_x(kp)), static_cast<Scalar>(point_y(kp)));
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !grid.image.contains(p)) {
      std::ostringstream msg;
      msg << "count_patch_features: keypoint #" << index << " at (" << p.x() << ", " << p.y()
          << ") is not finite or lies outside the image region";
      throw std::invalid_argument(msg.str());
    }
    ++counts[static_cast<std::size_t>(grid.patch_of(p))];
    ++index;
  }
  return counts;
}

/// Z from features per patch. Throws std::invalid_argument for a negative count.
inline PatchHistogram patch_histogram(const std::vector<int>& counts) {
  PatchHistogram z{};
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (counts[i] < 0) {
      std::ostringstream msg;
      msg << "patch_histogram: patch " << i << " has a negative feature count " << counts[i];
      throw std::invalid_argument(msg.str());
    }
    const int bin = patch_histogram_bin(counts[i]);
    if (bin >= 0) ++z[static_cast<std::size_t>(bin)];
  }
  return z;
}

/// S_cos(a, b) = a.b / (|a| |b|), in [0, 1]. The cosine is undefined for a zero vector (a frame
/// without features); we define it as 1 when both are zero (nothing to tell apart) and 0 when
/// exactly one is (the distributions share nothing).
inline double histogram_cosine(const PatchHistogram& a, const PatchHistogram& b) {
  std::int64_t dot = 0, na = 0, nb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    dot += static_cast<std::int64_t>(a[i]) * b[i];
    na += static_cast<std::int64_t>(a[i]) * a[i];
    nb += static_cast<std::int64_t>(b[i]) * b[i];
  }
  if (na == 0 && nb == 0) return 1.0;
  if (na == 0 || nb == 0) return 0.0;
  // One square root of the exact integer product, so that proportional vectors give exactly 1;
  // the clamp only absorbs the last-bit rounding of that root.
  return std::min(1.0, static_cast<double>(dot) / std::sqrt(static_cast<double>(na) * static_cast<double>(nb)));
}

/// (alpha_avg, beta_avg): the mean centre of the `num_dense` patches with the most features.
/// Resolutions: patches tied with the num_dense-th largest count are all included, so the set does
/// not depend on patch numbering; empty patches never count (fewer than num_dense non-empty patches:
/// the mean of the non-empty ones); a frame without features has the grid's centre (the image
/// centre) as its mean. Throws std::invalid_argument when counts and grid disagree in size,
/// num_dense < 1 or a count is negative.
template <typename Scalar>
Eigen::Matrix<Scalar, 2, 1> dense_patch_mean(const PatchGrid<Scalar>& grid, const std::vector<int>& counts,
                                             int num_dense) {
  if (counts.size() != static_cast<std::size_t>(grid.patch_count())) {
    std::ostringstream msg;
    msg << "dense_patch_mean: " << counts.size() << " patch counts for a grid of " << grid.cols << " x " << grid.rows;
    throw std::invalid_argument(msg.str());
  }
  if (num_dense < 1) throw std::invalid_argument("dense_patch_mean: num_dense must be at least 1");
  std::vector<int> occupied;
  for (const int c : counts) {
    if (c < 0) throw std::invalid_argument("dense_patch_mean: negative feature count");
    if (c > 0) occupied.push_back(c);
  }
  if (occupied.empty()) return grid.image.centre();
  const std::size_t take = std::min(occupied.size(), static_cast<std::size_t>(num_dense));
  std::nth_element(occupied.begin(), occupied.begin() + static_cast<std::ptrdiff_t>(take - 1), occupied.end(),
                   std::greater<int>());
  const int cutoff = occupied[take - 1];  // the take-th largest count
  Eigen::Matrix<Scalar, 2, 1> sum = Eigen::Matrix<Scalar, 2, 1>::Zero();
  int included = 0;
  for (int patch = 0; patch < grid.patch_count(); ++patch) {  // ascending index: a fixed summation order
    if (counts[static_cast<std::size_t>(patch)] >= cutoff) {
      sum += grid.patch_centre(patch);
      ++included;
    }
  }
  return sum / static_cast<Scalar>(included);
}

/// Mean of the instance centres (all classes), summed in the given order; none when there are no
/// instances (then D_sum = D_fp).
template <typename Scalar>
std::optional<Eigen::Matrix<Scalar, 2, 1>> semantic_centroid(const std::vector<Eigen::Matrix<Scalar, 2, 1>>& centres) {
  if (centres.empty()) return std::nullopt;
  Eigen::Matrix<Scalar, 2, 1> sum = Eigen::Matrix<Scalar, 2, 1>::Zero();
  for (const auto& c : centres) sum += c;
  return Eigen::Matrix<Scalar, 2, 1>(sum / static_cast<Scalar>(centres.size()));
}

}  // namespace cge
