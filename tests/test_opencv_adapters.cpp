// The OpenCV adapters (cge/opencv.hpp): cv::KeyPoint and cv::Point_ as points, cv::Mat depth
// (CV_16U with a scale, CV_32F metres), CV_8U binary masks, instance-label views, cv::Rect boxes.
// Each is checked pixel by pixel against values worked out by hand or read with cv::Mat::at, and
// DepthMADFilter gives bit-identical results through the adapters and through the core types.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/core/mask.hpp"
#include "cge/frontend/depth_mad_filter.hpp"
#include "cge/opencv.hpp"
#include "cge/opencv/disc_kernel.hpp"
#include "test_support.hpp"

namespace {

/// A depth image of doubles, to compare DepthView's value / scale with the core bit for bit.
struct DoubleDepth {
  int width = 0, height = 0;
  std::vector<double> metres;
};

}  // namespace

template <>
struct cge::traits::DepthImage<DoubleDepth> {
  static int width(const DoubleDepth& d) { return d.width; }
  static int height(const DoubleDepth& d) { return d.height; }
  static double depth_m(const DoubleDepth& d, int col, int row) {
    return d.metres[static_cast<std::size_t>(row) * static_cast<std::size_t>(d.width) + static_cast<std::size_t>(col)];
  }
};

TEST_CASE("cv::KeyPoint and cv::Point_ are point types", "[opencv][adapters]") {
  const cv::KeyPoint k(12.25f, 7.5f, 31.0f, 45.0f, 0.5f, 2);
  REQUIRE(cge::point_x(k) == 12.25f);
  REQUIRE(cge::point_y(k) == 7.5f);
  REQUIRE(cge::point_x(cv::Point2f(1.5f, 2.5f)) == 1.5f);
  REQUIRE(cge::point_y(cv::Point2d(3.25, 4.75)) == 4.75);
  REQUIRE(cge::point_x(cv::Point(9, 8)) == 9);
  REQUIRE(cge::point_y(cv::Point(9, 8)) == 8);
}

TEST_CASE("DepthView: CV_16U with a scale, CV_32F in metres", "[opencv][adapters][depth]") {
  SECTION("16-bit TUM depth: metres = value / 5000, 0 = no measurement") {
    cv::Mat raw(3, 4, CV_16UC1, cv::Scalar(0));
    raw.at<std::uint16_t>(0, 1) = 5000;
    raw.at<std::uint16_t>(1, 2) = 12345;
    raw.at<std::uint16_t>(2, 3) = 65535;
    const cge::opencv::DepthView view = cge::opencv::DepthView::from_u16(raw);
    using T = cge::traits::DepthImage<cge::opencv::DepthView>;
    REQUIRE(T::width(view) == 4);
    REQUIRE(T::height(view) == 3);
    REQUIRE(view.units_per_metre() == 5000);
    REQUIRE(T::depth_m(view, 1, 0) == 1.0);
    REQUIRE(T::depth_m(view, 2, 1) == 12345.0 / 5000.0);
    REQUIRE(T::depth_m(view, 3, 2) == 65535.0 / 5000.0);
    REQUIRE(T::depth_m(view, 0, 0) == 0.0);
    REQUIRE_FALSE(cge::is_valid_depth_m(T::depth_m(view, 0, 0)));
    const cge::opencv::DepthView mm(raw, 1000.0);  // millimetres (Kinect, RealSense)
    REQUIRE(mm.depth_m(2, 1) == 12.345);
  }
  SECTION("a region of interest (not continuous) reads its own pixels") {
    cv::Mat raw(10, 10, CV_16UC1);
    for (int r = 0; r < 10; ++r)
      for (int c = 0; c < 10; ++c) raw.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(100 * r + c);
    const cv::Mat roi = raw(cv::Rect(3, 2, 4, 5));
    REQUIRE_FALSE(roi.isContinuous());
    const cge::opencv::DepthView view(roi, 100.0);
    REQUIRE(view.width() == 4);
    REQUIRE(view.height() == 5);
    for (int r = 0; r < 5; ++r)
      for (int c = 0; c < 4; ++c) REQUIRE(view.depth_m(c, r) == (100.0 * (r + 2) + (c + 3)) / 100.0);
  }
  SECTION("float depth in metres: values and NaN pass through") {
    cv::Mat metres(2, 2, CV_32FC1, cv::Scalar(1.25f));
    metres.at<float>(1, 0) = std::numeric_limits<float>::quiet_NaN();
    const cge::opencv::DepthView view = cge::opencv::DepthView::from_metres(metres);
    REQUIRE(view.depth_m(0, 0) == 1.25);
    REQUIRE(std::isnan(view.depth_m(0, 1)));
  }
  SECTION("wrong type, bad scale or empty: clear errors") {
    const auto message = [](const cv::Mat& m, double scale) {
      return cge_test::invalid_argument_message([&] { cge::opencv::DepthView(m, scale); });
    };
    const cv::Mat u16(2, 2, CV_16UC1, cv::Scalar(1));
    REQUIRE_THAT(message(cv::Mat(2, 2, CV_8UC1), 1), Catch::Contains("CV_8UC1") && Catch::Contains("CV_16UC1"));
    REQUIRE_THAT(message(cv::Mat(2, 2, CV_16UC3), 5000), Catch::Contains("CV_16UC3"));
    REQUIRE_THAT(message(cv::Mat(2, 2, CV_64FC1), 1), Catch::Contains("CV_64FC1"));
    REQUIRE_THAT(message(cv::Mat(), 5000), Catch::Contains("empty"));
    REQUIRE_THAT(message(u16, 0), Catch::Contains("units_per_metre"));
    REQUIRE_THAT(message(u16, -5000), Catch::Contains("units_per_metre"));
    REQUIRE_THAT(message(u16, std::numeric_limits<double>::quiet_NaN()), Catch::Contains("units_per_metre"));
    REQUIRE_THAT(message(u16, std::numeric_limits<double>::infinity()), Catch::Contains("units_per_metre"));
    REQUIRE_THAT(
        cge_test::invalid_argument_message([] { cge::opencv::DepthView::from_metres(cv::Mat(2, 2, CV_16UC1)); }),
        Catch::Contains("from_metres") && Catch::Contains("CV_32FC1"));
    REQUIRE_THAT(cge_test::invalid_argument_message([] { cge::opencv::DepthView::from_u16(cv::Mat(2, 2, CV_32FC1)); }),
                 Catch::Contains("from_u16"));
  }
}

TEST_CASE("CV_8U binary masks and instance-label views", "[opencv][adapters][mask]") {
  using MatMask = cge::traits::Mask<cv::Mat>;
  using Instance = cge::traits::Mask<cge::opencv::InstanceMask>;
  SECTION("binary: any non-zero byte is set") {
    cv::Mat m(3, 5, CV_8UC1, cv::Scalar(0));
    m.at<std::uint8_t>(1, 2) = 255;
    m.at<std::uint8_t>(2, 4) = 1;
    REQUIRE(MatMask::width(m) == 5);
    REQUIRE(MatMask::height(m) == 3);
    REQUIRE_FALSE(MatMask::empty(m));
    REQUIRE(MatMask::empty(cv::Mat()));
    int set = 0;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 5; ++c) set += MatMask::is_set(m, c, r) ? 1 : 0;
    REQUIRE(set == 2);
    REQUIRE(MatMask::is_set(m, 2, 1));
    REQUIRE(MatMask::is_set(m, 4, 2));
    REQUIRE_NOTHROW(cge::check_mask_size(m, 5, 3, "mask"));
    REQUIRE_THROWS_AS(cge::check_mask_size(m, 5, 4, "mask"), std::invalid_argument);
  }
  SECTION("binary: another type is an error, not a misreading") {
    const cv::Mat labels(3, 5, CV_16UC1, cv::Scalar(1));
    REQUIRE_THAT(cge_test::invalid_argument_message([&] { MatMask::width(labels); }),
                 Catch::Contains("CV_16UC1") && Catch::Contains("InstanceMask"));
    REQUIRE_THROWS_AS(MatMask::is_set(labels, 0, 0), std::invalid_argument);
  }
  SECTION("instance labels: the pixels equal to one id") {
    cv::Mat labels(4, 6, CV_16UC1, cv::Scalar(0));
    labels.at<std::uint16_t>(0, 0) = 1;
    labels.at<std::uint16_t>(1, 3) = 300;
    labels.at<std::uint16_t>(2, 3) = 300;
    labels.at<std::uint16_t>(3, 5) = 2;
    const cge::opencv::InstanceMask id300(labels, 300);
    REQUIRE(Instance::width(id300) == 6);
    REQUIRE(Instance::height(id300) == 4);
    REQUIRE(id300.instance_id() == 300);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 6; ++c) REQUIRE(Instance::is_set(id300, c, r) == (labels.at<std::uint16_t>(r, c) == 300));
    // Its bounding box is the one OpenCV finds.
    const auto box = cge::bounding_box(id300);
    REQUIRE(box.has_value());
    const cv::Rect rect = cv::boundingRect(labels == 300);
    REQUIRE(box->x_min_px == rect.x);
    REQUIRE(box->y_min_px == rect.y);
    REQUIRE(box->width_px == rect.width);
    REQUIRE(box->height_px == rect.height);
    REQUIRE_FALSE(cge::bounding_box(cge::opencv::InstanceMask(labels, 7)).has_value());  // absent id

    cv::Mat labels8(2, 2, CV_8UC1, cv::Scalar(0));
    labels8.at<std::uint8_t>(1, 1) = 9;
    const cge::opencv::InstanceMask id9(labels8, 9);
    REQUIRE(id9.is_set(1, 1));
    REQUIRE_FALSE(id9.is_set(0, 1));
    REQUIRE(Instance::empty(cge::opencv::InstanceMask(cv::Mat(), 1)));
  }
  SECTION("instance labels: bad ids and types") {
    const cv::Mat labels(2, 2, CV_16UC1, cv::Scalar(0));
    const cv::Mat labels8(2, 2, CV_8UC1, cv::Scalar(0));
    REQUIRE_THAT(cge_test::invalid_argument_message([&] { cge::opencv::InstanceMask(labels, 0); }),
                 Catch::Contains("instance id 0") && Catch::Contains("background"));
    REQUIRE_THAT(cge_test::invalid_argument_message([&] { cge::opencv::InstanceMask(labels, 65536); }),
                 Catch::Contains("65536"));
    REQUIRE_THAT(cge_test::invalid_argument_message([&] { cge::opencv::InstanceMask(labels8, 256); }),
                 Catch::Contains("1..255"));
    REQUIRE_THAT(cge_test::invalid_argument_message([] { cge::opencv::InstanceMask(cv::Mat(2, 2, CV_32FC1), 1); }),
                 Catch::Contains("CV_32FC1"));
  }
}

TEST_CASE("cv::Rect converts to PixelBox without offsets", "[opencv][adapters][box]") {
  const cge::PixelBox box = cge::opencv::to_pixel_box(cv::Rect(10, 20, 30, 40));
  REQUIRE(box.x_min_px == 10);
  REQUIRE(box.y_min_px == 20);
  REQUIRE(box.width_px == 30);
  REQUIRE(box.height_px == 40);
  const cge::PixelSpan span = box.pixels();  // the same pixels as the cv::Rect
  REQUIRE(span.col_begin == 10);
  REQUIRE(span.col_end == 40);
  REQUIRE(span.row_begin == 20);
  REQUIRE(span.row_end == 60);
  const cge::PixelBox fractional = cge::opencv::to_pixel_box(cv::Rect2d(1.5, 2.25, 3.0, 4.5));
  REQUIRE(fractional.x_max_px() == 4.5);
  REQUIRE(fractional.y_max_px() == 6.75);
  const cv::Rect2d back = cge::opencv::to_rect2d(fractional);
  REQUIRE(back == cv::Rect2d(1.5, 2.25, 3.0, 4.5));
}

TEST_CASE("disc_kernel: the Euclidean disc, hand-worked at radii 0, 1 and 2", "[opencv][adapters][disc]") {
  const auto rows = [](const cv::Mat& k) {
    std::vector<std::string> out;
    for (int y = 0; y < k.rows; ++y) {
      std::string row;
      for (int x = 0; x < k.cols; ++x) row += k.at<std::uint8_t>(y, x) ? '#' : '.';
      out.push_back(row);
    }
    return out;
  };
  CHECK(rows(cge::opencv::disc_kernel(0)) == std::vector<std::string>{"#"});
  CHECK(rows(cge::opencv::disc_kernel(1)) == std::vector<std::string>{".#.", "###", ".#."});
  // Radius 2: the corners (dx, dy) = (+-2, +-1), (+-1, +-2) lie at sqrt(5) > 2, outside.
  CHECK(rows(cge::opencv::disc_kernel(2)) == std::vector<std::string>{"..#..", ".###.", "#####", ".###.", "..#.."});
  CHECK(cge::opencv::disc_kernel(3).type() == CV_8UC1);
  CHECK_THROWS_AS(cge::opencv::disc_kernel(-1), std::invalid_argument);
}

TEST_CASE("DepthMADFilter through the adapters equals the core types bit for bit", "[opencv][adapters][depth_mad]") {
  const int width = 64, height = 48;
  std::mt19937 fixture(31);
  cv::Mat raw(height, width, CV_16UC1);
  cv::Mat metres(height, width, CV_32FC1);
  cv::Mat labels(height, width, CV_16UC1, cv::Scalar(0));
  cv::circle(labels, cv::Point(20, 24), 12, cv::Scalar(4), cv::FILLED);
  cv::rectangle(labels, cv::Rect(36, 10, 20, 30), cv::Scalar(17), cv::FILLED);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const bool person = labels.at<std::uint16_t>(r, c) != 0;
      // 10% holes; people at 1.2 to 1.5 m, and so is a third of the background (what masks miss).
      const auto roll = fixture() % 100;
      const bool near = person || roll < 40;
      const std::uint16_t value =
          roll < 10 ? 0 : static_cast<std::uint16_t>(near ? 6000 + fixture() % 1500 : 4000 + fixture() % 20000);
      raw.at<std::uint16_t>(r, c) = value;
      metres.at<float>(r, c) =
          value == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(value) / 5000.f;
    }
  // The core twins of the same data.
  DoubleDepth double_depth{width, height, {}};
  cge::FloatDepthImage float_depth(width, height);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      double_depth.metres.push_back(raw.at<std::uint16_t>(r, c) / 5000.0);
      float_depth.at(c, r) = metres.at<float>(r, c);
    }
  const std::vector<int> ids{4, 17};
  std::vector<cge::opencv::InstanceMask> views;
  std::vector<cv::Mat> binaries;
  std::vector<cge::BinaryMask> cores;
  std::vector<cge::PixelBox> boxes;
  for (const int id : ids) {
    views.emplace_back(labels, id);
    binaries.push_back(labels == id);
    cge::BinaryMask core(width, height);
    for (int r = 0; r < height; ++r)
      for (int c = 0; c < width; ++c) core.at(c, r) = labels.at<std::uint16_t>(r, c) == id ? 1 : 0;
    cores.push_back(core);
    // Boxes larger than the masks, so that the depth test has work to do.
    cv::Rect rect = cv::boundingRect(labels == id);
    rect = (rect + cv::Size(8, 8)) - cv::Point(4, 4);
    rect &= cv::Rect(0, 0, width, height);
    boxes.push_back(cge::opencv::to_pixel_box(rect));
  }
  std::vector<cv::KeyPoint> cv_kps;
  std::vector<std::array<float, 2>> core_kps;
  for (int i = 0; i < 300; ++i) {
    const float x = static_cast<float>(fixture() % 6400) / 100.f;
    const float y = static_cast<float>(fixture() % 4800) / 100.f;
    cv_kps.emplace_back(x, y, 7.f);
    core_kps.push_back({x, y});
  }

  std::vector<cge::DynamicInstance<cge::opencv::InstanceMask>> by_view;
  std::vector<cge::DynamicInstance<cv::Mat>> by_binary;
  std::vector<cge::DynamicInstance<cge::BinaryMask>> by_core;
  for (std::size_t j = 0; j < ids.size(); ++j) {
    by_view.push_back(cge::dynamic_instance(views[j], boxes[j], 0));
    by_binary.push_back(cge::dynamic_instance(binaries[j], boxes[j], 0));
    by_core.push_back(cge::dynamic_instance(cores[j], boxes[j], 0));
  }

  cge::DepthMADSettings settings;
  settings.disc_radius_px = 2;
  cge::DepthMADFilter<> f(settings);
  const auto same = [](const cge::DepthMADResult& a, const cge::DepthMADResult& b) {
    REQUIRE(a.labels == b.labels);
    REQUIRE(a.instances.size() == b.instances.size());
    for (std::size_t j = 0; j < a.instances.size(); ++j) {
      REQUIRE(a.instances[j].valid_samples == b.instances[j].valid_samples);
      REQUIRE(a.instances[j].samples_off_mask == b.instances[j].samples_off_mask);
      REQUIRE(a.instances[j].mean_depth_m == b.instances[j].mean_depth_m);
      REQUIRE(a.instances[j].mad_m == b.instances[j].mad_m);
    }
  };

  f.engine.seed(3);
  const cge::DepthMADResult u16_view = f.filter(cv_kps, cge::opencv::DepthView::from_u16(raw), by_view);
  f.engine.seed(3);
  const cge::DepthMADResult u16_core = f.filter(core_kps, double_depth, by_core);
  same(u16_view, u16_core);
  f.engine.seed(3);
  same(f.filter(cv_kps, cge::opencv::DepthView::from_u16(raw), by_binary), u16_core);
  f.engine.seed(3);
  const cge::DepthMADResult f32_view = f.filter(cv_kps, cge::opencv::DepthView::from_metres(metres), by_view);
  f.engine.seed(3);
  same(f32_view, f.filter(core_kps, float_depth, by_core));
  // The fixture exercises every label.
  REQUIRE(u16_view.dynamic_by_mask_count > 0);
  REQUIRE(u16_view.dynamic_by_mad_count > 0);
  REQUIRE(u16_view.static_count > 0);
  REQUIRE(u16_view.instances[0].mad_test_applied);
  REQUIRE(u16_view.instances[1].mad_test_applied);

  // Sizes that differ are caught through the adapters too.
  const cv::Mat small = cv::Mat::zeros(10, 10, CV_8UC1);
  const std::vector<cge::DynamicInstance<cv::Mat>> wrong{cge::dynamic_instance(small, cge::PixelBox{0, 0, 5, 5}, 0)};
  REQUIRE_THAT(
      cge_test::invalid_argument_message([&] { f.filter(cv_kps, cge::opencv::DepthView::from_u16(raw), wrong); }),
      Catch::Contains("instance #0") && Catch::Contains("10 x 10"));
}
