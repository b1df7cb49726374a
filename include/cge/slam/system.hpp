#pragma once
// System: the reference pipeline assembled from its components (kiss-icp's pipeline class is the
// model: settings in, frames in, results out). It owns the segmentation source, the frame maker,
// the tracker, the keyframe policy and the map, and times each stage.
//
// Per frame (process): segmentation (modes Y, YM, YMK; skipped in mode none) -> features and depth
// -> dynamic elimination -> tracking -> keyframe decision and insertion (new map points from
// depth) -> after_keyframe_inserted(): local bundle adjustment around the new keyframe
// (settings.local_mapping, cge/slam/local_mapping.hpp), then loop closing and optimisation
// (section 7), which the loop closer plugs into. Call finish() after the last frame (the patch policy may still
// insert a pending keyframe).
//
// Deterministic: the same frames, instances and settings give the same records and map.
#include <array>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/frontend/keyframe_policy.hpp"
#include "cge/segmentation/instance_segmenter.hpp"
#include "cge/slam/frame.hpp"
#include "cge/slam/loop_correction.hpp"
#include "cge/slam/map.hpp"
#include "cge/slam/settings.hpp"
#include "cge/slam/tracker.hpp"

namespace cge {
namespace slam {

/// One RGB-D frame as the System takes it.
struct FrameInput {
  int index = 0;           ///< 0, 1, 2, ... strictly increasing
  double timestamp_s = 0;  ///< seconds
  cv::Mat bgr;             ///< CV_8UC3
  cv::Mat depth;           ///< CV_16UC1 in settings.frame.depth_units_per_metre units, or CV_32FC1 metres
  std::string stem;        ///< the RGB file name without extension (what mask folders are keyed by)
  /// Optional ground truth for the leak count: CV_8UC1 of the image's size, non-zero on the pixels
  /// of bodies that move in the world; empty = unknown (cge/slam/moving_keypoints.hpp).
  cv::Mat moving_mask;
};

/// Stages timed per frame, in the column order of timings.csv.
enum class Stage : int {
  segmentation,
  features,
  dynamic_filter,
  tracking,
  keyframe,
  local_mapping,
  loop_closing,
  optimisation,
  total
};
constexpr int kStageCount = 9;
/// "segmentation", "features", ... "total".
const char* to_string(Stage stage);

/// What happened to one frame.
struct FrameRecord {
  int index = 0;
  double timestamp_s = 0;
  TrackingState state = TrackingState::lost;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  ///< as tracked (meaningful unless lost)
  int reference_keyframe = -1;  ///< the keyframe the pose is kept relative to (-1 when lost)
  Eigen::Isometry3d T_reference_camera = Eigen::Isometry3d::Identity();
  int keypoints = 0;
  int dynamic_by_mask = 0;
  int dynamic_by_mad = 0;
  int instances = 0;  ///< segmented instances, all classes
  int matches = 0;
  int inliers = 0;
  int keyframe_id = -1;                ///< the keyframe made from this frame (possibly decided a few frames later)
  const char* keyframe_rule = "none";  ///< the policy rule that made it one
  /// Keypoints on FrameInput::moving_mask (pixel rounding of cge/slam/moving_keypoints.hpp), and of
  /// those the ones labelled static (passed on to tracking); both -1 when the mask was empty.
  int moving_keypoints = -1;
  int moving_kept = -1;
  std::array<double, kStageCount> times_ms{};  ///< per Stage, milliseconds (measurements)

  bool has_pose() const { return state != TrackingState::lost; }
};

/// One decision of the loop closer, as loops.csv lists it.
struct LoopRecord {
  int query_keyframe = -1;
  double query_timestamp_s = 0;
  int match_keyframe = -1;  ///< -1: no candidate
  double match_timestamp_s = 0;
  double bow_score = 0;
  double cge_score = 0;
  int matched_points = 0;
  bool accepted = false;
  std::string reason =
      "no_candidates";  ///< accepted, no_candidates, low_score, continuity, too_few_matches, pose_not_robust

  int tentative_matches = 0;             ///< LoopDecision::tentative_matches
  int verified_keyframes = 0;            ///< LoopDecision::verified_keyframes
  std::vector<int> connected_keyframes;  ///< LoopDecision::connected_keyframes
};

class LoopCloser;
class LocalBundleAdjustment;

class System {
 public:
  /// Throws std::invalid_argument for bad settings or intrinsics. `segmenter` may be null: no
  /// instances (modes Y/YM/YMK then behave as none, apart from the keyframe policy).
  System(const SystemSettings& settings, const PinholeIntrinsics<double>& intrinsics,
         std::unique_ptr<InstanceSegmenter> segmenter = nullptr);
  ~System();
  System(System&&) noexcept;
  System& operator=(System&&) noexcept;

  /// Enables loop closing (section 7): after each keyframe insertion the closer processes the new
  /// keyframe and its decision becomes a LoopRecord. With settings.loop_correction enabled an
  /// accepted loop is corrected at once (LoopCorrection: pose graph, then global BA), unless the last
  /// correction is at most loop_correction.min_keyframes_between keyframes old; its loop edge then
  /// joins the next correction. Set it before the first frame.
  void set_loop_closer(std::unique_ptr<LoopCloser> loop_closer);

  /// One frame, segmented by the owned segmenter (not in mode none). Throws std::invalid_argument
  /// for bad images (the message names the frame) or a frame index not greater than the last.
  const FrameRecord& process(const FrameInput& input);
  /// One frame with its instances given (segmentation_ms is recorded as the segmentation time).
  const FrameRecord& process(const FrameInput& input, const std::vector<SegmentedInstance>& instances,
                             double segmentation_ms = 0);
  /// End of sequence: lets the keyframe policy insert its last pending candidate.
  void finish();

  const SystemSettings& settings() const { return settings_; }
  const std::vector<FrameRecord>& frames() const { return records_; }
  const Map& map() const { return map_; }
  const std::vector<LoopRecord>& loops() const { return loops_; }
  /// Loop corrections applied (pose graph + bundle adjustment runs).
  int loop_corrections() const { return loop_correction_.corrections(); }
  /// The current pose estimate of a frame: its reference keyframe's current pose times the
  /// relative pose at tracking time (so optimisation of keyframes moves the whole trajectory).
  /// The relative pose is taken against the keyframe's pose as the tracker saw it, before the
  /// local BA and loop correction that the frame's keyframe decision may trigger; a keyframe's
  /// own frame is its keyframe (identity).
  Eigen::Isometry3d pose_of(const FrameRecord& record) const;

 private:
  struct Pending {
    Frame frame;
    TrackResult track;
    std::size_t record = 0;
  };
  void decide_keyframe(Frame& frame, TrackResult& track, std::size_t record);
  void apply_decision(const KeyframeDecision<double>& decision, Frame* current, TrackResult* track, std::size_t record);
  /// `record` is the keyframe's frame; `current_record` the frame being processed (kNoRecord when
  /// none is, as in finish()).
  int insert_keyframe(const Frame& frame, const TrackResult& track, std::size_t record, const char* rule,
                      std::size_t current_record);
  /// After a keyframe is in the map: loop closing (section 7) and the optimisation it triggers.
  /// The loop closer appends its decision to loops_ and corrects poses through map_; timed as the
  /// loop_closing and optimisation stages of the current frame.
  void after_keyframe_inserted(int keyframe_id);
  /// Map maintenance around a new keyframe and the start of its local BA (LocalMappingSettings),
  /// timed as local_mapping.
  void local_mapping(int keyframe_id);
  /// Solves at most `max_rounds` rounds of the pending local BA (ba_rounds_per_frame in a frame,
  /// kAllRounds before the map changes and at the end), or, when ba_iterations_per_frame > 0 and
  /// not kAllRounds, at most that many iterations; when it is done, the keyframe's local
  /// mapping ends (complete_keyframe). The time goes to `charged`'s stages.
  void advance_local_mapping(FrameRecord& charged, int max_rounds);
  static constexpr int kAllRounds = std::numeric_limits<int>::max();
  /// LocalMappingSettings::maintenance with the frame's close-depth threshold.
  MapMaintenanceSettings maintenance_settings() const;
  /// After a keyframe's local BA: redundant keyframes culled, then loop closing and correction.
  void complete_keyframe(int keyframe_id, FrameRecord& charged);
  static constexpr std::size_t kNoRecord = static_cast<std::size_t>(-1);
  /// Keeps record's pose relative to keyframe_id's pose as it is now (see pose_of).
  void keep_relative_to(std::size_t record, int keyframe_id);

  SystemSettings settings_;
  PinholeIntrinsics<double> intrinsics_;
  std::unique_ptr<InstanceSegmenter> segmenter_;
  FrameMaker frame_maker_;
  Tracker tracker_;
  KeyframePolicy<double> keyframe_policy_;
  Map map_;
  std::vector<FrameRecord> records_;
  std::vector<LoopRecord> loops_;
  std::deque<Pending> pending_;
  std::unique_ptr<LoopCloser> loop_closer_;
  std::unique_ptr<LocalBundleAdjustment> local_ba_;  ///< the local BA under way, null: none
  LoopCorrection loop_correction_;  ///< every accepted loop's edge, and the corrections
  /// Map points made by the last keyframes, not yet judged by map-point culling (ascending id).
  std::vector<std::int64_t> recent_points_;
  cv::Size image_size_;  ///< of the frames processed (projections into keyframes)
};

}  // namespace slam
}  // namespace cge
