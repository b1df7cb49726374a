// Readers and writer of the metrics module: TUM trajectories, ground-truth loops.txt, loops.csv.
// Every malformed input names its source and line; values are checked against the text itself.

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cge/metrics/ground_truth_loops_io.hpp"
#include "cge/metrics/loop_queries_io.hpp"
#include "cge/metrics/tum_trajectory_io.hpp"
#include "loop_queries_text.hpp"
#include "test_support.hpp"

using namespace cge::metrics;

namespace {

Trajectory read_text(const std::string& text, const TumReadSettings& settings = {}) {
  std::istringstream in(text);
  return read_tum_trajectory(in, "traj.txt", settings);
}

std::string tum_error(const std::string& text, const TumReadSettings& settings = {}) {
  return cge_test::invalid_argument_message([&] { read_text(text, settings); });
}

std::vector<GroundTruthLoop> read_loops_text(const std::string& text) {
  std::istringstream in(text);
  return read_ground_truth_loops(in, "loops.txt");
}

std::string loops_error(const std::string& text) {
  return cge_test::invalid_argument_message([&] { read_loops_text(text); });
}

const std::string kHeader =
    "query_timestamp,match_timestamp,query_keyframe,match_keyframe,bow_score,cge_score,matched_points,accepted,"
    "reason\n";

using cge_test::loops_csv_error;
using cge_test::read_loops_csv_text;

}  // namespace

TEST_CASE("TUM reader: fields, comments, blank lines, commas, CRLF, BOM", "[metrics]") {
  const std::string text =
      "\xEF\xBB\xBF# ground truth trajectory\n"
      "\n"
      "  # an indented comment\n"
      "1.5 1 2 3 0 0 0 1\r\n"
      "2.25,\t-1,0.5,+4,0,0,1,0\n"
      "3 0 0 0 0 0 0.70710678 0.70710678   \n";
  const Trajectory t = read_text(text);
  REQUIRE(t.size() == 3);
  CHECK(t[0].timestamp_s == 1.5);
  CHECK(t[0].T_world_camera.translation() == Eigen::Vector3d(1, 2, 3));
  CHECK(t[0].T_world_camera.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  CHECK(t[1].timestamp_s == 2.25);
  CHECK(t[1].T_world_camera.translation() == Eigen::Vector3d(-1, 0.5, 4));
  // q = (x 0, y 0, z 1, w 0): 180 degrees about z.
  Eigen::Matrix3d rz180;
  rz180 << -1, 0, 0, 0, -1, 0, 0, 0, 1;
  CHECK(t[1].T_world_camera.linear().isApprox(rz180, 1e-15));
  // 90 degrees about z, the quaternion normalised (its norm is 1 - 3e-9).
  Eigen::Matrix3d rz90;
  rz90 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  CHECK((t[2].T_world_camera.linear() - rz90).cwiseAbs().maxCoeff() < 1e-15);
  CHECK(std::abs(t[2].T_world_camera.linear().determinant() - 1.0) < 1e-15);
}

TEST_CASE("TUM reader: an input without poses gives an empty trajectory", "[metrics]") {
  CHECK(read_text("").empty());
  CHECK(read_text("# only a comment\n\n").empty());
}

TEST_CASE("TUM reader: malformed lines name the source and line", "[metrics]") {
  CHECK_THAT(tum_error("# c\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n"),
             Catch::Contains("traj.txt:3: expected 8 fields") && Catch::Contains("found 7"));
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1 9\n"), Catch::Contains("traj.txt:1: expected 8 fields"));
  CHECK_THAT(tum_error("1\n"), Catch::Contains("traj.txt:1: expected 8 fields"));
  CHECK_THAT(tum_error("1 0 zero 0 0 0 0 1\n"), Catch::Contains("traj.txt:1: ty 'zero' is not a number"));
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1x\n"), Catch::Contains("traj.txt:1: qw '1x' is not a number"));
  CHECK_THAT(tum_error("1 0 0 nan 0 0 0 1\n"), Catch::Contains("traj.txt:1: tz 'nan' is not finite"));
  CHECK_THAT(tum_error("inf 0 0 0 0 0 0 1\n"), Catch::Contains("traj.txt:1: timestamp 'inf' is not finite"));
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1e999\n"), Catch::Contains("traj.txt:1: qw '1e999' is not a number"));
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 2\n"),
             Catch::Contains("traj.txt:2: quaternion norm 2.0") && Catch::Contains("not close to 1"));
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 0\n"), Catch::Contains("traj.txt:1: quaternion norm 0.0"));
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1\n# c\n0.5 0 0 0 0 0 0 1\n"),
             Catch::Contains("traj.txt:3: timestamp 0.5 does not come after the one on line 1"));
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n"),
             Catch::Contains("traj.txt:2: timestamp 1.0 repeats the one on line 1"));
  // A '#' after the first field is not a comment.
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1 # trailing\n"), Catch::Contains("traj.txt:1: expected 8 fields"));
}

TEST_CASE("TUM reader: the quaternion tolerance is a setting", "[metrics]") {
  TumReadSettings loose;
  loose.max_quaternion_norm_error = 1.5;
  const Trajectory t = read_text("1 0 0 0 0 0 0 2\n", loose);
  REQUIRE(t.size() == 1);
  CHECK(t[0].T_world_camera.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  TumReadSettings strict;
  strict.max_quaternion_norm_error = 0;
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1.0001\n", strict), Catch::Contains("traj.txt:1: quaternion norm"));
  strict.max_quaternion_norm_error = -1;
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1\n", strict), Catch::Contains("max_quaternion_norm_error"));
}

TEST_CASE("TUM reader: positions beyond max_abs_translation_m are refused, naming the field", "[metrics]") {
  // The default bound (1e6 m): 1000 km passes, beyond it the line is refused.
  CHECK(read_text("1 1000000 -1000000 0 0 0 0 1\n").size() == 1);
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1\n2 02010625800 0 0 0 0 0 1\n"),
             Catch::Contains("traj.txt:2: tx '02010625800' lies beyond 1e+06 m"));
  CHECK_THAT(tum_error("1 0 0 -3e9 0 0 0 1\n"), Catch::Contains("traj.txt:1: tz '-3e9'"));
  TumReadSettings any;
  any.max_abs_translation_m = std::numeric_limits<double>::infinity();
  CHECK(read_text("1 0 0 -3e9 0 0 0 1\n", any).size() == 1);
  any.max_abs_translation_m = 0;
  CHECK_THAT(tum_error("1 0 0 0 0 0 0 1\n", any), Catch::Contains("max_abs_translation_m must be > 0"));
}

TEST_CASE("TUM reader: keep_last replaces a pose with a repeated stamp, as the TUM tools do", "[metrics]") {
  TumReadSettings settings;
  settings.duplicate_timestamps = DuplicateTimestamps::keep_last;
  std::istringstream in("1 0 0 0 0 0 0 1\n2 5 0 0 0 0 0 1\n# c\n2 7 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n");
  TumReadReport report;
  const Trajectory t = read_tum_trajectory(in, "traj.txt", settings, &report);
  REQUIRE(t.size() == 3);
  CHECK(t[1].timestamp_s == 2);
  CHECK(t[1].T_world_camera.translation().x() == 7);
  CHECK(report.replaced_lines == std::vector<std::size_t>{2});
  // Decreasing stamps stay an error.
  CHECK_THAT(tum_error("2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", settings), Catch::Contains("traj.txt:2:"));
}

TEST_CASE("TUM reader: keep_all keeps every line of a repeated stamp, in file order", "[metrics]") {
  TumReadSettings settings;
  settings.duplicate_timestamps = DuplicateTimestamps::keep_all;
  std::istringstream in("1 0 0 0 0 0 0 1\n2 5 0 0 0 0 0 1\n2 7 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n");
  const Trajectory t = read_tum_trajectory(in, "traj.txt", settings);
  REQUIRE(t.size() == 4);
  CHECK(t[1].timestamp_s == 2);
  CHECK(t[2].timestamp_s == 2);
  CHECK(t[1].T_world_camera.translation().x() == 5);
  CHECK(t[2].T_world_camera.translation().x() == 7);
  CHECK_THAT(tum_error("2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", settings),
             Catch::Contains("traj.txt:2:") && Catch::Contains("must not decrease"));
}

TEST_CASE("TUM reader: a missing file or a folder is named", "[metrics]") {
  CHECK_THAT(cge_test::invalid_argument_message([] { read_tum_trajectory_file("/nonexistent/cge/traj.txt"); }),
             Catch::Contains("cannot open '/nonexistent/cge/traj.txt'"));
  CHECK_THAT(cge_test::invalid_argument_message([] { read_tum_trajectory_file("/"); }),
             Catch::Contains("'/': it is a directory"));
}

TEST_CASE("TUM writer: format and a round trip", "[metrics]") {
  Trajectory t(3);
  t[0].timestamp_s = 1305031102.1604071;
  t[0].T_world_camera.translation() = Eigen::Vector3d(1.3563, -0.000012345678912, 0);
  t[1].timestamp_s = 1305031102.194330;
  t[1].T_world_camera.linear() = Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  t[1].T_world_camera.translation() = Eigen::Vector3d(-0.1, 0.2, 123.456789123);
  t[2].timestamp_s = 1305031102.226738;
  t[2].T_world_camera.linear() = Eigen::AngleAxisd(std::acos(-1.0), Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::ostringstream out;
  write_tum_trajectory(out, t);
  const std::string text = out.str();
  std::istringstream lines(text);
  std::string header, line0, line1, line2;
  std::getline(lines, header);
  std::getline(lines, line0);
  std::getline(lines, line1);
  std::getline(lines, line2);
  CHECK(header == "# timestamp tx ty tz qx qy qz qw");
  // 6 decimals for the stamp, 9 significant digits, no negative zero, qw >= 0.
  CHECK(line0 == "1305031102.160407 1.3563 -1.23456789e-05 0 0 0 0 1");
  CHECK(line1.rfind("1305031102.194330 -0.1 0.2 123.456789 ", 0) == 0);
  // 180 degrees about x: q = (1, 0, 0, ~0); whatever rounding leaves in qw, it is not negative.
  REQUIRE(line2.rfind("1305031102.226738 0 0 0 1 0 0 ", 0) == 0);
  const double qw = std::stod(line2.substr(std::string("1305031102.226738 0 0 0 1 0 0 ").size()));
  CHECK(qw >= 0);
  CHECK(qw < 1e-15);
  std::istringstream in(text);
  const Trajectory back = read_tum_trajectory(in, "written");
  REQUIRE(back.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(std::abs(back[i].timestamp_s - t[i].timestamp_s) <= 5e-7);
    CHECK((back[i].T_world_camera.matrix() - t[i].T_world_camera.matrix()).cwiseAbs().maxCoeff() <= 1e-6);
  }
  // The quaternion of line 1: (axis sin 1, cos 1) with qw = cos(1) > 0, 9 significant digits.
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 3).normalized() * std::sin(1.0);
  std::istringstream f1(line1);
  double v[8];
  for (double& x : v) f1 >> x;
  CHECK(std::abs(v[4] - axis.x()) < 1e-9);
  CHECK(std::abs(v[5] - axis.y()) < 1e-9);
  CHECK(std::abs(v[6] - axis.z()) < 1e-9);
  CHECK(std::abs(v[7] - std::cos(1.0)) < 1e-9);
}

TEST_CASE("TUM writer: refuses stamps that collide with 6 decimals and non-finite poses", "[metrics]") {
  Trajectory t(2);
  t[0].timestamp_s = 1.0000001;
  t[1].timestamp_s = 1.0000002;
  std::ostringstream out;
  CHECK_THAT(cge_test::invalid_argument_message([&] { write_tum_trajectory(out, t); }),
             Catch::Contains("do not increase with 6 decimals"));
  t[1].timestamp_s = 2;
  t[1].T_world_camera.translation().x() = std::nan("");
  CHECK_THAT(cge_test::invalid_argument_message([&] { write_tum_trajectory(out, t); }), Catch::Contains("not finite"));
  CHECK(out.str().empty());
}

TEST_CASE("ground-truth loops reader: the sim's loops.txt", "[metrics]") {
  const std::vector<GroundTruthLoop> loops = read_loops_text(
      "# ground-truth loops\n# file: 'x'\n# query_timestamp match_timestamp query_index match_index\n"
      "1000.500000 1000.033333 15 1\n"
      "\n"
      "1000.533333,1000.066667,16,2\n");
  REQUIRE(loops.size() == 2);
  CHECK(loops[0].query_timestamp_s == 1000.5);
  CHECK(loops[0].match_timestamp_s == 1000.033333);
  CHECK(loops[0].query_index == 15);
  CHECK(loops[0].match_index == 1);
  CHECK(loops[0].line == 4);
  CHECK(loops[1].query_index == 16);
  CHECK(loops[1].line == 6);
  CHECK(read_loops_text("# no loops\n").empty());
}

TEST_CASE("ground-truth loops reader: malformed lines", "[metrics]") {
  CHECK_THAT(loops_error("# c\n1 0.5 2\n"), Catch::Contains("loops.txt:2: expected 4 fields"));
  CHECK_THAT(loops_error("x 0.5 2 1\n"), Catch::Contains("loops.txt:1: query_timestamp 'x' is not a finite number"));
  CHECK_THAT(loops_error("1 nan 2 1\n"), Catch::Contains("loops.txt:1: match_timestamp 'nan'"));
  CHECK_THAT(loops_error("1 0.5 -2 1\n"), Catch::Contains("loops.txt:1: query_index '-2' is not a non-negative"));
  CHECK_THAT(loops_error("1 0.5 2 1.5\n"), Catch::Contains("loops.txt:1: match_index '1.5'"));
  CHECK_THAT(loops_error("1 0.5 2 2\n"), Catch::Contains("loops.txt:1: match_index 2 is not smaller"));
  CHECK_THAT(loops_error("1 1.5 2 1\n"), Catch::Contains("loops.txt:1: match_timestamp 1.5 is not earlier"));
}

TEST_CASE("loops.csv reader: rows with and without a match", "[metrics]") {
  const std::vector<LoopQuery> rows =
      read_loops_csv_text(kHeader +
                          "1000.100000,,3,,,,,0,no_candidates\n"
                          "1000.200000,1000.000000,4,0,0.5,0.25,12,0,too_few_matches\r\n"
                          "1000.300000,1000.033333,5,1,0.75,0.875,60,1,accepted\n");
  REQUIRE(rows.size() == 3);
  CHECK(rows[0].query_timestamp_s == 1000.1);
  CHECK_FALSE(rows[0].match_timestamp_s.has_value());
  CHECK_FALSE(rows[0].match_keyframe.has_value());
  CHECK_FALSE(rows[0].bow_score.has_value());
  CHECK_FALSE(rows[0].accepted);
  CHECK(rows[0].reason == "no_candidates");
  CHECK(rows[0].line == 2);
  CHECK(*rows[1].match_timestamp_s == 1000.0);
  CHECK(*rows[1].match_keyframe == 0);
  CHECK(*rows[1].bow_score == 0.5);
  CHECK(*rows[1].cge_score == 0.25);
  CHECK(*rows[1].matched_points == 12);
  CHECK(rows[1].reason == "too_few_matches");
  CHECK(rows[2].accepted);
  CHECK(rows[2].query_keyframe == 5);
  CHECK(read_loops_csv_text(kHeader).empty());
}

TEST_CASE("loops.csv reader: malformed input", "[metrics]") {
  CHECK_THAT(loops_csv_error(""), Catch::Contains("loops.csv:1: no header line"));
  CHECK_THAT(loops_csv_error("query_timestamp,match_timestamp\n"), Catch::Contains("loops.csv:1: expected the header"));
  CHECK_THAT(loops_csv_error(kHeader + "1,,3,,,,,0\n"),
             Catch::Contains("loops.csv:2: expected 9 comma-separated fields, found 8"));
  CHECK_THAT(loops_csv_error(kHeader + ",,3,,,,,0,low_score\n"),
             Catch::Contains("loops.csv:2: query_timestamp is empty"));
  CHECK_THAT(loops_csv_error(kHeader + "t,,3,,,,,0,low_score\n"), Catch::Contains("loops.csv:2: query_timestamp 't'"));
  CHECK_THAT(loops_csv_error(kHeader + "1,,-3,,,,,0,low_score\n"), Catch::Contains("loops.csv:2: query_keyframe '-3'"));
  CHECK_THAT(loops_csv_error(kHeader + "1,0.5,3,1,high,,,0,low_score\n"),
             Catch::Contains("loops.csv:2: bow_score 'high'"));
  CHECK_THAT(loops_csv_error(kHeader + "1,0.5,3,1,,,,yes,low_score\n"),
             Catch::Contains("loops.csv:2: accepted 'yes' is not 0 or 1"));
  CHECK_THAT(loops_csv_error(kHeader + "1,0.5,3,1,,,,0,\n"), Catch::Contains("loops.csv:2: reason is empty"));
  CHECK_THAT(loops_csv_error(kHeader + "1,0.5,3,1,,,,0,Low score\n"),
             Catch::Contains("loops.csv:2: reason 'Low score'"));
  CHECK_THAT(loops_csv_error(kHeader + "1,0.5,3,1,,,,1,low_score\n"),
             Catch::Contains("loops.csv:2: accepted is 1 but the reason is 'low_score'"));
  CHECK_THAT(loops_csv_error(kHeader + "1,0.5,3,1,,,,0,accepted\n"), Catch::Contains("loops.csv:2: accepted is 0"));
  CHECK_THAT(loops_csv_error(kHeader + "1,,3,,,,,1,accepted\n"), Catch::Contains("loops.csv:2: an accepted row needs"));
  CHECK_THAT(loops_csv_error(kHeader + "1,0.5,3,,,,,0,low_score\n"),
             Catch::Contains("loops.csv:2: match_timestamp and match_keyframe"));
}
