// The dynamic-feature leak count (cge/slam/moving_keypoints.hpp, FrameRecord::moving_keypoints and
// moving_kept): hand-built keypoints and masks, and the System on rendered frames against oracles
// that read the label images themselves.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/presets.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/slam/frame.hpp"
#include "cge/slam/label_instances.hpp"
#include "cge/slam/moving_keypoints.hpp"
#include "cge/slam/output_files.hpp"
#include "cge/slam/system.hpp"

namespace {

using cge::FeatureLabel;
using cge::slam::DynamicMode;

cv::KeyPoint keypoint_at(float x, float y) { return cv::KeyPoint(cv::Point2f(x, y), 7.f); }

cge::PinholeIntrinsics<double> intrinsics_of(const cge::sim::PinholeCamera& c) {
  return {c.fx_px, c.fy_px, c.cx_px, c.cy_px};
}

/// Oracle of the ground truth: the pixels of every instance the renderer says moves.
cv::Mat moving_pixels(const cge::sim::SequenceRenderer& renderer, const cv::Mat& labels) {
  cv::Mat mask(labels.size(), CV_8UC1, cv::Scalar(0));
  for (const cge::sim::InstanceInfo& i : renderer.instances()) {
    if (!i.moving) continue;
    for (int y = 0; y < labels.rows; ++y) {
      for (int x = 0; x < labels.cols; ++x) {
        if (labels.at<std::uint16_t>(y, x) == i.id) mask.at<std::uint8_t>(y, x) = 1;  // any non-zero value
      }
    }
  }
  return mask;
}

/// Keypoints of a frame on the mask, by the documented rounding, counted here independently.
int on_mask(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& mask) {
  int n = 0;
  for (const cv::KeyPoint& kp : keypoints) {
    const int x = std::clamp(static_cast<int>(std::floor(kp.pt.x + 0.5f)), 0, mask.cols - 1);
    const int y = std::clamp(static_cast<int>(std::floor(kp.pt.y + 0.5f)), 0, mask.rows - 1);
    n += mask.at<std::uint8_t>(y, x) != 0;
  }
  return n;
}

}  // namespace

TEST_CASE("count_moving_keypoints: hand-built keypoints on a rectangle, rounding and clamping", "[leak]") {
  // Moving body: columns 10 .. 19, rows 5 .. 9 of a 40 x 20 image, plus the bottom-right corner.
  cv::Mat mask(20, 40, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(10, 5, 10, 5)).setTo(200);
  mask.at<std::uint8_t>(19, 39) = 1;
  const std::vector<cv::KeyPoint> keypoints = {
      keypoint_at(12, 7),        // inside
      keypoint_at(9.5f, 7),      // rounds (half away from zero) to column 10: inside
      keypoint_at(9.49f, 7),     // column 9: outside
      keypoint_at(19.4f, 9.4f),  // (19, 9): inside
      keypoint_at(19.5f, 9),     // column 20: outside
      keypoint_at(15, 4.6f),     // row 5: inside
      keypoint_at(55, 30),       // beyond the image: clamped to (39, 19), inside
      keypoint_at(0, 0),         // outside
  };
  const std::vector<FeatureLabel> labels = {FeatureLabel::static_feature, FeatureLabel::dynamic_by_mask,
                                            FeatureLabel::static_feature, FeatureLabel::dynamic_by_mad,
                                            FeatureLabel::static_feature, FeatureLabel::static_feature,
                                            FeatureLabel::static_feature, FeatureLabel::dynamic_by_mask};
  // Inside: 0, 1, 3, 5, 6; of those static: 0, 5, 6.
  const cge::slam::MovingKeypointCounts c = cge::slam::count_moving_keypoints(keypoints, labels, mask);
  CHECK(c.moving_keypoints == 5);
  CHECK(c.moving_kept == 3);

  // Every label static (mode none): every moving keypoint is kept.
  const std::vector<FeatureLabel> all_static(keypoints.size(), FeatureLabel::static_feature);
  const cge::slam::MovingKeypointCounts none = cge::slam::count_moving_keypoints(keypoints, all_static, mask);
  CHECK(none.moving_kept == none.moving_keypoints);
  CHECK(none.moving_keypoints == 5);

  // A mask covering nothing: 0 of 0.
  const cge::slam::MovingKeypointCounts nothing =
      cge::slam::count_moving_keypoints(keypoints, labels, cv::Mat::zeros(20, 40, CV_8UC1));
  CHECK(nothing.moving_keypoints == 0);
  CHECK(nothing.moving_kept == 0);

  CHECK_THROWS_AS(cge::slam::count_moving_keypoints(keypoints, labels, cv::Mat()), std::invalid_argument);
  CHECK_THROWS_AS(cge::slam::count_moving_keypoints(keypoints, labels, cv::Mat::zeros(20, 40, CV_16UC1)),
                  std::invalid_argument);
  const std::vector<FeatureLabel> short_labels(3, FeatureLabel::static_feature);
  CHECK_THROWS_AS(cge::slam::count_moving_keypoints(keypoints, short_labels, mask), std::invalid_argument);
}

TEST_CASE("moving_mask_of: the union of the instances known to move", "[leak]") {
  const cv::Size size(8, 6);
  const auto instance = [&](int id, cv::Rect box, std::optional<bool> moving) {
    cge::SegmentedInstance i;
    i.id = id;
    i.mask = cv::Mat::zeros(size, CV_8UC1);
    i.mask(box).setTo(255);
    i.moving = moving;
    return i;
  };
  const std::vector<cge::SegmentedInstance> instances = {
      instance(1, cv::Rect(0, 0, 2, 2), true), instance(2, cv::Rect(4, 0, 2, 2), false),
      instance(3, cv::Rect(0, 4, 2, 2), std::nullopt), instance(4, cv::Rect(6, 4, 2, 2), true)};
  const cv::Mat mask = cge::slam::moving_mask_of(instances, size);
  REQUIRE(mask.type() == CV_8UC1);
  REQUIRE(mask.size() == size);
  CHECK(cv::countNonZero(mask) == 8);  // instances 1 and 4, 4 pixels each
  CHECK(mask.at<std::uint8_t>(0, 0) == 255);
  CHECK(mask.at<std::uint8_t>(5, 7) == 255);
  CHECK(mask.at<std::uint8_t>(0, 4) == 0);  // not moving
  CHECK(mask.at<std::uint8_t>(4, 0) == 0);  // unknown
  CHECK(cv::countNonZero(cge::slam::moving_mask_of({}, size)) == 0);
  std::vector<cge::SegmentedInstance> bad = {instance(1, cv::Rect(0, 0, 2, 2), true)};
  bad[0].mask = cv::Mat::zeros(3, 3, CV_8UC1);
  CHECK_THROWS_AS(cge::slam::moving_mask_of(bad, size), std::invalid_argument);
}

TEST_CASE("System: moving_keypoints and moving_kept on rendered walking frames, by mode", "[leak]") {
  const cge::sim::SequenceRenderer renderer(cge::sim::make_preset("walking_xyz", 12, 4));
  std::map<int, int> classes;
  for (const auto& i : renderer.instances()) classes[i.id] = i.class_id;
  const cge::PinholeIntrinsics<double> intrinsics = intrinsics_of(renderer.camera());
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(11, 11));

  // eroded: the instances' masks lose a 5-pixel rim (a network that misses the outline).
  const auto run = [&](DynamicMode mode, bool eroded, bool empty_truth) {
    cge::slam::SystemSettings settings;
    settings.mode = mode;
    cge::slam::System system(settings, intrinsics);
    for (int k = 0; k < renderer.frame_count(); ++k) {
      const cge::sim::RenderedFrame f = renderer.render(k);
      std::vector<cge::SegmentedInstance> instances =
          cge::slam::instances_from_label_image(f.instance_labels, classes, {cge::kCocoPerson});
      if (eroded) {
        for (auto& inst : instances) cv::erode(inst.mask, inst.mask, disc);
      }
      cge::slam::FrameInput in;
      in.index = f.index;
      in.timestamp_s = f.timestamp_s;
      in.bgr = f.rgb;
      in.depth = f.depth;
      in.moving_mask = empty_truth ? cv::Mat::zeros(f.rgb.size(), CV_8UC1) : moving_pixels(renderer, f.instance_labels);
      system.process(in, instances);
    }
    return system.frames();
  };

  // Oracle per frame: the keypoints FrameMaker extracts (deterministic), counted on the truth here.
  cge::slam::SystemSettings settings;
  cge::slam::FrameMaker maker(settings, intrinsics);
  std::vector<int> moving(static_cast<std::size_t>(renderer.frame_count()));
  std::vector<int> leak_eroded_y(moving.size());
  int total_moving = 0;
  for (int k = 0; k < renderer.frame_count(); ++k) {
    const cge::sim::RenderedFrame f = renderer.render(k);
    const cge::slam::Frame frame = maker.extract(f.index, f.timestamp_s, f.rgb, f.depth);
    const cv::Mat truth = moving_pixels(renderer, f.instance_labels);
    moving[static_cast<std::size_t>(k)] = on_mask(frame.keypoints, truth);
    total_moving += moving[static_cast<std::size_t>(k)];
    // Mode Y with eroded person masks keeps the moving keypoints off the eroded masks.
    cv::Mat eroded_person(truth.size(), CV_8UC1, cv::Scalar(0));
    for (const auto& [id, cls] : classes) {
      if (cls != cge::kCocoPerson) continue;
      cv::Mat m = f.instance_labels == id;
      cv::erode(m, m, disc);
      eroded_person.setTo(255, m);
    }
    const cv::Mat leak_pixels = (truth != 0) & (eroded_person == 0);
    leak_eroded_y[static_cast<std::size_t>(k)] = on_mask(frame.keypoints, leak_pixels);
  }
  REQUIRE(total_moving > 50);  // the frames show walking people

  const auto none = run(DynamicMode::none, false, false);
  const auto y = run(DynamicMode::Y, false, false);
  const auto y_eroded = run(DynamicMode::Y, true, false);
  const auto ym_eroded = run(DynamicMode::YM, true, false);
  const auto nothing = run(DynamicMode::Y, false, true);
  int leaked_y_eroded = 0;
  for (std::size_t k = 0; k < moving.size(); ++k) {
    INFO("frame " << k);
    CHECK(none[k].moving_keypoints == moving[k]);
    CHECK(none[k].moving_kept == moving[k]);  // mode none keeps everything
    CHECK(y[k].moving_keypoints == moving[k]);
    CHECK(y[k].moving_kept == 0);  // exact person masks cover every moving body
    CHECK(y_eroded[k].moving_kept == leak_eroded_y[k]);
    CHECK(ym_eroded[k].moving_kept <= y_eroded[k].moving_kept);  // MAD only adds dynamic labels
    CHECK(nothing[k].moving_keypoints == 0);
    CHECK(nothing[k].moving_kept == 0);
    leaked_y_eroded += y_eroded[k].moving_kept;
  }
  CHECK(leaked_y_eroded > 0);  // the eroded rim leaks: the check above is not trivially 0 == 0
}

TEST_CASE("System: no moving mask gives -1, a wrong one is refused; frames.csv carries the columns", "[leak]") {
  cge::slam::SystemSettings settings;
  settings.mode = DynamicMode::none;
  cge::slam::System system(settings, cge::PinholeIntrinsics<double>{});
  cge::slam::FrameInput in;
  in.bgr = cv::Mat(480, 640, CV_8UC3, cv::Scalar(90, 90, 90));
  in.depth = cv::Mat(480, 640, CV_16UC1, cv::Scalar(5000));
  const cge::slam::FrameRecord first = system.process(in);
  CHECK(first.moving_keypoints == -1);
  CHECK(first.moving_kept == -1);
  in.index = 1;
  in.moving_mask = cv::Mat::zeros(480, 640, CV_8UC1);
  const cge::slam::FrameRecord second = system.process(in);
  CHECK(second.moving_keypoints == 0);
  CHECK(second.moving_kept == 0);
  in.index = 2;
  in.moving_mask = cv::Mat::zeros(240, 320, CV_8UC1);
  CHECK_THROWS_WITH(system.process(in), Catch::Contains("frame 2") && Catch::Contains("moving mask"));
  in.moving_mask = cv::Mat::zeros(480, 640, CV_16UC1);
  CHECK_THROWS_WITH(system.process(in), Catch::Contains("moving mask"));

  std::ostringstream csv;
  cge::slam::write_frames_csv(csv, system.frames());
  std::istringstream lines(csv.str());
  std::string header, row0, row1;
  std::getline(lines, header);
  std::getline(lines, row0);
  std::getline(lines, row1);
  CHECK(header.size() >= 29);
  CHECK(header.substr(header.size() - 29) == ",moving_keypoints,moving_kept");
  CHECK(row0.substr(row0.size() - 6) == ",-1,-1");
  CHECK(row1.substr(row1.size() - 4) == ",0,0");
}
