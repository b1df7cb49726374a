#pragma once
// An occupied voxel of the octree map at its finest resolution, as the scores and pictures see it
// (no OctoMap types: cge/octomap/semantic_octree.hpp makes these).

#include <vector>

#include "cge/voxels/class_palette.hpp"
#include "cge/voxels/semantic_point.hpp"

namespace cge {
namespace mapping {

struct MapVoxel {
  VoxelIndex index = VoxelIndex::Zero();  ///< floor(centre / resolution): the voxel_of grid
  Rgb8 colour = kOtherClassColour;        ///< the node's colour
  std::uint16_t class_label = 0;          ///< class_label_of_colour(colour): COCO id + 1, 0 = none
};

/// The occupied voxels of a map with their resolution; voxels sorted by voxel_less, unique.
struct OccupiedVoxels {
  double resolution_m = 0.05;
  std::vector<MapVoxel> voxels;
};

}  // namespace mapping
}  // namespace cge
