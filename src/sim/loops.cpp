#include "cge/sim/loops.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cge {
namespace sim {

std::vector<LoopPair> ground_truth_loops(const std::vector<Eigen::Isometry3d>& T_world_camera,
                                         const LoopSettings& settings) {
  const auto bad = [](double v) { return !std::isfinite(v) || !(v > 0); };
  if (bad(settings.max_distance_m)) throw std::invalid_argument("LoopSettings.max_distance_m must be finite and > 0");
  if (bad(settings.max_angle_deg) || settings.max_angle_deg > 180) {
    throw std::invalid_argument("LoopSettings.max_angle_deg must be in (0, 180]");
  }
  if (bad(settings.min_travel_m)) throw std::invalid_argument("LoopSettings.min_travel_m must be finite and > 0");
  const std::size_t n = T_world_camera.size();
  std::vector<Eigen::Vector3d> centre(n), axis(n);
  std::vector<double> travelled(n, 0.0);  // path length from frame 0
  for (std::size_t i = 0; i < n; ++i) {
    if (!T_world_camera[i].matrix().allFinite()) {
      std::ostringstream msg;
      msg << "ground_truth_loops: pose " << i << " is not finite";
      throw std::invalid_argument(msg.str());
    }
    centre[i] = T_world_camera[i].translation();
    axis[i] = T_world_camera[i].linear().col(2).normalized();
    if (i > 0) travelled[i] = travelled[i - 1] + (centre[i] - centre[i - 1]).norm();
  }
  const double cos_max_angle = std::cos(settings.max_angle_deg * 3.14159265358979323846 / 180.0);
  const double max_d2 = settings.max_distance_m * settings.max_distance_m;
  std::vector<LoopPair> loops;
  for (std::size_t q = 0; q < n; ++q) {
    for (std::size_t m = 0; m < q; ++m) {
      if (travelled[q] - travelled[m] < settings.min_travel_m) break;  // travelled only grows with m
      if ((centre[q] - centre[m]).squaredNorm() > max_d2) continue;
      if (axis[q].dot(axis[m]) < cos_max_angle) continue;
      loops.push_back(LoopPair{static_cast<int>(q), static_cast<int>(m)});
    }
  }
  return loops;
}

}  // namespace sim
}  // namespace cge
