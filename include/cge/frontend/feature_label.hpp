#pragma once
// The verdict on one keypoint of the dynamic-feature elimination, with its reason.

#include <cstdint>

namespace cge {

/// Why a keypoint is kept or dropped (docs/METHOD.md section 1). The reason is kept, not just a
/// flag: it feeds the ablation (mask only vs mask + MAD) and the statistics of dynamic points
/// that leak through.
enum class FeatureLabel : std::uint8_t {
  static_feature,   ///< kept: in no dynamic mask, and not caught by the depth test of any box
  dynamic_by_mask,  ///< dropped: its pixel lies in a dynamic instance's mask (step 1)
  dynamic_by_mad,   ///< dropped: in a dynamic instance's box, depth within k * MAD of its mean (step 3)
};

/// "static", "dynamic_by_mask" or "dynamic_by_mad" (stable names for CSV and JSON output).
inline const char* to_string(FeatureLabel label) {
  switch (label) {
    case FeatureLabel::static_feature:
      return "static";
    case FeatureLabel::dynamic_by_mask:
      return "dynamic_by_mask";
    case FeatureLabel::dynamic_by_mad:
      return "dynamic_by_mad";
  }
  return "invalid";  // only for a value cast from an out-of-range integer
}

/// True for both dynamic labels.
inline bool is_dynamic(FeatureLabel label) { return label != FeatureLabel::static_feature; }

}  // namespace cge
