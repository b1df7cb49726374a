#include "cge/segmentation/instance_segmenter.hpp"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "cge/segmentation/coco_classes.hpp"

namespace cge {
namespace {

constexpr unsigned char kMaskOn = 255;

void check_instance_mask(const SegmentedInstance& instance, cv::Size image_size, const char* where) {
  if (instance.mask.type() != CV_8UC1 || instance.mask.size() != image_size) {
    std::ostringstream msg;
    msg << where << ": the mask of instance " << instance.id << " is " << instance.mask.cols << " x "
        << instance.mask.rows << " of type " << cv::typeToString(instance.mask.type()) << ", expected "
        << image_size.width << " x " << image_size.height << " CV_8UC1";
    throw std::invalid_argument(msg.str());
  }
}

void check_image_size(cv::Size image_size, const char* where) {
  if (image_size.width <= 0 || image_size.height <= 0) {
    std::ostringstream msg;
    msg << where << ": the image size " << image_size.width << " x " << image_size.height << " is empty";
    throw std::invalid_argument(msg.str());
  }
}

}  // namespace

std::string frame_stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

void check_coco_class_ids(const std::set<int>& class_ids, const char* where) {
  for (const int id : class_ids) {
    if (id < 0 || id >= kCocoClassCount) {
      throw std::invalid_argument(std::string(where) + ": dynamic class id " + std::to_string(id) +
                                  " is not a COCO class id (0 .. 79)");
    }
  }
}

cv::Mat union_dynamic_masks(const std::vector<SegmentedInstance>& instances, cv::Size image_size) {
  constexpr const char* kWhere = "union_dynamic_masks";
  check_image_size(image_size, kWhere);
  cv::Mat out(image_size, CV_8UC1, cv::Scalar(0));
  for (const auto& instance : instances) {
    if (!instance.dynamic) continue;
    check_instance_mask(instance, image_size, kWhere);
    out.setTo(kMaskOn, instance.mask);
  }
  return out;
}

cv::Mat instance_label_image(const std::vector<SegmentedInstance>& instances, cv::Size image_size) {
  constexpr const char* kWhere = "instance_label_image";
  check_image_size(image_size, kWhere);
  std::set<int> ids;
  for (const auto& instance : instances) {
    if (instance.id < 1 || instance.id > std::numeric_limits<std::uint16_t>::max()) {
      throw std::invalid_argument(std::string(kWhere) + ": instance id " + std::to_string(instance.id) +
                                  " is not in 1 .. 65535");
    }
    if (!ids.insert(instance.id).second) {
      throw std::invalid_argument(std::string(kWhere) + ": instance id " + std::to_string(instance.id) +
                                  " is used twice");
    }
    check_instance_mask(instance, image_size, kWhere);
  }
  cv::Mat out(image_size, CV_16UC1, cv::Scalar(0));
  // Paint back to front so that the instance earliest in the list ends on top.
  for (auto it = instances.rbegin(); it != instances.rend(); ++it) out.setTo(it->id, it->mask);
  return out;
}

PixelBox filter_box(const SegmentedInstance& instance, cv::Size image_size) {
  PixelBox box{instance.box_px.x, instance.box_px.y, instance.box_px.width, instance.box_px.height};
  box.width_px = std::min(box.width_px, image_size.width - box.x_min_px);
  box.height_px = std::min(box.height_px, image_size.height - box.y_min_px);
  return box;
}

}  // namespace cge
