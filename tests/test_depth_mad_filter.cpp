// DepthMADFilter (docs/METHOD.md section 1): hand-built depth and mask fixtures for every rule,
// hand-worked statistics under a scripted engine, and an independent brute-force oracle that
// re-derives the samples from the same seed for randomised fixtures.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cge/core/mask.hpp"
#include "cge/core/nearest_pixel.hpp"
#include "cge/core/uniform_double.hpp"
#include "cge/core/depth_image.hpp"
#include "cge/frontend/depth_mad_filter.hpp"
#include "cge/frontend/feature_label.hpp"
#include "cge/frontend/pixel_box.hpp"
#include "test_support.hpp"

namespace {

using cge::BinaryMask;
using cge::DepthMADFilter;
using cge::DepthMADResult;
using cge::DepthMADSettings;
using cge::DynamicInstance;
using cge::FeatureLabel;
using cge::FloatDepthImage;
using cge::PixelBox;
using Keypoints = std::vector<std::array<double, 2>>;
using Instances = std::vector<DynamicInstance<BinaryMask>>;

constexpr double nan_value = std::numeric_limits<double>::quiet_NaN();
constexpr float nan_float = std::numeric_limits<float>::quiet_NaN();

/// A 64-bit engine that replays a script of uniform doubles u (multiples of 2^-53 in [0, 1)) as
/// the raw outputs u * 2^64, and counts its draws.
struct ScriptedEngine {
  using result_type = std::uint64_t;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }
  std::vector<double> script;
  std::size_t draws = 0;
  result_type operator()() {
    const double u = script.at(draws % script.size());
    ++draws;
    return static_cast<result_type>(std::ldexp(u, 64));
  }
};

/// A 24-bit engine with a fixed output, to check how outputs are concatenated.
struct Fixed24Engine {
  using result_type = std::uint32_t;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return (1u << 24) - 1; }
  std::vector<result_type> outputs;
  std::size_t next = 0;
  result_type operator()() { return outputs.at(next++); }
};

/// Sets the pixels of the rectangle cols [c0, c1] x rows [r0, r1] (inclusive).
void fill_rect(BinaryMask& m, int c0, int r0, int c1, int r1) {
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) m.at(c, r) = 1;
}

DepthMADSettings settings_with(int n, int radius, int min_valid, double k = 1.0) {
  DepthMADSettings s;
  s.samples_per_instance = n;
  s.disc_radius_px = radius;
  s.min_valid_samples = min_valid;
  s.mad_scale = k;
  return s;
}

/// The u that puts a sample of the axis [lo, lo + len) at the centre of pixel `p`:
/// centre + (u - 1/2) len = p + 1/2.
double u_for_pixel(double lo, double len, int p) { return (p + 0.5 - lo) / len; }

// ---- independent oracle ---------------------------------------------------------------------------

struct OracleStats {
  int valid = 0, off_mask = 0, invalid_depth = 0;
  bool applied = false;
  double mean = nan_value, mad = nan_value;
};

/// Re-derives the samples from its own copy of the engine with the simplest code: 53 top bits per
/// double, floor to a pixel, a square scan for the disc, sums in sample order.
OracleStats oracle_stats(std::mt19937_64& eng, const FloatDepthImage& depth, const BinaryMask& mask,
                         const PixelBox& box, const DepthMADSettings& s) {
  OracleStats o;
  std::vector<double> d;
  const int c_lo = static_cast<int>(std::floor(box.x_min_px));
  const int c_hi = static_cast<int>(std::ceil(box.x_min_px + box.width_px)) - 1;
  const int r_lo = static_cast<int>(std::floor(box.y_min_px));
  const int r_hi = static_cast<int>(std::ceil(box.y_min_px + box.height_px)) - 1;
  for (int i = 0; i < s.samples_per_instance; ++i) {
    const double ux = std::ldexp(static_cast<double>(eng() >> 11), -53);
    const double uy = std::ldexp(static_cast<double>(eng() >> 11), -53);
    int c = static_cast<int>(std::floor(box.x_min_px + box.width_px / 2 + (ux - 0.5) * box.width_px));
    int r = static_cast<int>(std::floor(box.y_min_px + box.height_px / 2 + (uy - 0.5) * box.height_px));
    c = c < c_lo ? c_lo : (c > c_hi ? c_hi : c);
    r = r < r_lo ? r_lo : (r > r_hi ? r_hi : r);
    bool inside = true;
    const int rad = s.disc_radius_px;
    for (int dy = -rad; dy <= rad && inside; ++dy) {
      for (int dx = -rad; dx <= rad && inside; ++dx) {
        if (dx * dx + dy * dy > rad * rad) continue;
        const int x = c + dx, y = r + dy;
        if (x < 0 || y < 0 || x >= mask.width || y >= mask.height) {
          if (s.image_border_is_mask_edge) inside = false;
          continue;
        }
        if (mask.at(x, y) == 0) inside = false;
      }
    }
    if (!inside) {
      ++o.off_mask;
      continue;
    }
    const double v = depth.at(c, r);
    if (!(v > 0) || std::isinf(v)) {
      ++o.invalid_depth;
      continue;
    }
    d.push_back(v);
  }
  o.valid = static_cast<int>(d.size());
  o.applied = o.valid >= s.min_valid_samples;
  if (!d.empty()) {
    double sum = 0;
    for (const double v : d) sum += v;
    o.mean = sum / static_cast<double>(d.size());
    double dev = 0;
    for (const double v : d) dev += std::abs(v - o.mean);
    o.mad = dev / static_cast<double>(d.size());
  }
  return o;
}

/// Labels by the rules of section 1, from the oracle's statistics.
std::vector<FeatureLabel> oracle_labels(const Keypoints& kps, const FloatDepthImage& depth,
                                        const std::vector<BinaryMask>& masks, const std::vector<PixelBox>& boxes,
                                        const std::vector<OracleStats>& stats, double k) {
  std::vector<FeatureLabel> labels;
  for (const auto& kp : kps) {
    const int c = std::min(static_cast<int>(std::lround(kp[0])), depth.width - 1);
    const int r = std::min(static_cast<int>(std::lround(kp[1])), depth.height - 1);
    FeatureLabel label = FeatureLabel::static_feature;
    for (const BinaryMask& m : masks)
      if (m.at(c, r)) label = FeatureLabel::dynamic_by_mask;
    const double d = depth.at(c, r);
    if (label == FeatureLabel::static_feature && d > 0 && !std::isinf(d)) {
      for (std::size_t j = 0; j < boxes.size(); ++j) {
        const bool in_box = c >= std::floor(boxes[j].x_min_px) && c < std::ceil(boxes[j].x_max_px()) &&
                            r >= std::floor(boxes[j].y_min_px) && r < std::ceil(boxes[j].y_max_px());
        if (in_box && stats[j].applied && std::abs(d - stats[j].mean) < k * stats[j].mad) {
          label = FeatureLabel::dynamic_by_mad;
        }
      }
    }
    labels.push_back(label);
  }
  return labels;
}

int count_label(const std::vector<FeatureLabel>& labels, FeatureLabel which) {
  int n = 0;
  for (const FeatureLabel l : labels) n += l == which ? 1 : 0;
  return n;
}

}  // namespace

// ---- uniform doubles --------------------------------------------------------------------------------

TEST_CASE("uniform_unit_double takes the top 53 bits of the raw engine output", "[depth_mad][random]") {
  SECTION("64-bit engine: one output per double") {
    std::mt19937_64 a(12345), b(12345);
    for (int i = 0; i < 1000; ++i) {
      const std::uint64_t raw = b();
      REQUIRE(cge::uniform_unit_double(a) == static_cast<double>(raw >> 11) / 9007199254740992.0);
    }
  }
  SECTION("32-bit engine: two outputs, the first most significant") {
    std::mt19937 a(777), b(777);
    for (int i = 0; i < 1000; ++i) {
      const std::uint64_t hi = b();
      const std::uint64_t lo = b();
      REQUIRE(cge::uniform_unit_double(a) == static_cast<double>((hi << 21) | (lo >> 11)) / 9007199254740992.0);
    }
  }
  SECTION("24-bit engine: 24 + 24 + top 5 bits") {
    Fixed24Engine e;
    e.outputs = {0xABCDEFu, 0x123456u, 0xF80000u};  // the third contributes 0b11111
    const std::uint64_t expected = (std::uint64_t{0xABCDEF} << 29) | (std::uint64_t{0x123456} << 5) | 0x1Fu;
    REQUIRE(cge::uniform_unit_double(e) == static_cast<double>(expected) / 9007199254740992.0);
    REQUIRE(e.next == 3);
  }
  SECTION("the extremes: 0 and the largest double below 1") {
    ScriptedEngine e;
    e.script = {0.0};
    REQUIRE(cge::uniform_unit_double(e) == 0.0);
    Fixed24Engine top;
    top.outputs = {0xFFFFFFu, 0xFFFFFFu, 0xFFFFFFu};
    const double u = cge::uniform_unit_double(top);
    REQUIRE(u < 1.0);
    REQUIRE(u == 1.0 - std::ldexp(1.0, -53));
  }
  SECTION("std::mt19937_64 is specified bit for bit (its 10000th output is fixed by the standard)") {
    std::mt19937_64 e;  // default seed 5489
    e.discard(9999);
    REQUIRE(e() == 9981545732273789042ull);
  }
}

// ---- settings and small types ------------------------------------------------------------------------

TEST_CASE("DepthMADSettings: defaults, and every bad field is named", "[depth_mad][settings]") {
  const DepthMADSettings s;
  REQUIRE(s.samples_per_instance == 100);  // n, ours (the paper gives none)
  REQUIRE(s.disc_radius_px == 6);          // r, paper
  REQUIRE(s.mad_scale == 1.0);             // k, paper
  REQUIRE(s.min_valid_samples == 5);
  REQUIRE_FALSE(s.image_border_is_mask_edge);
  REQUIRE(s.depth_estimate == cge::DepthEstimate::box_samples);  // the paper's step 2
  REQUIRE(s.min_valid_mask_fraction == 0.5);
  REQUIRE_NOTHROW(s.validate());

  const auto message = [](DepthMADSettings bad) { return cge_test::invalid_argument_message([&] { bad.validate(); }); };
  DepthMADSettings bad;
  bad.samples_per_instance = 0;
  REQUIRE_THAT(message(bad), Catch::Contains("samples_per_instance"));
  bad = {};
  bad.disc_radius_px = -1;
  REQUIRE_THAT(message(bad), Catch::Contains("disc_radius_px"));
  bad = {};
  bad.min_valid_samples = 0;
  REQUIRE_THAT(message(bad), Catch::Contains("min_valid_samples"));
  for (const double k : {nan_value, -0.5, std::numeric_limits<double>::infinity()}) {
    bad = {};
    bad.mad_scale = k;
    REQUIRE_THAT(message(bad), Catch::Contains("mad_scale"));
  }
  for (const double fraction : {nan_value, -0.1, 1.5}) {
    bad = {};
    bad.min_valid_mask_fraction = fraction;
    REQUIRE_THAT(message(bad), Catch::Contains("min_valid_mask_fraction"));
  }
  bad = {};
  bad.depth_estimate = static_cast<cge::DepthEstimate>(7);
  REQUIRE_THAT(message(bad), Catch::Contains("depth_estimate"));
  // The filter validates its settings on every call.
  DepthMADFilter<> f;
  f.settings.mad_scale = nan_value;
  const FloatDepthImage depth(4, 4, 1.0f);
  REQUIRE_THAT(cge_test::invalid_argument_message([&] { f.filter(Keypoints{}, depth, Instances{}); }),
               Catch::Contains("mad_scale"));
}

TEST_CASE("FeatureLabel names and the depth validity rule", "[depth_mad]") {
  REQUIRE(std::string(cge::to_string(FeatureLabel::static_feature)) == "static");
  REQUIRE(std::string(cge::to_string(FeatureLabel::dynamic_by_mask)) == "dynamic_by_mask");
  REQUIRE(std::string(cge::to_string(FeatureLabel::dynamic_by_mad)) == "dynamic_by_mad");
  REQUIRE_FALSE(cge::is_dynamic(FeatureLabel::static_feature));
  REQUIRE(cge::is_dynamic(FeatureLabel::dynamic_by_mask));
  REQUIRE(cge::is_dynamic(FeatureLabel::dynamic_by_mad));

  REQUIRE(cge::is_valid_depth_m(0.5));
  REQUIRE(cge::is_valid_depth_m(1e-9));
  REQUIRE_FALSE(cge::is_valid_depth_m(0.0));
  REQUIRE_FALSE(cge::is_valid_depth_m(-0.0));
  REQUIRE_FALSE(cge::is_valid_depth_m(-1.0));
  REQUIRE_FALSE(cge::is_valid_depth_m(nan_value));
  REQUIRE_FALSE(cge::is_valid_depth_m(std::numeric_limits<double>::infinity()));
}

TEST_CASE("PixelBox: conversions, the pixels a box overlaps, validation", "[depth_mad][box]") {
  const PixelBox a = PixelBox::from_centre(10, 20, 4, 6);
  REQUIRE(a.x_min_px == 8);
  REQUIRE(a.y_min_px == 17);
  REQUIRE(a.x_max_px() == 12);
  REQUIRE(a.y_max_px() == 23);
  REQUIRE(a.centre_x_px() == 10);
  REQUIRE(a.centre_y_px() == 20);
  const PixelBox b = PixelBox::from_corners(1.5, 2.5, 4, 8);
  REQUIRE(b.width_px == 2.5);
  REQUIRE(b.height_px == 5.5);

  // Integer edges: exactly the pixels x .. x + w - 1, as a cv::Rect.
  const cge::PixelSpan whole = PixelBox{0, 0, 640, 480}.pixels();
  REQUIRE(whole.col_begin == 0);
  REQUIRE(whole.col_end == 640);
  REQUIRE(whole.row_begin == 0);
  REQUIRE(whole.row_end == 480);
  REQUIRE(whole.pixel_count() == 640 * 480);
  const cge::PixelSpan one = PixelBox{10, 20, 1, 1}.pixels();
  REQUIRE(one.pixel_count() == 1);
  REQUIRE(one.contains(10, 20));
  REQUIRE_FALSE(one.contains(11, 20));
  REQUIRE_FALSE(one.contains(10, 21));
  // Fractional edges: every pixel the box overlaps, [2.3, 5.7) -> columns 2..5.
  const cge::PixelSpan frac = PixelBox{2.3, 1.0, 3.4, 2.0}.pixels();
  REQUIRE(frac.col_begin == 2);
  REQUIRE(frac.col_end == 6);
  REQUIRE(frac.row_begin == 1);
  REQUIRE(frac.row_end == 3);

  REQUIRE_NOTHROW(PixelBox{0, 0, 640, 480}.validate(640, 480, "box"));
  const auto message = [](const PixelBox& box) {
    return cge_test::invalid_argument_message([&] { box.validate(640, 480, "the box"); });
  };
  REQUIRE_THAT(message(PixelBox{-0.5, 0, 10, 10}), Catch::Contains("outside the image"));
  REQUIRE_THAT(message(PixelBox{0, -1, 10, 10}), Catch::Contains("outside the image"));
  REQUIRE_THAT(message(PixelBox{630.5, 0, 10, 10}), Catch::Contains("outside the image"));
  REQUIRE_THAT(message(PixelBox{0, 470, 10, 10.5}), Catch::Contains("outside the image"));
  REQUIRE_THAT(message(PixelBox{700, 500, 10, 10}), Catch::Contains("outside the image"));
  REQUIRE_THAT(message(PixelBox{nan_value, 0, 10, 10}), Catch::Contains("not finite"));
  REQUIRE_THAT(message(PixelBox{0, 0, 10, nan_value}), Catch::Contains("not finite"));
  REQUIRE_THAT(message(PixelBox{0, 0, std::numeric_limits<double>::infinity(), 10}), Catch::Contains("not finite"));
  REQUIRE_THAT(message(PixelBox{5, 5, 0, 10}), Catch::Contains("no positive width"));
  REQUIRE_THAT(message(PixelBox{5, 5, 10, -2}), Catch::Contains("no positive width"));
  REQUIRE_THAT(message(PixelBox{100, 5, 1e-20, 10}), Catch::Contains("no positive width"));
  REQUIRE_THAT(message(PixelBox{-0.5, 0, 10, 10}), Catch::Contains("the box") && Catch::Contains("640 x 480"));
}

TEST_CASE("bounding_box of a mask: the set pixels' cv::Rect-like box", "[depth_mad][box]") {
  BinaryMask m(20, 10);
  REQUIRE_FALSE(cge::bounding_box(m).has_value());  // nothing set
  REQUIRE_FALSE(cge::bounding_box(BinaryMask{}).has_value());
  m.at(3, 7) = 1;
  m.at(11, 2) = 1;
  m.at(5, 4) = 1;
  const auto box = cge::bounding_box(m);
  REQUIRE(box.has_value());
  REQUIRE(box->x_min_px == 3);
  REQUIRE(box->y_min_px == 2);
  REQUIRE(box->width_px == 9);   // columns 3..11
  REQUIRE(box->height_px == 6);  // rows 2..7
  const cge::PixelSpan span = box->pixels();
  REQUIRE(span.col_begin == 3);
  REQUIRE(span.col_end == 12);
  REQUIRE(span.row_begin == 2);
  REQUIRE(span.row_end == 8);
}

// ---- hand-worked statistics and labels ------------------------------------------------------------------

TEST_CASE("hand-worked MAD test: Dev < k MAD is dynamic, Dev equal to MAD is static", "[depth_mad][rules]") {
  // 8 x 4 image. The instance's mask is row 0, columns 0..3, with depths 1, 1, 3, 3; its box is
  // columns 0..3, rows 0..3. A scripted engine puts the four samples on those four pixels, so
  // d_j = 2 and MAD_j = (1 + 1 + 1 + 1) / 4 = 1 (all dyadic: exact in float and double).
  FloatDepthImage depth(8, 4, 2.0f);
  const float row0[4] = {1, 1, 3, 3};
  for (int c = 0; c < 4; ++c) depth.at(c, 0) = row0[c];
  BinaryMask mask(8, 4);
  fill_rect(mask, 0, 0, 3, 0);
  const PixelBox box{0, 0, 4, 4};
  const Instances instances{cge::dynamic_instance(mask, box, 0)};

  // Keypoints (x, y) and depths at their pixels (the pixel is the rounded position).
  depth.at(0, 1) = 3.0f;           // Dev = 1 = MAD: static (strict inequality)
  depth.at(1, 1) = 2.5f;           // Dev = 0.5: dynamic
  depth.at(2, 1) = 1.0f;           // Dev = 1: static
  depth.at(3, 1) = 1.0009765625f;  // Dev = 1 - 2^-10: dynamic
  depth.at(0, 2) = 0.9990234375f;  // Dev = 1 + 2^-10: static
  depth.at(1, 2) = 0.0f;           // no depth: static
  depth.at(2, 2) = nan_float;      // no depth (NaN): static
  depth.at(3, 2) = -2.0f;          // negative = no depth: static
  depth.at(6, 3) = 2.0f;           // outside the box and the mask, depth = mean: static
  const Keypoints kps{{0.4, 1.4}, {1, 1},    {1.6, 0.6}, {3.4, 1}, {0, 2},    {1, 2},
                      {2, 2},     {3, 2.49}, {6, 3},     {2, 0},   {3.5, 0.5}};
  // {2, 0} lies in the mask (dynamic_by_mask); {3.5, 0.5} rounds to (4, 1): outside the box
  // (columns 0..3), depth 2 = mean, so static.

  ScriptedEngine engine;
  for (int c = 0; c < 4; ++c) {
    engine.script.push_back(u_for_pixel(0, 4, c));  // x on column c
    engine.script.push_back(u_for_pixel(0, 4, 0));  // y on row 0
  }
  DepthMADFilter<ScriptedEngine> f(settings_with(4, 0, 4), engine);

  const std::vector<FeatureLabel> expected_k1{
      FeatureLabel::static_feature,  FeatureLabel::dynamic_by_mad, FeatureLabel::static_feature,
      FeatureLabel::dynamic_by_mad,  FeatureLabel::static_feature, FeatureLabel::static_feature,
      FeatureLabel::static_feature,  FeatureLabel::static_feature, FeatureLabel::static_feature,
      FeatureLabel::dynamic_by_mask, FeatureLabel::static_feature};

  SECTION("k = 1 (paper)") {
    const DepthMADResult r = f.filter(kps, depth, instances);
    REQUIRE(f.engine.draws == 8);  // 2 n uniform doubles, one 64-bit output each
    REQUIRE(r.instances.size() == 1);
    const cge::InstanceDepthStats& s = r.instances[0];
    REQUIRE(s.samples_drawn == 4);
    REQUIRE(s.valid_samples == 4);
    REQUIRE(s.samples_off_mask == 0);
    REQUIRE(s.samples_invalid_depth == 0);
    REQUIRE(s.mad_test_applied);
    REQUIRE(s.mean_depth_m == 2.0);
    REQUIRE(s.mad_m == 1.0);
    REQUIRE(r.labels == expected_k1);
    REQUIRE(r.static_count == 8);
    REQUIRE(r.dynamic_by_mad_count == 2);
    REQUIRE(r.dynamic_by_mask_count == 1);
    REQUIRE(r.dynamic_count() == 3);
    REQUIRE(r.count(FeatureLabel::dynamic_by_mad) == 2);
  }
  SECTION("k = 2: Dev = 1 is now dynamic") {
    f.settings.mad_scale = 2.0;
    const DepthMADResult r = f.filter(kps, depth, instances);
    std::vector<FeatureLabel> expected = expected_k1;
    expected[0] = expected[2] = expected[4] = FeatureLabel::dynamic_by_mad;  // Dev 1, 1, 1 + 2^-10 < 2
    REQUIRE(r.labels == expected);
  }
  SECTION("k = 0 switches the depth test off") {
    f.settings.mad_scale = 0.0;
    const DepthMADResult r = f.filter(kps, depth, instances);
    REQUIRE(r.dynamic_by_mad_count == 0);
    REQUIRE(r.dynamic_by_mask_count == 1);
  }
  SECTION("too few valid samples: statistics reported, no MAD test") {
    f.settings.min_valid_samples = 5;  // only 4 samples exist
    const DepthMADResult r = f.filter(kps, depth, instances);
    REQUIRE(r.instances[0].valid_samples == 4);
    REQUIRE_FALSE(r.instances[0].mad_test_applied);
    REQUIRE(r.instances[0].mean_depth_m == 2.0);
    REQUIRE(r.instances[0].mad_m == 1.0);
    REQUIRE(r.dynamic_by_mad_count == 0);
    REQUIRE(r.dynamic_by_mask_count == 1);
    REQUIRE(r.static_count == 10);
  }
  SECTION("invalid sample depths are not valid samples") {
    depth.at(1, 0) = nan_float;
    depth.at(2, 0) = 0.0f;
    const DepthMADResult r = f.filter(kps, depth, instances);
    const cge::InstanceDepthStats& s = r.instances[0];
    REQUIRE(s.valid_samples == 2);
    REQUIRE(s.samples_invalid_depth == 2);
    REQUIRE(s.samples_off_mask == 0);
    REQUIRE_FALSE(s.mad_test_applied);  // 2 < 4
    REQUIRE(s.mean_depth_m == 2.0);     // depths 1 and 3
    REQUIRE(s.mad_m == 1.0);
    REQUIRE(r.dynamic_by_mad_count == 0);
  }
  SECTION("no valid sample at all: NaN statistics, no test") {
    for (int c = 0; c < 4; ++c) depth.at(c, 0) = 0.0f;
    const DepthMADResult r = f.filter(kps, depth, instances);
    REQUIRE(r.instances[0].valid_samples == 0);
    REQUIRE(r.instances[0].samples_invalid_depth == 4);
    REQUIRE(std::isnan(r.instances[0].mean_depth_m));
    REQUIRE(std::isnan(r.instances[0].mad_m));
    REQUIRE_FALSE(r.instances[0].mad_test_applied);
  }
}

TEST_CASE("a keypoint inside two boxes is tested against each; outside a box it is not", "[depth_mad][rules]") {
  // 16 x 8 image. Instance A: mask row 0 columns 0..3 with depths 1, 1, 3, 3 (mean 2, MAD 1), box
  // columns 0..7. Instance B: mask row 0 columns 8..11 with depths 5, 5, 7, 7 (mean 6, MAD 1), box
  // columns 4..11. The boxes overlap on columns 4..7; all boxes span rows 0..7.
  FloatDepthImage depth(16, 8, 4.0f);
  const float row0[12] = {1, 1, 3, 3, 4, 4, 4, 4, 5, 5, 7, 7};
  for (int c = 0; c < 12; ++c) depth.at(c, 0) = row0[c];
  BinaryMask mask_a(16, 8), mask_b(16, 8);
  fill_rect(mask_a, 0, 0, 3, 0);
  fill_rect(mask_b, 8, 0, 11, 0);
  const PixelBox box_a{0, 0, 8, 8}, box_b{4, 0, 8, 8};
  const Instances instances{cge::dynamic_instance(mask_a, box_a, 0), cge::dynamic_instance(mask_b, box_b, 0)};

  ScriptedEngine engine;
  for (int c = 0; c < 4; ++c) {  // instance A first (input order), x before y
    engine.script.push_back(u_for_pixel(0, 8, c));
    engine.script.push_back(u_for_pixel(0, 8, 0));
  }
  for (int c = 8; c < 12; ++c) {
    engine.script.push_back(u_for_pixel(4, 8, c));
    engine.script.push_back(u_for_pixel(0, 8, 0));
  }
  DepthMADFilter<ScriptedEngine> f(settings_with(4, 0, 4), engine);

  depth.at(5, 3) = 6.5f;   // both boxes: far from A's mean, within B's MAD -> dynamic
  depth.at(6, 3) = 2.5f;   // both boxes: within A's MAD -> dynamic
  depth.at(6, 4) = 4.0f;   // both boxes: Dev 2 from each -> static
  depth.at(1, 3) = 6.5f;   // box A only: B's statistics do not apply -> static
  depth.at(10, 3) = 2.5f;  // box B only: A's statistics do not apply -> static
  depth.at(14, 3) = 2.0f;  // no box: static
  const Keypoints kps{{5, 3}, {6, 3}, {6, 4}, {1, 3}, {10, 3}, {14, 3}, {9, 0}};

  const DepthMADResult r = f.filter(kps, depth, instances);
  REQUIRE(f.engine.draws == 16);
  REQUIRE(r.instances.size() == 2);
  REQUIRE(r.instances[0].mean_depth_m == 2.0);
  REQUIRE(r.instances[0].mad_m == 1.0);
  REQUIRE(r.instances[1].mean_depth_m == 6.0);
  REQUIRE(r.instances[1].mad_m == 1.0);
  REQUIRE(r.labels == std::vector<FeatureLabel>{FeatureLabel::dynamic_by_mad, FeatureLabel::dynamic_by_mad,
                                                FeatureLabel::static_feature, FeatureLabel::static_feature,
                                                FeatureLabel::static_feature, FeatureLabel::static_feature,
                                                FeatureLabel::dynamic_by_mask});

  SECTION("an instance without the MAD test does not stop the other's") {
    depth.at(0, 0) = depth.at(1, 0) = depth.at(2, 0) = 0.0f;  // A keeps one valid sample
    f.engine.draws = 0;
    const DepthMADResult r2 = f.filter(kps, depth, instances);
    REQUIRE_FALSE(r2.instances[0].mad_test_applied);
    REQUIRE(r2.instances[1].mad_test_applied);
    REQUIRE(r2.labels[0] == FeatureLabel::dynamic_by_mad);  // via B
    REQUIRE(r2.labels[1] == FeatureLabel::static_feature);  // only A would have caught it
  }
}

TEST_CASE("disc validity at the mask edge (radius 6, the disc is round, not square)", "[depth_mad][rules]") {
  // A 1 x 1 pixel box puts every sample on that pixel, so the disc test decides all n together.
  FloatDepthImage depth(64, 48, 2.0f);
  BinaryMask mask(64, 48);
  fill_rect(mask, 10, 10, 30, 30);
  DepthMADFilter<> f(settings_with(20, 6, 5));
  f.engine.seed(7);
  const auto stats_at = [&](int col, int row) {
    const Instances inst{
        cge::dynamic_instance(mask, PixelBox{static_cast<double>(col), static_cast<double>(row), 1, 1})};
    return f.filter(Keypoints{}, depth, inst).instances.at(0);
  };

  // Along an axis the disc reaches exactly r pixels.
  REQUIRE(stats_at(16, 20).valid_samples == 20);  // columns 10..22 all in the mask
  REQUIRE(stats_at(15, 20).valid_samples == 0);   // column 9 is not
  REQUIRE(stats_at(15, 20).samples_off_mask == 20);
  REQUIRE(stats_at(24, 20).valid_samples == 20);  // up to column 30
  REQUIRE(stats_at(25, 20).valid_samples == 0);
  REQUIRE(stats_at(20, 16).valid_samples == 20);
  REQUIRE(stats_at(20, 15).valid_samples == 0);

  // Diagonals: offset (-4, -4) is inside the disc (32 <= 36), (-5, -4) is not (41 > 36).
  mask.at(16, 16) = 0;
  REQUIRE(stats_at(20, 20).valid_samples == 0);
  mask.at(16, 16) = 1;
  mask.at(15, 16) = 0;
  REQUIRE(stats_at(20, 20).valid_samples == 20);
  mask.at(15, 16) = 1;
  // (6, 0) is on the disc's rim, (6, 1) is outside it (37 > 36).
  mask.at(26, 20) = 0;
  REQUIRE(stats_at(20, 20).valid_samples == 0);
  mask.at(26, 20) = 1;
  mask.at(26, 21) = 0;
  REQUIRE(stats_at(20, 20).valid_samples == 20);
  mask.at(26, 21) = 1;

  // Radius 0 tests the pixel alone.
  f.settings.disc_radius_px = 0;
  REQUIRE(stats_at(10, 10).valid_samples == 20);
  REQUIRE(stats_at(9, 10).valid_samples == 0);
  f.settings.disc_radius_px = 1;
  REQUIRE(stats_at(10, 10).valid_samples == 0);
  REQUIRE(stats_at(11, 11).valid_samples == 20);
}

TEST_CASE("disc at the image border: ignored by default, a mask edge on request", "[depth_mad][rules]") {
  FloatDepthImage depth(40, 30, 1.5f);
  BinaryMask mask(40, 30);
  fill_rect(mask, 0, 0, 20, 29);  // touches the left, top and bottom borders
  DepthMADFilter<> f(settings_with(10, 6, 5));
  const auto valid_at = [&](int col, int row) {
    const Instances inst{
        cge::dynamic_instance(mask, PixelBox{static_cast<double>(col), static_cast<double>(row), 1, 1})};
    return f.filter(Keypoints{}, depth, inst).instances.at(0).valid_samples;
  };
  REQUIRE(valid_at(2, 15) == 10);
  REQUIRE(valid_at(0, 0) == 10);
  REQUIRE(valid_at(14, 29) == 10);
  REQUIRE(valid_at(15, 29) == 0);  // the mask's own edge still counts
  f.settings.image_border_is_mask_edge = true;
  REQUIRE(valid_at(2, 15) == 0);
  REQUIRE(valid_at(5, 15) == 0);
  REQUIRE(valid_at(6, 15) == 10);  // the disc reaches column 0 exactly
  REQUIRE(valid_at(6, 6) == 10);
  REQUIRE(valid_at(6, 5) == 0);
  REQUIRE(valid_at(6, 23) == 10);
  REQUIRE(valid_at(6, 24) == 0);
}

TEST_CASE("samples stay inside the box's pixels, fractional edges included", "[depth_mad][rules]") {
  // The mask is exactly the pixels of the box [2.3, 5.7) x [1.0, 3.0): columns 2..5, rows 1..2.
  // With r = 0 every sample is valid; a pixel outside the mask would be caught.
  FloatDepthImage depth(10, 6, 1.0f);
  BinaryMask mask(10, 6);
  fill_rect(mask, 2, 1, 5, 2);
  const PixelBox box{2.3, 1.0, 3.4, 2.0};
  DepthMADFilter<> f(settings_with(2000, 0, 5));
  f.engine.seed(11);
  const Instances inst{cge::dynamic_instance(mask, box)};
  REQUIRE(f.filter(Keypoints{}, depth, inst).instances[0].valid_samples == 2000);
  // Column 2 covers 0.7 / 3.4 of the box's width: about 412 of 2000 samples land there.
  for (int r = 1; r <= 2; ++r) mask.at(2, r) = 0;
  f.engine.seed(11);
  const cge::InstanceDepthStats s = f.filter(Keypoints{}, depth, inst).instances[0];
  REQUIRE(s.samples_off_mask > 300);
  REQUIRE(s.samples_off_mask < 520);
  REQUIRE(s.valid_samples + s.samples_off_mask == 2000);
}

// ---- randomised fixtures against the oracle ----------------------------------------------------------------

TEST_CASE("statistics and labels equal an independent re-derivation from the same seed", "[depth_mad][oracle]") {
  const int width = 48, height = 40;
  for (const std::uint64_t seed : {1ull, 2ull, 99ull, 20250707ull}) {
    for (const bool border_edge : {false, true}) {
      for (const double k : {1.0, 1.5}) {
        // Fixture from its own generator: two ellipses (one touching the border), overlapping
        // boxes, depth with holes and NaNs, keypoints anywhere.
        std::mt19937_64 fixture(seed * 7919);
        const auto uniform = [&](double lo, double hi) {
          return lo + (hi - lo) * std::ldexp(static_cast<double>(fixture() >> 11), -53);
        };
        FloatDepthImage depth(width, height);
        for (float& d : depth.depth_m) {
          const double roll = uniform(0, 1);
          // A third of the background at the people's depth (what a mask misses of a person).
          d = roll < 0.08   ? 0.0f
              : roll < 0.12 ? nan_float
              : roll < 0.45 ? static_cast<float>(uniform(1.0, 1.3))
                            : static_cast<float>(uniform(0.5, 4.0));
        }
        std::vector<BinaryMask> masks(2, BinaryMask(width, height));
        const double cx[2] = {14, 4}, cy[2] = {18, 30}, ax[2] = {10, 9}, ay[2] = {14, 9};
        for (int j = 0; j < 2; ++j) {
          for (int r = 0; r < height; ++r)
            for (int c = 0; c < width; ++c) {
              const double u = (c - cx[j]) / ax[j], v = (r - cy[j]) / ay[j];
              if (u * u + v * v <= 1) masks[j].at(c, r) = 1;
            }
          // The person is nearer than the background on average: shift depths inside the mask.
          for (int r = 0; r < height; ++r)
            for (int c = 0; c < width; ++c)
              if (masks[j].at(c, r) && depth.at(c, r) > 0)
                depth.at(c, r) = static_cast<float>(1.0 + 0.3 * uniform(0, 1));
        }
        const std::vector<PixelBox> boxes{PixelBox{2.5, 2.0, 26.0, 32.5}, PixelBox{0.0, 19.25, 15.75, 20.75}};
        Keypoints kps;
        for (int i = 0; i < 400; ++i) kps.push_back({uniform(0, width), uniform(0, height)});
        kps.push_back({static_cast<double>(width), static_cast<double>(height)});  // far corner, clamped

        DepthMADSettings s = settings_with(150, 3, 5, k);
        s.image_border_is_mask_edge = border_edge;
        DepthMADFilter<> f(s);
        f.engine.seed(seed);
        const Instances inst{cge::dynamic_instance(masks[0], boxes[0], 0),
                             cge::dynamic_instance(masks[1], boxes[1], 0)};
        const DepthMADResult r = f.filter(kps, depth, inst);

        std::mt19937_64 oracle_engine(seed);
        std::vector<OracleStats> os;
        for (int j = 0; j < 2; ++j) os.push_back(oracle_stats(oracle_engine, depth, masks[j], boxes[j], s));
        REQUIRE(f.engine == oracle_engine);  // exactly 2 n draws per instance

        for (int j = 0; j < 2; ++j) {
          const cge::InstanceDepthStats& got = r.instances[static_cast<std::size_t>(j)];
          INFO("seed " << seed << " border " << border_edge << " instance " << j);
          REQUIRE(got.samples_drawn == 150);
          REQUIRE(got.valid_samples == os[j].valid);
          REQUIRE(got.samples_off_mask == os[j].off_mask);
          REQUIRE(got.samples_invalid_depth == os[j].invalid_depth);
          REQUIRE(got.mad_test_applied == os[j].applied);
          REQUIRE(got.mean_depth_m == Approx(os[j].mean).epsilon(1e-12));
          REQUIRE(got.mad_m == Approx(os[j].mad).epsilon(1e-12));
          REQUIRE(got.valid_samples > 5);  // the fixture exercises the test
          REQUIRE(got.samples_off_mask > 0);
          REQUIRE(got.samples_invalid_depth > 0);
        }
        const std::vector<FeatureLabel> expected = oracle_labels(kps, depth, masks, boxes, os, k);
        REQUIRE(r.labels == expected);
        REQUIRE(r.static_count == count_label(expected, FeatureLabel::static_feature));
        REQUIRE(r.dynamic_by_mask_count == count_label(expected, FeatureLabel::dynamic_by_mask));
        REQUIRE(r.dynamic_by_mad_count == count_label(expected, FeatureLabel::dynamic_by_mad));
        REQUIRE(r.dynamic_by_mad_count > 0);  // every label occurs
        REQUIRE(r.dynamic_by_mask_count > 0);
        REQUIRE(r.static_count > 0);
      }
    }
  }
}

// ---- the mask_pixels estimate against a brute-force oracle ---------------------------------------------

namespace {

/// d_j and MAD_j over every pixel that is in the mask, in the box's pixels and has depth, found by
/// scanning the whole image; the test needs min_valid of them and the fraction of the mask's
/// pixels in the box.
OracleStats oracle_mask_stats(const FloatDepthImage& depth, const BinaryMask& mask, const PixelBox& box,
                              const DepthMADSettings& s) {
  OracleStats o;
  std::vector<double> d;
  int mask_pixels = 0;
  for (int r = 0; r < depth.height; ++r) {
    for (int c = 0; c < depth.width; ++c) {
      const bool in_box = c >= std::floor(box.x_min_px) && c < std::ceil(box.x_max_px()) &&
                          r >= std::floor(box.y_min_px) && r < std::ceil(box.y_max_px());
      if (!in_box || mask.at(c, r) == 0) continue;
      ++mask_pixels;
      const double v = depth.at(c, r);
      if (v > 0 && !std::isinf(v)) {
        d.push_back(v);
      } else {
        ++o.invalid_depth;
      }
    }
  }
  o.valid = static_cast<int>(d.size());
  o.applied = o.valid >= s.min_valid_samples && o.valid >= s.min_valid_mask_fraction * mask_pixels;
  if (!d.empty()) {
    double sum = 0;
    for (const double v : d) sum += v;
    o.mean = sum / static_cast<double>(d.size());
    double dev = 0;
    for (const double v : d) dev += std::abs(v - o.mean);
    o.mad = dev / static_cast<double>(d.size());
  }
  return o;
}

}  // namespace

TEST_CASE("mask_pixels: statistics and labels equal a scan of the whole image, nothing drawn",
          "[depth_mad][oracle][mask_pixels]") {
  const int width = 48, height = 40;
  for (const std::uint64_t seed : {3ull, 17ull, 20251202ull}) {
    for (const double hole_rate : {0.1, 0.7}) {  // enough depth in the masks, and too little
      std::mt19937_64 fixture(seed);
      const auto uniform = [&](double lo, double hi) {
        return lo + (hi - lo) * std::ldexp(static_cast<double>(fixture() >> 11), -53);
      };
      FloatDepthImage depth(width, height);
      for (float& d : depth.depth_m) d = static_cast<float>(uniform(0.5, 4.0));
      std::vector<BinaryMask> masks(2, BinaryMask(width, height));
      const double cx[2] = {14, 36}, cy[2] = {18, 26}, ax[2] = {10, 9}, ay[2] = {14, 12};
      for (int j = 0; j < 2; ++j) {
        for (int r = 0; r < height; ++r)
          for (int c = 0; c < width; ++c) {
            const double u = (c - cx[j]) / ax[j], v = (r - cy[j]) / ay[j];
            if (u * u + v * v > 1) continue;
            masks[j].at(c, r) = 1;
            const double roll = uniform(0, 1);
            depth.at(c, r) = roll < hole_rate / 2 ? 0.0f
                             : roll < hole_rate   ? nan_float
                                                  : static_cast<float>(1.0 + 0.4 * uniform(0, 1));
          }
      }
      // The second box cuts its ellipse: mask pixels outside the box do not count.
      const std::vector<PixelBox> boxes{PixelBox{3.5, 3.0, 22.0, 30.5}, PixelBox{30.0, 18.25, 18.0, 21.75}};
      Keypoints kps;
      for (int i = 0; i < 400; ++i) kps.push_back({uniform(0, width), uniform(0, height)});
      for (const double k : {1.0, 2.0}) {
        DepthMADSettings s = settings_with(100, 6, 5, k);
        s.depth_estimate = cge::DepthEstimate::mask_pixels;
        DepthMADFilter<ScriptedEngine> f(s);
        f.engine.script = {0.5};
        const Instances inst{cge::dynamic_instance(masks[0], boxes[0], 0),
                             cge::dynamic_instance(masks[1], boxes[1], 0)};
        const DepthMADResult r = f.filter(kps, depth, inst);
        REQUIRE(f.engine.draws == 0);
        std::vector<OracleStats> os;
        for (int j = 0; j < 2; ++j) os.push_back(oracle_mask_stats(depth, masks[j], boxes[j], s));
        for (int j = 0; j < 2; ++j) {
          INFO("seed " << seed << " holes " << hole_rate << " instance " << j);
          const cge::InstanceDepthStats& got = r.instances[static_cast<std::size_t>(j)];
          REQUIRE(got.valid_samples == os[j].valid);
          REQUIRE(got.samples_invalid_depth == os[j].invalid_depth);
          REQUIRE(got.samples_drawn == os[j].valid + os[j].invalid_depth);
          REQUIRE(got.samples_off_mask == 0);
          REQUIRE(got.mad_test_applied == os[j].applied);
          REQUIRE(got.mad_test_applied == (hole_rate < 0.5));  // the fixture exercises both outcomes
          REQUIRE(got.skip_reason ==
                  (got.mad_test_applied ? cge::MadSkipReason::none : cge::MadSkipReason::too_little_depth_in_mask));
          REQUIRE(got.mean_depth_m == Approx(os[j].mean).epsilon(1e-12));
          REQUIRE(got.mad_m == Approx(os[j].mad).epsilon(1e-12));
        }
        const std::vector<FeatureLabel> expected = oracle_labels(kps, depth, masks, boxes, os, k);
        REQUIRE(r.labels == expected);
        REQUIRE(r.dynamic_by_mad_count == count_label(expected, FeatureLabel::dynamic_by_mad));
        if (hole_rate < 0.5) REQUIRE(r.dynamic_by_mad_count > 0);
      }
    }
  }
}

TEST_CASE("skip reasons: too few valid samples, too little depth in the mask", "[depth_mad][rules][mask_pixels]") {
  // A 10 x 10 mask in a 20 x 20 image; depth 1 m on 30 of its 100 pixels (rows 0 .. 2 of the mask).
  FloatDepthImage depth(20, 20, 0.0f);
  BinaryMask mask(20, 20);
  fill_rect(mask, 5, 5, 14, 14);
  for (int r = 5; r <= 7; ++r)
    for (int c = 5; c <= 14; ++c) depth.at(c, r) = 1.0f;
  const Instances inst{cge::dynamic_instance(mask, PixelBox{5, 5, 10, 10})};

  DepthMADSettings s = settings_with(100, 0, 5);
  s.depth_estimate = cge::DepthEstimate::mask_pixels;
  DepthMADFilter<> f(s);
  cge::InstanceDepthStats st = f.filter(Keypoints{}, depth, inst).instances[0];
  CHECK(st.samples_drawn == 100);
  CHECK(st.valid_samples == 30);
  CHECK(st.samples_invalid_depth == 70);
  CHECK_FALSE(st.mad_test_applied);
  CHECK(st.skip_reason == cge::MadSkipReason::too_little_depth_in_mask);  // 0.3 < 0.5
  CHECK(st.mean_depth_m == 1.0);                                          // reported all the same
  f.settings.min_valid_mask_fraction = 0.3;                               // 30 >= 0.3 * 100
  st = f.filter(Keypoints{}, depth, inst).instances[0];
  CHECK(st.mad_test_applied);
  CHECK(st.skip_reason == cge::MadSkipReason::none);
  f.settings.min_valid_samples = 31;  // the count is checked first
  st = f.filter(Keypoints{}, depth, inst).instances[0];
  CHECK(st.skip_reason == cge::MadSkipReason::too_few_valid_samples);

  // box_samples with no depth anywhere: every sample invalid, too few.
  DepthMADFilter<> g(settings_with(40, 0, 5));
  g.engine.seed(1);
  st = g.filter(Keypoints{}, FloatDepthImage(20, 20, 0.0f), inst).instances[0];
  CHECK(st.valid_samples == 0);
  CHECK(st.samples_invalid_depth == 40);
  CHECK_FALSE(st.mad_test_applied);
  CHECK(st.skip_reason == cge::MadSkipReason::too_few_valid_samples);
  st = g.filter(Keypoints{}, depth, inst).instances[0];
  CHECK(st.mad_test_applied == (st.valid_samples >= 5));
  CHECK(st.skip_reason == (st.mad_test_applied ? cge::MadSkipReason::none : cge::MadSkipReason::too_few_valid_samples));

  CHECK(std::string(cge::to_string(cge::MadSkipReason::none)) == "none");
  CHECK(std::string(cge::to_string(cge::MadSkipReason::too_few_valid_samples)) == "too_few_valid_samples");
  CHECK(std::string(cge::to_string(cge::MadSkipReason::too_little_depth_in_mask)) == "too_little_depth_in_mask");
  CHECK(std::string(cge::to_string(cge::DepthEstimate::box_samples)) == "box_samples");
  CHECK(std::string(cge::to_string(cge::DepthEstimate::mask_pixels)) == "mask_pixels");
}

// ---- determinism ------------------------------------------------------------------------------------

TEST_CASE("same seed, same result; the engine advances between calls", "[depth_mad][determinism]") {
  FloatDepthImage depth(32, 24);
  for (int r = 0; r < 24; ++r)
    for (int c = 0; c < 32; ++c) depth.at(c, r) = 1.0f + 0.01f * static_cast<float>((c * 7 + r * 13) % 50);
  BinaryMask mask(32, 24);
  fill_rect(mask, 8, 4, 20, 20);
  const Instances inst{cge::dynamic_instance(mask, PixelBox{6, 2, 18, 20})};
  Keypoints kps;
  for (int i = 0; i < 100; ++i) kps.push_back({(i * 37) % 32 + 0.25, (i * 11) % 24 + 0.75});

  DepthMADFilter<> f(settings_with(50, 2, 5));
  f.engine.seed(42);
  const DepthMADResult a = f.filter(kps, depth, inst);
  const DepthMADResult b = f.filter(kps, depth, inst);  // engine advanced: other samples
  f.engine.seed(42);
  const DepthMADResult c = f.filter(kps, depth, inst);
  REQUIRE(a.labels == c.labels);
  REQUIRE(a.instances[0].valid_samples == c.instances[0].valid_samples);
  REQUIRE(a.instances[0].mean_depth_m == c.instances[0].mean_depth_m);  // bit-identical
  REQUIRE(a.instances[0].mad_m == c.instances[0].mad_m);
  REQUIRE(a.instances[0].mean_depth_m != b.instances[0].mean_depth_m);

  // Labels are in input order: reversing the keypoints reverses the labels.
  Keypoints reversed(kps.rbegin(), kps.rend());
  f.engine.seed(42);
  const DepthMADResult d = f.filter(reversed, depth, inst);
  REQUIRE(std::vector<FeatureLabel>(d.labels.rbegin(), d.labels.rend()) == a.labels);

  // A call that throws draws nothing.
  f.engine.seed(42);
  const std::mt19937_64 before = f.engine;
  Keypoints bad = kps;
  bad.push_back({nan_value, 1});
  REQUIRE_THROWS_AS(f.filter(bad, depth, inst), std::invalid_argument);
  REQUIRE(f.engine == before);
}

TEST_CASE("no instances, no keypoints: all static, nothing drawn", "[depth_mad][rules]") {
  const FloatDepthImage depth(8, 8, 1.0f);
  DepthMADFilter<ScriptedEngine> f;
  f.engine.script = {0.5};
  const DepthMADResult r = f.filter(Keypoints{{1, 1}, {7.5, 7.9}}, depth, Instances{});
  REQUIRE(r.labels == std::vector<FeatureLabel>(2, FeatureLabel::static_feature));
  REQUIRE(r.instances.empty());
  REQUIRE(f.engine.draws == 0);
  BinaryMask mask(8, 8, 1);
  const DepthMADResult e = f.filter(Keypoints{}, depth, Instances{cge::dynamic_instance(mask, PixelBox{0, 0, 8, 8})});
  REQUIRE(e.labels.empty());
  REQUIRE(e.instances.size() == 1);
  REQUIRE(f.engine.draws == 200);
}

// ---- bad input -----------------------------------------------------------------------------------------

TEST_CASE("bad input: clear errors naming the item", "[depth_mad][errors]") {
  const FloatDepthImage depth(20, 10, 1.0f);
  BinaryMask mask(20, 10, 1);
  BinaryMask small(10, 10, 1);
  const BinaryMask empty_mask;
  const PixelBox box{0, 0, 20, 10};
  DepthMADFilter<> f;
  const auto message = [&](const Keypoints& kps, const FloatDepthImage& d, const Instances& inst) {
    return cge_test::invalid_argument_message([&] { f.filter(kps, d, inst); });
  };
  const Instances good{cge::dynamic_instance(mask, box)};

  SECTION("depth and mask sizes differ") {
    const std::string m =
        message({}, depth, Instances{cge::dynamic_instance(mask, box), cge::dynamic_instance(small, box)});
    REQUIRE_THAT(m, Catch::Contains("instance #1") && Catch::Contains("10 x 10") && Catch::Contains("20 x 10"));
  }
  SECTION("empty and missing masks") {
    REQUIRE_THAT(message({}, depth, Instances{cge::dynamic_instance(empty_mask, box)}),
                 Catch::Contains("instance #0") && Catch::Contains("empty mask"));
    REQUIRE_THAT(message({}, depth, Instances{DynamicInstance<BinaryMask>{nullptr, box, 0}}),
                 Catch::Contains("instance #0") && Catch::Contains("no mask"));
  }
  SECTION("boxes outside the image or not finite") {
    REQUIRE_THAT(message({}, depth, Instances{cge::dynamic_instance(mask, PixelBox{1, 0, 20, 10})}),
                 Catch::Contains("instance #0: the box") && Catch::Contains("outside the image"));
    REQUIRE_THAT(message({}, depth, Instances{cge::dynamic_instance(mask, PixelBox{0, -0.25, 5, 5})}),
                 Catch::Contains("outside the image"));
    REQUIRE_THAT(message({}, depth, Instances{cge::dynamic_instance(mask, PixelBox{nan_value, 0, 5, 5})}),
                 Catch::Contains("not finite"));
    REQUIRE_THAT(message({}, depth, Instances{cge::dynamic_instance(mask, PixelBox{3, 3, 0, 5})}),
                 Catch::Contains("no positive width"));
  }
  SECTION("empty depth image") {
    REQUIRE_THAT(message({}, FloatDepthImage{}, Instances{}), Catch::Contains("depth image is empty"));
  }
  SECTION("keypoints not finite or outside [0, W] x [0, H]") {
    REQUIRE_THAT(message({{1, 1}, {nan_value, 2}}, depth, good), Catch::Contains("keypoint #1"));
    REQUIRE_THAT(message({{-0.01, 2}}, depth, good), Catch::Contains("keypoint #0") && Catch::Contains("outside"));
    REQUIRE_THAT(message({{20.01, 2}}, depth, good), Catch::Contains("keypoint #0"));
    REQUIRE_THAT(message({{2, 10.5}}, depth, good), Catch::Contains("keypoint #0"));
    REQUIRE_THAT(message({{std::numeric_limits<double>::infinity(), 2}}, depth, good), Catch::Contains("keypoint #0"));
    // The closed rectangle is accepted, as by GraphBuilder: x = W lies on the last column.
    REQUIRE(f.filter(Keypoints{{20, 10}, {0, 0}}, depth, good).labels.size() == 2);
  }
  SECTION("NaN depth is a missing measurement, never an error") {
    FloatDepthImage nan_depth(20, 10, nan_float);
    const DepthMADResult r = f.filter(Keypoints{{5, 5}}, nan_depth, Instances{});
    REQUIRE(r.labels[0] == FeatureLabel::static_feature);
  }
}

TEST_CASE("nearest_pixel_index: hand-worked roundings and clamps", "[depth_mad][core]") {
  using cge::nearest_pixel_index;
  // Pixel i has its centre at i: halves go away from zero, the value just below a half goes down.
  CHECK(nearest_pixel_index(0.0, 640) == 0);
  CHECK(nearest_pixel_index(std::nextafter(0.5, 0.0), 640) == 0);
  CHECK(nearest_pixel_index(0.5, 640) == 1);
  CHECK(nearest_pixel_index(2.5, 640) == 3);
  CHECK(nearest_pixel_index(2.4999, 640) == 2);
  CHECK(nearest_pixel_index(638.6, 640) == 639);
  // The far border (a keypoint exactly on x = width is inside the image) and beyond clamp to the last
  // pixel; small negative values clamp to the first.
  CHECK(nearest_pixel_index(640.0, 640) == 639);
  CHECK(nearest_pixel_index(700.0, 640) == 639);
  CHECK(nearest_pixel_index(-0.7, 640) == 0);
  CHECK(nearest_pixel_index(0.7, 1) == 0);
}
