#include "cge/sim/tum_writer.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <utility>

#include <opencv2/imgcodecs.hpp>

#include "cge/dataset/tum_layout.hpp"
#include "cge/metrics/tum_trajectory_io.hpp"
#include "cge/segmentation/coco_classes.hpp"

namespace cge {
namespace sim {
namespace fs = std::filesystem;
namespace {

constexpr int kMaxPngCompression = 9;
constexpr std::size_t kLabelCount = std::size_t{std::numeric_limits<std::uint16_t>::max()} + 1;

using namespace dataset::tum_layout;

// ORB-SLAM2 reads Viewer.* in its viewer thread; absent keys would read as 0. TUM3.yaml's values.
constexpr std::array<std::pair<const char*, const char*>, 10> kOrbSlamViewerDefaults = {{
    {"Viewer.KeyFrameSize", "0.05"},
    {"Viewer.KeyFrameLineWidth", "1"},
    {"Viewer.GraphLineWidth", "0.9"},
    {"Viewer.PointSize", "2"},
    {"Viewer.CameraSize", "0.08"},
    {"Viewer.CameraLineWidth", "3"},
    {"Viewer.ViewpointX", "0"},
    {"Viewer.ViewpointY", "-0.7"},
    {"Viewer.ViewpointZ", "-1.8"},
    {"Viewer.ViewpointF", "500"},
}};

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

/// Writes bytes to a file, replacing it; throws std::runtime_error naming the path on failure.
void write_file(const fs::path& path, const char* data, std::size_t size) {
  errno = 0;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (out) out.write(data, static_cast<std::streamsize>(size));
  if (out) out.close();
  if (!out) {
    const int err = errno;
    throw std::runtime_error("cannot write " + quoted(path) + (err != 0 ? std::string(": ") + std::strerror(err) : ""));
  }
}

void write_file(const fs::path& path, const std::string& text) { write_file(path, text.data(), text.size()); }

void write_file(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  write_file(path, reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

void make_folder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw std::runtime_error("cannot create the folder " + quoted(dir) + (ec ? ": " + ec.message() : ""));
  }
}

std::vector<std::uint8_t> encode_png(const cv::Mat& image, int compression, const char* what) {
  std::vector<std::uint8_t> bytes;
  bool ok = false;
  try {
    // Without a compression parameter OpenCV takes its speed path (zlib level 1, RLE, SUB filter).
    const std::vector<int> params =
        compression == kPngFast ? std::vector<int>{} : std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, compression};
    ok = cv::imencode(kImageExtension, image, bytes, params);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(std::string("cannot encode the ") + what + " image as PNG: " + e.what());
  }
  if (!ok) throw std::runtime_error(std::string("cannot encode the ") + what + " image as PNG");
  return bytes;
}

/// "x" with the fewest digits that read back as x; ".0" appended to integral values, so that a
/// YAML reader sees a real number.
std::string yaml_real(double x) {
  std::array<char, 64> buf{};
  const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  std::string s(buf.data(), r.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // 'n': inf and nan stay as they are
  return s;
}

/// printf-style "%.<decimals>f" without a minus sign on a value that prints as zero.
void require_image(const cv::Mat& image, int type, const PinholeCamera& camera, const std::string& what, int frame) {
  if (image.type() != type || image.cols != camera.width_px || image.rows != camera.height_px) {
    throw std::invalid_argument("frame " + std::to_string(frame) + ": the " + what + " image must be " +
                                cv::typeToString(type) + " of " + std::to_string(camera.width_px) + " x " +
                                std::to_string(camera.height_px) + " pixels, got " + cv::typeToString(image.type()) +
                                " of " + std::to_string(image.cols) + " x " + std::to_string(image.rows));
  }
}

/// Throws when a pixel of labels (CV_16UC1) is not marked in `known`.
void require_known_labels(const cv::Mat& labels, const std::vector<std::uint8_t>& known, const std::string& what,
                          int frame) {
  for (int y = 0; y < labels.rows; ++y) {
    const std::uint16_t* row = labels.ptr<std::uint16_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (!known[row[x]]) {
        throw std::invalid_argument("frame " + std::to_string(frame) + ": " + what + " label " +
                                    std::to_string(row[x]) + " at pixel (" + std::to_string(x) + ", " +
                                    std::to_string(y) + ") is not in the instance table");
      }
    }
  }
}

void check_instance_table(const std::vector<InstanceInfo>& instances, const std::string& where) {
  std::vector<std::uint8_t> seen(kLabelCount, 0);
  for (const InstanceInfo& inst : instances) {
    if (inst.id == 0) throw std::invalid_argument(where + ": instance id 0 is the background");
    if (seen[inst.id])
      throw std::invalid_argument(where + ": instance id " + std::to_string(inst.id) + " appears twice");
    seen[inst.id] = 1;
    if (inst.class_id < 0 || inst.class_id >= kCocoClassCount) {
      throw std::invalid_argument(where + ": instance " + std::to_string(inst.id) + " has class id " +
                                  std::to_string(inst.class_id) + ", not a COCO class id (0 .. 79)");
    }
  }
}

std::vector<InstanceInfo> sorted_by_id(std::vector<InstanceInfo> instances) {
  std::sort(instances.begin(), instances.end(),
            [](const InstanceInfo& l, const InstanceInfo& r) { return l.id < r.id; });
  return instances;
}

bool same_instance(const InstanceInfo& a, const InstanceInfo& b) {
  return a.id == b.id && a.class_id == b.class_id && a.moving == b.moving;
}

}  // namespace

// ---- formats ------------------------------------------------------------------------------------

std::string format_tum_timestamp(double timestamp_s) { return metrics::format_tum_timestamp(timestamp_s); }

Eigen::Quaterniond canonical_quaternion(const Eigen::Matrix3d& R) { return metrics::canonical_quaternion(R); }

std::string format_tum_pose(double timestamp_s, const Eigen::Isometry3d& T_world_camera) {
  return metrics::format_tum_pose(timestamp_s, T_world_camera, metrics::TumDigits::decimals_9);
}

std::string format_instances_csv(const std::vector<InstanceInfo>& instances) {
  std::string csv = "id,class_id,class_name,moving\n";
  for (const InstanceInfo& inst : sorted_by_id(instances)) {
    csv += std::to_string(inst.id) + "," + std::to_string(inst.class_id) + "," +
           std::string(coco_class_name(inst.class_id)) + "," + (inst.moving ? "1" : "0") + "\n";
  }
  return csv;
}

std::string format_camera_yaml(const PinholeCamera& camera, double frame_rate_hz, const TumWriterSettings& s) {
  std::string y;
  const auto real = [&y](const char* key, double v) { y += std::string(key) + ": " + yaml_real(v) + "\n"; };
  const auto integer = [&y](const char* key, int v) { y += std::string(key) + ": " + std::to_string(v) + "\n"; };
  y += "%YAML:1.0\n---\n";
  y += "# Camera of a cge synthetic sequence in ORB-SLAM2's TUM settings format (RGB-D).\n";
  y += "# Pinhole, no distortion; depth images hold DepthMapFactor units per metre.\n";
  real("Camera.fx", camera.fx_px);
  real("Camera.fy", camera.fy_px);
  real("Camera.cx", camera.cx_px);
  real("Camera.cy", camera.cy_px);
  real("Camera.k1", 0.0);
  real("Camera.k2", 0.0);
  real("Camera.p1", 0.0);
  real("Camera.p2", 0.0);
  real("Camera.k3", 0.0);
  integer("Camera.width", camera.width_px);
  integer("Camera.height", camera.height_px);
  real("Camera.fps", frame_rate_hz);
  real("Camera.bf", s.orb_baseline_times_fx);
  y += "# Colour order as in the TUM settings (the PNGs are stored as RGB; ORB-SLAM2 reads them as TUM's).\n";
  integer("Camera.RGB", 1);
  real("ThDepth", s.orb_close_depth_baselines);
  real("DepthMapFactor", camera.depth_units_per_metre);
  real("cge.DepthSigmaPerMetre", s.depth_sigma_per_m);
  integer("ORBextractor.nFeatures", s.orb_features);
  real("ORBextractor.scaleFactor", s.orb_scale_factor);
  integer("ORBextractor.nLevels", s.orb_levels);
  integer("ORBextractor.iniThFAST", s.orb_initial_fast_threshold);
  integer("ORBextractor.minThFAST", s.orb_min_fast_threshold);
  for (const auto& [key, value] : kOrbSlamViewerDefaults) y += std::string(key) + ": " + value + "\n";
  return y;
}

// ---- checks -------------------------------------------------------------------------------------

void check_output_folder(const fs::path& out_dir, bool force) {
  std::error_code ec;
  const fs::file_status st = fs::status(out_dir, ec);
  if (!fs::exists(st)) return;
  if (!fs::is_directory(st)) {
    throw std::invalid_argument("output folder " + quoted(out_dir) + " exists and is not a folder");
  }
  const bool empty = fs::directory_iterator(out_dir, ec) == fs::directory_iterator();
  if (ec) throw std::invalid_argument("cannot list the output folder " + quoted(out_dir) + ": " + ec.message());
  if (!empty && !force) {
    throw std::invalid_argument("output folder " + quoted(out_dir) +
                                " exists and is not empty; refusing to write into it without force (cge_sim "
                                "--force), which overwrites only the sequence's own files and deletes nothing");
  }
}

void check_sequence(const FrameSource& source, const SegmentationErrorModel& model) {
  if (source.frame_count() < 1) {
    throw std::invalid_argument("the sequence has " + std::to_string(source.frame_count()) +
                                " frames; it needs at least one");
  }
  const PinholeCamera& c = source.camera();
  const bool finite = std::isfinite(c.fx_px) && std::isfinite(c.fy_px) && std::isfinite(c.cx_px) &&
                      std::isfinite(c.cy_px) && std::isfinite(c.depth_units_per_metre);
  if (!finite || c.fx_px <= 0 || c.fy_px <= 0 || c.width_px <= 0 || c.height_px <= 0 || c.depth_units_per_metre <= 0) {
    throw std::invalid_argument("the camera needs finite positive focal lengths, image size and depth scale");
  }
  if (!(std::isfinite(source.frame_rate_hz()) && source.frame_rate_hz() > 0)) {
    throw std::invalid_argument("the frame rate must be finite and positive, got " +
                                std::to_string(source.frame_rate_hz()));
  }
  check_instance_table(source.instances(), "the sequence's instance table");
  for (const LoopPair& loop : source.loops()) {
    if (!(loop.match_frame >= 0 && loop.match_frame < loop.query_frame && loop.query_frame < source.frame_count())) {
      throw std::invalid_argument("loop pair (query " + std::to_string(loop.query_frame) + ", match " +
                                  std::to_string(loop.match_frame) + ") needs 0 <= match < query < " +
                                  std::to_string(source.frame_count()));
    }
  }
  validate(model.settings);
  const std::vector<InstanceInfo> table = sorted_by_id(source.instances());
  if (table.size() != model.scene_instances().size() ||
      !std::equal(table.begin(), table.end(), model.scene_instances().begin(), same_instance)) {
    throw std::invalid_argument("the segmentation error model was made for a different instance table");
  }
  if (model.settings.false_positive_probability > 0) {
    model.false_positive_id(source.frame_count() - 1);  // throws when the ids run out
  }
}

SimulatedFrame simulate_frame(const FrameSource& source, const SegmentationErrorModel& model, int index) {
  SimulatedFrame s;
  s.frame = source.render(index);
  if (s.frame.index != index) {
    throw std::invalid_argument("the frame source returned frame " + std::to_string(s.frame.index) + " for index " +
                                std::to_string(index));
  }
  s.segmentation = model.apply(s.frame.instance_labels, index);
  return s;
}

// ---- encoding and writing -----------------------------------------------------------------------

EncodedFrame encode_frame(const RenderedFrame& frame, const SegmentationResult& segmentation, int png_compression) {
  if (png_compression < kPngFast || png_compression > kMaxPngCompression) {
    throw std::invalid_argument("PNG compression level " + std::to_string(png_compression) + " is not in -1 .. 9");
  }
  EncodedFrame e;
  e.rgb = encode_png(frame.rgb, png_compression, "rgb");
  e.depth = encode_png(frame.depth, png_compression, "depth");
  e.mask = encode_png(frame.instance_labels, png_compression, "instance-label");
  e.segmentation = encode_png(segmentation.instance_labels, png_compression, "segmentation");
  return e;
}

TumSequenceWriter::TumSequenceWriter(fs::path out_dir, const PinholeCamera& camera, double frame_rate_hz,
                                     std::vector<InstanceInfo> scene_instances, TumWriterSettings settings)
    : out_dir_(std::move(out_dir)),
      camera_(camera),
      frame_rate_hz_(frame_rate_hz),
      scene_instances_(sorted_by_id(std::move(scene_instances))),
      settings_(std::move(settings)) {
  if (settings_.png_compression < kPngFast || settings_.png_compression > kMaxPngCompression) {
    throw std::invalid_argument("TumWriterSettings::png_compression " + std::to_string(settings_.png_compression) +
                                " is not in -1 .. 9");
  }
  if (settings_.description.find_first_of("\r\n") != std::string::npos) {
    throw std::invalid_argument("TumWriterSettings::description must be one line");
  }
  check_instance_table(scene_instances_, "the sequence's instance table");
  check_output_folder(out_dir_, settings_.force);
  for (const char* sub : {kRgbDir, kDepthDir, kMasksDir, kSegmentationDir}) make_folder(out_dir_ / sub);
}

void TumSequenceWriter::write_frame(const RenderedFrame& frame, const SegmentationResult& segmentation) {
  write_checked(frame, segmentation, nullptr);
}

void TumSequenceWriter::write_frame(const RenderedFrame& frame, const SegmentationResult& segmentation,
                                    const EncodedFrame& encoded) {
  if (encoded.rgb.empty() || encoded.depth.empty() || encoded.mask.empty() || encoded.segmentation.empty()) {
    throw std::invalid_argument("frame " + std::to_string(frame.index) + ": an encoded image is empty");
  }
  write_checked(frame, segmentation, &encoded);
}

void TumSequenceWriter::write_checked(const RenderedFrame& frame, const SegmentationResult& segmentation,
                                      const EncodedFrame* encoded) {
  if (finished_) throw std::logic_error("TumSequenceWriter::write_frame after finish()");
  const int n = frame.index;
  require_image(frame.rgb, CV_8UC3, camera_, "rgb", n);
  require_image(frame.depth, CV_16UC1, camera_, "depth", n);
  require_image(frame.instance_labels, CV_16UC1, camera_, "instance-label", n);
  require_image(segmentation.instance_labels, CV_16UC1, camera_, "segmentation", n);
  if (!(std::isfinite(frame.timestamp_s) && frame.timestamp_s >= 0)) {
    throw std::invalid_argument("frame " + std::to_string(n) + ": timestamp " + std::to_string(frame.timestamp_s) +
                                " is not a finite non-negative number of seconds");
  }
  const std::string stem = format_tum_timestamp(frame.timestamp_s);
  if (!stems_.empty() && !(frame.timestamp_s > timestamps_.back() && stem != stems_.back())) {
    throw std::invalid_argument("frame " + std::to_string(n) + ": timestamp " + stem +
                                " does not come after the previous frame's " + stems_.back() +
                                " (6 decimals; file names would collide)");
  }
  const Eigen::Matrix3d R = frame.T_world_camera.linear();
  const double orthonormality_error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!frame.T_world_camera.matrix().allFinite() || !(orthonormality_error <= settings_.rotation_tolerance) ||
      R.determinant() <= 0) {
    throw std::invalid_argument("frame " + std::to_string(n) + ": T_world_camera is not a rigid motion");
  }

  // Labels: the ground truth uses scene ids; the segmentation also its own false positives.
  std::vector<std::uint8_t> known(kLabelCount, 0);
  known[0] = 1;
  for (const InstanceInfo& inst : scene_instances_) known[inst.id] = 1;
  require_known_labels(frame.instance_labels, known, "ground-truth", n);
  check_instance_table(segmentation.instances, "frame " + std::to_string(n) + ": the segmentation's instance table");
  std::vector<InstanceInfo> new_false_positives;
  for (const InstanceInfo& inst : segmentation.instances) {
    const auto scene = std::lower_bound(scene_instances_.begin(), scene_instances_.end(), inst.id,
                                        [](const InstanceInfo& a, std::uint16_t id) { return a.id < id; });
    if (scene != scene_instances_.end() && scene->id == inst.id) {
      if (!same_instance(*scene, inst)) {
        throw std::invalid_argument("frame " + std::to_string(n) + ": segmentation instance " +
                                    std::to_string(inst.id) + " differs from the scene's instance of that id");
      }
      continue;
    }
    const auto earlier = std::find_if(false_positives_.begin(), false_positives_.end(),
                                      [&inst](const InstanceInfo& f) { return f.id == inst.id; });
    if (earlier != false_positives_.end() && !same_instance(*earlier, inst)) {
      throw std::invalid_argument("frame " + std::to_string(n) + ": segmentation instance " + std::to_string(inst.id) +
                                  " differs from an earlier frame's instance of that id");
    }
    if (earlier == false_positives_.end()) new_false_positives.push_back(inst);
    known[inst.id] = 1;
  }
  require_known_labels(segmentation.instance_labels, known, "segmentation", n);

  const EncodedFrame own = encoded ? EncodedFrame{} : encode_frame(frame, segmentation, settings_.png_compression);
  const EncodedFrame& bytes = encoded ? *encoded : own;
  const std::string file = stem + kImageExtension;
  write_file(out_dir_ / kRgbDir / file, bytes.rgb);
  write_file(out_dir_ / kDepthDir / file, bytes.depth);
  write_file(out_dir_ / kMasksDir / file, bytes.mask);
  write_file(out_dir_ / kSegmentationDir / file, bytes.segmentation);

  timestamps_.push_back(frame.timestamp_s);
  stems_.push_back(stem);
  poses_.push_back(frame.T_world_camera);
  false_positives_.insert(false_positives_.end(), new_false_positives.begin(), new_false_positives.end());
}

void TumSequenceWriter::finish(const std::vector<LoopPair>& loops) {
  if (finished_) throw std::logic_error("TumSequenceWriter::finish called twice");
  const int n = frames_written();
  if (n == 0) throw std::invalid_argument("TumSequenceWriter::finish: no frame was written");
  for (const LoopPair& loop : loops) {
    if (!(loop.match_frame >= 0 && loop.match_frame < loop.query_frame && loop.query_frame < n)) {
      throw std::invalid_argument("loop pair (query " + std::to_string(loop.query_frame) + ", match " +
                                  std::to_string(loop.match_frame) + ") needs 0 <= match < query < " +
                                  std::to_string(n));
    }
  }

  write_file(out_dir_ / kMasksDir / kInstancesFile, format_instances_csv(scene_instances_));
  std::vector<InstanceInfo> segmentation_instances = scene_instances_;
  segmentation_instances.insert(segmentation_instances.end(), false_positives_.begin(), false_positives_.end());
  write_file(out_dir_ / kSegmentationDir / kInstancesFile, format_instances_csv(segmentation_instances));
  write_file(out_dir_ / kCameraFile, format_camera_yaml(camera_, frame_rate_hz_, settings_));

  const std::string source_line = "# file: '" + settings_.description + "'\n";
  std::string rgb = "# color images\n" + source_line + "# timestamp filename\n";
  std::string depth = "# depth maps\n" + source_line + "# timestamp filename\n";
  std::string associations;
  std::string groundtruth = "# ground truth trajectory\n" + source_line + "# timestamp tx ty tz qx qy qz qw\n";
  for (int i = 0; i < n; ++i) {
    const std::string& s = stems_[static_cast<std::size_t>(i)];
    rgb += s + " " + kRgbDir + "/" + s + kImageExtension + "\n";
    depth += s + " " + kDepthDir + "/" + s + kImageExtension + "\n";
    associations +=
        s + " " + kRgbDir + "/" + s + kImageExtension + " " + s + " " + kDepthDir + "/" + s + kImageExtension + "\n";
    groundtruth +=
        format_tum_pose(timestamps_[static_cast<std::size_t>(i)], poses_[static_cast<std::size_t>(i)]) + "\n";
  }
  write_file(out_dir_ / kRgbList, rgb);
  write_file(out_dir_ / kDepthList, depth);
  write_file(out_dir_ / kAssociationsFile, associations);
  write_file(out_dir_ / kGroundTruthFile, groundtruth);

  std::string loop_text =
      "# ground-truth loops: the query frame revisits the place seen in the match frame (match < query)\n"
      "# indices count the frames of rgb.txt from 0\n"
      "# query_timestamp match_timestamp query_index match_index\n";
  for (const LoopPair& loop : loops) {
    loop_text += stems_[static_cast<std::size_t>(loop.query_frame)] + " " +
                 stems_[static_cast<std::size_t>(loop.match_frame)] + " " + std::to_string(loop.query_frame) + " " +
                 std::to_string(loop.match_frame) + "\n";
  }
  write_file(out_dir_ / kLoopsFile, loop_text);
  finished_ = true;
}

void write_tum_sequence(const FrameSource& source, const SegmentationErrorModel& model, const fs::path& out_dir,
                        const TumWriterSettings& settings, const WriteProgress& progress) {
  check_sequence(source, model);
  const int n = source.frame_count();
  TumSequenceWriter writer(out_dir, source.camera(), source.frame_rate_hz(), source.instances(), settings);
  for (int i = 0; i < n; ++i) {
    const SimulatedFrame s = simulate_frame(source, model, i);
    writer.write_frame(s.frame, s.segmentation);
    if (progress) progress(i + 1, n);
  }
  writer.finish(source.loops());
}

}  // namespace sim
}  // namespace cge
