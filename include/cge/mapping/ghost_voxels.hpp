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
//
// Keyframe poses (GhostVoxelSettings::frame_poses): a map built by a SLAM run puts each keyframe's
// points where its *estimated* pose says; a static floor seen with a pose a few millimetres off can
// fall into a voxel that the ground-truth P \ S counts as a ghost. Given the run's keyframe poses
// (e.g. cge_slam's keyframes.txt, already in the map's frame), only those frames are back-projected,
// each with its given pose: the ghost set is then P \ S of exactly the pixels and poses the map was
// built from, so an occupied voxel counts only when no static pixel of a keyframe lands in it and a
// moving person's pixel does (docs/MAPS.md, "Ghost voxels").

#include <cstddef>
#include <filesystem>
#include <vector>

#include <Eigen/Geometry>

#include "cge/voxels/map_voxel.hpp"
#include "cge/voxels/semantic_integrity.hpp"
#include "cge/voxels/semantic_point.hpp"
#include "cge/metrics/trajectory.hpp"

namespace cge {
namespace mapping {

struct GhostVoxelSettings {
  int pixel_stride = 1;                 ///< use every n-th pixel along rows and columns, >= 1
  double max_time_difference_s = 1e-3;  ///< largest gap between a frame and its ground-truth pose, seconds
  /// The map's frame from the ground truth's world frame: the ghost set is placed where a map built
  /// in another frame (a SLAM run starts at its first camera) has it; e.g. the inverse of the
  /// trajectory alignment T_groundtruth_estimate of cge::metrics::compute_ate. Identity: ground-truth poses.
  Eigen::Isometry3d T_map_world = Eigen::Isometry3d::Identity();
  /// Frames to back-project with their own poses T_map_camera instead of every frame with its
  /// ground-truth pose, e.g. a run's keyframes (timestamp within max_time_difference_s of a frame's).
  /// Empty: every frame, ground truth and T_map_world. Given: groundtruth.txt and T_map_world are not used.
  metrics::Trajectory frame_poses;
};

struct GhostVoxels {
  double resolution_m = 0.05;
  std::vector<VoxelIndex> ghost;  ///< P \ S, sorted by voxel_less
  std::size_t person_voxels = 0;  ///< |P|
  std::size_t static_voxels = 0;  ///< |S|
  int frames = 0;                 ///< frames read
};

/// The ghost set of the sequence in `folder` at `resolution_m`. Throws std::invalid_argument naming
/// the file when masks/, masks/instances.csv, camera.yaml or groundtruth.txt (without frame_poses)
/// are missing or malformed, a frame has no mask or no ground-truth pose, a mask's size differs from
/// its depth, or a pose of frame_poses matches no frame or is not finite.
GhostVoxels ghost_voxels_from_sequence(const std::filesystem::path& folder, double resolution_m,
                                       const GhostVoxelSettings& settings = {});

/// P \ S: the voxels of `person` that are not in `still` (both in any order, repeats allowed);
/// sorted by voxel_less, unique.
std::vector<VoxelIndex> ghost_set(std::vector<VoxelIndex> person, std::vector<VoxelIndex> still);

/// Occupied voxels of the map in the ghost set, over all occupied voxels (0 for an empty map).
/// Throws std::invalid_argument when the resolutions differ by more than 1e-9 m.
double ghost_fraction(const OccupiedVoxels& map, const GhostVoxels& ghosts);

}  // namespace mapping
}  // namespace cge
