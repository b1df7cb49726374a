#include "cge/sim/segmentation_error_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "cge/core/splitmix64.hpp"
#include "cge/opencv/disc_kernel.hpp"

namespace cge {
namespace sim {
namespace {

constexpr int kMaxLabel = std::numeric_limits<std::uint16_t>::max();

/// What a stream of random numbers decides; each decision has its own stream, so changing one
/// probability never changes another decision.
enum class Decision : std::uint64_t { miss = 1, feet = 2, false_positive = 3 };

/// Counter-based generator: the stream of (seed, frame, instance id, decision) is splitmix64
/// started from a hash of the four, so it is independent of everything else that is drawn.
class DrawStream {
 public:
  DrawStream(std::uint64_t seed, int frame_index, std::uint64_t instance_id, Decision decision)
      : stream_(start(seed, frame_index, instance_id, decision)) {}
  /// Uniform in [0, 1).
  double uniform() { return stream_.next_unit(); }
  /// Uniform in [lo, hi].
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

 private:
  static std::uint64_t start(std::uint64_t seed, int frame_index, std::uint64_t instance_id, Decision decision) {
    std::uint64_t h = splitmix64(seed);
    h = splitmix64_mix(h ^ (static_cast<std::uint64_t>(frame_index) + kSplitMix64Increment));
    h = splitmix64_mix(h ^ (instance_id + kSplitMix64Increment));
    return splitmix64_mix(h ^ (static_cast<std::uint64_t>(decision) + kSplitMix64Increment));
  }
  SplitMix64 stream_;
};

/// Instance bounding box, inclusive pixel bounds.
struct Box {
  int min_x = std::numeric_limits<int>::max();
  int min_y = std::numeric_limits<int>::max();
  int max_x = -1;
  int max_y = -1;
  bool empty() const { return max_x < 0; }
  cv::Rect grown(int margin, const cv::Size& image) const {
    const int x0 = std::max(0, min_x - margin);
    const int y0 = std::max(0, min_y - margin);
    const int x1 = std::min(image.width - 1, max_x + margin);
    const int y1 = std::min(image.height - 1, max_y + margin);
    return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
  }
};

/// The Euclidean disc of radius r as a structuring element: offsets with dx^2 + dy^2 <= r^2.
void require_probability(const char* name, double p) {
  if (!(p >= 0.0 && p <= 1.0)) {
    throw std::invalid_argument(std::string("SegmentationErrorSettings::") + name + " must be in [0, 1], got " +
                                std::to_string(p));
  }
}

void require_class(const char* name, int class_id) {
  if (class_id < 0 || class_id >= kCocoClassCount) {
    throw std::invalid_argument(std::string(name) + ": class id " + std::to_string(class_id) +
                                " is not a COCO class id (0 .. 79)");
  }
}

/// Moves the boundary of instance `id` (bounding box `box` in the ground truth) by offset_px.
void offset_boundary(const cv::Mat& truth, cv::Mat& out, std::uint16_t id, const Box& box, int offset_px) {
  const int radius = std::abs(offset_px);
  const cv::Rect roi = box.grown(radius, truth.size());
  const cv::Mat truth_roi = truth(roi);
  cv::Mat out_roi = out(roi);
  cv::Mat inside;
  cv::compare(truth_roi, cv::Scalar(id), inside, cv::CMP_EQ);  // 255 on the instance
  const cv::Mat kernel = opencv::disc_kernel(radius);
  cv::Mat moved;
  if (offset_px > 0) {
    // Outside the image is not the instance: nothing grows in from the border.
    cv::dilate(inside, moved, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    for (int y = 0; y < roi.height; ++y) {
      const std::uint8_t* m = moved.ptr<std::uint8_t>(y);
      const std::uint16_t* t = truth_roi.ptr<std::uint16_t>(y);
      std::uint16_t* o = out_roi.ptr<std::uint16_t>(y);
      for (int x = 0; x < roi.width; ++x) {
        if (m[x] != 0 && t[x] == 0 && o[x] == 0) o[x] = id;
      }
    }
  } else {
    // Outside the image counts as the instance: the image border is not an edge the network sees.
    cv::erode(inside, moved, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(255));
    for (int y = 0; y < roi.height; ++y) {
      const std::uint8_t* m = moved.ptr<std::uint8_t>(y);
      const std::uint16_t* t = truth_roi.ptr<std::uint16_t>(y);
      std::uint16_t* o = out_roi.ptr<std::uint16_t>(y);
      for (int x = 0; x < roi.width; ++x) {
        if (m[x] == 0 && t[x] == id) o[x] = 0;
      }
    }
  }
}

/// Removes the bottom `fraction` of the rows of instance `id` inside `roi`; false when the
/// instance has no pixel left there.
bool cut_feet(cv::Mat& out, std::uint16_t id, const cv::Rect& roi, double fraction) {
  int top = -1;
  int bottom = -1;
  for (int y = roi.y; y < roi.y + roi.height; ++y) {
    const std::uint16_t* o = out.ptr<std::uint16_t>(y) + roi.x;
    if (std::find(o, o + roi.width, id) != o + roi.width) {
      if (top < 0) top = y;
      bottom = y;
    }
  }
  if (top < 0) return false;
  const int height = bottom - top + 1;
  const int cut_rows = static_cast<int>(std::lround(fraction * height));
  for (int y = bottom - cut_rows + 1; y <= bottom; ++y) {
    std::uint16_t* o = out.ptr<std::uint16_t>(y) + roi.x;
    std::replace(o, o + roi.width, id, std::uint16_t{0});
  }
  return true;
}

/// Draws the false positive of one frame over the background of `out`; the number of its pixels.
int draw_false_positive(cv::Mat& out, std::uint16_t id, DrawStream& draws, const SegmentationErrorSettings& s) {
  const double width = out.cols;
  const double height = out.rows;
  const double axis_y =
      height * draws.uniform(s.false_positive_min_height_fraction, s.false_positive_max_height_fraction);
  const double axis_x =
      std::min(width, axis_y * draws.uniform(s.false_positive_min_aspect, s.false_positive_max_aspect));
  const double a = axis_x / 2;  // semi-axes, pixels
  const double b = axis_y / 2;
  // Centre at a pixel-centre coordinate such that the ellipse stays inside [0, W-1] x [0, H-1].
  const double cx = draws.uniform(std::min(a, (width - 1) / 2), std::max(width - 1 - a, (width - 1) / 2));
  const double cy = draws.uniform(std::min(b, (height - 1) / 2), std::max(height - 1 - b, (height - 1) / 2));
  const int y0 = std::max(0, static_cast<int>(std::ceil(cy - b)));
  const int y1 = std::min(out.rows - 1, static_cast<int>(std::floor(cy + b)));
  const int x0 = std::max(0, static_cast<int>(std::ceil(cx - a)));
  const int x1 = std::min(out.cols - 1, static_cast<int>(std::floor(cx + a)));
  int drawn = 0;
  for (int y = y0; y <= y1; ++y) {
    std::uint16_t* o = out.ptr<std::uint16_t>(y);
    const double ny = (y - cy) / b;
    for (int x = x0; x <= x1; ++x) {
      const double nx = (x - cx) / a;
      if (nx * nx + ny * ny <= 1.0 && o[x] == 0) {
        o[x] = id;
        ++drawn;
      }
    }
  }
  return drawn;
}

}  // namespace

void validate(const SegmentationErrorSettings& s) {
  if (s.boundary_offset_px < -kMaxBoundaryOffsetPx || s.boundary_offset_px > kMaxBoundaryOffsetPx) {
    throw std::invalid_argument("SegmentationErrorSettings: boundary_offset_px must lie in -" +
                                std::to_string(kMaxBoundaryOffsetPx) + " .. " + std::to_string(kMaxBoundaryOffsetPx) +
                                " pixels, got " + std::to_string(s.boundary_offset_px));
  }
  require_probability("feet_loss_probability", s.feet_loss_probability);
  require_probability("feet_loss_fraction", s.feet_loss_fraction);
  require_probability("miss_probability", s.miss_probability);
  require_probability("false_positive_probability", s.false_positive_probability);
  require_class("SegmentationErrorSettings::false_positive_class_id", s.false_positive_class_id);
  for (const int c : s.affected_class_ids) require_class("SegmentationErrorSettings::affected_class_ids", c);
  if (!(s.false_positive_min_height_fraction > 0 &&
        s.false_positive_min_height_fraction <= s.false_positive_max_height_fraction &&
        s.false_positive_max_height_fraction <= 1)) {
    throw std::invalid_argument(
        "SegmentationErrorSettings: false-positive height fractions need 0 < min <= max <= 1, got min " +
        std::to_string(s.false_positive_min_height_fraction) + ", max " +
        std::to_string(s.false_positive_max_height_fraction));
  }
  if (!(s.false_positive_min_aspect > 0 && s.false_positive_min_aspect <= s.false_positive_max_aspect &&
        std::isfinite(s.false_positive_max_aspect))) {
    throw std::invalid_argument(
        "SegmentationErrorSettings: false-positive aspect ratios need 0 < min <= max, got min " +
        std::to_string(s.false_positive_min_aspect) + ", max " + std::to_string(s.false_positive_max_aspect));
  }
}

SegmentationErrorSettings exact_segmentation() {
  SegmentationErrorSettings s;
  s.boundary_offset_px = 0;
  s.feet_loss_probability = 0;
  s.miss_probability = 0;
  s.false_positive_probability = 0;
  return s;
}

SegmentationErrorModel::SegmentationErrorModel(std::vector<InstanceInfo> scene_instances, std::uint64_t seed,
                                               SegmentationErrorSettings model_settings)
    : settings(std::move(model_settings)), scene_instances_(std::move(scene_instances)), seed_(seed) {
  std::sort(scene_instances_.begin(), scene_instances_.end(),
            [](const InstanceInfo& l, const InstanceInfo& r) { return l.id < r.id; });
  for (std::size_t i = 0; i < scene_instances_.size(); ++i) {
    const InstanceInfo& inst = scene_instances_[i];
    if (inst.id == 0) throw std::invalid_argument("SegmentationErrorModel: instance id 0 is the background");
    if (i > 0 && scene_instances_[i - 1].id == inst.id) {
      throw std::invalid_argument("SegmentationErrorModel: instance id " + std::to_string(inst.id) +
                                  " appears twice in the instance table");
    }
    require_class(("SegmentationErrorModel: instance " + std::to_string(inst.id)).c_str(), inst.class_id);
  }
  const int largest = scene_instances_.empty() ? 0 : scene_instances_.back().id;
  // With id 65535 in the scene there is no room left; false_positive_id() then throws.
  first_false_positive_id_ = static_cast<std::uint16_t>(std::min(largest + 1, kMaxLabel));
}

std::uint16_t SegmentationErrorModel::false_positive_id(int frame_index) const {
  const long long id = static_cast<long long>(first_false_positive_id_) + frame_index;
  const int largest_scene_id = scene_instances_.empty() ? 0 : scene_instances_.back().id;
  if (frame_index < 0 || id > kMaxLabel || largest_scene_id == kMaxLabel) {
    throw std::invalid_argument("SegmentationErrorModel: frame " + std::to_string(frame_index) +
                                " has no false-positive id: ids after the largest scene id " +
                                std::to_string(largest_scene_id) + " run out at 65535");
  }
  return static_cast<std::uint16_t>(id);
}

SegmentationResult SegmentationErrorModel::apply(const cv::Mat& ground_truth, int frame_index) const {
  validate(settings);
  if (frame_index < 0) {
    throw std::invalid_argument("SegmentationErrorModel::apply: frame index " + std::to_string(frame_index) +
                                " is negative");
  }
  if (ground_truth.empty() || ground_truth.type() != CV_16UC1) {
    throw std::invalid_argument("SegmentationErrorModel::apply: frame " + std::to_string(frame_index) +
                                ": the instance labels must be a non-empty CV_16UC1 image");
  }

  // Bounding box of every id present; ids outside the table are an error.
  const int largest_id = scene_instances_.empty() ? 0 : scene_instances_.back().id;
  std::vector<int> row_of_id(static_cast<std::size_t>(largest_id) + 1, -1);
  for (std::size_t i = 0; i < scene_instances_.size(); ++i) row_of_id[scene_instances_[i].id] = static_cast<int>(i);
  std::vector<Box> boxes(scene_instances_.size());
  for (int y = 0; y < ground_truth.rows; ++y) {
    const std::uint16_t* t = ground_truth.ptr<std::uint16_t>(y);
    for (int x = 0; x < ground_truth.cols; ++x) {
      const std::uint16_t id = t[x];
      if (id == 0) continue;
      if (id > largest_id || row_of_id[id] < 0) {
        throw std::invalid_argument("SegmentationErrorModel::apply: frame " + std::to_string(frame_index) + ": label " +
                                    std::to_string(id) + " at pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                    ") is not in the instance table");
      }
      Box& b = boxes[static_cast<std::size_t>(row_of_id[id])];
      b.min_x = std::min(b.min_x, x);
      b.max_x = std::max(b.max_x, x);
      b.min_y = std::min(b.min_y, y);
      b.max_y = std::max(b.max_y, y);
    }
  }

  SegmentationResult result;
  result.instance_labels = ground_truth.clone();
  result.instances = scene_instances_;
  cv::Mat& out = result.instance_labels;

  for (std::size_t i = 0; i < scene_instances_.size(); ++i) {
    const InstanceInfo& inst = scene_instances_[i];
    const Box& box = boxes[i];
    if (box.empty()) continue;
    const bool affected =
        settings.affect_all_classes || std::find(settings.affected_class_ids.begin(), settings.affected_class_ids.end(),
                                                 inst.class_id) != settings.affected_class_ids.end();
    if (!affected) continue;

    DrawStream miss_draw(seed_, frame_index, inst.id, Decision::miss);
    if (miss_draw.uniform() < settings.miss_probability) {
      cv::Mat roi = out(box.grown(0, out.size()));
      roi.setTo(cv::Scalar(0), roi == inst.id);
      result.events.missed_ids.push_back(inst.id);
      continue;
    }
    if (settings.boundary_offset_px != 0) offset_boundary(ground_truth, out, inst.id, box, settings.boundary_offset_px);
    DrawStream feet_draw(seed_, frame_index, inst.id, Decision::feet);
    if (feet_draw.uniform() < settings.feet_loss_probability &&
        cut_feet(out, inst.id, box.grown(std::max(0, settings.boundary_offset_px), out.size()),
                 settings.feet_loss_fraction)) {
      result.events.feet_cut_ids.push_back(inst.id);
    }
  }

  DrawStream fp_draw(seed_, frame_index, 0, Decision::false_positive);
  if (fp_draw.uniform() < settings.false_positive_probability) {
    InstanceInfo fp;
    fp.id = false_positive_id(frame_index);
    fp.class_id = settings.false_positive_class_id;
    fp.moving = false;  // nothing is there, so nothing moves
    if (draw_false_positive(out, fp.id, fp_draw, settings) > 0) {
      result.events.false_positive = fp;
      result.instances.push_back(fp);
    }
  }
  return result;
}

}  // namespace sim
}  // namespace cge
