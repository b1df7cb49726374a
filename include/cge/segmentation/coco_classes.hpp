#pragma once
// The 80 COCO object classes in the order YOLOv8 (and most COCO-trained detectors) number them.
// Shared by the segmenters, the synthetic sequences (whose objects carry COCO classes so that real
// and synthetic data look alike to the pipeline) and the semantic maps.

#include <optional>
#include <string_view>

namespace cge {

/// Number of COCO classes (ids 0 .. 79).
inline constexpr int kCocoClassCount = 80;

/// COCO id of the class "person", the default dynamic class of the method.
inline constexpr int kCocoPerson = 0;

/// Name of a COCO class id, e.g. 0 -> "person", 62 -> "tv"; throws std::out_of_range naming the id
/// when it is not in 0 .. 79.
std::string_view coco_class_name(int class_id);

/// Id of a COCO class name (exact, lower case, as coco_class_name spells it), or nullopt.
std::optional<int> coco_class_id(std::string_view name);

}  // namespace cge
