#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/segmentation/yolov8_segmenter.hpp"
#include "onnx_test_models.hpp"
#include "temp_dir.hpp"
#include "test_support.hpp"

namespace {

constexpr int kRows = cge::kYolov8PredictionRows;            // 116
constexpr int kFirstCoefficient = 4 + cge::kCocoClassCount;  // 84

// One hand-made detection: a column of the prediction output.
struct Det {
  float cx, cy, w, h;
  int class_id;
  float score;
  std::vector<float> coefficients = std::vector<float>(cge::kYolov8MaskCoefficients, 0.f);
};

cv::Mat predictions(int anchors, const std::vector<std::pair<int, Det>>& at) {
  const int sizes[] = {1, kRows, anchors};
  cv::Mat p(3, sizes, CV_32F, cv::Scalar(0));
  float* data = p.ptr<float>();
  const auto set = [&](int row, int anchor, float v) { data[row * anchors + anchor] = v; };
  for (const auto& [a, d] : at) {
    set(0, a, d.cx);
    set(1, a, d.cy);
    set(2, a, d.w);
    set(3, a, d.h);
    set(4 + d.class_id, a, d.score);
    for (int k = 0; k < cge::kYolov8MaskCoefficients; ++k) set(kFirstCoefficient + k, a, d.coefficients[k]);
  }
  return p;
}

cv::Mat prototypes(int rows, int cols, float value = 0) {
  const int sizes[] = {1, cge::kYolov8MaskCoefficients, rows, cols};
  return cv::Mat(4, sizes, CV_32F, cv::Scalar(value));
}

float& proto_at(cv::Mat& protos, int k, int r, int c) {
  return protos.ptr<float>()[(k * protos.size[2] + r) * protos.size[3] + c];
}

// The mask of docs/SEGMENTATION.md (step 6) written out naively, pixel by pixel in double precision: the
// prototype map sigmoid(coefficients . prototypes), zero on cells whose centre is outside the box
// and outside the grid, sampled bilinearly at each original pixel centre inside the box.
// `uncertain` counts pixels whose value is within 1e-4 of the threshold (rounding may flip them)
// and marks them 128 in the returned mask.
cv::Mat oracle_mask(const Det& d, const cv::Mat& protos, const cge::Letterbox& lb, double threshold) {
  const int rows = protos.size[2], cols = protos.size[3];
  const double cell_w = static_cast<double>(lb.input_size.width) / cols;
  const double cell_h = static_cast<double>(lb.input_size.height) / rows;
  const double x1 = d.cx - d.w / 2.0, x2 = d.cx + d.w / 2.0, y1 = d.cy - d.h / 2.0, y2 = d.cy + d.h / 2.0;
  const auto cell = [&](int r, int c) -> double {
    if (r < 0 || c < 0 || r >= rows || c >= cols) return 0;
    const double xc = (c + 0.5) * cell_w, yc = (r + 0.5) * cell_h;
    if (!(xc >= x1 && xc < x2 && yc >= y1 && yc < y2)) return 0;
    double logit = 0;
    for (int k = 0; k < cge::kYolov8MaskCoefficients; ++k) {
      logit += static_cast<double>(d.coefficients[k]) * protos.ptr<float>()[(k * rows + r) * cols + c];
    }
    return 1 / (1 + std::exp(-logit));
  };
  const double sx = static_cast<double>(lb.scaled_size.width) / lb.image_size.width;
  const double sy = static_cast<double>(lb.scaled_size.height) / lb.image_size.height;
  const double bx1 = std::clamp((x1 - lb.pad_left_px) / sx, 0.0, double(lb.image_size.width));
  const double bx2 = std::clamp((x2 - lb.pad_left_px) / sx, 0.0, double(lb.image_size.width));
  const double by1 = std::clamp((y1 - lb.pad_top_px) / sy, 0.0, double(lb.image_size.height));
  const double by2 = std::clamp((y2 - lb.pad_top_px) / sy, 0.0, double(lb.image_size.height));
  cv::Mat mask(lb.image_size, CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      if (!(u + 0.5 >= bx1 && u + 0.5 < bx2 && v + 0.5 >= by1 && v + 0.5 < by2)) continue;
      const double fx = ((u + 0.5) * sx + lb.pad_left_px) / cell_w - 0.5;
      const double fy = ((v + 0.5) * sy + lb.pad_top_px) / cell_h - 0.5;
      const int c0 = static_cast<int>(std::floor(fx)), r0 = static_cast<int>(std::floor(fy));
      const double wx = fx - c0, wy = fy - r0;
      const double value = (1 - wy) * ((1 - wx) * cell(r0, c0) + wx * cell(r0, c0 + 1)) +
                           wy * ((1 - wx) * cell(r0 + 1, c0) + wx * cell(r0 + 1, c0 + 1));
      if (std::abs(value - threshold) < 1e-4) {
        mask.at<unsigned char>(v, u) = 128;
      } else if (value > threshold) {
        mask.at<unsigned char>(v, u) = 255;
      }
    }
  }
  return mask;
}

// The retina decoding written out naively in double precision: at each original pixel centre
// inside the box, the logit sum_k c_k P_k interpolated bilinearly between the four nearest cell
// centres (positions clamped to the grid, so its edge values extend beyond it), then the sigmoid.
// Pixels within 1e-4 of the threshold are marked 128, as in oracle_mask.
cv::Mat oracle_mask_retina(const Det& d, const cv::Mat& protos, const cge::Letterbox& lb, double threshold) {
  const int rows = protos.size[2], cols = protos.size[3];
  const double cell_w = static_cast<double>(lb.input_size.width) / cols;
  const double cell_h = static_cast<double>(lb.input_size.height) / rows;
  const auto logit = [&](int r, int c) {
    double sum = 0;
    for (int k = 0; k < cge::kYolov8MaskCoefficients; ++k) {
      sum += static_cast<double>(d.coefficients[k]) * protos.ptr<float>()[(k * rows + r) * cols + c];
    }
    return sum;
  };
  const double sx = static_cast<double>(lb.scaled_size.width) / lb.image_size.width;
  const double sy = static_cast<double>(lb.scaled_size.height) / lb.image_size.height;
  const double bx1 = std::clamp((d.cx - d.w / 2.0 - lb.pad_left_px) / sx, 0.0, double(lb.image_size.width));
  const double bx2 = std::clamp((d.cx + d.w / 2.0 - lb.pad_left_px) / sx, 0.0, double(lb.image_size.width));
  const double by1 = std::clamp((d.cy - d.h / 2.0 - lb.pad_top_px) / sy, 0.0, double(lb.image_size.height));
  const double by2 = std::clamp((d.cy + d.h / 2.0 - lb.pad_top_px) / sy, 0.0, double(lb.image_size.height));
  cv::Mat mask(lb.image_size, CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      if (!(u + 0.5 >= bx1 && u + 0.5 < bx2 && v + 0.5 >= by1 && v + 0.5 < by2)) continue;
      const double fx = std::clamp(((u + 0.5) * sx + lb.pad_left_px) / cell_w - 0.5, 0.0, cols - 1.0);
      const double fy = std::clamp(((v + 0.5) * sy + lb.pad_top_px) / cell_h - 0.5, 0.0, rows - 1.0);
      const int c0 = static_cast<int>(std::floor(fx)), r0 = static_cast<int>(std::floor(fy));
      const int c1 = std::min(c0 + 1, cols - 1), r1 = std::min(r0 + 1, rows - 1);
      const double wx = fx - c0, wy = fy - r0;
      const double l = (1 - wy) * ((1 - wx) * logit(r0, c0) + wx * logit(r0, c1)) +
                       wy * ((1 - wx) * logit(r1, c0) + wx * logit(r1, c1));
      const double value = 1 / (1 + std::exp(-l));
      if (std::abs(value - threshold) < 1e-4) {
        mask.at<unsigned char>(v, u) = 128;
      } else if (value > threshold) {
        mask.at<unsigned char>(v, u) = 255;
      }
    }
  }
  return mask;
}

// Pixels where `mask` and the oracle disagree, not counting the oracle's uncertain pixels.
int disagreements(const cv::Mat& mask, const cv::Mat& oracle) {
  int n = 0;
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      const auto o = oracle.at<unsigned char>(v, u);
      if (o != 128 && o != mask.at<unsigned char>(v, u)) ++n;
    }
  }
  return n;
}

// The hand-worked case shared by the decoder test and the tiny-model test: a 64 x 32 image in a
// 32 x 32 input (scale 0.5, 8 px grey above and below), one person box cx 12, cy 16, w = h = 8
// input pixels, i.e. x 16 .. 32, y 8 .. 24 in the image, and prototype plane 0 = 8 with coefficient
// 1: p = sigmoid(8) on the 2 x 2 cells inside the box, 0 elsewhere. Along x the bilinear weight of
// the box's cells at pixels u = 16, 17, 18, 19 is 0.5625, 0.6875, 0.8125, 0.9375 (mirrored at the
// right edge, 1 inside), the same along y; the value is p times the product. It stays above 0.5
// except where the two edge distances dx + dy <= 2 (e.g. 0.5625 * 0.8125 p = 0.457 at dx 0, dy 2;
// 0.6875^2 p = 0.473 at dx = dy = 1; 0.5625 * 0.9375 p = 0.527 at dx 0, dy 3 is on): the box
// with its three-pixel corners cut.
constexpr float kHandCx = 12, kHandCy = 16, kHandSide = 8, kHandScore = 0.9f, kHandPrototype = 8;
const cv::Rect kHandBox(16, 8, 16, 16);

bool hand_worked_pixel_on(int u, int v) {
  if (!kHandBox.contains(cv::Point(u, v))) return false;
  const int dx = std::min(u - kHandBox.x, kHandBox.x + kHandBox.width - 1 - u);
  const int dy = std::min(v - kHandBox.y, kHandBox.y + kHandBox.height - 1 - v);
  return dx + dy > 2;
}

void check_hand_worked_mask(const cv::Mat& mask) {
  REQUIRE(mask.type() == CV_8UC1);
  REQUIRE(mask.size() == cv::Size(64, 32));
  int wrong = 0;
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      if ((mask.at<unsigned char>(v, u) == 255) != hand_worked_pixel_on(u, v)) ++wrong;
      if (mask.at<unsigned char>(v, u) != 0 && mask.at<unsigned char>(v, u) != 255) ++wrong;
    }
  }
  CHECK(wrong == 0);
  CHECK(cv::countNonZero(mask) == 16 * 16 - 4 * 6);
}

Det hand_worked_detection() {
  Det d{kHandCx, kHandCy, kHandSide, kHandSide, cge::kCocoPerson, kHandScore};
  d.coefficients[0] = 1;
  return d;
}

std::string shared_file(const std::string& relative) { return std::string(CGE_SHARED_DIR) + "/" + relative; }

}  // namespace

// ---- letterbox ---------------------------------------------------------------------------------

/// A random decoding case on a 16 x 16 prototype grid for the naive-oracle tests: random
/// prototypes, and three detections of different classes (so that suppression keeps all three)
/// with centres on the letterboxed image and boxes that may cross its border.
struct RandomDecodeCase {
  cv::Mat protos;
  std::vector<std::pair<int, Det>> dets;
};
RandomDecodeCase random_decode_case(const cge::Letterbox& lb, std::mt19937& rng) {
  std::normal_distribution<float> normal(0.f, 1.f);
  std::uniform_real_distribution<float> uniform(0.f, 1.f);
  RandomDecodeCase c;
  c.protos = prototypes(16, 16);
  for (int k = 0; k < cge::kYolov8MaskCoefficients; ++k) {
    for (int r = 0; r < 16; ++r) {
      for (int col = 0; col < 16; ++col) proto_at(c.protos, k, r, col) = 2 * normal(rng);
    }
  }
  for (int i = 0; i < 3; ++i) {
    const float cx = static_cast<float>(lb.pad_left_px) + static_cast<float>(lb.scaled_size.width) * uniform(rng);
    const float cy = static_cast<float>(lb.pad_top_px) + static_cast<float>(lb.scaled_size.height) * uniform(rng);
    Det d{cx, cy, 6 + 40 * uniform(rng), 6 + 40 * uniform(rng), i, 0.5f + 0.1f * static_cast<float>(i)};
    for (float& w : d.coefficients) w = normal(rng);
    c.dets.push_back({2 * i + 1, d});
  }
  return c;
}

TEST_CASE("Letterbox: hand-worked scales and paddings", "[segmentation][yolov8]") {
  struct Case {
    cv::Size image, input, scaled;
    int left, top;
  };
  const Case cases[] = {
      {{640, 480}, {640, 640}, {640, 480}, 0, 80},  // TUM into the 640 model: no scaling
      {{640, 480}, {320, 320}, {320, 240}, 0, 40},  // half size
      {{480, 640}, {640, 640}, {480, 640}, 80, 0},  // portrait
      {{20, 13}, {32, 32}, {32, 21}, 0, 5},         // 13 * 1.6 = 20.8 -> 21; padding 11 = 5 + 6
      {{100, 50}, {64, 64}, {64, 32}, 0, 16},       // scale 0.64
      {{64, 64}, {64, 32}, {32, 32}, 16, 0},        // landscape input
  };
  for (const Case& c : cases) {
    const cge::Letterbox lb = cge::make_letterbox(c.image, c.input);
    INFO(c.image << " into " << c.input);
    CHECK(lb.scaled_size == c.scaled);
    CHECK(lb.pad_left_px == c.left);
    CHECK(lb.pad_top_px == c.top);
    CHECK(lb.scale_x() == Approx(double(c.scaled.width) / c.image.width));
  }
  CHECK_THROWS_AS(cge::make_letterbox({0, 10}, {32, 32}), std::invalid_argument);
  CHECK_THROWS_AS(cge::make_letterbox({10, 10}, {32, 0}), std::invalid_argument);
}

TEST_CASE("letterbox_image: the image at its offset, grey padding around it", "[segmentation][yolov8]") {
  cv::Mat image(13, 20, CV_8UC3);
  cv::randu(image, 0, 256);
  const cge::Letterbox lb = cge::make_letterbox(image.size(), {32, 32});
  const cv::Mat out = cge::letterbox_image(image, lb, 114);
  REQUIRE(out.size() == cv::Size(32, 32));
  REQUIRE(out.type() == CV_8UC3);
  cv::Mat scaled;
  cv::resize(image, scaled, lb.scaled_size, 0, 0, cv::INTER_LINEAR);
  const cv::Rect inside(lb.pad_left_px, lb.pad_top_px, lb.scaled_size.width, lb.scaled_size.height);
  CHECK(cv::norm(out(inside), scaled, cv::NORM_INF) == 0);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      if (inside.contains(cv::Point(x, y))) continue;
      CHECK(out.at<cv::Vec3b>(y, x) == cv::Vec3b(114, 114, 114));
    }
  }
  // Scale 1: an exact copy in the middle.
  const cge::Letterbox same = cge::make_letterbox({32, 16}, {32, 32});
  cv::Mat small(16, 32, CV_8UC3);
  cv::randu(small, 0, 256);
  CHECK(cv::norm(cge::letterbox_image(small, same, 0)(cv::Rect(0, 8, 32, 16)), small, cv::NORM_INF) == 0);
  CHECK_THROWS_AS(cge::letterbox_image(small, lb, 114), std::invalid_argument);
}

// ---- decoding ----------------------------------------------------------------------------------

TEST_CASE("decode_yolov8_seg: the hand-worked box and mask", "[segmentation][yolov8]") {
  const cge::Letterbox lb = cge::make_letterbox({64, 32}, {32, 32});
  cv::Mat protos = prototypes(8, 8);
  for (int r = 0; r < 8; ++r) {
    for (int c = 0; c < 8; ++c) proto_at(protos, 0, r, c) = kHandPrototype;
  }
  const auto out = cge::decode_yolov8_seg(predictions(21, {{5, hand_worked_detection()}}), protos, lb, {});
  REQUIRE(out.size() == 1);
  const cge::SegmentedInstance& s = out.front();
  CHECK(s.id == 1);
  CHECK(s.class_id == cge::kCocoPerson);
  CHECK(s.score == kHandScore);
  CHECK(s.dynamic);
  CHECK_FALSE(s.moving.has_value());
  CHECK(s.box_px.x == 16.f);
  CHECK(s.box_px.y == 8.f);
  CHECK(s.box_px.width == 16.f);
  CHECK(s.box_px.height == 16.f);
  check_hand_worked_mask(s.mask);
  CHECK(disagreements(s.mask, oracle_mask(hand_worked_detection(), protos, lb, 0.5)) == 0);

  // All prototypes 0: probability 0.5 everywhere, not above the threshold: the detection stays,
  // with an empty mask.
  const auto flat = cge::decode_yolov8_seg(predictions(21, {{5, hand_worked_detection()}}), prototypes(8, 8), lb, {});
  REQUIRE(flat.size() == 1);
  CHECK(cv::countNonZero(flat.front().mask) == 0);
}

TEST_CASE("decode_yolov8_seg: masks equal a naive pixel-by-pixel oracle", "[segmentation][yolov8]") {
  // Random prototypes and coefficients, letterboxes with scaling and padding on either side.
  const cv::Size images[] = {{100, 60}, {60, 100}, {64, 64}, {37, 91}};
  std::mt19937 rng(20250707);
  for (const cv::Size image : images) {
    const cge::Letterbox lb = cge::make_letterbox(image, {64, 64});
    const auto [protos, dets] = random_decode_case(lb, rng);
    const auto out = cge::decode_yolov8_seg(predictions(7, dets), protos, lb, {});
    INFO("image " << image);
    REQUIRE(out.size() == 3);
    for (const auto& s : out) {
      const Det& d = dets[static_cast<std::size_t>(s.class_id)].second;
      const cv::Mat oracle = oracle_mask(d, protos, lb, 0.5);
      CHECK(disagreements(s.mask, oracle) == 0);
      CHECK(cv::countNonZero(oracle == 255) > 0);  // the case is not vacuous
    }
  }
}

TEST_CASE("decode_yolov8_seg retina: the hand-worked box is filled to its edges", "[segmentation][yolov8]") {
  // The hand-worked case decoded in the retina order: the logit is 8 on every cell, also outside
  // the box (no crop on the grid), so every pixel whose centre lies in the box is on (sigmoid(8) >
  // 0.5) and the corners are not cut; pixels outside the box stay off.
  const cge::Letterbox lb = cge::make_letterbox({64, 32}, {32, 32});
  cv::Mat protos = prototypes(8, 8);
  for (int r = 0; r < 8; ++r) {
    for (int c = 0; c < 8; ++c) proto_at(protos, 0, r, c) = kHandPrototype;
  }
  cge::Yolov8Settings retina;
  retina.mask_decoding = cge::Yolov8MaskDecoding::retina;
  const auto out = cge::decode_yolov8_seg(predictions(21, {{5, hand_worked_detection()}}), protos, lb, retina);
  REQUIRE(out.size() == 1);
  CHECK(out[0].box_px == cv::Rect2f(16.f, 8.f, 16.f, 16.f));
  cv::Mat expected(32, 64, CV_8UC1, cv::Scalar(0));
  expected(kHandBox).setTo(255);
  CHECK(cv::norm(out[0].mask, expected, cv::NORM_INF) == 0);

  // A logit step: -8 on cell columns 0 .. 2, +8 from column 3 on. Cell centres are at input
  // x = 4c + 2, so the interpolated logit crosses 0 halfway between x 10 and 14, at input x 12 =
  // image x 24 (scale 0.5): the box's pixels u >= 24 (centre 24.5) are on, u <= 23 off, on every
  // row (the step does not depend on y).
  for (int r = 0; r < 8; ++r) {
    for (int c = 0; c < 8; ++c) proto_at(protos, 0, r, c) = c <= 2 ? -kHandPrototype : kHandPrototype;
  }
  const auto step = cge::decode_yolov8_seg(predictions(21, {{5, hand_worked_detection()}}), protos, lb, retina);
  REQUIRE(step.size() == 1);
  expected.setTo(0);
  expected(cv::Rect(24, 8, 8, 16)).setTo(255);
  CHECK(cv::norm(step[0].mask, expected, cv::NORM_INF) == 0);
  CHECK(disagreements(step[0].mask, oracle_mask_retina(hand_worked_detection(), protos, lb, 0.5)) == 0);
}

TEST_CASE("decode_yolov8_seg retina: masks equal a naive pixel-by-pixel oracle", "[segmentation][yolov8]") {
  // As the oracle test of the default order: random prototypes and coefficients, letterboxes with
  // scaling and padding on either side, boxes that may cross the image border.
  const cv::Size images[] = {{100, 60}, {60, 100}, {64, 64}, {37, 91}};
  std::mt19937 rng(20250708);
  cge::Yolov8Settings retina;
  retina.mask_decoding = cge::Yolov8MaskDecoding::retina;
  for (const cv::Size image : images) {
    const cge::Letterbox lb = cge::make_letterbox(image, {64, 64});
    const auto [protos, dets] = random_decode_case(lb, rng);
    const auto out = cge::decode_yolov8_seg(predictions(7, dets), protos, lb, retina);
    const auto cropped = cge::decode_yolov8_seg(predictions(7, dets), protos, lb, {});
    INFO("image " << image);
    REQUIRE(out.size() == 3);
    REQUIRE(cropped.size() == 3);
    int differing = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
      const cv::Mat oracle =
          oracle_mask_retina(dets[static_cast<std::size_t>(out[i].class_id)].second, protos, lb, 0.5);
      CHECK(disagreements(out[i].mask, oracle) == 0);
      CHECK(cv::countNonZero(oracle == 255) > 0);  // the case is not vacuous
      CHECK(out[i].box_px == cropped[i].box_px);   // only the masks depend on the order
      differing += cv::countNonZero(out[i].mask != cropped[i].mask);
    }
    CHECK(differing > 0);  // the two orders are different decodings
  }
}

TEST_CASE("decode_yolov8_seg: best class per anchor, inclusive confidence threshold", "[segmentation][yolov8]") {
  const cge::Letterbox lb = cge::make_letterbox({64, 64}, {64, 64});
  cv::Mat p = predictions(4, {{0, {10, 10, 8, 8, 0, 0.25f}},    // exactly the threshold: kept
                              {1, {30, 10, 8, 8, 0, 0.2499f}},  // below: dropped
                              {2, {50, 10, 8, 8, 0, 0.3f}},     // person 0.3, but chair 0.6 wins
                              {3, {10, 40, 8, 8, 5, 0.4f}}});   // bus 0.4 and car 0.4: car (lower id)
  p.ptr<float>()[(4 + 56) * 4 + 2] = 0.6f;
  p.ptr<float>()[(4 + 2) * 4 + 3] = 0.4f;
  const auto out = cge::decode_yolov8_seg(p, prototypes(16, 16), lb, {});
  REQUIRE(out.size() == 3);
  CHECK(out[0].class_id == 56);
  CHECK(out[0].score == 0.6f);
  CHECK_FALSE(out[0].dynamic);
  CHECK(out[1].class_id == 2);
  CHECK(out[1].score == 0.4f);
  CHECK(out[2].class_id == 0);
  CHECK(out[2].score == 0.25f);
  CHECK(out[2].dynamic);
}

TEST_CASE("decode_yolov8_seg: class-aware non-maximum suppression", "[segmentation][yolov8]") {
  const cge::Letterbox lb = cge::make_letterbox({64, 64}, {64, 64});
  // Boxes (x from .. to, y 0 .. 10): A 0..10, B 1..11 (IoU with A 90/110 = 0.818), C 5..15
  // (IoU with A 50/150 = 0.333), D = B as a chair, E = A with a lower score.
  const std::vector<std::pair<int, Det>> dets = {{0, {5, 5, 10, 10, 0, 0.9f}},
                                                 {1, {6, 5, 10, 10, 0, 0.8f}},
                                                 {2, {10, 5, 10, 10, 0, 0.7f}},
                                                 {3, {6, 5, 10, 10, 56, 0.85f}},
                                                 {4, {5, 5, 10, 10, 0, 0.6f}}};
  const auto scores = [](const std::vector<cge::SegmentedInstance>& v) {
    std::vector<float> s;
    for (const auto& i : v) s.push_back(i.score);
    return s;
  };
  cge::Yolov8Settings settings;  // IoU threshold 0.7: B and E go
  CHECK(scores(cge::decode_yolov8_seg(predictions(5, dets), prototypes(16, 16), lb, settings)) ==
        std::vector<float>{0.9f, 0.85f, 0.7f});
  settings.nms_iou_threshold = 0.85f;  // B stays, E (IoU 1) goes
  CHECK(scores(cge::decode_yolov8_seg(predictions(5, dets), prototypes(16, 16), lb, settings)) ==
        std::vector<float>{0.9f, 0.85f, 0.8f, 0.7f});
  settings.nms_iou_threshold = 0.3f;  // C goes too
  CHECK(scores(cge::decode_yolov8_seg(predictions(5, dets), prototypes(16, 16), lb, settings)) ==
        std::vector<float>{0.9f, 0.85f});
}

TEST_CASE("decode_yolov8_seg: ties by anchor, ids by rank, max_detections", "[segmentation][yolov8]") {
  const cge::Letterbox lb = cge::make_letterbox({64, 64}, {64, 64});
  const std::vector<std::pair<int, Det>> dets = {
      {3, {50, 50, 6, 6, 0, 0.5f}}, {1, {10, 10, 6, 6, 0, 0.5f}}, {2, {30, 30, 6, 6, 0, 0.7f}}};
  auto out = cge::decode_yolov8_seg(predictions(4, dets), prototypes(16, 16), lb, {});
  REQUIRE(out.size() == 3);
  CHECK(out[0].box_px.x == 27.f);  // score 0.7
  CHECK(out[1].box_px.x == 7.f);   // score 0.5, anchor 1
  CHECK(out[2].box_px.x == 47.f);  // score 0.5, anchor 3
  for (int i = 0; i < 3; ++i) CHECK(out[static_cast<std::size_t>(i)].id == i + 1);

  cge::Yolov8Settings settings;
  settings.max_detections = 2;
  out = cge::decode_yolov8_seg(predictions(4, dets), prototypes(16, 16), lb, settings);
  REQUIRE(out.size() == 2);
  CHECK(out[1].box_px.x == 7.f);
}

TEST_CASE("decode_yolov8_seg: boxes clipped to the image, detections in the padding dropped",
          "[segmentation][yolov8]") {
  // 64 x 32 image in a 64 x 64 input: 16 grey rows above and below.
  const cge::Letterbox lb = cge::make_letterbox({64, 32}, {64, 64});
  const auto out = cge::decode_yolov8_seg(predictions(3, {{0, {32, 6, 20, 8, 0, 0.9f}},     // y 2 .. 10: padding
                                                          {1, {0, 30, 20, 40, 0, 0.8f}}}),  // x -10 .. 10
                                          prototypes(16, 16), lb, {});
  REQUIRE(out.size() == 1);
  CHECK(out[0].id == 1);
  CHECK(out[0].score == 0.8f);
  CHECK(out[0].box_px.x == 0.f);
  CHECK(out[0].box_px.width == 10.f);
  CHECK(out[0].box_px.y == 0.f);        // 10 - 16 clipped
  CHECK(out[0].box_px.height == 32.f);  // 50 - 16 clipped to 32
}

TEST_CASE("decode_yolov8_seg: shapes and types that do not fit are named", "[segmentation][yolov8]") {
  const cge::Letterbox lb = cge::make_letterbox({64, 64}, {64, 64});
  const int wrong_rows[] = {1, 115, 5};
  const cv::Mat p115(3, wrong_rows, CV_32F, cv::Scalar(0));
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::decode_yolov8_seg(p115, prototypes(16, 16), lb, {}); }),
             Catch::Contains("1x115x5") && Catch::Contains("1x116x5 and 1x32x16x16"));
  CHECK_THAT(
      cge_test::invalid_argument_message([&] { cge::decode_yolov8_seg(predictions(5, {}), prototypes(8, 8), lb, {}); }),
      Catch::Contains("1x32x8x8") && Catch::Contains("1x32x16x16"));
  cv::Mat p64;
  predictions(5, {}).convertTo(p64, CV_64F);
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::decode_yolov8_seg(p64, prototypes(16, 16), lb, {}); }),
             Catch::Contains("CV_64F"));
}

TEST_CASE("Yolov8Settings: values outside their ranges are named", "[segmentation][yolov8]") {
  const auto message = [](auto change) {
    cge::Yolov8Settings s;
    change(s);
    return cge_test::invalid_argument_message([&] { cge::check_settings(s); });
  };
  CHECK_NOTHROW(cge::check_settings({}));
  CHECK_THAT(message([](auto& s) { s.confidence_threshold = 0; }), Catch::Contains("confidence_threshold"));
  CHECK_THAT(message([](auto& s) { s.confidence_threshold = 1.5f; }), Catch::Contains("confidence_threshold"));
  CHECK_THAT(message([](auto& s) { s.nms_iou_threshold = -0.1f; }), Catch::Contains("nms_iou_threshold"));
  CHECK_THAT(message([](auto& s) { s.mask_threshold = 1; }), Catch::Contains("mask_threshold"));
  CHECK_THAT(message([](auto& s) { s.mask_threshold = std::nanf(""); }), Catch::Contains("mask_threshold"));
  CHECK_THAT(message([](auto& s) { s.max_detections = 0; }), Catch::Contains("max_detections"));
  CHECK_THAT(message([](auto& s) { s.mask_decoding = static_cast<cge::Yolov8MaskDecoding>(7); }),
             Catch::Contains("mask_decoding 7"));
  CHECK(std::string(cge::to_string(cge::Yolov8MaskDecoding::prototype_crop)) == "prototype_crop");
  CHECK(std::string(cge::to_string(cge::Yolov8MaskDecoding::retina)) == "retina");
  CHECK_THAT(message([](auto& s) { s.pad_value = 256; }), Catch::Contains("pad_value"));
  CHECK_THAT(message([](auto& s) { s.dynamic_class_ids = {0, 80}; }), Catch::Contains("80"));
}

// ---- the segmenter on hand-made ONNX files ----------------------------------------------------------

TEST_CASE("Yolov8Segmenter: missing, unreadable and non-ONNX model files are named", "[segmentation][yolov8]") {
  const cge_test::TempDir dir("cge_test_yolov8_files");
  const auto message = [](const std::string& path) {
    return cge_test::invalid_argument_message([&] { cge::Yolov8Segmenter s(path); });
  };
  const std::string missing = dir.file("missing.onnx");
  CHECK_THAT(message(missing), Catch::Contains(missing) && Catch::Contains("does not exist"));
  CHECK_THAT(message(dir.path().string()), Catch::Contains("is a directory"));

  const std::string text = dir.file("text.onnx");
  cge_test::onnx::write_file(text, "this is not a model\n");
  CHECK_THAT(message(text), Catch::Contains(text) && Catch::Contains("is not an ONNX model"));
  const std::string empty = dir.file("empty.onnx");
  cge_test::onnx::write_file(empty, "");
  CHECK_THAT(message(empty), Catch::Contains("is not an ONNX model"));
  const std::string model = cge_test::onnx::elementwise_model({1, 3, 64, 64});
  const std::string truncated = dir.file("truncated.onnx");
  cge_test::onnx::write_file(truncated, model.substr(0, model.size() / 2));
  CHECK_THAT(message(truncated), Catch::Contains("is not an ONNX model") && Catch::Contains("at byte"));
}

TEST_CASE("Yolov8Segmenter: ONNX models that are not YOLOv8-seg are named with their shapes",
          "[segmentation][yolov8]") {
  namespace onnx = cge_test::onnx;
  const cge_test::TempDir dir("cge_test_yolov8_models");
  const auto message = [&](const std::string& name, const std::string& bytes) {
    const std::string path = dir.file(name);
    onnx::write_file(path, bytes);
    return cge_test::invalid_argument_message([&] { cge::Yolov8Segmenter s(path); });
  };
  CHECK_THAT(message("relu.onnx", onnx::elementwise_model({1, 3, 64, 64})),
             Catch::Contains("relu.onnx") && Catch::Contains("not a YOLOv8-seg model") &&
                 Catch::Contains("1x116x84 and 1x32x16x16") && Catch::Contains("gives 1: 1x3x64x64"));
  CHECK_THAT(message("two.onnx", onnx::elementwise_model({1, 3, 64, 64}, 2)),
             Catch::Contains("gives 2: 1x3x64x64, 1x3x64x64"));
  CHECK_THAT(message("symbolic.onnx", onnx::elementwise_model({1, 3, -1, -1})),
             Catch::Contains("1x3x?x?") && Catch::Contains("fixed"));
  CHECK_THAT(message("odd.onnx", onnx::elementwise_model({1, 3, 48, 64})), Catch::Contains("multiples of 32"));
  CHECK_THAT(message("grey.onnx", onnx::elementwise_model({1, 1, 64, 64})), Catch::Contains("expected 1x3xHxW"));
  CHECK_THAT(message("inputs.onnx", onnx::elementwise_model({1, 3, 64, 64}, 1, {1, 3, 64, 64})),
             Catch::Contains("2 inputs"));

  onnx::YoloConstants c;
  c.prediction.assign(115, 0.f);
  c.prototype.assign(32, 0.f);
  CHECK_THAT(message("rows115.onnx", onnx::yolo_shaped_model(c)),
             Catch::Contains("1x116x21 and 1x32x8x8") && Catch::Contains("1x115x21, 1x32x8x8"));
  c.prediction.assign(116, 0.f);
  c.prototype.assign(31, 0.f);
  CHECK_THAT(message("planes31.onnx", onnx::yolo_shaped_model(c)), Catch::Contains("1x116x21, 1x31x8x8"));

  onnx::Message g;  // parses as ONNX, but OpenCV knows no such operator
  g.message_field(1, onnx::node("NoSuchOperator", {"images"}, {"out"}));
  g.message_field(11, onnx::value_info("images", {1, 3, 32, 32}));
  g.message_field(12, onnx::value_info("out", {1, 3, 32, 32}));
  CHECK_THAT(message("unknown.onnx", onnx::model(g)), Catch::Contains("OpenCV's DNN module cannot run the model"));
}

TEST_CASE("Yolov8Segmenter: end to end on a tiny model with constant outputs", "[segmentation][yolov8]") {
  namespace onnx = cge_test::onnx;
  const cge_test::TempDir dir("cge_test_yolov8_tiny");
  // Every anchor predicts the hand-worked detection; suppression keeps one.
  onnx::YoloConstants c;
  c.prediction.assign(kRows, 0.f);
  c.prediction[0] = kHandCx;
  c.prediction[1] = kHandCy;
  c.prediction[2] = c.prediction[3] = kHandSide;
  c.prediction[4 + cge::kCocoPerson] = kHandScore;
  c.prediction[kFirstCoefficient] = 1;
  c.prototype.assign(cge::kYolov8MaskCoefficients, 0.f);
  c.prototype[0] = kHandPrototype;
  const std::string path = dir.file("tiny.onnx");
  onnx::write_file(path, onnx::yolo_shaped_model(c));

  cge::Yolov8Segmenter segmenter(path);
  CHECK(segmenter.input_size() == cv::Size(32, 32));
  CHECK(segmenter.model_path() == path);
  CHECK(segmenter.dynamic_classes() == std::set<int>{cge::kCocoPerson});

  cv::Mat image(32, 64, CV_8UC3);
  cv::randu(image, 0, 256);
  const auto out = segmenter.segment({image, "frame"});
  REQUIRE(out.size() == 1);
  CHECK(out[0].class_id == cge::kCocoPerson);
  CHECK(out[0].score == kHandScore);
  CHECK(out[0].box_px == cv::Rect2f(16.f, 8.f, 16.f, 16.f));
  CHECK(out[0].dynamic);
  check_hand_worked_mask(out[0].mask);

  // Deterministic: the same frame again gives the same instances.
  const auto again = segmenter.segment({image, "frame"});
  REQUIRE(again.size() == 1);
  CHECK(again[0].box_px == out[0].box_px);
  CHECK(cv::norm(again[0].mask, out[0].mask, cv::NORM_INF) == 0);

  // A portrait image: padding left and right (scale 0.5, 8 px each side).
  const auto portrait = segmenter.segment({cv::Mat(64, 32, CV_8UC3, cv::Scalar::all(50)), "portrait"});
  REQUIRE(portrait.size() == 1);
  CHECK(portrait[0].box_px == cv::Rect2f(0.f, 24.f, 16.f, 16.f));

  // The dynamic class set.
  segmenter.set_dynamic_classes({56});
  CHECK_FALSE(segmenter.segment({image, "frame"})[0].dynamic);
  CHECK_THAT(cge_test::invalid_argument_message([&] { segmenter.set_dynamic_classes({80}); }), Catch::Contains("80"));
  CHECK(segmenter.dynamic_classes() == std::set<int>{56});

  // Settings are replaced only when valid.
  cge::Yolov8Settings strict;
  strict.confidence_threshold = 0.95f;
  segmenter.set_settings(strict);
  CHECK(segmenter.segment({image, "frame"}).empty());
  strict.max_detections = 0;
  CHECK_THROWS_AS(segmenter.set_settings(strict), std::invalid_argument);
  CHECK(segmenter.settings().max_detections == cge::Yolov8Settings{}.max_detections);

  // Images it cannot take.
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               segmenter.segment({cv::Mat(), "f1"});
             }),
             Catch::Contains("frame 'f1'") && Catch::Contains("empty"));
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               segmenter.segment({cv::Mat(8, 8, CV_8UC1), "f2"});
             }),
             Catch::Contains("CV_8UC1") && Catch::Contains("expected CV_8UC3"));
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               segmenter.segment({cv::Mat(8, 8, CV_16UC3), "f3"});
             }),
             Catch::Contains("CV_16UC3"));
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               segmenter.segment({cv::Mat(8, 8, CV_8UC4), "f4"});
             }),
             Catch::Contains("CV_8UC4"));

  // Moving hands the network over; the moved-from object says so instead of crashing.
  cge::Yolov8Segmenter moved = std::move(segmenter);
  CHECK(moved.segment({image, "frame"}).empty());  // still the strict settings
  CHECK_THROWS_AS(segmenter.segment({image, "frame"}), std::logic_error);
}

// ---- real data (../shared) ---------------------------------------------------------------------------

namespace {

constexpr const char* kTumFrame = "1341846313.592026";

struct PersonMatch {
  double iou = 0;        // best IoU of a Mask R-CNN person with a YOLOv8 person
  double contained = 0;  // fraction of that YOLOv8 mask inside the Mask R-CNN person
  int yolo_index = -1;
};

// The Mask R-CNN people of the frame: the mask image is a binary union (value 0 on people, 1
// elsewhere; checked against the RGB by eye), so each person is a connected component. Specks
// under 1% of the image are not people.
std::vector<cv::Mat> maskrcnn_people(const cv::Mat& union_mask) {
  cv::Mat labels;
  const int n = cv::connectedComponents(union_mask == 0, labels, 8, CV_32S);
  std::vector<cv::Mat> people;
  for (int k = 1; k < n; ++k) {
    cv::Mat person = labels == k;
    if (static_cast<std::size_t>(cv::countNonZero(person)) >= union_mask.total() / 100) people.push_back(person);
  }
  return people;
}

std::vector<PersonMatch> match_people(const std::vector<cv::Mat>& people,
                                      const std::vector<cge::SegmentedInstance>& instances) {
  std::vector<PersonMatch> matches;
  for (const cv::Mat& person : people) {
    PersonMatch best;
    for (std::size_t i = 0; i < instances.size(); ++i) {
      if (instances[i].class_id != cge::kCocoPerson) continue;
      const double inter = cv::countNonZero(person & instances[i].mask);
      const double uni = cv::countNonZero(person | instances[i].mask);
      if (uni > 0 && inter / uni > best.iou) {
        best.iou = inter / uni;
        best.contained = inter / cv::countNonZero(instances[i].mask);
        best.yolo_index = static_cast<int>(i);
      }
    }
    matches.push_back(best);
  }
  return matches;
}

// IoU of the frame's person mask: the union of the YOLOv8 person instances against the Mask R-CNN
// person mask, which is itself a union (no instances are stored).
double person_mask_iou(const cv::Mat& union_mask, const std::vector<cge::SegmentedInstance>& instances) {
  cv::Mat ours = cv::Mat::zeros(union_mask.size(), CV_8UC1);
  for (const auto& s : instances) {
    if (s.class_id == cge::kCocoPerson) ours |= s.mask;
  }
  const cv::Mat theirs = union_mask == 0;
  const double uni = cv::countNonZero(ours | theirs);
  return uni > 0 ? cv::countNonZero(ours & theirs) / uni : 0.0;
}

}  // namespace

TEST_CASE("Yolov8Segmenter 640 on TUM fr3 walking_xyz: both people (skipped without ../shared)",
          "[segmentation][yolov8][shared]") {
  const std::string model = shared_file("models/yolov8n-seg-640.onnx");
  const std::string rgb = shared_file(std::string("data/tum_fr3_walking_xyz/rgb/") + kTumFrame + ".png");
  const std::string reference =
      shared_file(std::string("data/tum_fr3_walking_xyz/mask_maskrcnn/") + kTumFrame + ".png");
  if (!std::filesystem::exists(model) || !std::filesystem::exists(rgb) || !std::filesystem::exists(reference)) {
    WARN("skipped: " << model << " or the TUM frame is absent");
    return;
  }
  cge::Yolov8Segmenter segmenter(model);
  CHECK(segmenter.input_size() == cv::Size(640, 640));
  const cv::Mat image = cv::imread(rgb, cv::IMREAD_COLOR);
  const cv::Mat union_mask = cv::imread(reference, cv::IMREAD_UNCHANGED);
  REQUIRE(union_mask.type() == CV_8UC1);
  const auto people = maskrcnn_people(union_mask);
  REQUIRE(people.size() == 2);

  const auto instances = segmenter.segment({image, kTumFrame});
  const auto matches = match_people(people, instances);
  // Each Mask R-CNN person is matched by its own YOLOv8 person. On this frame the Mask R-CNN masks
  // reach about 10 px beyond the people all round (98% and 99.99% of the YOLOv8 masks lie inside
  // them; eroding them by 8 px raises the IoUs from 0.69 / 0.85 to 0.82 / 0.92), which caps the IoU
  // of a tight mask: hence 0.65 per person, plus a containment check (docs/SEGMENTATION.md).
  REQUIRE(matches.size() == 2);
  CHECK(matches[0].yolo_index >= 0);
  CHECK(matches[1].yolo_index >= 0);
  CHECK(matches[0].yolo_index != matches[1].yolo_index);
  for (const auto& m : matches) {
    INFO("IoU " << m.iou << ", contained " << m.contained);
    CHECK(m.iou >= 0.65);
    CHECK(m.contained >= 0.95);
  }
  // The frame's person mask against the reference person mask: the IoU of at least 0.7.
  const double frame_iou = person_mask_iou(union_mask, instances);
  INFO("person-mask IoU " << frame_iou);
  CHECK(frame_iou >= 0.7);
  for (const auto& s : instances) {
    CHECK(s.dynamic == (s.class_id == cge::kCocoPerson));
    CHECK(s.mask.size() == image.size());
    CHECK(cv::Rect2f(0.f, 0.f, 640.f, 480.f).contains(s.box_px.tl()));
  }

  // The retina decoding (docs/SEGMENTATION.md compares the two orders on both annotated frames;
  // it is not the default because it is not better for every person) meets the same bounds.
  cge::Yolov8Settings retina;
  retina.mask_decoding = cge::Yolov8MaskDecoding::retina;
  segmenter.set_settings(retina);
  const auto retina_matches = match_people(people, segmenter.segment({image, kTumFrame}));
  REQUIRE(retina_matches.size() == 2);
  CHECK(retina_matches[0].yolo_index != retina_matches[1].yolo_index);
  for (const auto& m : retina_matches) {
    INFO("retina: IoU " << m.iou << ", contained " << m.contained);
    CHECK(m.yolo_index >= 0);
    CHECK(m.iou >= 0.65);
    CHECK(m.contained >= 0.95);
  }
  segmenter.set_settings({});

  // Deterministic: the same frame again gives identical instances.
  const auto again = segmenter.segment({image, kTumFrame});
  REQUIRE(again.size() == instances.size());
  for (std::size_t i = 0; i < again.size(); ++i) {
    CHECK(again[i].class_id == instances[i].class_id);
    CHECK(again[i].score == instances[i].score);
    CHECK(again[i].box_px == instances[i].box_px);
    CHECK(cv::norm(again[i].mask, instances[i].mask, cv::NORM_INF) == 0);
  }
}

TEST_CASE("Yolov8Segmenter 320 on TUM fr3 walking_xyz: loads and runs (skipped without ../shared)",
          "[segmentation][yolov8][shared]") {
  const std::string model = shared_file("models/yolov8n-seg-320.onnx");
  const std::string rgb = shared_file(std::string("data/tum_fr3_walking_xyz/rgb/") + kTumFrame + ".png");
  if (!std::filesystem::exists(model) || !std::filesystem::exists(rgb)) {
    WARN("skipped: " << model << " or the TUM frame is absent");
    return;
  }
  // Its IoUs are reported in docs/SEGMENTATION.md, not required here.
  cge::Yolov8Segmenter segmenter(model);
  CHECK(segmenter.input_size() == cv::Size(320, 320));
  const auto instances = segmenter.segment({cv::imread(rgb, cv::IMREAD_COLOR), kTumFrame});
  for (const auto& s : instances) CHECK(s.mask.size() == cv::Size(640, 480));
}
