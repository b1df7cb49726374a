#pragma once
// The pixel a sub-pixel coordinate falls on, written once for every reader of masks and depth
// (DepthMADFilter, GraphBuilder, the OpenCV adapters): the nearest pixel centre.

#include <algorithm>
#include <cmath>

namespace cge {

/// Index of the pixel whose centre is nearest to `coordinate` along an axis of `extent` pixels,
/// clamped into [0, extent - 1] (extent >= 1). Pixel i has its centre at i, so a coordinate on the
/// far border (== extent) reads the last pixel. std::lround rounds the exact value, halves away
/// from zero; floor(x + 0.5) would round 0.49999999999999994 up, because x + 0.5 rounds to 1.
/// The coordinate must be finite (callers validate it and name the keypoint when it is not).
inline int nearest_pixel_index(double coordinate, int extent) {
  return std::clamp(static_cast<int>(std::lround(coordinate)), 0, extent - 1);
}

}  // namespace cge
