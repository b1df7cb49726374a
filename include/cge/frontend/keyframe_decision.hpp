#pragma once
// What a keyframe policy answers for each frame: which frame (if any) becomes a keyframe, by which
// rule, and the quantities it measured, for logs and ablations. Shared by PatchKeyframeSelector
// and OrbSlam2KeyframePolicy.

#include <cstdint>

#include "cge/frontend/frame_summary.hpp"

namespace cge {

enum class KeyframeRule : std::uint8_t {
  none,                     ///< no keyframe at this step
  first_frame,              ///< the first frame after construction or reset()
  tracking_guard,           ///< patch policy: tracked map points under the floor (ours, not the paper's)
  semantic_change,          ///< patch policy: |Num_cur - Num_ref| >= Num_th, inserted at once
  large_motion,             ///< patch policy: a candidate with D_sum > D_th, inserted at once
  interval_best_candidate,  ///< patch policy: interval end (or flush), the candidate with the highest D_sum
  tracked_ratio,            ///< ORB-SLAM2 baseline: tracked points under ratio x the reference keyframe's
  max_frame_gap,            ///< ORB-SLAM2 baseline: max_frame_gap frames since the reference keyframe
  close_points,             ///< ORB-SLAM2 baseline: few close points tracked, many untracked
  coverage_guard,           ///< patch policy: the frame tracks too few of its own close points (ours)
};

/// Stable lower-case name of a rule, for logs and settings files.
inline const char* to_string(KeyframeRule rule) {
  switch (rule) {
    case KeyframeRule::none:
      return "none";
    case KeyframeRule::first_frame:
      return "first_frame";
    case KeyframeRule::tracking_guard:
      return "tracking_guard";
    case KeyframeRule::semantic_change:
      return "semantic_change";
    case KeyframeRule::large_motion:
      return "large_motion";
    case KeyframeRule::interval_best_candidate:
      return "interval_best_candidate";
    case KeyframeRule::tracked_ratio:
      return "tracked_ratio";
    case KeyframeRule::max_frame_gap:
      return "max_frame_gap";
    case KeyframeRule::close_points:
      return "close_points";
    case KeyframeRule::coverage_guard:
      return "coverage_guard";
  }
  return "unknown";
}

/// Quantities a step measured for the frame it saw, against the reference keyframe of that moment.
template <typename Scalar>
struct KeyframeMeasures {
  // Patch policy (patch_measures is true for every step after the first frame).
  bool patch_measures = false;
  Scalar s_cos = Scalar(0);          ///< S_cos(Z_cur, Z_ref), in [0, 1]
  Scalar d_fp = Scalar(0);           ///< distance of the dense-patch means, pixels
  Scalar d_se = Scalar(0);           ///< distance of the semantic centroids, pixels; 0 unless semantic_term
  Scalar d_sum = Scalar(0);          ///< rho D_fp + (1 - rho) D_se, or D_fp without semantic_term
  bool semantic_term = false;        ///< both frames have instances, so D_se entered D_sum
  bool candidate = false;            ///< the frame passed the candidate test (and has features)
  int interval_position = 0;         ///< 1..k: this frame's place in the current interval
  int instance_count = 0;            ///< Num_cur
  int reference_instance_count = 0;  ///< Num_ref
  int semantic_change_frames = 0;  ///< consecutive frames, this one included, the semantic change has held
  // Both policies.
  int tracked_points = 0;            ///< the frame's tracked map points
  int reference_tracked_points = 0;  ///< the reference keyframe's (see set_reference_tracked_points)
  int frames_since_reference = 0;    ///< steps since the reference keyframe's own step (this one included)
  // Patch policy's coverage guard (-1: the summary did not count close points).
  int tracked_close_points = -1;            ///< the frame's tracked close points
  int untracked_close_points = -1;          ///< the frame's untracked close points
  int reference_tracked_close_points = -1;  ///< the reference keyframe's tracked close points at its step (reported; no rule reads it)
};

template <typename Scalar>
struct KeyframeDecision {
  /// The frame this step saw; kNoFrame for flush().
  std::int64_t frame_id = kNoFrame;
  /// The rule that fired; none when no keyframe is inserted.
  KeyframeRule rule = KeyframeRule::none;
  /// The frame that becomes a keyframe now: the current one, an earlier pending candidate
  /// (interval_best_candidate), or kNoFrame. It is the reference for every later frame.
  std::int64_t keyframe_id = kNoFrame;
  /// The current frame is a pending candidate after this step: keep its data (pose, features)
  /// until a later decision names it or pending_ids() no longer lists it.
  bool keep_current = false;
  KeyframeMeasures<Scalar> measures;

  bool inserts_keyframe() const { return keyframe_id != kNoFrame; }
};

}  // namespace cge
