// Tests of the TUM RGB-D folder reader: lists, association (against a literal transcription of
// associate.py), a synthetic sequence written by cge::sim and read back, every error with its
// file and line, and the real TUM frames in /work/shared when present.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cge/dataset/tum_list.hpp"
#include "cge/dataset/tum_sequence.hpp"
#include "cge/sim/frame_source.hpp"
#include "cge/sim/segmentation_error_model.hpp"
#include "cge/sim/tum_writer.hpp"
#include "dataset_test_support.hpp"
#include "temp_dir.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using cge::dataset::TumSequence;
using cge::dataset::TumSequenceSettings;
using cge_test::invalid_argument_message;
using cge_test::TempDir;

namespace {

void write_text(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary);
  out << text;
}

/// associate.py, literally: every pair under the limit, sorted by (difference, a, b), greedy.
std::vector<cge::dataset::TimestampMatch> oracle_associate(const std::vector<double>& a, const std::vector<double>& b,
                                                           double max_difference, double offset) {
  std::vector<std::tuple<double, double, double, std::size_t, std::size_t>> potential;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j)
      if (std::abs(a[i] - (b[j] + offset)) < max_difference)
        potential.emplace_back(std::abs(a[i] - (b[j] + offset)), a[i], b[j], i, j);
  std::sort(potential.begin(), potential.end());
  std::vector<bool> used_a(a.size()), used_b(b.size());
  std::vector<cge::dataset::TimestampMatch> matches;
  for (const auto& [d, ta, tb, i, j] : potential) {
    if (used_a[i] || used_b[j]) continue;
    used_a[i] = used_b[j] = true;
    matches.push_back({i, j});
  }
  std::sort(matches.begin(), matches.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  return matches;
}

bool equal_images(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a.reshape(1) != b.reshape(1)) == 0;
}

/// A folder with valid 4 x 3 images: rgb/<t>.png and depth/<t>.png for the given stems.
void write_images(const fs::path& dir, const std::vector<std::string>& stems) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  for (const std::string& s : stems) {
    cv::imwrite((dir / "rgb" / (s + ".png")).string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(1, 2, 3)));
    cv::imwrite((dir / "depth" / (s + ".png")).string(), cv::Mat(3, 4, CV_16UC1, cv::Scalar(5000)));
  }
}

std::string list(const std::vector<std::string>& stems, const std::string& sub) {
  std::string s = "# " + sub + "\n# timestamp filename\n";
  for (const std::string& t : stems) s += t + " " + sub + "/" + t + ".png\n";
  return s;
}

}  // namespace

// ---- lists ---------------------------------------------------------------------------------------

TEST_CASE("TUM list: comments, blank lines, tabs and CR are accepted", "[dataset][tum_list]") {
  std::istringstream in("# color images\n\n1.5 rgb/1.5.png\r\n  \t# indented comment\n2.25\trgb/2.25.png\n");
  const auto entries = cge::dataset::parse_tum_list(in, "rgb.txt");
  REQUIRE(entries.size() == 2);
  CHECK(entries[0].timestamp_s == 1.5);
  CHECK(entries[0].path == "rgb/1.5.png");
  CHECK(entries[0].line == 3);
  CHECK(entries[1].timestamp_s == 2.25);
  CHECK(entries[1].token == "2.25");
  CHECK(entries[1].line == 5);
}

TEST_CASE("TUM list: malformed lines are named by file and line", "[dataset][tum_list]") {
  const auto message = [](const std::string& text) {
    return invalid_argument_message([&] {
      std::istringstream in(text);
      cge::dataset::parse_tum_list(in, "lists/rgb.txt");
    });
  };
  CHECK_THAT(message("1 a.png\n2 b.png extra\n"), Contains("lists/rgb.txt:2") && Contains("3 fields"));
  CHECK_THAT(message("# c\n1.0\n"), Contains("lists/rgb.txt:2") && Contains("1 fields"));
  CHECK_THAT(message("1 a.png\nabc b.png\n"), Contains("lists/rgb.txt:2") && Contains("'abc'"));
  CHECK_THAT(message("1.5x a.png\n"), Contains("lists/rgb.txt:1"));
  CHECK_THAT(message("nan a.png\n"), Contains("lists/rgb.txt:1"));
  CHECK_THAT(message("2 a.png\n# c\n1 b.png\n"), Contains("lists/rgb.txt:3") && Contains("line 1"));
  CHECK_THAT(message("2 a.png\n2 b.png\n"), Contains("lists/rgb.txt:2"));
}

// ---- association ---------------------------------------------------------------------------------

TEST_CASE("Association: a hand-worked case", "[dataset][association]") {
  // Differences: (1.00, 1.015) 0.015; (1.00, 1.02) 0.02 (not < 0.02); (1.03, 1.015) 0.015;
  // (1.03, 1.02) 0.01. Greedy: (1.03, 1.02) first, then (1.00, 1.015); 1.10 has no partner.
  const std::vector<double> rgb = {1.00, 1.03, 1.10};
  const std::vector<double> depth = {1.015, 1.02};
  const auto m = cge::dataset::associate_timestamps(rgb, depth, 0.02);
  REQUIRE(m.size() == 2);
  CHECK(m[0] == cge::dataset::TimestampMatch{0, 0});
  CHECK(m[1] == cge::dataset::TimestampMatch{1, 1});
  // With an offset of +0.08 on depth, only 1.10 - (1.02 + 0.08) = 0 and 1.10 - 1.095 qualify.
  const auto shifted = cge::dataset::associate_timestamps(rgb, depth, 0.02, 0.08);
  REQUIRE(shifted.size() == 1);
  CHECK(shifted[0] == cge::dataset::TimestampMatch{2, 1});
}

TEST_CASE("Association: equals a literal associate.py on random lists", "[dataset][association]") {
  std::mt19937 rng(20251122);
  for (int trial = 0; trial < 300; ++trial) {
    // Timestamps on a coarse grid (many equal differences, so the tie rule matters) or continuous.
    const bool grid = trial % 2 == 0;
    std::uniform_int_distribution<int> count(0, 40);
    std::uniform_real_distribution<double> step(0.001, 0.05);
    const auto make = [&](int n) {
      std::vector<double> t;
      double x = 100.0;
      for (int i = 0; i < n; ++i) {
        x += grid ? 0.005 * (1 + static_cast<int>(rng() % 6)) : step(rng);
        t.push_back(grid ? std::round(x * 200) / 200 : x);
      }
      return t;
    };
    const std::vector<double> a = make(count(rng)), b = make(count(rng));
    const double max_difference = (trial % 3 == 0) ? 0.02 : 0.005 + 0.001 * (trial % 30);
    const double offset = (trial % 5 == 0) ? 0.01 : 0.0;
    CAPTURE(trial, a.size(), b.size(), max_difference, offset);
    CHECK(cge::dataset::associate_timestamps(a, b, max_difference, offset) ==
          oracle_associate(a, b, max_difference, offset));
  }
}

TEST_CASE("Association: invalid arguments", "[dataset][association]") {
  CHECK_THROWS_AS(cge::dataset::associate_timestamps({1, 2}, {1}, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(cge::dataset::associate_timestamps({2, 1}, {1}, 0.02), std::invalid_argument);
  CHECK_THROWS_AS(cge::dataset::associate_timestamps({1}, {1, 1}, 0.02), std::invalid_argument);
  CHECK_THROWS_AS(cge::dataset::associate_timestamps({1}, {1}, 0.02, std::nan("")), std::invalid_argument);
}

// ---- a synthetic sequence read back --------------------------------------------------------------

TEST_CASE("TumSequence: a cge::sim sequence reads back with its images and ground truth", "[dataset][tum_sequence]") {
  const auto seq = cge_test::tiny_sequence(5);
  cge::sim::SegmentationErrorModel model(seq.instances(), 3, cge::sim::exact_segmentation());
  TempDir tmp{"cge_test_dataset"};
  const fs::path dir = tmp.path() / "seq";
  cge::sim::write_tum_sequence(seq, model, dir);

  for (const bool use_file : {false, true}) {
    CAPTURE(use_file);
    TumSequenceSettings settings;
    settings.use_associations_file = use_file;
    const TumSequence s(dir, settings);
    REQUIRE(s.frame_count() == 5);
    CHECK(s.unassociated_rgb_count() == 0);
    REQUIRE(s.masks_folder());
    CHECK(*s.masks_folder() == dir / "masks");
    REQUIRE(s.segmentation_folder());
    CHECK(*s.segmentation_folder() == dir / "segmentation");
    REQUIRE(s.camera_settings_file());
    CHECK(*s.camera_settings_file() == dir / "camera.yaml");
    REQUIRE(s.ground_truth().size() == 5);
    for (int i = 0; i < 5; ++i) {
      CAPTURE(i);
      const cge::sim::RenderedFrame& truth = seq.frames[static_cast<std::size_t>(i)];
      const cge::dataset::TumFrame f = s.load(i);
      CHECK(f.index == i);
      CHECK(std::abs(f.rgb_timestamp_s - truth.timestamp_s) < 1e-6);
      CHECK(f.depth_timestamp_s == f.rgb_timestamp_s);
      CHECK(f.rgb_stem == cge::sim::format_tum_timestamp(truth.timestamp_s));
      CHECK(f.depth_stem == f.rgb_stem);
      CHECK(equal_images(f.bgr, truth.rgb));
      CHECK(equal_images(f.depth, truth.depth));
      const cv::Mat metres = f.depth_metres();
      REQUIRE(metres.type() == CV_32FC1);
      const double expected_m = truth.depth.at<std::uint16_t>(7, 9) / 5000.0;  // float: relative 1e-6
      CHECK(std::abs(metres.at<float>(7, 9) - expected_m) <= 1e-6 * expected_m);
      CHECK(f.frame_image().stem == f.rgb_stem);
      const cge::dataset::GroundTruthPose& gt = s.ground_truth()[static_cast<std::size_t>(i)];
      CHECK(std::abs(gt.timestamp_s - truth.timestamp_s) < 1e-6);
      CHECK((gt.T_world_camera.matrix() - truth.T_world_camera.matrix()).cwiseAbs().maxCoeff() < 1e-8);
    }
    CHECK_THROWS_AS(s.load(5), std::out_of_range);
    CHECK_THROWS_AS(s.load(-1), std::out_of_range);
  }
}

TEST_CASE("TumSequence: lists with unequal rates associate and drop unpaired RGB frames", "[dataset][tum_sequence]") {
  TempDir tmp{"cge_test_dataset"};
  const fs::path dir = tmp.path();
  write_images(dir, {"10.000", "10.010", "10.033", "10.066", "10.200"});
  write_text(dir / "rgb.txt", list({"10.000", "10.033", "10.066", "10.200"}, "rgb"));
  write_text(dir / "depth.txt", list({"10.010", "10.066"}, "depth"));
  const TumSequence s(dir);
  // 10.000-10.010 (0.010) and 10.066-10.066 (0) pair; 10.033 loses 10.010 to 10.000 and 10.066 to 10.066.
  REQUIRE(s.frame_count() == 2);
  CHECK(s.unassociated_rgb_count() == 2);
  CHECK(s.files(0).rgb_timestamp_s == 10.0);
  CHECK(s.files(0).depth_timestamp_s == 10.01);
  CHECK(s.files(1).rgb_timestamp_s == 10.066);
  CHECK(s.files(1).depth_path == dir / "depth/10.066.png");
  CHECK(s.files(1).rgb_source == (dir / "rgb.txt").string() + ":5");
  CHECK_FALSE(s.has_ground_truth());
  CHECK_FALSE(s.masks_folder());
  CHECK_FALSE(s.camera_settings_file());
  CHECK(s.load(1).rgb_stem == "10.066");
}

// ---- errors --------------------------------------------------------------------------------------

TEST_CASE("TumSequence: every bad input names its file and line", "[dataset][tum_sequence][errors]") {
  TempDir tmp{"cge_test_dataset"};
  const fs::path dir = tmp.path();
  write_images(dir, {"1.0", "2.0"});
  const std::string rgb_txt = (dir / "rgb.txt").string();
  const std::string depth_txt = (dir / "depth.txt").string();
  const auto open = [&dir] { return invalid_argument_message([&dir] { TumSequence s(dir); }); };
  const auto load = [&dir](int i) { return invalid_argument_message([&dir, i] { TumSequence(dir).load(i); }); };

  SECTION("missing folder") {
    CHECK_THAT(invalid_argument_message([&dir] { TumSequence s(dir / "nope"); }), Contains("nope"));
  }
  SECTION("missing rgb.txt") {
    write_text(dir / "depth.txt", list({"1.0"}, "depth"));
    CHECK_THAT(open(), Contains(rgb_txt) && Contains("does not exist"));
  }
  SECTION("missing depth.txt") {
    write_text(dir / "rgb.txt", list({"1.0"}, "rgb"));
    CHECK_THAT(open(), Contains(depth_txt) && Contains("does not exist"));
  }
  SECTION("a list that is a folder") {
    fs::create_directories(dir / "rgb.txt");
    write_text(dir / "depth.txt", list({"1.0"}, "depth"));
    CHECK_THAT(open(), Contains(rgb_txt) && Contains("not a regular file"));
  }
  SECTION("malformed line") {
    write_text(dir / "rgb.txt", list({"1.0"}, "rgb"));
    write_text(dir / "depth.txt", "# depth\n1.0 depth/1.0.png\n2.0 depth/2.0.png trailing\n");
    CHECK_THAT(open(), Contains(depth_txt + ":3") && Contains("3 fields"));
  }
  SECTION("decreasing timestamps") {
    write_text(dir / "rgb.txt", "2.0 rgb/2.0.png\n1.0 rgb/1.0.png\n");
    write_text(dir / "depth.txt", list({"1.0", "2.0"}, "depth"));
    CHECK_THAT(open(), Contains(rgb_txt + ":2") && Contains("must increase"));
  }
  SECTION("empty sequence") {
    write_text(dir / "rgb.txt", "# color images\n# nothing here\n");
    write_text(dir / "depth.txt", list({"1.0"}, "depth"));
    CHECK_THAT(open(), Contains(rgb_txt) && Contains("empty"));
  }
  SECTION("no associations") {
    write_text(dir / "rgb.txt", list({"1.0"}, "rgb"));
    write_text(dir / "depth.txt", list({"2.0"}, "depth"));
    CHECK_THAT(open(), Contains(rgb_txt) && Contains(depth_txt) && Contains("associates"));
  }
  SECTION("missing image") {
    write_text(dir / "rgb.txt", list({"1.0", "3.0"}, "rgb"));
    write_text(dir / "depth.txt", list({"1.0", "3.0"}, "depth"));
    CHECK_NOTHROW(TumSequence(dir).load(0));
    CHECK_THAT(load(1), Contains(rgb_txt + ":4") && Contains("rgb/3.0.png") && Contains("does not exist"));
  }
  SECTION("unreadable image") {
    write_text(dir / "rgb" / "2.0.png", "this is not a PNG");
    write_text(dir / "rgb.txt", list({"1.0", "2.0"}, "rgb"));
    write_text(dir / "depth.txt", list({"1.0", "2.0"}, "depth"));
    CHECK_THAT(load(1), Contains(rgb_txt + ":4") && Contains("rgb/2.0.png") && Contains("cannot read"));
  }
  SECTION("depth image not 16-bit") {
    cv::imwrite((dir / "depth" / "2.0.png").string(), cv::Mat(3, 4, CV_8UC1, cv::Scalar(9)));
    write_text(dir / "rgb.txt", list({"1.0", "2.0"}, "rgb"));
    write_text(dir / "depth.txt", list({"1.0", "2.0"}, "depth"));
    CHECK_THAT(load(1), Contains(depth_txt + ":4") && Contains("CV_16UC1"));
  }
  SECTION("RGB and depth of different sizes") {
    cv::imwrite((dir / "depth" / "2.0.png").string(), cv::Mat(4, 4, CV_16UC1, cv::Scalar(9)));
    write_text(dir / "rgb.txt", list({"1.0", "2.0"}, "rgb"));
    write_text(dir / "depth.txt", list({"1.0", "2.0"}, "depth"));
    CHECK_THAT(load(1),
               Contains(rgb_txt + ":4") && Contains(depth_txt + ":4") && Contains("4 x 3") && Contains("4 x 4"));
  }
  SECTION("malformed ground truth") {
    write_text(dir / "rgb.txt", list({"1.0"}, "rgb"));
    write_text(dir / "depth.txt", list({"1.0"}, "depth"));
    const std::string gt = (dir / "groundtruth.txt").string();
    write_text(dir / "groundtruth.txt", "# gt\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
    CHECK_THAT(open(), Contains(gt + ":3") && Contains("found 7"));
    write_text(dir / "groundtruth.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 x\n");
    CHECK_THAT(open(), Contains(gt + ":2") && Contains("qw"));
    write_text(dir / "groundtruth.txt", "1.0 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n");
    CHECK_THAT(open(), Contains(gt + ":2") && Contains("must not decrease"));
    write_text(dir / "groundtruth.txt", "1.0 0 0 0 0 0 0 1\n1.0 1 0 0 0 0 0 1\n");  // equal: both kept
    CHECK(TumSequence(dir).ground_truth().size() == 2);
    write_text(dir / "groundtruth.txt", "1.0 0 0 0 0 0 0 2\n");
    CHECK_THAT(open(), Contains(gt + ":1") && Contains("norm"));
  }
  SECTION("malformed associations.txt, when used") {
    write_text(dir / "associations.txt", "1.0 rgb/1.0.png 1.0\n");
    TumSequenceSettings settings;
    settings.use_associations_file = true;
    CHECK_THAT(invalid_argument_message([&] { TumSequence s(dir, settings); }),
               Contains((dir / "associations.txt").string() + ":1") && Contains("3 fields"));
    // Not used by default: the missing lists are the error then.
    CHECK_THAT(open(), Contains(rgb_txt));
  }
  SECTION("invalid settings") {
    TumSequenceSettings settings;
    settings.depth_units_per_metre = 0;
    CHECK_THAT(invalid_argument_message([&] { TumSequence s(dir, settings); }), Contains("depth_units_per_metre"));
  }
}

// ---- real TUM frames -----------------------------------------------------------------------------

TEST_CASE("TumSequence: real TUM fr3 walking_xyz frames (skipped when /work/shared is absent)",
          "[dataset][tum_sequence][real]") {
  const fs::path data = fs::path(CGE_SHARED_DIR) / "data" / "tum_fr3_walking_xyz";
  if (!fs::is_directory(data / "rgb") || !fs::is_directory(data / "depth")) {
    WARN("skipped: " << data.string() << " not found");
    return;
  }
  // The shared folder has images but no lists: write TUM lists that point at them (absolute paths).
  std::vector<fs::path> rgb, depth;
  for (const auto& e : fs::directory_iterator(data / "rgb")) rgb.push_back(e.path());
  for (const auto& e : fs::directory_iterator(data / "depth")) depth.push_back(e.path());
  std::sort(rgb.begin(), rgb.end());
  std::sort(depth.begin(), depth.end());
  if (rgb.size() != 3 || depth.size() != 2) {
    WARN("skipped: expected 3 RGB and 2 depth images in " << data.string());
    return;
  }
  TempDir tmp{"cge_test_dataset_real"};
  std::string rgb_txt = "# color images\n", depth_txt = "# depth maps\n";
  for (const fs::path& p : rgb) rgb_txt += p.stem().string() + " " + p.string() + "\n";
  for (const fs::path& p : depth) depth_txt += p.stem().string() + " " + p.string() + "\n";
  write_text(tmp.path() / "rgb.txt", rgb_txt);
  write_text(tmp.path() / "depth.txt", depth_txt);
  const TumSequence s(tmp.path());
  // README: depth of the first two frames 62 and 25 microseconds after the RGB; none for the third.
  REQUIRE(s.frame_count() == 2);
  CHECK(s.unassociated_rgb_count() == 1);
  for (int i = 0; i < 2; ++i) {
    const cge::dataset::TumFrame f = s.load(i);
    CHECK(f.rgb_stem == rgb[static_cast<std::size_t>(i)].stem().string());
    CHECK(f.depth_stem == depth[static_cast<std::size_t>(i)].stem().string());
    CHECK(f.bgr.type() == CV_8UC3);
    CHECK(f.bgr.cols == 640);
    CHECK(f.bgr.rows == 480);
    CHECK(f.depth.type() == CV_16UC1);
    CHECK(std::abs(f.depth_timestamp_s - f.rgb_timestamp_s) < 1e-4);
  }
}

TEST_CASE("TumSequence: the official fr1_xyz and fr2_desk ground truth (skipped when /work/shared is absent)",
          "[dataset][tum_sequence][real]") {
  const fs::path dir = fs::path(CGE_SHARED_DIR) / "data" / "tum_trajectories";
  for (const char* name : {"freiburg1_xyz-groundtruth.txt", "fr2_desk_groundtruth.txt"}) {
    CAPTURE(name);
    const fs::path file = dir / name;
    if (!fs::is_regular_file(file)) {
      WARN("skipped: " << file.string() << " not found");
      continue;
    }
    TempDir tmp{"cge_test_dataset_gt"};
    write_images(tmp.path(), {"1.0"});
    write_text(tmp.path() / "rgb.txt", list({"1.0"}, "rgb"));
    write_text(tmp.path() / "depth.txt", list({"1.0"}, "depth"));
    fs::copy_file(file, tmp.path() / "groundtruth.txt");
    const TumSequence s(tmp.path());

    // Independent parse: every non-comment line, quaternion normalised here.
    std::ifstream in(file);
    std::vector<std::vector<double>> rows;
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::vector<double> v(8);
      for (double& x : v) fields >> x;
      rows.push_back(v);
    }
    REQUIRE(s.ground_truth().size() == rows.size());
    double worst = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::vector<double>& v = rows[i];
      const Eigen::Quaterniond q = Eigen::Quaterniond(v[7], v[4], v[5], v[6]).normalized();
      Eigen::Matrix4d expected = Eigen::Matrix4d::Identity();
      expected.topLeftCorner<3, 3>() = q.toRotationMatrix();
      expected.topRightCorner<3, 1>() = Eigen::Vector3d(v[1], v[2], v[3]);
      CHECK(s.ground_truth()[i].timestamp_s == v[0]);
      worst = std::max(worst, (s.ground_truth()[i].T_world_camera.matrix() - expected).cwiseAbs().maxCoeff());
    }
    CHECK(worst < 1e-12);
  }
}
