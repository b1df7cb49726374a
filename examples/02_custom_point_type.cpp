// Example 2: plugging a foreign keypoint type into GraphBuilder and CGESimilarity.
//
// The toolkit reads points only through cge::traits::Point2<P>::x / ::y (see
// cge/core/point_traits.hpp). A type you cannot or do not want to change, such as this keypoint
// struct of some host SLAM system, is adapted by one specialisation: no wrapper, no copy.

#include <cstdio>
#include <vector>

#include "cge/core/point_traits.hpp"
#include "cge/entropy/cge_similarity.hpp"
#include "cge/graph/graph_builder.hpp"

// The host system's keypoint: pixel coordinates u (column) and v (row), plus data we do not need.
struct MyKeypoint {
  float u, v;
  int octave;
};

// The adapter: a specialisation of cge::traits::Point2 in namespace cge::traits.
namespace cge {
namespace traits {
template <>
struct Point2<MyKeypoint> {
  static float x(const MyKeypoint& p) { return p.u; }
  static float y(const MyKeypoint& p) { return p.v; }
};
}  // namespace traits
}  // namespace cge

int main() {
  // Two frames of a 640 x 480 camera: a grid of keypoints, and the same grid shifted a little
  // with one keypoint missing (as after a small camera motion).
  std::vector<MyKeypoint> current, candidate;
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 8; ++col) {
      const float u = 40.0f + 75.0f * static_cast<float>(col);
      const float v = 40.0f + 80.0f * static_cast<float>(row);
      current.push_back({u, v, row % 3});
      if (row != 2 || col != 5) candidate.push_back({u + 6.0f, v + 3.0f, row % 3});
    }
  }

  const cge::ImageRegion<double> image;  // 640 x 480 pixels, origin (0, 0)

  // GraphBuilder accepts any range of adapted points.
  cge::GraphBuilder<double> builder;
  const cge::Graph<double> g = builder.build(image, current);
  std::printf("frame graph: %d nodes, %d edges\n", g.num_nodes(), g.num_edges());

  // CGESimilarity builds both graphs (each with respect to the other frame's dynamic mask; here
  // neither frame has one: cge::NoMask) and compares their entropies.
  cge::CGESimilarity<double> similarity;
  const std::vector<cge::SemanticInstance<double>> no_instances;
  const cge::NoMask no_mask;
  const auto score = similarity.score(image, cge::frame_view<double>(current, no_mask, no_instances),
                                      cge::frame_view<double>(candidate, no_mask, no_instances));
  std::printf("I(current) = %.6f, I(candidate) = %.6f\n", score.current.information_index,
              score.candidate.information_index);
  std::printf("H_W(current) = %.6f, H_W(candidate) = %.6f bits\n", score.current.edge_entropy_bits,
              score.candidate.edge_entropy_bits);
  std::printf("similarity S_sum = %.6f (edge entropy %s)\n", score.similarity,
              score.used_edge_entropy ? "used" : "not used: no static semantic instances in either frame");
  return 0;
}
