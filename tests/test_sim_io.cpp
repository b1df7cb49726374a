// Tests of the segmentation error model and the TUM-layout writer of synthetic sequences.
// The error model is checked against brute-force oracles on small hand-made label images; the
// writer by reading every file back with independent parsers (and OpenCV's own readers).

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/sim/frame_source.hpp"
#include "cge/sim/segmentation_error_model.hpp"
#include "cge/sim/tum_writer.hpp"
#include "temp_dir.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using cge::sim::InstanceInfo;
using cge::sim::SegmentationErrorModel;
using cge::sim::SegmentationErrorSettings;

namespace {

constexpr int kPerson = 0;
constexpr int kChair = 56;

InstanceInfo instance(std::uint16_t id, int class_id, bool moving) {
  InstanceInfo i;
  i.id = id;
  i.class_id = class_id;
  i.moving = moving;
  return i;
}

cv::Mat blank(int width, int height) { return cv::Mat(height, width, CV_16UC1, cv::Scalar(0)); }

void fill_rect(cv::Mat& labels, int x0, int y0, int x1, int y1, std::uint16_t id) {  // inclusive bounds
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) labels.at<std::uint16_t>(y, x) = id;
}

void fill_disc(cv::Mat& labels, int cx, int cy, int r, std::uint16_t id) {
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x)
      if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r) labels.at<std::uint16_t>(y, x) = id;
}

int count_label(const cv::Mat& labels, std::uint16_t id) {
  int n = 0;
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) n += labels.at<std::uint16_t>(y, x) == id;
  return n;
}

bool equal_images(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a.reshape(1) != b.reshape(1)) == 0;
}

/// Brute force of the boundary offset rule (segmentation_error_model.hpp): dilation gives a
/// background pixel to the lowest affected id with a pixel within k; erosion clears a pixel of an
/// affected id with a pixel of another label (inside the image) within |k|.
cv::Mat oracle_offset(const cv::Mat& truth, const std::vector<std::uint16_t>& affected_ascending, int k) {
  cv::Mat out = truth.clone();
  const int kk = k * k;
  for (const std::uint16_t id : affected_ascending) {
    for (int py = 0; py < truth.rows; ++py) {
      for (int px = 0; px < truth.cols; ++px) {
        const std::uint16_t own = truth.at<std::uint16_t>(py, px);
        const bool candidate = k > 0 ? (own == 0 && out.at<std::uint16_t>(py, px) == 0) : own == id;
        if (!candidate) continue;
        bool hit = false;
        for (int qy = 0; qy < truth.rows && !hit; ++qy) {
          for (int qx = 0; qx < truth.cols && !hit; ++qx) {
            const int d2 = (qx - px) * (qx - px) + (qy - py) * (qy - py);
            if (d2 > kk) continue;
            const std::uint16_t other = truth.at<std::uint16_t>(qy, qx);
            hit = k > 0 ? other == id : other != id;
          }
        }
        if (hit) out.at<std::uint16_t>(py, px) = k > 0 ? id : 0;
      }
    }
  }
  return out;
}

SegmentationErrorSettings only_offset(int k) {
  SegmentationErrorSettings s = cge::sim::exact_segmentation();
  s.boundary_offset_px = k;
  return s;
}

using cge_test::TempDir;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> data_lines(const fs::path& p) {  // lines that are not '#' comments
  std::vector<std::string> lines;
  std::istringstream in(read_text(p));
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  return lines;
}

/// Every regular file under dir, as relative path -> bytes.
std::map<std::string, std::string> tree(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).generic_string()] = read_text(e.path());
  return files;
}

/// A small sequence made by hand: 64 x 48 pixels, a person walking right, a static chair, a
/// camera moving along x and turning about z.
cge::sim::InMemoryFrameSource small_sequence(int frames) {
  cge::sim::InMemoryFrameSource s;
  s.camera_model.width_px = 64;
  s.camera_model.height_px = 48;
  s.camera_model.fx_px = 50.5;
  s.camera_model.fy_px = 51.25;
  s.camera_model.cx_px = 31.5;
  s.camera_model.cy_px = 23.5;
  s.rate_hz = 30;
  s.instance_table = {instance(2, kChair, false), instance(1, kPerson, true)};  // any order
  cv::RNG rng(7);
  for (int i = 0; i < frames; ++i) {
    cge::sim::RenderedFrame f;
    f.index = i;
    f.timestamp_s = 1000.0 + i / 30.0;
    f.T_world_camera = Eigen::Translation3d(0.1 * i, -0.05 * i, 1.5) *
                       Eigen::AngleAxisd(0.3 * i - 0.5, Eigen::Vector3d(0.2, 0.3, 1.0).normalized());
    f.rgb = cv::Mat(48, 64, CV_8UC3);
    rng.fill(f.rgb, cv::RNG::UNIFORM, 0, 256);
    f.depth = cv::Mat(48, 64, CV_16UC1);
    rng.fill(f.depth, cv::RNG::UNIFORM, 0, 40000);
    f.instance_labels = blank(64, 48);
    fill_rect(f.instance_labels, 40, 25, 55, 40, 2);
    fill_rect(f.instance_labels, 5 + 3 * i, 8, 15 + 3 * i, 44, 1);
    s.frames.push_back(f);
  }
  if (frames > 3) s.loop_pairs = {{frames - 1, 0}, {frames - 2, 1}};
  return s;
}

SegmentationErrorSettings noisy_settings() {
  SegmentationErrorSettings e;
  e.boundary_offset_px = -1;
  e.feet_loss_probability = 0.5;
  e.miss_probability = 0.2;
  e.false_positive_probability = 0.6;
  e.false_positive_min_height_fraction = 0.2;
  e.false_positive_max_height_fraction = 0.4;
  return e;
}

}  // namespace

// ---- error model: boundary offset ----------------------------------------------------------------

TEST_CASE("Segmentation error model: dilation by k matches the brute-force distance oracle", "[sim][error_model]") {
  for (int k = 1; k <= 4; ++k) {
    CAPTURE(k);
    cv::Mat truth = blank(40, 30);
    fill_rect(truth, 8, 6, 20, 14, 1);  // a rectangle
    fill_disc(truth, 30, 20, 4, 1);     // and a disc, same person
    fill_rect(truth, 0, 25, 3, 29, 1);  // touching the image corner
    SegmentationErrorModel model({instance(1, kPerson, true)}, 1, only_offset(k));
    const cv::Mat out = model.apply(truth, 0).instance_labels;
    CHECK(equal_images(out, oracle_offset(truth, {1}, k)));
  }
}

TEST_CASE("Segmentation error model: a single pixel dilates to the Euclidean disc (hand counts)",
          "[sim][error_model]") {
  // Lattice points with dx^2 + dy^2 <= k^2: 5 for k = 1, 13 for k = 2, 29 for k = 3.
  const std::map<int, int> disc_points = {{1, 5}, {2, 13}, {3, 29}};
  for (const auto& [k, points] : disc_points) {
    cv::Mat truth = blank(21, 21);
    truth.at<std::uint16_t>(10, 10) = 1;
    SegmentationErrorModel model({instance(1, kPerson, true)}, 1, only_offset(k));
    CHECK(count_label(model.apply(truth, 0).instance_labels, 1) == points);
  }
}

TEST_CASE("Segmentation error model: erosion by k matches the brute-force oracle", "[sim][error_model]") {
  for (int k = 1; k <= 4; ++k) {
    CAPTURE(k);
    cv::Mat truth = blank(40, 30);
    fill_disc(truth, 12, 12, 9, 1);
    fill_rect(truth, 25, 0, 39, 12, 1);  // touches the top and right borders: those sides keep their pixels
    SegmentationErrorModel model({instance(1, kPerson, true)}, 1, only_offset(-k));
    CHECK(equal_images(model.apply(truth, 0).instance_labels, oracle_offset(truth, {1}, -k)));
  }
}

TEST_CASE("Segmentation error model: a rectangle eroded by k loses k pixels on each inner side (hand counts)",
          "[sim][error_model]") {
  cv::Mat truth = blank(40, 30);
  fill_rect(truth, 10, 5, 29, 14, 1);  // 20 x 10
  SegmentationErrorModel model({instance(1, kPerson, true)}, 1, only_offset(-2));
  CHECK(count_label(model.apply(truth, 0).instance_labels, 1) == 16 * 6);
  cv::Mat at_border = blank(40, 30);
  fill_rect(at_border, 0, 0, 19, 9, 1);  // 20 x 10 in the corner: only the right and bottom sides erode
  CHECK(count_label(model.apply(at_border, 0).instance_labels, 1) == 18 * 8);
}

TEST_CASE("Segmentation error model: touching instances, the lower id wins and nothing is overwritten",
          "[sim][error_model]") {
  cv::Mat truth = blank(40, 30);
  fill_rect(truth, 5, 5, 14, 20, 3);
  fill_rect(truth, 17, 5, 26, 20, 1);  // a gap of two columns (15, 16) between the persons
  fill_rect(truth, 30, 5, 35, 20, 2);  // a chair: not affected
  const std::vector<InstanceInfo> table = {instance(1, kPerson, true), instance(2, kChair, false),
                                           instance(3, kPerson, true)};
  for (const int k : {-3, -1, 1, 2, 5}) {
    CAPTURE(k);
    SegmentationErrorModel model(table, 1, only_offset(k));
    const cv::Mat out = model.apply(truth, 0).instance_labels;
    CHECK(equal_images(out, oracle_offset(truth, {1, 3}, k)));
    // The chair keeps exactly its ground-truth pixels.
    CHECK(equal_images(out == 2, truth == 2));
  }
  SECTION("all classes") {
    SegmentationErrorSettings s = only_offset(-2);
    s.affect_all_classes = true;
    SegmentationErrorModel model(table, 1, s);
    CHECK(equal_images(model.apply(truth, 0).instance_labels, oracle_offset(truth, {1, 2, 3}, -2)));
  }
}

// ---- error model: feet, misses, false positives ----------------------------------------------------

TEST_CASE("Segmentation error model: feet loss removes exactly the bottom fraction of the rows", "[sim][error_model]") {
  cv::Mat truth = blank(40, 60);
  fill_disc(truth, 12, 8, 4, 1);        // head, rows 4 .. 12
  fill_rect(truth, 8, 13, 16, 43, 1);   // body and legs, rows 13 .. 43: height 40 rows
  fill_rect(truth, 25, 10, 35, 50, 2);  // a chair keeps its bottom
  SegmentationErrorSettings s = cge::sim::exact_segmentation();
  s.feet_loss_probability = 1;
  for (const double fraction : {0.0, 0.1, 0.25, 0.5, 1.0}) {
    CAPTURE(fraction);
    s.feet_loss_fraction = fraction;
    SegmentationErrorModel model({instance(1, kPerson, true), instance(2, kChair, false)}, 9, s);
    const auto r = model.apply(truth, 3);
    const int cut = static_cast<int>(std::lround(fraction * 40));  // rows 4 .. 43 are 40 rows
    cv::Mat expected = truth.clone();
    for (int y = 44 - cut; y <= 43; ++y)
      for (int x = 0; x < 40; ++x)
        if (expected.at<std::uint16_t>(y, x) == 1) expected.at<std::uint16_t>(y, x) = 0;
    CHECK(equal_images(r.instance_labels, expected));
    CHECK(r.events.feet_cut_ids == std::vector<std::uint16_t>{1});
  }
  s.feet_loss_probability = 0;
  SegmentationErrorModel none({instance(1, kPerson, true), instance(2, kChair, false)}, 9, s);
  for (int frame = 0; frame < 50; ++frame) CHECK(equal_images(none.apply(truth, frame).instance_labels, truth));
}

TEST_CASE("Segmentation error model: miss probability 0 and 1, and its frequency", "[sim][error_model]") {
  cv::Mat truth = blank(30, 20);
  fill_rect(truth, 2, 2, 8, 15, 1);
  fill_rect(truth, 12, 2, 18, 15, 2);
  fill_rect(truth, 20, 2, 28, 15, 3);  // chair
  const std::vector<InstanceInfo> table = {instance(1, kPerson, true), instance(2, kPerson, false),
                                           instance(3, kChair, false)};
  SegmentationErrorSettings s = cge::sim::exact_segmentation();

  s.miss_probability = 1;
  SegmentationErrorModel always(table, 4, s);
  cv::Mat chair_only = blank(30, 20);
  fill_rect(chair_only, 20, 2, 28, 15, 3);
  for (int frame = 0; frame < 20; ++frame) {
    const auto r = always.apply(truth, frame);
    CHECK(equal_images(r.instance_labels, chair_only));
    CHECK(r.events.missed_ids == std::vector<std::uint16_t>{1, 2});
  }

  s.miss_probability = 0;
  SegmentationErrorModel never(table, 4, s);
  for (int frame = 0; frame < 20; ++frame) CHECK(equal_images(never.apply(truth, frame).instance_labels, truth));

  // 2000 frames at p = 0.3: the binomial standard deviation of the rate is 0.0102; allow 5 of them.
  s.miss_probability = 0.3;
  SegmentationErrorModel some(table, 4, s);
  const int frames = 2000;
  int missed_1 = 0, missed_2 = 0, both = 0;
  for (int frame = 0; frame < frames; ++frame) {
    const auto r = some.apply(truth, frame);
    const bool m1 = count_label(r.instance_labels, 1) == 0;
    const bool m2 = count_label(r.instance_labels, 2) == 0;
    missed_1 += m1;
    missed_2 += m2;
    both += m1 && m2;
    CHECK(count_label(r.instance_labels, 3) == count_label(truth, 3));
  }
  CHECK(std::abs(missed_1 / double(frames) - 0.3) < 0.051);
  CHECK(std::abs(missed_2 / double(frames) - 0.3) < 0.051);
  // Independent per instance: both missed at about 0.09 (sd 0.0064).
  CHECK(std::abs(both / double(frames) - 0.09) < 0.033);
}

TEST_CASE("Segmentation error model: false positives get new stable ids, land on background, have their size",
          "[sim][error_model]") {
  cv::Mat truth = blank(80, 60);
  fill_rect(truth, 10, 10, 30, 50, 1);
  fill_rect(truth, 50, 5, 70, 30, 7);
  const std::vector<InstanceInfo> table = {instance(1, kPerson, true), instance(7, kChair, false)};
  SegmentationErrorSettings s = cge::sim::exact_segmentation();
  s.false_positive_probability = 1;
  s.false_positive_class_id = 39;  // bottle
  s.false_positive_min_height_fraction = 0.2;
  s.false_positive_max_height_fraction = 0.5;
  SegmentationErrorModel model(table, 11, s);
  REQUIRE(model.first_false_positive_id() == 8);
  int hidden = 0;  // a blob that falls wholly on the instances draws no pixel and is no false positive
  for (int frame = 0; frame < 100; ++frame) {
    CAPTURE(frame);
    const auto r = model.apply(truth, frame);
    const std::uint16_t id = static_cast<std::uint16_t>(8 + frame);
    // Scene instances untouched, the blob only where the truth is background.
    CHECK(equal_images(r.instance_labels == 1, truth == 1));
    CHECK(equal_images(r.instance_labels == 7, truth == 7));
    const cv::Mat blob = r.instance_labels == id;
    CHECK(cv::countNonZero(blob & (truth != 0)) == 0);
    CHECK(cv::countNonZero(blob | (r.instance_labels == 0) | (truth != 0)) == 80 * 60);
    if (!r.events.false_positive) {
      ++hidden;
      CHECK(equal_images(r.instance_labels, truth));
      CHECK(r.instances.size() == 2);
      continue;
    }
    CHECK(r.events.false_positive->id == id);
    CHECK(r.events.false_positive->class_id == 39);
    REQUIRE(r.instances.size() == 3);
    CHECK(r.instances.back().id == id);
    CHECK(cv::countNonZero(blob) > 0);
    // Height of the ellipse: at most 0.5 of 60 rows plus one (instances may hide part of it).
    CHECK(cv::boundingRect(blob).height <= 31);
  }
  CHECK(hidden < 20);  // the instances cover a third of the image, the blobs are larger than a hidden one
  s.false_positive_probability = 0;
  SegmentationErrorModel none(table, 11, s);
  for (int frame = 0; frame < 50; ++frame) CHECK_FALSE(none.apply(truth, frame).events.false_positive.has_value());

  // On an empty background the whole ellipse is drawn: its height is in the drawn range.
  s.false_positive_probability = 1;
  SegmentationErrorModel open({}, 3, s);
  REQUIRE(open.first_false_positive_id() == 1);
  for (int frame = 0; frame < 100; ++frame) {
    const cv::Rect box = cv::boundingRect(open.apply(blank(80, 60), frame).instance_labels == 1 + frame);
    CHECK(box.height >= 0.2 * 60 - 1);
    CHECK(box.height <= 0.5 * 60 + 1);
    CHECK(box.width <= box.height);  // aspect 0.3 .. 0.6, plus rounding
  }

  // Frequency at p = 0.25 over 2000 frames (sd 0.0097).
  s.false_positive_probability = 0.25;
  SegmentationErrorModel some(table, 11, s);
  int with = 0;
  for (int frame = 0; frame < 2000; ++frame) with += some.apply(truth, frame).events.false_positive.has_value();
  CHECK(std::abs(with / 2000.0 - 0.25) < 0.049);
}

TEST_CASE("Segmentation error model: deterministic per (seed, frame), in any order", "[sim][error_model]") {
  cv::Mat truth = blank(64, 48);
  fill_rect(truth, 5, 5, 20, 45, 1);
  fill_rect(truth, 30, 10, 45, 46, 2);
  const std::vector<InstanceInfo> table = {instance(1, kPerson, true), instance(2, kPerson, true)};
  SegmentationErrorModel a(table, 42, noisy_settings());
  SegmentationErrorModel b(table, 42, noisy_settings());
  SegmentationErrorModel other_seed(table, 43, noisy_settings());
  const int frames = 40;
  std::vector<cv::Mat> forward;
  for (int f = 0; f < frames; ++f) forward.push_back(a.apply(truth, f).instance_labels);
  int differ = 0;
  for (int f = frames - 1; f >= 0; --f) {
    CHECK(equal_images(b.apply(truth, f).instance_labels, forward[static_cast<std::size_t>(f)]));
    CHECK(equal_images(a.apply(truth, f).instance_labels, forward[static_cast<std::size_t>(f)]));
    differ += !equal_images(other_seed.apply(truth, f).instance_labels, forward[static_cast<std::size_t>(f)]);
  }
  CHECK(differ > 0);

  // One instance's decisions do not depend on the other instances in the frame.
  cv::Mat alone = blank(64, 48);
  fill_rect(alone, 5, 5, 20, 45, 1);
  for (int f = 0; f < frames; ++f) {
    SegmentationErrorSettings s = noisy_settings();
    s.false_positive_probability = 0;
    SegmentationErrorModel m(table, 42, s);
    CHECK(equal_images(m.apply(alone, f).instance_labels == 1, m.apply(truth, f).instance_labels == 1));
  }
}

TEST_CASE("Segmentation error model: bad input is refused with a message", "[sim][error_model]") {
  cv::Mat truth = blank(10, 10);
  truth.at<std::uint16_t>(3, 4) = 5;
  SegmentationErrorModel model({instance(1, kPerson, true)}, 1);
  CHECK_THAT(cge_test::invalid_argument_message([&] { model.apply(truth, 0); }),
             Catch::Contains("label 5 at pixel (4, 3)"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { model.apply(cv::Mat(10, 10, CV_8UC1), 0); }),
             Catch::Contains("CV_16UC1"));
  CHECK_THAT(cge_test::invalid_argument_message([&] { model.apply(blank(10, 10), -1); }), Catch::Contains("negative"));
  SegmentationErrorModel bad = model;
  bad.settings.miss_probability = 1.5;
  CHECK_THAT(cge_test::invalid_argument_message([&] { bad.apply(blank(10, 10), 0); }),
             Catch::Contains("miss_probability"));
  bad = model;
  bad.settings.affected_class_ids = {80};
  CHECK_THAT(cge_test::invalid_argument_message([&] { bad.apply(blank(10, 10), 0); }), Catch::Contains("80"));
  bad = model;
  bad.settings.false_positive_min_height_fraction = 0.6;
  CHECK_THAT(cge_test::invalid_argument_message([&] { bad.apply(blank(10, 10), 0); }),
             Catch::Contains("height fractions"));
  CHECK_THAT(cge_test::invalid_argument_message([] {
               SegmentationErrorModel({instance(3, kPerson, true), instance(3, kChair, false)}, 1);
             }),
             Catch::Contains("instance id 3 appears twice"));
  CHECK_THAT(cge_test::invalid_argument_message([] { SegmentationErrorModel({instance(0, kPerson, true)}, 1); }),
             Catch::Contains("background"));
  // False-positive ids run out at 65535.
  SegmentationErrorModel high({instance(65530, kPerson, true)}, 1);
  CHECK(high.first_false_positive_id() == 65531);
  CHECK(high.false_positive_id(4) == 65535);
  CHECK_THAT(cge_test::invalid_argument_message([&] { high.false_positive_id(5); }), Catch::Contains("65535"));
  SegmentationErrorModel full({instance(65535, kPerson, true)}, 1);
  CHECK_THAT(cge_test::invalid_argument_message([&] { full.false_positive_id(0); }), Catch::Contains("65535"));
}

// ---- writer: formats ------------------------------------------------------------------------------

TEST_CASE("TUM format: timestamps with 6 decimals, poses with a canonical quaternion", "[sim][tum_writer]") {
  CHECK(cge::sim::format_tum_timestamp(1341846313.592026) == "1341846313.592026");
  CHECK(cge::sim::format_tum_timestamp(0.1 / 3) == "0.033333");
  CHECK(cge::sim::format_tum_timestamp(-1e-9) == "0.000000");
  const Eigen::Isometry3d T = Eigen::Translation3d(1, -2, 0.5) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  // 90 degrees about z: q = (0, 0, sin 45, cos 45).
  CHECK(cge::sim::format_tum_pose(2.5, T) ==
        "2.500000 1.000000000 -2.000000000 0.500000000 0.000000000 0.000000000 0.707106781 0.707106781");
  // Half turns have qw = 0 exactly; the sign rule makes the first non-zero component positive.
  const Eigen::Quaterniond qx = cge::sim::canonical_quaternion(Eigen::Vector3d(1, -1, -1).asDiagonal());
  CHECK(qx.coeffs() == Eigen::Vector4d(1, 0, 0, 0));
  const Eigen::Quaterniond qz = cge::sim::canonical_quaternion(Eigen::Vector3d(-1, -1, 1).asDiagonal());
  CHECK(qz.coeffs() == Eigen::Vector4d(0, 0, 1, 0));
  cv::RNG rng(3);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d axis(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
    const Eigen::Matrix3d Ri = Eigen::AngleAxisd(rng.uniform(0.0, 2 * M_PI), axis.normalized()).toRotationMatrix();
    const Eigen::Quaterniond qi = cge::sim::canonical_quaternion(Ri);
    CHECK(qi.w() >= 0);
    CHECK((qi.toRotationMatrix() - Ri).cwiseAbs().maxCoeff() < 1e-12);
  }
}

TEST_CASE("TUM writer: every file read back matches the sequence", "[sim][tum_writer]") {
  const auto seq = small_sequence(6);
  SegmentationErrorModel model(seq.instances(), 5, noisy_settings());
  TempDir tmp{"cge_test_sim_io"};
  const fs::path out = tmp.path() / "seq";
  std::vector<std::pair<int, int>> progress;
  cge::sim::TumWriterSettings ws;
  ws.description = "unit test";
  cge::sim::write_tum_sequence(seq, model, out, ws, [&](int done, int total) { progress.emplace_back(done, total); });
  REQUIRE(progress.size() == 6);
  for (int i = 0; i < 6; ++i) CHECK(progress[static_cast<std::size_t>(i)] == std::make_pair(i + 1, 6));

  // The files, and nothing else.
  std::set<std::string> expected = {"rgb.txt",     "depth.txt", "associations.txt",    "groundtruth.txt",
                                    "camera.yaml", "loops.txt", "masks/instances.csv", "segmentation/instances.csv"};
  std::vector<std::string> stems;
  for (const auto& f : seq.frames) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6f", f.timestamp_s);
    stems.push_back(buf);
    for (const char* dir : {"rgb/", "depth/", "masks/", "segmentation/"}) expected.insert(dir + stems.back() + ".png");
  }
  std::set<std::string> written;
  for (const auto& [name, bytes] : tree(out)) written.insert(name);
  CHECK(written == expected);

  // rgb.txt, depth.txt, associations.txt: TUM's header, then one line per frame.
  const std::string rgb_txt = read_text(out / "rgb.txt");
  CHECK(rgb_txt.rfind("# color images\n# file: 'unit test'\n# timestamp filename\n", 0) == 0);
  CHECK(read_text(out / "depth.txt").rfind("# depth maps\n", 0) == 0);
  const auto rgb_lines = data_lines(out / "rgb.txt");
  const auto depth_lines = data_lines(out / "depth.txt");
  const auto assoc_lines = data_lines(out / "associations.txt");
  REQUIRE(rgb_lines.size() == 6);
  REQUIRE(depth_lines.size() == 6);
  REQUIRE(assoc_lines.size() == 6);
  std::set<std::uint16_t> segmentation_ids;
  for (std::size_t i = 0; i < 6; ++i) {
    CAPTURE(i);
    const auto& frame = seq.frames[i];
    CHECK(rgb_lines[i] == stems[i] + " rgb/" + stems[i] + ".png");
    CHECK(depth_lines[i] == stems[i] + " depth/" + stems[i] + ".png");
    CHECK(assoc_lines[i] == stems[i] + " rgb/" + stems[i] + ".png " + stems[i] + " depth/" + stems[i] + ".png");
    // Lossless images: the PNGs decode to the frame's images.
    CHECK(equal_images(cv::imread((out / "rgb" / (stems[i] + ".png")).string(), cv::IMREAD_UNCHANGED), frame.rgb));
    CHECK(equal_images(cv::imread((out / "depth" / (stems[i] + ".png")).string(), cv::IMREAD_UNCHANGED), frame.depth));
    CHECK(equal_images(cv::imread((out / "masks" / (stems[i] + ".png")).string(), cv::IMREAD_UNCHANGED),
                       frame.instance_labels));
    const cv::Mat seg = cv::imread((out / "segmentation" / (stems[i] + ".png")).string(), cv::IMREAD_UNCHANGED);
    CHECK(equal_images(seg, model.apply(frame.instance_labels, static_cast<int>(i)).instance_labels));
    for (int y = 0; y < seg.rows; ++y)
      for (int x = 0; x < seg.cols; ++x) segmentation_ids.insert(seg.at<std::uint16_t>(y, x));
  }

  // groundtruth.txt: header, then the poses, read back to 1e-9.
  CHECK(read_text(out / "groundtruth.txt")
            .rfind("# ground truth trajectory\n# file: 'unit test'\n# timestamp tx ty tz qx qy qz qw\n", 0) == 0);
  const auto gt_lines = data_lines(out / "groundtruth.txt");
  REQUIRE(gt_lines.size() == 6);
  for (std::size_t i = 0; i < 6; ++i) {
    std::istringstream in(gt_lines[i]);
    std::string stamp;
    double tx, ty, tz, qx, qy, qz, qw;
    REQUIRE(in >> stamp >> tx >> ty >> tz >> qx >> qy >> qz >> qw);
    std::string rest;
    CHECK_FALSE(in >> rest);
    CHECK(stamp == stems[i]);
    const Eigen::Isometry3d& T = seq.frames[i].T_world_camera;
    CHECK((Eigen::Vector3d(tx, ty, tz) - T.translation()).cwiseAbs().maxCoeff() < 1e-9);
    CHECK(qw >= 0);
    const Eigen::Matrix3d R = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    CHECK((R - T.linear()).cwiseAbs().maxCoeff() < 1e-8);
  }

  // instances.csv: the mask-folder format; the segmentation's lists the false positives that occur.
  CHECK(read_text(out / "masks" / "instances.csv") == "id,class_id,class_name,moving\n1,0,person,1\n2,56,chair,0\n");
  const auto seg_csv = data_lines(out / "segmentation" / "instances.csv");
  REQUIRE(seg_csv.size() >= 3);
  CHECK(seg_csv[0] == "id,class_id,class_name,moving");
  CHECK(seg_csv[1] == "1,0,person,1");
  CHECK(seg_csv[2] == "2,56,chair,0");
  std::set<std::uint16_t> listed = {0, 1, 2};
  for (std::size_t i = 3; i < seg_csv.size(); ++i) {
    const int id = std::stoi(seg_csv[i]);
    CHECK(id >= 3);
    CHECK(id < 3 + 6);
    CHECK(seg_csv[i] == std::to_string(id) + ",0,person,0");
    listed.insert(static_cast<std::uint16_t>(id));
  }
  for (const std::uint16_t id : segmentation_ids) CHECK(listed.count(id) == 1);
  CHECK(listed.size() > 3);  // p = 0.6 over 6 frames: this seed draws some (the ids checked above)

  // camera.yaml through OpenCV's reader, as ORB-SLAM2 reads it.
  cv::FileStorage yaml((out / "camera.yaml").string(), cv::FileStorage::READ);
  REQUIRE(yaml.isOpened());
  CHECK(double(yaml["Camera.fx"]) == 50.5);
  CHECK(double(yaml["Camera.fy"]) == 51.25);
  CHECK(double(yaml["Camera.cx"]) == 31.5);
  CHECK(double(yaml["Camera.cy"]) == 23.5);
  for (const char* k : {"Camera.k1", "Camera.k2", "Camera.k3", "Camera.p1", "Camera.p2"}) CHECK(double(yaml[k]) == 0);
  CHECK(int(yaml["Camera.width"]) == 64);
  CHECK(int(yaml["Camera.height"]) == 48);
  CHECK(double(yaml["Camera.fps"]) == 30);
  CHECK(int(yaml["Camera.RGB"]) == 1);
  CHECK(double(yaml["DepthMapFactor"]) == 5000);
  CHECK(double(yaml["ThDepth"]) == 40);
  CHECK(double(yaml["Camera.bf"]) == 40);
  CHECK(int(yaml["ORBextractor.nFeatures"]) == 1000);
  CHECK(double(yaml["ORBextractor.scaleFactor"]) == Approx(1.2));
  CHECK(int(yaml["ORBextractor.nLevels"]) == 8);
  CHECK(int(yaml["ORBextractor.iniThFAST"]) == 20);
  CHECK(int(yaml["ORBextractor.minThFAST"]) == 7);
  CHECK(float(yaml["Viewer.ViewpointF"]) == 500);

  // loops.txt: "query_timestamp match_timestamp query_index match_index".
  const auto loop_lines = data_lines(out / "loops.txt");
  REQUIRE(loop_lines.size() == 2);
  CHECK(loop_lines[0] == stems[5] + " " + stems[0] + " 5 0");
  CHECK(loop_lines[1] == stems[4] + " " + stems[1] + " 4 1");
}

TEST_CASE("TUM writer: same sequence and seed, same bytes in every file", "[sim][tum_writer]") {
  const auto seq = small_sequence(5);
  TempDir tmp{"cge_test_sim_io"};
  SegmentationErrorModel model(seq.instances(), 77, noisy_settings());
  cge::sim::write_tum_sequence(seq, model, tmp.path() / "a", {});
  SegmentationErrorModel again(seq.instances(), 77, noisy_settings());
  cge::sim::write_tum_sequence(seq, again, tmp.path() / "b", {});
  const auto a = tree(tmp.path() / "a");
  const auto b = tree(tmp.path() / "b");
  CHECK(a.size() == 5 * 4 + 8);
  CHECK(a == b);
  // Another error-model seed changes the segmentation and nothing else.
  SegmentationErrorModel other(seq.instances(), 78, noisy_settings());
  cge::sim::write_tum_sequence(seq, other, tmp.path() / "c", {});
  const auto c = tree(tmp.path() / "c");
  REQUIRE(c.size() >= 4 * 5 + 7);
  bool segmentation_differs = false;
  for (const auto& [name, bytes] : a) {
    if (name.rfind("segmentation/", 0) == 0) {
      segmentation_differs |= c.count(name) == 0 || c.at(name) != bytes;
    } else {
      CHECK(c.at(name) == bytes);
    }
  }
  CHECK(segmentation_differs);
}

TEST_CASE("TUM writer: a non-empty folder is refused; with force only the writer's files change", "[sim][tum_writer]") {
  const auto seq = small_sequence(3);
  SegmentationErrorModel model(seq.instances(), 1);
  TempDir tmp{"cge_test_sim_io"};
  const fs::path out = tmp.path() / "seq";
  fs::create_directories(out / "rgb");
  { std::ofstream(out / "notes.txt") << "the user's notes\n"; }
  { std::ofstream(out / "rgb" / "mine.png") << "not a png"; }
  { std::ofstream(out / "rgb.txt") << "an old list\n"; }
  const auto before = tree(out);

  const std::string msg =
      cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, out, {}); });
  CHECK_THAT(msg, Catch::Contains(out.string()) && Catch::Contains("not empty") && Catch::Contains("force"));
  CHECK(tree(out) == before);
  CHECK_FALSE(fs::exists(out / "depth"));

  cge::sim::TumWriterSettings force;
  force.force = true;
  cge::sim::write_tum_sequence(seq, model, out, force);
  const auto after = tree(out);
  CHECK(after.at("notes.txt") == "the user's notes\n");
  CHECK(after.at("rgb/mine.png") == "not a png");
  CHECK(after.at("rgb.txt").rfind("# color images", 0) == 0);  // the writer's own file, overwritten
  CHECK(after.size() == 2 + 3 * 4 + 8);

  // An empty existing folder is fine without force; a file in the folder's place is not.
  fs::create_directories(tmp.path() / "empty");
  cge::sim::write_tum_sequence(seq, model, tmp.path() / "empty", {});
  CHECK(fs::exists(tmp.path() / "empty" / "groundtruth.txt"));
  { std::ofstream(tmp.path() / "a_file") << "x"; }
  CHECK_THAT(cge_test::invalid_argument_message(
                 [&] { cge::sim::write_tum_sequence(seq, model, tmp.path() / "a_file", force); }),
             Catch::Contains("not a folder"));
}

TEST_CASE("TUM writer: a file that cannot be written is reported with its path", "[sim][tum_writer]") {
  const auto seq = small_sequence(2);
  SegmentationErrorModel model(seq.instances(), 1);
  TempDir tmp{"cge_test_sim_io"};
  fs::create_directories(tmp.path() / "groundtruth.txt");  // a folder where the writer wants a file
  cge::sim::TumWriterSettings force;
  force.force = true;
  try {
    cge::sim::write_tum_sequence(seq, model, tmp.path(), force);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains((tmp.path() / "groundtruth.txt").string()));
  }
}

TEST_CASE("TUM writer: bad sequences are refused before the disk is touched", "[sim][tum_writer]") {
  TempDir tmp{"cge_test_sim_io"};
  const fs::path out = tmp.path() / "never";
  auto seq = small_sequence(0);
  SegmentationErrorModel model(seq.instances(), 1);
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, out, {}); }),
             Catch::Contains("0 frames"));
  seq = small_sequence(4);
  seq.loop_pairs = {{1, 2}};
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, out, {}); }),
             Catch::Contains("loop pair (query 1, match 2)"));
  seq = small_sequence(4);
  seq.instance_table.push_back(instance(9, 80, false));
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, out, {}); }),
             Catch::Contains("instance 9"));
  seq = small_sequence(4);
  seq.camera_model.fx_px = std::nan("");
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, out, {}); }),
             Catch::Contains("camera"));
  seq = small_sequence(4);
  SegmentationErrorModel other_table({instance(1, kPerson, true)}, 1);
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, other_table, out, {}); }),
             Catch::Contains("different instance table"));
  CHECK_FALSE(fs::exists(out));
}

TEST_CASE("TUM writer: bad frames are refused with the frame named", "[sim][tum_writer]") {
  TempDir tmp{"cge_test_sim_io"};
  auto seq = small_sequence(4);
  SegmentationErrorModel model(seq.instances(), 1);
  seq.frames[2].depth = cv::Mat(48, 64, CV_32FC1, cv::Scalar(1.0f));
  CHECK_THAT(cge_test::invalid_argument_message(
                 [&] { cge::sim::write_tum_sequence(seq, model, tmp.path() / "depth_type", {}); }),
             Catch::Contains("frame 2: the depth image must be CV_16UC1"));
  seq = small_sequence(4);
  seq.frames[3].timestamp_s = seq.frames[2].timestamp_s + 1e-7;  // same 6-decimal stem
  CHECK_THAT(
      cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, tmp.path() / "stamps", {}); }),
      Catch::Contains("frame 3: timestamp"));
  seq = small_sequence(4);
  seq.frames[1].T_world_camera.linear() *= 2.0;
  CHECK_THAT(
      cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, tmp.path() / "scaled", {}); }),
      Catch::Contains("frame 1: T_world_camera is not a rigid motion"));
  seq = small_sequence(4);
  seq.frames[0].instance_labels.at<std::uint16_t>(0, 0) = 4;
  CHECK_THAT(
      cge_test::invalid_argument_message([&] { cge::sim::write_tum_sequence(seq, model, tmp.path() / "label", {}); }),
      Catch::Contains("label 4 at pixel (0, 0)"));
}

namespace {
/// A type with the renderer's announced members (cge/sim/renderer.hpp), to check the adapter.
struct FakeRenderer {
  cge::sim::InMemoryFrameSource frames = small_sequence(3);
  int frame_count() const { return frames.frame_count(); }
  const cge::sim::PinholeCamera& camera() const { return frames.camera(); }
  double frame_rate_hz() const { return frames.frame_rate_hz(); }
  const std::vector<InstanceInfo>& instances() const { return frames.instances(); }
  const std::vector<cge::sim::LoopPair>& loops() const { return frames.loops(); }
  cge::sim::RenderedFrame render(int index) const { return frames.render(index); }
};
}  // namespace

TEST_CASE("RendererFrameSource: a renderer-like type written like any other source", "[sim][tum_writer]") {
  const cge::sim::RendererFrameSource<FakeRenderer> source{FakeRenderer{}};
  CHECK(source.frame_count() == 3);
  CHECK(source.camera().width_px == 64);
  CHECK(source.render(2).index == 2);
  TempDir tmp{"cge_test_sim_io"};
  SegmentationErrorModel model(source.instances(), 3, noisy_settings());
  cge::sim::write_tum_sequence(source, model, tmp.path() / "a", {});
  cge::sim::write_tum_sequence(source.renderer().frames, model, tmp.path() / "b", {});
  CHECK(tree(tmp.path() / "a") == tree(tmp.path() / "b"));
}

TEST_CASE("simulate_frame: a frame and its segmentation in memory", "[sim][tum_writer]") {
  auto seq = small_sequence(4);
  SegmentationErrorModel model(seq.instances(), 8, noisy_settings());
  for (int i = 0; i < 4; ++i) {
    const cge::sim::SimulatedFrame s = cge::sim::simulate_frame(seq, model, i);
    CHECK(s.frame.index == i);
    CHECK(equal_images(s.frame.rgb, seq.frames[static_cast<std::size_t>(i)].rgb));
    CHECK(equal_images(s.segmentation.instance_labels, model.apply(s.frame.instance_labels, i).instance_labels));
  }
  seq.frames[2].index = 3;
  CHECK_THAT(cge_test::invalid_argument_message([&] { cge::sim::simulate_frame(seq, model, 2); }),
             Catch::Contains("returned frame 3 for index 2"));
}

TEST_CASE("TumSequenceWriter: frames encoded by the caller give the same files", "[sim][tum_writer]") {
  const auto seq = small_sequence(4);
  SegmentationErrorModel model(seq.instances(), 21, noisy_settings());
  TempDir tmp{"cge_test_sim_io"};
  cge::sim::write_tum_sequence(seq, model, tmp.path() / "a", {});
  cge::sim::check_sequence(seq, model);
  cge::sim::TumSequenceWriter writer(tmp.path() / "b", seq.camera(), seq.frame_rate_hz(), seq.instances());
  for (int i = 0; i < 4; ++i) {
    const auto s = cge::sim::simulate_frame(seq, model, i);
    writer.write_frame(s.frame, s.segmentation,
                       cge::sim::encode_frame(s.frame, s.segmentation, writer.settings().png_compression));
  }
  writer.finish(seq.loops());
  CHECK(tree(tmp.path() / "a") == tree(tmp.path() / "b"));
  const auto s = cge::sim::simulate_frame(seq, model, 0);
  CHECK_THAT(cge_test::invalid_argument_message([&] { writer.write_frame(s.frame, s.segmentation, {}); }),
             Catch::Contains("encoded image is empty"));
}
