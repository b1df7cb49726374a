#include "cge/dataset/segmentation_source.hpp"

#include <array>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "cge/segmentation/precomputed_mask_reader.hpp"

namespace cge {
namespace dataset {
namespace fs = std::filesystem;
namespace {

constexpr std::array<SegmentationSource, 4> kSources = {SegmentationSource::none, SegmentationSource::ground_truth,
                                                        SegmentationSource::yolo, SegmentationSource::precomputed};
constexpr const char* kInstancesFile = "instances.csv";

std::string in_quotes(const fs::path& p) { return "'" + p.string() + "'"; }

std::unique_ptr<InstanceSegmenter> mask_folder_reader(const fs::path& folder, const char* source, bool strict,
                                                      const std::set<int>& dynamic_class_ids) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw std::invalid_argument(std::string("segmentation source ") + source + ": the mask folder " +
                                in_quotes(folder) + " does not exist");
  }
  if (!fs::is_regular_file(folder / kInstancesFile, ec)) {
    throw std::invalid_argument(std::string("segmentation source ") + source + ": the mask folder " +
                                in_quotes(folder) + " has no " + kInstancesFile);
  }
  PrecomputedMaskSettings s;
  s.dynamic_class_ids = dynamic_class_ids;
  s.require_every_frame = strict;
  return std::make_unique<PrecomputedMaskReader>(folder.string(), s);
}

}  // namespace

const char* to_string(SegmentationSource source) {
  switch (source) {
    case SegmentationSource::none:
      return "none";
    case SegmentationSource::ground_truth:
      return "ground_truth";
    case SegmentationSource::yolo:
      return "yolo";
    case SegmentationSource::precomputed:
      return "precomputed";
  }
  return "unknown";
}

SegmentationSource parse_segmentation_source(const std::string& name) {
  std::string valid;
  for (const SegmentationSource s : kSources) {
    if (name == to_string(s)) return s;
    valid += std::string(valid.empty() ? "" : ", ") + to_string(s);
  }
  throw std::invalid_argument("unknown segmentation source '" + name + "' (valid: " + valid + ")");
}

const char* folder_name(GroundTruthMasks masks) { return masks == GroundTruthMasks::exact ? "masks" : "segmentation"; }

NoSegmenter::NoSegmenter(std::set<int> dynamic_class_ids) : dynamic_class_ids_(std::move(dynamic_class_ids)) {
  check_coco_class_ids(dynamic_class_ids_, "NoSegmenter");
}

std::vector<SegmentedInstance> NoSegmenter::segment(const FrameImage&) { return {}; }

void NoSegmenter::set_dynamic_classes(const std::set<int>& class_ids) {
  check_coco_class_ids(class_ids, "NoSegmenter");
  dynamic_class_ids_ = class_ids;
}

void SegmentationSourceSettings::validate() const {
  if (temporal_filter_sources.empty()) return;
  try {
    temporal_filter.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("SegmentationSourceSettings: temporal_filter: ") + e.what());
  }
}

namespace {

std::unique_ptr<InstanceSegmenter> make_unfiltered_segmenter(const SegmentationSourceSettings& settings,
                                                             const fs::path& dataset_folder) {
  switch (settings.source) {
    case SegmentationSource::none:
      return std::make_unique<NoSegmenter>(settings.dynamic_class_ids);
    case SegmentationSource::ground_truth: {
      const fs::path folder = dataset_folder / folder_name(settings.ground_truth_masks);
      std::error_code ec;
      if (!fs::is_directory(folder, ec)) {
        throw std::invalid_argument("segmentation source ground_truth: " + in_quotes(folder) +
                                    " does not exist; only synthetic sequences (cge_sim) have ground-truth masks; "
                                    "use yolo or precomputed for other sequences");
      }
      return mask_folder_reader(folder, "ground_truth", true, settings.dynamic_class_ids);
    }
    case SegmentationSource::yolo: {
      if (settings.yolo_model_path.empty()) {
        throw std::invalid_argument("segmentation source yolo: no model file given (a YOLOv8-seg ONNX file)");
      }
      std::error_code ec;
      if (!fs::is_regular_file(settings.yolo_model_path, ec)) {
        throw std::invalid_argument("segmentation source yolo: the model file " + in_quotes(settings.yolo_model_path) +
                                    " does not exist");
      }
      Yolov8Settings yolo = settings.yolo;
      yolo.dynamic_class_ids = settings.dynamic_class_ids;
      return std::make_unique<Yolov8Segmenter>(settings.yolo_model_path, yolo);
    }
    case SegmentationSource::precomputed:
      if (settings.mask_folder.empty()) {
        throw std::invalid_argument("segmentation source precomputed: no mask folder given");
      }
      return mask_folder_reader(settings.mask_folder, "precomputed", settings.require_every_frame,
                                settings.dynamic_class_ids);
  }
  throw std::invalid_argument("make_segmenter: invalid segmentation source");
}

}  // namespace

std::unique_ptr<InstanceSegmenter> make_segmenter(const SegmentationSourceSettings& settings,
                                                  const fs::path& dataset_folder) {
  settings.validate();
  std::unique_ptr<InstanceSegmenter> segmenter = make_unfiltered_segmenter(settings, dataset_folder);
  if (settings.temporal_filter_sources.count(settings.source) == 0) return segmenter;
  return std::make_unique<TemporalInstanceFilter>(std::move(segmenter), settings.temporal_filter);
}

}  // namespace dataset
}  // namespace cge
