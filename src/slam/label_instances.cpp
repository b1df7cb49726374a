#include "cge/slam/label_instances.hpp"

#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace cge {
namespace slam {

std::vector<SegmentedInstance> instances_from_label_image(const cv::Mat& labels, const std::map<int, int>& class_of_id,
                                                          const std::set<int>& dynamic_class_ids) {
  if (labels.type() != CV_16UC1 && labels.type() != CV_8UC1) {
    throw std::invalid_argument("instances_from_label_image: the label image has type " +
                                cv::typeToString(labels.type()) + ", expected CV_16UC1 or CV_8UC1");
  }
  cv::Mat labels16;
  labels.convertTo(labels16, CV_16U);
  std::set<int> ids;
  for (int r = 0; r < labels16.rows; ++r) {
    const auto* row = labels16.ptr<std::uint16_t>(r);
    for (int c = 0; c < labels16.cols; ++c) {
      if (row[c] != 0) ids.insert(row[c]);
    }
  }
  std::vector<SegmentedInstance> out;
  for (const int id : ids) {
    const auto it = class_of_id.find(id);
    if (it == class_of_id.end()) {
      throw std::invalid_argument("instances_from_label_image: instance id " + std::to_string(id) +
                                  " has no class in the instance table");
    }
    SegmentedInstance inst;
    inst.id = id;
    inst.class_id = it->second;
    inst.score = 1;
    inst.mask = labels16 == id;
    const cv::Rect box = cv::boundingRect(inst.mask);
    inst.box_px = cv::Rect2f(box);
    inst.dynamic = dynamic_class_ids.count(inst.class_id) > 0;
    out.push_back(std::move(inst));
  }
  return out;
}

}  // namespace slam
}  // namespace cge
