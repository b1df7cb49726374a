#pragma once
// OrbSlam2KeyframePolicy: the baseline of docs/METHOD.md (keyframe selection), ORB-SLAM2's RGB-D
// keyframe decision (Tracking::NeedNewKeyFrame) reduced to what a FrameSummary carries, behind the
// same interface as PatchKeyframeSelector (step, flush, reset, reference_id, pending_ids,
// set_reference_tracked_points).
//
// ORB-SLAM2 inserts when (c1a || c1b || c1c) && c2, with, for RGB-D:
//   need_close: tracked close points < 100 and untracked close points > 70 (close: depth under
//               ThDepth baselines; the frame could add many near points the map lacks),
//   c1a: max_frames (the frame rate) passed since the last keyframe,
//   c1b: min_frames (0) passed and local mapping idle,
//   c1c: tracked < 0.25 x the reference keyframe's tracked points, or need_close,
//   c2:  (tracked < ratio x reference's tracked, or need_close) and tracked > 15; ratio 0.75, 0.4
//        while the map holds a single keyframe.
// The reference keyframe's count is its map points observed at least nMinObs times (3; 2 while the
// map holds at most 2 keyframes), which only the host knows: it passes it through
// set_reference_tracked_points() before each step. With no mapping thread local mapping is always
// idle, so c1b holds from min_frame_gap on (at 0: always) and the decision is c2; c1a and c1c
// matter only with min_frame_gap > 0. The rule that fired is reported as tracked_ratio,
// close_points or max_frame_gap (in that order of precedence).
// Every decision is immediate, so nothing is ever pending. Deterministic; a throwing step()
// changes nothing.

#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/frontend/frame_summary.hpp"
#include "cge/frontend/keyframe_decision.hpp"

namespace cge {

template <typename Scalar>
struct OrbSlam2KeyframeSettings {
  /// c2: insert when tracked points < this x the reference keyframe's, in (0, 1] (ORB-SLAM2
  /// thRefRatio: 0.75 for stereo and RGB-D, 0.9 monocular).
  Scalar reference_ratio = Scalar(0.75);
  /// The same while only one keyframe has been inserted, in (0, 1] (ORB-SLAM2: 0.4 while nKFs < 2).
  Scalar first_reference_ratio = Scalar(0.4);
  /// c1c: tracking is weak when tracked points < this x the reference's, in [0, 1] (ORB-SLAM2: 0.25).
  Scalar weak_tracking_ratio = Scalar(0.25);
  /// c1b: frames since the reference keyframe before the mapper may take one (ORB-SLAM2:
  /// mMinFrames = 0), >= 0.
  int min_frame_gap = 0;
  /// c1a: frames since the reference keyframe after which a keyframe is due (ORB-SLAM2:
  /// mMaxFrames = the camera's frame rate, 30 on TUM), >= 1.
  int max_frame_gap = 30;
  /// c2: no insertion unless more than this many map points are tracked (ORB-SLAM2: 15), >= 0.
  int min_tracked_points = 15;
  /// need_close: fewer tracked close points than this ... (ORB-SLAM2: 100), >= 0
  int close_tracked_below = 100;
  /// ... and more untracked close points than this (ORB-SLAM2: 70), >= 0.
  int close_untracked_above = 70;

  bool use_tracked_ratio = true;  ///< the ratio part of c2 (and c1c's weak-tracking test)
  /// Ours, not ORB-SLAM2's: also insert once max_frame_gap frames have passed even when c2 does not
  /// hold (with more than min_tracked_points tracked), i.e. at least one keyframe every
  /// max_frame_gap frames. Off by default: ORB-SLAM2 always requires c2.
  bool use_max_frame_gap = false;
  bool use_close_points = true;   ///< need_close (needs the summary's close-point counts)

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    auto fail = [](const char* what) { throw std::invalid_argument(std::string("OrbSlam2KeyframeSettings: ") + what); };
    if (!(reference_ratio > 0 && reference_ratio <= 1)) fail("reference_ratio must lie in (0, 1]");
    if (!(first_reference_ratio > 0 && first_reference_ratio <= 1)) fail("first_reference_ratio must lie in (0, 1]");
    if (!(weak_tracking_ratio >= 0 && weak_tracking_ratio <= 1)) fail("weak_tracking_ratio must lie in [0, 1]");
    if (min_frame_gap < 0) fail("min_frame_gap must not be negative");
    if (max_frame_gap < 1) fail("max_frame_gap must be at least 1");
    if (min_tracked_points < 0) fail("min_tracked_points must not be negative");
    if (close_tracked_below < 0 || close_untracked_above < 0) fail("close-point thresholds must not be negative");
  }
};

template <typename Scalar = double>
class OrbSlam2KeyframePolicy {
 public:
  using Settings = OrbSlam2KeyframeSettings<Scalar>;
  using Summary = FrameSummary<Scalar>;
  using Decision = KeyframeDecision<Scalar>;

  Settings settings;

  OrbSlam2KeyframePolicy() = default;
  explicit OrbSlam2KeyframePolicy(const Settings& s) : settings(s) {}

  /// One frame; only frame_id, tracked_points and the close-point counts are read (patch counts
  /// may be empty). Throws
  /// std::invalid_argument (and changes nothing) for bad settings, a bad summary or a frame id not
  /// greater than the previous one.
  Decision step(const Summary& frame) {
    settings.validate();
    frame.validate();
    if (last_id_ != kNoFrame && frame.frame_id <= last_id_) {
      std::ostringstream msg;
      msg << "OrbSlam2KeyframePolicy: frame ids must increase, got " << frame.frame_id << " after " << last_id_;
      throw std::invalid_argument(msg.str());
    }
    last_id_ = frame.frame_id;
    ++steps_;

    Decision d;
    d.frame_id = frame.frame_id;
    d.measures.tracked_points = frame.tracked_points;
    d.measures.instance_count = frame.instance_count();
    if (!has_reference_) {
      make_reference(frame);
      d.rule = KeyframeRule::first_frame;
      d.keyframe_id = frame.frame_id;
      return d;
    }
    const std::int64_t gap = steps_ - reference_.step;
    d.measures.reference_tracked_points = reference_.tracked_points;
    d.measures.frames_since_reference = static_cast<int>(gap);

    const Scalar tracked = static_cast<Scalar>(frame.tracked_points);
    const Scalar reference = static_cast<Scalar>(reference_.tracked_points);
    const Scalar ratio = keyframes_ < 2 ? settings.first_reference_ratio : settings.reference_ratio;
    const bool need_close = settings.use_close_points && frame.tracked_close_points >= 0 &&
                            frame.untracked_close_points >= 0 &&
                            frame.tracked_close_points < settings.close_tracked_below &&
                            frame.untracked_close_points > settings.close_untracked_above;
    const bool below_ratio = settings.use_tracked_ratio && tracked < ratio * reference;
    const bool c1a = gap >= settings.max_frame_gap;
    const bool c1b = gap >= settings.min_frame_gap;  // local mapping is always idle here
    const bool c1c = (settings.use_tracked_ratio && tracked < settings.weak_tracking_ratio * reference) || need_close;
    const bool c2 = (below_ratio || need_close) && frame.tracked_points > settings.min_tracked_points;
    if ((c1a || c1b || c1c) && c2) {
      d.rule = below_ratio ? KeyframeRule::tracked_ratio : KeyframeRule::close_points;
    } else if (settings.use_max_frame_gap && c1a && frame.tracked_points > settings.min_tracked_points) {
      d.rule = KeyframeRule::max_frame_gap;
    }
    if (d.rule != KeyframeRule::none) {
      d.keyframe_id = frame.frame_id;
      make_reference(frame);
    }
    return d;
  }

  /// Nothing is ever pending: returns a decision without a keyframe.
  Decision flush() { return Decision{}; }

  /// Forget everything: the next frame is a first frame again. Settings are kept.
  void reset() {
    has_reference_ = false;
    reference_ = Reference{};
    steps_ = 0;
    keyframes_ = 0;
    last_id_ = kNoFrame;
  }

  /// ORB-SLAM2 compares with the map points the reference keyframe observes, which the host knows
  /// only after creating them (at the first keyframe the frame itself tracks none). Call this after
  /// each insertion with that number. Throws std::logic_error before the first frame.
  void set_reference_tracked_points(int tracked_points) {
    if (!has_reference_) throw std::logic_error("OrbSlam2KeyframePolicy: no reference keyframe yet");
    if (tracked_points < 0) throw std::invalid_argument("OrbSlam2KeyframePolicy: negative reference tracked points");
    reference_.tracked_points = tracked_points;
  }

  std::int64_t reference_id() const { return has_reference_ ? reference_.id : kNoFrame; }
  std::vector<std::int64_t> pending_ids() const { return {}; }

 private:
  struct Reference {
    std::int64_t id = kNoFrame;
    std::int64_t step = 0;  // 1-based step number since reset()
    int tracked_points = 0;
  };

  void make_reference(const Summary& frame) {
    has_reference_ = true;
    ++keyframes_;
    reference_ = Reference{frame.frame_id, steps_, frame.tracked_points};
  }

  bool has_reference_ = false;
  Reference reference_;
  std::int64_t steps_ = 0;
  int keyframes_ = 0;  // inserted since reset(): ORB-SLAM2's nKFs for the first-keyframe ratio
  std::int64_t last_id_ = kNoFrame;
};

}  // namespace cge
