#pragma once
// OrbSlam2KeyframePolicy: the baseline of ALGORITHMS.md section 2, ORB-SLAM2's keyframe decision
// (Tracking::NeedNewKeyFrame) reduced to what a FrameSummary carries, behind the same interface as
// PatchKeyframeSelector (step, flush, reset, reference_id, pending_ids, set_reference_tracked_points).
//
// ORB-SLAM2 inserts when (c1a || c1b || c1c) && c2 with
//   c1a: max_frames passed since the last keyframe,  c1b: min_frames passed and local mapping idle,
//   c1c: (stereo/RGB-D) tracking weak,  c2: tracked < ratio x reference's tracked and tracked > 15.
// Here, with no mapping thread (local mapping is always idle) and no per-point depth:
// - tracked_ratio: frames_since_reference >= min_frame_gap, tracked < reference_ratio x the
//   reference keyframe's tracked points, and tracked > min_tracked_points (c1b && c2);
// - max_frame_gap: frames_since_reference >= max_frame_gap and tracked > min_tracked_points. With an
//   idle mapper ORB-SLAM2's c1a adds nothing to c1b; we read "max gap" as "at least one keyframe
//   every max_frame_gap frames", the usual meaning, and let it be switched off.
// c1c and the "close points" test are not modelled. The reference is the last keyframe inserted
// (ORB-SLAM2 uses the keyframe sharing most points with the frame; a host can override its count
// with set_reference_tracked_points()).
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
  /// Insert when tracked points < this x the reference keyframe's, in (0, 1] (the specification's
  /// 90%, ORB-SLAM2's monocular value; it uses 0.75 for stereo and RGB-D, 0.4 while the map holds
  /// fewer than 2 keyframes).
  Scalar reference_ratio = Scalar(0.9);
  /// No tracked_ratio insertion before this many frames since the reference keyframe (ORB-SLAM2:
  /// mMinFrames = 0).
  int min_frame_gap = 0;
  /// Insert once this many frames have passed since the reference keyframe, >= 1 (ORB-SLAM2:
  /// mMaxFrames = the frame rate; 30 for TUM RGB-D).
  int max_frame_gap = 30;
  /// No insertion unless more than this many map points are tracked (ORB-SLAM2: 15).
  int min_tracked_points = 15;

  bool use_tracked_ratio = true;  ///< tracked_ratio rule
  bool use_max_frame_gap = true;  ///< max_frame_gap rule

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    auto fail = [](const char* what) { throw std::invalid_argument(std::string("OrbSlam2KeyframeSettings: ") + what); };
    if (!(reference_ratio > 0 && reference_ratio <= 1)) fail("reference_ratio must lie in (0, 1]");
    if (min_frame_gap < 0) fail("min_frame_gap must not be negative");
    if (max_frame_gap < 1) fail("max_frame_gap must be at least 1");
    if (min_tracked_points < 0) fail("min_tracked_points must not be negative");
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

  /// One frame; only frame_id and tracked_points are read (patch counts may be empty). Throws
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

    const bool enough_tracked = frame.tracked_points > settings.min_tracked_points;
    if (settings.use_tracked_ratio && enough_tracked && gap >= settings.min_frame_gap &&
        static_cast<Scalar>(frame.tracked_points) <
            settings.reference_ratio * static_cast<Scalar>(reference_.tracked_points)) {
      d.rule = KeyframeRule::tracked_ratio;
    } else if (settings.use_max_frame_gap && enough_tracked && gap >= settings.max_frame_gap) {
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
    reference_ = Reference{frame.frame_id, steps_, frame.tracked_points};
  }

  bool has_reference_ = false;
  Reference reference_;
  std::int64_t steps_ = 0;
  std::int64_t last_id_ = kNoFrame;
};

}  // namespace cge
