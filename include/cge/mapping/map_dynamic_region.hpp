#pragma once
// The pixels a map must leave out of a keyframe: its dynamic mask grown by what a segmenter tends
// to miss (docs/MAPS.md, "Dynamic region").
//
// A segmentation network misses the rim of a person (an eroded mask), the feet (the bottom of the
// mask lost) and now and then a whole frame's instance. The dynamic-feature filter handles the
// first two for keypoints with the depth MAD of each instance (docs/METHOD.md section 1); the map
// applies the same idea to its pixels:
//   1. every mask pixel and every pixel within `edge_dilation_px` of one (the eroded rim);
//   2. per instance (an 8-connected component of the mask with at least `min_instance_px` pixels
//      with valid depth): its depth band, median +- mad_scale * MAD of the depths of its pixels
//      (MAD = median absolute deviation from the median), the half width clamped to
//      [min_band_half_width_m, max_band_half_width_m]; every pixel inside the instance's box,
//      grown by fractions of the box height (most downwards, where feet get lost), whose depth
//      lies in the band also counts as dynamic.
// A missed instance has no mask in its frame and is left to the octree's free-space carving.
//
// Determinism: no randomness, no threads; the result depends on the two images only.

#include <opencv2/core.hpp>

namespace cge {
namespace mapping {

struct DynamicRegionSettings {
  /// The rim: pixels within this Euclidean distance of the mask join it, pixels, >= 0. A network's
  /// mask often stops 1-3 pixels short of the silhouette (the simulator erodes by 2).
  int edge_dilation_px = 3;
  /// Components with fewer pixels of valid depth get no depth band (too few for a median), >= 1.
  int min_instance_px = 30;
  /// k of the depth band median +- k * MAD, dimensionless, >= 0. A body's MAD about its median is a
  /// few centimetres; feet and a swinging arm lie several MADs out.
  double mad_scale = 4.0;
  /// Lower clamp of the band's half width, metres, >= 0: a flat-on torso has a tiny MAD, but the
  /// limbs around it are still tens of centimetres nearer or farther.
  double min_band_half_width_m = 0.25;
  /// Upper clamp of the band's half width, metres, >= min: two people merged into one component
  /// must not make a band that swallows the wall behind them.
  double max_band_half_width_m = 0.6;
  /// Box growth, as fractions of the box's height in pixels, >= 0: sideways (arms, erosion) ...
  double box_margin_side = 0.1;
  /// ... upwards (hair, head cut by erosion) ...
  double box_margin_top = 0.05;
  /// ... and downwards: lost feet take the bottom 15 % of a mask, i.e. about 18 % of the height
  /// that is left; 0.3 also covers a stride's foot ahead of the box.
  double box_margin_bottom = 0.3;
};

/// Throws std::invalid_argument naming the first setting out of range.
void check_settings(const DynamicRegionSettings& settings);

/// The dynamic region (see above) of a keyframe: CV_8UC1, 255 = leave out, 0 = map. `dynamic_mask`
/// is CV_8UC1 (non-zero = dynamic), `depth_m` CV_32FC1 metres (0 or not finite = no depth), both of
/// one size. An empty mask gives an all-zero region. Throws std::invalid_argument for wrong types
/// or sizes.
cv::Mat dynamic_region(const cv::Mat& dynamic_mask, const cv::Mat& depth_m, const DynamicRegionSettings& settings);

}  // namespace mapping
}  // namespace cge
