#pragma once
// Keyframes made from rendered synthetic frames, and a KeyframeDatabaseView whose covisibility is
// decided from ground-truth poses, for the loop-closing tests and benchmark.
//
// A keyframe here is what a tracker with perfect poses and perfect masks would make: ORB features
// (cv::ORB), depth back-projected through the camera, dynamic mask and labels from the ground-truth
// instance labels of the moving instances, one semantic instance per labelled object in view.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <vector>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "cge/core/pinhole_intrinsics.hpp"
#include "cge/sim/sequence.hpp"
#include "cge/slam/keyframe.hpp"
#include "cge/slam/keyframe_database_view.hpp"

namespace cge_test {

inline cge::PinholeIntrinsics<double> intrinsics_of(const cge::sim::PinholeCamera& c) {
  cge::PinholeIntrinsics<double> k;
  k.fx_px = c.fx_px;
  k.fy_px = c.fy_px;
  k.cx_px = c.cx_px;
  k.cy_px = c.cy_px;
  return k;
}

/// Labelled objects smaller than this many pixels are not reported as instances (a segmenter would
/// miss them too).
constexpr int kMinInstancePixels = 200;

inline cge::slam::Keyframe keyframe_from_frame(const cge::sim::RenderedFrame& frame,
                                               const cge::sim::PinholeCamera& camera,
                                               const std::vector<cge::sim::InstanceInfo>& instances, int id,
                                               int orb_features = 1000) {
  cge::slam::Keyframe kf;
  kf.id = id;
  kf.frame_index = frame.index;
  kf.timestamp_s = frame.timestamp_s;
  kf.T_world_camera = frame.T_world_camera;

  std::map<int, const cge::sim::InstanceInfo*> info;
  for (const auto& i : instances) info[i.id] = &i;
  const cv::Mat& labels = frame.instance_labels;
  kf.dynamic_mask = cv::Mat(labels.rows, labels.cols, CV_8UC1, cv::Scalar(0));
  struct Box {
    int x0 = std::numeric_limits<int>::max(), y0 = std::numeric_limits<int>::max(), x1 = -1, y1 = -1, pixels = 0;
  };
  std::map<int, Box> boxes;
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      const int l = labels.at<std::uint16_t>(y, x);
      if (l == 0) continue;
      Box& b = boxes[l];
      b.x0 = std::min(b.x0, x);
      b.y0 = std::min(b.y0, y);
      b.x1 = std::max(b.x1, x);
      b.y1 = std::max(b.y1, y);
      ++b.pixels;
      const auto it = info.find(l);
      if (it != info.end() && it->second->moving) kf.dynamic_mask.at<std::uint8_t>(y, x) = 255;
    }
  }
  for (const auto& kv : boxes) {
    const auto it = info.find(kv.first);
    if (it == info.end() || kv.second.pixels < kMinInstancePixels) continue;
    cge::SemanticInstance<double> s;
    s.centre_px = Eigen::Vector2d(0.5 * (kv.second.x0 + kv.second.x1), 0.5 * (kv.second.y0 + kv.second.y1));
    s.class_id = it->second->class_id;
    s.dynamic = it->second->moving;
    kf.instances.push_back(s);
  }

  cv::Mat grey;
  cv::cvtColor(frame.rgb, grey, cv::COLOR_BGR2GRAY);
  cv::ORB::create(orb_features)->detectAndCompute(grey, cv::noArray(), kf.keypoints, kf.descriptors);
  const cge::PinholeIntrinsics<double> k = intrinsics_of(camera);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const cv::KeyPoint& p : kf.keypoints) {
    const int u = std::min(labels.cols - 1, std::max(0, static_cast<int>(std::lround(p.pt.x))));
    const int v = std::min(labels.rows - 1, std::max(0, static_cast<int>(std::lround(p.pt.y))));
    kf.labels.push_back(kf.dynamic_mask.at<std::uint8_t>(v, u) != 0 ? cge::FeatureLabel::dynamic_by_mask
                                                                    : cge::FeatureLabel::static_feature);
    const int raw = frame.depth.at<std::uint16_t>(v, u);
    kf.points_camera_m.push_back(raw == 0 ? Eigen::Vector3d(nan, nan, nan)
                                          : k.backproject(p.pt.x, p.pt.y, raw / camera.depth_units_per_metre));
    kf.map_point_ids.push_back(-1);
  }
  return kf;
}

/// Covisibility from poses: keyframes at most `window` ids apart whose optical axes differ by less
/// than `max_angle_deg` (as a tracker's local map would link them; a revisit much later is not
/// covisible until the loop is closed). Ordered by id distance, then by id.
class PoseCovisibilityView final : public cge::slam::KeyframeDatabaseView {
 public:
  PoseCovisibilityView(const std::vector<cge::slam::Keyframe>& keyframes, int window, double max_angle_deg)
      : keyframes_(keyframes), window_(window), max_angle_deg_(max_angle_deg) {}
  /// Keyframes 0 .. count - 1 are in the map (the loop closer sees the map grow).
  void set_count(int count) { count_ = count; }
  int keyframe_count() const override { return count_; }
  const cge::slam::Keyframe& keyframe(int id) const override { return keyframes_.at(static_cast<std::size_t>(id)); }
  std::vector<int> covisible_keyframes(int id, int max_count) const override {
    std::vector<int> out;
    const Eigen::Vector3d axis = keyframe(id).T_world_camera.linear().col(2);
    for (int j = std::max(0, id - window_); j < std::min(count_, id + window_ + 1); ++j) {
      if (j == id) continue;
      const double c = std::max(-1.0, std::min(1.0, axis.dot(keyframe(j).T_world_camera.linear().col(2))));
      if (std::acos(c) * 180.0 / M_PI < max_angle_deg_) out.push_back(j);
    }
    std::stable_sort(out.begin(), out.end(), [id](int a, int b) { return std::abs(a - id) < std::abs(b - id); });
    if (max_count >= 0 && static_cast<int>(out.size()) > max_count) out.resize(static_cast<std::size_t>(max_count));
    return out;
  }

 private:
  const std::vector<cge::slam::Keyframe>& keyframes_;
  int window_;
  double max_angle_deg_;
  int count_ = 0;
};

}  // namespace cge_test
