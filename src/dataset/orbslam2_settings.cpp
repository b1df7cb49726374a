#include "cge/dataset/orbslam2_settings.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <opencv2/calib3d.hpp>

namespace cge {
namespace dataset {
namespace fs = std::filesystem;
namespace {

constexpr int kMaxFastThreshold = 255;  // FAST thresholds are 8-bit intensity differences

/// Reads typed values from the file and names the file, key and line in every message.
class KeyReader {
 public:
  KeyReader(const fs::path& file, OrbSlam2Settings& out) : file_(file.string()), out_(out) {
    std::error_code ec;
    if (fs::is_directory(file, ec)) throw std::invalid_argument("the settings file '" + file_ + "' is a directory");
    if (!fs::is_regular_file(file, ec)) {
      throw std::invalid_argument("the settings file '" + file_ + "' does not exist or is not a regular file");
    }
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::invalid_argument("cannot open the settings file '" + file_ + "'");
    for (std::string line; std::getline(in, line);) lines_.push_back(line);
    check_single_document();
    try {
      storage_.open(file_, cv::FileStorage::READ);
    } catch (const cv::Exception& e) {
      throw std::invalid_argument("the settings file '" + file_ +
                                  "' is not a YAML file cv::FileStorage can read: " + e.what());
    }
    if (!storage_.isOpened() || !storage_.root().isMap()) {
      throw std::invalid_argument(
          "the settings file '" + file_ +
          "' is not a YAML map cv::FileStorage can read (ORB-SLAM2 files start with %YAML:1.0)");
    }
  }

  /// A settings file is one YAML document: at most one "---" line, before any key, and no other
  /// line starting with "---" or "...". cv::FileStorage's parser can loop for ever on further
  /// document markers (found by fuzzing, OpenCV 4.6), so they are refused here, with their line.
  void check_single_document() const {
    bool marker_seen = false, key_seen = false;
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      std::string l = lines_[i];
      if (!l.empty() && l.back() == '\r') l.pop_back();
      const std::string at = file_ + ":" + std::to_string(i + 1) + ": ";
      if (l.compare(0, 3, "---") == 0 || l.compare(0, 3, "...") == 0) {
        const bool plain = l.find_first_not_of(" \t", 3) == std::string::npos && l[0] == '-';
        if (!plain || marker_seen || key_seen) {
          throw std::invalid_argument(at + "'" + l + "': a settings file holds one YAML document (one '---' line, "
                                      "after %YAML:1.0 and before the keys)");
        }
        marker_seen = true;
        continue;
      }
      const std::size_t first = l.find_first_not_of(" \t");
      if (first != std::string::npos && l[first] != '#' && l[first] != '%') key_seen = true;
    }
  }

  /// "<file>:<line>: key <key>" (the line of the first `key:` in the text, when there is one).
  std::string where(const std::string& key) const {
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      const std::string& l = lines_[i];
      const std::size_t begin = l.find_first_not_of(" \t");
      if (begin == std::string::npos || l.compare(begin, key.size(), key) != 0) continue;
      const std::size_t colon = l.find_first_not_of(" \t", begin + key.size());
      if (colon != std::string::npos && l[colon] == ':') return file_ + ":" + std::to_string(i + 1) + ": key " + key;
    }
    return file_ + ": key " + key;
  }

  /// The number at `key`; nullopt (recorded in defaulted_keys) when absent and not required.
  std::optional<double> real(const std::string& key, bool required) {
    const cv::FileNode node = storage_[key];
    if (node.empty() || node.isNone()) {
      if (required) throw std::invalid_argument(file_ + ": the required key " + key + " is missing");
      out_.defaulted_keys.push_back(key);
      return std::nullopt;
    }
    double value = 0;
    if (node.isInt()) {
      value = static_cast<int>(node);
    } else if (node.isReal()) {
      value = static_cast<double>(node);
    } else {
      throw std::invalid_argument(where(key) + ": expected a number, got " + describe(node));
    }
    if (!std::isfinite(value)) throw std::invalid_argument(where(key) + ": the value is not finite");
    return value;
  }

  std::optional<int> integer(const std::string& key, bool required) {
    const std::optional<double> v = real(key, required);
    if (!v) return std::nullopt;
    if (*v != std::round(*v) || std::abs(*v) > std::numeric_limits<int>::max()) {
      throw std::invalid_argument(where(key) + ": expected an integer, got " + number(*v));
    }
    return static_cast<int>(*v);
  }

  void require(bool ok, const std::string& key, double value, const char* rule) const {
    if (!ok) throw std::invalid_argument(where(key) + ": " + number(value) + " is out of range (" + rule + ")");
  }

 private:
  static std::string number(double v) {
    std::ostringstream s;
    s.precision(std::numeric_limits<double>::max_digits10);
    s << v;
    return s.str();
  }
  static std::string describe(const cv::FileNode& node) {
    if (node.isString()) return "the string '" + static_cast<std::string>(node) + "'";
    if (node.isSeq()) return "a sequence";
    if (node.isMap()) return "a map";
    return "a value of another type";
  }

  std::string file_;
  OrbSlam2Settings& out_;
  std::vector<std::string> lines_;
  cv::FileStorage storage_;
};

}  // namespace

bool coarsest_level_fits(const OrbExtractorSettings& orb, int width_px, int height_px) {
  const double smaller_side = std::min(width_px, height_px);
  return orb.levels >= 1 && smaller_side / std::pow(orb.scale_factor, orb.levels - 1) >= 1.0;
}

cv::Mat OrbSlam2Settings::camera_matrix() const {
  return (cv::Mat_<double>(3, 3) << camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
}

OrbSlam2Settings read_orbslam2_settings(const fs::path& file) {
  OrbSlam2Settings s;
  s.source = file.string();
  KeyReader r(file, s);
  constexpr bool kRequired = true;
  constexpr bool kOptional = false;

  s.camera.fx_px = *r.real("Camera.fx", kRequired);
  s.camera.fy_px = *r.real("Camera.fy", kRequired);
  s.camera.cx_px = *r.real("Camera.cx", kRequired);
  s.camera.cy_px = *r.real("Camera.cy", kRequired);
  r.require(s.camera.fx_px > 0, "Camera.fx", s.camera.fx_px, "> 0");
  r.require(s.camera.fy_px > 0, "Camera.fy", s.camera.fy_px, "> 0");
  s.distortion.k1 = *r.real("Camera.k1", kRequired);
  s.distortion.k2 = *r.real("Camera.k2", kRequired);
  s.distortion.p1 = *r.real("Camera.p1", kRequired);
  s.distortion.p2 = *r.real("Camera.p2", kRequired);
  s.distortion.k3 = r.real("Camera.k3", kOptional).value_or(s.distortion.k3);

  const std::optional<int> width = r.integer("Camera.width", kOptional);
  const std::optional<int> height = r.integer("Camera.height", kOptional);
  if (width.has_value() != height.has_value()) {
    throw std::invalid_argument(r.where(width ? "Camera.width" : "Camera.height") +
                                ": Camera.width and Camera.height must be given together");
  }
  if (width) {
    r.require(*width > 0, "Camera.width", *width, "> 0");
    r.require(*height > 0, "Camera.height", *height, "> 0");
    s.width_px = *width;
    s.height_px = *height;
  }
  s.fps_hz = r.real("Camera.fps", kOptional).value_or(s.fps_hz);
  r.require(s.fps_hz > 0, "Camera.fps", s.fps_hz, "> 0");
  s.bf_px_m = r.real("Camera.bf", kOptional).value_or(s.bf_px_m);
  r.require(s.bf_px_m > 0, "Camera.bf", s.bf_px_m, "> 0");
  if (const std::optional<int> rgb = r.integer("Camera.RGB", kOptional)) {
    r.require(*rgb == 0 || *rgb == 1, "Camera.RGB", *rgb, "0 or 1");
    s.rgb_order = *rgb == 1;
  }
  s.th_depth_baselines = r.real("ThDepth", kOptional).value_or(s.th_depth_baselines);
  r.require(s.th_depth_baselines > 0, "ThDepth", s.th_depth_baselines, "> 0");
  s.depth_map_factor = *r.real("DepthMapFactor", kRequired);
  r.require(s.depth_map_factor > 0, "DepthMapFactor", s.depth_map_factor, "> 0");
  s.depth_sigma_per_m_key = r.real("cge.DepthSigmaPerMetre", kOptional);
  if (s.depth_sigma_per_m_key) {
    r.require(*s.depth_sigma_per_m_key > 0, "cge.DepthSigmaPerMetre", *s.depth_sigma_per_m_key, "> 0");
  }

  OrbExtractorSettings& o = s.orb;
  o.features = r.integer("ORBextractor.nFeatures", kOptional).value_or(o.features);
  r.require(o.features >= 1 && o.features <= kMaxOrbFeatures, "ORBextractor.nFeatures", o.features,
            ("1 .. " + std::to_string(kMaxOrbFeatures)).c_str());
  o.scale_factor = r.real("ORBextractor.scaleFactor", kOptional).value_or(o.scale_factor);
  r.require(o.scale_factor > 1, "ORBextractor.scaleFactor", o.scale_factor, "> 1");
  o.levels = r.integer("ORBextractor.nLevels", kOptional).value_or(o.levels);
  r.require(o.levels >= 1 && o.levels <= kMaxOrbLevels, "ORBextractor.nLevels", o.levels,
            ("1 .. " + std::to_string(kMaxOrbLevels)).c_str());
  if (s.width_px > 0) {
    r.require(coarsest_level_fits(o, s.width_px, s.height_px), "ORBextractor.nLevels", o.levels,
              "the coarsest level of a Camera.width x Camera.height image keeps no pixel: scaleFactor^(nLevels - 1) "
              "must not exceed the smaller side");
  }
  o.initial_fast_threshold = r.integer("ORBextractor.iniThFAST", kOptional).value_or(o.initial_fast_threshold);
  r.require(o.initial_fast_threshold >= 1 && o.initial_fast_threshold <= kMaxFastThreshold, "ORBextractor.iniThFAST",
            o.initial_fast_threshold, "1 .. 255");
  o.min_fast_threshold = r.integer("ORBextractor.minThFAST", kOptional).value_or(o.min_fast_threshold);
  r.require(o.min_fast_threshold >= 1 && o.min_fast_threshold <= kMaxFastThreshold, "ORBextractor.minThFAST",
            o.min_fast_threshold, "1 .. 255");

  if (!s.distortion.is_zero()) {
    s.notes.push_back(s.source +
                      ": non-zero lens distortion (k1 k2 p1 p2 k3); images are used as they are and keypoints "
                      "are undistorted (undistort_keypoints)");
  }
  return s;
}

std::vector<cv::Point2f> undistort_points(const std::vector<cv::Point2f>& points_px, const OrbSlam2Settings& settings,
                                          const UndistortSettings& undistort) {
  return opencv::undistort_pixels(points_px, settings.camera, settings.distortion, undistort);
}

std::vector<cv::KeyPoint> undistort_keypoints(const std::vector<cv::KeyPoint>& keypoints,
                                              const OrbSlam2Settings& settings, const UndistortSettings& undistort) {
  std::vector<cv::Point2f> points;
  points.reserve(keypoints.size());
  for (const cv::KeyPoint& k : keypoints) points.push_back(k.pt);
  const std::vector<cv::Point2f> moved = undistort_points(points, settings, undistort);
  std::vector<cv::KeyPoint> out = keypoints;
  for (std::size_t i = 0; i < out.size(); ++i) out[i].pt = moved[i];
  return out;
}

}  // namespace dataset
}  // namespace cge
