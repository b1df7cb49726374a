#pragma once
// TemporalInstanceFilter: an InstanceSegmenter decorator that steadies a network's static-class
// instances over consecutive frames. On real sequences YOLOv8-seg finds a monitor, a chair or a
// keyboard in one frame and misses it in the next; the patch keyframe rule (instance count,
// semantic centroid) and the CGE graph's semantic nodes follow that flicker (docs/SEGMENTATION.md,
// "Flicker of static objects", has the measurement).
//
// The rule, per frame (calls to segment() are taken as consecutive frames of one sequence):
// - Instances of dynamic classes (SegmentedInstance::dynamic, as the wrapped segmenter marks them)
//   pass on at once, unchanged, every frame they are detected: a person's mask never lags.
// - Instances of static classes are associated with the tracks of earlier frames: every pair of a
//   track and a detection of the same class whose overlap (IoU of masks or of boxes, see
//   TemporalOverlap) reaches min_iou is a candidate; candidates are taken greedily, highest IoU
//   first (ties: lower track index, then lower detection index), each track and detection once.
//   A track compares against its last detection, so it is found again after a dropout. A
//   detection left over starts a new track.
// - A track is passed on in a frame when it was detected in at least N (min_frames_seen) of the
//   last M (window_frames) frames, the current one included. A detected track passes on as its
//   current detection; a track passing on without a detection in this frame (a short dropout)
//   passes on as its last detection (mask, box, score). So a new object appears after N - 1
//   frames, a dropout of up to M - N frames is bridged, and an object gone for good is held for
//   M - N frames. A track detected in none of the last M frames is forgotten, and every track
//   when a frame's size differs from the previous frame's.
//
// Output order: the wrapped segmenter's detections that pass on, in its order, then the held
// tracks in the order the tracks were started; ids are renumbered 1, 2, ... in that order (ids are
// per frame, as the wrapped segmenters' ranks are). Deterministic: no randomness, fixed tie rules,
// the same frames in the same order give the same instances. Not thread-safe (it holds state).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/segmentation/instance_segmenter.hpp"

namespace cge {

/// What the association compares.
enum class TemporalOverlap {
  box,   ///< IoU of the boxes (box_px)
  mask,  ///< IoU of the masks (pixels set in both / pixels set in either)
};

/// "box" or "mask".
inline const char* to_string(TemporalOverlap overlap) { return overlap == TemporalOverlap::mask ? "mask" : "box"; }

struct TemporalInstanceFilterSettings {
  /// Largest window the filter supports (one bit per frame in a 64-bit history).
  static constexpr int kMaxWindowFrames = 64;

  /// M: frames in the window, the current one included, 1 .. kMaxWindowFrames. Default (ours, 3 of
  /// 4) measured on TUM fr1/rpy with yolov8n-seg-320 against 1/3, 2/3, 3/5, 4/5, 4/6 and 6/8: the
  /// lowest ATE of them and 70 keyframes instead of 126 unfiltered (docs/SEGMENTATION.md).
  int window_frames = 4;
  /// N: a static-class instance passes on when detected in at least N of the last M frames,
  /// 1 .. M. N = M = 1 passes everything on unchanged. Default: see window_frames.
  int min_frames_seen = 3;
  /// Least IoU, in (0, 1], for two detections of one class in consecutive frames to be one object
  /// (ours: 0.3; a static object moves by the camera's motion between frames, a few per cent of the
  /// image at 30 Hz, and its detections' boxes overlap far more than that).
  double min_iou = 0.3;
  /// What the IoU is taken of (box: cheap, the default; mask: per pixel).
  TemporalOverlap overlap = TemporalOverlap::box;

  /// Throws std::invalid_argument naming the first field outside its range.
  void validate() const {
    const auto fail = [](const std::string& what) {
      throw std::invalid_argument("TemporalInstanceFilterSettings: " + what);
    };
    if (window_frames < 1 || window_frames > kMaxWindowFrames) {
      fail("window_frames must lie in 1 .. " + std::to_string(kMaxWindowFrames) + ", got " +
           std::to_string(window_frames));
    }
    if (min_frames_seen < 1 || min_frames_seen > window_frames) {
      fail("min_frames_seen must lie in 1 .. window_frames (" + std::to_string(window_frames) + "), got " +
           std::to_string(min_frames_seen));
    }
    if (!(min_iou > 0 && min_iou <= 1)) fail("min_iou must lie in (0, 1], got " + std::to_string(min_iou));
  }
};

/// What the last segment() call did with the static-class instances.
struct TemporalFilterFrameCounts {
  int detected = 0;    ///< instances the wrapped segmenter returned (all classes)
  int suppressed = 0;  ///< static-class detections not passed on (seen in fewer than N of M frames)
  int held = 0;        ///< tracks passed on without a detection in this frame
  int passed = 0;      ///< instances returned
};

namespace detail {

/// IoU of two boxes; 0 when both are empty.
inline double box_iou(const cv::Rect2f& a, const cv::Rect2f& b) {
  const double inter = static_cast<double>((a & b).area());
  const double uni = static_cast<double>(a.area()) + static_cast<double>(b.area()) - inter;
  return uni > 0 ? inter / uni : 0.0;
}

/// IoU of two CV_8UC1 masks of one size, counted inside the union of their boxes (no pixel of
/// either mask lies outside its box); `area_a`, `area_b` are the masks' pixel counts.
inline double mask_iou(const cv::Mat& a, int area_a, const cv::Rect2f& box_a, const cv::Mat& b, int area_b,
                       const cv::Rect2f& box_b) {
  const cv::Rect image(0, 0, a.cols, a.rows);
  const auto whole = [](const cv::Rect2f& r) {
    const cv::Point tl(static_cast<int>(std::floor(r.x)), static_cast<int>(std::floor(r.y)));
    const cv::Point br(static_cast<int>(std::ceil(r.x + r.width)), static_cast<int>(std::ceil(r.y + r.height)));
    return cv::Rect(tl, br);
  };
  const cv::Rect roi = (whole(box_a) | whole(box_b)) & image;
  const int inter = roi.area() > 0 ? cv::countNonZero(a(roi) & b(roi)) : 0;
  const int uni = area_a + area_b - inter;
  return uni > 0 ? static_cast<double>(inter) / uni : 0.0;
}

}  // namespace detail

class TemporalInstanceFilter final : public InstanceSegmenter {
 public:
  /// Wraps `inner`. Throws std::invalid_argument for a null segmenter or invalid settings.
  TemporalInstanceFilter(std::unique_ptr<InstanceSegmenter> inner, const TemporalInstanceFilterSettings& settings)
      : inner_(std::move(inner)), settings_(settings) {
    if (inner_ == nullptr) throw std::invalid_argument("TemporalInstanceFilter: no segmenter to wrap (null)");
    settings_.validate();
  }

  std::vector<SegmentedInstance> segment(const FrameImage& frame) override {
    std::vector<SegmentedInstance> detections = inner_->segment(frame);
    // A frame of another size starts another sequence: a held mask would not fit it.
    if (frame.bgr.size() != image_size_) tracks_.clear();
    image_size_ = frame.bgr.size();
    counts_ = TemporalFilterFrameCounts{};
    counts_.detected = static_cast<int>(detections.size());
    for (Track& t : tracks_) t.history <<= 1;  // the new frame: not seen yet

    // Areas of the static detections' masks (mask overlap only).
    std::vector<int> areas(detections.size(), 0);
    if (settings_.overlap == TemporalOverlap::mask) {
      for (std::size_t d = 0; d < detections.size(); ++d) {
        if (!detections[d].dynamic) areas[d] = cv::countNonZero(checked_mask(detections[d], frame));
      }
    }
    // Candidate pairs, best IoU first; ties by track index, then detection index.
    std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      for (std::size_t d = 0; d < detections.size(); ++d) {
        const SegmentedInstance& det = detections[d];
        if (det.dynamic || det.class_id != tracks_[t].last.class_id) continue;
        const double iou = settings_.overlap == TemporalOverlap::mask
                               ? detail::mask_iou(tracks_[t].last.mask, tracks_[t].area, tracks_[t].last.box_px,
                                                  det.mask, areas[d], det.box_px)
                               : detail::box_iou(tracks_[t].last.box_px, det.box_px);
        if (iou >= settings_.min_iou) pairs.emplace_back(iou, t, d);
      }
    }
    std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
      if (std::get<0>(a) != std::get<0>(b)) return std::get<0>(a) > std::get<0>(b);
      if (std::get<1>(a) != std::get<1>(b)) return std::get<1>(a) < std::get<1>(b);
      return std::get<2>(a) < std::get<2>(b);
    });
    constexpr std::size_t kNone = static_cast<std::size_t>(-1);
    std::vector<std::size_t> track_of(detections.size(), kNone);
    std::vector<bool> track_taken(tracks_.size(), false);
    for (const auto& [iou, t, d] : pairs) {
      if (track_taken[t] || track_of[d] != kNone) continue;
      track_taken[t] = true;
      track_of[d] = t;
    }
    for (std::size_t d = 0; d < detections.size(); ++d) {
      if (detections[d].dynamic || track_of[d] != kNone) continue;
      track_of[d] = tracks_.size();
      tracks_.push_back(Track{});
      track_taken.push_back(true);
    }

    // Update the detected tracks, then decide what passes on.
    std::vector<SegmentedInstance> out;
    std::vector<bool> detected_now(tracks_.size(), false);
    for (std::size_t d = 0; d < detections.size(); ++d) {
      if (detections[d].dynamic) continue;
      Track& t = tracks_[track_of[d]];
      t.history |= 1u;
      t.last = detections[d];
      t.last.mask = detections[d].mask.clone();  // the caller owns the returned masks and may write them
      t.area = areas[d];
      detected_now[track_of[d]] = true;
    }
    for (std::size_t d = 0; d < detections.size(); ++d) {
      if (!detections[d].dynamic && !passes(tracks_[track_of[d]])) {
        ++counts_.suppressed;
        continue;
      }
      out.push_back(std::move(detections[d]));
    }
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      if (detected_now[t] || !passes(tracks_[t])) continue;
      out.push_back(tracks_[t].last);
      out.back().mask = tracks_[t].last.mask.clone();
      ++counts_.held;
    }
    // Forget the tracks detected in none of the last M frames.
    tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(), [this](const Track& t) { return seen(t) == 0; }),
                  tracks_.end());
    for (std::size_t i = 0; i < out.size(); ++i) out[i].id = static_cast<int>(i) + 1;
    counts_.passed = static_cast<int>(out.size());
    return out;
  }

  void set_dynamic_classes(const std::set<int>& class_ids) override { inner_->set_dynamic_classes(class_ids); }
  const std::set<int>& dynamic_classes() const override { return inner_->dynamic_classes(); }

  /// The wrapped segmenter.
  const InstanceSegmenter& inner() const { return *inner_; }
  /// Forgets every track (a new sequence starts).
  void reset() { tracks_.clear(); }
  const TemporalInstanceFilterSettings& settings() const { return settings_; }
  /// What the last segment() call did.
  const TemporalFilterFrameCounts& last_counts() const { return counts_; }
  /// The static-class objects tracked now.
  int track_count() const { return static_cast<int>(tracks_.size()); }

 private:
  struct Track {
    SegmentedInstance last;     ///< its last detection
    int area = 0;               ///< pixels set in last.mask (mask overlap only)
    std::uint64_t history = 0;  ///< bit i: detected i frames ago (bit 0: the current frame)
  };

  std::uint64_t window_bits() const {
    return settings_.window_frames == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << settings_.window_frames) - 1;
  }
  int seen(const Track& t) const {
    std::uint64_t bits = t.history & window_bits();
    int n = 0;
    for (; bits != 0; bits &= bits - 1) ++n;
    return n;
  }
  bool passes(const Track& t) const { return seen(t) >= settings_.min_frames_seen; }

  static const cv::Mat& checked_mask(const SegmentedInstance& s, const FrameImage& frame) {
    if (s.mask.type() != CV_8UC1 || s.mask.size() != frame.bgr.size()) {
      throw std::invalid_argument("TemporalInstanceFilter: instance " + std::to_string(s.id) +
                                  " has a mask that is not CV_8UC1 of the image's size");
    }
    return s.mask;
  }

  std::unique_ptr<InstanceSegmenter> inner_;
  TemporalInstanceFilterSettings settings_;
  std::vector<Track> tracks_;
  cv::Size image_size_;  ///< the size of the last frame
  TemporalFilterFrameCounts counts_;
};

}  // namespace cge
