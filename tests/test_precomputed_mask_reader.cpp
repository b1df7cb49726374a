#include <catch2/catch.hpp>

#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cge/segmentation/precomputed_mask_reader.hpp"
#include "temp_dir.hpp"
#include "test_support.hpp"

namespace {

const char* const kCsv =
    "id,class_id,class_name,moving\n"
    "# people first\n"
    "1,0,person,1\n"
    "\n"
    "7,56,chair,0\n"
    "300,62,tv,\n"
    "65535,0,person,\n";

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::map<int, cge::MaskFolderInstance> parse(const std::string& text) {
  std::istringstream in(text);
  return cge::read_instances_csv(in, "masks/instances.csv");
}

std::string parse_error(const std::string& text) {
  return cge_test::invalid_argument_message([&] { parse(text); });
}

// A 40 x 30 label image with random rectangles of the given ids (later ones on top).
cv::Mat random_labels(std::mt19937& rng, const std::vector<int>& ids) {
  cv::Mat labels(30, 40, CV_16UC1, cv::Scalar(0));
  std::uniform_int_distribution<int> x(0, 35), y(0, 25), side(1, 12);
  for (const int id : ids) {
    const cv::Rect r = cv::Rect(x(rng), y(rng), side(rng), side(rng)) & cv::Rect(0, 0, 40, 30);
    labels(r).setTo(id);
  }
  return labels;
}

}  // namespace

TEST_CASE("read_instances_csv: the four columns, comments and empty lines", "[segmentation][mask_folder]") {
  const auto instances = parse(kCsv);
  REQUIRE(instances.size() == 4);
  const auto& person = instances.at(1);
  CHECK(person.class_id == 0);
  CHECK(person.class_name == "person");
  CHECK(person.moving == std::optional<bool>(true));
  CHECK(person.line == 3);
  CHECK(instances.at(7).moving == std::optional<bool>(false));
  CHECK(instances.at(7).line == 5);
  CHECK_FALSE(instances.at(300).moving.has_value());
  CHECK(instances.at(65535).class_id == 0);
  // Windows line ends, spaces in names, a header only.
  const auto crlf = parse("id,class_id,class_name,moving\r\n2,58,potted plant,0\r\n");
  CHECK(crlf.at(2).class_name == "potted plant");
  CHECK(parse("# written by a test\nid,class_id,class_name,moving\n").empty());
}

TEST_CASE("read_instances_csv: malformed files are named with file and line", "[segmentation][mask_folder]") {
  const std::string header = "id,class_id,class_name,moving\n";
  CHECK_THAT(parse_error(""), Catch::Contains("masks/instances.csv") && Catch::Contains("header"));
  CHECK_THAT(parse_error("id,class,name,moving\n1,0,person,1\n"),
             Catch::Contains("masks/instances.csv:1:") && Catch::Contains("header"));
  CHECK_THAT(parse_error(header + "1,0,person\n"), Catch::Contains("instances.csv:2:") && Catch::Contains("found 3"));
  CHECK_THAT(parse_error(header + "1,0,person,1,extra\n"), Catch::Contains(":2:") && Catch::Contains("found 5"));
  CHECK_THAT(parse_error(header + "# c\n0,0,person,1\n"), Catch::Contains(":3:") && Catch::Contains("id '0'"));
  CHECK_THAT(parse_error(header + "65536,0,person,1\n"), Catch::Contains(":2:") && Catch::Contains("65536"));
  CHECK_THAT(parse_error(header + "x1,0,person,1\n"), Catch::Contains(":2:") && Catch::Contains("id 'x1'"));
  CHECK_THAT(parse_error(header + "1,80,thing,1\n"), Catch::Contains(":2:") && Catch::Contains("class_id '80'"));
  CHECK_THAT(parse_error(header + "1,-1,thing,1\n"), Catch::Contains("class_id '-1'"));
  CHECK_THAT(parse_error(header + "1,0,person,yes\n"), Catch::Contains(":2:") && Catch::Contains("moving 'yes'"));
  CHECK_THAT(parse_error(header + "1,0,person,1\n\n1,56,chair,0\n"),
             Catch::Contains(":4:") && Catch::Contains("id 1 repeats line 2"));
}

TEST_CASE("PrecomputedMaskReader: masks, boxes and classes against a brute-force oracle",
          "[segmentation][mask_folder]") {
  const cge_test::TempDir dir("cge_test_mask_folder");
  write_text(dir.file("instances.csv"), kCsv);
  std::mt19937 rng(17);
  const std::vector<int> ids = {1, 7, 300, 65535};
  const cv::Mat labels16 = random_labels(rng, ids);
  REQUIRE(cv::imwrite(dir.file("0001.png"), labels16));
  cv::Mat labels8(30, 40, CV_8UC1, cv::Scalar(0));  // 8-bit images are accepted too
  labels8(cv::Rect(3, 4, 5, 6)).setTo(7);
  REQUIRE(cv::imwrite(dir.file("0002.png"), labels8));
  REQUIRE(cv::imwrite(dir.file("0003.png"), cv::Mat(30, 40, CV_16UC1, cv::Scalar(0))));

  cge::PrecomputedMaskReader reader(dir.path().string());
  CHECK(reader.instances().size() == 4);
  CHECK(reader.dynamic_classes() == std::set<int>{cge::kCocoPerson});

  const auto out = reader.segment({cv::Mat(30, 40, CV_8UC3), "0001"});
  // Oracle: for each id present, the pixels carrying it and their extent, by brute force.
  std::vector<int> present;
  for (const int id : ids) {
    if (cv::countNonZero(labels16 == id) > 0) present.push_back(id);
  }
  REQUIRE(out.size() == present.size());
  REQUIRE(present.size() >= 2);  // the seed leaves several ids visible
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto& s = out[i];
    const int id = present[i];  // by id ascending
    CHECK(s.id == id);
    int x0 = 1000, y0 = 1000, x1 = -1, y1 = -1;
    for (int y = 0; y < labels16.rows; ++y) {
      for (int x = 0; x < labels16.cols; ++x) {
        const bool on = labels16.at<std::uint16_t>(y, x) == id;
        CHECK((s.mask.at<unsigned char>(y, x) == 255) == on);
        if (on) {
          x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
        }
      }
    }
    CHECK(s.mask.type() == CV_8UC1);
    CHECK(cv::countNonZero((s.mask != 0) & (s.mask != 255)) == 0);
    CHECK(s.box_px == cv::Rect2f(float(x0), float(y0), float(x1 - x0 + 1), float(y1 - y0 + 1)));
    const auto& row = reader.instances().at(id);
    CHECK(s.class_id == row.class_id);
    CHECK(s.moving == row.moving);
    CHECK(s.dynamic == (row.class_id == cge::kCocoPerson));
    CHECK(s.score == 1.f);
  }

  // Reading the instances back into a label image gives the file's labels.
  CHECK(cv::norm(cge::instance_label_image(out, labels16.size()), labels16, cv::NORM_INF) == 0);

  const auto eight = reader.read("0002", {40, 30});
  REQUIRE(eight.size() == 1);
  CHECK(eight[0].id == 7);
  CHECK(eight[0].box_px == cv::Rect2f(3.f, 4.f, 5.f, 6.f));
  CHECK(reader.read("0003", {40, 30}).empty());  // all zero: no instances
  CHECK(reader.read("0004", {40, 30}).empty());  // no file: no instances

  reader.set_dynamic_classes({56, 62});
  for (const auto& s : reader.read("0001", {40, 30})) CHECK(s.dynamic == (s.class_id == 56 || s.class_id == 62));
  CHECK_THROWS_AS(reader.set_dynamic_classes({100}), std::invalid_argument);
}

TEST_CASE("PrecomputedMaskReader: bad folders and images are named", "[segmentation][mask_folder]") {
  const cge_test::TempDir dir("cge_test_mask_folder_errors");
  const std::string folder = dir.path().string();
  const auto error = [](auto f) { return cge_test::invalid_argument_message(f); };

  CHECK_THAT(error([&] { cge::PrecomputedMaskReader r(dir.file("absent")); }), Catch::Contains("does not exist"));
  CHECK_THAT(error([&] { cge::PrecomputedMaskReader r(folder); }), Catch::Contains("instances.csv"));
  write_text(dir.file("instances.csv"), "id,class_id,class_name,moving\n1,0,person,1\n2,99,x,1\n");
  CHECK_THAT(error([&] { cge::PrecomputedMaskReader r(folder); }),
             Catch::Contains(dir.file("instances.csv") + ":3:") && Catch::Contains("class_id '99'"));
  write_text(dir.file("instances.csv"), "id,class_id,class_name,moving\n1,0,person,1\n");
  cge::PrecomputedMaskSettings bad_settings;
  bad_settings.dynamic_class_ids = {-3};
  CHECK_THAT(error([&] { cge::PrecomputedMaskReader r(folder, bad_settings); }), Catch::Contains("-3"));

  cge::PrecomputedMaskReader reader(folder);
  cv::Mat labels(30, 40, CV_16UC1, cv::Scalar(0));
  labels(cv::Rect(1, 1, 3, 3)).setTo(1);
  labels.at<std::uint16_t>(20, 30) = 5;  // not in instances.csv
  REQUIRE(cv::imwrite(dir.file("unknown_id.png"), labels));
  CHECK_THAT(error([&] {
               reader.read("unknown_id", {40, 30});
             }),
             Catch::Contains("unknown_id.png") && Catch::Contains("instance id 5") && Catch::Contains("x 30, y 20"));
  REQUIRE(cv::imwrite(dir.file("colour.png"), cv::Mat(30, 40, CV_8UC3, cv::Scalar::all(1))));
  CHECK_THAT(error([&] {
               reader.read("colour", {40, 30});
             }),
             Catch::Contains("colour.png") && Catch::Contains("CV_8UC3"));
  REQUIRE(cv::imwrite(dir.file("small.png"), cv::Mat(20, 40, CV_16UC1, cv::Scalar(0))));
  CHECK_THAT(error([&] {
               reader.read("small", {40, 30});
             }),
             Catch::Contains("small.png") && Catch::Contains("40 x 20") && Catch::Contains("40 x 30"));
  write_text(dir.file("garbage.png"), "not a png");
  CHECK_THAT(error([&] {
               reader.read("garbage", {40, 30});
             }),
             Catch::Contains("garbage.png") && Catch::Contains("cannot be read"));
  CHECK_THAT(error([&] { reader.read("", {40, 30}); }), Catch::Contains("not a file stem"));
  CHECK_THAT(error([&] { reader.read("../x", {40, 30}); }), Catch::Contains("not a file stem"));
  CHECK_THAT(error([&] { reader.segment({cv::Mat(), "frame"}); }), Catch::Contains("frame 'frame'"));

  // Strict mode: a frame without an image is an error.
  cge::PrecomputedMaskSettings strict;
  strict.require_every_frame = true;
  cge::PrecomputedMaskReader strict_reader(folder, strict);
  CHECK_THAT(error([&] {
               strict_reader.read("1341846313.592026", {40, 30});
             }),
             Catch::Contains("1341846313.592026.png") && Catch::Contains("no mask image"));
}
