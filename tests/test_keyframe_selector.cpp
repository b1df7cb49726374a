// Tests of keyframe selection (docs/METHOD.md section 2): the patch statistics against brute-force
// and hand-worked values, every rule of PatchKeyframeSelector firing and not firing, the interval
// end, an offline reference implementation of the state machine on random sequences, determinism,
// the ORB-SLAM2 baseline's rules, and the run-time switch between the two.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cge/core/image_region.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/frontend/frame_summary.hpp"
#include "cge/frontend/keyframe_decision.hpp"
#include "cge/frontend/keyframe_policy.hpp"
#include "cge/frontend/orbslam2_keyframe_policy.hpp"
#include "cge/frontend/patch_grid.hpp"
#include "cge/frontend/patch_keyframe_selector.hpp"
#include "cge/frontend/patch_statistics.hpp"
#include "test_support.hpp"

namespace {

using P = Eigen::Vector2d;
using Image = cge::ImageRegion<double>;
using Grid = cge::PatchGrid<double>;
using Summary = cge::FrameSummary<double>;
using Decision = cge::KeyframeDecision<double>;
using Selector = cge::PatchKeyframeSelector<double>;
using Settings = cge::PatchKeyframeSettings<double>;
using Orb = cge::OrbSlam2KeyframePolicy<double>;
using OrbSettings = cge::OrbSlam2KeyframeSettings<double>;
using Rule = cge::KeyframeRule;
using cge_test::invalid_argument_message;

Image make_image(double width, double height, P origin = P::Zero()) {
  Image img;
  img.width_px = width;
  img.height_px = height;
  img.origin_px = origin;
  return img;
}

Grid make_grid(const Image& image, int cols, int rows) {
  Grid g;
  g.image = image;
  g.cols = cols;
  g.rows = rows;
  return g;
}

// =============================================================================================
// Oracles written from the specification
// =============================================================================================

/// Features per patch by testing every point against every patch rectangle: [x0, x0 + w) x
/// [y0, y0 + h), the far border of the image belonging to the last column / row.
std::vector<int> brute_counts(const Grid& g, const std::vector<P>& points) {
  const double w = g.image.width_px / g.cols;
  const double h = g.image.height_px / g.rows;
  std::vector<int> counts(static_cast<std::size_t>(g.cols * g.rows), 0);
  bool each_in_one_patch = true;  // checks the oracle itself
  for (const P& p : points) {
    int hits = 0;
    for (int r = 0; r < g.rows; ++r) {
      for (int c = 0; c < g.cols; ++c) {
        const double x0 = g.image.origin_px.x() + c * w;
        const double y0 = g.image.origin_px.y() + r * h;
        const bool in_x = p.x() >= x0 && (p.x() < x0 + w || (c == g.cols - 1 && p.x() <= x0 + w));
        const bool in_y = p.y() >= y0 && (p.y() < y0 + h || (r == g.rows - 1 && p.y() <= y0 + h));
        if (in_x && in_y) {
          ++counts[static_cast<std::size_t>(r * g.cols + c)];
          ++hits;
        }
      }
    }
    each_in_one_patch = each_in_one_patch && hits == 1;
  }
  REQUIRE(each_in_one_patch);
  return counts;
}

/// Z literally as the spec words it.
cge::PatchHistogram spec_histogram(const std::vector<int>& counts) {
  cge::PatchHistogram z{};
  for (const int c : counts) {
    for (int i = 0; i <= 9; ++i) {
      if (2 * i < c && c <= 2 * (i + 1)) ++z[static_cast<std::size_t>(i)];
    }
    if (c > 20) ++z[10];
  }
  return z;
}

/// Cosine with the norms taken separately (the textbook formula) and the same zero conventions.
double spec_cosine(const cge::PatchHistogram& a, const cge::PatchHistogram& b) {
  double dot = 0, na = 0, nb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    dot += double(a[i]) * b[i];
    na += double(a[i]) * a[i];
    nb += double(b[i]) * b[i];
  }
  if (na == 0 && nb == 0) return 1.0;
  if (na == 0 || nb == 0) return 0.0;
  return dot / (std::sqrt(na) * std::sqrt(nb));
}

/// Dense-patch mean by ranks: a non-empty patch is among the densest when fewer than num_dense
/// patches have strictly more features (so ties at the cut are all in). No features: image centre.
P rank_dense_mean(const Grid& g, const std::vector<int>& counts, int num_dense) {
  const double w = g.image.width_px / g.cols;
  const double h = g.image.height_px / g.rows;
  P sum = P::Zero();
  int n = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (counts[i] == 0) continue;
    int strictly_more = 0;
    for (const int c : counts) strictly_more += c > counts[i] ? 1 : 0;
    if (strictly_more < num_dense) {
      const int col = static_cast<int>(i) % g.cols;
      const int row = static_cast<int>(i) / g.cols;
      sum += P(g.image.origin_px.x() + (col + 0.5) * w, g.image.origin_px.y() + (row + 0.5) * h);
      ++n;
    }
  }
  return n == 0 ? P(g.image.origin_px + P(g.image.width_px / 2, g.image.height_px / 2)) : P(sum / n);
}

// =============================================================================================
// Hand-built frames on a 4 x 2 grid over 640 x 480: patches of 160 x 240 px with centres
// x = 80, 240, 400, 560 and y = 120, 360.
// =============================================================================================

Grid grid42() { return make_grid(make_image(640, 480), 4, 2); }

Settings settings42() {
  Settings s;
  s.patch_cols = 4;
  s.patch_rows = 2;
  s.num_dense = 2;
  s.interval_frames = 4;
  s.cosine_threshold = 0.95;
  s.motion_threshold_px = 90;
  s.rho = 0.5;
  s.instance_change_threshold = 2;
  s.tracking_floor = 50;
  return s;
}

Summary frame(std::int64_t id, std::vector<int> counts, std::vector<P> centres = {}, int tracked = 100) {
  Summary f;
  f.frame_id = id;
  f.grid = grid42();
  f.patch_counts = std::move(counts);
  f.instance_centres_px = std::move(centres);
  f.tracked_points = tracked;
  return f;
}

// Reference: Z = {bin 4: 2}, dense mean (160, 120).
const std::vector<int> kRef{10, 10, 0, 0, 0, 0, 0, 0};
// Z = {bin 4: 1, bin 0: 1}, S_cos vs kRef = 1/sqrt(2); dense mean (160, 120), D_fp = 0.
const std::vector<int> kStill{10, 1, 0, 0, 0, 0, 0, 0};
// Same Z as kRef (S_cos = 1), dense mean (480, 120), D_fp = 320: large but no candidate.
const std::vector<int> kShiftedSameZ{0, 0, 10, 10, 0, 0, 0, 0};
// Z = {bin 4: 1, bin 0: 3}, S_cos vs kRef = 1/sqrt(10); the tie at 1 brings in p1..p3: dense mean
// (320, 120), D_fp = 160.
const std::vector<int> kFar{10, 1, 1, 1, 0, 0, 0, 0};
// Z = {bin 4: 1, bin 0: 2}, S_cos vs kRef = 1/sqrt(5); dense mean (240, 120), D_fp = 80.
const std::vector<int> kNear{10, 1, 1, 0, 0, 0, 0, 0};
const std::vector<int> kEmpty(8, 0);

/// An instance dx pixels right of (100, 100): with kStill and a reference instance at (100, 100),
/// D_se = dx and D_sum = 0.5 * 0 + 0.5 * dx.
std::vector<P> at(double dx) { return {P(100 + dx, 100)}; }

void require_none(const Decision& d) {
  REQUIRE(d.rule == Rule::none);
  REQUIRE(d.keyframe_id == cge::kNoFrame);
  REQUIRE_FALSE(d.inserts_keyframe());
}

void require_insert(const Decision& d, Rule rule, std::int64_t id) {
  REQUIRE(d.rule == rule);
  REQUIRE(d.keyframe_id == id);
  REQUIRE(d.inserts_keyframe());
}

}  // namespace

// =============================================================================================
// Patch statistics
// =============================================================================================

TEST_CASE("patch histogram: bins 2i < c <= 2(i+1), c > 20 in bin 10, empty patches in no bin",
          "[keyframe][histogram]") {
  for (int c = 0; c <= 60; ++c) {
    const int bin = cge::patch_histogram_bin(c);
    int expected = -1;
    for (int i = 0; i <= 9; ++i) {
      if (2 * i < c && c <= 2 * (i + 1)) expected = i;
    }
    if (c > 20) expected = 10;
    INFO("count " << c);
    REQUIRE(bin == expected);
  }
  // Hand-built counts, including every boundary.
  const std::vector<int> counts{0, 1, 2, 3, 4, 5, 19, 20, 21, 100, 0, 2};
  cge::PatchHistogram expected{};
  expected[0] = 3;   // 1, 2, 2
  expected[1] = 2;   // 3, 4
  expected[2] = 1;   // 5
  expected[9] = 2;   // 19, 20
  expected[10] = 2;  // 21, 100
  REQUIRE(cge::patch_histogram(counts) == expected);
  REQUIRE(cge::patch_histogram(std::vector<int>(100, 0)) == cge::PatchHistogram{});
  const std::string msg = invalid_argument_message([] { cge::patch_histogram({1, -1}); });
  REQUIRE(msg.find("patch 1") != std::string::npos);
}

TEST_CASE("patch counts and histogram equal a brute-force recount from raw points", "[keyframe][histogram][oracle]") {
  std::mt19937 rng(20250707);
  for (int trial = 0; trial < 40; ++trial) {
    const int cols = 1 + static_cast<int>(rng() % 12);
    const int rows = 1 + static_cast<int>(rng() % 9);
    // Patch sizes that are multiples of 1/8 px and coordinates on a 1/8 px lattice: every
    // comparison is exact, so boundaries are tested exactly.
    const double w8 = 8.0 * static_cast<double>(1 + rng() % 80);
    const double h8 = 8.0 * static_cast<double>(1 + rng() % 60);
    const P origin(static_cast<double>(rng() % 50) - 25, static_cast<double>(rng() % 50) - 25);
    const Grid g = make_grid(make_image(cols * w8 / 8, rows * h8 / 8, origin), cols, rows);
    std::vector<P> points;
    const int n = static_cast<int>(rng() % 1500);
    for (int i = 0; i < n; ++i) {
      const double x = origin.x() + static_cast<double>(rng() % static_cast<unsigned>(cols * w8 + 1)) / 8;
      const double y = origin.y() + static_cast<double>(rng() % static_cast<unsigned>(rows * h8 + 1)) / 8;
      points.emplace_back(x, y);
    }
    // Every patch corner, including the far borders.
    for (int r = 0; r <= rows; ++r) {
      for (int c = 0; c <= cols; ++c) points.emplace_back(origin.x() + c * w8 / 8, origin.y() + r * h8 / 8);
    }
    const std::vector<int> counts = cge::count_patch_features(g, points);
    REQUIRE(counts == brute_counts(g, points));
    REQUIRE(cge::patch_histogram(counts) == spec_histogram(counts));
  }
}

TEST_CASE("patch counts read any adapted point type and reject points outside the image",
          "[keyframe][histogram][errors]") {
  const Grid g = make_grid(make_image(100, 50), 2, 1);
  const std::vector<std::array<float, 2>> arrays{{10.f, 10.f}, {49.9f, 0.f}, {50.f, 0.f}, {100.f, 50.f}};
  REQUIRE(cge::count_patch_features(g, arrays) == std::vector<int>{2, 2});
  const std::vector<std::pair<int, int>> pairs{{0, 0}, {99, 49}};
  REQUIRE(cge::count_patch_features(g, pairs) == std::vector<int>{1, 1});

  const std::vector<P> outside{P(1, 1), P(100.5, 10)};
  REQUIRE(invalid_argument_message([&] { cge::count_patch_features(g, outside); }).find("#1") != std::string::npos);
  const std::vector<P> nan{P(std::nan(""), 1)};
  REQUIRE(invalid_argument_message([&] { cge::count_patch_features(g, nan); }).find("#0") != std::string::npos);
  Grid bad = g;
  bad.cols = 0;
  REQUIRE(invalid_argument_message([&] { cge::count_patch_features(bad, outside); }).find("cols") != std::string::npos);
}

TEST_CASE("histogram cosine: hand-worked values and the zero-vector conventions", "[keyframe][cosine]") {
  cge::PatchHistogram a{}, b{}, zero{};
  a[0] = 1;
  b[0] = 1;
  b[1] = 1;
  REQUIRE(cge::histogram_cosine(a, b) == Approx(1 / std::sqrt(2.0)).epsilon(1e-15));
  a = {};
  b = {};
  a[2] = 3;
  a[3] = 4;
  b[2] = 4;
  b[3] = 3;
  REQUIRE(cge::histogram_cosine(a, b) == Approx(24.0 / 25.0).epsilon(1e-15));
  // Proportional vectors: exactly 1 (one square root of the exact product).
  cge::PatchHistogram c{};
  c[2] = 9;
  c[3] = 12;
  REQUIRE(cge::histogram_cosine(a, c) == 1.0);
  cge::PatchHistogram d{};
  d[10] = 7;
  REQUIRE(cge::histogram_cosine(a, d) == 0.0);  // disjoint bins
  REQUIRE(cge::histogram_cosine(zero, zero) == 1.0);
  REQUIRE(cge::histogram_cosine(zero, a) == 0.0);
  REQUIRE(cge::histogram_cosine(a, zero) == 0.0);
  // Symmetry and agreement with the textbook formula on random histograms.
  std::mt19937 rng(7);
  for (int t = 0; t < 500; ++t) {
    cge::PatchHistogram x{}, y{};
    for (std::size_t i = 0; i < x.size(); ++i) {
      x[i] = static_cast<int>(rng() % 30);
      y[i] = static_cast<int>(rng() % 30) * static_cast<int>(rng() % 2);
    }
    const double cxy = cge::histogram_cosine(x, y);
    REQUIRE(cxy == cge::histogram_cosine(y, x));
    REQUIRE(cxy >= 0.0);
    REQUIRE(cxy <= 1.0);
    REQUIRE(cxy == Approx(spec_cosine(x, y)).epsilon(1e-14).margin(1e-15));
  }
}

TEST_CASE("dense-patch mean: hand-worked values, ties at the cut, few or no features", "[keyframe][dense]") {
  const Grid g = grid42();
  // Top two: p3 (9) and p4 (7): centres (560, 120) and (80, 360).
  REQUIRE(cge::dense_patch_mean(g, {1, 0, 2, 9, 7, 0, 3, 0}, 2) == P(320, 240));
  // Top one.
  REQUIRE(cge::dense_patch_mean(g, {1, 0, 2, 9, 7, 0, 3, 0}, 1) == P(560, 120));
  // A tie at the cut: p1, p2 and p5 all hold 4, so all three join p0 (5).
  REQUIRE(cge::dense_patch_mean(g, {5, 4, 4, 0, 0, 4, 0, 0}, 2) ==
          P((80 + 240 + 400 + 240) / 4.0, (120 * 3 + 360) / 4.0));
  // Fewer non-empty patches than num_dense: only the non-empty ones count.
  REQUIRE(cge::dense_patch_mean(g, {0, 0, 0, 0, 0, 0, 0, 3}, 5) == P(560, 360));
  // No features at all: the image centre (origin included).
  REQUIRE(cge::dense_patch_mean(g, kEmpty, 3) == P(320, 240));
  const Grid shifted = make_grid(make_image(640, 480, P(10, -20)), 4, 2);
  REQUIRE(cge::dense_patch_mean(shifted, kEmpty, 3) == P(330, 220));
  REQUIRE(cge::dense_patch_mean(shifted, {0, 0, 0, 0, 0, 0, 0, 3}, 5) == P(570, 340));
  // Errors.
  REQUIRE(invalid_argument_message([&] { cge::dense_patch_mean(g, {1, 2}, 2); }).find("4 x 2") != std::string::npos);
  REQUIRE(invalid_argument_message([&] { cge::dense_patch_mean(g, kRef, 0); }).find("num_dense") != std::string::npos);
}

TEST_CASE("dense-patch mean equals a rank-based recomputation", "[keyframe][dense][oracle]") {
  std::mt19937 rng(99);
  for (int t = 0; t < 300; ++t) {
    const int cols = 1 + static_cast<int>(rng() % 10);
    const int rows = 1 + static_cast<int>(rng() % 10);
    const Grid g = make_grid(make_image(640, 480, P(static_cast<double>(rng() % 7), 3)), cols, rows);
    std::vector<int> counts(static_cast<std::size_t>(cols * rows));
    const int spread = 1 + static_cast<int>(rng() % 6);  // small spreads force many ties
    for (int& c : counts) c = static_cast<int>(rng() % static_cast<unsigned>(spread));
    const int num_dense = 1 + static_cast<int>(rng() % 15);
    const P mean = cge::dense_patch_mean(g, counts, num_dense);
    const P expected = rank_dense_mean(g, counts, num_dense);
    REQUIRE(mean.x() == Approx(expected.x()).epsilon(1e-12));
    REQUIRE(mean.y() == Approx(expected.y()).epsilon(1e-12));
  }
}

TEST_CASE("semantic centroid: mean of all instance centres, none without instances", "[keyframe][centroid]") {
  REQUIRE_FALSE(cge::semantic_centroid(std::vector<P>{}).has_value());
  const auto c = cge::semantic_centroid(std::vector<P>{P(0, 0), P(30, 0), P(0, 60)});
  REQUIRE(c.has_value());
  REQUIRE(*c == P(10, 20));
}

TEST_CASE("make_frame_summary counts keypoints and keeps every instance centre", "[keyframe][summary]") {
  const Image image = make_image(640, 480);
  const std::vector<P> kps{P(1, 1), P(170, 5), P(639, 479), P(640, 480), P(400, 300)};
  std::vector<cge::SemanticInstance<double>> instances(2);
  instances[0].centre_px = P(50, 60);
  instances[0].dynamic = true;  // dynamic instances count too (all classes)
  instances[1].centre_px = P(500, 400);
  instances[1].class_id = 56;
  cge::PatchKeyframeSettings<double> paper_rule = settings42();
  paper_rule.dynamic_instances_only = false;  // the paper counts every instance
  const Selector selector(paper_rule);
  const Summary s = selector.summarise(7, image, kps, instances, 123);
  REQUIRE(s.frame_id == 7);
  REQUIRE(s.grid == grid42());
  REQUIRE(s.patch_counts == brute_counts(grid42(), kps));
  REQUIRE(s.patch_counts == std::vector<int>{1, 1, 0, 0, 0, 0, 1, 2});
  REQUIRE(s.instance_centres_px == std::vector<P>{P(50, 60), P(500, 400)});
  REQUIRE(s.instance_count() == 2);
  REQUIRE(s.tracked_points == 123);

  instances[1].centre_px = P(700, 10);
  REQUIRE(invalid_argument_message([&] { selector.summarise(8, image, kps, instances, 1); }).find("instance #1") !=
          std::string::npos);
  instances[1].centre_px = P(70, 10);
  REQUIRE(invalid_argument_message([&] { selector.summarise(8, image, kps, instances, -1); }).find("tracked") !=
          std::string::npos);
  REQUIRE(invalid_argument_message([&] { selector.summarise(-2, image, kps, instances, 1); }).find("frame_id") !=
          std::string::npos);
}

TEST_CASE("make_frame_summary with dynamic_instances_only keeps only dynamic instances' centres", "[keyframe][summary]") {
  const Image image = make_image(640, 480);
  const std::vector<P> kps{P(1, 1), P(400, 300)};
  std::vector<cge::SemanticInstance<double>> instances(3);
  instances[0].centre_px = P(50, 60);
  instances[0].dynamic = true;
  instances[1].centre_px = P(500, 400);  // a static object: a chair, say
  instances[1].class_id = 56;
  instances[2].centre_px = P(300, 200);
  instances[2].dynamic = true;
  cge::PatchKeyframeSettings<double> settings = settings42();
  settings.dynamic_instances_only = true;
  const Summary s = Selector(settings).summarise(7, image, kps, instances, 10);
  REQUIRE(s.instance_centres_px == std::vector<P>{P(50, 60), P(300, 200)});
  // So static objects coming into view change neither Num_cur nor the centroid.
  instances[1].centre_px = P(600, 20);
  instances.push_back(instances[1]);
  const Summary more_static = Selector(settings).summarise(8, image, kps, instances, 10);
  REQUIRE(more_static.instance_centres_px == s.instance_centres_px);
  settings.dynamic_instances_only = false;
  REQUIRE(Selector(settings).summarise(8, image, kps, instances, 10).instance_count() == 4);
}

// =============================================================================================
// PatchKeyframeSelector rules
// =============================================================================================

TEST_CASE("selector: the first frame is a keyframe and becomes the reference", "[keyframe][rules]") {
  Selector sel(settings42());
  REQUIRE(sel.reference_id() == cge::kNoFrame);
  const Decision d = sel.step(frame(5, kRef));
  require_insert(d, Rule::first_frame, 5);
  REQUIRE(d.frame_id == 5);
  REQUIRE_FALSE(d.measures.patch_measures);
  REQUIRE(sel.reference_id() == 5);
  // An identical frame: S_cos = 1, nothing moved, no candidate.
  const Decision same = sel.step(frame(6, kRef));
  require_none(same);
  REQUIRE(same.measures.patch_measures);
  REQUIRE(same.measures.s_cos == 1.0);
  REQUIRE(same.measures.d_fp == 0.0);
  REQUIRE_FALSE(same.measures.candidate);
  REQUIRE(same.measures.interval_position == 1);
  REQUIRE(same.measures.frames_since_reference == 1);
}

TEST_CASE("selector: the candidate test S_cos < S_th_z", "[keyframe][rules]") {
  Settings s = settings42();
  SECTION("below the threshold: a candidate, kept pending") {
    Selector sel(s);
    sel.step(frame(0, kRef));
    const Decision d = sel.step(frame(1, kStill));
    require_none(d);
    REQUIRE(d.measures.s_cos == Approx(1 / std::sqrt(2.0)).epsilon(1e-15));
    REQUIRE(d.measures.candidate);
    REQUIRE(d.keep_current);
    REQUIRE(sel.pending_ids() == std::vector<std::int64_t>{1});
  }
  SECTION("at the threshold: not a candidate (strict)") {
    s.cosine_threshold = cge::histogram_cosine(cge::patch_histogram(kStill), cge::patch_histogram(kRef));
    Selector sel(s);
    sel.step(frame(0, kRef));
    const Decision d = sel.step(frame(1, kStill));
    REQUIRE_FALSE(d.measures.candidate);
    REQUIRE_FALSE(d.keep_current);
    REQUIRE(sel.pending_ids().empty());
  }
  SECTION("switched off: every frame with features is a candidate") {
    s.use_candidate_test = false;
    Selector sel(s);
    sel.step(frame(0, kRef));
    const Decision d = sel.step(frame(1, kRef));
    REQUIRE(d.measures.s_cos == 1.0);
    REQUIRE(d.measures.candidate);
    REQUIRE(sel.pending_ids() == std::vector<std::int64_t>{1});
  }
}

TEST_CASE("selector: large motion inserts a candidate at once", "[keyframe][rules]") {
  Settings s = settings42();
  SECTION("D_sum > D_th fires, drops the pending candidates and restarts the interval") {
    Selector sel(s);
    sel.step(frame(0, kRef, at(0)));
    REQUIRE(sel.step(frame(1, kStill, at(20))).keep_current);
    const Decision d = sel.step(frame(2, kFar));  // no instances: D_sum = D_fp = 160
    require_insert(d, Rule::large_motion, 2);
    REQUIRE(d.measures.d_fp == 160.0);
    REQUIRE(d.measures.d_sum == 160.0);
    REQUIRE_FALSE(d.measures.semantic_term);
    REQUIRE_FALSE(d.keep_current);
    REQUIRE(sel.pending_ids().empty());
    REQUIRE(sel.reference_id() == 2);
    REQUIRE(sel.interval_position() == 0);
    // The interval restarts after the insertion: frame 3 (a candidate against frame 2, D_sum = 80)
    // is inserted when frames 3..6 have been seen, not at the old interval's end (frame 4).
    const Decision d3 = sel.step(frame(3, {0, 0, 10, 0, 0, 0, 0, 0}));
    REQUIRE(d3.measures.candidate);
    REQUIRE(d3.measures.d_sum == 80.0);
    REQUIRE(d3.measures.interval_position == 1);
    require_none(sel.step(frame(4, kFar)));
    require_none(sel.step(frame(5, kFar)));
    require_insert(sel.step(frame(6, kFar)), Rule::interval_best_candidate, 3);
  }
  SECTION("D_sum == D_th does not fire (strict), D_sum just above does") {
    Selector sel(s);
    sel.step(frame(0, kRef, at(0)));
    const Decision at_threshold = sel.step(frame(1, kStill, at(180)));
    REQUIRE(at_threshold.measures.d_sum == 90.0);
    REQUIRE(at_threshold.measures.semantic_term);
    require_none(at_threshold);
    REQUIRE(at_threshold.keep_current);
    require_insert(sel.step(frame(2, kStill, at(182))), Rule::large_motion, 2);
  }
  SECTION("a large D_fp without candidacy does not fire") {
    Selector sel(s);
    sel.step(frame(0, kRef));
    const Decision d = sel.step(frame(1, kShiftedSameZ));
    REQUIRE(d.measures.s_cos == 1.0);
    REQUIRE(d.measures.d_fp == 320.0);
    REQUIRE_FALSE(d.measures.candidate);
    require_none(d);
  }
  SECTION("switched off: the candidate waits for the interval end") {
    s.use_large_motion = false;
    Selector sel(s);
    sel.step(frame(0, kRef));
    const Decision d = sel.step(frame(1, kFar));
    require_none(d);
    REQUIRE(d.keep_current);
    sel.step(frame(2, kRef));
    sel.step(frame(3, kRef));
    require_insert(sel.step(frame(4, kRef)), Rule::interval_best_candidate, 1);
  }
}

TEST_CASE("selector: D_sum mixes D_fp and D_se only when both frames have instances", "[keyframe][rules]") {
  Settings s = settings42();
  s.motion_threshold_px = 1000;  // measure only
  auto measure = [&](const Settings& settings, std::vector<P> ref_instances, std::vector<P> cur_instances) {
    Selector sel(settings);
    sel.step(frame(0, kRef, std::move(ref_instances)));
    return sel.step(frame(1, kNear, std::move(cur_instances))).measures;
  };
  // D_fp = 80; instance centroids (100, 100) and (160, 180): D_se = 100.
  auto m = measure(s, {P(100, 100)}, {P(160, 180)});
  REQUIRE(m.d_fp == 80.0);
  REQUIRE(m.d_se == 100.0);
  REQUIRE(m.semantic_term);
  REQUIRE(m.d_sum == 90.0);
  // Centroids of several instances: (50, 100) and (150, 100) average to (100, 100).
  m = measure(s, {P(50, 100), P(150, 100)}, {P(160, 180)});
  REQUIRE(m.d_se == Approx(100.0).epsilon(1e-15));
  REQUIRE(m.instance_count == 1);
  REQUIRE(m.reference_instance_count == 2);
  Settings quarter = s;
  quarter.rho = 0.25;
  REQUIRE(measure(quarter, {P(100, 100)}, {P(160, 180)}).d_sum == 0.25 * 80 + 0.75 * 100);
  Settings no_semantics = s;
  no_semantics.rho = 1;
  REQUIRE(measure(no_semantics, {P(100, 100)}, {P(160, 180)}).d_sum == 80.0);
  // Either frame without instances: D_sum = D_fp.
  for (const auto& [ref_inst, cur_inst] :
       std::vector<std::pair<std::vector<P>, std::vector<P>>>{{{}, {P(160, 180)}}, {{P(100, 100)}, {}}, {{}, {}}}) {
    m = measure(s, ref_inst, cur_inst);
    REQUIRE_FALSE(m.semantic_term);
    REQUIRE(m.d_se == 0.0);
    REQUIRE(m.d_sum == 80.0);
  }
}

TEST_CASE("selector: the interval end inserts the candidate with the highest D_sum", "[keyframe][rules][interval]") {
  Selector sel(settings42());  // k = 4
  sel.step(frame(0, kRef, at(0)));
  Decision d = sel.step(frame(1, kStill, at(20)));  // D_sum 10
  REQUIRE(d.measures.d_sum == 10.0);
  REQUIRE(d.keep_current);
  d = sel.step(frame(2, kRef, at(0)));  // no candidate
  REQUIRE_FALSE(d.keep_current);
  d = sel.step(frame(3, kStill, at(60)));  // D_sum 30
  REQUIRE(sel.pending_ids() == std::vector<std::int64_t>{1, 3});
  REQUIRE(sel.interval_position() == 3);
  d = sel.step(frame(4, kStill, at(60)));  // D_sum 30, a tie: the earlier frame 3 wins
  require_insert(d, Rule::interval_best_candidate, 3);
  REQUIRE(d.frame_id == 4);
  REQUIRE(d.measures.interval_position == 4);
  REQUIRE_FALSE(d.keep_current);
  REQUIRE(sel.pending_ids().empty());
  REQUIRE(sel.reference_id() == 3);
  // Frame 3 is now the reference: the next frame is measured against its histogram and instance.
  d = sel.step(frame(5, kStill, at(60)));
  require_none(d);
  REQUIRE(d.measures.s_cos == 1.0);
  REQUIRE(d.measures.d_sum == 0.0);
  REQUIRE(d.measures.interval_position == 1);
  REQUIRE(d.measures.frames_since_reference == 2);  // frames 4 and 5 since frame 3
}

TEST_CASE("selector: an interval without candidates inserts nothing", "[keyframe][rules][interval]") {
  Selector sel(settings42());
  sel.step(frame(0, kRef));
  for (std::int64_t id = 1; id <= 9; ++id) require_none(sel.step(frame(id, kRef)));
  REQUIRE(sel.reference_id() == 0);
  REQUIRE(sel.interval_position() == 1);  // two full intervals of 4 and one frame
}

TEST_CASE("selector: intervals of length 1 decide on every frame", "[keyframe][rules][interval]") {
  Settings s = settings42();
  s.interval_frames = 1;
  Selector sel(s);
  sel.step(frame(0, kRef, at(0)));
  require_none(sel.step(frame(1, kRef, at(0))));
  const Decision d = sel.step(frame(2, kStill, at(20)));
  require_insert(d, Rule::interval_best_candidate, 2);
  REQUIRE_FALSE(d.keep_current);
  REQUIRE(sel.pending_ids().empty());
}

TEST_CASE("selector: switching the interval rule off keeps nothing pending", "[keyframe][rules][interval]") {
  Settings s = settings42();
  s.use_interval_best = false;
  s.interval_frames = 2;
  Selector sel(s);
  sel.step(frame(0, kRef, at(0)));
  for (std::int64_t id = 1; id <= 6; ++id) {
    const Decision d = sel.step(frame(id, kStill, at(20)));
    require_none(d);
    REQUIRE(d.measures.candidate);
    REQUIRE_FALSE(d.keep_current);
  }
  REQUIRE(sel.pending_ids().empty());
  require_none(sel.flush());
  // Large motion still works.
  require_insert(sel.step(frame(7, kFar)), Rule::large_motion, 7);
}

TEST_CASE("selector: semantic change |Num_cur - Num_ref| >= Num_th inserts at once", "[keyframe][rules]") {
  Settings s = settings42();  // Num_th = 2
  Selector sel(s);
  sel.step(frame(0, kRef, {P(10, 10)}));
  require_none(sel.step(frame(1, kRef, {P(10, 10), P(20, 20)})));  // +1
  require_none(sel.step(frame(2, kRef, {})));                      // -1
  REQUIRE(sel.step(frame(3, kRef, {P(10, 10)})).measures.candidate == false);
  const Decision d = sel.step(frame(4, kRef, {P(10, 10), P(20, 20), P(30, 30)}));  // +2
  require_insert(d, Rule::semantic_change, 4);
  REQUIRE(d.measures.instance_count == 3);
  REQUIRE(d.measures.reference_instance_count == 1);
  require_insert(sel.step(frame(5, kRef, {P(10, 10)})), Rule::semantic_change, 5);  // -2 from the new reference
  s.use_semantic_change = false;
  Selector off(s);
  off.step(frame(0, kRef, {}));
  require_none(off.step(frame(1, kRef, {P(1, 1), P(2, 2), P(3, 3), P(4, 4)})));
}

TEST_CASE("selector: a semantic change held for semantic_change_frames frames inserts, a shorter one does not", "[keyframe][rules]") {
  Settings s = settings42();  // Num_th 2
  s.semantic_change_frames = 3;
  Selector sel(s);
  sel.step(frame(0, kRef, {P(10, 10)}));
  const std::vector<P> three = {P(10, 10), P(20, 20), P(30, 30)};
  // Two frames of change, then the count is back: a dropout, no keyframe.
  REQUIRE(sel.step(frame(1, kRef, three)).measures.semantic_change_frames == 1);
  require_none(sel.step(frame(2, kRef, three)));
  REQUIRE(sel.step(frame(3, kRef, {P(10, 10)})).measures.semantic_change_frames == 0);
  // Three frames of change: the third inserts.
  require_none(sel.step(frame(4, kRef, three)));
  require_none(sel.step(frame(5, kRef, three)));
  const Decision d = sel.step(frame(6, kRef, three));
  require_insert(d, Rule::semantic_change, 6);
  REQUIRE(d.measures.semantic_change_frames == 3);
  // Against the new reference (3 instances) the count starts again.
  REQUIRE(sel.step(frame(7, kRef, {P(10, 10)})).measures.semantic_change_frames == 1);
}

TEST_CASE("selector: the tracking guard fires under the floor, first in priority", "[keyframe][rules]") {
  Settings s = settings42();  // floor 50
  Selector sel(s);
  sel.step(frame(0, kRef, {}, 300));
  require_none(sel.step(frame(1, kRef, {}, 50)));
  const Decision d = sel.step(frame(2, kRef, {}, 49));
  require_insert(d, Rule::tracking_guard, 2);
  REQUIRE(d.measures.tracked_points == 49);
  REQUIRE(d.measures.reference_tracked_points == 300);
  // Guard, semantic change and large motion at once: the guard is reported.
  require_insert(sel.step(frame(3, kFar, {P(1, 1), P(2, 2)}, 10)), Rule::tracking_guard, 3);
  // Semantic change before large motion.
  require_insert(sel.step(frame(4, kRef, {}, 100)), Rule::semantic_change, 4);
  s.use_tracking_guard = false;
  Selector off(s);
  off.step(frame(0, kRef, {}, 300));
  require_none(off.step(frame(1, kRef, {}, 0)));
}

Summary with_close(Summary f, int tracked_close, int untracked_close) {
  f.tracked_close_points = tracked_close;
  f.untracked_close_points = untracked_close;
  return f;
}

TEST_CASE("selector: the coverage guard fires when the frame tracks under the ratio of its own close points",
          "[keyframe][rules]") {
  Settings s = settings42();  // coverage ratio 0.2, more than 70 untracked close points
  REQUIRE(s.coverage_ratio == 0.2);
  REQUIRE(s.coverage_min_untracked_close == 70);
  Selector sel(s);
  sel.step(with_close(frame(0, kRef, {}, 300), 200, 100));
  // 100 of 500 close points is the ratio exactly (strict: no insertion); 99 of 499 is under it.
  require_none(sel.step(with_close(frame(1, kRef, {}, 300), 100, 400)));
  Decision d = sel.step(with_close(frame(2, kRef, {}, 300), 99, 400));
  require_insert(d, Rule::coverage_guard, 2);
  REQUIRE(d.measures.tracked_close_points == 99);
  REQUIRE(d.measures.untracked_close_points == 400);
  REQUIRE(d.measures.reference_tracked_close_points == 200);
  // The reference's own count plays no part: a reference that tracked few close points (inserted
  // by this guard, 99) does not silence the guard for the frames after it.
  require_insert(sel.step(with_close(frame(3, kRef, {}, 300), 30, 200)), Rule::coverage_guard, 3);
  // 17 of 88 is under 0.2, but 71 untracked are needed: 17 + 70 stays, 17 + 71 fires.
  require_none(sel.step(with_close(frame(4, kRef, {}, 300), 17, 70)));
  require_insert(sel.step(with_close(frame(5, kRef, {}, 300), 17, 71)), Rule::coverage_guard, 5);
  // No close point tracked at all fires it too.
  require_insert(sel.step(with_close(frame(6, kRef, {}, 300), 0, 71)), Rule::coverage_guard, 6);
  // After the tracking guard, before the semantic change.
  require_insert(sel.step(with_close(frame(7, kRef, {}, 10), 0, 400)), Rule::tracking_guard, 7);
  require_insert(sel.step(with_close(frame(8, kRef, {P(1, 1), P(2, 2)}, 300), 10, 400)), Rule::coverage_guard, 8);
  SECTION("counts not measured (-1) never fire it") {
    Selector unknown(s);
    unknown.step(frame(0, kRef, {}, 300));
    const Decision u = unknown.step(with_close(frame(1, kRef, {}, 300), -1, 500));
    require_none(u);
    REQUIRE(u.measures.reference_tracked_close_points == -1);
    require_none(unknown.step(with_close(frame(2, kRef, {}, 300), 0, -1)));
    require_none(unknown.step(frame(3, kRef, {}, 300)));
  }
  SECTION("switched off, or ratio 0") {
    Settings off = s;
    off.use_coverage_guard = false;
    Settings zero = s;
    zero.coverage_ratio = 0;
    for (const Settings& variant : {off, zero}) {
      Selector o(variant);
      o.step(with_close(frame(0, kRef, {}, 300), 200, 100));
      require_none(o.step(with_close(frame(1, kRef, {}, 300), 0, 1000)));
    }
  }
  SECTION("bad settings are refused") {
    Settings bad = s;
    bad.coverage_ratio = 1.5;
    REQUIRE(invalid_argument_message([&] { Selector(bad).step(frame(0, kRef)); }).find("coverage_ratio") !=
            std::string::npos);
    bad = s;
    bad.coverage_min_untracked_close = -1;
    REQUIRE(invalid_argument_message([&] { Selector(bad).step(frame(0, kRef)); })
                .find("coverage_min_untracked_close") != std::string::npos);
  }
}

TEST_CASE("selector: frames without features", "[keyframe][rules][edge]") {
  SECTION("a featureless frame is never a candidate") {
    Settings s = settings42();
    s.use_candidate_test = false;
    Selector sel(s);
    sel.step(frame(0, kRef));
    const Decision d = sel.step(frame(1, kEmpty));
    REQUIRE(d.measures.s_cos == 0.0);
    REQUIRE(d.measures.d_fp == Approx((P(320, 240) - P(160, 120)).norm()).epsilon(1e-15));
    REQUIRE_FALSE(d.measures.candidate);
    require_none(d);
  }
  SECTION("a featureless reference: another featureless frame has S_cos 1, a frame with features 0") {
    Selector sel(settings42());
    sel.step(frame(0, kEmpty));
    const Decision empty = sel.step(frame(1, kEmpty));
    REQUIRE(empty.measures.s_cos == 1.0);
    REQUIRE_FALSE(empty.measures.candidate);
    const Decision d = sel.step(frame(2, kStill));
    REQUIRE(d.measures.s_cos == 0.0);
    REQUIRE(d.measures.candidate);
    // D_fp is measured from the image centre, the featureless frame's dense mean: 200 px > D_th.
    REQUIRE(d.measures.d_fp == 200.0);
    require_insert(d, Rule::large_motion, 2);
  }
}

TEST_CASE("selector: flush closes the last partial interval", "[keyframe][rules][interval]") {
  Selector sel(settings42());
  require_none(sel.flush());  // nothing seen yet
  sel.step(frame(0, kRef, at(0)));
  sel.step(frame(1, kStill, at(20)));  // D_sum 10
  sel.step(frame(2, kStill, at(40)));  // D_sum 20
  const Decision d = sel.flush();
  require_insert(d, Rule::interval_best_candidate, 2);
  REQUIRE(d.frame_id == cge::kNoFrame);
  REQUIRE(sel.reference_id() == 2);
  REQUIRE(sel.pending_ids().empty());
  require_none(sel.flush());
  // Usable afterwards: the next frame opens a new interval against frame 2.
  const Decision next = sel.step(frame(3, kStill, at(40)));
  REQUIRE(next.measures.interval_position == 1);
  REQUIRE(next.measures.d_sum == 0.0);
}

TEST_CASE("selector: reset starts a new sequence", "[keyframe][rules]") {
  Selector sel(settings42());
  sel.step(frame(10, kRef));
  sel.step(frame(11, kStill));
  sel.reset();
  REQUIRE(sel.reference_id() == cge::kNoFrame);
  REQUIRE(sel.pending_ids().empty());
  require_insert(sel.step(frame(3, kStill)), Rule::first_frame, 3);  // ids may start over
}

TEST_CASE("selector: set_reference_tracked_points is logged and needs a reference", "[keyframe][rules]") {
  Selector sel(settings42());
  REQUIRE_THROWS_AS(sel.set_reference_tracked_points(10), std::logic_error);
  sel.step(frame(0, kRef, {}, 60));
  sel.set_reference_tracked_points(500);
  REQUIRE(sel.step(frame(1, kRef, {}, 400)).measures.reference_tracked_points == 500);
  REQUIRE_THROWS_AS(sel.set_reference_tracked_points(-1), std::invalid_argument);
}

TEST_CASE("selector rejects invalid input and stays unchanged", "[keyframe][errors]") {
  Selector sel(settings42());
  Selector twin(settings42());
  for (Selector* s : {&sel, &twin}) {
    s->step(frame(0, kRef, at(0)));
    s->step(frame(1, kStill, at(20)));
  }
  auto check = [&](const Summary& bad, const char* expected) {
    const std::string msg = invalid_argument_message([&] { sel.step(bad); });
    INFO(msg);
    REQUIRE(msg.find(expected) != std::string::npos);
  };
  check(frame(1, kStill), "increase");
  check(frame(0, kStill), "increase");
  Summary wrong_grid = frame(5, std::vector<int>(100, 1));
  wrong_grid.grid = make_grid(make_image(640, 480), 10, 10);
  check(wrong_grid, "10 x 10");
  check(frame(5, {1, 2, 3}), "3 patch counts");
  check(frame(5, {1, 2, 3, 4, 5, 6, 7, -8}), "patch 7");
  check(frame(5, kRef, {P(1, 1), P(650, 1)}), "instance #1");
  check(frame(5, kRef, {P(std::nan(""), 1)}), "instance #0");
  check(frame(5, kRef, {}, -3), "tracked_points");
  check(frame(-5, kRef), "frame_id");
  Summary bad_image = frame(5, kRef);
  bad_image.grid.image.width_px = 0;
  check(bad_image, "width_px");
  // Nothing changed: the next valid frame gives what the twin gives.
  REQUIRE(sel.pending_ids() == twin.pending_ids());
  for (std::int64_t id = 2; id <= 4; ++id) {
    const Decision a = sel.step(frame(id, kStill, at(10.0 * double(id))));
    const Decision b = twin.step(frame(id, kStill, at(10.0 * double(id))));
    REQUIRE(a.rule == b.rule);
    REQUIRE(a.keyframe_id == b.keyframe_id);
    REQUIRE(a.measures.interval_position == b.measures.interval_position);
  }
}

TEST_CASE("selector settings are validated with the field named", "[keyframe][errors]") {
  auto message = [](void (*edit)(Settings&)) {
    Settings s = settings42();
    edit(s);
    Selector sel(s);
    return invalid_argument_message([&] { sel.step(frame(0, kRef)); });
  };
  REQUIRE(message([](Settings& s) { s.interval_frames = 0; }).find("interval_frames") != std::string::npos);
  REQUIRE(message([](Settings& s) { s.patch_cols = 0; }).find("patch_cols") != std::string::npos);
  REQUIRE(message([](Settings& s) { s.cosine_threshold = 1.5; }).find("cosine_threshold") != std::string::npos);
  REQUIRE(message([](Settings& s) { s.cosine_threshold = std::nan(""); }).find("cosine_threshold") !=
          std::string::npos);
  REQUIRE(message([](Settings& s) { s.num_dense = 0; }).find("num_dense") != std::string::npos);
  REQUIRE(message([](Settings& s) { s.rho = -0.1; }).find("rho") != std::string::npos);
  REQUIRE(message([](Settings& s) { s.motion_threshold_px = -1; }).find("motion_threshold_px") != std::string::npos);
  REQUIRE(message([](Settings& s) {
            s.motion_threshold_px = std::numeric_limits<double>::infinity();
          }).find("motion_threshold_px") != std::string::npos);
  REQUIRE(message([](Settings& s) { s.instance_change_threshold = 0; }).find("instance_change_threshold") !=
          std::string::npos);
  REQUIRE(message([](Settings& s) { s.tracking_floor = -1; }).find("tracking_floor") != std::string::npos);
}

// =============================================================================================
// The state machine against an offline reference implementation on random sequences
// =============================================================================================

namespace {

/// One frame of a synthetic sequence, in raw form (keypoints, not counts).
struct RawFrame {
  std::int64_t id;
  std::vector<P> keypoints;
  std::vector<P> instances;
  int tracked;
  int tracked_close = -1;
  int untracked_close = -1;
};

/// A camera panning over a textured canvas with occasional jumps, objects that come and go, and
/// tracking that sometimes weakens. Coordinates on a 1/8 px lattice.
std::vector<RawFrame> random_sequence(std::uint32_t seed, int length) {
  std::mt19937 rng(seed);
  auto uniform = [&](int lo, int hi) { return lo + static_cast<int>(rng() % static_cast<unsigned>(hi - lo + 1)); };
  std::vector<P> canvas;
  for (int i = 0; i < 6000; ++i) {
    // Texture density varies across the canvas, so the patch histogram changes as the view moves.
    const int x = uniform(0, 8 * 2000);
    const int y = uniform(0, 8 * 480);
    if (uniform(0, 99) < 30 + 60 * ((x / (8 * 250)) % 2)) canvas.emplace_back(x / 8.0, y / 8.0);
  }
  std::vector<RawFrame> frames;
  double pan = 0;
  std::vector<P> objects{P(100, 100), P(400, 300)};
  std::int64_t id = 0;
  for (int t = 0; t < length; ++t) {
    id += 1 + uniform(0, 2);  // ids increase with gaps
    pan += uniform(0, 100) < 5 ? uniform(-300, 300) : uniform(-12, 20);
    pan = std::clamp(pan, 0.0, 1360.0);
    RawFrame f;
    f.id = id;
    for (const P& c : canvas) {
      const double x = c.x() - std::round(pan * 8) / 8;
      if (x >= 0 && x <= 640 && uniform(0, 99) < 90) f.keypoints.emplace_back(x, c.y());
    }
    const int event = uniform(0, 99);
    if (event < 4 && objects.size() < 6) objects.emplace_back(double(uniform(0, 640)), double(uniform(0, 480)));
    if (event >= 96 && !objects.empty()) objects.pop_back();
    if (event >= 48 && event < 50) objects.clear();
    for (P& o : objects) {
      o.x() = std::clamp(o.x() + uniform(-6, 6), 0.0, 640.0);
      o.y() = std::clamp(o.y() + uniform(-6, 6), 0.0, 480.0);
    }
    f.instances = objects;
    f.tracked = uniform(0, 99) < 3 ? uniform(0, 60) : uniform(80, 400);
    // Close points: unmeasured now and then; mostly steady, sometimes collapsing as in a fast turn.
    if (uniform(0, 99) >= 5) {
      f.tracked_close = uniform(0, 99) < 6 ? uniform(0, 40) : uniform(60, 250);
      f.untracked_close = uniform(0, 300);
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

struct OracleFeatures {
  std::int64_t id;
  cge::PatchHistogram z;
  P dense;
  std::optional<P> centroid;
  int num;
  bool has_features;
  int tracked_close;
};

OracleFeatures oracle_features(const RawFrame& f, const Grid& g, int num_dense) {
  OracleFeatures o;
  o.id = f.id;
  const std::vector<int> counts = brute_counts(g, f.keypoints);
  o.z = spec_histogram(counts);
  o.dense = rank_dense_mean(g, counts, num_dense);
  if (!f.instances.empty()) {
    P sum = P::Zero();
    for (const P& c : f.instances) sum += c;
    o.centroid = P(sum / static_cast<double>(f.instances.size()));
  }
  o.num = static_cast<int>(f.instances.size());
  o.has_features = !f.keypoints.empty();
  o.tracked_close = f.tracked_close;
  return o;
}

struct OracleStep {
  Rule rule = Rule::none;
  std::int64_t keyframe_id = cge::kNoFrame;
};

/// The method written as an offline loop over intervals (one per iteration), from the spec and the
/// documented resolutions: an immediate insertion ends the interval and the next one starts right
/// after it; an interval of k frames ends with its best candidate. Returns one entry per frame
/// plus one for the final flush.
std::vector<OracleStep> oracle_run(const std::vector<RawFrame>& frames, const Settings& s) {
  const Grid g = make_grid(make_image(640, 480), s.patch_cols, s.patch_rows);
  const std::size_t n = frames.size();
  const std::size_t k = static_cast<std::size_t>(s.interval_frames);
  std::vector<OracleStep> out(n + 1);
  if (n == 0) return out;
  OracleFeatures ref = oracle_features(frames[0], g, s.num_dense);
  out[0] = {Rule::first_frame, frames[0].id};
  std::size_t start = 1;
  int held = 0;  // consecutive frames the semantic change has held against ref
  while (start < n) {
    std::vector<std::pair<double, OracleFeatures>> candidates;  // (D_sum, features), in order
    std::size_t next_start = std::min(start + k, n);
    for (std::size_t j = start; j < std::min(start + k, n); ++j) {
      const OracleFeatures cur = oracle_features(frames[j], g, s.num_dense);
      const double s_cos = spec_cosine(cur.z, ref.z);
      const double d_fp = (cur.dense - ref.dense).norm();
      const bool semantic = cur.centroid && ref.centroid;
      const double d_sum = semantic ? s.rho * d_fp + (1 - s.rho) * (*cur.centroid - *ref.centroid).norm() : d_fp;
      const bool candidate = cur.has_features && (!s.use_candidate_test || s_cos < s.cosine_threshold);
      const bool changed = s.use_semantic_change && std::abs(cur.num - ref.num) >= s.instance_change_threshold;
      held = changed ? held + 1 : 0;
      Rule immediate = Rule::none;
      if (s.use_tracking_guard && frames[j].tracked < s.tracking_floor) {
        immediate = Rule::tracking_guard;
      } else if (s.use_coverage_guard && frames[j].tracked_close >= 0 &&
                 frames[j].untracked_close > s.coverage_min_untracked_close &&
                 frames[j].tracked_close < s.coverage_ratio * (frames[j].tracked_close + frames[j].untracked_close)) {
        immediate = Rule::coverage_guard;
      } else if (changed && held >= s.semantic_change_frames) {
        immediate = Rule::semantic_change;
      } else if (s.use_large_motion && candidate && d_sum > s.motion_threshold_px) {
        immediate = Rule::large_motion;
      }
      if (immediate != Rule::none) {
        out[j] = {immediate, cur.id};
        ref = cur;
        held = 0;
        candidates.clear();
        next_start = j + 1;
        break;
      }
      if (candidate && s.use_interval_best) candidates.emplace_back(d_sum, cur);
    }
    if (!candidates.empty()) {
      std::size_t best = 0;
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (candidates[i].first > candidates[best].first) best = i;
      }
      // A complete interval decides on its last frame; a partial one at the end of the sequence on the flush.
      const std::size_t where = next_start == start + k ? start + k - 1 : n;
      out[where] = {Rule::interval_best_candidate, candidates[best].second.id};
      ref = candidates[best].second;
      held = 0;
    }
    start = next_start;
  }
  return out;
}

std::vector<Decision> run(Selector& sel, const std::vector<RawFrame>& frames) {
  std::vector<Decision> out;
  for (const RawFrame& f : frames) {
    Summary s = sel.summarise(
        f.id, make_image(640, 480), f.keypoints,
        [&] {
          std::vector<cge::SemanticInstance<double>> inst(f.instances.size());
          for (std::size_t i = 0; i < inst.size(); ++i) {
            inst[i].centre_px = f.instances[i];
            inst[i].dynamic = true;  // counted under either setting of dynamic_instances_only, as the oracle does
          }
          return inst;
        }(),
        f.tracked);
    s.tracked_close_points = f.tracked_close;
    s.untracked_close_points = f.untracked_close;
    out.push_back(sel.step(s));
  }
  out.push_back(sel.flush());
  return out;
}

bool same_decision(const Decision& a, const Decision& b) {
  const auto& x = a.measures;
  const auto& y = b.measures;
  return a.frame_id == b.frame_id && a.rule == b.rule && a.keyframe_id == b.keyframe_id &&
         a.keep_current == b.keep_current && x.patch_measures == y.patch_measures && x.s_cos == y.s_cos &&
         x.d_fp == y.d_fp && x.d_se == y.d_se && x.d_sum == y.d_sum && x.semantic_term == y.semantic_term &&
         x.candidate == y.candidate && x.interval_position == y.interval_position &&
         x.instance_count == y.instance_count && x.reference_instance_count == y.reference_instance_count &&
         x.tracked_points == y.tracked_points && x.reference_tracked_points == y.reference_tracked_points &&
         x.frames_since_reference == y.frames_since_reference && x.tracked_close_points == y.tracked_close_points &&
         x.untracked_close_points == y.untracked_close_points &&
         x.reference_tracked_close_points == y.reference_tracked_close_points;
}

}  // namespace

TEST_CASE("selector matches an offline reference implementation on random sequences", "[keyframe][oracle]") {
  int fired[16] = {};
  for (std::uint32_t seed = 1; seed <= 12; ++seed) {
    const std::vector<RawFrame> frames = random_sequence(seed, 150);
    Settings s;  // defaults: 10 x 10 grid, k = 10
    s.interval_frames = 1 + static_cast<int>(seed % 12);
    s.use_large_motion = seed % 5 != 0;
    s.use_semantic_change = seed % 7 != 0;
    s.use_candidate_test = seed % 11 != 0;
    s.semantic_change_frames = 1 + static_cast<int>(seed % 3);
    s.use_coverage_guard = seed % 4 != 0;
    Selector sel(s);
    const std::vector<Decision> got = run(sel, frames);
    const std::vector<OracleStep> expected = oracle_run(frames, s);
    REQUIRE(got.size() == expected.size());
    std::int64_t last_keyframe = cge::kNoFrame;
    Selector replay(s);
    for (std::size_t i = 0; i < got.size(); ++i) {
      INFO("seed " << seed << ", step " << i);
      REQUIRE(got[i].rule == expected[i].rule);
      REQUIRE(got[i].keyframe_id == expected[i].keyframe_id);
      ++fired[static_cast<int>(got[i].rule)];
      if (got[i].inserts_keyframe()) {
        REQUIRE(got[i].keyframe_id > last_keyframe);  // keyframes in temporal order
        last_keyframe = got[i].keyframe_id;
      }
    }
    // Pending frames stay within the current interval and keep_current tells the host about them.
    for (const RawFrame& f : frames) {
      Summary sum;
      sum.frame_id = f.id;
      sum.grid = replay.grid(make_image(640, 480));
      sum.patch_counts = brute_counts(sum.grid, f.keypoints);
      sum.instance_centres_px = f.instances;
      sum.tracked_points = f.tracked;
      sum.tracked_close_points = f.tracked_close;
      sum.untracked_close_points = f.untracked_close;
      const Decision d = replay.step(sum);
      const std::vector<std::int64_t> pending = replay.pending_ids();
      REQUIRE(pending.size() <= static_cast<std::size_t>(s.interval_frames - 1));
      REQUIRE(static_cast<int>(pending.size()) <= replay.interval_position());
      REQUIRE(d.keep_current == (!pending.empty() && pending.back() == f.id));
    }
  }
  // Every rule of the method fired somewhere, so the comparison above was not vacuous.
  for (const Rule r : {Rule::first_frame, Rule::tracking_guard, Rule::coverage_guard, Rule::semantic_change,
                       Rule::large_motion, Rule::interval_best_candidate, Rule::none}) {
    INFO(cge::to_string(r));
    REQUIRE(fired[static_cast<int>(r)] > 0);
  }
}

TEST_CASE("selector is deterministic; a copy continues exactly like the original", "[keyframe][determinism]") {
  const std::vector<RawFrame> frames = random_sequence(42, 120);
  Selector a, b;
  const std::vector<Decision> da = run(a, frames);
  const std::vector<Decision> db = run(b, frames);
  REQUIRE(da.size() == db.size());
  for (std::size_t i = 0; i < da.size(); ++i) REQUIRE(same_decision(da[i], db[i]));

  const std::vector<RawFrame> first(frames.begin(), frames.begin() + 57);
  const std::vector<RawFrame> rest(frames.begin() + 57, frames.end());
  Selector c;
  for (const RawFrame& f : first) {
    Summary s =
        c.summarise(f.id, make_image(640, 480), f.keypoints, std::vector<cge::SemanticInstance<double>>{}, f.tracked);
    s.instance_centres_px = f.instances;
    s.tracked_close_points = f.tracked_close;
    s.untracked_close_points = f.untracked_close;
    c.step(s);
  }
  Selector copy = c;
  const std::vector<Decision> dc = run(c, rest);
  const std::vector<Decision> dcopy = run(copy, rest);
  for (std::size_t i = 0; i < dc.size(); ++i) REQUIRE(same_decision(dc[i], dcopy[i]));
  // ... and like the uninterrupted run.
  for (std::size_t i = 0; i < dc.size(); ++i) REQUIRE(same_decision(dc[i], da[57 + i]));
}

// =============================================================================================
// ORB-SLAM2 baseline
// =============================================================================================

namespace {
Summary tracked(std::int64_t id, int points) {
  Summary s;
  s.frame_id = id;
  s.tracked_points = points;
  return s;  // no patch counts: the baseline does not read them
}
/// The baseline with one ratio throughout and a keyframe at least every max_gap frames (the
/// monocular ratio and our max-gap extension), which the tests below use to isolate each rule.
OrbSettings orb_settings(int max_gap = 1000) {
  OrbSettings s;
  s.max_frame_gap = max_gap;
  s.reference_ratio = 0.9;
  s.first_reference_ratio = 0.9;
  s.use_max_frame_gap = true;
  return s;
}
Summary tracked_close(std::int64_t id, int points, int close_tracked, int close_untracked) {
  Summary s = tracked(id, points);
  s.tracked_close_points = close_tracked;
  s.untracked_close_points = close_untracked;
  return s;
}
}  // namespace

TEST_CASE("ORB-SLAM2 baseline: tracked points under 90% of the reference keyframe's", "[keyframe][orbslam2]") {
  Orb orb(orb_settings());
  require_insert(orb.step(tracked(0, 200)), Rule::first_frame, 0);
  require_none(orb.step(tracked(1, 200)));
  require_none(orb.step(tracked(2, 181)));  // 181 >= 180
  const Decision d = orb.step(tracked(3, 170));
  require_insert(d, Rule::tracked_ratio, 3);
  REQUIRE(d.measures.tracked_points == 170);
  REQUIRE(d.measures.reference_tracked_points == 200);
  REQUIRE(d.measures.frames_since_reference == 3);
  REQUIRE_FALSE(d.measures.patch_measures);
  // The new reference holds 170: 153 = 0.9 x 170 is the new line.
  require_none(orb.step(tracked(4, 160)));
  require_insert(orb.step(tracked(5, 152)), Rule::tracked_ratio, 5);
  REQUIRE(orb.pending_ids().empty());
  REQUIRE_FALSE(orb.step(tracked(6, 152)).keep_current);
}

TEST_CASE("ORB-SLAM2 baseline: the RGB-D defaults (0.4 with one keyframe, then 0.75, no max-gap insertion)",
          "[keyframe][orbslam2]") {
  OrbSettings defaults;
  REQUIRE(defaults.reference_ratio == 0.75);
  REQUIRE(defaults.first_reference_ratio == 0.4);
  REQUIRE(defaults.max_frame_gap == 30);
  REQUIRE(defaults.min_tracked_points == 15);
  REQUIRE_FALSE(defaults.use_max_frame_gap);
  Orb orb(defaults);
  require_insert(orb.step(tracked(0, 0)), Rule::first_frame, 0);
  orb.set_reference_tracked_points(400);
  // One keyframe in the map: the line is 0.4 x 400 = 160.
  require_none(orb.step(tracked(1, 160)));
  require_insert(orb.step(tracked(2, 159)), Rule::tracked_ratio, 2);
  orb.set_reference_tracked_points(200);
  // Two keyframes: 0.75 x 200 = 150.
  require_none(orb.step(tracked(3, 150)));
  require_insert(orb.step(tracked(4, 149)), Rule::tracked_ratio, 4);
  orb.set_reference_tracked_points(200);
  // c1a alone never inserts: 100 frames with every point tracked.
  for (std::int64_t i = 5; i < 105; ++i) require_none(orb.step(tracked(i, 200)));
}

TEST_CASE("ORB-SLAM2 baseline: the close-point rule", "[keyframe][orbslam2]") {
  Orb orb{OrbSettings{}};
  orb.step(tracked(0, 0));
  orb.set_reference_tracked_points(200);
  // Tracking is fine by the ratio (190 of 200), but few close points are tracked and many are not.
  require_insert(orb.step(tracked_close(1, 190, 99, 71)), Rule::close_points, 1);
  orb.set_reference_tracked_points(200);
  require_none(orb.step(tracked_close(2, 190, 100, 71)));  // 100 tracked close points: enough
  require_none(orb.step(tracked_close(3, 190, 99, 70)));   // 70 untracked: not more than 70
  require_none(orb.step(tracked_close(4, 190, -1, -1)));   // not counted: the rule is off
  require_none(orb.step(tracked_close(5, 15, 0, 500)));    // c2 needs more than 15 tracked points
  OrbSettings off;
  off.use_close_points = false;
  Orb without(off);
  without.step(tracked(0, 0));
  without.set_reference_tracked_points(200);
  require_none(without.step(tracked_close(1, 190, 0, 500)));
}

TEST_CASE("ORB-SLAM2 baseline: the ratio boundary is strict", "[keyframe][orbslam2]") {
  OrbSettings s = orb_settings();
  s.reference_ratio = 0.5;  // exact in binary
  s.first_reference_ratio = 0.5;
  Orb orb(s);
  orb.step(tracked(0, 200));
  require_none(orb.step(tracked(1, 100)));
  require_insert(orb.step(tracked(2, 99)), Rule::tracked_ratio, 2);
}

TEST_CASE("ORB-SLAM2 baseline: nothing is inserted with 15 or fewer tracked points", "[keyframe][orbslam2]") {
  Orb orb(orb_settings(3));
  orb.step(tracked(0, 200));
  require_none(orb.step(tracked(1, 15)));
  require_none(orb.step(tracked(2, 0)));
  require_none(orb.step(tracked(3, 15)));  // max gap reached, still too few
  require_insert(orb.step(tracked(4, 16)), Rule::tracked_ratio, 4);
}

TEST_CASE("ORB-SLAM2 baseline: min and max frame gaps", "[keyframe][orbslam2]") {
  SECTION("min gap delays the ratio rule") {
    OrbSettings s = orb_settings();
    s.min_frame_gap = 3;
    Orb orb(s);
    orb.step(tracked(0, 200));
    require_none(orb.step(tracked(1, 100)));
    require_none(orb.step(tracked(2, 100)));
    require_insert(orb.step(tracked(3, 100)), Rule::tracked_ratio, 3);
  }
  SECTION("max gap inserts every max_frame_gap frames, counted in frames not ids") {
    Orb orb(orb_settings(5));
    orb.step(tracked(0, 200));
    std::vector<std::int64_t> keyframes;
    for (std::int64_t i = 1; i <= 12; ++i) {
      const Decision d = orb.step(tracked(10 * i, 200));  // ids with gaps
      if (d.inserts_keyframe()) {
        REQUIRE(d.rule == Rule::max_frame_gap);
        REQUIRE(d.measures.frames_since_reference == 5);
        keyframes.push_back(d.keyframe_id);
      }
    }
    REQUIRE(keyframes == std::vector<std::int64_t>{50, 100});
  }
  SECTION("switched off") {
    OrbSettings s = orb_settings(2);
    s.use_max_frame_gap = false;
    s.use_tracked_ratio = false;
    Orb orb(s);
    orb.step(tracked(0, 200));
    for (std::int64_t i = 1; i <= 6; ++i) require_none(orb.step(tracked(i, 20)));
  }
}

TEST_CASE("ORB-SLAM2 baseline: the host sets the reference keyframe's map points", "[keyframe][orbslam2]") {
  Orb orb(orb_settings());
  REQUIRE_THROWS_AS(orb.set_reference_tracked_points(1), std::logic_error);
  orb.step(tracked(0, 0));  // the first frame tracks nothing: the ratio rule cannot fire
  require_none(orb.step(tracked(1, 300)));
  orb.set_reference_tracked_points(400);  // the map points created with the first keyframe
  const Decision d = orb.step(tracked(2, 300));
  require_insert(d, Rule::tracked_ratio, 2);
  REQUIRE(d.measures.reference_tracked_points == 400);
}

TEST_CASE("ORB-SLAM2 baseline: errors, flush and reset", "[keyframe][orbslam2][errors]") {
  Orb orb(orb_settings());
  orb.step(tracked(5, 200));
  REQUIRE(invalid_argument_message([&] { orb.step(tracked(5, 100)); }).find("increase") != std::string::npos);
  REQUIRE(invalid_argument_message([&] { orb.step(tracked(6, -1)); }).find("tracked_points") != std::string::npos);
  require_insert(orb.step(tracked(6, 100)), Rule::tracked_ratio, 6);  // unchanged by the failed steps
  require_none(orb.flush());
  orb.reset();
  REQUIRE(orb.reference_id() == cge::kNoFrame);
  require_insert(orb.step(tracked(0, 10)), Rule::first_frame, 0);
  auto message = [](void (*edit)(OrbSettings&)) {
    OrbSettings s;
    edit(s);
    Orb o(s);
    return invalid_argument_message([&] { o.step(tracked(0, 1)); });
  };
  REQUIRE(message([](OrbSettings& s) { s.reference_ratio = 0; }).find("reference_ratio") != std::string::npos);
  REQUIRE(message([](OrbSettings& s) { s.reference_ratio = 1.1; }).find("reference_ratio") != std::string::npos);
  REQUIRE(message([](OrbSettings& s) { s.min_frame_gap = -1; }).find("min_frame_gap") != std::string::npos);
  REQUIRE(message([](OrbSettings& s) { s.max_frame_gap = 0; }).find("max_frame_gap") != std::string::npos);
  REQUIRE(message([](OrbSettings& s) { s.min_tracked_points = -1; }).find("min_tracked_points") != std::string::npos);
}

// =============================================================================================
// Run-time choice between the policies
// =============================================================================================

TEST_CASE("KeyframePolicy forwards to the policy a setting names", "[keyframe][policy]") {
  REQUIRE(cge::parse_keyframe_policy_kind("patch") == cge::KeyframePolicyKind::patch);
  REQUIRE(cge::parse_keyframe_policy_kind("orbslam2") == cge::KeyframePolicyKind::orbslam2);
  REQUIRE(std::string(cge::to_string(cge::KeyframePolicyKind::orbslam2)) == "orbslam2");
  REQUIRE(invalid_argument_message([] { cge::parse_keyframe_policy_kind("orb"); }).find("'patch' or 'orbslam2'") !=
          std::string::npos);
  REQUIRE(cge::KeyframePolicy<double>().kind() == cge::KeyframePolicyKind::patch);

  const std::vector<RawFrame> frames = random_sequence(3, 80);
  for (const auto kind : {cge::KeyframePolicyKind::patch, cge::KeyframePolicyKind::orbslam2}) {
    Settings ps;
    ps.interval_frames = 5;
    OrbSettings os;
    os.max_frame_gap = 7;
    cge::KeyframePolicy<double> policy(kind, ps, os);
    REQUIRE(policy.kind() == kind);
    Selector direct_patch(ps);
    Orb direct_orb(os);
    for (const RawFrame& f : frames) {
      Summary s;
      s.frame_id = f.id;
      s.grid = direct_patch.grid(make_image(640, 480));
      s.patch_counts = cge::count_patch_features(s.grid, f.keypoints);
      s.instance_centres_px = f.instances;
      s.tracked_points = f.tracked;
      const Decision got = policy.step(s);
      const Decision want = kind == cge::KeyframePolicyKind::patch ? direct_patch.step(s) : direct_orb.step(s);
      REQUIRE(same_decision(got, want));
      const std::vector<std::int64_t> want_pending =
          kind == cge::KeyframePolicyKind::patch ? direct_patch.pending_ids() : direct_orb.pending_ids();
      REQUIRE(policy.pending_ids() == want_pending);
    }
    const std::int64_t want_reference =
        kind == cge::KeyframePolicyKind::patch ? direct_patch.reference_id() : direct_orb.reference_id();
    REQUIRE(policy.reference_id() == want_reference);
    policy.set_reference_tracked_points(77);
    policy.flush();
    policy.reset();
    REQUIRE(policy.reference_id() == cge::kNoFrame);
  }
  // The rule names are distinct (they go into logs).
  std::vector<std::string> names;
  for (int r = 0; r <= static_cast<int>(Rule::close_points); ++r)
    names.push_back(cge::to_string(static_cast<Rule>(r)));
  std::sort(names.begin(), names.end());
  REQUIRE(std::adjacent_find(names.begin(), names.end()) == names.end());
}
