#include "cge/dataset/tum_sequence.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "cge/dataset/tum_layout.hpp"
#include "cge/dataset/tum_list.hpp"
#include "cge/io/stderr_capture.hpp"
#include "cge/metrics/tum_trajectory_io.hpp"
#include "text_fields.hpp"

namespace cge {
namespace dataset {
namespace fs = std::filesystem;
namespace {

using namespace tum_layout;

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

fs::path resolve(const fs::path& folder, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() ? p : folder / p;
}

std::optional<fs::path> existing_folder(const fs::path& p) {
  std::error_code ec;
  if (fs::is_directory(p, ec)) return p;
  return std::nullopt;
}

std::optional<fs::path> existing_file(const fs::path& p) {
  std::error_code ec;
  if (fs::is_regular_file(p, ec)) return p;
  return std::nullopt;
}

/// The frames of associations.txt: `t_rgb rgb_path t_depth depth_path` per line.
std::vector<TumFrameFiles> read_associations(const fs::path& folder, const fs::path& file) {
  constexpr std::size_t kFields = 4;
  std::ifstream in = detail::open_text_file(file);
  std::vector<TumFrameFiles> frames;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    const std::vector<std::string_view> fields = detail::split_fields(text);
    if (fields.empty() || fields[0][0] == '#') continue;
    const std::string where = file.string() + ":" + std::to_string(line);
    if (fields.size() != kFields) {
      throw std::invalid_argument(where + ": expected `rgb_timestamp rgb_path depth_timestamp depth_path`, got " +
                                  std::to_string(fields.size()) + " fields");
    }
    TumFrameFiles f;
    f.rgb_timestamp_s = detail::parse_real(fields[0], where, "RGB timestamp");
    f.depth_timestamp_s = detail::parse_real(fields[2], where, "depth timestamp");
    f.rgb_path = resolve(folder, std::string(fields[1]));
    f.depth_path = resolve(folder, std::string(fields[3]));
    f.rgb_source = f.depth_source = where;
    if (!frames.empty() && !(f.rgb_timestamp_s > frames.back().rgb_timestamp_s)) {
      throw std::invalid_argument(where + ": RGB timestamp " + std::string(fields[0]) +
                                  " does not come after the previous line's; timestamps must increase");
    }
    frames.push_back(std::move(f));
  }
  if (in.bad()) throw std::invalid_argument(file.string() + ": read error");
  if (frames.empty()) throw std::invalid_argument(file.string() + ": no frames (the sequence is empty)");
  return frames;
}

std::vector<double> timestamps(const std::vector<TumListEntry>& entries) {
  std::vector<double> t;
  t.reserve(entries.size());
  for (const TumListEntry& e : entries) t.push_back(e.timestamp_s);
  return t;
}

cv::Mat read_image(const fs::path& path, int flags, const std::string& source, const char* what) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw std::invalid_argument(source + ": the " + what + " image " + quoted(path) + " does not exist");
  }
  cv::Mat image;
  // The decoders' own complaints (libpng's "Read Error") join this message instead of preceding it.
  io::StderrCapture decoder_messages;
  try {
    image = cv::imread(path.string(), flags);
  } catch (const cv::Exception& e) {
    decoder_messages.finish();
    throw std::invalid_argument(source + ": cannot read the " + what + " image " + quoted(path) + ": " + e.what());
  }
  const std::string said = decoder_messages.finish();
  if (image.empty()) {
    throw std::invalid_argument(source + ": cannot read the " + what + " image " + quoted(path) +
                                " (not an image OpenCV can decode" + (said.empty() ? "" : ": " + said) + ")");
  }
  return image;
}

}  // namespace

void check_settings(const TumSequenceSettings& s) {
  if (!(std::isfinite(s.max_time_difference_s) && s.max_time_difference_s > 0)) {
    throw std::invalid_argument("TumSequenceSettings::max_time_difference_s must be finite and positive");
  }
  if (!std::isfinite(s.depth_time_offset_s)) {
    throw std::invalid_argument("TumSequenceSettings::depth_time_offset_s must be finite");
  }
  if (!(std::isfinite(s.depth_units_per_metre) && s.depth_units_per_metre > 0)) {
    throw std::invalid_argument("TumSequenceSettings::depth_units_per_metre must be finite and positive");
  }
  if (!(s.quaternion_norm_tolerance >= 0 && s.quaternion_norm_tolerance < 1)) {
    throw std::invalid_argument("TumSequenceSettings::quaternion_norm_tolerance must be in [0, 1)");
  }
}

cv::Mat TumFrame::depth_metres() const {
  cv::Mat m;
  depth.convertTo(m, CV_32F, 1.0 / depth_units_per_metre);
  return m;
}

TumSequence::TumSequence(fs::path folder, TumSequenceSettings settings)
    : folder_(std::move(folder)), settings_(settings) {
  check_settings(settings_);
  std::error_code ec;
  if (!fs::is_directory(folder_, ec)) {
    throw std::invalid_argument("the sequence folder " + quoted(folder_) + " does not exist or is not a folder");
  }
  const std::optional<fs::path> associations = existing_file(folder_ / kAssociationsFile);
  if (settings_.use_associations_file && associations) {
    files_ = read_associations(folder_, *associations);
  } else {
    const fs::path rgb_file = folder_ / kRgbList;
    const fs::path depth_file = folder_ / kDepthList;
    const std::vector<TumListEntry> rgb = read_tum_list(rgb_file);
    const std::vector<TumListEntry> depth = read_tum_list(depth_file);
    if (rgb.empty()) throw std::invalid_argument(rgb_file.string() + ": no frames (the sequence is empty)");
    if (depth.empty()) throw std::invalid_argument(depth_file.string() + ": no frames (the sequence is empty)");
    const std::vector<TimestampMatch> matches = associate_timestamps(
        timestamps(rgb), timestamps(depth), settings_.max_time_difference_s, settings_.depth_time_offset_s);
    if (matches.empty()) {
      throw std::invalid_argument("no timestamp of " + rgb_file.string() + " (" + rgb.front().token + " .. " +
                                  rgb.back().token + ") associates with one of " + depth_file.string() + " (" +
                                  depth.front().token + " .. " + depth.back().token + ") within " +
                                  std::to_string(settings_.max_time_difference_s) + " s");
    }
    for (const TimestampMatch& m : matches) {
      const TumListEntry& r = rgb[m.first];
      const TumListEntry& d = depth[m.second];
      TumFrameFiles f;
      f.rgb_timestamp_s = r.timestamp_s;
      f.depth_timestamp_s = d.timestamp_s;
      f.rgb_path = resolve(folder_, r.path);
      f.depth_path = resolve(folder_, d.path);
      f.rgb_source = rgb_file.string() + ":" + std::to_string(r.line);
      f.depth_source = depth_file.string() + ":" + std::to_string(d.line);
      files_.push_back(std::move(f));
    }
    unassociated_rgb_ = static_cast<int>(rgb.size() - matches.size());
  }
  if (const auto gt = existing_file(folder_ / kGroundTruthFile)) {
    // The core reader, keeping repeated stamps in file order: TUM's own fr2_desk ground truth
    // repeats one, and a dataset reader should hand over the file as it is.
    metrics::TumReadSettings read;
    read.max_quaternion_norm_error = settings_.quaternion_norm_tolerance;
    read.duplicate_timestamps = metrics::DuplicateTimestamps::keep_all;
    for (const metrics::StampedPose& pose : metrics::read_tum_trajectory_file(gt->string(), read)) {
      ground_truth_.push_back(GroundTruthPose{pose.timestamp_s, pose.T_world_camera});
    }
  }
  masks_folder_ = existing_folder(folder_ / kMasksDir);
  segmentation_folder_ = existing_folder(folder_ / kSegmentationDir);
  camera_settings_file_ = existing_file(folder_ / kCameraFile);
}

const TumFrameFiles& TumSequence::files(int index) const {
  if (index < 0 || index >= frame_count()) {
    throw std::out_of_range("TumSequence: frame " + std::to_string(index) + " is not in 0 .. " +
                            std::to_string(frame_count() - 1));
  }
  return files_[static_cast<std::size_t>(index)];
}

TumFrame TumSequence::load(int index) const {
  const TumFrameFiles& f = files(index);
  TumFrame frame;
  frame.index = index;
  frame.rgb_timestamp_s = f.rgb_timestamp_s;
  frame.depth_timestamp_s = f.depth_timestamp_s;
  frame.rgb_stem = frame_stem(f.rgb_path.string());
  frame.depth_stem = frame_stem(f.depth_path.string());
  frame.depth_units_per_metre = settings_.depth_units_per_metre;
  frame.bgr = read_image(f.rgb_path, cv::IMREAD_COLOR, f.rgb_source, "RGB");
  frame.depth = read_image(f.depth_path, cv::IMREAD_UNCHANGED, f.depth_source, "depth");
  if (frame.depth.type() != CV_16UC1) {
    throw std::invalid_argument(f.depth_source + ": the depth image " + quoted(f.depth_path) + " is " +
                                cv::typeToString(frame.depth.type()) + ", expected single-channel 16-bit (CV_16UC1)");
  }
  if (frame.bgr.size() != frame.depth.size()) {
    throw std::invalid_argument(f.rgb_source + ", " + f.depth_source + ": the RGB image " + quoted(f.rgb_path) +
                                " is " + std::to_string(frame.bgr.cols) + " x " + std::to_string(frame.bgr.rows) +
                                " pixels but the depth image " + quoted(f.depth_path) + " is " +
                                std::to_string(frame.depth.cols) + " x " + std::to_string(frame.depth.rows));
  }
  return frame;
}

}  // namespace dataset
}  // namespace cge
