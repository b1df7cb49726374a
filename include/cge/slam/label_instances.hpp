#pragma once
// Instances from an instance-label image held in memory (the synthetic sequences' masks, rendered
// in process): what PrecomputedMaskReader::read makes from a mask-folder PNG, without the file.
#include <map>
#include <set>
#include <vector>

#include <opencv2/core.hpp>

#include "cge/segmentation/instance_segmenter.hpp"

namespace cge {
namespace slam {

/// The instances of `labels` (CV_16UC1 or CV_8UC1, 0 = background), by id ascending: mask = the
/// pixels with that id, box = their bounding box (whole pixels), class from `class_of_id`, dynamic
/// when the class is in `dynamic_class_ids`, score 1. Throws std::invalid_argument for another
/// image type or an id missing from class_of_id.
std::vector<SegmentedInstance> instances_from_label_image(const cv::Mat& labels, const std::map<int, int>& class_of_id,
                                                          const std::set<int>& dynamic_class_ids);

}  // namespace slam
}  // namespace cge
