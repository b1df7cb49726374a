#pragma once
// DepthMADFilter: dynamic-feature elimination by instance masks plus the mean absolute deviation
// (MAD) of depth inside each dynamic instance's box (docs/METHOD.md section 1; the resolutions of
// the paper's ambiguities are in docs/METHOD.md).
//
// Pixels: a keypoint at (u, v) lies on pixel (round(u), round(v)), halves away from zero (OpenCV's
// convention: pixel centres at integer coordinates, as in GraphBuilder), clamped to the last column
// and row; keypoints must be finite and inside [0, W] x [0, H]. Boxes use area coordinates (see
// cge/frontend/pixel_box.hpp); a sample p_i of a box lies on pixel (floor(p_x), floor(p_y)).
//
// Determinism: the only randomness is the public `engine`, which the caller seeds. A call draws
// exactly 2 * samples_per_instance uniform doubles per instance with DepthEstimate::box_samples
// (none with mask_pixels) (cge/core/uniform_double.hpp,
// identical on every standard library), instance by instance in input order, x before y, and
// nothing else. Same input and same engine state: bit-identical result. The engine advances from
// call to call; reseed it per frame (e.g. with the frame index) to make a frame's labels depend on
// that frame alone. Input is validated before the first draw, so a call that throws leaves the
// engine untouched. filter() is not const (it advances the engine); use one filter per thread.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "cge/core/concepts.hpp"
#include "cge/core/mask.hpp"
#include "cge/core/nearest_pixel.hpp"
#include "cge/core/point_traits.hpp"
#include "cge/core/uniform_double.hpp"
#include "cge/core/depth_image.hpp"
#include "cge/frontend/feature_label.hpp"
#include "cge/frontend/pixel_box.hpp"

namespace cge {

/// Where an instance's depth statistics (d_j, MAD_j) come from.
enum class DepthEstimate {
  /// n random samples in the box, valid when the disc of radius r around the sample lies in the
  /// mask and the sample has depth (the paper's step 2).
  box_samples,
  /// every pixel of the box that is in the mask and has depth; no randomness (ours: on the TUM
  /// frame with depth on the people it caught every edge feature, docs/SEGMENTATION.md).
  mask_pixels,
};

/// "box_samples" or "mask_pixels".
inline const char* to_string(DepthEstimate estimate) {
  return estimate == DepthEstimate::mask_pixels ? "mask_pixels" : "box_samples";
}

/// Why an instance got no MAD test.
enum class MadSkipReason {
  none,                      ///< the test was applied
  too_few_valid_samples,     ///< valid_samples < min_valid_samples
  too_little_depth_in_mask,  ///< mask_pixels: valid / mask pixels < min_valid_mask_fraction
};

/// "none", "too_few_valid_samples", "too_little_depth_in_mask".
inline const char* to_string(MadSkipReason reason) {
  switch (reason) {
    case MadSkipReason::none:
      return "none";
    case MadSkipReason::too_few_valid_samples:
      return "too_few_valid_samples";
    case MadSkipReason::too_little_depth_in_mask:
      return "too_little_depth_in_mask";
  }
  return "unknown";
}

struct DepthMADSettings {
  /// n: random samples drawn in each instance's box (ours: 100, the specification's default; the
  /// paper names n but gives no value; the mean of 100 draws is off by about 1/10 of the spread).
  int samples_per_instance = 100;
  /// r: a sample is valid only when every pixel within this distance of its pixel is in the
  /// instance mask, pixels (paper: 6). 0 tests the sample's pixel alone.
  int disc_radius_px = 6;
  /// An instance with fewer valid samples gets no MAD test (ours: a mean and MAD from fewer than 5
  /// depths are too noisy to drop features on).
  int min_valid_samples = 5;
  /// k: a keypoint in a box is dynamic when |d - mean| < k * MAD (paper: 1), dimensionless, >= 0.
  double mad_scale = 1.0;
  /// false (ours, as cv::erode's default border): disc pixels outside the image are ignored, since
  /// the image border cuts an object rather than bounding it. true: they count as outside the mask.
  bool image_border_is_mask_edge = false;
  /// Where d_j and MAD_j come from (box_samples: the paper's step 2). samples_per_instance,
  /// disc_radius_px and image_border_is_mask_edge apply to box_samples only.
  DepthEstimate depth_estimate = DepthEstimate::box_samples;
  /// mask_pixels: the MAD test also needs at least this fraction of the mask's pixels in the box to
  /// have depth, in [0, 1] (ours: 0.5; on TUM fr3 walking_xyz a mask with depth on the person had
  /// 80 to 96 % of its pixels valid, one whose depth was lost 4 to 6 %, and the few valid pixels
  /// of the latter were mostly background, which the test would then have dropped).
  double min_valid_mask_fraction = 0.5;

  /// Throws std::invalid_argument naming the bad field.
  void validate() const {
    const auto fail = [](const std::string& what) { throw std::invalid_argument("DepthMADSettings: " + what); };
    if (samples_per_instance < 1) fail("samples_per_instance must be at least 1");
    if (disc_radius_px < 0) fail("disc_radius_px must not be negative");
    if (min_valid_samples < 1) fail("min_valid_samples must be at least 1");
    if (!(std::isfinite(mad_scale) && mad_scale >= 0)) fail("mad_scale must be finite and not negative");
    if (depth_estimate != DepthEstimate::box_samples && depth_estimate != DepthEstimate::mask_pixels) {
      fail("depth_estimate is not box_samples or mask_pixels");
    }
    if (!(min_valid_mask_fraction >= 0 && min_valid_mask_fraction <= 1)) {
      fail("min_valid_mask_fraction must lie in [0, 1]");
    }
  }
};

/// One instance of a dynamic class as the filter sees it: a view; the caller owns the mask and
/// keeps it alive during filter(). Only instances of dynamic classes belong here (the choice of
/// dynamic classes is the segmentation front end's).
template <typename Mask>
struct DynamicInstance {
  const Mask* mask = nullptr;  ///< binary mask adapted by cge::traits::Mask, the depth image's size
  PixelBox box_px;             ///< the instance's box, area coordinates (cge/frontend/pixel_box.hpp)
  int class_id = 0;            ///< informative only (e.g. COCO 0 = person); the filter does not read it
};

/// A DynamicInstance viewing `mask`.
template <typename Mask>
DynamicInstance<Mask> dynamic_instance(const Mask& mask, const PixelBox& box_px, int class_id = 0) {
  return DynamicInstance<Mask>{&mask, box_px, class_id};
}
/// Deleted: the instance would point at a temporary.
template <typename Mask>
DynamicInstance<Mask> dynamic_instance(const Mask&& mask, const PixelBox& box_px, int class_id = 0) = delete;

/// What one instance's samples gave (step 2). With DepthEstimate::mask_pixels every mask pixel in
/// the box is a sample: samples_drawn counts them, samples_off_mask is 0.
struct InstanceDepthStats {
  int samples_drawn = 0;          ///< n (mask_pixels: the mask's pixels in the box)
  int valid_samples = 0;          ///< disc inside the mask and valid depth
  int samples_off_mask = 0;       ///< rejected: the disc around the sample leaves the mask
  int samples_invalid_depth = 0;  ///< rejected: disc inside the mask, but no depth at the sample
  bool mad_test_applied = false;  ///< valid_samples >= min_valid_samples (mask_pixels: and the fraction)
  MadSkipReason skip_reason = MadSkipReason::none;  ///< why the test was not applied
  /// d_j and MAD_j over the valid samples, metres; NaN when there is none. Reported whenever
  /// valid_samples > 0, even when too few for the MAD test.
  double mean_depth_m = std::numeric_limits<double>::quiet_NaN();
  double mad_m = std::numeric_limits<double>::quiet_NaN();
};

/// The filter's output: one label per keypoint in input order (never shortened), one statistics
/// record per instance in input order, and the label counts.
struct DepthMADResult {
  std::vector<FeatureLabel> labels;
  std::vector<InstanceDepthStats> instances;
  int static_count = 0;
  int dynamic_by_mask_count = 0;
  int dynamic_by_mad_count = 0;

  int count(FeatureLabel label) const {
    switch (label) {
      case FeatureLabel::static_feature:
        return static_count;
      case FeatureLabel::dynamic_by_mask:
        return dynamic_by_mask_count;
      case FeatureLabel::dynamic_by_mad:
        return dynamic_by_mad_count;
    }
    return 0;
  }
  int dynamic_count() const { return dynamic_by_mask_count + dynamic_by_mad_count; }
};

namespace detail {

/// Largest h >= 0 with h^2 <= r^2 - dy^2, in integers (|dy| <= r): the half width of the pixel
/// disc of radius r on the row dy away from its centre.
inline std::int64_t disc_half_width(std::int64_t radius, std::int64_t dy) {
  const std::int64_t rest = radius * radius - dy * dy;
  auto h = static_cast<std::int64_t>(std::sqrt(static_cast<double>(rest)));
  while (h > 0 && h * h > rest) --h;
  while ((h + 1) * (h + 1) <= rest) ++h;
  return h;
}

/// True when every pixel (col + dx, row + dy) with dx^2 + dy^2 <= r^2 is set in the mask. Pixels
/// outside the image fail the test when border_is_edge, and are skipped otherwise.
template <typename Mask>
bool disc_inside_mask(const Mask& mask, int col, int row, int radius, int width, int height, bool border_is_edge) {
  using T = traits::Mask<Mask>;
  const std::int64_t r = radius;
  // The disc reaches exactly r pixels along each axis.
  if (border_is_edge && (col - r < 0 || row - r < 0 || col + r >= width || row + r >= height)) return false;
  const std::int64_t dy_begin = std::max<std::int64_t>(-r, -row);
  const std::int64_t dy_end = std::min<std::int64_t>(r, height - 1 - row);
  for (std::int64_t dy = dy_begin; dy <= dy_end; ++dy) {
    const std::int64_t h = disc_half_width(r, dy);
    const int c_begin = static_cast<int>(std::max<std::int64_t>(col - h, 0));
    const int c_end = static_cast<int>(std::min<std::int64_t>(col + h, width - 1));
    const int y = static_cast<int>(row + dy);
    for (int c = c_begin; c <= c_end; ++c) {
      if (!T::is_set(mask, c, y)) return false;
    }
  }
  return true;
}

}  // namespace detail

/// The dynamic-feature filter of docs/METHOD.md section 1. RandomEngine: any engine accepted by
/// cge::uniform_unit_double (outputs spanning 0 .. 2^b - 1), default std::mt19937_64.
template <typename RandomEngine = std::mt19937_64>
class DepthMADFilter {
 public:
  using Engine = RandomEngine;

  DepthMADSettings settings;
  /// The source of the box samples; seed it (engine.seed(s)) for reproducible runs.
  RandomEngine engine;

  DepthMADFilter() = default;
  explicit DepthMADFilter(const DepthMADSettings& s, RandomEngine e = RandomEngine())
      : settings(s), engine(std::move(e)) {}

  /// Labels every keypoint (step 1: mask test; step 3: depth test against each box it lies in) and
  /// estimates each instance's depth statistics (step 2).
  /// `keypoints`: any range of points adapted by cge::traits::Point2, pixel coordinates (OpenCV's).
  /// `depth`: adapted by cge::traits::DepthImage; its size is the image size. 0, NaN (any value
  ///   not finite and positive) = no measurement: such a keypoint skips the depth test, such a
  ///   sample is not valid. This is never an error.
  /// `instances`: the dynamic instances, each with a mask of the depth image's size and a box
  ///   inside the image.
  /// Throws std::invalid_argument, naming the item, for bad settings, an empty depth image, a
  /// null, empty or wrongly sized mask, a box that is not finite, has no area or reaches outside
  /// the image, and a keypoint that is not finite or lies outside [0, W] x [0, H].
  template <typename Keypoints, typename Depth, typename Mask>
  DepthMADResult filter(const Keypoints& keypoints, const Depth& depth,
                        const std::vector<DynamicInstance<Mask>>& instances) {
#if CGE_HAS_CONCEPTS
    static_assert(Point2Like<std::decay_t<decltype(*std::begin(keypoints))>>,
                  "keypoints must be a range of points adapted by cge::traits::Point2 (cge/core/point_traits.hpp)");
    static_assert(DepthImageLike<Depth>,
                  "depth must be adapted by cge::traits::DepthImage (cge/core/depth_image.hpp)");
    static_assert(MaskLike<Mask>, "masks must be adapted by cge::traits::Mask (cge/core/mask.hpp)");
#endif
    using DepthTraits = traits::DepthImage<Depth>;
    using MaskTraits = traits::Mask<Mask>;

    // Validate everything before the first draw.
    settings.validate();
    const int width = DepthTraits::width(depth);
    const int height = DepthTraits::height(depth);
    if (width <= 0 || height <= 0) {
      std::ostringstream msg;
      msg << "DepthMADFilter: the depth image is empty (" << width << " x " << height << " pixels)";
      throw std::invalid_argument(msg.str());
    }
    std::vector<PixelSpan> box_pixels;
    box_pixels.reserve(instances.size());
    for (std::size_t j = 0; j < instances.size(); ++j) {
      const DynamicInstance<Mask>& inst = instances[j];
      const std::string which = "DepthMADFilter: instance #" + std::to_string(j);
      if (inst.mask == nullptr) throw std::invalid_argument(which + " has no mask (null pointer)");
      if (MaskTraits::empty(*inst.mask)) throw std::invalid_argument(which + " has an empty mask");
      check_mask_size(*inst.mask, width, height, (which + ": the mask").c_str());
      inst.box_px.validate(width, height, (which + ": the box").c_str());
      box_pixels.push_back(inst.box_px.pixels());
    }
    std::vector<Pixel> keypoint_pixels;
    std::size_t index = 0;
    for (const auto& kp : keypoints) {
      const double x = static_cast<double>(point_x(kp));
      const double y = static_cast<double>(point_y(kp));
      if (!(x >= 0 && x <= width && y >= 0 && y <= height)) {  // also rejects NaN
        std::ostringstream msg;
        msg << "DepthMADFilter: keypoint #" << index << " at (" << x << ", " << y
            << ") is not finite or lies outside the image [0, " << width << "] x [0, " << height << "]";
        throw std::invalid_argument(msg.str());
      }
      keypoint_pixels.push_back(Pixel{nearest_pixel_index(x, width), nearest_pixel_index(y, height)});
      ++index;
    }

    DepthMADResult result;
    // Step 2: depth statistics per instance.
    result.instances.reserve(instances.size());
    std::vector<double> valid_depths;
    for (std::size_t j = 0; j < instances.size(); ++j) {
      result.instances.push_back(
          estimate(depth, *instances[j].mask, instances[j].box_px, box_pixels[j], width, height, valid_depths));
    }

    // Steps 1 and 3: label the keypoints.
    result.labels.reserve(keypoint_pixels.size());
    for (const Pixel& p : keypoint_pixels) {
      FeatureLabel label = FeatureLabel::static_feature;
      for (const DynamicInstance<Mask>& inst : instances) {
        if (MaskTraits::is_set(*inst.mask, p.col, p.row)) {
          label = FeatureLabel::dynamic_by_mask;
          break;
        }
      }
      if (label == FeatureLabel::static_feature) {
        const double d = static_cast<double>(DepthTraits::depth_m(depth, p.col, p.row));
        if (is_valid_depth_m(d)) {
          for (std::size_t j = 0; j < instances.size(); ++j) {
            const InstanceDepthStats& s = result.instances[j];
            if (s.mad_test_applied && box_pixels[j].contains(p.col, p.row) &&
                std::abs(d - s.mean_depth_m) < settings.mad_scale * s.mad_m) {
              label = FeatureLabel::dynamic_by_mad;
              break;
            }
          }
        }
      }
      result.labels.push_back(label);
      switch (label) {
        case FeatureLabel::static_feature:
          ++result.static_count;
          break;
        case FeatureLabel::dynamic_by_mask:
          ++result.dynamic_by_mask_count;
          break;
        case FeatureLabel::dynamic_by_mad:
          ++result.dynamic_by_mad_count;
          break;
      }
    }
    return result;
  }

 private:
  struct Pixel {
    int col, row;
  };

  /// Step 2 for one instance: draws the samples (box_samples) or visits the mask's pixels in the
  /// box row by row (mask_pixels), keeps the valid depths (in valid_depths, a reused buffer) and
  /// reduces them, summing in sample order.
  template <typename Depth, typename Mask>
  InstanceDepthStats estimate(const Depth& depth, const Mask& mask, const PixelBox& box, const PixelSpan& span,
                              int width, int height, std::vector<double>& valid_depths) {
    InstanceDepthStats s;
    valid_depths.clear();
    if (settings.depth_estimate == DepthEstimate::mask_pixels) {
      for (int row = span.row_begin; row < span.row_end; ++row) {
        for (int col = span.col_begin; col < span.col_end; ++col) {
          if (!traits::Mask<Mask>::is_set(mask, col, row)) continue;
          ++s.samples_drawn;
          const double d = static_cast<double>(traits::DepthImage<Depth>::depth_m(depth, col, row));
          if (is_valid_depth_m(d)) {
            valid_depths.push_back(d);
          } else {
            ++s.samples_invalid_depth;
          }
        }
      }
      reduce(valid_depths, s);
      if (s.mad_test_applied &&
          static_cast<double>(s.valid_samples) < settings.min_valid_mask_fraction * s.samples_drawn) {
        s.mad_test_applied = false;
        s.skip_reason = MadSkipReason::too_little_depth_in_mask;
      }
      return s;
    }
    s.samples_drawn = settings.samples_per_instance;
    const double centre_x = box.centre_x_px();
    const double centre_y = box.centre_y_px();
    for (int i = 0; i < settings.samples_per_instance; ++i) {
      // p_i = centre + U(-l/2, +l/2) per axis, U(-l/2, l/2) = (u - 1/2) l with u uniform in [0, 1).
      const double u_x = uniform_unit_double(engine);
      const double u_y = uniform_unit_double(engine);
      const double x = centre_x + (u_x - 0.5) * box.width_px;
      const double y = centre_y + (u_y - 0.5) * box.height_px;
      // The clamp only matters when rounding puts x on the box's far edge.
      const int col = std::clamp(static_cast<int>(std::floor(x)), span.col_begin, span.col_end - 1);
      const int row = std::clamp(static_cast<int>(std::floor(y)), span.row_begin, span.row_end - 1);
      if (!detail::disc_inside_mask(mask, col, row, settings.disc_radius_px, width, height,
                                    settings.image_border_is_mask_edge)) {
        ++s.samples_off_mask;
        continue;
      }
      const double d = static_cast<double>(traits::DepthImage<Depth>::depth_m(depth, col, row));
      if (!is_valid_depth_m(d)) {
        ++s.samples_invalid_depth;
        continue;
      }
      valid_depths.push_back(d);
    }
    reduce(valid_depths, s);
    return s;
  }

  /// valid_samples, the test's minimum and the mean and MAD of the valid depths, summed in order.
  void reduce(const std::vector<double>& valid_depths, InstanceDepthStats& s) const {
    s.valid_samples = static_cast<int>(valid_depths.size());
    s.mad_test_applied = s.valid_samples >= settings.min_valid_samples;
    if (!s.mad_test_applied) s.skip_reason = MadSkipReason::too_few_valid_samples;
    if (s.valid_samples > 0) {
      const double n_valid = static_cast<double>(s.valid_samples);
      double sum = 0;
      for (const double d : valid_depths) sum += d;
      s.mean_depth_m = sum / n_valid;
      double deviation_sum = 0;
      for (const double d : valid_depths) deviation_sum += std::abs(d - s.mean_depth_m);
      s.mad_m = deviation_sum / n_valid;
    }
  }
};

}  // namespace cge
