#include "cge/segmentation/yolov8_segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include "onnx_graph_info.hpp"

namespace cge {
namespace {

constexpr int kMaxPadValue = 255;
constexpr int kOnnxFloat = 1;                     // TensorProto.DataType FLOAT
constexpr int kInputChannels = 3;                 // RGB
constexpr int kInputRank = 4;                     // N x C x H x W
constexpr int kPredictionRank = 3;                // 1 x 116 x A
constexpr int kPrototypeRank = 4;                 // 1 x 32 x H/4 x W/4
constexpr int kDetectionStrides[] = {8, 16, 32};  // the three detection heads of YOLOv8
constexpr double kPixelCentre = 0.5;              // pixel i covers [i, i + 1); its centre is i + 0.5
constexpr unsigned char kMaskOn = 255;
constexpr double kInputScale = 1.0 / 255;  // 8-bit colour to [0, 1]

std::string shape_string(const cv::Mat& m) {
  if (m.dims == 0) return "(empty)";
  std::string s;
  for (int i = 0; i < m.dims; ++i) s += (i ? "x" : "") + std::to_string(m.size[i]);
  return s;
}

std::string dims_string(const std::vector<std::int64_t>& dims) {
  std::string s;
  for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? "x" : "") + (dims[i] < 0 ? "?" : std::to_string(dims[i]));
  return s.empty() ? "(scalar)" : s;
}

std::string size_string(cv::Size size) { return std::to_string(size.width) + " x " + std::to_string(size.height); }

// The shapes a YOLOv8-seg COCO model has for a W x H input: 1 x 116 x A and 1 x 32 x H/4 x W/4.
std::string expected_outputs(cv::Size input_size, int anchors) {
  return "1x" + std::to_string(kYolov8PredictionRows) + "x" + std::to_string(anchors) + " and 1x" +
         std::to_string(kYolov8MaskCoefficients) + "x" + std::to_string(input_size.height / kYolov8PrototypeStride) +
         "x" + std::to_string(input_size.width / kYolov8PrototypeStride);
}

int anchor_count(cv::Size input_size) {
  int count = 0;
  for (const int stride : kDetectionStrides) count += (input_size.width / stride) * (input_size.height / stride);
  return count;
}

bool is_prototype_shape(const cv::Mat& m, cv::Size input_size) {
  return m.dims == kPrototypeRank && m.size[0] == 1 && m.size[1] == kYolov8MaskCoefficients &&
         m.size[2] == input_size.height / kYolov8PrototypeStride &&
         m.size[3] == input_size.width / kYolov8PrototypeStride;
}

bool is_prediction_shape(const cv::Mat& m) {
  return m.dims == kPredictionRank && m.size[0] == 1 && m.size[1] == kYolov8PredictionRows;
}

struct Candidate {
  int anchor = 0;
  int class_id = 0;
  float score = 0;
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;  // input pixels
};

double iou(const Candidate& a, const Candidate& b) {
  const double w = std::min(a.x2, b.x2) - std::max(a.x1, b.x1);
  const double h = std::min(a.y2, b.y2) - std::max(a.y1, b.y1);
  if (w <= 0 || h <= 0) return 0;
  const double inter = w * h;
  const double uni = (a.x2 - a.x1) * (a.y2 - a.y1) + (b.x2 - b.x1) * (b.y2 - b.y1) - inter;
  return uni > 0 ? inter / uni : 0;
}

// Best class per anchor, thresholded, sorted by score (ties: anchor index).
std::vector<Candidate> candidates(const cv::Mat& predictions, const Yolov8Settings& settings) {
  const int anchors = predictions.size[2];
  const float* p = predictions.ptr<float>();
  const auto row = [&](int r) { return p + static_cast<std::ptrdiff_t>(r) * anchors; };
  std::vector<Candidate> out;
  for (int a = 0; a < anchors; ++a) {
    int best = 0;
    float best_score = row(kYolov8BoxValues)[a];
    for (int c = 1; c < kCocoClassCount; ++c) {
      const float s = row(kYolov8BoxValues + c)[a];
      if (s > best_score) {
        best_score = s;
        best = c;
      }
    }
    if (!(best_score >= settings.confidence_threshold)) continue;  // also drops NaN
    const double cx = row(0)[a], cy = row(1)[a], w = row(2)[a], h = row(3)[a];
    if (!std::isfinite(cx) || !std::isfinite(cy) || !std::isfinite(w) || !std::isfinite(h) || w <= 0 || h <= 0) {
      continue;
    }
    out.push_back({a, best, best_score, cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2});
  }
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return a.score != b.score ? a.score > b.score : a.anchor < b.anchor;
  });
  return out;
}

// Greedy class-aware NMS over candidates sorted best first; keeps at most max_detections.
std::vector<Candidate> suppress(const std::vector<Candidate>& sorted, const Yolov8Settings& settings) {
  std::vector<Candidate> kept;
  for (const Candidate& c : sorted) {
    if (static_cast<int>(kept.size()) == settings.max_detections) break;
    const bool overlaps = std::any_of(kept.begin(), kept.end(), [&](const Candidate& k) {
      return k.class_id == c.class_id && iou(k, c) > settings.nms_iou_threshold;
    });
    if (!overlaps) kept.push_back(c);
  }
  return kept;
}

// First index i of a pixel grid whose centre i + 0.5 is at or after position x.
int first_centre_at_or_after(double x) { return static_cast<int>(std::ceil(x - kPixelCentre)); }

// The instance mask: sigmoid(coefficients . prototypes) on the prototype cells whose centres lie in
// the box (zero elsewhere), sampled bilinearly at the centre of every original pixel inside the
// box, thresholded. `probability` is a zeroed (rows + 2) x (cols + 2) work grid with a zero border,
// left zeroed on return.
void decode_mask(const Candidate& c, const float* coefficients, std::ptrdiff_t coefficient_step,
                 const cv::Mat& prototypes, const Letterbox& lb, const cv::Rect& box_pixels,
                 const Yolov8Settings& settings, cv::Mat& probability, cv::Mat& mask) {
  const int rows = prototypes.size[2];
  const int cols = prototypes.size[3];
  const double cells_per_input_x = static_cast<double>(cols) / lb.input_size.width;
  const double cells_per_input_y = static_cast<double>(rows) / lb.input_size.height;
  const int c0 = std::max(0, first_centre_at_or_after(c.x1 * cells_per_input_x));
  const int c1 = std::min(cols, first_centre_at_or_after(c.x2 * cells_per_input_x));
  const int r0 = std::max(0, first_centre_at_or_after(c.y1 * cells_per_input_y));
  const int r1 = std::min(rows, first_centre_at_or_after(c.y2 * cells_per_input_y));
  if (c0 >= c1 || r0 >= r1) return;  // the box covers no cell centre: empty mask

  // Linear combination of the prototypes over the box's cells, then the sigmoid.
  const std::ptrdiff_t plane = static_cast<std::ptrdiff_t>(rows) * cols;
  const float* proto = prototypes.ptr<float>();
  for (int k = 0; k < kYolov8MaskCoefficients; ++k) {
    const float w = coefficients[k * coefficient_step];
    const float* proto_k = proto + k * plane;
    for (int r = r0; r < r1; ++r) {
      float* out = probability.ptr<float>(r + 1) + 1;
      const float* in = proto_k + static_cast<std::ptrdiff_t>(r) * cols;
      for (int col = c0; col < c1; ++col) out[col] += w * in[col];
    }
  }
  for (int r = r0; r < r1; ++r) {
    float* out = probability.ptr<float>(r + 1) + 1;
    for (int col = c0; col < c1; ++col) out[col] = 1.0f / (1.0f + std::exp(-out[col]));
  }

  // Where each original pixel centre falls on the cell grid: cell index and bilinear weight. The
  // zero border of `probability` stands for the cells outside the grid.
  struct Tap {
    int index;  // left/top neighbour in the bordered grid
    float weight;
  };
  const auto taps = [](int first, int count, double scale, int pad, double cells_per_input, int cells) {
    std::vector<Tap> t(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
      const double input = (first + i + kPixelCentre) * scale + pad;
      const double cell = input * cells_per_input - kPixelCentre;  // in cell-centre coordinates
      const double left = std::clamp(std::floor(cell), -1.0, static_cast<double>(cells - 1));
      t[static_cast<std::size_t>(i)] = {static_cast<int>(left) + 1, static_cast<float>(cell - left)};
    }
    return t;
  };
  const auto tx = taps(box_pixels.x, box_pixels.width, lb.scale_x(), lb.pad_left_px, cells_per_input_x, cols);
  const auto ty = taps(box_pixels.y, box_pixels.height, lb.scale_y(), lb.pad_top_px, cells_per_input_y, rows);
  for (int j = 0; j < box_pixels.height; ++j) {
    const Tap& y = ty[static_cast<std::size_t>(j)];
    const float* top = probability.ptr<float>(y.index);
    const float* bottom = probability.ptr<float>(y.index + 1);
    unsigned char* out = mask.ptr<unsigned char>(box_pixels.y + j) + box_pixels.x;
    for (int i = 0; i < box_pixels.width; ++i) {
      const Tap& x = tx[static_cast<std::size_t>(i)];
      const float upper = top[x.index] + x.weight * (top[x.index + 1] - top[x.index]);
      const float lower = bottom[x.index] + x.weight * (bottom[x.index + 1] - bottom[x.index]);
      const float value = upper + y.weight * (lower - upper);
      out[i] = value > settings.mask_threshold ? kMaskOn : 0;
    }
  }

  for (int r = r0; r < r1; ++r) {
    std::fill(probability.ptr<float>(r + 1) + 1 + c0, probability.ptr<float>(r + 1) + 1 + c1, 0.0f);
  }
}

// The retina mask: the logit map sum_k c_k P_k on the whole prototype grid (no crop there),
// sampled bilinearly at the centre of every original pixel inside the box, the grid's edge values
// extended beyond it (as a bilinear resize without corner alignment does), then sigmoid and
// threshold. `logits` is a rows x cols work grid; only the cells the box's pixels read are written.
void decode_mask_retina(const float* coefficients, std::ptrdiff_t coefficient_step, const cv::Mat& prototypes,
                        const Letterbox& lb, const cv::Rect& box_pixels, const Yolov8Settings& settings,
                        cv::Mat& logits, cv::Mat& mask) {
  const int rows = prototypes.size[2];
  const int cols = prototypes.size[3];
  const double cells_per_input_x = static_cast<double>(cols) / lb.input_size.width;
  const double cells_per_input_y = static_cast<double>(rows) / lb.input_size.height;

  // Where each original pixel centre falls on the cell grid: the two neighbouring cells (equal at
  // the grid's edge) and the weight of the second.
  struct Tap {
    int first, second;
    float weight;
  };
  const auto taps = [](int first, int count, double scale, int pad, double cells_per_input, int cells) {
    std::vector<Tap> t(static_cast<std::size_t>(count));
    const double last = cells - 1;
    for (int i = 0; i < count; ++i) {
      const double input = (first + i + kPixelCentre) * scale + pad;
      const double cell = std::clamp(input * cells_per_input - kPixelCentre, 0.0, last);
      const double left = std::floor(cell);
      const int index = static_cast<int>(left);
      t[static_cast<std::size_t>(i)] = {index, std::min(index + 1, cells - 1), static_cast<float>(cell - left)};
    }
    return t;
  };
  const auto tx = taps(box_pixels.x, box_pixels.width, lb.scale_x(), lb.pad_left_px, cells_per_input_x, cols);
  const auto ty = taps(box_pixels.y, box_pixels.height, lb.scale_y(), lb.pad_top_px, cells_per_input_y, rows);
  // Taps are monotonic: the cells read span the first tap's first cell to the last tap's second.
  const int c0 = tx.front().first, c1 = tx.back().second + 1;
  const int r0 = ty.front().first, r1 = ty.back().second + 1;

  const std::ptrdiff_t plane = static_cast<std::ptrdiff_t>(rows) * cols;
  const float* proto = prototypes.ptr<float>();
  for (int r = r0; r < r1; ++r) std::fill(logits.ptr<float>(r) + c0, logits.ptr<float>(r) + c1, 0.0f);
  for (int k = 0; k < kYolov8MaskCoefficients; ++k) {
    const float w = coefficients[k * coefficient_step];
    const float* proto_k = proto + k * plane;
    for (int r = r0; r < r1; ++r) {
      float* out = logits.ptr<float>(r);
      const float* in = proto_k + static_cast<std::ptrdiff_t>(r) * cols;
      for (int col = c0; col < c1; ++col) out[col] += w * in[col];
    }
  }

  for (int j = 0; j < box_pixels.height; ++j) {
    const Tap& y = ty[static_cast<std::size_t>(j)];
    const float* top = logits.ptr<float>(y.first);
    const float* bottom = logits.ptr<float>(y.second);
    unsigned char* out = mask.ptr<unsigned char>(box_pixels.y + j) + box_pixels.x;
    for (int i = 0; i < box_pixels.width; ++i) {
      const Tap& x = tx[static_cast<std::size_t>(i)];
      const float upper = top[x.first] + x.weight * (top[x.second] - top[x.first]);
      const float lower = bottom[x.first] + x.weight * (bottom[x.second] - bottom[x.first]);
      const float logit = upper + y.weight * (lower - upper);
      out[i] = 1.0f / (1.0f + std::exp(-logit)) > settings.mask_threshold ? kMaskOn : 0;
    }
  }
}

std::vector<unsigned char> read_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw std::invalid_argument("Yolov8Segmenter: model file " + path + " does not exist");
  if (fs::is_directory(path, ec)) {
    throw std::invalid_argument("Yolov8Segmenter: model file " + path + " is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("Yolov8Segmenter: model file " + path + " cannot be opened for reading");
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::invalid_argument("Yolov8Segmenter: error while reading model file " + path);
  return bytes;
}

// The fixed W x H of the model's single 1 x 3 x H x W float input.
cv::Size model_input_size(const detail::OnnxGraphInfo& info, const std::string& path) {
  const std::string where = "Yolov8Segmenter: " + path + ": ";
  if (info.inputs.size() != 1) {
    throw std::invalid_argument(where + "the model has " + std::to_string(info.inputs.size()) +
                                " inputs, a YOLOv8-seg model has one (1x3xHxW)");
  }
  const detail::OnnxValueInfo& in = info.inputs.front();
  const auto& d = in.dims;
  const std::string described = "the input '" + in.name + "' is " + dims_string(d);
  if (in.elem_type != kOnnxFloat) {
    throw std::invalid_argument(where + "the input '" + in.name + "' has ONNX element type " +
                                std::to_string(in.elem_type) + ", expected 1 (float)");
  }
  if (d.size() != kInputRank || (d[0] != 1 && d[0] != -1) || d[1] != kInputChannels) {
    throw std::invalid_argument(where + described + ", expected 1x3xHxW");
  }
  if (d[2] <= 0 || d[3] <= 0) {
    throw std::invalid_argument(where + described +
                                ": H and W must be fixed (export the model with a fixed image size)");
  }
  if (d[2] % kYolov8MaxStride != 0 || d[3] % kYolov8MaxStride != 0 || d[2] > std::numeric_limits<int>::max() ||
      d[3] > std::numeric_limits<int>::max()) {
    throw std::invalid_argument(where + described + ": H and W must be multiples of 32");
  }
  return {static_cast<int>(d[3]), static_cast<int>(d[2])};
}

}  // namespace

const char* to_string(Yolov8MaskDecoding decoding) {
  switch (decoding) {
    case Yolov8MaskDecoding::prototype_crop:
      return "prototype_crop";
    case Yolov8MaskDecoding::retina:
      return "retina";
  }
  return "invalid";  // only for a value cast from an out-of-range integer
}

void check_settings(const Yolov8Settings& s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("Yolov8Settings: " + what); };
  if (!(s.confidence_threshold > 0 && s.confidence_threshold <= 1)) {
    fail("confidence_threshold " + std::to_string(s.confidence_threshold) + " is not in (0, 1]");
  }
  if (!(s.nms_iou_threshold >= 0 && s.nms_iou_threshold <= 1)) {
    fail("nms_iou_threshold " + std::to_string(s.nms_iou_threshold) + " is not in [0, 1]");
  }
  if (!(s.mask_threshold > 0 && s.mask_threshold < 1)) {
    fail("mask_threshold " + std::to_string(s.mask_threshold) + " is not in (0, 1)");
  }
  if (s.mask_decoding != Yolov8MaskDecoding::prototype_crop && s.mask_decoding != Yolov8MaskDecoding::retina) {
    fail("mask_decoding " + std::to_string(static_cast<int>(s.mask_decoding)) + " is not a Yolov8MaskDecoding");
  }
  if (s.max_detections < 1) fail("max_detections " + std::to_string(s.max_detections) + " is not >= 1");
  if (s.pad_value < 0 || s.pad_value > kMaxPadValue)
    fail("pad_value " + std::to_string(s.pad_value) + " is not in 0 .. 255");
  check_coco_class_ids(s.dynamic_class_ids, "Yolov8Settings");
}

Letterbox make_letterbox(cv::Size image_size, cv::Size input_size) {
  if (image_size.width <= 0 || image_size.height <= 0 || input_size.width <= 0 || input_size.height <= 0) {
    throw std::invalid_argument("make_letterbox: empty size (image " + size_string(image_size) + ", input " +
                                size_string(input_size) + ")");
  }
  const double scale = std::min(static_cast<double>(input_size.width) / image_size.width,
                                static_cast<double>(input_size.height) / image_size.height);
  Letterbox lb;
  lb.image_size = image_size;
  lb.input_size = input_size;
  // The side that limits the scale fills the input exactly; the other is rounded, at least 1 px.
  lb.scaled_size.width = std::clamp(static_cast<int>(std::lround(image_size.width * scale)), 1, input_size.width);
  lb.scaled_size.height = std::clamp(static_cast<int>(std::lround(image_size.height * scale)), 1, input_size.height);
  lb.pad_left_px = (input_size.width - lb.scaled_size.width) / 2;
  lb.pad_top_px = (input_size.height - lb.scaled_size.height) / 2;
  return lb;
}

cv::Mat letterbox_image(const cv::Mat& image, const Letterbox& lb, int pad_value) {
  if (image.size() != lb.image_size) {
    throw std::invalid_argument("letterbox_image: the image is " + size_string(image.size()) +
                                " but the letterbox was made for " + size_string(lb.image_size));
  }
  cv::Mat scaled;
  if (lb.scaled_size == image.size()) {
    scaled = image;
  } else {
    cv::resize(image, scaled, lb.scaled_size, 0, 0, cv::INTER_LINEAR);
  }
  cv::Mat out;
  const int right = lb.input_size.width - lb.scaled_size.width - lb.pad_left_px;
  const int bottom = lb.input_size.height - lb.scaled_size.height - lb.pad_top_px;
  cv::copyMakeBorder(scaled, out, lb.pad_top_px, bottom, lb.pad_left_px, right, cv::BORDER_CONSTANT,
                     cv::Scalar::all(pad_value));
  return out;
}

std::vector<SegmentedInstance> decode_yolov8_seg(const cv::Mat& predictions, const cv::Mat& prototypes,
                                                 const Letterbox& lb, const Yolov8Settings& settings) {
  check_settings(settings);
  if (predictions.type() != CV_32F || prototypes.type() != CV_32F || !is_prediction_shape(predictions) ||
      !is_prototype_shape(prototypes, lb.input_size) || !predictions.isContinuous() || !prototypes.isContinuous()) {
    throw std::invalid_argument("decode_yolov8_seg: the outputs are " + shape_string(predictions) + " and " +
                                shape_string(prototypes) + " (" + cv::typeToString(predictions.type()) + ", " +
                                cv::typeToString(prototypes.type()) + "), expected continuous CV_32F " +
                                expected_outputs(lb.input_size, predictions.dims == kPredictionRank
                                                                    ? predictions.size[2]
                                                                    : anchor_count(lb.input_size)) +
                                " for a " + size_string(lb.input_size) + " input");
  }
  const std::vector<Candidate> kept = suppress(candidates(predictions, settings), settings);

  const int anchors = predictions.size[2];
  const float* first_coefficient =
      predictions.ptr<float>() + static_cast<std::ptrdiff_t>(kYolov8BoxValues + kCocoClassCount) * anchors;
  const bool retina = settings.mask_decoding == Yolov8MaskDecoding::retina;
  // Work grids: a zero-bordered probability grid (prototype_crop) or a logit grid (retina).
  cv::Mat probability = retina ? cv::Mat(prototypes.size[2], prototypes.size[3], CV_32F)
                               : cv::Mat(prototypes.size[2] + 2, prototypes.size[3] + 2, CV_32F, cv::Scalar(0));
  const double sx = lb.scale_x(), sy = lb.scale_y();
  const double width = lb.image_size.width, height = lb.image_size.height;

  std::vector<SegmentedInstance> out;
  for (const Candidate& c : kept) {
    // The box in the original image, clipped to it.
    const double x1 = std::clamp((c.x1 - lb.pad_left_px) / sx, 0.0, width);
    const double x2 = std::clamp((c.x2 - lb.pad_left_px) / sx, 0.0, width);
    const double y1 = std::clamp((c.y1 - lb.pad_top_px) / sy, 0.0, height);
    const double y2 = std::clamp((c.y2 - lb.pad_top_px) / sy, 0.0, height);
    if (!(x2 > x1 && y2 > y1)) continue;  // wholly in the padding

    SegmentedInstance instance;
    instance.id = static_cast<int>(out.size()) + 1;
    instance.class_id = c.class_id;
    instance.score = c.score;
    instance.box_px = cv::Rect2f(static_cast<float>(x1), static_cast<float>(y1), static_cast<float>(x2 - x1),
                                 static_cast<float>(y2 - y1));
    instance.dynamic = settings.dynamic_class_ids.count(c.class_id) > 0;
    instance.mask = cv::Mat(lb.image_size, CV_8UC1, cv::Scalar(0));
    // Original pixels whose centres lie in the box.
    const int u0 = first_centre_at_or_after(x1), u1 = first_centre_at_or_after(x2);
    const int v0 = first_centre_at_or_after(y1), v1 = first_centre_at_or_after(y2);
    if (u1 > u0 && v1 > v0) {
      const cv::Rect box_pixels(u0, v0, u1 - u0, v1 - v0);
      if (retina) {
        decode_mask_retina(first_coefficient + c.anchor, anchors, prototypes, lb, box_pixels, settings, probability,
                           instance.mask);
      } else {
        decode_mask(c, first_coefficient + c.anchor, anchors, prototypes, lb, box_pixels, settings, probability,
                    instance.mask);
      }
    }
    out.push_back(std::move(instance));
  }
  return out;
}

struct Yolov8Segmenter::Network {
  cv::dnn::Net net;
  std::vector<std::string> output_names;
  int prediction_output = 0;  // index into output_names of the 1 x 116 x A output
};

Yolov8Segmenter::Yolov8Segmenter(const std::string& model_path, Yolov8Settings settings)
    : model_path_(model_path), settings_(std::move(settings)) {
  check_settings(settings_);
  const std::vector<unsigned char> bytes = read_file(model_path_);
  input_size_ = model_input_size(detail::read_onnx_graph_info(bytes, "Yolov8Segmenter: " + model_path_), model_path_);

  network_ = std::make_unique<Network>();
  const std::string where = "Yolov8Segmenter: " + model_path_ + ": ";
  std::vector<cv::Mat> outputs;
  try {
    network_->net = cv::dnn::readNetFromONNX(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    network_->output_names = network_->net.getUnconnectedOutLayersNames();
    const cv::Mat grey(input_size_, CV_8UC3, cv::Scalar::all(settings_.pad_value));
    network_->net.setInput(cv::dnn::blobFromImage(grey, kInputScale, cv::Size(), cv::Scalar(), true, false, CV_32F));
    network_->net.forward(outputs, network_->output_names);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument(where + "OpenCV's DNN module cannot run the model: " + e.what());
  }
  std::string found;
  for (const auto& o : outputs) found += (found.empty() ? "" : ", ") + shape_string(o);
  const int anchors = anchor_count(input_size_);
  const bool fits = outputs.size() == 2 && ((is_prediction_shape(outputs[0]) && outputs[0].size[2] == anchors &&
                                             is_prototype_shape(outputs[1], input_size_)) ||
                                            (is_prediction_shape(outputs[1]) && outputs[1].size[2] == anchors &&
                                             is_prototype_shape(outputs[0], input_size_)));
  if (!fits) {
    throw std::invalid_argument(where + "not a YOLOv8-seg model for the 80 COCO classes: for its " +
                                size_string(input_size_) + " input it should give two outputs, " +
                                expected_outputs(input_size_, anchors) + ", but gives " +
                                std::to_string(outputs.size()) + (outputs.empty() ? "" : ": " + found));
  }
  network_->prediction_output = is_prediction_shape(outputs[0]) ? 0 : 1;
}

Yolov8Segmenter::~Yolov8Segmenter() = default;
Yolov8Segmenter::Yolov8Segmenter(Yolov8Segmenter&&) noexcept = default;
Yolov8Segmenter& Yolov8Segmenter::operator=(Yolov8Segmenter&&) noexcept = default;

std::vector<SegmentedInstance> Yolov8Segmenter::segment(const FrameImage& frame) {
  const std::string where = "Yolov8Segmenter: frame '" + frame.stem + "': ";
  if (!network_) throw std::logic_error(where + "this segmenter was moved from and holds no network");
  if (frame.bgr.empty()) throw std::invalid_argument(where + "the image is empty");
  if (frame.bgr.type() != CV_8UC3) {
    throw std::invalid_argument(where + "the image is " + cv::typeToString(frame.bgr.type()) +
                                ", expected CV_8UC3 (8-bit BGR)");
  }
  const Letterbox lb = make_letterbox(frame.bgr.size(), input_size_);
  const cv::Mat input = letterbox_image(frame.bgr, lb, settings_.pad_value);
  network_->net.setInput(cv::dnn::blobFromImage(input, kInputScale, cv::Size(), cv::Scalar(), true, false, CV_32F));
  std::vector<cv::Mat> outputs;
  network_->net.forward(outputs, network_->output_names);
  const int p = network_->prediction_output;
  return decode_yolov8_seg(outputs[static_cast<std::size_t>(p)], outputs[static_cast<std::size_t>(1 - p)], lb,
                           settings_);
}

void Yolov8Segmenter::set_dynamic_classes(const std::set<int>& class_ids) {
  check_coco_class_ids(class_ids, "Yolov8Segmenter::set_dynamic_classes");
  settings_.dynamic_class_ids = class_ids;
}

void Yolov8Segmenter::set_settings(const Yolov8Settings& settings) {
  check_settings(settings);
  settings_ = settings;
}

}  // namespace cge
