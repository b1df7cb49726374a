#pragma once
// Ghost voxels of a synthetic sequence: where a moving person was at some time and no static surface
// ever is. A map that left people in shows them as occupied voxels there (docs/MAPS.md).
//
// From a sequence folder written by cge::sim (docs/SIMULATION.md): every pixel_stride-th pixel with
// depth of every frame is back-projected with the ground-truth pose (groundtruth.txt, matched by
// timestamp) and the intrinsics of camera.yaml. Pixels of instances that masks/instances.csv marks
// moving (exact ground-truth labels, masks/<stem>.png) go to the person set P, the rest to the
// static set S; the ghost set is P \ S. Voxels as voxel_of (OctoMap's grid) at the map's resolution.
// Counting S removes the floor under the feet and the walls a person touches: only the space the
// bodies swept remains.

#include <cstddef>
#include <filesystem>
#include <vector>

#include <Eigen/Geometry>

#include "cge/mapping/map_voxel.hpp"
#include "cge/mapping/semantic_point.hpp"

namespace cge {
namespace mapping {

struct GhostVoxelSettings {
  int pixel_stride = 1;                 ///< use every n-th pixel along rows and columns, >= 1
  double max_time_difference_s = 1e-3;  ///< largest gap between a frame and its ground-truth pose, seconds
  /// The map's frame from the ground truth's world frame: the ghost set is placed where a map built
  /// in another frame (a SLAM run starts at its first camera) has it; e.g. the inverse of the
  /// trajectory alignment T_groundtruth_estimate of cge::metrics::compute_ate. Identity: ground-truth poses.
  Eigen::Isometry3d T_map_world = Eigen::Isometry3d::Identity();
};

struct GhostVoxels {
  double resolution_m = 0.05;
  std::vector<VoxelIndex> ghost;  ///< P \ S, sorted by voxel_less
  std::size_t person_voxels = 0;  ///< |P|
  std::size_t static_voxels = 0;  ///< |S|
  int frames = 0;                 ///< frames read
};

/// The ghost set of the sequence in `folder` at `resolution_m`. Throws std::invalid_argument naming
/// the file when masks/, masks/instances.csv, camera.yaml or groundtruth.txt are missing or
/// malformed, a frame has no mask or no ground-truth pose, or a mask's size differs from its depth.
GhostVoxels ghost_voxels_from_sequence(const std::filesystem::path& folder, double resolution_m,
                                       const GhostVoxelSettings& settings = {});

/// Occupied voxels of the map in the ghost set, over all occupied voxels (0 for an empty map).
/// Throws std::invalid_argument when the resolutions differ by more than 1e-9 m.
double ghost_fraction(const OccupiedVoxels& map, const GhostVoxels& ghosts);

}  // namespace mapping
}  // namespace cge
