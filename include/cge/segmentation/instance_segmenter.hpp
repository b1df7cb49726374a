#pragma once
// The instance-segmenter interface of the segmentation front end, the instance type it returns, and
// helpers that combine a frame's instances into one dynamic mask or one instance-label image.
//
// Two implementations come with the toolkit: Yolov8Segmenter (a YOLOv8-seg ONNX model through
// OpenCV's DNN module, cge/segmentation/yolov8_segmenter.hpp) and PrecomputedMaskReader (per-frame
// instance-label PNGs computed elsewhere, cge/segmentation/precomputed_mask_reader.hpp). Both take
// the same FrameImage, so a pipeline switches between them without other changes.
//
// What downstream components read: the dynamic-feature filter takes the dynamic instances' masks
// and boxes (x_min, y_min, width, height in pixels); the graph builder takes the static instances'
// box centres (to_semantic_instance) and the union of the dynamic masks (union_dynamic_masks).

#include <optional>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/core/semantic_instance.hpp"
#include "cge/frontend/pixel_box.hpp"

namespace cge {

/// One frame as a segmenter sees it.
struct FrameImage {
  cv::Mat bgr;       ///< the colour image, CV_8UC3 in OpenCV's BGR order (what cv::imread returns)
  std::string stem;  ///< the frame's name: its RGB file name without extension (TUM: the timestamp)
};

/// One object instance found in a frame.
struct SegmentedInstance {
  int id = 0;                  ///< >= 1; YOLOv8: rank in the frame (1 = best score); mask folder: its label id
  int class_id = 0;            ///< COCO class id, 0 .. 79 (cge/segmentation/coco_classes.hpp)
  float score = 1;             ///< detection confidence in [0, 1]; 1 for precomputed masks
  cv::Rect2f box_px;           ///< x_min, y_min, width, height in pixels of the original image, inside it
  cv::Mat mask;                ///< CV_8UC1 of the image's size, 255 on the instance, 0 elsewhere; owned
  bool dynamic = false;        ///< class_id is in the segmenter's dynamic class set
  std::optional<bool> moving;  ///< whether the body moves in the world, when the source knows it
};

/// Common interface of the instance segmenters. Not thread-safe: use one segmenter per thread.
class InstanceSegmenter {
 public:
  virtual ~InstanceSegmenter() = default;

  /// The instances of the frame, in the order the implementation documents. Deterministic: the
  /// same frame gives the same instances. Throws std::invalid_argument for invalid input.
  virtual std::vector<SegmentedInstance> segment(const FrameImage& frame) = 0;

  /// The COCO classes whose instances are marked dynamic (default: {person}). Throws
  /// std::invalid_argument naming an id outside 0 .. 79.
  virtual void set_dynamic_classes(const std::set<int>& class_ids) = 0;
  virtual const std::set<int>& dynamic_classes() const = 0;

 protected:
  InstanceSegmenter() = default;
  InstanceSegmenter(const InstanceSegmenter&) = default;
  InstanceSegmenter(InstanceSegmenter&&) = default;
  InstanceSegmenter& operator=(const InstanceSegmenter&) = default;
  InstanceSegmenter& operator=(InstanceSegmenter&&) = default;
};

/// The file name of `path` without directory and last extension, e.g. "rgb/1341846313.592026.png"
/// -> "1341846313.592026": the FrameImage::stem of an RGB file.
std::string frame_stem(const std::string& path);

/// Throws std::invalid_argument unless every id is a COCO class id (0 .. 79); `where` names the caller.
void check_coco_class_ids(const std::set<int>& class_ids, const char* where);

/// The union of the masks of the dynamic instances: CV_8UC1 of image_size, 255 where any dynamic
/// instance covers the pixel, 0 elsewhere (all 0 without dynamic instances). Throws
/// std::invalid_argument when a dynamic instance's mask is not CV_8UC1 of image_size.
cv::Mat union_dynamic_masks(const std::vector<SegmentedInstance>& instances, cv::Size image_size);

/// An instance-label image (the mask-folder format): CV_16UC1 of image_size, 0 = background,
/// otherwise the SegmentedInstance::id of the instance covering the pixel; where masks overlap, the
/// instance earlier in the list wins (for YOLOv8 output: the higher score). Throws
/// std::invalid_argument when an id is outside 1 .. 65535 or used twice, or a mask has the wrong
/// type or size.
cv::Mat instance_label_image(const std::vector<SegmentedInstance>& instances, cv::Size image_size);

/// The instance's box as the dynamic-feature filter takes it. box_px is stored in float, so a box
/// clipped to the image may pass its far border by a rounding error, which PixelBox::validate
/// rejects: the far edges are clamped to image_size here (nothing else changes).
PixelBox filter_box(const SegmentedInstance& instance, cv::Size image_size);

/// The instance as the graph builder and the semantic pre-judgment see it: box centre, class and
/// whether the class is dynamic.
template <typename Scalar>
SemanticInstance<Scalar> to_semantic_instance(const SegmentedInstance& instance) {
  SemanticInstance<Scalar> s;
  s.centre_px.x() = static_cast<Scalar>(instance.box_px.x + instance.box_px.width / 2);
  s.centre_px.y() = static_cast<Scalar>(instance.box_px.y + instance.box_px.height / 2);
  s.class_id = instance.class_id;
  s.dynamic = instance.dynamic;
  return s;
}

}  // namespace cge
