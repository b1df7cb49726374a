// The pipeline's geometry toolkit (cge/slam/geometry/): NearestTwo, one-to-one descriptor matching,
// projection matching, PnP RANSAC and its pose conversion. Oracles: brute force over every pair,
// hand-built cameras and points with known poses, Eigen's angle-axis rotation.

#include <catch2/catch.hpp>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/bow/binary_descriptor.hpp"
#include "cge/slam/frame.hpp"
#include "cge/slam/geometry/descriptor_matching.hpp"
#include "cge/slam/geometry/nearest_two.hpp"
#include "cge/slam/geometry/pnp_ransac.hpp"
#include "cge/slam/geometry/projection_matching.hpp"
#include "cge/slam/two_nearest_descriptors.hpp"

using cge::slam::DescriptorPair;
using cge::slam::Frame;
using cge::slam::KeypointGrid;
using cge::slam::NearestTwo;
using cge::slam::OneToOneRule;
using cge::slam::PointToProject;
using cge::slam::ProjectionSearch;

namespace {

cv::Mat random_descriptors(int rows, std::mt19937& rng) {
  cv::Mat m(rows, 32, CV_8UC1);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < 32; ++c) m.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(byte(rng));
  return m;
}

/// `base` with the first `bits` bits flipped: Hamming distance exactly `bits` from it.
cv::Mat flipped(const cv::Mat& base_row, int bits) {
  cv::Mat out = base_row.clone();
  for (int b = 0; b < bits; ++b) out.at<std::uint8_t>(0, b / 8) ^= static_cast<std::uint8_t>(1u << (b % 8));
  return out;
}

int hamming(const cv::Mat& a, int ra, const cv::Mat& b, int rb) {
  int d = 0;
  for (int c = 0; c < 32; ++c) {
    unsigned x = static_cast<unsigned>(a.at<std::uint8_t>(ra, c) ^ b.at<std::uint8_t>(rb, c));
    while (x) {
      d += static_cast<int>(x & 1u);
      x >>= 1;
    }
  }
  return d;
}

cge::PinholeIntrinsics<double> test_camera() {
  cge::PinholeIntrinsics<double> k;
  k.fx_px = 500;
  k.fy_px = 510;
  k.cx_px = 320;
  k.cy_px = 240;
  return k;
}

/// A 640 x 480 frame whose keypoints sit at `pixels` with `descriptors`, all static.
Frame frame_with(const std::vector<cv::Point2f>& pixels, const cv::Mat& descriptors) {
  Frame f;
  f.image_size = cv::Size(640, 480);
  f.undistorted_bounds = {0, 0, 640, 480};
  for (const cv::Point2f& p : pixels) {
    f.keypoints.emplace_back(p, 8.f);
    f.undistorted_px.push_back(p);
    f.labels.push_back(cge::FeatureLabel::static_feature);
    f.points_camera_m.emplace_back(0, 0, 1);
  }
  f.descriptors = descriptors.clone();
  return f;
}

}  // namespace

TEST_CASE("NearestTwo keeps the two smallest distances, the earlier candidate on ties", "[slam_geometry]") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> dist(0, 20);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = trial % 6;
    std::vector<int> d(static_cast<std::size_t>(n));
    NearestTwo nearest;
    for (int i = 0; i < n; ++i) {
      d[static_cast<std::size_t>(i)] = dist(rng);
      nearest.add(i, d[static_cast<std::size_t>(i)]);
    }
    // Oracle: a stable sort of (distance, index).
    std::vector<int> order(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return d[static_cast<std::size_t>(a)] < d[static_cast<std::size_t>(b)]; });
    if (n == 0) {
      CHECK(nearest.best_index == -1);
      CHECK_FALSE(nearest.passes(256, 1.0));
      continue;
    }
    CHECK(nearest.best_index == order[0]);
    CHECK(nearest.best == d[static_cast<std::size_t>(order[0])]);
    if (n > 1) {
      CHECK(nearest.second_index == order[1]);
      CHECK(nearest.second == d[static_cast<std::size_t>(order[1])]);
    } else {
      CHECK(nearest.second_index == -1);
    }
  }
}

TEST_CASE("NearestTwo::passes applies the distance and ratio tests", "[slam_geometry]") {
  NearestTwo one;
  one.add(3, 40);
  CHECK(one.passes(40, 0.5));  // no second candidate: no ratio test
  CHECK_FALSE(one.passes(39, 0.5));
  NearestTwo two;
  two.add(0, 30);
  two.add(1, 40);
  CHECK(two.passes(50, 0.76));        // 30 < 30.4
  CHECK_FALSE(two.passes(50, 0.75));  // 30 < 30 fails: strict
  CHECK_FALSE(two.passes(29, 1.0));
}

TEST_CASE("two_nearest_descriptors agrees with a brute-force sort", "[slam_geometry]") {
  std::mt19937 rng(11);
  const cv::Mat query = random_descriptors(30, rng);
  const cv::Mat train = random_descriptors(25, rng);
  const auto knn = cge::slam::two_nearest_descriptors(query, train);
  REQUIRE(knn.size() == 30);
  for (int q = 0; q < query.rows; ++q) {
    std::vector<std::pair<int, int>> all;  // (distance, train row)
    for (int t = 0; t < train.rows; ++t) all.emplace_back(hamming(query, q, train, t), t);
    std::sort(all.begin(), all.end());
    const auto& k = knn[static_cast<std::size_t>(q)];
    REQUIRE(k.size() == 2);
    CHECK(k[0].trainIdx == all[0].second);
    CHECK(static_cast<int>(k[0].distance) == all[0].first);
    CHECK(k[1].trainIdx == all[1].second);
    CHECK(static_cast<int>(k[1].distance) == all[1].first);
  }
}

TEST_CASE("match_descriptors_one_to_one agrees with brute force under both rules", "[slam_geometry]") {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    // Train rows are noisy copies of a few queries, so several queries compete for one row.
    const cv::Mat query = random_descriptors(40, rng);
    cv::Mat train(12, 32, CV_8UC1);
    std::uniform_int_distribution<int> pick(0, 39), bits(0, 60);
    for (int t = 0; t < train.rows; ++t) flipped(query.row(pick(rng)), bits(rng)).copyTo(train.row(t));
    const int max_distance = 50;
    const double ratio = 0.8;
    for (const OneToOneRule rule : {OneToOneRule::closest, OneToOneRule::first_claim}) {
      // Oracle: every pair's distance, each query's two nearest by a sort, then the claims.
      std::vector<DescriptorPair> claim(static_cast<std::size_t>(train.rows));
      for (int q = 0; q < query.rows; ++q) {
        std::vector<std::pair<int, int>> all;
        for (int t = 0; t < train.rows; ++t) all.emplace_back(hamming(query, q, train, t), t);
        std::sort(all.begin(), all.end());
        if (all[0].first > max_distance || !(all[0].first < ratio * all[1].first)) continue;
        DescriptorPair& c = claim[static_cast<std::size_t>(all[0].second)];
        const bool take = c.query < 0 || (rule == OneToOneRule::closest && all[0].first < c.distance);
        if (take) c = DescriptorPair{q, all[0].second, all[0].first};
      }
      std::vector<DescriptorPair> expected;
      for (const DescriptorPair& c : claim)
        if (c.query >= 0) expected.push_back(c);
      const std::vector<DescriptorPair> got =
          cge::slam::match_descriptors_one_to_one(query, train, max_distance, ratio, rule);
      REQUIRE(got.size() == expected.size());
      for (std::size_t i = 0; i < got.size(); ++i) {
        CHECK(got[i].query == expected[i].query);
        CHECK(got[i].train == expected[i].train);
        CHECK(got[i].distance == expected[i].distance);
      }
    }
  }
}

TEST_CASE("match_descriptors_one_to_one: the closest claimant wins, or the first", "[slam_geometry]") {
  std::mt19937 rng(5);
  const cv::Mat train = random_descriptors(2, rng);
  cv::Mat query;
  query.push_back(flipped(train.row(0), 20));  // query 0 claims train 0 at 20 bits
  query.push_back(flipped(train.row(0), 5));   // query 1 claims train 0 at 5 bits
  query.push_back(flipped(train.row(1), 5));   // query 2 claims train 1 at 5 bits
  const auto closest = cge::slam::match_descriptors_one_to_one(query, train, 64, 0.9, OneToOneRule::closest);
  REQUIRE(closest.size() == 2);
  CHECK(closest[0].train == 0);
  CHECK(closest[0].query == 1);
  CHECK(closest[0].distance == 5);
  CHECK(closest[1].query == 2);
  const auto first = cge::slam::match_descriptors_one_to_one(query, train, 64, 0.9, OneToOneRule::first_claim);
  REQUIRE(first.size() == 2);
  CHECK(first[0].query == 0);
  CHECK(first[0].distance == 20);
  // The distance test drops query 0 at 19 bits; empty inputs give nothing.
  const auto tight = cge::slam::match_descriptors_one_to_one(query, train, 19, 0.9, OneToOneRule::first_claim);
  REQUIRE(tight.size() == 2);
  CHECK(tight[0].query == 1);
  CHECK(cge::slam::match_descriptors_one_to_one(cv::Mat(), train, 64, 0.9).empty());
  CHECK(cge::slam::match_descriptors_one_to_one(query, cv::Mat(), 64, 0.9).empty());
  CHECK_THROWS_AS(cge::slam::match_descriptors_one_to_one(cv::Mat(2, 16, CV_8UC1), train, 64, 0.9),
                  std::invalid_argument);
}

TEST_CASE("isometry_from_rvec_tvec is the angle-axis rotation and the translation", "[slam_geometry]") {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const double angle = 0.7;
  const cv::Mat rvec = (cv::Mat_<double>(3, 1) << axis.x() * angle, axis.y() * angle, axis.z() * angle);
  const cv::Mat tvec = (cv::Mat_<double>(3, 1) << 0.1, -2.0, 3.5);
  const Eigen::Isometry3d T = cge::slam::isometry_from_rvec_tvec(rvec, tvec);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  CHECK((T.linear() - R).norm() < 1e-12);
  CHECK((T.translation() - Eigen::Vector3d(0.1, -2.0, 3.5)).norm() == 0.0);
  const cv::Matx33d K = cge::slam::camera_matrix(test_camera());
  CHECK(K(0, 0) == 500);
  CHECK(K(1, 1) == 510);
  CHECK(K(0, 2) == 320);
  CHECK(K(1, 2) == 240);
  CHECK(K(2, 2) == 1);
  CHECK(K(1, 0) == 0);
}

TEST_CASE("solve_pnp_ransac recovers a known pose and rejects the outliers", "[slam_geometry]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  Eigen::Isometry3d T_camera_world = Eigen::Isometry3d::Identity();
  T_camera_world.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.1, 1, 0.2).normalized()).toRotationMatrix();
  T_camera_world.translation() = Eigen::Vector3d(0.3, -0.1, 0.5);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> xy(-1.5, 1.5), z(2.0, 5.0), offset(30, 80);
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  std::vector<int> outliers;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d p_camera(xy(rng), xy(rng), z(rng));
    const Eigen::Vector3d X = T_camera_world.inverse() * p_camera;
    Eigen::Vector2d uv = K.project(p_camera);
    if (i % 6 == 5) {  // every sixth correspondence is wrong by 30 .. 80 px
      uv.x() += offset(rng);
      outliers.push_back(i);
    }
    object.emplace_back(X.x(), X.y(), X.z());
    image.emplace_back(uv.x(), uv.y());
  }
  const cge::slam::PnpRansacResult r = cge::slam::solve_pnp_ransac(object, image, K, {});
  REQUIRE(r.ok);
  CHECK((r.T_camera_object.matrix() - T_camera_world.matrix()).norm() < 1e-6);
  CHECK(r.inliers.size() == 50);
  for (const int o : outliers) CHECK(std::find(r.inliers.begin(), r.inliers.end(), o) == r.inliers.end());
}

TEST_CASE("solve_pnp_ransac reports no pose for unusable input instead of throwing", "[slam_geometry]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  // Three correspondences: fewer than a RANSAC sample.
  const std::vector<cv::Point3d> object = {{0, 0, 3}, {1, 0, 3}, {0, 1, 3}};
  const std::vector<cv::Point2d> image = {{320, 240}, {486.7, 240}, {320, 410}};
  cge::slam::PnpRansacResult r;
  CHECK_NOTHROW(r = cge::slam::solve_pnp_ransac(object, image, K, {}));
  CHECK_FALSE(r.ok);
  // Unpaired lists: OpenCV asserts (cv::Exception); the toolkit answers ok = false.
  const std::vector<cv::Point3d> four = {{0, 0, 3}, {1, 0, 3}, {0, 1, 3}, {1, 1, 4}};
  CHECK_NOTHROW(r = cge::slam::solve_pnp_ransac(four, image, K, {}));
  CHECK_FALSE(r.ok);
}

TEST_CASE("match_by_projection matches hand-placed points and keeps one point per keypoint", "[slam_geometry]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  std::mt19937 rng(21);
  const cv::Mat point_descriptors = random_descriptors(5, rng);
  // Camera at the origin looking along +z (T_world_camera = identity): a point at (x, y, z)
  // projects to (500 x / z + 320, 510 y / z + 240).
  std::vector<PointToProject> points(5);
  points[0].position_world = Eigen::Vector3d(0, 0, 2);        // (320, 240)
  points[1].position_world = Eigen::Vector3d(0.4, 0.2, 2);    // (420, 291)
  points[2].position_world = Eigen::Vector3d(0, 0, -2);       // behind the camera
  points[3].position_world = Eigen::Vector3d(-1.32, 0, 2);    // (-10, 240): outside the image
  points[4].position_world = Eigen::Vector3d(0.004, 0, 2);    // (321, 240): competes with point 0
  for (int k = 0; k < 5; ++k) points[static_cast<std::size_t>(k)].descriptor = point_descriptors.ptr<std::uint8_t>(k);

  cv::Mat kp_descriptors;
  kp_descriptors.push_back(flipped(point_descriptors.row(0), 3));   // keypoint 0 at (322, 241)
  kp_descriptors.push_back(flipped(point_descriptors.row(1), 10));  // keypoint 1 at (418, 290)
  kp_descriptors.push_back(flipped(point_descriptors.row(3), 2));   // keypoint 2 at (2, 240), near point 3
  kp_descriptors.push_back(random_descriptors(1, rng));             // keypoint 3 at (100, 100): nothing near
  // Point 4 is nearest to keypoint 0 too, at more than 3 bits (its descriptor is random).
  const Frame frame = frame_with({{322, 241}, {418, 290}, {2, 240}, {100, 100}}, kp_descriptors);
  const KeypointGrid grid(frame);
  ProjectionSearch search;
  search.radius_px = 15;
  search.max_hamming = 256;
  search.ratio = 1.0;
  std::vector<int> in_image;
  const std::vector<int> source = cge::slam::match_by_projection(frame, grid, K, points, Eigen::Isometry3d::Identity(),
                                                                 search, &in_image);
  const int d40 = hamming(point_descriptors, 4, kp_descriptors, 0);
  REQUIRE(source.size() == 4);
  CHECK(source[0] == (d40 < 3 ? 4 : 0));
  CHECK(source[1] == 1);
  CHECK(source[2] == -1);  // point 3 projects outside the image
  CHECK(source[3] == -1);
  CHECK(in_image == std::vector<int>{0, 1, 4});

  search.require_in_image = false;
  in_image.clear();
  const std::vector<int> anywhere = cge::slam::match_by_projection(frame, grid, K, points, Eigen::Isometry3d::Identity(),
                                                                   search, &in_image);
  CHECK(anywhere[2] == 3);  // 12 px from (-10, 240), inside the 15 px window
  CHECK(in_image == std::vector<int>{0, 1, 3, 4});

  // The distance test: keypoint 1 is 10 bits from its point.
  search.max_hamming = 9;
  const std::vector<int> strict = cge::slam::match_by_projection(frame, grid, K, points, Eigen::Isometry3d::Identity(),
                                                                 search);
  CHECK(strict[1] == -1);

  // A moved camera: the same world point seen from x = +0.4 m projects 100 px to the left.
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  T_world_camera.translation() = Eigen::Vector3d(0.4, 0.2, 0);
  search.max_hamming = 256;
  const std::vector<int> moved = cge::slam::match_by_projection(frame, grid, K, points, T_world_camera, search);
  CHECK(moved[1] == -1);
  CHECK(moved[0] == 1);  // point 1 now projects to (320, 240), next to keypoint 0
}

TEST_CASE("match_by_projection agrees with a brute-force search over every keypoint", "[slam_geometry]") {
  const cge::PinholeIntrinsics<double> K = test_camera();
  std::mt19937 rng(33);
  std::uniform_real_distribution<float> u(0, 640), v(0, 480);
  std::uniform_real_distribution<double> xy(-2, 2), depth(-0.5, 6);
  std::uniform_real_distribution<float> jitter(-12, 12);
  std::uniform_int_distribution<int> bits(0, 60);
  for (int trial = 0; trial < 10; ++trial) {
    const cv::Mat point_descriptors = random_descriptors(200, rng);
    std::vector<PointToProject> points(200);
    for (int k = 0; k < 200; ++k) {
      points[static_cast<std::size_t>(k)].position_world = Eigen::Vector3d(xy(rng), xy(rng), depth(rng));
      points[static_cast<std::size_t>(k)].descriptor = point_descriptors.ptr<std::uint8_t>(k);
    }
    // Keypoints 0 .. 149 near the projections of points 0 .. 149 (when in front) with descriptors a
    // few bits off theirs, so many points match and neighbours compete; the rest anywhere.
    std::vector<cv::Point2f> pixels;
    cv::Mat descriptors = random_descriptors(300, rng);
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector3d& p = points[static_cast<std::size_t>(i % 200)].position_world;
      if (i < 150 && p.z() > 0.5) {
        const Eigen::Vector2d uv = K.project(p);
        pixels.emplace_back(std::clamp(static_cast<float>(uv.x()) + jitter(rng), 0.f, 639.f),
                            std::clamp(static_cast<float>(uv.y()) + jitter(rng), 0.f, 479.f));
        flipped(point_descriptors.row(i), bits(rng)).copyTo(descriptors.row(i));
      } else {
        pixels.emplace_back(u(rng), v(rng));
      }
    }
    Frame frame = frame_with(pixels, descriptors);
    for (int i = 0; i < 300; i += 7) frame.labels[static_cast<std::size_t>(i)] = cge::FeatureLabel::dynamic_by_mask;
    ProjectionSearch search;
    search.radius_px = 20;
    search.max_hamming = 50;
    search.ratio = 0.9;
    const std::vector<int> got =
        cge::slam::match_by_projection(frame, KeypointGrid(frame), K, points, Eigen::Isometry3d::Identity(), search);
    // Oracle: every static keypoint within the radius, sorted by distance. A tie for the nearest
    // fails the ratio test (ratio < 1), and a keypoint claimed twice at one distance keeps the
    // earlier point, so no tie leaves the answer open.
    std::vector<int> best_distance(300, INT_MAX);
    std::vector<int> winner(300, -1);
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector3d& p = points[static_cast<std::size_t>(k)].position_world;
      if (p.z() < search.min_depth_m) continue;
      const Eigen::Vector2d uv = K.project(p);
      if (!frame.undistorted_bounds.contains(uv.x(), uv.y())) continue;
      std::vector<std::pair<int, int>> near;  // (distance, keypoint)
      for (int i = 0; i < 300; ++i) {
        if (!frame.is_static(i)) continue;
        const double du = pixels[static_cast<std::size_t>(i)].x - uv.x(), dv = pixels[static_cast<std::size_t>(i)].y - uv.y();
        if (du * du + dv * dv > search.radius_px * search.radius_px) continue;
        near.emplace_back(hamming(point_descriptors, k, frame.descriptors, i), i);
      }
      if (near.empty()) continue;
      std::sort(near.begin(), near.end());
      if (near[0].first > search.max_hamming) continue;
      if (near.size() > 1 && !(near[0].first < search.ratio * near[1].first)) continue;
      const auto i = static_cast<std::size_t>(near[0].second);
      if (near[0].first < best_distance[i]) {
        best_distance[i] = near[0].first;
        winner[i] = k;
      }
    }
    int matched = 0;
    for (std::size_t i = 0; i < 300; ++i) {
      CHECK(got[i] == winner[i]);
      matched += winner[i] >= 0;
    }
    CHECK(matched > 20);  // the comparison is not vacuous
  }
}
