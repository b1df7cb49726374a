#pragma once
// RenderedFrameSource: a synthetic preset rendered in memory, frame by frame, with its exact
// ground truth: poses, the masks of the moving bodies (for the dynamic-feature leak), instance
// segmentation through the network-like error model, and ground-truth loops.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "cge/run/frame_source.hpp"
#include "cge/sim/renderer.hpp"
#include "cge/sim/segmentation_error_model.hpp"

namespace cge {
namespace run {

class RenderedFrameSource final : public FrameSource {
 public:
  /// Rendered sequences longer than this get no ground-truth loops (see ground_truth_loops).
  static constexpr int kMaxLoopTruthFrames = 1800;

  /// The first `frames` frames of `preset` (cge::sim::make_preset) with `seed`; `segment`: the
  /// source gives each frame's instances (the error model on the exact labels).
  RenderedFrameSource(const std::string& preset, int frames, std::uint64_t seed, bool segment);

  int frame_count() const override { return renderer_.frame_count(); }
  const sim::PinholeCamera& camera() const { return renderer_.camera(); }
  slam::FrameInput frame(int index) override;
  bool provides_instances() const override { return segment_; }
  std::vector<SegmentedInstance> instances(int index) override;
  GroundTruthPoses ground_truth() const override;
  /// The loop scenes' own ground truth; for the other presets the same rule (cge::sim::
  /// ground_truth_loops, its default settings: back within 0.3 m and 20 degrees after at least 2 m
  /// of travel) applied to the rendered poses. Only the loops of the queried keyframes are kept: on
  /// a camera that stays in one place (walking_xyz) almost every pair of distant frames is a loop.
  /// The pairs grow with the square of the length, so beyond kMaxLoopTruthFrames frames (at most
  /// 1.6 million pairs, 13 MB while they are filtered) there is no ground truth (std::nullopt).
  std::optional<std::vector<metrics::GroundTruthLoop>> ground_truth_loops(
      const std::set<std::string>& queries) const override;

 private:
  sim::SequenceRenderer renderer_;
  sim::SegmentationErrorModel model_;
  bool segment_;
  std::map<int, int> class_of_id_;
  std::vector<int> moving_ids_;
  sim::RenderedFrame last_;
};

}  // namespace run
}  // namespace cge
