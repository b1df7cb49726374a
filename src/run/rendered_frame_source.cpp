#include "cge/run/rendered_frame_source.hpp"

#include <cstdio>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/sim/loops.hpp"
#include "cge/sim/presets.hpp"
#include "cge/slam/label_instances.hpp"

namespace cge {
namespace run {

RenderedFrameSource::RenderedFrameSource(const std::string& preset, int frames, std::uint64_t seed, bool segment)
    : renderer_(sim::make_preset(preset, frames, seed)), model_(renderer_.instances(), seed), segment_(segment) {
  for (const sim::InstanceInfo& i : renderer_.instances()) {
    class_of_id_[i.id] = i.class_id;
    if (i.moving) moving_ids_.push_back(i.id);
  }
}

slam::FrameInput RenderedFrameSource::frame(int index) {
  last_ = renderer_.render(index);
  slam::FrameInput in;
  in.index = index;
  in.timestamp_s = last_.timestamp_s;
  in.bgr = last_.rgb;
  in.depth = last_.depth;
  char stem[32];
  std::snprintf(stem, sizeof stem, "%.6f", last_.timestamp_s);
  in.stem = stem;
  // Ground truth of the leak count: the exact labels of the bodies that move.
  in.moving_mask = cv::Mat::zeros(last_.instance_labels.size(), CV_8UC1);
  for (const int id : moving_ids_) in.moving_mask.setTo(255, last_.instance_labels == id);
  return in;
}

std::vector<SegmentedInstance> RenderedFrameSource::instances(int index) {
  const sim::SegmentationResult seg = model_.apply(last_.instance_labels, index);
  std::map<int, int> classes = class_of_id_;
  for (const sim::InstanceInfo& i : seg.instances) classes[i.id] = i.class_id;  // false positives
  return slam::instances_from_label_image(seg.instance_labels, classes, {kCocoPerson});
}

GroundTruthPoses RenderedFrameSource::ground_truth() const {
  GroundTruthPoses gt;
  const sim::SequenceSpec& spec = renderer_.spec();
  for (std::size_t i = 0; i < spec.T_world_camera.size(); ++i) {
    gt.emplace_back(spec.start_timestamp_s + static_cast<double>(i) / spec.frame_rate_hz, spec.T_world_camera[i]);
  }
  return gt;
}

std::optional<std::vector<metrics::GroundTruthLoop>> RenderedFrameSource::ground_truth_loops(
    const std::set<std::string>& queries) const {
  const sim::SequenceSpec& spec = renderer_.spec();
  if (spec.T_world_camera.size() > static_cast<std::size_t>(kMaxLoopTruthFrames)) return std::nullopt;
  const auto stamp = [&spec](int i) { return spec.start_timestamp_s + static_cast<double>(i) / spec.frame_rate_hz; };
  const bool loop_scene = spec.name.rfind("loop_", 0) == 0;
  const std::vector<sim::LoopPair> pairs = loop_scene ? spec.loops : sim::ground_truth_loops(spec.T_world_camera);
  std::vector<metrics::GroundTruthLoop> loops;
  char text[32];
  for (const sim::LoopPair& p : pairs) {
    std::snprintf(text, sizeof text, "%.6f", stamp(p.query_frame));
    if (queries.count(text) == 0) continue;
    metrics::GroundTruthLoop l;
    l.query_timestamp_s = stamp(p.query_frame);
    l.match_timestamp_s = stamp(p.match_frame);
    l.query_index = p.query_frame;
    l.match_index = p.match_frame;
    loops.push_back(l);
  }
  return loops;
}

}  // namespace run
}  // namespace cge
