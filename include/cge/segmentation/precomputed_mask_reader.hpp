#pragma once
// PrecomputedMaskReader: instance masks computed elsewhere (another network, another machine, the
// synthetic sequences), read from a mask folder, behind the same interface as the segmenters.
//
// The mask-folder format (docs/SEGMENTATION.md):
// - <stem>.png per frame, <stem> = the frame's RGB file name without extension. Single channel,
//   16-bit unsigned (8-bit accepted), 0 = background, k >= 1 = instance id k. A frame without
//   instances may have an all-zero image or no image at all.
// - instances.csv: header `id,class_id,class_name,moving`, then one line per instance id used in
//   any image: id (1 .. 65535, unique), COCO class id (0 .. 79), class name (informative only, no
//   commas), moving (1, 0, or empty = unknown). Lines starting with '#' and empty lines are ignored.
//
// The reader holds the parsed instances.csv and reads one PNG per call; it keeps no other state,
// so reading a frame twice gives the same instances.

#include <iosfwd>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/segmentation/coco_classes.hpp"
#include "cge/segmentation/instance_segmenter.hpp"

namespace cge {

/// One line of instances.csv.
struct MaskFolderInstance {
  int id = 0;                  ///< 1 .. 65535
  int class_id = 0;            ///< COCO class id, 0 .. 79
  std::string class_name;      ///< as written in the file (informative only)
  std::optional<bool> moving;  ///< empty when the file leaves it unknown
  int line = 0;                ///< 1-based line in instances.csv, for messages
};

/// Parses instances.csv from `in`; `source` names it in messages. Returns the instances by id.
/// Throws std::invalid_argument "<source>:<line>: ..." for a missing or wrong header, a line without
/// exactly four fields, an id outside 1 .. 65535 or repeated, a class id outside 0 .. 79, a moving
/// value other than 1, 0 or empty, or a number that does not parse.
std::map<int, MaskFolderInstance> read_instances_csv(std::istream& in, const std::string& source);

struct PrecomputedMaskSettings {
  /// COCO classes whose instances are marked dynamic.
  std::set<int> dynamic_class_ids = {kCocoPerson};
  /// Strict mode: a frame without a PNG in the folder is an error instead of "no instances".
  bool require_every_frame = false;
};

class PrecomputedMaskReader final : public InstanceSegmenter {
 public:
  /// Opens the folder and parses its instances.csv. Throws std::invalid_argument when the folder
  /// or instances.csv is missing, or instances.csv is malformed (file and line), or the settings
  /// name a class id outside 0 .. 79.
  explicit PrecomputedMaskReader(const std::string& folder, PrecomputedMaskSettings settings = {});

  /// The instances of <folder>/<frame.stem>.png; frame.bgr only gives the expected size (any type,
  /// not empty). Same as read(frame.stem, frame.bgr.size()).
  std::vector<SegmentedInstance> segment(const FrameImage& frame) override;

  /// The instances in <folder>/<stem>.png, by id ascending: mask = the pixels with that id, box =
  /// their bounding box (whole pixels), class, moving and dynamic from instances.csv and the dynamic
  /// class set, score 1. No file: no instances (or an error in strict mode). Throws
  /// std::invalid_argument naming the file when it is unreadable, not single-channel 8/16-bit, not
  /// image_size, or uses an id missing from instances.csv; also for a stem that is empty or has a
  /// path separator.
  std::vector<SegmentedInstance> read(const std::string& stem, cv::Size image_size) const;

  void set_dynamic_classes(const std::set<int>& class_ids) override;
  const std::set<int>& dynamic_classes() const override { return settings_.dynamic_class_ids; }

  const PrecomputedMaskSettings& settings() const { return settings_; }
  const std::string& folder() const { return folder_; }
  /// instances.csv, by id.
  const std::map<int, MaskFolderInstance>& instances() const { return instances_; }

 private:
  std::string folder_;
  PrecomputedMaskSettings settings_;
  std::map<int, MaskFolderInstance> instances_;
};

}  // namespace cge
