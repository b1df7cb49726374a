#pragma once
// A tiny synthetic sequence for the dataset tests (written to disk with cge::sim's TUM writer).

#include <cstdint>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "cge/sim/frame_source.hpp"

namespace cge_test {

inline cge::sim::InstanceInfo sim_instance(std::uint16_t id, int class_id, bool moving) {
  cge::sim::InstanceInfo i;
  i.id = id;
  i.class_id = class_id;
  i.moving = moving;
  return i;
}

/// A small hand-made sequence: 40 x 30 pixels, random images, a moving camera, a
/// walking person (id 1) and a chair (id 2).
inline cge::sim::InMemoryFrameSource tiny_sequence(int frames) {
  cge::sim::InMemoryFrameSource s;
  s.camera_model.width_px = 40;
  s.camera_model.height_px = 30;
  s.camera_model.fx_px = 41.5;
  s.camera_model.fy_px = 42.0;
  s.camera_model.cx_px = 19.5;
  s.camera_model.cy_px = 14.5;
  s.rate_hz = 30;
  s.instance_table = {sim_instance(1, 0, true), sim_instance(2, 56, false)};  // person, chair
  cv::RNG rng(11);
  for (int i = 0; i < frames; ++i) {
    cge::sim::RenderedFrame f;
    f.index = i;
    f.timestamp_s = 1305031102.175304 + i / 30.0;
    f.T_world_camera = Eigen::Translation3d(0.2 * i, -0.1 * i, 1.0 + 0.05 * i) *
                       Eigen::AngleAxisd(0.4 * i - 1.0, Eigen::Vector3d(0.3, -0.2, 1.0).normalized());
    f.rgb = cv::Mat(30, 40, CV_8UC3);
    rng.fill(f.rgb, cv::RNG::UNIFORM, 0, 256);
    f.depth = cv::Mat(30, 40, CV_16UC1);
    rng.fill(f.depth, cv::RNG::UNIFORM, 0, 30000);
    f.instance_labels = cv::Mat(30, 40, CV_16UC1, cv::Scalar(0));
    f.instance_labels(cv::Rect(2 + 2 * i, 5, 8, 20)).setTo(1);
    f.instance_labels(cv::Rect(28, 18, 9, 10)).setTo(2);
    s.frames.push_back(f);
  }
  return s;
}

}  // namespace cge_test
