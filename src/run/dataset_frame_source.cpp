#include "cge/run/dataset_frame_source.hpp"

#include "cge/dataset/segmentation_source.hpp"
#include "cge/slam/moving_keypoints.hpp"

namespace cge {
namespace run {

namespace fs = std::filesystem;

std::unique_ptr<PrecomputedMaskReader> open_exact_masks(const fs::path& folder) {
  const fs::path exact_masks = folder / dataset::folder_name(dataset::GroundTruthMasks::exact);
  if (!fs::exists(exact_masks / "instances.csv")) return nullptr;
  PrecomputedMaskSettings mask_settings;
  mask_settings.require_every_frame = true;  // the simulator writes a PNG for every frame
  return std::make_unique<PrecomputedMaskReader>(exact_masks.string(), mask_settings);
}

fs::path loops_file_of(const fs::path& folder) {
  const fs::path loops_file = folder / "loops.txt";
  return fs::is_regular_file(loops_file) ? loops_file : fs::path();
}

DatasetFrameSource::DatasetFrameSource(std::unique_ptr<dataset::TumSequence> sequence, int frames,
                                       std::unique_ptr<PrecomputedMaskReader> moving_masks,
                                       const fs::path& loops_file)
    : sequence_(std::move(sequence)), frames_(frames), moving_masks_(std::move(moving_masks)) {
  if (!loops_file.empty()) loops_ = metrics::read_ground_truth_loops_file(loops_file.string());
}

slam::FrameInput DatasetFrameSource::frame(int index) {
  const dataset::TumFrame f = sequence_->load(index);
  slam::FrameInput in;
  in.index = index;
  in.timestamp_s = f.rgb_timestamp_s;
  in.bgr = f.bgr;
  in.depth = f.depth;
  in.stem = f.rgb_stem;
  if (moving_masks_ != nullptr) {
    in.moving_mask = slam::moving_mask_of(moving_masks_->read(in.stem, in.bgr.size()), in.bgr.size());
  }
  return in;
}

GroundTruthPoses DatasetFrameSource::ground_truth() const {
  GroundTruthPoses gt;
  for (const auto& p : sequence_->ground_truth()) gt.emplace_back(p.timestamp_s, p.T_world_camera);
  return gt;
}

std::optional<std::vector<metrics::GroundTruthLoop>> DatasetFrameSource::ground_truth_loops(
    const std::set<std::string>& /*queries*/) const {
  return loops_;
}

}  // namespace run
}  // namespace cge
