#pragma once
// What an ORB-SLAM2 RGB-D settings file (cge/dataset/orbslam2_settings.hpp) sets in the pipeline's
// settings: the camera (intrinsics and lens distortion), the depth scale, the close/far depth
// threshold, the ORB extractor and the baseline keyframe policy's frame gap.
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
  // ORB-SLAM2's mMaxFrames is the frame rate.
  settings.orbslam2_keyframes.max_frame_gap = std::max(1, static_cast<int>(std::lround(file.fps_hz)));
}

}  // namespace slam
}  // namespace cge
