#pragma once
// ORB-SLAM2 settings files for RGB-D (the `%YAML:1.0` TUM1.yaml / TUM2.yaml / TUM3.yaml kind, and
// the camera.yaml of the synthetic sequences), read with cv::FileStorage so that existing
// configurations work unchanged.
//
// Keys (docs/DATASETS.md has the table):
//   required  Camera.fx Camera.fy Camera.cx Camera.cy (pixels), Camera.k1 Camera.k2 Camera.p1
//             Camera.p2 (OpenCV's radial-tangential model), DepthMapFactor (depth units per metre)
//   optional  Camera.k3 (0), Camera.width Camera.height (unknown), Camera.fps (30), Camera.bf (40),
//             Camera.RGB (unknown), ThDepth (40), ORBextractor.nFeatures (1000) .scaleFactor (1.2)
//             .nLevels (8) .iniThFAST (20) .minThFAST (7)   -- ORB-SLAM2's TUM values
// Other keys (Viewer.*) are ignored. A number may be written as an integer or a real; an integer
// key accepts a real only when it is integral.
//
// Distortion: fr3 images (and the synthetic ones) are undistorted, fr1 and fr2 are not. Like
// ORB-SLAM2, we do not undistort images; non-zero coefficients are accepted, reported in `notes`,
// and undistort_points / undistort_keypoints move keypoints to the ideal pinhole camera.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/core/lens_distortion.hpp"
#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/opencv/undistort.hpp"

namespace cge {
namespace dataset {

/// OpenCV's radial-tangential distortion (k1, k2, p1, p2, k3), unitless (cge/core/lens_distortion.hpp).
using LensDistortion = cge::LensDistortion;

/// ORB extractor settings (ORBextractor.*).
struct OrbExtractorSettings {
  int features = 1000;              ///< nFeatures: features per image
  double scale_factor = 1.2;        ///< scaleFactor: scale between pyramid levels, > 1
  int levels = 8;                   ///< nLevels: pyramid levels
  int initial_fast_threshold = 20;  ///< iniThFAST: FAST threshold, intensity levels
  int min_fast_threshold = 7;       ///< minThFAST: fallback FAST threshold where few corners, intensity levels
};

struct OrbSlam2Settings {
  PinholeIntrinsics<double> camera;  ///< Camera.fx fy cx cy, pixels
  LensDistortion distortion;         ///< Camera.k1 k2 p1 p2 k3
  int width_px = 0;                  ///< Camera.width, pixels; 0 = not in the file
  int height_px = 0;                 ///< Camera.height, pixels; 0 = not in the file
  double fps_hz = 30;                ///< Camera.fps, frames per second
  double bf_px_m = 40;               ///< Camera.bf: (virtual) stereo baseline times fx, pixels x metres
  std::optional<bool> rgb_order;     ///< Camera.RGB: true = images are RGB, false = BGR; unset if absent
  double th_depth_baselines = 40;    ///< ThDepth: close/far depth threshold, in baselines
  double depth_map_factor = 5000;    ///< DepthMapFactor: depth image units per metre
  /// cge.DepthSigmaPerMetre (our key; ORB-SLAM2 ignores it): depth standard deviation sigma_z =
  /// value * z^2, 1/m, > 0; unset if absent (see depth_sigma_per_m()).
  std::optional<double> depth_sigma_per_m_key;
  OrbExtractorSettings orb;          ///< ORBextractor.*

  std::string source;                       ///< the file read
  std::vector<std::string> defaulted_keys;  ///< optional keys absent from the file (defaults used)
  std::vector<std::string> notes;           ///< facts worth telling the user (e.g. non-zero distortion)

  /// The stereo baseline, metres (bf / fx).
  double baseline_m() const { return bf_px_m / camera.fx_px; }
  /// ORB-SLAM2's close/far depth threshold, metres (ThDepth * bf / fx).
  double close_depth_threshold_m() const { return th_depth_baselines * baseline_m(); }
  /// The depth weight for tracking and bundle adjustment, sigma_z = value * z^2, 1/m: the file's
  /// cge.DepthSigmaPerMetre, else ORB-SLAM2's own: it weighs depth as a virtual stereo coordinate
  /// u_R = u - bf / z with the pixel's sigma, so sigma_z = sigma_px z^2 / bf (1 / bf at sigma_px 1).
  double depth_sigma_per_m() const { return depth_sigma_per_m_key.value_or(1.0 / bf_px_m); }
  /// The 3 x 3 CV_64F camera matrix.
  cv::Mat camera_matrix() const;
};

/// Largest accepted ORBextractor.nLevels and .nFeatures: every level is an image and the extractor
/// reserves per feature, so a stray huge value exhausts memory; ORB-SLAM2's files use 8 levels and
/// 1000 .. 2000 features.
constexpr int kMaxOrbLevels = 64;
constexpr int kMaxOrbFeatures = 100000;

/// Whether every level of the ORB pyramid of a width x height image keeps at least one pixel,
/// min(width, height) / scaleFactor^(nLevels - 1) >= 1 (OpenCV's ORB stops with an assertion on
/// a level it rounds to 0 x 0).
bool coarsest_level_fits(const OrbExtractorSettings& orb, int width_px, int height_px);

/// Reads an ORB-SLAM2 settings file. Throws std::invalid_argument naming the file (and the key,
/// with its line when it can be found) when the file is missing or not readable by cv::FileStorage,
/// a required key is missing, a value is not a number (or not an integer for an integer key), or a
/// value is out of range (fx, fy, fps, bf, ThDepth, DepthMapFactor > 0; width and height > 0 and
/// given together; nFeatures in 1 .. kMaxOrbFeatures, nLevels in 1 .. kMaxOrbLevels; scaleFactor
/// > 1; FAST thresholds in 1 .. 255; with Camera.width and .height, coarsest_level_fits).
OrbSlam2Settings read_orbslam2_settings(const std::filesystem::path& file);

/// How keypoints are undistorted (cv::undistortPoints' iteration).
using UndistortSettings = cge::opencv::UndistortSettings;

/// The pixels of an ideal pinhole camera (same intrinsics, no distortion) that the given distorted
/// pixels correspond to. Returns the input unchanged when the distortion is zero.
std::vector<cv::Point2f> undistort_points(const std::vector<cv::Point2f>& points_px, const OrbSlam2Settings& settings,
                                          const UndistortSettings& undistort = {});

/// The same on keypoints: returns copies with undistorted `pt` (size, angle, octave, response kept).
std::vector<cv::KeyPoint> undistort_keypoints(const std::vector<cv::KeyPoint>& keypoints,
                                              const OrbSlam2Settings& settings,
                                              const UndistortSettings& undistort = {});

}  // namespace dataset
}  // namespace cge
