#pragma once
// From a run's options (cge/run/slam_run_options.hpp) to the pipeline's settings: the System's
// and the LoopCloser's settings, the segmentation source's temporal filter, the ORB-SLAM2 settings
// file, and the checks of the images against them. Bad options throw std::invalid_argument naming
// the option (or the settings file and key).
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/dataset/segmentation_source.hpp"
#include "cge/run/slam_run_options.hpp"

namespace cge {
namespace run {

/// A number as "%g" prints it (messages and help texts).
std::string short_number(double value);

/// The dynamic mode of `--mode` ("--mode: ..." when unknown).
slam::DynamicMode parse_mode_option(const std::string& text);

/// all, mean or min as a TieMode ("<option>: 'x' is not all, mean or min" otherwise).
TieMode parse_tie_mode(const std::string& option, const std::string& text);

/// The temporal filter ("N/M" or "off") and its overlap ("box" or "mask") into `seg`.
void apply_temporal_filter(const std::string& text, const std::string& overlap,
                           dataset::SegmentationSourceSettings& seg);

/// The System's settings the options decide (mode, seed, MAD depth estimate, keyframes, local
/// mapping and map maintenance, loop correction); the camera comes from the frame source or file.
slam::SystemSettings system_settings_from(const SlamRunOptions& options);

/// Checks the options that choose the frames and the segmentation (frames, preset, segmentation
/// source and what it needs, out) and fills the default segmentation of `mode`. `warn` receives
/// the options that are given but not used.
void check_run_options(SlamRunOptions& options, slam::DynamicMode mode,
                       const std::function<void(const std::string&)>& warn);

/// The LoopCloser's settings the options decide (scoring and its gate, CGE scaling and ties,
/// geometric verification), validated.
slam::LoopCloserSettings loop_closer_settings_from(const SlamRunOptions& options);

/// Camera, distortion, depth scale, depth weight, ORB extractor and keyframe gap from an ORB-SLAM2
/// settings file (cge/slam/settings_from_orbslam2.hpp).
void apply_settings_file(const std::filesystem::path& file, PinholeIntrinsics<double>& intrinsics,
                         slam::SystemSettings& settings);

/// Compares the first image with the settings file (Camera.width x Camera.height, when it gives
/// them) and with the ORB pyramid, whose coarsest level must keep a pixel.
void check_first_image(const cv::Size& image, const std::optional<std::filesystem::path>& settings_file,
                       const slam::OrbSettings& orb);

}  // namespace run
}  // namespace cge
