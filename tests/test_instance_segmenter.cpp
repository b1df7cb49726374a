#include <catch2/catch.hpp>

#include <vector>

#include <opencv2/core.hpp>

#include "cge/segmentation/instance_segmenter.hpp"
#include "test_support.hpp"

namespace {

// An instance whose mask is the rectangle r of a w x h image.
cge::SegmentedInstance rect_instance(int id, int class_id, bool dynamic, cv::Rect r, cv::Size size) {
  cge::SegmentedInstance s;
  s.id = id;
  s.class_id = class_id;
  s.dynamic = dynamic;
  s.box_px = cv::Rect2f(static_cast<float>(r.x), static_cast<float>(r.y), static_cast<float>(r.width),
                        static_cast<float>(r.height));
  s.mask = cv::Mat(size, CV_8UC1, cv::Scalar(0));
  s.mask(r).setTo(255);
  return s;
}

}  // namespace

TEST_CASE("frame_stem: the RGB file name without directory and extension", "[segmentation]") {
  CHECK(cge::frame_stem("rgb/1341846313.592026.png") == "1341846313.592026");
  CHECK(cge::frame_stem("/data/seq/rgb/000017.jpg") == "000017");
  CHECK(cge::frame_stem("frame") == "frame");
}

TEST_CASE("union_dynamic_masks: pixel-wise OR of the dynamic instances only", "[segmentation]") {
  const cv::Size size(12, 8);
  const std::vector<cge::SegmentedInstance> instances = {
      rect_instance(1, 0, true, cv::Rect(0, 0, 4, 4), size),    // person
      rect_instance(2, 56, false, cv::Rect(2, 2, 6, 6), size),  // chair: not dynamic
      rect_instance(3, 0, true, cv::Rect(3, 3, 5, 2), size),    // person overlapping the first
  };
  const cv::Mat u = cge::union_dynamic_masks(instances, size);
  REQUIRE(u.type() == CV_8UC1);
  REQUIRE(u.size() == size);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const bool expected = (x < 4 && y < 4) || (x >= 3 && x < 8 && y >= 3 && y < 5);
      CHECK(u.at<unsigned char>(y, x) == (expected ? 255 : 0));
    }
  }
  const cv::Mat none = cge::union_dynamic_masks({}, size);
  CHECK(cv::countNonZero(none) == 0);
  CHECK(none.size() == size);
}

TEST_CASE("union_dynamic_masks: wrong mask sizes and empty images are named", "[segmentation]") {
  const auto bad = rect_instance(7, 0, true, cv::Rect(0, 0, 2, 2), cv::Size(5, 5));
  const std::string msg = cge_test::invalid_argument_message([&] { cge::union_dynamic_masks({bad}, cv::Size(6, 5)); });
  CHECK_THAT(msg, Catch::Contains("instance 7") && Catch::Contains("5 x 5") && Catch::Contains("6 x 5"));
  // A static instance's mask is not read at all.
  auto ignored = bad;
  ignored.dynamic = false;
  CHECK_NOTHROW(cge::union_dynamic_masks({ignored}, cv::Size(6, 5)));
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::union_dynamic_masks({}, cv::Size(0, 5)); }),
             Catch::Contains("empty"));
}

TEST_CASE("instance_label_image: ids where masks are, the earlier instance on top", "[segmentation]") {
  const cv::Size size(10, 6);
  const std::vector<cge::SegmentedInstance> instances = {
      rect_instance(300, 0, true, cv::Rect(0, 0, 5, 5), size),
      rect_instance(65535, 56, false, cv::Rect(3, 1, 7, 5), size),
  };
  const cv::Mat labels = cge::instance_label_image(instances, size);
  REQUIRE(labels.type() == CV_16UC1);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      int expected = 0;
      if (x >= 3 && y >= 1) expected = 65535;
      if (x < 5 && y < 5) expected = 300;  // first in the list wins
      CHECK(labels.at<std::uint16_t>(y, x) == expected);
    }
  }
}

TEST_CASE("instance_label_image: invalid and repeated ids are errors", "[segmentation]") {
  const cv::Size size(4, 4);
  CHECK_THAT(cge_test::invalid_argument_message(
                 [&] { cge::instance_label_image({rect_instance(0, 0, true, cv::Rect(0, 0, 1, 1), size)}, size); }),
             Catch::Contains("instance id 0"));
  CHECK_THAT(cge_test::invalid_argument_message(
                 [&] { cge::instance_label_image({rect_instance(65536, 0, true, cv::Rect(0, 0, 1, 1), size)}, size); }),
             Catch::Contains("65536"));
  CHECK_THAT(cge_test::invalid_argument_message([&] {
               cge::instance_label_image({rect_instance(2, 0, true, cv::Rect(0, 0, 1, 1), size),
                                          rect_instance(2, 0, true, cv::Rect(1, 1, 1, 1), size)},
                                         size);
             }),
             Catch::Contains("used twice"));
  auto wrong_type = rect_instance(1, 0, true, cv::Rect(0, 0, 1, 1), size);
  wrong_type.mask.convertTo(wrong_type.mask, CV_16U);
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::instance_label_image({wrong_type}, size); }),
             Catch::Contains("CV_16UC1"));
}

TEST_CASE("to_semantic_instance: box centre, class and dynamic flag", "[segmentation]") {
  cge::SegmentedInstance s;
  s.box_px = cv::Rect2f(10.f, 20.f, 30.f, 41.f);
  s.class_id = 56;
  s.dynamic = false;
  const auto semantic = cge::to_semantic_instance<double>(s);
  CHECK(semantic.centre_px.x() == 25.0);
  CHECK(semantic.centre_px.y() == 40.5);
  CHECK(semantic.class_id == 56);
  CHECK_FALSE(semantic.dynamic);
}

TEST_CASE("check_coco_class_ids: ids outside 0 .. 79 are named", "[segmentation]") {
  CHECK_NOTHROW(cge::check_coco_class_ids({0, 56, 79}, "test"));
  CHECK_THAT(cge_test::invalid_argument_message([] {
               cge::check_coco_class_ids({0, 80}, "test");
             }),
             Catch::Contains("80"));
  CHECK_THAT(cge_test::invalid_argument_message([] { cge::check_coco_class_ids({-1}, "test"); }),
             Catch::Contains("-1"));
}

TEST_CASE("filter_box: a box clipped in float stays inside the image for the filter", "[segmentation]") {
  const cv::Size image(640, 480);
  cge::SegmentedInstance inside;
  inside.box_px = cv::Rect2f(10.25f, 20.5f, 100.f, 50.f);
  const cge::PixelBox a = cge::filter_box(inside, image);
  CHECK(a.x_min_px == 10.25);
  CHECK(a.y_min_px == 20.5);
  CHECK(a.width_px == 100.0);
  CHECK(a.height_px == 50.0);
  CHECK_NOTHROW(a.validate(image.width, image.height, "box"));

  // x + width in float rounds past the border (x = 0.1f is not exact): clamped to end at 640, 480.
  cge::SegmentedInstance at_border;
  at_border.box_px = cv::Rect2f(0.1f, 0.3f, 639.9f + 1e-4f, 479.7f + 1e-4f);
  const cge::PixelBox b = cge::filter_box(at_border, image);
  CHECK(b.x_min_px + b.width_px <= 640.0);
  CHECK(b.y_min_px + b.height_px <= 480.0);
  CHECK(b.x_min_px == static_cast<double>(0.1f));
  CHECK_NOTHROW(b.validate(image.width, image.height, "box"));
}
