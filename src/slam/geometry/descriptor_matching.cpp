#include "cge/slam/geometry/descriptor_matching.hpp"

#include "cge/slam/two_nearest_descriptors.hpp"

namespace cge {
namespace slam {

std::vector<DescriptorPair> match_descriptors_one_to_one(const cv::Mat& query, const cv::Mat& train,
                                                         int max_distance, double ratio, OneToOneRule rule) {
  const std::vector<std::vector<cv::DMatch>> knn = two_nearest_descriptors(query, train);
  std::vector<DescriptorPair> by_train(static_cast<std::size_t>(train.rows));
  for (const std::vector<cv::DMatch>& k : knn) {
    if (k.empty()) continue;
    // Distances are whole bit counts held exactly in float.
    const int best = static_cast<int>(k[0].distance);
    if (best > max_distance) continue;
    if (k.size() > 1 && !(best < ratio * static_cast<int>(k[1].distance))) continue;
    DescriptorPair& slot = by_train[static_cast<std::size_t>(k[0].trainIdx)];
    // Queries arrive in ascending order: under closest a strictly smaller distance replaces the
    // claimant (a tie keeps the smaller query index); under first_claim nothing replaces it.
    const bool replace = slot.query < 0 || (rule == OneToOneRule::closest && best < slot.distance);
    if (replace) slot = DescriptorPair{k[0].queryIdx, k[0].trainIdx, best};
  }
  std::vector<DescriptorPair> out;
  for (const DescriptorPair& p : by_train) {
    if (p.query >= 0) out.push_back(p);
  }
  return out;
}

}  // namespace slam
}  // namespace cge
