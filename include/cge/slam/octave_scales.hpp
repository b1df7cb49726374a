#pragma once
// OctaveScales: scale_factor^octave, the pixel size of an ORB pyramid level (ORB-SLAM2's
// mvScaleFactors), looked up instead of computed with std::pow at every candidate keypoint of the
// point fusion and every observation of the bundle-adjustment setup: on the real fr1/rpy slice the
// fusion of a keyframe took 4.3 ms median with std::pow there, 2.9 ms with the table (docs/
// BENCHMARK.md). The table holds the values std::pow gives, so a lookup returns the same double
// as the call it replaces and the outputs stay the same byte for byte.
#include <algorithm>
#include <array>
#include <cmath>

namespace cge {
namespace slam {

class OctaveScales {
 public:
  /// Levels 0 .. kTableLevels - 1 are tabulated; higher ones fall back to std::pow.
  static constexpr int kTableLevels = 32;

  explicit OctaveScales(double scale_factor) : scale_factor_(scale_factor) {
    for (int level = 0; level < kTableLevels; ++level) table_[static_cast<std::size_t>(level)] = std::pow(scale_factor, level);
  }

  /// scale_factor^max(octave, 0): a keypoint without an octave (-1) counts as level 0.
  double operator()(int octave) const {
    const int level = std::max(octave, 0);
    return level < kTableLevels ? table_[static_cast<std::size_t>(level)] : std::pow(scale_factor_, level);
  }

  double scale_factor() const { return scale_factor_; }

 private:
  double scale_factor_;
  std::array<double, kTableLevels> table_{};
};

}  // namespace slam
}  // namespace cge
