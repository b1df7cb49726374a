// Every public class template explicitly instantiated for float and double, so that every member
// compiles (a member of a class template is otherwise only compiled when something calls it), plus
// one call of each function template and member template, with a few checks that float and double
// agree.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cge/cge.hpp"
#include "cge/frontend/keyframe_policy.hpp"

namespace cge_test_instantiation {
/// A custom coefficient function with a name, for CustomCoefficients<F>.
struct HalfPower {
  double operator()(int k, int /*diameter*/) const { return std::pow(0.5, k); }
};
using CoefficientFunction = double (*)(int, int);
}  // namespace cge_test_instantiation

#define CGE_INSTANTIATE_ALL(S)                                                                                      \
  template struct cge::Edge<S>;                                                                                     \
  template class cge::Graph<S>;                                                                                     \
  template struct cge::ImageRegion<S>;                                                                              \
  template struct cge::SemanticInstance<S>;                                                                         \
  template struct cge::traits::Point2<Eigen::Matrix<S, 2, 1>>;                                                      \
  template struct cge::traits::Point2<std::array<S, 2>>;                                                            \
  template struct cge::traits::Point2<std::pair<S, S>>;                                                             \
  template class cge::BruteForceNeighborSearch<S>;                                                                  \
  template class cge::GridNeighborSearch<S>;                                                                        \
  template struct cge::GraphBuilderSettings<S>;                                                                     \
  template struct cge::FrameNodes<S>;                                                                               \
  template class cge::GraphBuilder<S, cge::BruteForceNeighborSearch<S>>;                                            \
  template class cge::GraphBuilder<S, cge::GridNeighborSearch<S>>;                                                  \
  template struct cge::GraphBuilderWorkspace<S, cge::BruteForceNeighborSearch<S>>;                                  \
  template struct cge::GraphBuilderWorkspace<S, cge::GridNeighborSearch<S>>;                                        \
  template struct cge::DegreeDegreeSettings<S>;                                                                     \
  template struct cge::DegreeDegreeResult<S>;                                                                       \
  template class cge::DegreeDegreeEntropy<S>;                                                                       \
  template class cge::DegreeDegreeEntropy<S, cge::CustomCoefficients<cge_test_instantiation::HalfPower>>;           \
  template class cge::DegreeDegreeEntropy<S, cge::CustomCoefficients<cge_test_instantiation::CoefficientFunction>>; \
  template class cge::ShannonEdgeEntropy<S>;                                                                        \
  template struct cge::CGESimilaritySettings<S>;                                                                    \
  template struct cge::GraphEntropies<S>;                                                                           \
  template struct cge::CGEScore<S>;                                                                                 \
  template struct cge::FrameView<S, std::vector<Eigen::Matrix<S, 2, 1>>, cge::BinaryMask>;                          \
  template class cge::CGESimilarity<S>;                                                                             \
  template class cge::CGESimilarity<S, cge::BruteForceNeighborSearch<S>>;

CGE_INSTANTIATE_ALL(float)
CGE_INSTANTIATE_ALL(double)
template struct cge::CustomCoefficients<cge_test_instantiation::HalfPower>;
template struct cge::CustomCoefficients<cge_test_instantiation::CoefficientFunction>;
template class cge::DepthMADFilter<std::mt19937_64>;
template class cge::DepthMADFilter<std::mt19937>;
template struct cge::DynamicInstance<cge::BinaryMask>;
template struct cge::DynamicInstance<cge::NoMask>;

#undef CGE_INSTANTIATE_ALL

namespace {

double inverse_k(int k, int /*diameter*/) { return 1.0 / k; }

/// Calls every function template and member template for one scalar type; returns the pieces the
/// test case compares between float and double.
template <typename S>
struct Run {
  using Point = Eigen::Matrix<S, 2, 1>;
  std::vector<cge::Edge<S>> edges;
  S index_grid = 0;
  S index_brute = 0;
  S edge_entropy = 0;
  S similarity = 0;
  std::vector<double> exponents;
  std::vector<cge::FeatureLabel> depth_mad_labels;

  Run() {
    const Point a(S(1), S(2));
    const Point b(S(4), S(6));
    REQUIRE(cge::squared_distance(a, b) == S(25));
    REQUIRE(cge::within_radius(a, b, S(5)));
    REQUIRE_FALSE(cge::within_radius(a, b, S(4.5)));
    REQUIRE(cge::point_x(a) == S(1));
    REQUIRE(cge::point_y(std::array<S, 2>{S(3), S(7)}) == S(7));
    REQUIRE(cge::point_x(std::make_pair(S(8), S(9))) == S(8));

    // Neighbour searches directly.
    const std::vector<Point> pts{Point(0, 0), Point(3, 4), Point(10, 0), Point(0, 5)};
    for (int policy = 0; policy < 2; ++policy) {
      std::vector<std::int32_t> found;
      auto visit = [&](std::int32_t j, S d2) {
        REQUIRE(d2 == cge::squared_distance(pts[0], pts[static_cast<std::size_t>(j)]));
        found.push_back(j);
      };
      if (policy == 0) {
        cge::BruteForceNeighborSearch<S> ns;
        ns.build(pts, S(5));
        ns.for_each_within(0, S(5), visit);
      } else {
        cge::GridNeighborSearch<S> ns;
        ns.build(pts, S(5));
        ns.for_each_within(0, S(5), visit);
      }
      std::sort(found.begin(), found.end());
      REQUIRE(found == std::vector<std::int32_t>{1, 3});
    }

    // Masks.
    cge::BinaryMask mask(640, 480);
    for (int y = 100; y < 200; ++y)
      for (int x = 100; x < 200; ++x) mask.at(x, y) = 1;
    cge::check_mask_size(mask, 640, 480, "mask");
    cge::check_mask_size(cge::NoMask{}, 640, 480, "no mask");

    // Graph construction: integer coordinates, R = 800 / 16 = 50, so float and double agree exactly
    // on every distance test. Keypoints through three adapted point types.
    cge::ImageRegion<S> image;
    std::vector<Point> eigen_kps;
    std::vector<std::array<S, 2>> array_kps;
    std::vector<std::pair<double, double>> pair_kps;
    for (int i = 0; i < 120; ++i) {
      const int x = (i * 37) % 640;
      const int y = (i * 53 + i * i) % 480;
      eigen_kps.emplace_back(S(x), S(y));
      array_kps.push_back({S(x), S(y)});
      pair_kps.emplace_back(x, y);
    }
    const std::vector<cge::SemanticInstance<S>> instances{
        {Point(S(320), S(100)), 56, false}, {Point(S(150), S(150)), 0, true}, {Point(S(50), S(400)), 60, false}};
    cge::GraphBuilderSettings<S> settings;
    settings.radius_fraction_of_diagonal = S(0.0625);
    settings.dense_patch_threshold = 2;
    const cge::GraphBuilder<S, cge::GridNeighborSearch<S>> grid(settings);
    const cge::GraphBuilder<S, cge::BruteForceNeighborSearch<S>> brute(settings);
    const cge::Graph<S> g = grid.build(image, eigen_kps, mask, cge::NoMask{}, instances);
    REQUIRE(brute.build(image, array_kps, mask, cge::NoMask{}, instances) == g);
    REQUIRE(grid.build(image, pair_kps, mask, cge::NoMask{}, instances) == g);
    const cge::FrameNodes<S> nodes = brute.build_nodes(image, eigen_kps, mask, cge::BinaryMask(), instances);
    REQUIRE(brute.build_edges(image, nodes) == g);
    REQUIRE(grid.build(image, eigen_kps).num_nodes() >= 3);  // the overload without masks
    REQUIRE(grid.base_radius(image) == S(50));
    edges = g.edges();

    // Entropies: DDE on graphs of either scalar type, all coefficient policies.
    const cge::DegreeDegreeEntropy<S> dde;
    const auto result = dde.compute(g);
    exponents = std::vector<double>(result.exponents.begin(), result.exponents.end());
    index_grid = dde.information_index(g);
    const cge::Graph<double> as_double = cge::Graph<double>::from_edges(2, {{0, 1, 1.0}}, false);
    REQUIRE(dde.compute(as_double).information_index == S(0));
    const cge::Graph<float> as_float = cge::Graph<float>::from_edges(2, {{0, 1, 1.0f}}, false);
    REQUIRE(dde.compute(as_float).entropy_bits == S(1));
    REQUIRE(dde.from_table(cge::shortest_path_degree_sums(g, cge::TieMode::mean)).exponents.size() ==
            static_cast<std::size_t>(g.num_nodes()));
    REQUIRE(cge::hop_diameter(g).diameter == result.diameter);
    const cge::TwinClasses twins = cge::twin_classes(g);
    REQUIRE(twins.num_classes >= 1);
    REQUIRE(twins.num_classes <= g.num_nodes());
    const cge::DegreeDegreeEntropy<S, cge::CustomCoefficients<cge_test_instantiation::HalfPower>> half(
        cge::DegreeDegreeSettings<S>{}, cge::custom_coefficients(cge_test_instantiation::HalfPower{}));
    const cge::DegreeDegreeEntropy<S, cge::CustomCoefficients<cge_test_instantiation::CoefficientFunction>> inv(
        cge::DegreeDegreeSettings<S>{},
        cge::custom_coefficients<cge_test_instantiation::CoefficientFunction>(&inverse_k));
    REQUIRE(std::isfinite(half.compute(g).information_index));
    REQUIRE(std::isfinite(inv.information_index(g)));
    index_brute = dde.information_index(brute.build(image, eigen_kps, mask, cge::NoMask{}, instances));
    edge_entropy = cge::ShannonEdgeEntropy<S>().compute(g);
    REQUIRE(cge::ShannonEdgeEntropy<S>().compute(as_double) == S(0));

    // Similarity.
    const std::map<int, int> counts = cge::static_class_counts(instances);
    REQUIRE(counts.size() == 2);
    REQUIRE(cge::compare_semantics(instances, instances).which == cge::SemanticCase::compared);
    REQUIRE(cge::entropy_similarity(S(1), S(0), 2) == S(0.5));
    cge::CGESimilarity<S> sim;
    sim.graph_builder.settings = settings;
    const auto cur = cge::frame_view(eigen_kps, mask, instances);
    const cge::NoMask no_mask;
    const auto cand = cge::frame_view(array_kps, no_mask, instances);
    const cge::CGEScore<S> score = sim.score(image, cur, cand);
    similarity = score.similarity;
    REQUIRE(score.similarity > S(0));
    REQUIRE(score.similarity <= S(1));
    cge::CGESimilarity<S, cge::BruteForceNeighborSearch<S>> sim_brute;
    sim_brute.graph_builder.settings = settings;
    REQUIRE(sim_brute.score(image, cur, cand).similarity == score.similarity);

    // Dynamic-feature elimination: keypoints of this scalar type, both engines.
    cge::FloatDepthImage depth(640, 480, 3.0f);
    for (int y = 100; y < 200; ++y)
      for (int x = 100; x < 200; ++x) depth.at(x, y) = 1.0f + 0.001f * static_cast<float>(x + y - 200);
    const std::vector<cge::DynamicInstance<cge::BinaryMask>> dynamic{
        cge::dynamic_instance(mask, cge::PixelBox{90, 90, 130, 130}, 0)};
    cge::DepthMADFilter<> mad;
    mad.engine.seed(5);
    const cge::DepthMADResult labelled = mad.filter(eigen_kps, depth, dynamic);
    REQUIRE(labelled.labels.size() == eigen_kps.size());
    REQUIRE(labelled.instances.at(0).mad_test_applied);
    depth_mad_labels = labelled.labels;
    cge::DepthMADFilter<std::mt19937> mad32(cge::DepthMADSettings{}, std::mt19937(5));
    REQUIRE(mad32.filter(array_kps, depth, dynamic).labels.size() == array_kps.size());
    const std::vector<cge::DynamicInstance<cge::NoMask>> none;
    REQUIRE(mad.filter(pair_kps, depth, none).static_count == static_cast<int>(pair_kps.size()));
  }
};

}  // namespace

TEST_CASE("every template instantiates and runs for float and double alike", "[instantiation]") {
  const Run<float> f;
  const Run<double> d;
  // Same structure on integer coordinates: same edges, weights equal to float precision.
  REQUIRE(f.edges.size() == d.edges.size());
  REQUIRE(f.edges.size() > 100);
  for (std::size_t i = 0; i < d.edges.size(); ++i) {
    REQUIRE(f.edges[i].u == d.edges[i].u);
    REQUIRE(f.edges[i].v == d.edges[i].v);
    REQUIRE(f.edges[i].weight == Approx(d.edges[i].weight).epsilon(1e-6));
  }
  // Delta and E are accumulated in double whatever the scalar (the result is stored as the scalar).
  REQUIRE(f.exponents.size() == d.exponents.size());
  for (std::size_t v = 0; v < d.exponents.size(); ++v) {
    REQUIRE(f.exponents[v] == static_cast<double>(static_cast<float>(d.exponents[v])));
  }
  REQUIRE(f.index_grid == Approx(d.index_grid).epsilon(1e-6));
  REQUIRE(f.index_brute == f.index_grid);
  REQUIRE(d.index_brute == d.index_grid);
  REQUIRE(f.edge_entropy == Approx(d.edge_entropy).epsilon(1e-6));
  REQUIRE(f.similarity == Approx(d.similarity).epsilon(1e-5));
  REQUIRE(f.depth_mad_labels == d.depth_mad_labels);  // integer keypoints: the same pixels
}

// Keyframe selection (cge/frontend): every class template for float and double, and one run of
// each policy and free function template; float and double must take the same decisions on
// integer-valued input.
#define CGE_INSTANTIATE_KEYFRAME(S)                 \
  template struct cge::PatchGrid<S>;                \
  template struct cge::FrameSummary<S>;             \
  template struct cge::KeyframeMeasures<S>;         \
  template struct cge::KeyframeDecision<S>;         \
  template struct cge::PatchKeyframeSettings<S>;    \
  template class cge::PatchKeyframeSelector<S>;     \
  template struct cge::OrbSlam2KeyframeSettings<S>; \
  template class cge::OrbSlam2KeyframePolicy<S>;    \
  template class cge::KeyframePolicy<S>;

CGE_INSTANTIATE_KEYFRAME(float)
CGE_INSTANTIATE_KEYFRAME(double)
#undef CGE_INSTANTIATE_KEYFRAME

namespace {

/// Decisions (rule, keyframe id) of both policies on a fixed integer-valued sequence.
template <typename S>
std::vector<std::pair<int, std::int64_t>> keyframe_run() {
  using Point = Eigen::Matrix<S, 2, 1>;
  const cge::ImageRegion<S> image;
  const cge::PatchGrid<S> grid = cge::PatchKeyframeSelector<S>().grid(image);
  REQUIRE(cge::dense_patch_mean(grid, std::vector<int>(100, 0), 3) == Point(S(320), S(240)));
  REQUIRE(cge::semantic_centroid(std::vector<Point>{Point(S(2), S(4))}).value() == Point(S(2), S(4)));
  std::vector<std::pair<int, std::int64_t>> out;
  cge::KeyframePolicy<S> patch(cge::KeyframePolicyKind::patch);
  cge::KeyframePolicy<S> orb(cge::KeyframePolicyKind::orbslam2);
  for (int t = 0; t < 60; ++t) {
    std::vector<std::array<S, 2>> kps;
    for (int i = 0; i < 400; ++i) {
      kps.push_back({S((i * 37 + t * t * 3) % 640), S((i * 53 + (i * i) % 97 + t * 5) % 480)});
    }
    std::vector<cge::SemanticInstance<S>> instances(static_cast<std::size_t>(t % 7 < 4 ? 1 : 3));
    for (auto& inst : instances) inst.centre_px = Point(S(100 + 4 * t), S(200));
    const cge::FrameSummary<S> summary = cge::make_frame_summary<S>(t, grid, kps, instances, 60 + (t * 29) % 300);
    REQUIRE(summary.patch_counts == cge::count_patch_features(grid, kps));
    const cge::KeyframeDecision<S> a = patch.step(summary);
    const cge::KeyframeDecision<S> b = orb.step(summary);
    out.emplace_back(static_cast<int>(a.rule), a.keyframe_id);
    out.emplace_back(static_cast<int>(b.rule), b.keyframe_id);
  }
  const cge::KeyframeDecision<S> last = patch.flush();
  out.emplace_back(static_cast<int>(last.rule), last.keyframe_id);
  patch.reset();
  orb.reset();
  return out;
}

}  // namespace

TEST_CASE("keyframe policies instantiate and decide alike for float and double", "[instantiation][keyframe]") {
  const auto f = keyframe_run<float>();
  const auto d = keyframe_run<double>();
  REQUIRE(f == d);
  // Not vacuous: both policies inserted keyframes after the first frame.
  int inserted = 0;
  for (std::size_t i = 2; i < d.size(); ++i) inserted += d[i].second != cge::kNoFrame ? 1 : 0;
  REQUIRE(inserted >= 4);
}
