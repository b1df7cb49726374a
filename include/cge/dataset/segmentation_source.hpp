#pragma once
// Where a run's instance masks come from (the segmentation sources of the ablation modes), and a
// factory that makes the matching InstanceSegmenter:
//   none          no instances (mode "none", or to time the pipeline without segmentation)
//   ground_truth  a synthetic sequence's own masks: segmentation/ (after the segmentation error
//                 model, what a network would output; the default) or masks/ (exact), read with
//                 PrecomputedMaskReader in strict mode (the simulator writes a PNG per frame)
//   yolo          a YOLOv8-seg ONNX model (Yolov8Segmenter)
//   precomputed   a mask folder computed elsewhere (PrecomputedMaskReader)
// A source named in SegmentationSourceSettings::temporal_filter_sources has its segmenter wrapped
// in a TemporalInstanceFilter (static objects that a network finds in one frame and misses in the
// next are passed on only once seen in N of the last M frames; people at once).

#include <filesystem>
#include <memory>
#include <set>
#include <string>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/segmentation/instance_segmenter.hpp"
#include "cge/segmentation/temporal_instance_filter.hpp"
#include "cge/segmentation/yolov8_segmenter.hpp"

namespace cge {
namespace dataset {

enum class SegmentationSource { none, ground_truth, yolo, precomputed };

/// Which of a synthetic sequence's mask folders the ground_truth source reads.
enum class GroundTruthMasks {
  after_error_model,  ///< segmentation/: the ground truth after the segmentation error model
  exact,              ///< masks/: the exact ground truth
};

/// "none", "ground_truth", "yolo", "precomputed".
const char* to_string(SegmentationSource source);
/// The inverse of to_string; throws std::invalid_argument listing the valid names.
SegmentationSource parse_segmentation_source(const std::string& name);
/// "segmentation" (after_error_model) or "masks" (exact): the folder name in a synthetic sequence.
const char* folder_name(GroundTruthMasks masks);

struct SegmentationSourceSettings {
  SegmentationSource source = SegmentationSource::none;
  /// ground_truth: which mask folder of the sequence.
  GroundTruthMasks ground_truth_masks = GroundTruthMasks::after_error_model;
  /// yolo: the ONNX file of a YOLOv8-seg COCO model.
  std::string yolo_model_path;
  /// yolo: thresholds and mask decoding (its dynamic_class_ids is replaced by dynamic_class_ids below).
  Yolov8Settings yolo;
  /// precomputed: the mask folder (docs/SEGMENTATION.md format).
  std::string mask_folder;
  /// precomputed: a frame without a PNG is an error instead of "no instances".
  bool require_every_frame = false;
  /// COCO classes whose instances are marked dynamic, for every source.
  std::set<int> dynamic_class_ids = {kCocoPerson};
  /// The sources whose segmenter is wrapped in a TemporalInstanceFilter with temporal_filter.
  /// Default {yolo}: on TUM fr1/rpy with yolov8n-seg-320 the filter cut the keyframes that the
  /// flicker of static objects added (docs/SEGMENTATION.md, "Flicker of static objects"). Not
  /// ground_truth: the synthetic error model's missed frames are what that source studies.
  std::set<SegmentationSource> temporal_filter_sources = {SegmentationSource::yolo};
  /// N of M and the association of the temporal filter.
  TemporalInstanceFilterSettings temporal_filter;

  /// Throws std::invalid_argument naming the bad field (the temporal filter's settings, when a
  /// source is filtered).
  void validate() const;
};

/// The segmenter of the `none` source: every frame has no instances.
class NoSegmenter final : public InstanceSegmenter {
 public:
  explicit NoSegmenter(std::set<int> dynamic_class_ids = {kCocoPerson});
  std::vector<SegmentedInstance> segment(const FrameImage& frame) override;
  void set_dynamic_classes(const std::set<int>& class_ids) override;
  const std::set<int>& dynamic_classes() const override { return dynamic_class_ids_; }

 private:
  std::set<int> dynamic_class_ids_;
};

/// The segmenter of the chosen source. dataset_folder is the sequence folder (used by
/// ground_truth only). Throws std::invalid_argument naming the source and the missing path when
/// the source's files are missing (ground_truth: <dataset_folder>/segmentation or masks with its
/// instances.csv; yolo: an empty or missing model path; precomputed: an empty or missing folder),
/// and passes on the errors of the segmenters' constructors (malformed instances.csv, a file that
/// is not a YOLOv8-seg model, a class id outside 0 .. 79) and of settings.validate(). A source in
/// settings.temporal_filter_sources comes wrapped in a TemporalInstanceFilter.
std::unique_ptr<InstanceSegmenter> make_segmenter(const SegmentationSourceSettings& settings,
                                                  const std::filesystem::path& dataset_folder);

}  // namespace dataset
}  // namespace cge
