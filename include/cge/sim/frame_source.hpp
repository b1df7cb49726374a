#pragma once
// FrameSource: what the sequence writer needs from a synthetic sequence, as an interface, so that
// the writer and its tests do not depend on how frames are made (the renderer, a list of frames
// made by hand in a test, a replayed recording).
//
// Contract: frame_count() >= 0 frames, render(i) for 0 <= i < frame_count() returns frame i
// (RenderedFrame::index == i) and may be called in any order and more than once with the same
// result; instances() lists every id that any instance-label image uses; loops() refer to frame
// indices of this source. The references returned stay valid as long as the source lives.

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cge/sim/sequence.hpp"

namespace cge {
namespace sim {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual int frame_count() const = 0;
  virtual const PinholeCamera& camera() const = 0;
  virtual double frame_rate_hz() const = 0;
  virtual const std::vector<InstanceInfo>& instances() const = 0;
  virtual const std::vector<LoopPair>& loops() const = 0;
  virtual RenderedFrame render(int index) const = 0;
};

/// Any type with the members above (the renderer, cge/sim/renderer.hpp) as a FrameSource. The
/// adapter owns the renderer: `RendererFrameSource<SequenceRenderer> source(SequenceRenderer(spec));`.
template <typename Renderer>
class RendererFrameSource final : public FrameSource {
 public:
  explicit RendererFrameSource(Renderer renderer) : renderer_(std::move(renderer)) {}
  int frame_count() const override { return renderer_.frame_count(); }
  const PinholeCamera& camera() const override { return renderer_.camera(); }
  double frame_rate_hz() const override { return renderer_.frame_rate_hz(); }
  const std::vector<InstanceInfo>& instances() const override { return renderer_.instances(); }
  const std::vector<LoopPair>& loops() const override { return renderer_.loops(); }
  RenderedFrame render(int index) const override { return renderer_.render(index); }
  const Renderer& renderer() const { return renderer_; }

 private:
  Renderer renderer_;
};

/// Frames held in memory (made by hand in a test, or rendered earlier). render() returns a deep
/// copy, so a caller that modifies a frame never changes the source.
class InMemoryFrameSource final : public FrameSource {
 public:
  PinholeCamera camera_model;
  double rate_hz = 30;
  std::vector<InstanceInfo> instance_table;
  std::vector<LoopPair> loop_pairs;
  std::vector<RenderedFrame> frames;

  int frame_count() const override { return static_cast<int>(frames.size()); }
  const PinholeCamera& camera() const override { return camera_model; }
  double frame_rate_hz() const override { return rate_hz; }
  const std::vector<InstanceInfo>& instances() const override { return instance_table; }
  const std::vector<LoopPair>& loops() const override { return loop_pairs; }
  RenderedFrame render(int index) const override {
    if (index < 0 || index >= frame_count()) {
      throw std::out_of_range("InMemoryFrameSource::render: frame " + std::to_string(index) + " is not in 0 .. " +
                              std::to_string(frame_count() - 1));
    }
    const RenderedFrame& f = frames[static_cast<std::size_t>(index)];
    RenderedFrame copy;
    copy.index = f.index;
    copy.timestamp_s = f.timestamp_s;
    copy.T_world_camera = f.T_world_camera;
    copy.rgb = f.rgb.clone();
    copy.depth = f.depth.clone();
    copy.instance_labels = f.instance_labels.clone();
    return copy;
  }
};

}  // namespace sim
}  // namespace cge
