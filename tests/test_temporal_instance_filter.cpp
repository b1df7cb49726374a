// Tests of TemporalInstanceFilter on hand-made instance sequences: a scripted segmenter hands the
// filter a list of instances per frame, and the expected output of every frame is written down
// from the rule (detected in N of the last M frames; people at once), or computed by a direct
// count over presence patterns where the association is unambiguous.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/segmentation/temporal_instance_filter.hpp"
#include "test_support.hpp"

using Catch::Matchers::Contains;
using cge::SegmentedInstance;
using cge::TemporalInstanceFilter;
using cge::TemporalInstanceFilterSettings;
using cge::TemporalOverlap;
using cge_test::invalid_argument_message;

namespace {

const cv::Size kImage(64, 48);
constexpr int kChair = 56;
constexpr int kTv = 62;

SegmentedInstance rect_instance(int class_id, cv::Rect r, float score = 0.9f) {
  SegmentedInstance s;
  s.id = 1;
  s.class_id = class_id;
  s.score = score;
  s.dynamic = class_id == cge::kCocoPerson;
  s.box_px = cv::Rect2f(static_cast<float>(r.x), static_cast<float>(r.y), static_cast<float>(r.width),
                        static_cast<float>(r.height));
  s.mask = cv::Mat(kImage, CV_8UC1, cv::Scalar(0));
  s.mask(r).setTo(255);
  return s;
}

/// Returns the scripted instances of frame i on its i-th call (ids numbered 1, 2, ... per frame),
/// no instances after the script ends.
class ScriptedSegmenter final : public cge::InstanceSegmenter {
 public:
  explicit ScriptedSegmenter(std::vector<std::vector<SegmentedInstance>> frames) : frames_(std::move(frames)) {}
  std::vector<SegmentedInstance> segment(const cge::FrameImage&) override {
    if (next_ >= frames_.size()) return {};
    std::vector<SegmentedInstance> out;
    for (const SegmentedInstance& s : frames_[next_]) {
      out.push_back(s);
      out.back().mask = s.mask.clone();
      out.back().id = static_cast<int>(out.size());
    }
    ++next_;
    return out;
  }
  void set_dynamic_classes(const std::set<int>& ids) override { dynamic_ = ids; }
  const std::set<int>& dynamic_classes() const override { return dynamic_; }

 private:
  std::vector<std::vector<SegmentedInstance>> frames_;
  std::size_t next_ = 0;
  std::set<int> dynamic_ = {cge::kCocoPerson};
};

TemporalInstanceFilterSettings n_of_m(int n, int m, TemporalOverlap overlap = TemporalOverlap::box) {
  TemporalInstanceFilterSettings s;
  s.min_frames_seen = n;
  s.window_frames = m;
  s.overlap = overlap;
  return s;
}

/// The filter's output for every frame of the script.
std::vector<std::vector<SegmentedInstance>> run(const std::vector<std::vector<SegmentedInstance>>& script,
                                                const TemporalInstanceFilterSettings& settings, int extra_frames = 0,
                                                std::vector<cge::TemporalFilterFrameCounts>* counts = nullptr) {
  TemporalInstanceFilter filter(std::make_unique<ScriptedSegmenter>(script), settings);
  const cv::Mat image(kImage, CV_8UC3, cv::Scalar::all(0));
  std::vector<std::vector<SegmentedInstance>> out;
  for (std::size_t i = 0; i < script.size() + static_cast<std::size_t>(extra_frames); ++i) {
    out.push_back(filter.segment({image, std::to_string(i)}));
    if (counts) counts->push_back(filter.last_counts());
  }
  return out;
}

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

void check_ids_are_ranks(const std::vector<SegmentedInstance>& frame) {
  for (std::size_t i = 0; i < frame.size(); ++i) CHECK(frame[i].id == static_cast<int>(i) + 1);
}

}  // namespace

TEST_CASE("TemporalInstanceFilter: a static object appears, drops out for one frame, reappears, leaves",
          "[segmentation][temporal_filter]") {
  // The monitor moves one pixel a frame (the camera's motion); absent in frames 2 and 5 .. 8.
  const auto tv = [](int frame) { return rect_instance(kTv, cv::Rect(10 + frame, 10, 20, 14)); };
  const std::vector<std::vector<SegmentedInstance>> script = {{tv(0)}, {tv(1)}, {}, {tv(3)}, {tv(4)}, {}, {}, {}, {}};
  std::vector<cge::TemporalFilterFrameCounts> counts;
  const auto out = run(script, n_of_m(2, 3), 0, &counts);

  // Frame 0: seen 1 of 1 -> held back. 1: 2 of 2 -> passed. 2: a dropout, 2 of 3 -> passed as its
  // last detection (frame 1's). 3, 4: passed. 5: frames 3, 4 -> 2 of 3, held; 6: frame 4 only -> 1
  // of 3, not passed.
  const std::vector<std::size_t> expected_sizes = {0, 1, 1, 1, 1, 1, 0, 0, 0};
  REQUIRE(out.size() == expected_sizes.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    CAPTURE(i);
    CHECK(out[i].size() == expected_sizes[i]);
    check_ids_are_ranks(out[i]);
  }
  CHECK(counts[0].suppressed == 1);
  CHECK(counts[0].detected == 1);
  CHECK(counts[0].passed == 0);
  CHECK(same_pixels(out[1][0].mask, tv(1).mask));
  CHECK(out[1][0].box_px == tv(1).box_px);
  // The dropout frame carries frame 1's detection.
  CHECK(counts[2].held == 1);
  CHECK(same_pixels(out[2][0].mask, tv(1).mask));
  CHECK(out[2][0].box_px == tv(1).box_px);
  CHECK(out[2][0].class_id == kTv);
  CHECK_FALSE(out[2][0].dynamic);
  CHECK(same_pixels(out[3][0].mask, tv(3).mask));
  CHECK(counts[3].held == 0);
  CHECK(same_pixels(out[5][0].mask, tv(4).mask));
  CHECK(counts[5].held == 1);
}

TEST_CASE("TemporalInstanceFilter: the track is forgotten after M frames without a detection",
          "[segmentation][temporal_filter]") {
  const SegmentedInstance chair = rect_instance(kChair, cv::Rect(5, 5, 10, 10));
  TemporalInstanceFilter filter(
      std::make_unique<ScriptedSegmenter>(std::vector<std::vector<SegmentedInstance>>{{chair}, {}, {}, {}, {chair}}),
      n_of_m(2, 3));
  const cv::Mat image(kImage, CV_8UC3, cv::Scalar::all(0));
  const std::vector<int> tracks = {1, 1, 1, 0, 1};
  const std::vector<std::size_t> passed = {0, 0, 0, 0, 0};  // frame 4 starts a new track: 1 of 1
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    CAPTURE(i);
    CHECK(filter.segment({image, "f"}).size() == passed[i]);
    CHECK(filter.track_count() == tracks[i]);
  }
}

TEST_CASE("TemporalInstanceFilter: a frame of another size forgets the tracks", "[segmentation][temporal_filter]") {
  const SegmentedInstance chair = rect_instance(kChair, cv::Rect(5, 5, 10, 10));
  TemporalInstanceFilter filter(
      std::make_unique<ScriptedSegmenter>(std::vector<std::vector<SegmentedInstance>>{{chair}, {chair}, {}, {}}),
      n_of_m(2, 3));
  const cv::Mat image(kImage, CV_8UC3, cv::Scalar::all(0));
  CHECK(filter.segment({image, "0"}).empty());
  CHECK(filter.segment({image, "1"}).size() == 1);
  CHECK(filter.segment({image, "2"}).size() == 1);  // held
  CHECK(filter.track_count() == 1);
  const cv::Mat other(kImage.height + 1, kImage.width, CV_8UC3, cv::Scalar::all(0));
  CHECK(filter.segment({other, "3"}).empty());  // no mask of the old size is held into it
  CHECK(filter.track_count() == 0);
}

TEST_CASE("TemporalInstanceFilter: two instances of one class keep their identities",
          "[segmentation][temporal_filter]") {
  // Two chairs side by side moving right; the left one is missed in frame 2, the right one in 3.
  const auto left = [](int f) { return rect_instance(kChair, cv::Rect(2 + f, 20, 14, 14)); };
  const auto right = [](int f) { return rect_instance(kChair, cv::Rect(30 + f, 20, 14, 14)); };
  const std::vector<std::vector<SegmentedInstance>> script = {
      {left(0), right(0)}, {right(1), left(1)}, {right(2)}, {left(3)}, {left(4), right(4)}};
  std::vector<cge::TemporalFilterFrameCounts> counts;
  const auto out = run(script, n_of_m(2, 3), 0, &counts);
  REQUIRE(out[0].empty());
  // Frame 1: both passed, in the segmenter's order.
  REQUIRE(out[1].size() == 2);
  CHECK(out[1][0].box_px == right(1).box_px);
  CHECK(out[1][1].box_px == left(1).box_px);
  // Frame 2: the right one detected, the left one held at its frame-1 place.
  REQUIRE(out[2].size() == 2);
  CHECK(out[2][0].box_px == right(2).box_px);
  CHECK(out[2][1].box_px == left(1).box_px);
  CHECK(counts[2].held == 1);
  // Frame 3: the left one (its track last seen in frame 1, two pixels away) detected, the right held.
  REQUIRE(out[3].size() == 2);
  CHECK(out[3][0].box_px == left(3).box_px);
  CHECK(out[3][1].box_px == right(2).box_px);
  // Frame 4: both detected; no new track was started on the way.
  REQUIRE(out[4].size() == 2);
  CHECK(counts[4].held == 0);
  CHECK(counts[4].suppressed == 0);
  for (const auto& frame : out) check_ids_are_ranks(frame);
}

TEST_CASE("TemporalInstanceFilter: greedy association takes the best IoU first", "[segmentation][temporal_filter]") {
  // Tracks A (x 0..20) and B (x 8..28); detections D0 (x 7..27) and D1 (x 0..9), boxes 10 high.
  // IoU: A-D0 130/270 = 0.48, A-D1 90/200 = 0.45, B-D0 190/210 = 0.90, B-D1 10/280 = 0.04.
  // Best first: B-D0, then A-D1: both continue a track and pass with N = M = 2. (Taking the
  // tracks in order instead would give A-D0 and leave D1 a new object, held back.)
  const SegmentedInstance a = rect_instance(kChair, cv::Rect(0, 0, 20, 10));
  const SegmentedInstance b = rect_instance(kChair, cv::Rect(8, 0, 20, 10));
  const SegmentedInstance d0 = rect_instance(kChair, cv::Rect(7, 0, 20, 10));
  const SegmentedInstance d1 = rect_instance(kChair, cv::Rect(0, 0, 9, 10));
  CHECK(cge::detail::box_iou(a.box_px, d0.box_px) == Approx(130.0 / 270));
  CHECK(cge::detail::box_iou(a.box_px, d1.box_px) == Approx(90.0 / 200));
  CHECK(cge::detail::box_iou(b.box_px, d0.box_px) == Approx(190.0 / 210));
  std::vector<cge::TemporalFilterFrameCounts> counts;
  const auto out = run({{a, b}, {d0, d1}}, n_of_m(2, 2), 0, &counts);
  CHECK(out[0].empty());
  REQUIRE(out[1].size() == 2);
  CHECK(out[1][0].box_px == d0.box_px);
  CHECK(out[1][1].box_px == d1.box_px);
  CHECK(counts[1].suppressed == 0);
  CHECK(counts[1].held == 0);
}

TEST_CASE("TemporalInstanceFilter: other classes and small overlaps are other objects",
          "[segmentation][temporal_filter]") {
  const SegmentedInstance chair = rect_instance(kChair, cv::Rect(10, 10, 20, 20));
  const SegmentedInstance tv_same_place = rect_instance(kTv, cv::Rect(10, 10, 20, 20));
  const SegmentedInstance chair_far = rect_instance(kChair, cv::Rect(26, 10, 20, 20));  // IoU 80/720 < 0.3
  std::vector<cge::TemporalFilterFrameCounts> counts;
  const auto out = run({{chair}, {tv_same_place}, {chair_far}}, n_of_m(1, 3), 0, &counts);
  CHECK(out[0].size() == 1);
  // Frame 1: the tv does not continue the chair's track: the tv, and the chair held.
  REQUIRE(out[1].size() == 2);
  CHECK(out[1][0].class_id == kTv);
  CHECK(out[1][1].class_id == kChair);
  CHECK(counts[1].held == 1);
  // Frame 2: the far chair is a new object: it, and both earlier objects held.
  REQUIRE(out[2].size() == 3);
  CHECK(out[2][0].box_px == chair_far.box_px);
  CHECK(out[2][1].box_px == chair.box_px);
  CHECK(out[2][2].class_id == kTv);
  CHECK(counts[2].held == 2);
}

TEST_CASE("TemporalInstanceFilter: a person passes at once, every frame it is detected, never held",
          "[segmentation][temporal_filter]") {
  const auto person = [](int f) { return rect_instance(cge::kCocoPerson, cv::Rect(5 + 3 * f, 5, 12, 30)); };
  const SegmentedInstance chair = rect_instance(kChair, cv::Rect(40, 20, 12, 12));
  const std::vector<std::vector<SegmentedInstance>> script = {{person(0), chair}, {}, {chair, person(2)}, {person(3)}};
  std::vector<cge::TemporalFilterFrameCounts> counts;
  const auto out = run(script, n_of_m(3, 3), 0, &counts);
  REQUIRE(out[0].size() == 1);
  CHECK(out[0][0].dynamic);
  CHECK(same_pixels(out[0][0].mask, person(0).mask));
  CHECK(out[1].empty());  // no person held over the dropout
  REQUIRE(out[2].size() == 1);
  CHECK(out[2][0].box_px == person(2).box_px);
  REQUIRE(out[3].size() == 1);
  CHECK(out[3][0].box_px == person(3).box_px);
  CHECK(counts[2].suppressed == 1);  // the chair: 2 of 3
}

TEST_CASE("TemporalInstanceFilter: N = M = 1 passes everything on unchanged but the ids",
          "[segmentation][temporal_filter]") {
  const std::vector<std::vector<SegmentedInstance>> script = {
      {rect_instance(kTv, cv::Rect(1, 1, 9, 9)), rect_instance(0, cv::Rect(20, 2, 9, 30))},
      {},
      {rect_instance(kChair, cv::Rect(30, 30, 9, 9))}};
  const auto out = run(script, n_of_m(1, 1));
  for (std::size_t f = 0; f < script.size(); ++f) {
    REQUIRE(out[f].size() == script[f].size());
    for (std::size_t i = 0; i < script[f].size(); ++i) {
      CHECK(out[f][i].class_id == script[f][i].class_id);
      CHECK(out[f][i].box_px == script[f][i].box_px);
      CHECK(same_pixels(out[f][i].mask, script[f][i].mask));
    }
  }
}

// The oracle: objects of different classes far apart, so each class is one object; the filter
// must pass class c in frame t exactly when c was present in at least N of frames t-M+1 .. t.
TEST_CASE("TemporalInstanceFilter: presence patterns against a direct window count",
          "[segmentation][temporal_filter]") {
  std::mt19937 engine(20251202);
  std::bernoulli_distribution present(0.6);
  const std::vector<int> classes = {kChair, kTv, 63, 66};  // chair, tv, laptop, keyboard
  constexpr int kFrames = 40;
  for (const std::pair<int, int>& n_m :
       std::vector<std::pair<int, int>>{{1, 1}, {1, 3}, {2, 3}, {3, 4}, {3, 5}, {4, 4}}) {
    const int n = n_m.first, m = n_m.second;
    CAPTURE(n, m);
    std::vector<std::vector<bool>> seen(classes.size(), std::vector<bool>(kFrames));
    std::vector<std::vector<SegmentedInstance>> script(kFrames);
    for (int t = 0; t < kFrames; ++t) {
      for (std::size_t c = 0; c < classes.size(); ++c) {
        seen[c][static_cast<std::size_t>(t)] = present(engine);
        if (seen[c][static_cast<std::size_t>(t)]) {
          script[static_cast<std::size_t>(t)].push_back(
              rect_instance(classes[c], cv::Rect(static_cast<int>(c) * 16, 10, 12, 12)));
        }
      }
    }
    const auto out = run(script, n_of_m(n, m));
    for (int t = 0; t < kFrames; ++t) {
      CAPTURE(t);
      std::set<int> expected, got;
      for (std::size_t c = 0; c < classes.size(); ++c) {
        int count = 0;
        for (int k = std::max(0, t - m + 1); k <= t; ++k) count += seen[c][static_cast<std::size_t>(k)];
        if (count >= n) expected.insert(classes[c]);
      }
      for (const SegmentedInstance& s : out[static_cast<std::size_t>(t)]) got.insert(s.class_id);
      CHECK(got == expected);
      CHECK(out[static_cast<std::size_t>(t)].size() == expected.size());
    }
  }
}

TEST_CASE("TemporalInstanceFilter: mask overlap against a pixel count, and where it differs from the box's",
          "[segmentation][temporal_filter]") {
  // Two L shapes whose boxes coincide but whose pixels barely touch.
  SegmentedInstance a = rect_instance(kChair, cv::Rect(10, 10, 20, 20));
  SegmentedInstance b = a;
  a.mask.setTo(0);
  b.mask = cv::Mat(kImage, CV_8UC1, cv::Scalar(0));
  a.mask(cv::Rect(10, 10, 20, 4)).setTo(255);  // top bar
  a.mask(cv::Rect(10, 10, 4, 20)).setTo(255);  // left bar
  b.mask(cv::Rect(10, 26, 20, 4)).setTo(255);  // bottom bar
  b.mask(cv::Rect(26, 10, 4, 20)).setTo(255);  // right bar
  int inter = 0, uni = 0;
  for (int y = 0; y < kImage.height; ++y) {
    for (int x = 0; x < kImage.width; ++x) {
      const bool in_a = a.mask.at<std::uint8_t>(y, x) != 0, in_b = b.mask.at<std::uint8_t>(y, x) != 0;
      inter += in_a && in_b;
      uni += in_a || in_b;
    }
  }
  const double expected = static_cast<double>(inter) / uni;
  CHECK(cge::detail::mask_iou(a.mask, cv::countNonZero(a.mask), a.box_px, b.mask, cv::countNonZero(b.mask), b.box_px) ==
        Approx(expected).epsilon(1e-12));
  CHECK(expected < 0.3);
  CHECK(cge::detail::box_iou(a.box_px, b.box_px) == 1.0);
  // Box overlap: one object seen twice -> passed in frame 1 with N = 2. Mask overlap: two objects.
  CHECK(run({{a}, {b}}, n_of_m(2, 2, TemporalOverlap::box))[1].size() == 1);
  CHECK(run({{a}, {b}}, n_of_m(2, 2, TemporalOverlap::mask))[1].empty());
}

TEST_CASE("TemporalInstanceFilter: deterministic, and its output masks are the caller's",
          "[segmentation][temporal_filter]") {
  std::mt19937 engine(7);
  std::uniform_int_distribution<int> coord(0, 40), side(4, 20), cls(55, 60), count(0, 4);
  std::vector<std::vector<SegmentedInstance>> script(30);
  for (auto& frame : script) {
    const int k = count(engine);
    for (int i = 0; i < k; ++i) {
      const int x = coord(engine), y = coord(engine) / 2;
      frame.push_back(rect_instance(cls(engine), cv::Rect(x, y, std::min(side(engine), 64 - x), 12)));
    }
  }
  const auto first = run(script, n_of_m(2, 4, TemporalOverlap::mask));
  const auto second = run(script, n_of_m(2, 4, TemporalOverlap::mask));
  REQUIRE(first.size() == second.size());
  for (std::size_t f = 0; f < first.size(); ++f) {
    REQUIRE(first[f].size() == second[f].size());
    for (std::size_t i = 0; i < first[f].size(); ++i) {
      CHECK(first[f][i].id == second[f][i].id);
      CHECK(first[f][i].class_id == second[f][i].class_id);
      CHECK(first[f][i].box_px == second[f][i].box_px);
      CHECK(same_pixels(first[f][i].mask, second[f][i].mask));
    }
  }
  // Writing a returned mask does not change what the filter holds.
  const SegmentedInstance tv = rect_instance(kTv, cv::Rect(10, 10, 10, 10));
  TemporalInstanceFilter filter(
      std::make_unique<ScriptedSegmenter>(std::vector<std::vector<SegmentedInstance>>{{tv}, {}}), n_of_m(1, 2));
  const cv::Mat image(kImage, CV_8UC3, cv::Scalar::all(0));
  std::vector<SegmentedInstance> f0 = filter.segment({image, "0"});
  REQUIRE(f0.size() == 1);
  f0[0].mask.setTo(0);
  const std::vector<SegmentedInstance> f1 = filter.segment({image, "1"});
  REQUIRE(f1.size() == 1);
  CHECK(same_pixels(f1[0].mask, tv.mask));
}

TEST_CASE("TemporalInstanceFilter: settings and input errors are named", "[segmentation][temporal_filter][errors]") {
  const auto make = [](const TemporalInstanceFilterSettings& s) {
    TemporalInstanceFilter f(std::make_unique<ScriptedSegmenter>(std::vector<std::vector<SegmentedInstance>>{}), s);
  };
  const TemporalInstanceFilterSettings defaults;  // measured on TUM fr1/rpy (docs/SEGMENTATION.md)
  CHECK(defaults.min_frames_seen == 3);
  CHECK(defaults.window_frames == 4);
  CHECK(defaults.min_iou == 0.3);
  CHECK(defaults.overlap == TemporalOverlap::box);
  CHECK_NOTHROW(defaults.validate());
  CHECK_THAT(invalid_argument_message([&] { make(n_of_m(1, 0)); }), Contains("window_frames"));
  CHECK_THAT(invalid_argument_message([&] { make(n_of_m(1, 65)); }), Contains("window_frames"));
  CHECK_THAT(invalid_argument_message([&] { make(n_of_m(0, 3)); }), Contains("min_frames_seen"));
  CHECK_THAT(invalid_argument_message([&] { make(n_of_m(4, 3)); }), Contains("min_frames_seen"));
  TemporalInstanceFilterSettings s;
  s.min_iou = 0;
  CHECK_THAT(invalid_argument_message([&] { make(s); }), Contains("min_iou"));
  s.min_iou = 1.5;
  CHECK_THAT(invalid_argument_message([&] { make(s); }), Contains("min_iou"));
  CHECK_NOTHROW(make(n_of_m(64, 64)));
  CHECK_THAT(invalid_argument_message([] { TemporalInstanceFilter f(nullptr, TemporalInstanceFilterSettings{}); }),
             Contains("null"));
  // A mask of the wrong size with mask overlap.
  SegmentedInstance bad = rect_instance(kChair, cv::Rect(0, 0, 4, 4));
  bad.mask = cv::Mat(10, 10, CV_8UC1, cv::Scalar(255));
  TemporalInstanceFilter f(std::make_unique<ScriptedSegmenter>(std::vector<std::vector<SegmentedInstance>>{{bad}}),
                           n_of_m(1, 1, TemporalOverlap::mask));
  const cv::Mat image(kImage, CV_8UC3, cv::Scalar::all(0));
  CHECK_THAT(invalid_argument_message([&] { f.segment({image, "0"}); }), Contains("mask"));
}

TEST_CASE("TemporalInstanceFilter: forwards the dynamic classes to the wrapped segmenter",
          "[segmentation][temporal_filter]") {
  auto inner = std::make_unique<ScriptedSegmenter>(std::vector<std::vector<SegmentedInstance>>{});
  const ScriptedSegmenter* raw = inner.get();
  TemporalInstanceFilter f(std::move(inner), TemporalInstanceFilterSettings{});
  f.set_dynamic_classes({0, 16});
  CHECK(raw->dynamic_classes() == std::set<int>{0, 16});
  CHECK(f.dynamic_classes() == std::set<int>{0, 16});
  CHECK(&f.inner() == raw);
}
