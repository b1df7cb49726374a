#pragma once
// A point of the dense semantic cloud and the voxel grid the maps share.

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "cge/voxels/class_palette.hpp"

namespace cge {
namespace mapping {

/// One point of the dense semantic cloud, world frame.
struct SemanticPoint {
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();  ///< world coordinates, metres
  Rgb8 colour;                                           ///< display colour (class colour or image colour)
  std::uint16_t class_label = 0;                         ///< COCO class id + 1, 0 = no class
};

/// Integer coordinates of a voxel of side voxel_m: floor(p * (1 / voxel_m)) per axis, the rule of
/// OctoMap's coordToKey (its key minus 2^15), so cloud, octree and ghost voxels share one grid.
using VoxelIndex = Eigen::Vector3i;

/// The voxel containing p. Throws std::invalid_argument when voxel_m is not finite and > 0 or when
/// a coordinate of p / voxel_m is not finite or outside the int range.
inline VoxelIndex voxel_of(const Eigen::Vector3f& p, double voxel_m) {
  if (!(std::isfinite(voxel_m) && voxel_m > 0)) {
    throw std::invalid_argument("voxel_of: voxel size must be finite and > 0 (got " + std::to_string(voxel_m) + ")");
  }
  VoxelIndex v;
  for (int k = 0; k < 3; ++k) {
    const double q = std::floor(static_cast<double>(p[k]) * (1.0 / voxel_m));
    if (!(q >= std::numeric_limits<int>::min() && q <= std::numeric_limits<int>::max())) {
      throw std::invalid_argument("voxel_of: coordinate " + std::to_string(p[k]) + " is outside the voxel grid");
    }
    v[k] = static_cast<int>(q);
  }
  return v;
}

/// Lexicographic order (x, then y, then z) of voxel indices: the order of every sorted voxel list.
inline bool voxel_less(const VoxelIndex& a, const VoxelIndex& b) {
  if (a.x() != b.x()) return a.x() < b.x();
  if (a.y() != b.y()) return a.y() < b.y();
  return a.z() < b.z();
}

}  // namespace mapping
}  // namespace cge
