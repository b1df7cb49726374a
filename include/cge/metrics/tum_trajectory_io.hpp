#pragma once
// TUM RGB-D trajectory text: one pose per line, "timestamp tx ty tz qx qy qz qw" (seconds, metres,
// unit quaternion with the scalar last), the pose being T_world_camera.
//
// Reading (docs/EVALUATION.md):
//   - fields are separated by any run of blanks, tabs or commas (as the TUM tools accept);
//   - blank lines and lines whose first non-blank character is '#' are skipped;
//   - every other line has exactly 8 numbers, all finite; the quaternion's norm must lie within
//     TumReadSettings::max_quaternion_norm_error of 1 and is then normalised (TUM ground truth
//     has 4 decimals, so its quaternions are off by about 1e-4);
//   - timestamps strictly increase. A repeated timestamp is refused by default; with
//     DuplicateTimestamps::keep_last the later line replaces the earlier one, which is what the
//     TUM tools do (they key poses by timestamp in a dict); keep_all keeps both (TumSequence). The official fr2_desk
//     ground truth has one such repeat (line 10863). A decreasing timestamp is always refused;
//   - any violation throws ParseError (a std::invalid_argument), "<source>:<line>: <reason>".
//   An input without poses gives an empty trajectory; whether that is acceptable is the caller's call.
// Writing: an optional '#' header line, then the timestamp with 6 decimals and the other values
// with 9 significant digits, the quaternion signed so that qw >= 0 (one spelling per rotation).

#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <Eigen/Geometry>

#include "cge/metrics/text_input.hpp"
#include "cge/metrics/trajectory.hpp"

namespace cge {
namespace metrics {

/// What the reader does with a line whose timestamp equals the previous line's.
enum class DuplicateTimestamps {
  refuse,     ///< throw ParseError (the default: a repeated stamp usually means a broken writer)
  keep_last,  ///< the later line replaces the earlier pose (the TUM tools' behaviour)
  keep_all,   ///< both lines kept, in file order (for readers that must not drop a line; the
              ///< trajectory then has equal timestamps, which association does not accept)
};

/// Optional report of a read: lines whose pose was replaced by a later line with the same stamp.
struct TumReadReport {
  std::vector<std::size_t> replaced_lines;
};

struct TumReadSettings {
  /// Largest accepted | |q| - 1 | before normalising, dimensionless; beyond it a line is refused
  /// as a corrupt quaternion rather than silently rescaled.
  double max_quaternion_norm_error = 1e-2;
  DuplicateTimestamps duplicate_timestamps = DuplicateTimestamps::refuse;  ///< see above
  /// Largest accepted |tx|, |ty|, |tz|, metres (> 0; infinity accepts every finite value). No RGB-D
  /// trajectory spans 1000 km, and one far position wrecks the ATE alignment silently: a pose
  /// 2e9 m away made a trajectory's ATE against itself 0.54 m instead of 0 (found by fuzzing),
  /// because the other positions' spread fell below double precision beside it.
  double max_abs_translation_m = 1e6;
};

namespace detail {
/// `value` by std::to_chars (locale-independent), with one spelling of zero; used by the writer
/// and for settings in the reader's messages.
inline std::string format_number(double value, std::chars_format format, int precision) {
  char buf[64];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, value, format, precision);
  if (r.ec != std::errc()) throw std::invalid_argument("cannot format number");
  std::string s(buf, r.ptr);
  // No "-0" or "-0.000000": one spelling of zero.
  if (!s.empty() && s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}
}  // namespace detail

/// Reads a TUM trajectory from a stream; `source` names it in error messages.
inline Trajectory read_tum_trajectory(std::istream& in, const std::string& source, const TumReadSettings& settings = {},
                                      TumReadReport* report = nullptr) {
  if (!(settings.max_quaternion_norm_error >= 0 && std::isfinite(settings.max_quaternion_norm_error))) {
    throw std::invalid_argument("TumReadSettings::max_quaternion_norm_error must be finite and >= 0");
  }
  if (!(settings.max_abs_translation_m > 0)) {
    throw std::invalid_argument("TumReadSettings::max_abs_translation_m must be > 0");
  }
  constexpr std::size_t kFields = 8;
  constexpr std::array<const char*, kFields> kNames = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  Trajectory trajectory;
  detail::LineReader reader(in, source);
  std::string line;
  std::size_t previous_line = 0;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const std::vector<std::string_view> fields = detail::split_blank_or_comma(line);
    if (fields.size() != kFields) {
      reader.fail("expected 8 fields (timestamp tx ty tz qx qy qz qw), found " + std::to_string(fields.size()));
    }
    std::array<double, kFields> v{};
    for (std::size_t i = 0; i < kFields; ++i) {
      if (!detail::parse_double(fields[i], v[i])) {
        reader.fail(std::string(kNames[i]) + " " + detail::quoted(fields[i]) + " is not a number");
      }
      if (!std::isfinite(v[i]))
        reader.fail(std::string(kNames[i]) + " " + detail::quoted(fields[i]) + " is not finite");
    }
    for (std::size_t i = 1; i <= 3; ++i) {
      if (!(std::abs(v[i]) <= settings.max_abs_translation_m)) {
        reader.fail(std::string(kNames[i]) + " " + detail::quoted(fields[i]) + " lies beyond " +
                    detail::format_number(settings.max_abs_translation_m, std::chars_format::general, 6) +
                    " m (not metres? see max_abs_translation_m)");
      }
    }
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // w, x, y, z
    const double norm = q.norm();
    if (!(std::abs(norm - 1.0) <= settings.max_quaternion_norm_error)) {
      reader.fail("quaternion norm " + std::to_string(norm) + " is not close to 1 (tolerance " +
                  std::to_string(settings.max_quaternion_norm_error) + ")");
    }
    q.coeffs() /= norm;
    StampedPose pose;
    pose.timestamp_s = v[0];
    pose.T_world_camera.linear() = q.toRotationMatrix();
    pose.T_world_camera.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    if (!trajectory.empty() && v[0] == trajectory.back().timestamp_s &&
        settings.duplicate_timestamps == DuplicateTimestamps::keep_last) {
      if (report != nullptr) report->replaced_lines.push_back(previous_line);
      trajectory.back() = pose;
      previous_line = reader.line_number();
      continue;
    }
    if (!trajectory.empty() && v[0] == trajectory.back().timestamp_s &&
        settings.duplicate_timestamps == DuplicateTimestamps::keep_all) {
      trajectory.push_back(pose);
      previous_line = reader.line_number();
      continue;
    }
    if (!trajectory.empty() && v[0] == trajectory.back().timestamp_s) {
      reader.fail("timestamp " + std::string(fields[0]) + " repeats the one on line " + std::to_string(previous_line) +
                  " (the TUM tools keep the later line; allow that with DuplicateTimestamps::keep_last)");
    }
    if (!trajectory.empty() && !(v[0] > trajectory.back().timestamp_s)) {
      reader.fail("timestamp " + std::string(fields[0]) + " does not come after the one on line " +
                  std::to_string(previous_line) +
                  (settings.duplicate_timestamps == DuplicateTimestamps::keep_all ? " (timestamps must not decrease)"
                                                                                  : " (timestamps must increase)"));
    }
    trajectory.push_back(pose);
    previous_line = reader.line_number();
  }
  return trajectory;
}

/// Reads a TUM trajectory file; errors name the file (and line).
inline Trajectory read_tum_trajectory_file(const std::string& path, const TumReadSettings& settings = {},
                                           TumReadReport* report = nullptr) {
  std::ifstream file = detail::open_input_file(path);
  return read_tum_trajectory(file, path, settings, report);
}


/// The quaternion of a rotation with one spelling: normalised, qw >= 0 and, when qw == 0, the first
/// non-zero of qx, qy, qz positive (q and -q are the same rotation).
inline Eigen::Quaterniond canonical_quaternion(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  const Eigen::Vector4d c = q.coeffs();  // x, y, z, w
  bool flip = c.w() < 0;
  if (c.w() == 0) {
    for (int i = 0; i < 3; ++i) {
      if (c[i] != 0) {
        flip = c[i] < 0;
        break;
      }
    }
  }
  if (flip) q.coeffs() = -q.coeffs();
  return q;
}

/// How a pose line spells its seven numbers.
enum class TumDigits {
  significant_9,  ///< 9 significant digits (printf %.9g): trajectories and keyframes of cge_slam
  decimals_9,     ///< 9 decimals (printf %.9f): cge_sim's ground truth
};

/// A timestamp as TUM writes it: seconds with 6 decimals ("1305031102.175304"), one spelling of
/// zero.
inline std::string format_tum_timestamp(double timestamp_s) {
  return detail::format_number(timestamp_s, std::chars_format::fixed, 6);
}

/// One pose line without the newline, "timestamp tx ty tz qx qy qz qw": the timestamp by
/// format_tum_timestamp, the rest by `digits`, the quaternion by canonical_quaternion, one spelling
/// of zero ("0", never "-0"). The one writer of TUM pose lines in the project.
inline std::string format_tum_pose(double timestamp_s, const Eigen::Isometry3d& T_world_camera,
                                   TumDigits digits = TumDigits::significant_9) {
  const Eigen::Quaterniond q = canonical_quaternion(T_world_camera.linear());
  const Eigen::Vector3d t = T_world_camera.translation();
  std::string line = format_tum_timestamp(timestamp_s);
  for (const double value : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) {
    line += ' ';
    line += digits == TumDigits::significant_9 ? detail::format_number(value, std::chars_format::general, 9)
                                               : detail::format_number(value, std::chars_format::fixed, 9);
  }
  return line;
}

/// One trajectory line without the newline (format_tum_pose with 9 significant digits).
inline std::string format_tum_pose(const StampedPose& pose) {
  return format_tum_pose(pose.timestamp_s, pose.T_world_camera);
}

/// Writes a trajectory, preceded by "# <header>" when the header is not empty. Throws
/// std::invalid_argument for a non-finite pose or timestamps that do not increase in their
/// 6-decimal form (the file would not read back).
inline void write_tum_trajectory(std::ostream& out, const Trajectory& trajectory,
                                 const std::string& header = "timestamp tx ty tz qx qy qz qw") {
  require_valid_trajectory(trajectory, "write_tum_trajectory");
  std::string text;
  if (!header.empty()) text += "# " + header + "\n";
  std::string previous_stamp;
  double previous_value = 0.0;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const std::string line = format_tum_pose(trajectory[i]);
    const std::string stamp = line.substr(0, line.find(' '));
    double value = 0.0;
    detail::parse_double(stamp, value);
    if (i > 0 && !(value > previous_value)) {
      throw std::invalid_argument("write_tum_trajectory: timestamps " + previous_stamp + " and " + stamp + " (poses " +
                                  std::to_string(i - 1) + ", " + std::to_string(i) +
                                  ") do not increase with 6 decimals");
    }
    previous_stamp = stamp;
    previous_value = value;
    text += line;
    text += '\n';
  }
  out << text;
  if (!out) throw std::runtime_error("write_tum_trajectory: the stream refused the text");
}

}  // namespace metrics
}  // namespace cge
