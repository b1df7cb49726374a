#pragma once
// The writer of synthetic sequences in the layout of the TUM RGB-D benchmark, plus the masks:
//
//   rgb/<stem>.png            8-bit colour (the frame's BGR image, stored as PNG's RGB)
//   depth/<stem>.png          16-bit depth, camera.depth_units_per_metre per metre (5000), 0 = none
//   masks/<stem>.png          16-bit ground-truth instance labels   } the mask-folder format
//   masks/instances.csv       id,class_id,class_name,moving         } (docs/SIMULATION.md)
//   segmentation/<stem>.png   16-bit labels after the segmentation error model
//   segmentation/instances.csv   the scene's instances plus the false positives that occur
//   rgb.txt, depth.txt        "timestamp filename" lists, as in TUM
//   associations.txt          "t rgb/<stem>.png t depth/<stem>.png", as TUM's associate.py writes
//   groundtruth.txt           "timestamp tx ty tz qx qy qz qw" (T_world_camera; qw >= 0)
//   camera.yaml               ORB-SLAM2 TUM settings (Camera.fx ..., DepthMapFactor, ORBextractor.*)
//   loops.txt                 "query_timestamp match_timestamp query_index match_index"
//
// <stem> is the timestamp with 6 decimals (e.g. 0.033333). Every file is a function of the frames,
// the instance table, the camera and the settings only (no dates, no paths, no host names): the
// same sequence and seed give the same bytes. Nothing is ever deleted: an existing non-empty output
// folder is refused unless settings.force, and then only the files above are (over)written.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/sim/frame_source.hpp"
#include "cge/sim/segmentation_error_model.hpp"
#include "cge/sim/sequence.hpp"

namespace cge {
namespace sim {

/// TumWriterSettings::png_compression value that selects OpenCV's fast PNG path.
inline constexpr int kPngFast = -1;

struct TumWriterSettings {
  /// PNG compression of every image. kPngFast (-1): OpenCV's speed path (zlib level 1, RLE
  /// matching, the SUB row filter), the fastest by far on rendered frames; 0 .. 9: that zlib level
  /// with libpng's adaptive row filters, about 3 times slower for files ~5% smaller (level 0:
  /// slower and 2.3 times larger). Measurements in docs/SIMULATION.md.
  int png_compression = kPngFast;
  /// Write into an existing non-empty folder (overwriting this writer's own files, deleting nothing).
  bool force = false;
  /// Written into the "# file:" header line of rgb.txt, depth.txt and groundtruth.txt, where TUM
  /// names its source bag (e.g. "cge_sim walking_xyz frames 300 seed 1"); no newlines.
  std::string description = "cge synthetic sequence";
  /// Largest |(R^T R - I)_ij| accepted for the rotation of a pose (else the frame is refused).
  double rotation_tolerance = 1e-6;
  /// ORB-SLAM2 settings written to camera.yaml beside the intrinsics (their TUM3.yaml values).
  double orb_baseline_times_fx = 40.0;      ///< Camera.bf: virtual stereo baseline times fx, pixels x metres
  double orb_close_depth_baselines = 40.0;  ///< ThDepth: close/far threshold, in baselines
  /// cge.DepthSigmaPerMetre: the depth weight the pipeline should give this sequence, sigma_z =
  /// value * z^2, 1/m (ours: the rendered noise is the Kinect v1 model alone, without the
  /// registration and timing errors of real frames; 0.003 is the weight the rendered presets were
  /// measured with, docs/REAL_DATA.md). ORB-SLAM2 ignores keys it does not know.
  double depth_sigma_per_m = 0.003;
  int orb_features = 1000;                  ///< ORBextractor.nFeatures
  double orb_scale_factor = 1.2;            ///< ORBextractor.scaleFactor
  int orb_levels = 8;                       ///< ORBextractor.nLevels
  int orb_initial_fast_threshold = 20;      ///< ORBextractor.iniThFAST
  int orb_min_fast_threshold = 7;           ///< ORBextractor.minThFAST
};

/// Progress: called after each frame with the number of frames written and the total.
using WriteProgress = std::function<void(int frames_done, int frame_count)>;

/// The PNG bytes of one frame's four images (what write_frame puts on disk).
struct EncodedFrame {
  std::vector<std::uint8_t> rgb, depth, mask, segmentation;
};

/// Writes a sequence frame by frame. The constructor prepares the folder (creating it, or refusing
/// it when it exists and is not empty, unless settings.force); write_frame() adds one frame's
/// images; finish() writes the lists, tables, camera file and loops. Frames must come in strictly
/// increasing timestamp order with distinct 6-decimal stems.
///
/// Errors: std::invalid_argument for bad input (a folder refused, images of the wrong type or
/// size, labels not in the tables, timestamps out of order), std::runtime_error naming the path
/// for a file or folder that cannot be written.
class TumSequenceWriter {
 public:
  TumSequenceWriter(std::filesystem::path out_dir, const PinholeCamera& camera, double frame_rate_hz,
                    std::vector<InstanceInfo> scene_instances, TumWriterSettings settings = {});

  void write_frame(const RenderedFrame& frame, const SegmentationResult& segmentation);

  /// The same with the PNGs encoded by the caller, which must pass
  /// encode_frame(frame, segmentation, settings().png_compression): encoding is most of a frame's
  /// time and is a pure function, so a caller may run it on other threads and commit frames here in
  /// order (cge_sim does). The frame is checked as by the other overload; the bytes are not.
  void write_frame(const RenderedFrame& frame, const SegmentationResult& segmentation, const EncodedFrame& encoded);

  /// loops: ground-truth loop pairs, frame indices of the frames written (in write order).
  void finish(const std::vector<LoopPair>& loops);

  const std::filesystem::path& out_dir() const { return out_dir_; }
  int frames_written() const { return static_cast<int>(timestamps_.size()); }
  const TumWriterSettings& settings() const { return settings_; }

 private:
  void write_checked(const RenderedFrame& frame, const SegmentationResult& segmentation, const EncodedFrame* encoded);

  std::filesystem::path out_dir_;
  PinholeCamera camera_;
  double frame_rate_hz_;
  std::vector<InstanceInfo> scene_instances_;  // ascending id
  TumWriterSettings settings_;
  std::vector<double> timestamps_;
  std::vector<std::string> stems_;
  std::vector<Eigen::Isometry3d> poses_;
  std::vector<InstanceInfo> false_positives_;  // ascending id (ids grow with the frame index)
  bool finished_ = false;
};

/// The whole sequence: every frame of `source` through `model` into out_dir, then finish().
/// Checks the sequence (at least one frame, camera, instance table, loops) before touching the disk.
void write_tum_sequence(const FrameSource& source, const SegmentationErrorModel& model,
                        const std::filesystem::path& out_dir, const TumWriterSettings& settings = {},
                        const WriteProgress& progress = {});

/// Encodes one frame's images as PNG (no disk access; for tests and benchmarks); png_compression
/// as TumWriterSettings::png_compression.
EncodedFrame encode_frame(const RenderedFrame& frame, const SegmentationResult& segmentation, int png_compression);

/// Throws std::invalid_argument when out_dir exists and is not an empty directory (and !force, for
/// a non-empty directory); the message names the folder. Touches nothing.
void check_output_folder(const std::filesystem::path& out_dir, bool force);

/// Checks what does not depend on the frames' pixels: at least one frame, a finite positive
/// camera and frame rate, a valid instance table that the model was made for, loops inside the
/// sequence with match < query, and false-positive ids for every frame (when enabled).
void check_sequence(const FrameSource& source, const SegmentationErrorModel& model);

/// One frame rendered and passed through the error model, in memory (no disk access).
struct SimulatedFrame {
  RenderedFrame frame;
  SegmentationResult segmentation;
};

/// Frame `index` of `source` with its segmentation by `model`; throws std::invalid_argument when
/// the source returns a frame with another index.
SimulatedFrame simulate_frame(const FrameSource& source, const SegmentationErrorModel& model, int index);

// ---- the text formats, exposed for readers and tests ----

/// A timestamp as TUM writes it (metrics::format_tum_timestamp): seconds with 6 decimals
/// ("1305031102.175304"); it is also the file stem of the frame's images.
std::string format_tum_timestamp(double timestamp_s);

/// The ground-truth line: metrics::format_tum_pose with 9 decimals for every value after the
/// timestamp (the quaternion by metrics::canonical_quaternion, so a pose has one spelling).
std::string format_tum_pose(double timestamp_s, const Eigen::Isometry3d& T_world_camera);

/// metrics::canonical_quaternion: the unique quaternion of a rotation under the writer's sign rule.
Eigen::Quaterniond canonical_quaternion(const Eigen::Matrix3d& R);

/// The instances.csv of the mask-folder format (header and one line per instance, ascending id).
std::string format_instances_csv(const std::vector<InstanceInfo>& instances);

/// camera.yaml: ORB-SLAM2's TUM settings, readable by cv::FileStorage. (cv::FileStorage cannot
/// write these keys itself: it refuses the '.' in "Camera.fx".)
std::string format_camera_yaml(const PinholeCamera& camera, double frame_rate_hz, const TumWriterSettings& settings);

}  // namespace sim
}  // namespace cge
