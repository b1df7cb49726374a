#pragma once
// SegmentationErrorModel: turns a ground-truth instance-label image into what an instance
// segmentation network might output for it, with the errors such networks make, each with its
// own setting: boundaries shifted by some pixels (mostly eroded: networks miss the thin edge that
// the depth MAD test is meant to catch), the feet cut off, whole instances missed in a frame, and
// false positives (a blob where there is no object, with its own class and id).
//
// What happens to one frame (docs/SIMULATION.md has the exact rules):
// 1. Every instance of an affected class (settings.affected_class_ids, or all classes) present in
//    the image, in ascending id order:
//    a. missed with probability miss_probability: all its pixels become background;
//    b. otherwise its mask is dilated (boundary_offset_px > 0) or eroded (< 0) by a Euclidean
//       disc: dilation adds the background pixels within boundary_offset_px of the mask (it never
//       takes pixels of another instance; where two dilations reach the same pixel the lower id
//       wins); erosion removes the pixels with a pixel of another label within |boundary_offset_px|
//       (the image border does not erode: the network sees no edge there);
//    c. then, with probability feet_loss_probability, the bottom rows of the mask are removed:
//       round(feet_loss_fraction * h) rows, h the height of the mask's bounding box after (b).
// 2. With probability false_positive_probability, one false positive: a filled axis-aligned
//    ellipse of random size and place inside the image, drawn over background pixels only, with
//    class false_positive_class_id and id false_positive_id(frame_index).
//
// Determinism: every random decision is a pure function of (seed, frame index, instance id, what
// is decided), through a counter-based generator of our own (no std distributions, whose output
// differs between standard libraries). Frames can be processed in any order, any number of times,
// with the same result on every platform; one instance's decisions do not depend on which other
// instances are in the frame. apply() is const and re-entrant.
//
// False-positive ids: first_false_positive_id() = (largest scene instance id) + 1, and frame i's
// false positive has id first_false_positive_id() + i, so ids never collide with the scene's,
// never with each other, and do not depend on the order frames are processed in. A sequence may
// thus have at most 65535 - first_false_positive_id() + 1 frames with false positives enabled.

#include <cstdint>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/sequence.hpp"

namespace cge {
namespace sim {

/// Largest |SegmentationErrorSettings::boundary_offset_px|, pixels. The disc kernel holds
/// (2r + 1)^2 cells and the morphology's cost grows with r^2 per pixel, so a stray large value
/// would allocate gigabytes or run for hours; a network's boundary errors are a few pixels, and 100
/// is an eighth of a 640 x 480 image's diagonal.
constexpr int kMaxBoundaryOffsetPx = 100;

struct SegmentationErrorSettings {
  /// Pixels the boundary of each affected mask moves: > 0 dilates, < 0 erodes, 0 keeps it; at most
  /// kMaxBoundaryOffsetPx either way. Default -2: a network that misses the outermost pixels of a person.
  int boundary_offset_px = -2;
  /// Probability (per affected instance and frame) that the feet are lost, in [0, 1].
  double feet_loss_probability = 0.2;
  /// Fraction of the mask's height (bounding box, bottom rows) removed when the feet are lost, [0, 1].
  double feet_loss_fraction = 0.15;
  /// Probability (per affected instance and frame) that the instance is missed entirely, [0, 1].
  double miss_probability = 0.03;
  /// Probability per frame of one false positive, [0, 1].
  double false_positive_probability = 0.02;
  /// COCO class of false positives (default person: a false "person" hides static features).
  int false_positive_class_id = kCocoPerson;
  /// Height of a false-positive ellipse (full axis) as a fraction of the image height, drawn
  /// uniformly from [min, max]; 0 < min <= max <= 1.
  double false_positive_min_height_fraction = 0.15;
  double false_positive_max_height_fraction = 0.5;
  /// Width / height of a false-positive ellipse, drawn uniformly from [min, max]; 0 < min <= max.
  /// The default is about the shape of a standing person.
  double false_positive_min_aspect = 0.3;
  double false_positive_max_aspect = 0.6;
  /// COCO classes whose instances receive the errors (1); others are copied unchanged.
  std::vector<int> affected_class_ids = {kCocoPerson};
  /// When true, every class is affected and affected_class_ids is ignored.
  bool affect_all_classes = false;
};

/// What the model did to one frame (for diagnostics and tests; the image is the output).
struct SegmentationEvents {
  std::vector<std::uint16_t> missed_ids;    ///< instances removed entirely, ascending
  std::vector<std::uint16_t> feet_cut_ids;  ///< instances whose bottom rows were removed, ascending
  /// The false positive when one was drawn and at least one of its pixels was background.
  std::optional<InstanceInfo> false_positive;
};

/// One frame as the simulated network sees it.
struct SegmentationResult {
  cv::Mat instance_labels;              ///< CV_16UC1, 0 = background
  std::vector<InstanceInfo> instances;  ///< the scene table plus this frame's false positive, ascending id
  SegmentationEvents events;
};

class SegmentationErrorModel {
 public:
  SegmentationErrorSettings settings;

  /// scene_instances: the sequence's instance table (ids 1 .. 65535, unique, COCO classes).
  /// Throws std::invalid_argument naming the bad entry.
  SegmentationErrorModel(std::vector<InstanceInfo> scene_instances, std::uint64_t seed,
                         SegmentationErrorSettings settings = {});

  /// The erroneous labels of frame frame_index (>= 0) whose exact labels are ground_truth
  /// (CV_16UC1, every id in the scene table). Throws std::invalid_argument naming the problem
  /// (wrong type, unknown id, bad settings, a false-positive id past 65535).
  SegmentationResult apply(const cv::Mat& ground_truth, int frame_index) const;

  /// Id of frame frame_index's false positive (whether or not the frame has one).
  std::uint16_t false_positive_id(int frame_index) const;
  std::uint16_t first_false_positive_id() const { return first_false_positive_id_; }
  const std::vector<InstanceInfo>& scene_instances() const { return scene_instances_; }
  std::uint64_t seed() const { return seed_; }

 private:
  std::vector<InstanceInfo> scene_instances_;  // ascending id
  std::uint64_t seed_;
  std::uint16_t first_false_positive_id_;
};

/// Throws std::invalid_argument naming the first setting outside its range.
void validate(const SegmentationErrorSettings& settings);

/// Settings under which the model copies the ground truth unchanged.
SegmentationErrorSettings exact_segmentation();

}  // namespace sim
}  // namespace cge
