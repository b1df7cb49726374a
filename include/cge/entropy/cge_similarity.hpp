#pragma once
// CGESimilarity: combinatorial graph entropy similarity of two frames (docs/METHOD.md section 6).
//
//   S_ge(I1, I2) = 1 / (1 + |I1 - I2|^a)
//   same static semantic layout (S_cos_x >= S_th_x, or neither frame has static instances):
//       S_sum = S_ge(degree-degree indices)
//   structure changed (S_cos_x < S_th_x, or only one frame has static instances):
//       S_sum = mu S_ge(degree-degree indices) + (1 - mu) S_ge(edge entropies)
// Each frame's graph is built with respect to the other (stability uses both dynamic masks).

#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cge/core/image_region.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/semantic_prejudgment.hpp"
#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/graph/graph_builder.hpp"

namespace cge {

template <typename Scalar>
struct CGESimilaritySettings {
  /// S_th_x: semantic cosine at or above which the layout counts as unchanged. Our default; the
  /// paper gives none.
  Scalar semantic_threshold = Scalar(0.95);
  /// mu: weight of the degree-degree term when the structure changed (paper: 0.5).
  Scalar degree_weight = Scalar(0.5);
  /// a in S_ge = 1 / (1 + |dI|^a): an integer > 1 (ours: 2, the smallest allowed; the paper gives
  /// none). Not the functional's alpha.
  int similarity_exponent = 2;
};

/// What a frame's graph contributes to the similarity.
template <typename Scalar>
struct GraphEntropies {
  Scalar information_index = 0;  ///< I of the degree-degree entropy
  Scalar edge_entropy_bits = 0;  ///< H_W of the edge-weighted graph
  std::int32_t nodes = 0;
  std::int32_t edges = 0;
};

template <typename Scalar>
struct CGEScore {
  Scalar similarity = 0;         ///< S_sum in [0, 1]
  Scalar degree_similarity = 0;  ///< S_ge of the information indices
  Scalar edge_similarity = 0;    ///< S_ge of the edge entropies (computed always, used when structure changed)
  bool used_edge_entropy = false;
  SemanticComparison semantics;
  GraphEntropies<Scalar> current;
  GraphEntropies<Scalar> candidate;
};

/// Non-owning view of one frame's inputs. Keypoints: any range adapted by cge::traits::Point2;
/// Mask: any type adapted by cge::traits::Mask (NoMask when there are no dynamic objects).
template <typename Scalar, typename Keypoints, typename Mask>
struct FrameView {
  const Keypoints& keypoints;
  const Mask& dynamic_mask;
  const std::vector<SemanticInstance<Scalar>>& instances;
};

template <typename Scalar, typename Keypoints, typename Mask>
FrameView<Scalar, Keypoints, Mask> frame_view(const Keypoints& keypoints, const Mask& dynamic_mask,
                                              const std::vector<SemanticInstance<Scalar>>& instances) {
  return FrameView<Scalar, Keypoints, Mask>{keypoints, dynamic_mask, instances};
}

/// S_ge(x, y) = 1 / (1 + |x - y|^a), a >= 2 an integer.
template <typename Scalar>
Scalar entropy_similarity(Scalar x, Scalar y, int exponent) {
  if (exponent < 2) {
    throw std::invalid_argument("entropy_similarity: the exponent a must be an integer greater than 1");
  }
  const double d = std::fabs(static_cast<double>(x) - static_cast<double>(y));
  double p = 1.0;
  for (int i = 0; i < exponent; ++i) p *= d;
  return static_cast<Scalar>(1.0 / (1.0 + p));
}

template <typename Scalar = double, typename NeighborSearch = GridNeighborSearch<Scalar>,
          typename DegreeEntropy = DegreeDegreeEntropy<Scalar>, typename EdgeEntropy = ShannonEdgeEntropy<Scalar>>
class CGESimilarity {
 public:
  using Settings = CGESimilaritySettings<Scalar>;
  using Score = CGEScore<Scalar>;

  Settings settings;
  GraphBuilder<Scalar, NeighborSearch> graph_builder;
  DegreeEntropy degree_entropy;
  EdgeEntropy edge_entropy;

  /// Builds both graphs (each with respect to the other frame) and scores them.
  template <typename KpA, typename MaskA, typename KpB, typename MaskB>
  Score score(const ImageRegion<Scalar>& image, const FrameView<Scalar, KpA, MaskA>& current,
              const FrameView<Scalar, KpB, MaskB>& candidate) const {
    const Graph<Scalar> g_cur =
        graph_builder.build(image, current.keypoints, current.dynamic_mask, candidate.dynamic_mask, current.instances);
    const Graph<Scalar> g_cand = graph_builder.build(image, candidate.keypoints, candidate.dynamic_mask,
                                                     current.dynamic_mask, candidate.instances);
    require_nodes(g_cur, "current");
    require_nodes(g_cand, "candidate");
    return combine(entropies(g_cur), entropies(g_cand), compare_semantics(current.instances, candidate.instances));
  }

  /// I and H_W of one graph.
  GraphEntropies<Scalar> entropies(const Graph<Scalar>& g) const {
    GraphEntropies<Scalar> e;
    e.information_index = degree_entropy.information_index(g);
    e.edge_entropy_bits = edge_entropy.compute(g);
    e.nodes = g.num_nodes();
    e.edges = g.num_edges();
    return e;
  }

  /// The decision and the weighted sum, from per-graph values (for hosts that cache them).
  Score combine(const GraphEntropies<Scalar>& current, const GraphEntropies<Scalar>& candidate,
                const SemanticComparison& semantics) const {
    validate();
    Score s;
    s.current = current;
    s.candidate = candidate;
    s.semantics = semantics;
    s.degree_similarity =
        entropy_similarity(current.information_index, candidate.information_index, settings.similarity_exponent);
    s.edge_similarity =
        entropy_similarity(current.edge_entropy_bits, candidate.edge_entropy_bits, settings.similarity_exponent);
    switch (semantics.which) {
      case SemanticCase::both_empty:
        s.used_edge_entropy = false;
        break;
      case SemanticCase::one_empty:
        s.used_edge_entropy = true;
        break;
      case SemanticCase::compared:
        s.used_edge_entropy = semantics.cosine < settings.semantic_threshold;
        break;
    }
    s.similarity = s.used_edge_entropy
                       ? settings.degree_weight * s.degree_similarity + (1 - settings.degree_weight) * s.edge_similarity
                       : s.degree_similarity;
    return s;
  }

 private:
  static void require_nodes(const Graph<Scalar>& g, const char* which) {
    if (g.num_nodes() == 0) {
      throw std::invalid_argument(std::string("CGESimilarity: the ") + which +
                                  " frame's graph has no nodes (no stable keypoints and no static semantic instances)");
    }
  }

  void validate() const {
    if (!(settings.degree_weight >= 0 && settings.degree_weight <= 1)) {
      throw std::invalid_argument("CGESimilaritySettings: degree_weight (mu) must lie in [0, 1]");
    }
    if (!std::isfinite(settings.semantic_threshold)) {
      throw std::invalid_argument("CGESimilaritySettings: semantic_threshold must be finite");
    }
    if (settings.similarity_exponent < 2) {
      throw std::invalid_argument("CGESimilaritySettings: similarity_exponent (a) must be an integer greater than 1");
    }
  }
};

}  // namespace cge
