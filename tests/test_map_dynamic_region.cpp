// Tests of the map's dynamic region (cge/mapping/map_dynamic_region.hpp): a hand-built person whose
// segmentation lost its rim and feet, where the oracle knows which pixels must be left out and which
// must stay; and a brute-force re-implementation (own flood fill, full sorts, distance tests) on
// random masks and depths.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/mapping/map_dynamic_region.hpp"
#include "cge/mapping/semantic_map_builder.hpp"

using cge::mapping::DynamicRegionSettings;

namespace {

/// Brute force of dynamic_region's documented rule, without OpenCV's morphology or labelling.
cv::Mat brute_force_region(const cv::Mat& mask, const cv::Mat& depth, const DynamicRegionSettings& s) {
  const int w = mask.cols, h = mask.rows;
  cv::Mat out(h, w, CV_8UC1, cv::Scalar(0));
  const auto in_mask = [&](int u, int v) { return mask.at<std::uint8_t>(v, u) != 0; };
  const auto valid = [&](int u, int v) {
    const float z = depth.at<float>(v, u);
    return z > 0 && std::isfinite(z);
  };
  const int r = s.edge_dilation_px;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
      for (int y = std::max(0, v - r); y <= std::min(h - 1, v + r) && !out.at<std::uint8_t>(v, u); ++y)
        for (int x = std::max(0, u - r); x <= std::min(w - 1, u + r); ++x)
          if (in_mask(x, y) && (x - u) * (x - u) + (y - v) * (y - v) <= r * r) {
            out.at<std::uint8_t>(v, u) = 255;
            break;
          }
  // Components by flood fill (8-neighbours).
  std::vector<int> component(static_cast<std::size_t>(w * h), 0);
  int next = 0;
  for (int v0 = 0; v0 < h; ++v0)
    for (int u0 = 0; u0 < w; ++u0) {
      if (!in_mask(u0, v0) || component[static_cast<std::size_t>(v0 * w + u0)] != 0) continue;
      ++next;
      std::vector<std::pair<int, int>> stack{{u0, v0}}, pixels;
      component[static_cast<std::size_t>(v0 * w + u0)] = next;
      while (!stack.empty()) {
        const auto [u, v] = stack.back();
        stack.pop_back();
        pixels.push_back({u, v});
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int x = u + dx, y = v + dy;
            if (x < 0 || y < 0 || x >= w || y >= h || !in_mask(x, y)) continue;
            int& c = component[static_cast<std::size_t>(y * w + x)];
            if (c == 0) {
              c = next;
              stack.push_back({x, y});
            }
          }
      }
      int left = w, right = -1, top = h, bottom = -1;
      std::vector<float> d;
      for (const auto& [u, v] : pixels) {
        left = std::min(left, u);
        right = std::max(right, u);
        top = std::min(top, v);
        bottom = std::max(bottom, v);
        if (valid(u, v)) d.push_back(depth.at<float>(v, u));
      }
      if (static_cast<int>(d.size()) < s.min_instance_px) continue;
      std::sort(d.begin(), d.end());
      const float median = d[(d.size() - 1) / 2];
      std::vector<float> dev;
      for (const float x : d) dev.push_back(std::abs(x - median));
      std::sort(dev.begin(), dev.end());
      const double half =
          std::min(std::max(s.mad_scale * dev[(dev.size() - 1) / 2], s.min_band_half_width_m), s.max_band_half_width_m);
      const int box_h = bottom - top + 1;
      const int side = static_cast<int>(std::ceil(s.box_margin_side * box_h));
      const int up = static_cast<int>(std::ceil(s.box_margin_top * box_h));
      const int down = static_cast<int>(std::ceil(s.box_margin_bottom * box_h));
      for (int v = std::max(0, top - up); v <= std::min(h - 1, bottom + down); ++v)
        for (int u = std::max(0, left - side); u <= std::min(w - 1, right + side); ++u)
          if (valid(u, v) && std::abs(static_cast<double>(depth.at<float>(v, u)) - median) <= half)
            out.at<std::uint8_t>(v, u) = 255;
    }
  return out;
}

}  // namespace

TEST_CASE("Dynamic region: a person with lost rim and feet is left out whole, the rest stays",
          "[maps][dynamic_region]") {
  // 80 x 100 image: a wall at 3 m; the floor (rows >= 80) at 2.6 .. 2.0 m, nearer lower down;
  // a person at 2.0 m +- 5 cm (columns 30 .. 49, rows 20 .. 84, feet rows 75 .. 84 at 2.1 m);
  // a static box at 2.0 m far to the right (columns 70 .. 77, rows 40 .. 50): same depth, outside
  // the grown box; a picture frame at 2.9 m inside the grown box (columns 52 .. 54, rows 30 .. 40).
  const int w = 80, h = 100;
  cv::Mat depth(h, w, CV_32FC1, cv::Scalar(3.0f));
  for (int v = 80; v < h; ++v)
    for (int u = 0; u < w; ++u) depth.at<float>(v, u) = 2.6f - 0.03f * static_cast<float>(v - 80);
  cv::Mat person(h, w, CV_8UC1, cv::Scalar(0));
  for (int v = 20; v <= 84; ++v)
    for (int u = 30; u <= 49; ++u) {
      person.at<std::uint8_t>(v, u) = 255;
      depth.at<float>(v, u) = v >= 75 ? 2.1f : 2.0f + 0.05f * static_cast<float>((u + v) % 3 - 1);
    }
  for (int v = 40; v <= 50; ++v)
    for (int u = 70; u <= 77; ++u) depth.at<float>(v, u) = 2.0f;
  for (int v = 30; v <= 40; ++v)
    for (int u = 52; u <= 54; ++u) depth.at<float>(v, u) = 2.9f;
  depth.at<float>(50, 40) = 0;  // a hole in the person's depth: no depth, never in the region

  // The segmentation: the person eroded by 2 pixels and its bottom 15 % (10 rows) lost.
  cv::Mat seg(h, w, CV_8UC1, cv::Scalar(0));
  for (int v = 22; v <= 72; ++v)
    for (int u = 32; u <= 47; ++u) seg.at<std::uint8_t>(v, u) = 255;

  DynamicRegionSettings s;  // defaults: dilation 3, band >= 0.25 m, box + 10 % sides, + 30 % down
  const cv::Mat region = cge::mapping::dynamic_region(seg, depth, s);
  REQUIRE(region.type() == CV_8UC1);
  REQUIRE(region.size() == depth.size());
  int person_missed = 0, box_taken = 0, frame_taken = 0;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const bool out = region.at<std::uint8_t>(v, u) != 0;
      if (person.at<std::uint8_t>(v, u) && depth.at<float>(v, u) > 0 && !out) ++person_missed;
      if (u >= 70 && u <= 77 && v >= 40 && v <= 50 && out) ++box_taken;
      if (u >= 52 && u <= 54 && v >= 30 && v <= 40 && out) ++frame_taken;
    }
  CHECK(person_missed == 0);                    // rim, feet and body: all left out
  CHECK(box_taken == 0);                        // same depth, but outside the grown box
  CHECK(frame_taken == 0);                      // inside the box, but outside the depth band
  CHECK(region.at<std::uint8_t>(50, 40) != 0);  // the hole is inside the mask: left out by the mask itself
  CHECK(region.at<std::uint8_t>(10, 40) == 0);  // wall above the person
  CHECK(region.at<std::uint8_t>(86, 40) == 0);  // floor below the feet, 2.42 m: outside the band
  CHECK(region.at<std::uint8_t>(60, 27) == 0);  // wall beside the person: in the box (from column 26), not in the band

  // The mask alone (band and dilation off) misses exactly the lost rim and feet.
  DynamicRegionSettings off;
  off.edge_dilation_px = 0;
  off.mad_scale = 0;
  off.min_band_half_width_m = 0;
  off.max_band_half_width_m = 0;
  off.box_margin_side = off.box_margin_top = off.box_margin_bottom = 0;
  const cv::Mat bare = cge::mapping::dynamic_region(seg, depth, off);
  // Band half width 0 still takes the pixels at exactly the median depth (2.0 m) in the box.
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const bool in_box = u >= 32 && u <= 47 && v >= 22 && v <= 72;
      const bool expected = in_box && (seg.at<std::uint8_t>(v, u) || depth.at<float>(v, u) == 2.0f);
      REQUIRE((bare.at<std::uint8_t>(v, u) != 0) == expected);
    }
}

TEST_CASE("Dynamic region equals a brute-force evaluation of its rule on random masks", "[maps][dynamic_region]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (int trial = 0; trial < 20; ++trial) {
    const int w = 30 + trial, h = 40 - trial / 2;
    cv::Mat mask(h, w, CV_8UC1, cv::Scalar(0));
    cv::Mat depth(h, w, CV_32FC1);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const float r = unit(rng);
        depth.at<float>(v, u) = r < 0.05f ? 0.f : r < 0.07f ? std::nanf("") : 1.f + 3.f * unit(rng);
      }
    const int blobs = 1 + trial % 4;
    for (int b = 0; b < blobs; ++b) {  // rectangles with ragged edges, some touching
      const int u0 = static_cast<int>(unit(rng) * static_cast<float>(w - 8));
      const int v0 = static_cast<int>(unit(rng) * static_cast<float>(h - 10));
      const float z = 1.5f + 2.f * unit(rng);
      for (int v = v0; v < v0 + 10; ++v)
        for (int u = u0; u < u0 + 8; ++u) {
          if (unit(rng) < 0.1f) continue;
          mask.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(1 + (u + v) % 255);  // any non-zero
          if (unit(rng) < 0.8f) depth.at<float>(v, u) = z + 0.1f * (unit(rng) - 0.5f);
        }
    }
    DynamicRegionSettings s;
    s.edge_dilation_px = trial % 4;
    s.min_instance_px = 1 + trial % 30;
    s.mad_scale = 0.5 * (trial % 7);
    s.min_band_half_width_m = 0.02 * (trial % 5);
    s.max_band_half_width_m = s.min_band_half_width_m + 0.1 * (trial % 3);
    s.box_margin_side = 0.1 * (trial % 3);
    s.box_margin_top = 0.05 * (trial % 2);
    s.box_margin_bottom = 0.15 * (trial % 4);
    const cv::Mat ours = cge::mapping::dynamic_region(mask, depth, s);
    const cv::Mat oracle = brute_force_region(mask, depth, s);
    INFO("trial " << trial);
    REQUIRE(cv::countNonZero(ours != oracle) == 0);
  }
}

TEST_CASE("Dynamic region: empty mask, bad images and settings", "[maps][dynamic_region]") {
  const cv::Mat depth(4, 5, CV_32FC1, cv::Scalar(1.0f));
  const cv::Mat none = cge::mapping::dynamic_region(cv::Mat(), depth, {});
  CHECK(none.size() == depth.size());
  CHECK(cv::countNonZero(none) == 0);
  CHECK_THROWS_AS(cge::mapping::dynamic_region(cv::Mat(4, 5, CV_8UC1), cv::Mat(4, 5, CV_16UC1), {}),
                  std::invalid_argument);
  CHECK_THROWS_AS(cge::mapping::dynamic_region(cv::Mat(4, 4, CV_8UC1), depth, {}), std::invalid_argument);
  DynamicRegionSettings s;
  s.edge_dilation_px = -1;
  CHECK_THROWS_WITH(cge::mapping::check_settings(s), Catch::Contains("edge_dilation_px"));
  s = {};
  s.max_band_half_width_m = 0.1;  // below the minimum 0.25
  CHECK_THROWS_WITH(cge::mapping::check_settings(s), Catch::Contains("max_band_half_width_m"));
  s = {};
  s.box_margin_bottom = -0.1;
  CHECK_THROWS_WITH(cge::mapping::check_settings(s), Catch::Contains("margins"));
  cge::mapping::SemanticMapSettings map_settings;
  map_settings.dynamic_region.mad_scale = std::nan("");
  CHECK_THROWS_WITH(cge::mapping::check_settings(map_settings), Catch::Contains("mad_scale"));
}

TEST_CASE("Keyframe points leave out the grown dynamic region, or the mask alone when asked",
          "[maps][dynamic_region]") {
  cge::PinholeIntrinsics<double> K;
  K.fx_px = K.fy_px = 50;
  K.cx_px = 20;
  K.cy_px = 20;
  cge::slam::Keyframe kf;
  kf.depth_m = cv::Mat(40, 40, CV_32FC1, cv::Scalar(3.0f));
  kf.dynamic_mask = cv::Mat(40, 40, CV_8UC1, cv::Scalar(0));
  for (int v = 10; v < 30; ++v)
    for (int u = 15; u < 25; ++u) kf.depth_m.at<float>(v, u) = 1.5f;  // the person
  for (int v = 12; v < 26; ++v)
    for (int u = 17; u < 23; ++u) kf.dynamic_mask.at<std::uint8_t>(v, u) = 255;  // its eroded, feetless mask
  cge::mapping::SemanticMapSettings settings;
  settings.pixel_stride = settings.octree_pixel_stride = 1;
  const auto near_points = [&](const cge::mapping::SemanticMapSettings& s) {
    const std::vector<cge::mapping::SemanticPoint> pts = cge::mapping::SemanticMapBuilder(K, s).keyframe_points(kf);
    return std::count_if(pts.begin(), pts.end(), [](const auto& p) { return p.position_m.z() < 2.f; });
  };
  // Grown (defaults): no person point; the region equals dynamic_region() pixel for pixel.
  CHECK(near_points(settings) == 0);
  const cv::Mat region = cge::mapping::dynamic_region(kf.dynamic_mask, kf.depth_m, settings.dynamic_region);
  const auto total = cge::mapping::SemanticMapBuilder(K, settings).keyframe_points(kf).size();
  CHECK(total == static_cast<std::size_t>(40 * 40 - cv::countNonZero(region)));
  // The mask alone: the 10 x 20 person minus the 6 x 14 mask stays.
  settings.grow_dynamic_mask = false;
  CHECK(near_points(settings) == 10 * 20 - 6 * 14);
}
