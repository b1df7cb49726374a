#pragma once
// Pictures of the maps without a 3-D viewer: an orthographic top view (looking down the world's -z
// axis, world x to the right, world y up in the image) of the octree's occupied voxels or of the
// dense cloud, with a z-buffer (the highest surface wins) and the class colour darkened with depth
// below the highest point, so that floor, furniture and walls read apart.

#include <filesystem>
#include <limits>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/voxels/map_voxel.hpp"
#include "cge/voxels/semantic_point.hpp"

namespace cge {
namespace mapping {

struct MapImageSettings {
  double pixels_per_metre = 60;  ///< image scale, pixels per metre, > 0
  int margin_px = 8;             ///< white border around the map, pixels, >= 0
  int max_side_px = 4096;        ///< larger maps are refused (std::invalid_argument), pixels
  double min_shade = 0.45;       ///< brightness of the lowest point relative to the highest, in [0, 1]
  /// Leave out everything above this height (e.g. the ceiling), metres; +infinity keeps all.
  double clip_above_m = std::numeric_limits<double>::infinity();
  int point_radius_px = 0;  ///< cloud points drawn as squares of side 2 r + 1 pixels, >= 0
};

/// Top view of the occupied voxels (CV_8UC3, BGR, white background). An empty map gives an image
/// of margins only.
cv::Mat render_top_view(const OccupiedVoxels& map, const MapImageSettings& settings = {});

/// Top view of a cloud.
cv::Mat render_top_view(const std::vector<SemanticPoint>& cloud, const MapImageSettings& settings = {});

/// Writes a PNG; std::invalid_argument when the file exists and !overwrite, std::runtime_error when
/// it cannot be written.
void write_png(const std::filesystem::path& path, const cv::Mat& image, bool overwrite = false);

}  // namespace mapping
}  // namespace cge
