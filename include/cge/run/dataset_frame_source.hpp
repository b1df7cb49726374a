#pragma once
// DatasetFrameSource: the frames of a TUM RGB-D folder (or a cge_sim folder in that layout), with
// the ground truth the folder holds: groundtruth.txt poses, the exact masks of the moving bodies
// (a synthetic folder's masks/, for the dynamic-feature leak) and loops.txt (a cge_sim loop scene).
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "cge/dataset/tum_sequence.hpp"
#include "cge/run/frame_source.hpp"
#include "cge/segmentation/precomputed_mask_reader.hpp"

namespace cge {
namespace run {

/// The exact ground-truth masks of a synthetic folder (masks/ with instances.csv, a PNG for every
/// frame), or null when the folder has none (real data).
std::unique_ptr<PrecomputedMaskReader> open_exact_masks(const std::filesystem::path& folder);

/// The folder's loops.txt when it has one, else an empty path.
std::filesystem::path loops_file_of(const std::filesystem::path& folder);

class DatasetFrameSource final : public FrameSource {
 public:
  /// The first `frames` frames of `sequence`. `moving_masks`: the exact masks (open_exact_masks), or
  /// null: the frames then carry no moving mask. `loops_file`: loops.txt, or empty when there is none.
  DatasetFrameSource(std::unique_ptr<dataset::TumSequence> sequence, int frames,
                     std::unique_ptr<PrecomputedMaskReader> moving_masks, const std::filesystem::path& loops_file);

  int frame_count() const override { return frames_; }
  slam::FrameInput frame(int index) override;
  GroundTruthPoses ground_truth() const override;
  /// The loops file as it is, as cge_eval loops reads it.
  std::optional<std::vector<metrics::GroundTruthLoop>> ground_truth_loops(
      const std::set<std::string>& queries) const override;

  const dataset::TumSequence& sequence() const { return *sequence_; }

 private:
  std::unique_ptr<dataset::TumSequence> sequence_;
  int frames_;
  std::unique_ptr<PrecomputedMaskReader> moving_masks_;
  std::optional<std::vector<metrics::GroundTruthLoop>> loops_;
};

}  // namespace run
}  // namespace cge
