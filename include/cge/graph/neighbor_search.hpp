#pragma once
// Fixed-radius neighbour search over a frame's node positions: the policy behind GraphBuilder.
//
// Contract for a policy NS used as GraphBuilder<Scalar, NS>:
//   void build(const std::vector<Eigen::Matrix<Scalar, 2, 1>>& points, Scalar typical_radius);
//       index the points (called once per graph; typical_radius is the base radius R in pixels)
//   template <class Visit> void for_each_within(std::int32_t query, Scalar radius, Visit&& visit) const;
//       call visit(j, d2) exactly once for every indexed point j != query with
//       within_radius(points[query], points[j], radius), in any order, where
//       d2 = squared_distance(points[query], points[j]).
// Every policy must decide membership with cge::within_radius and nothing else: that is what makes
// the graphs of all policies identical, bit for bit. A policy may only skip points it has proved
// to lie outside the radius.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "cge/graph/grid_scan_avx512.hpp"

namespace cge {

/// Which implementation scans a grid query's candidates. Both report the same points with the
/// same squared distances: the choice changes only the speed.
enum class GridScanKernel {
  automatic,  ///< AVX-512 where the CPU has it (double and float coordinates), else portable
  portable,   ///< plain C++
  avx512,     ///< x86-64 with AVX-512 F; build() throws std::invalid_argument where it cannot run
};

/// The one membership test of every neighbour search: squared Euclidean distance <= radius^2,
/// computed the same way everywhere so that all policies agree to the last bit.
template <typename Scalar>
inline bool within_radius(const Eigen::Matrix<Scalar, 2, 1>& a, const Eigen::Matrix<Scalar, 2, 1>& b, Scalar radius) {
  const Scalar dx = a.x() - b.x();
  const Scalar dy = a.y() - b.y();
  return dx * dx + dy * dy <= radius * radius;
}

/// Squared Euclidean distance, computed as in within_radius.
template <typename Scalar>
inline Scalar squared_distance(const Eigen::Matrix<Scalar, 2, 1>& a, const Eigen::Matrix<Scalar, 2, 1>& b) {
  const Scalar dx = a.x() - b.x();
  const Scalar dy = a.y() - b.y();
  return dx * dx + dy * dy;
}

/// O(n) per query. The reference every other policy is tested against.
template <typename Scalar>
class BruteForceNeighborSearch {
 public:
  using Point = Eigen::Matrix<Scalar, 2, 1>;

  void build(const std::vector<Point>& points, Scalar /*typical_radius*/) { points_ = &points; }

  template <typename Visit>
  void for_each_within(std::int32_t query, Scalar radius, Visit&& visit) const {
    const std::vector<Point>& pts = *points_;
    const Point& q = pts[static_cast<std::size_t>(query)];
    const Scalar rr = radius * radius;
    for (std::int32_t j = 0; j < static_cast<std::int32_t>(pts.size()); ++j) {
      const Scalar d2 = squared_distance(q, pts[static_cast<std::size_t>(j)]);
      if (d2 <= rr && j != query) visit(j, d2);
    }
  }

 private:
  const std::vector<Point>* points_ = nullptr;
};

/// Uniform grid with square cells (counting-sort layout, no per-cell allocation). Coordinates are
/// copied in cell order so that a query scans contiguous memory.
/// Expected O(1 + neighbours) per query at radius ~ cell size for points spread over the image.
template <typename Scalar>
class GridNeighborSearch {
 public:
  using Point = Eigen::Matrix<Scalar, 2, 1>;

  /// Cell side as a multiple of the typical radius R. 1 means a query at R scans at most 3 x 3 cells.
  Scalar cell_size_factor = Scalar(1);
  /// Upper bound on the number of cells, so that a tiny radius cannot allocate a huge grid.
  std::int64_t max_cells = std::int64_t(1) << 20;
  /// Implementation of the candidate scan (same results, different speed).
  GridScanKernel scan_kernel = GridScanKernel::automatic;

  /// True when `kernel` can scan Scalar coordinates here (automatic and portable always can).
  static bool scan_kernel_available(GridScanKernel kernel) {
    return kernel != GridScanKernel::avx512 || (kSimdScalar && detail::avx512_grid_scan_supported());
  }

  void build(const std::vector<Point>& points, Scalar typical_radius) {
    if (!scan_kernel_available(scan_kernel)) {
      throw std::invalid_argument(
          "GridNeighborSearch: the avx512 scan needs an x86-64 CPU with AVX-512 F, a GCC or Clang build, and "
          "float or double coordinates");
    }
    use_avx512_ = kSimdScalar && scan_kernel != GridScanKernel::portable && detail::avx512_grid_scan_supported();
    const std::size_t n = points.size();
    cols_ = rows_ = 0;
    if (n == 0) return;
    min_ = points[0];
    Point max = points[0];
    for (const Point& p : points) {
      min_ = min_.cwiseMin(p);
      max = max.cwiseMax(p);
    }
    const Scalar extent = std::max(max.x() - min_.x(), max.y() - min_.y());
    cell_ = typical_radius * cell_size_factor;
    if (!(cell_ > 0) || !std::isfinite(cell_)) cell_ = extent > 0 ? extent : Scalar(1);
    // Decide in floating point and convert only counts that fit: with a tiny cell the integer
    // counts (and their product) would overflow. A grid has at least one cell.
    const Scalar cell_limit = static_cast<Scalar>(std::max<std::int64_t>(max_cells, 1));
    for (;;) {  // enlarge cells until the grid respects max_cells
      const Scalar cols = std::floor((max.x() - min_.x()) / cell_) + 1;
      const Scalar rows = std::floor((max.y() - min_.y()) / cell_) + 1;
      if (cols * rows <= cell_limit) {
        cols_ = static_cast<std::int64_t>(cols);
        rows_ = static_cast<std::int64_t>(rows);
        break;
      }
      cell_ *= 2;
    }
    inv_cell_ = Scalar(1) / cell_;
    std::vector<std::int32_t> cell_of(n);
    cell_start_.assign(static_cast<std::size_t>(cols_ * rows_) + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t c = cell_index(points[i].x() - min_.x(), cols_);
      const std::int64_t r = cell_index(points[i].y() - min_.y(), rows_);
      cell_of[i] = static_cast<std::int32_t>(r * cols_ + c);
      ++cell_start_[static_cast<std::size_t>(cell_of[i]) + 1];
    }
    for (std::size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
    members_.resize(n);
    xs_.resize(n);
    ys_.resize(n);
    std::vector<std::int32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t slot = static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++);
      members_[slot] = static_cast<std::int32_t>(i);
      xs_[slot] = points[i].x();
      ys_[slot] = points[i].y();
    }
    points_ = &points;
    hit_member_.resize(n + detail::kGridScanPadding);
    hit_d2_.resize(n + detail::kGridScanPadding);
  }

  template <typename Visit>
  void for_each_within(std::int32_t query, Scalar radius, Visit&& visit) const {
    if (cols_ == 0) return;
    const Point& q = (*points_)[static_cast<std::size_t>(query)];
    // Pad the scanned range by a relative epsilon: within_radius may accept a point a few ulps
    // beyond `radius` after rounding, and such a point must not be skipped.
    const Scalar reach = radius * (Scalar(1) + Scalar(64) * std::numeric_limits<Scalar>::epsilon());
    const std::int64_t c0 = cell_index(q.x() - reach - min_.x(), cols_);
    const std::int64_t c1 = cell_index(q.x() + reach - min_.x(), cols_);
    const std::int64_t r0 = cell_index(q.y() - reach - min_.y(), rows_);
    const std::int64_t r1 = cell_index(q.y() + reach - min_.y(), rows_);
    const Scalar rr = radius * radius;
    const Scalar qx = q.x();
    const Scalar qy = q.y();
    // Compact the hits of all rows without a branch per candidate (the test is taken about half
    // the time, so a branch would mispredict constantly), then visit them in one loop.
    std::size_t hits = 0;
#if CGE_GRID_SCAN_HAVE_AVX512
    if constexpr (kSimdScalar) {
      if (use_avx512_ && r1 - r0 < kMaxRuns) {
        std::int32_t begin[kMaxRuns], end[kMaxRuns];
        const int runs = static_cast<int>(r1 - r0 + 1);
        for (int i = 0; i < runs; ++i) {
          // Cells of a row are contiguous, so one run covers columns c0..c1.
          const std::size_t row_base = static_cast<std::size_t>((r0 + i) * cols_);
          begin[i] = cell_start_[row_base + static_cast<std::size_t>(c0)];
          end[i] = cell_start_[row_base + static_cast<std::size_t>(c1) + 1];
        }
        hits = detail::grid_scan_avx512(xs_.data(), ys_.data(), members_.data(), begin, end, runs, qx, qy, rr, query,
                                        hit_member_.data(), hit_d2_.data());
        for (std::size_t h = 0; h < hits; ++h) visit(hit_member_[h], hit_d2_[h]);
        return;
      }
    }
#endif
    for (std::int64_t r = r0; r <= r1; ++r) {
      const std::size_t row_base = static_cast<std::size_t>(r * cols_);
      // Cells of a row are contiguous, so one run covers columns c0..c1.
      const std::int32_t begin = cell_start_[row_base + static_cast<std::size_t>(c0)];
      const std::int32_t end = cell_start_[row_base + static_cast<std::size_t>(c1) + 1];
      for (std::int32_t k = begin; k < end; ++k) {
        // Same arithmetic as squared_distance(q, p_j), so the result is bit-identical.
        const Scalar dx = qx - xs_[static_cast<std::size_t>(k)];
        const Scalar dy = qy - ys_[static_cast<std::size_t>(k)];
        const Scalar d2 = dx * dx + dy * dy;
        const std::int32_t j = members_[static_cast<std::size_t>(k)];
        hit_member_[hits] = j;
        hit_d2_[hits] = d2;
        hits += static_cast<std::size_t>((d2 <= rr) & (j != query));
      }
    }
    for (std::size_t h = 0; h < hits; ++h) visit(hit_member_[h], hit_d2_[h]);
  }

 private:
  /// Cell coordinate of an offset from the grid's minimum, clamped to [0, count - 1]. Truncation
  /// equals floor for non-negative values, and every negative value clamps to 0 either way.
  std::int64_t cell_index(Scalar offset, std::int64_t count) const {
    const Scalar c = offset * inv_cell_;
    if (!(c >= Scalar(0))) return 0;
    if (c >= static_cast<Scalar>(count)) return count - 1;
    return static_cast<std::int64_t>(c);
  }

  const std::vector<Point>* points_ = nullptr;
  Point min_ = Point::Zero();
  Scalar cell_ = Scalar(1);
  Scalar inv_cell_ = Scalar(1);
  std::int64_t cols_ = 0;
  std::int64_t rows_ = 0;
  std::vector<std::int32_t> cell_start_;
  std::vector<std::int32_t> members_;
  std::vector<Scalar> xs_, ys_;
  static constexpr bool kSimdScalar = std::is_same<Scalar, double>::value || std::is_same<Scalar, float>::value;
  static constexpr std::int64_t kMaxRuns = 16;  // rows scanned by one AVX-512 call (more: portable)
  bool use_avx512_ = false;
  // Scratch for the hits of a query. Mutable: a query changes no observable state, and
  // GraphBuilder works on its own copy of the policy, so concurrent builds never share it.
  mutable std::vector<std::int32_t> hit_member_;
  mutable std::vector<Scalar> hit_d2_;
};

}  // namespace cge
