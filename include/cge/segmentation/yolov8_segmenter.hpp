#pragma once
// Yolov8Segmenter: instance segmentation with a YOLOv8-seg ONNX model (80 COCO classes) run by
// OpenCV's DNN module, and the pieces it is made of (letterbox, output decoding), public so that
// the output of the same model run by another runtime can be decoded identically.
//
// Steps (docs/SEGMENTATION.md has the details): letterbox the BGR image into the model's fixed
// input (aspect kept, grey padding, RGB, / 255); one forward pass; decode the 1 x 116 x A
// predictions (cx, cy, w, h in input pixels, 80 class scores already passed through a sigmoid, 32
// mask coefficients per anchor); keep the best class of each anchor if its score reaches the
// confidence threshold; class-aware greedy non-maximum suppression; per kept detection, a mask
// from the coefficients and the 1 x 32 x H/4 x W/4 prototypes in one of two orders
// (Yolov8MaskDecoding): sigmoid on the prototype grid, cropped to the box there, sampled
// bilinearly at every original pixel inside the box and thresholded; or ("retina") the
// coefficients' combination sampled bilinearly at every original pixel inside the box, then the
// sigmoid and the threshold, so that the box crops at image resolution.
//
// Determinism: no randomness; ties in score are broken by anchor index, so the same image gives
// the same instances. OpenCV may use its own worker threads inside the forward pass; the results
// do not depend on them.

#include <memory>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/segmentation/instance_segmenter.hpp"

namespace cge {

/// Output layout of a YOLOv8-seg model for COCO.
inline constexpr int kYolov8BoxValues = 4;          ///< cx, cy, w, h per anchor
inline constexpr int kYolov8MaskCoefficients = 32;  ///< mask coefficients per anchor = prototypes
inline constexpr int kYolov8PrototypeStride = 4;    ///< input pixels per prototype cell
inline constexpr int kYolov8MaxStride = 32;         ///< input sides must be multiples of this
inline constexpr int kYolov8PredictionRows = kYolov8BoxValues + kCocoClassCount + kYolov8MaskCoefficients;

/// The order in which a detection's mask is decoded (docs/SEGMENTATION.md, "Masks").
enum class Yolov8MaskDecoding {
  /// sigmoid on the prototype grid, zero on the cells whose centre is outside the box (the crop),
  /// bilinear sample at each original pixel inside the box, threshold: Ultralytics' default
  /// (process_mask), whose crop at a quarter of the input resolution rounds off the box's corners.
  prototype_crop,
  /// bilinear sample of the coefficients' combination of the prototypes (equivalently: the
  /// prototypes upsampled to the image before the product) at each original pixel inside the box,
  /// sigmoid, threshold: Ultralytics' retina_masks (process_mask_native); the crop to the box is in
  /// image pixels.
  retina,
};

/// "prototype_crop" or "retina".
const char* to_string(Yolov8MaskDecoding decoding);

struct Yolov8Settings {
  /// Minimum class score (already a probability) for a detection to be kept, in (0, 1].
  float confidence_threshold = 0.25f;
  /// A box whose IoU with a kept, better box of the same class exceeds this is dropped, in [0, 1].
  float nms_iou_threshold = 0.7f;
  /// Mask probability above which a pixel belongs to the instance, in (0, 1).
  float mask_threshold = 0.5f;
  /// Order of the mask decoding (sigmoid and crop before or after the resampling to the image).
  Yolov8MaskDecoding mask_decoding = Yolov8MaskDecoding::prototype_crop;
  /// At most this many instances per frame (the best scores), >= 1.
  int max_detections = 300;
  /// Grey level of the letterbox padding (the value YOLOv8 was trained with), 0 .. 255.
  int pad_value = 114;
  /// COCO classes whose instances are marked dynamic.
  std::set<int> dynamic_class_ids = {kCocoPerson};
};

/// Throws std::invalid_argument naming the first setting outside its range.
void check_settings(const Yolov8Settings& settings);

/// How an image sits in the network input: scaled by scaled_size / image_size (aspect kept, sides
/// rounded to whole pixels) and centred, with pad_left_px / pad_top_px padding before it (the odd
/// pixel of an odd padding goes after it). input = original * scale + pad, in continuous
/// coordinates where pixel i covers [i, i + 1).
struct Letterbox {
  cv::Size image_size;   ///< the original image, pixels
  cv::Size input_size;   ///< the network input, pixels
  cv::Size scaled_size;  ///< the image scaled into the input, before padding, pixels
  int pad_left_px = 0;
  int pad_top_px = 0;

  double scale_x() const { return static_cast<double>(scaled_size.width) / image_size.width; }
  double scale_y() const { return static_cast<double>(scaled_size.height) / image_size.height; }
};

/// The letterbox of an image into an input; throws std::invalid_argument for empty sizes.
Letterbox make_letterbox(cv::Size image_size, cv::Size input_size);

/// The letterboxed image (same type as `image`, input_size): bilinear resize, constant padding.
cv::Mat letterbox_image(const cv::Mat& image, const Letterbox& letterbox, int pad_value);

/// Turns the two outputs of one forward pass into instances of the original image: predictions
/// 1 x 116 x A and prototypes 1 x 32 x (H/4) x (W/4) for a W x H input, both CV_32F (A may be any
/// count, e.g. a hand-made test case). Instances come by score, best first (ties: lower anchor
/// index first), with ids 1, 2, ...; a detection whose box lies wholly in the padding is dropped.
/// Throws std::invalid_argument naming the shapes when they do not fit the letterbox.
std::vector<SegmentedInstance> decode_yolov8_seg(const cv::Mat& predictions, const cv::Mat& prototypes,
                                                 const Letterbox& letterbox, const Yolov8Settings& settings);

/// YOLOv8-seg through OpenCV's DNN module. Not copyable (it owns the network); movable (a
/// moved-from segmenter throws std::logic_error from segment()).
class Yolov8Segmenter final : public InstanceSegmenter {
 public:
  /// Loads the ONNX model, reads its fixed input size from the file, runs one forward pass on a
  /// grey image and checks the output shapes. Throws std::invalid_argument naming the file when it
  /// is missing or unreadable, not ONNX, has no fixed 1 x 3 x H x W float input (H, W multiples of
  /// 32), cannot be loaded by OpenCV, or its outputs are not those of a YOLOv8-seg COCO model (the
  /// message lists the shapes found); also for invalid settings.
  explicit Yolov8Segmenter(const std::string& model_path, Yolov8Settings settings = {});
  ~Yolov8Segmenter() override;
  Yolov8Segmenter(Yolov8Segmenter&&) noexcept;
  Yolov8Segmenter& operator=(Yolov8Segmenter&&) noexcept;
  Yolov8Segmenter(const Yolov8Segmenter&) = delete;
  Yolov8Segmenter& operator=(const Yolov8Segmenter&) = delete;

  /// Instances of frame.bgr (CV_8UC3, BGR), by score, best first. frame.stem only names the frame
  /// in error messages. Throws std::invalid_argument for an empty image or another type.
  std::vector<SegmentedInstance> segment(const FrameImage& frame) override;

  void set_dynamic_classes(const std::set<int>& class_ids) override;
  const std::set<int>& dynamic_classes() const override { return settings_.dynamic_class_ids; }

  const Yolov8Settings& settings() const { return settings_; }
  /// Replaces all settings (checked first; nothing changes when they are invalid).
  void set_settings(const Yolov8Settings& settings);

  /// The model's fixed input size (width x height), pixels.
  cv::Size input_size() const { return input_size_; }
  const std::string& model_path() const { return model_path_; }

 private:
  struct Network;
  std::string model_path_;
  Yolov8Settings settings_;
  cv::Size input_size_;
  std::unique_ptr<Network> network_;
};

}  // namespace cge
