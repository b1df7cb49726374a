#include "cge/slam/keypoint_spread.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace cge {
namespace slam {

std::vector<cv::KeyPoint> spread_over_cells(const std::vector<cv::KeyPoint>& candidates, int oversampling,
                                            int cell_px, double scale_factor) {
  if (oversampling <= 1) return candidates;
  const std::size_t s = static_cast<std::size_t>(oversampling);
  std::map<int, std::vector<int>> by_level;
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    by_level[std::max(candidates[static_cast<std::size_t>(i)].octave, 0)].push_back(i);
  }
  std::vector<char> keep(candidates.size(), 0);
  for (const auto& [level, members] : by_level) {
    const double cell = cell_px * std::pow(scale_factor, level);
    std::map<std::pair<int, int>, std::vector<int>> cells;  // (row, col) -> candidates
    for (const int i : members) {
      const cv::Point2f& p = candidates[static_cast<std::size_t>(i)].pt;
      cells[{static_cast<int>(p.y / cell), static_cast<int>(p.x / cell)}].push_back(i);
    }
    const auto stronger = [&](int a, int b) {
      const float ra = candidates[static_cast<std::size_t>(a)].response;
      const float rb = candidates[static_cast<std::size_t>(b)].response;
      return ra != rb ? ra > rb : a < b;
    };
    std::vector<std::vector<int>> ranked;
    for (auto& entry : cells) {
      std::sort(entry.second.begin(), entry.second.end(), stronger);
      ranked.push_back(std::move(entry.second));
    }
    std::sort(ranked.begin(), ranked.end(),
              [&](const std::vector<int>& a, const std::vector<int>& b) { return stronger(a.front(), b.front()); });
    const std::size_t quota = (members.size() + s / 2) / s;  // members / oversampling, halves up
    std::size_t taken = 0;
    for (std::size_t rank = 0; taken < quota; ++rank) {
      for (const std::vector<int>& cell_members : ranked) {
        if (rank < cell_members.size() && taken < quota) {
          keep[static_cast<std::size_t>(cell_members[rank])] = 1;
          ++taken;
        }
      }
    }
  }
  std::vector<cv::KeyPoint> out;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (keep[i]) out.push_back(candidates[i]);
  }
  return out;
}

}  // namespace slam
}  // namespace cge
