#include "cge/segmentation/coco_classes.hpp"

#include <array>
#include <stdexcept>
#include <string>

namespace cge {
namespace {

// Index = class id, as in the COCO 2017 detection task with its 80 used categories.
constexpr std::array<std::string_view, kCocoClassCount> kNames = {
    "person",        "bicycle",      "car",           "motorcycle",    "airplane",     "bus",
    "train",         "truck",        "boat",          "traffic light", "fire hydrant", "stop sign",
    "parking meter", "bench",        "bird",          "cat",           "dog",          "horse",
    "sheep",         "cow",          "elephant",      "bear",          "zebra",        "giraffe",
    "backpack",      "umbrella",     "handbag",       "tie",           "suitcase",     "frisbee",
    "skis",          "snowboard",    "sports ball",   "kite",          "baseball bat", "baseball glove",
    "skateboard",    "surfboard",    "tennis racket", "bottle",        "wine glass",   "cup",
    "fork",          "knife",        "spoon",         "bowl",          "banana",       "apple",
    "sandwich",      "orange",       "broccoli",      "carrot",        "hot dog",      "pizza",
    "donut",         "cake",         "chair",         "couch",         "potted plant", "bed",
    "dining table",  "toilet",       "tv",            "laptop",        "mouse",        "remote",
    "keyboard",      "cell phone",   "microwave",     "oven",          "toaster",      "sink",
    "refrigerator",  "book",         "clock",         "vase",          "scissors",     "teddy bear",
    "hair drier",    "toothbrush"};

}  // namespace

std::string_view coco_class_name(int class_id) {
  if (class_id < 0 || class_id >= kCocoClassCount) {
    throw std::out_of_range("coco_class_name: class id " + std::to_string(class_id) + " is not in 0 .. 79");
  }
  return kNames[static_cast<std::size_t>(class_id)];
}

std::optional<int> coco_class_id(std::string_view name) {
  for (int id = 0; id < kCocoClassCount; ++id) {
    if (kNames[static_cast<std::size_t>(id)] == name) return id;
  }
  return std::nullopt;
}

}  // namespace cge
