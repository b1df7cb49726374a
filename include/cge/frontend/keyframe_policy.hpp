#pragma once
// KeyframePolicy: one of the keyframe policies, chosen at run time by a setting (the reference
// pipeline's switch between the method and the baseline). A std::variant, not a virtual base: the
// policy is a value (copy it to snapshot the state machine), and each call is one std::visit.
//
// Contract every alternative meets (and a custom policy added here must meet):
//   KeyframeDecision<Scalar> step(const FrameSummary<Scalar>&);  // throws and changes nothing on bad input
//   KeyframeDecision<Scalar> flush();                            // end of sequence
//   void reset();
//   void set_reference_tracked_points(int);
//   std::int64_t reference_id() const;                           // kNoFrame before the first frame
//   std::vector<std::int64_t> pending_ids() const;               // frames the host must keep

#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "cge/frontend/frame_summary.hpp"
#include "cge/frontend/keyframe_decision.hpp"
#include "cge/frontend/orbslam2_keyframe_policy.hpp"
#include "cge/frontend/patch_keyframe_selector.hpp"

namespace cge {

enum class KeyframePolicyKind : std::uint8_t {
  patch,     ///< PatchKeyframeSelector, the method
  orbslam2,  ///< OrbSlam2KeyframePolicy, the baseline
};

inline const char* to_string(KeyframePolicyKind kind) {
  return kind == KeyframePolicyKind::patch ? "patch" : "orbslam2";
}

/// "patch" or "orbslam2"; throws std::invalid_argument naming the accepted values otherwise.
inline KeyframePolicyKind parse_keyframe_policy_kind(const std::string& name) {
  if (name == "patch") return KeyframePolicyKind::patch;
  if (name == "orbslam2") return KeyframePolicyKind::orbslam2;
  throw std::invalid_argument("unknown keyframe policy '" + name + "' (expected 'patch' or 'orbslam2')");
}

template <typename Scalar = double>
class KeyframePolicy {
 public:
  using Summary = FrameSummary<Scalar>;
  using Decision = KeyframeDecision<Scalar>;
  using Variant = std::variant<PatchKeyframeSelector<Scalar>, OrbSlam2KeyframePolicy<Scalar>>;

  /// The configured policy; reach its settings with std::get / std::get_if.
  Variant policy;

  /// The method with default settings.
  KeyframePolicy() = default;
  KeyframePolicy(PatchKeyframeSelector<Scalar> p) : policy(std::move(p)) {}   // NOLINT: implicit on purpose
  KeyframePolicy(OrbSlam2KeyframePolicy<Scalar> p) : policy(std::move(p)) {}  // NOLINT: implicit on purpose
  /// The policy of `kind`, configured by the matching settings (the other settings are ignored).
  explicit KeyframePolicy(KeyframePolicyKind kind, const PatchKeyframeSettings<Scalar>& patch = {},
                          const OrbSlam2KeyframeSettings<Scalar>& orbslam2 = {}) {
    if (kind == KeyframePolicyKind::patch) {
      policy = PatchKeyframeSelector<Scalar>(patch);
    } else {
      policy = OrbSlam2KeyframePolicy<Scalar>(orbslam2);
    }
  }

  KeyframePolicyKind kind() const {
    return policy.index() == 0 ? KeyframePolicyKind::patch : KeyframePolicyKind::orbslam2;
  }

  Decision step(const Summary& frame) {
    return std::visit([&](auto& p) { return p.step(frame); }, policy);
  }
  Decision flush() {
    return std::visit([](auto& p) { return p.flush(); }, policy);
  }
  void reset() {
    std::visit([](auto& p) { p.reset(); }, policy);
  }
  void set_reference_tracked_points(int tracked_points) {
    std::visit([&](auto& p) { p.set_reference_tracked_points(tracked_points); }, policy);
  }
  std::int64_t reference_id() const {
    return std::visit([](const auto& p) { return p.reference_id(); }, policy);
  }
  std::vector<std::int64_t> pending_ids() const {
    return std::visit([](const auto& p) { return p.pending_ids(); }, policy);
  }
};

}  // namespace cge
