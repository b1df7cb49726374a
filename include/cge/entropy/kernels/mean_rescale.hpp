#pragma once
// The rescaling rule of TieMode::mean that every degree-sum kernel applies (docs/METHOD.md
// section 4), in one place so that the kernels' tables agree bit for bit.
//
// TieMode::mean needs only the ratio S / N, and every later level is linear in this one, so a
// source whose path counts grow huge has its whole level scaled by mean_rescale_factor(): exact
// (a power of two), and N never overflows however tie-rich the graph. TieMode::all needs the true
// sums and reports overflow instead. The rule: a level is rescaled when its largest count passed
// 2^512.

#include <cmath>
#include <cstdint>

#include "cge/core/bits.hpp"

namespace cge {
namespace detail {

inline bool mean_level_needs_rescale(double level_max_count) { return level_max_count > std::ldexp(1.0, 512); }
inline double mean_rescale_factor() { return std::ldexp(1.0, -512); }

/// The lanes of `active_lanes` whose level needs rescaling (level_max_count[lane]: largest count),
/// for the kernels that run 64 sources at once.
inline std::uint64_t lanes_to_rescale(std::uint64_t active_lanes, const double* level_max_count) {
  std::uint64_t large = 0;
  for (std::uint64_t m = active_lanes; m; m &= m - 1) {
    const int i = lowest_bit(m);
    if (mean_level_needs_rescale(level_max_count[i])) large |= std::uint64_t(1) << i;
  }
  return large;
}

}  // namespace detail
}  // namespace cge
