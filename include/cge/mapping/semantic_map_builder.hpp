#pragma once
// SemanticMapBuilder: the dense semantic point cloud and the semantic octree of a run, built from
// keyframes (docs/METHOD.md section 8; docs/MAPS.md).
//
// Per keyframe: every `pixel_stride`-th pixel with valid depth in (0, max_range_m], outside the
// dynamic region (the dynamic mask grown by dynamic_region()), is back-projected with the keyframe's pose
// T_world_camera. The cloud keeps these points voxel-filtered per keyframe (cloud_voxel_m) and once more over all
// keyframes on request (cloud()); the octree gets them as one scan from the camera centre. Because poses change after
// loop closure, rebuild(keyframes) clears both and inserts every keyframe again.
//
// Needs Keyframe::depth_m (CV_32FC1), and uses bgr (CV_8UC3, for colour_unlabelled_from_image),
// class_labels (CV_16UC1, empty = no classes) and dynamic_mask (CV_8UC1, empty = nothing dynamic)
// when present; images of one keyframe must have one size.
//
// Determinism: no threads, no hashing in any output order: same keyframes, same bytes.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "cge/core/lens_distortion.hpp"
#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/mapping/map_dynamic_region.hpp"
#include "cge/voxels/map_voxel.hpp"
#include "cge/voxels/semantic_integrity.hpp"
#include "cge/voxels/semantic_point.hpp"
#include "cge/octomap/semantic_octree.hpp"
#include "cge/slam/keyframe.hpp"

namespace cge {
namespace mapping {

struct SemanticMapSettings {
  int pixel_stride = 2;  ///< cloud: back-project every n-th pixel along rows and columns, >= 1
  /// Octree: cast rays to every n-th pixel only (a multiple of pixel_stride). A 5 cm voxel at 3 m
  /// spans about 9 pixels, so 4 loses little and is 4 times cheaper than 2.
  int octree_pixel_stride = 4;
  double max_range_m = 4.0;      ///< depth beyond this is not used (sensor noise grows with range), metres
  double cloud_voxel_m = 0.02;   ///< voxel filter of the dense cloud, metres, > 0
  bool use_dynamic_mask = true;  ///< leave out pixels of Keyframe::dynamic_mask (false: map everything)
  /// Leave out the mask's dynamic_region() (rim, depth band of each instance: what a segmenter
  /// missed) instead of the mask's pixels alone. Only with use_dynamic_mask.
  bool grow_dynamic_mask = true;
  DynamicRegionSettings dynamic_region;  ///< how the mask grows (map_dynamic_region.hpp)
  /// Colour of the cloud's points without a preset class colour: false = grey, true = the image's
  /// colour. (The octree always uses grey for them: its colours carry the class.)
  bool colour_unlabelled_from_image = false;
  /// Per keyframe and class, at least this many back-projected points make an integrity entity.
  int min_entity_points = 20;
  octomap_adapter::SemanticOctreeSettings octree;  ///< resolution (0.05 m) and occupancy model
};

/// Throws std::invalid_argument naming the first setting out of range.
void check_settings(const SemanticMapSettings& settings);

/// The map figures summary.json reports.
struct MapFigures {
  std::size_t keyframes = 0;            ///< keyframes inserted
  std::size_t cloud_points = 0;         ///< points of the voxel-filtered cloud
  std::size_t occupied_voxels = 0;      ///< occupied octree voxels at the finest resolution
  double integrity = 0;                 ///< Score_INT over keyframe entities (semantic_integrity.hpp)
  double fluctuation = 0;               ///< Score_flu
  int entities = 0;                     ///< keyframe entities scored
  std::size_t octree_memory_bytes = 0;  ///< OctoMap memoryUsage() plus the class votes
};

class SemanticMapBuilder {
 public:
  /// `distortion`: the colour camera's lens distortion (the depth image is registered to it); each
  /// pixel is back-projected along its undistorted ray.
  SemanticMapBuilder(const PinholeIntrinsics<double>& intrinsics, const SemanticMapSettings& settings = {},
                     const LensDistortion& distortion = {});

  /// Adds one keyframe to the cloud and the octree. Throws std::invalid_argument naming the
  /// keyframe id and the image when an image has the wrong type or size or the pose is not finite.
  void insert(const slam::Keyframe& keyframe);
  /// Clears the map and inserts every keyframe again (after loop closure moved the poses).
  void rebuild(const std::vector<slam::Keyframe>& keyframes);
  void clear();

  /// The static points of one keyframe in world coordinates (before any voxel filter), every
  /// pixel_stride-th pixel; with `octree_grid` set, only those on the octree_pixel_stride grid.
  std::vector<SemanticPoint> keyframe_points(const slam::Keyframe& keyframe, bool octree_grid = false) const;

  /// The dense cloud, voxel-filtered over all keyframes (cloud_voxel_m).
  std::vector<SemanticPoint> cloud() const;
  /// The octree's occupied voxels.
  OccupiedVoxels occupied_voxels() const { return octree_.occupied_voxels(); }
  /// Integrity entities: per keyframe, the voxel bounding box of each class's points.
  const std::vector<IntegrityEntity>& entities() const { return entities_; }

  /// Files; never overwrite unless asked (std::invalid_argument), std::runtime_error when unwritable.
  void write_ply(const std::filesystem::path& path, bool overwrite = false) const;
  void write_octree(const std::filesystem::path& path_ot, const std::filesystem::path& path_bt, bool overwrite = false);

  MapFigures scores() const;

  octomap_adapter::SemanticOctree& octree() { return octree_; }
  const SemanticMapSettings& settings() const { return settings_; }
  const PinholeIntrinsics<double>& intrinsics() const { return intrinsics_; }

 private:
  /// keyframe_points() at `stride` into `points`; with octree_positions set, also the points on the
  /// octree_pixel_stride grid (positions and labels), from the same pass.
  void back_project(const slam::Keyframe& keyframe, int stride, std::vector<SemanticPoint>& points,
                    std::vector<Eigen::Vector3f>* octree_positions, std::vector<std::uint16_t>* octree_labels) const;

  /// Per pixel of an image of `size`, the undistorted normalised ray ((u - cx) / fx, (v - cy) / fy)
  /// as CV_32FC2; computed once per image size (only with distortion).
  const cv::Mat& undistorted_rays(cv::Size size) const;

  PinholeIntrinsics<double> intrinsics_;
  LensDistortion distortion_;
  mutable cv::Mat rays_;  ///< cache of undistorted_rays(); not thread-safe, like the rest of the builder
  SemanticMapSettings settings_;
  octomap_adapter::SemanticOctree octree_;
  std::vector<SemanticPoint> filtered_points_;  ///< per-keyframe filtered points, in insertion order
  std::vector<IntegrityEntity> entities_;
  std::size_t keyframes_ = 0;
};

}  // namespace mapping
}  // namespace cge
