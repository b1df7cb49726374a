#pragma once
// What an ORB-SLAM2 RGB-D settings file (cge/dataset/orbslam2_settings.hpp) sets in the pipeline's
// settings: the camera (intrinsics and lens distortion), the depth scale, the close/far depth
// threshold, the ORB extractor, the depth weight of tracking and bundle adjustment, and the baseline
// keyframe policy's frame gap.
#include <algorithm>
#include <cmath>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/dataset/orbslam2_settings.hpp"
#include "cge/slam/settings.hpp"

namespace cge {
namespace slam {

/// Overwrites `intrinsics` and the fields of `settings` the file decides; leaves the rest.
inline void apply_orbslam2_settings(const dataset::OrbSlam2Settings& file, PinholeIntrinsics<double>& intrinsics,
                                    SystemSettings& settings) {
  intrinsics = file.camera;
  FrameSettings& frame = settings.frame;
  frame.distortion = file.distortion;
  frame.depth_units_per_metre = file.depth_map_factor;
  frame.close_depth_m = file.close_depth_threshold_m();  // ThDepth * bf / fx
  frame.orb.features = file.orb.features;
  frame.orb.scale_factor = file.orb.scale_factor;
  frame.orb.levels = file.orb.levels;
  frame.orb.initial_fast_threshold = file.orb.initial_fast_threshold;
  frame.orb.min_fast_threshold = file.orb.min_fast_threshold;
  // Real Kinect frames carry depth errors beyond the sensor's noise (registration to the colour
  // image, timing during fast motion): on the real fr1/rpy slice the tight rendered weight (0.003)
  // flagged a quarter of the local BA's observations as outliers (docs/REAL_DATA.md).
  const double depth_sigma_per_m = file.depth_sigma_per_m();
  settings.tracker.refinement_depth_sigma_per_m = depth_sigma_per_m;
  settings.local_mapping.depth_sigma_per_m = depth_sigma_per_m;
  settings.loop_correction.depth_sigma_per_m = depth_sigma_per_m;
  // ORB-SLAM2's mMaxFrames is the frame rate.
  settings.orbslam2_keyframes.max_frame_gap = std::max(1, static_cast<int>(std::lround(file.fps_hz)));
}

}  // namespace slam
}  // namespace cge
