// Tests of CGESimilarity (docs/METHOD.md section 6): S_ge, the semantic pre-judgment, the weighted
// combination, and score() against graphs built by hand with GraphBuilder.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cge/core/image_region.hpp"
#include "cge/core/mask.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/entropy/cge_similarity.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/semantic_prejudgment.hpp"
#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/graph_builder.hpp"

namespace {

using P = Eigen::Vector2d;
using Instance = cge::SemanticInstance<double>;
using Entropies = cge::GraphEntropies<double>;

Instance make_instance(double x, double y, int class_id, bool dynamic = false) {
  Instance inst;
  inst.centre_px = P(x, y);
  inst.class_id = class_id;
  inst.dynamic = dynamic;
  return inst;
}

Entropies entropies(double index, double edge_bits) {
  Entropies e;
  e.information_index = index;
  e.edge_entropy_bits = edge_bits;
  return e;
}

/// S_ge written out from the spec: 1 / (1 + |x - y|^a).
double s_ge(double x, double y, int a) { return 1.0 / (1.0 + std::pow(std::fabs(x - y), a)); }

cge::Graph<double> unweighted(int n, const std::vector<std::pair<int, int>>& edges) {
  std::vector<cge::Edge<double>> e;
  for (const auto& [u, v] : edges) e.push_back({u, v, 1.0});
  return cge::Graph<double>::from_edges(n, e, false);
}

cge::SemanticComparison compared(double cosine) {
  cge::SemanticComparison c;
  c.which = cge::SemanticCase::compared;
  c.cosine = cosine;
  return c;
}

}  // namespace

TEST_CASE("entropy_similarity is 1 / (1 + |x - y|^a)", "[similarity]") {
  CHECK(cge::entropy_similarity(0.0, 0.0, 2) == 1.0);
  CHECK(cge::entropy_similarity(1.0, 0.0, 2) == 0.5);
  CHECK(cge::entropy_similarity(3.0, 1.0, 2) == Approx(0.2).epsilon(1e-15));
  CHECK(cge::entropy_similarity(1.0, 3.0, 2) == Approx(0.2).epsilon(1e-15));
  CHECK(cge::entropy_similarity(1.0, 3.0, 3) == Approx(1.0 / 9.0).epsilon(1e-15));
  CHECK(cge::entropy_similarity(0.5, 0.0, 3) == Approx(1.0 / 1.125).epsilon(1e-15));
  CHECK(cge::entropy_similarity(2.0f, 0.0f, 4) == Approx(1.0 / 17.0).epsilon(1e-7));
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int i = 0; i < 200; ++i) {
    const double x = u(rng);
    const double y = u(rng);
    const int a = 2 + i % 4;
    const double s = cge::entropy_similarity(x, y, a);
    CHECK(s == Approx(s_ge(x, y, a)).epsilon(1e-14));
    CHECK(s == cge::entropy_similarity(y, x, a));
    CHECK(s > 0.0);
    CHECK(s <= 1.0);
  }
  CHECK_THROWS_AS(cge::entropy_similarity(1.0, 2.0, 1), std::invalid_argument);
  CHECK_THROWS_AS(cge::entropy_similarity(1.0, 2.0, 0), std::invalid_argument);
  CHECK_THROWS_AS(cge::entropy_similarity(1.0, 2.0, -2), std::invalid_argument);
}

TEST_CASE("CGESimilarity::combine reproduces the paper's example", "[similarity][spec]") {
  // Indices and edge entropies chosen so that S_ge = 0.9053 and 0.925 (a = 2): |dI| = sqrt(1/S - 1).
  const double d_index = std::sqrt(1.0 / 0.9053 - 1.0);
  const double d_edge = std::sqrt(1.0 / 0.925 - 1.0);
  const cge::CGESimilarity<double> sim;
  REQUIRE(sim.settings.degree_weight == 0.5);
  REQUIRE(sim.settings.similarity_exponent == 2);
  const auto score =
      sim.combine(entropies(1.0, 4.0), entropies(1.0 + d_index, 4.0 - d_edge), compared(0.2));  // structure changed
  CHECK(score.used_edge_entropy);
  CHECK(score.degree_similarity == Approx(0.9053).epsilon(1e-12));
  CHECK(score.edge_similarity == Approx(0.925).epsilon(1e-12));
  // 0.5 * 0.9053 + 0.5 * 0.925 = 0.91515, which the paper rounds to 0.9152.
  CHECK(score.similarity == Approx(0.91515).epsilon(1e-12));
  CHECK(score.similarity == Approx(0.9152).margin(1e-4));  // agrees to the paper's four decimals
}

TEST_CASE("S_ge between the K_{1,4} and P5 indices", "[similarity][spec]") {
  const cge::Graph<double> star = unweighted(5, {{0, 1}, {0, 2}, {0, 3}, {0, 4}});
  const cge::Graph<double> path = unweighted(5, {{0, 1}, {1, 2}, {2, 3}, {3, 4}});
  const cge::DegreeDegreeEntropy<double> dde;  // alpha 0.5, lambda 1, exp coefficients
  const double i_star = dde.information_index(star);
  const double i_path = dde.information_index(path);
  CHECK(cge::entropy_similarity(i_star, i_path, 2) == Approx(0.935580422938954).epsilon(1e-12));
  // Through CGESimilarity: same semantic layout, so the degree-degree term alone.
  const cge::CGESimilarity<double> sim;
  const auto score = sim.combine(sim.entropies(star), sim.entropies(path), cge::SemanticComparison{});
  CHECK_FALSE(score.used_edge_entropy);
  CHECK(score.similarity == Approx(0.935580422938954).epsilon(1e-12));
  CHECK(score.current.nodes == 5);
  CHECK(score.current.edges == 4);
  CHECK(score.current.information_index == i_star);
  CHECK(score.candidate.information_index == i_path);
  // Unweighted graphs have unit weights: H_W = log2 4 = 2 for both.
  CHECK(score.current.edge_entropy_bits == Approx(2.0).epsilon(1e-15));
  CHECK(score.edge_similarity == Approx(1.0).epsilon(1e-15));
}

TEST_CASE("semantic pre-judgment", "[similarity][semantics]") {
  const std::vector<Instance> none;
  const std::vector<Instance> only_dynamic{make_instance(10, 10, 0, true), make_instance(20, 20, 0, true)};
  // X_a = {1: 2, 3: 1}, X_b = {1: 1, 3: 2}: cosine (2 + 2) / (sqrt 5 sqrt 5) = 0.8.
  const std::vector<Instance> a{make_instance(1, 1, 1), make_instance(2, 2, 1), make_instance(3, 3, 3),
                                make_instance(4, 4, 0, true)};
  const std::vector<Instance> b{make_instance(5, 5, 3), make_instance(6, 6, 1), make_instance(7, 7, 3)};
  const std::vector<Instance> c{make_instance(5, 5, 9)};

  SECTION("static class counts ignore dynamic instances") {
    const auto counts = cge::static_class_counts(a);
    CHECK(counts.size() == 2);
    CHECK(counts.at(1) == 2);
    CHECK(counts.at(3) == 1);
    CHECK(cge::static_class_counts(only_dynamic).empty());
  }
  SECTION("both empty: unweighted index only") {
    for (const auto* x : {&none, &only_dynamic}) {
      for (const auto* y : {&none, &only_dynamic}) {
        const cge::SemanticComparison s = cge::compare_semantics(*x, *y);
        CHECK(s.which == cge::SemanticCase::both_empty);
        const auto score = cge::CGESimilarity<double>().combine(entropies(0.3, 5.0), entropies(0.8, 2.0), s);
        CHECK_FALSE(score.used_edge_entropy);
        CHECK(score.similarity == Approx(s_ge(0.3, 0.8, 2)).epsilon(1e-14));
        CHECK(score.similarity == score.degree_similarity);
      }
    }
  }
  SECTION("one empty: combined") {
    for (const auto& [x, y] : {std::make_pair(&a, &none), std::make_pair(&only_dynamic, &b)}) {
      const cge::SemanticComparison s = cge::compare_semantics(*x, *y);
      CHECK(s.which == cge::SemanticCase::one_empty);
      const auto score = cge::CGESimilarity<double>().combine(entropies(0.3, 5.0), entropies(0.8, 2.0), s);
      CHECK(score.used_edge_entropy);
      CHECK(score.similarity == Approx(0.5 * s_ge(0.3, 0.8, 2) + 0.5 * s_ge(5.0, 2.0, 2)).epsilon(1e-14));
    }
  }
  SECTION("cosine against the threshold") {
    const cge::SemanticComparison s = cge::compare_semantics(a, b);
    REQUIRE(s.which == cge::SemanticCase::compared);
    CHECK(s.cosine == Approx(0.8).epsilon(1e-15));
    CHECK(cge::compare_semantics(b, a).cosine == Approx(0.8).epsilon(1e-15));
    CHECK(cge::compare_semantics(a, a).cosine == Approx(1.0).epsilon(1e-15));
    CHECK(cge::compare_semantics(a, c).cosine == 0.0);
    // Counts matter, not only classes: {1: 2, 3: 1} vs {1: 4, 3: 2} is the same layout (cosine 1).
    const std::vector<Instance> a2{make_instance(1, 1, 1), make_instance(2, 2, 1), make_instance(3, 3, 3),
                                   make_instance(1, 2, 1), make_instance(2, 1, 1), make_instance(3, 1, 3)};
    CHECK(cge::compare_semantics(a, a2).cosine == Approx(1.0).epsilon(1e-15));

    cge::CGESimilarity<double> sim;
    const Entropies cur = entropies(0.3, 5.0);
    const Entropies cand = entropies(0.8, 2.0);
    const double unweighted_only = s_ge(0.3, 0.8, 2);
    const double combined = 0.5 * s_ge(0.3, 0.8, 2) + 0.5 * s_ge(5.0, 2.0, 2);
    REQUIRE(unweighted_only != Approx(combined));
    sim.settings.semantic_threshold = 0.95;  // 0.8 < 0.95: structure changed
    CHECK(sim.combine(cur, cand, s).similarity == Approx(combined).epsilon(1e-14));
    CHECK(sim.combine(cur, cand, s).used_edge_entropy);
    sim.settings.semantic_threshold = 0.5;  // 0.8 >= 0.5: same layout
    CHECK(sim.combine(cur, cand, s).similarity == Approx(unweighted_only).epsilon(1e-14));
    CHECK_FALSE(sim.combine(cur, cand, s).used_edge_entropy);
    sim.settings.semantic_threshold = 1.0;  // cosine exactly 1 is "at or above"
    CHECK_FALSE(sim.combine(cur, cand, cge::compare_semantics(a, a)).used_edge_entropy);
    CHECK(sim.combine(cur, cand, compared(0.999999)).used_edge_entropy);
    sim.settings.semantic_threshold = 0.8;  // exactly at the threshold: same layout
    CHECK_FALSE(sim.combine(cur, cand, compared(0.8)).used_edge_entropy);
    // mu weights the two terms.
    sim.settings.semantic_threshold = 0.95;
    sim.settings.degree_weight = 0.25;
    CHECK(sim.combine(cur, cand, s).similarity ==
          Approx(0.25 * s_ge(0.3, 0.8, 2) + 0.75 * s_ge(5.0, 2.0, 2)).epsilon(1e-14));
    sim.settings.similarity_exponent = 3;
    CHECK(sim.combine(cur, cand, s).similarity ==
          Approx(0.25 * s_ge(0.3, 0.8, 3) + 0.75 * s_ge(5.0, 2.0, 3)).epsilon(1e-14));
  }
}

TEST_CASE("CGESimilarity rejects bad settings", "[similarity][errors]") {
  const Entropies e = entropies(0.1, 1.0);
  const cge::SemanticComparison s;
  auto with = [&](auto change) {
    cge::CGESimilarity<double> sim;
    change(sim.settings);
    return sim;
  };
  using S = cge::CGESimilaritySettings<double>;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(with([](S& x) { x.degree_weight = 1.5; }).combine(e, e, s), std::invalid_argument);
  CHECK_THROWS_AS(with([](S& x) { x.degree_weight = -0.1; }).combine(e, e, s), std::invalid_argument);
  CHECK_THROWS_AS(with([&](S& x) { x.degree_weight = nan; }).combine(e, e, s), std::invalid_argument);
  CHECK_THROWS_WITH(with([](S& x) { x.degree_weight = 2; }).combine(e, e, s), Catch::Contains("degree_weight"));
  CHECK_THROWS_AS(with([&](S& x) { x.semantic_threshold = nan; }).combine(e, e, s), std::invalid_argument);
  CHECK_THROWS_WITH(with([](S& x) { x.similarity_exponent = 1; }).combine(e, e, s),
                    Catch::Contains("similarity_exponent"));
  // The extremes of mu are valid.
  CHECK_NOTHROW(with([](S& x) { x.degree_weight = 0; }).combine(e, e, s));
  CHECK_NOTHROW(with([](S& x) { x.degree_weight = 1; }).combine(e, e, s));
}

namespace {

struct Frame {
  std::vector<P> keypoints;
  cge::BinaryMask mask;
  std::vector<Instance> instances;
};

Frame random_frame(std::mt19937& rng, int n, int with_person) {
  Frame f;
  std::uniform_real_distribution<double> ux(0.0, 640.0);
  std::uniform_real_distribution<double> uy(0.0, 480.0);
  for (int i = 0; i < n; ++i) f.keypoints.emplace_back(ux(rng), uy(rng));
  f.mask = cge::BinaryMask(640, 480);
  for (int k = 0; k < with_person; ++k) {
    const int x0 = std::uniform_int_distribution<int>(0, 500)(rng);
    const int y0 = std::uniform_int_distribution<int>(0, 300)(rng);
    for (int y = y0; y < y0 + 150; ++y)
      for (int x = x0; x < x0 + 100; ++x) f.mask.at(x, y) = 1;
    f.instances.push_back(make_instance(x0 + 50.0, y0 + 75.0, 0, true));
  }
  const int objects = std::uniform_int_distribution<int>(0, 4)(rng);
  for (int i = 0; i < objects; ++i) {
    f.instances.push_back(make_instance(ux(rng), uy(rng), std::uniform_int_distribution<int>(56, 60)(rng)));
  }
  return f;
}

}  // namespace

TEST_CASE("CGESimilarity::score equals building both graphs by hand and combining", "[similarity]") {
  std::mt19937 rng(4711);
  const cge::ImageRegion<double> image;  // 640 x 480
  cge::CGESimilarity<double> sim;
  sim.graph_builder.settings.dense_patch_threshold = 8;
  const cge::DegreeDegreeEntropy<double> dde;
  const cge::ShannonEdgeEntropy<double> shannon;
  int combined_cases = 0;
  int unweighted_cases = 0;
  int partner_mask_mattered = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const Frame cur = random_frame(rng, std::uniform_int_distribution<int>(1, 400)(rng), trial % 3);
    Frame cand = random_frame(rng, std::uniform_int_distribution<int>(1, 400)(rng), (trial / 3) % 2);
    if (trial % 2 == 0) {
      // A revisit: the same static objects seen from elsewhere (same classes, other positions).
      cand.instances.erase(
          std::remove_if(cand.instances.begin(), cand.instances.end(), [](const Instance& i) { return !i.dynamic; }),
          cand.instances.end());
      for (const Instance& inst : cur.instances) {
        if (!inst.dynamic) {
          cand.instances.push_back(
              make_instance(640.0 - inst.centre_px.x(), 480.0 - inst.centre_px.y(), inst.class_id));
        }
      }
    }
    // Each graph is built with respect to the other frame's mask.
    const cge::Graph<double> g_cur = sim.graph_builder.build(image, cur.keypoints, cur.mask, cand.mask, cur.instances);
    const cge::Graph<double> g_cand =
        sim.graph_builder.build(image, cand.keypoints, cand.mask, cur.mask, cand.instances);
    partner_mask_mattered +=
        g_cur != sim.graph_builder.build(image, cur.keypoints, cur.mask, cge::NoMask{}, cur.instances);
    const double i_cur = dde.information_index(g_cur);
    const double i_cand = dde.information_index(g_cand);
    const double h_cur = shannon.compute(g_cur);
    const double h_cand = shannon.compute(g_cand);
    const cge::SemanticComparison sem = cge::compare_semantics(cur.instances, cand.instances);
    const bool combine = sem.which == cge::SemanticCase::one_empty ||
                         (sem.which == cge::SemanticCase::compared && sem.cosine < sim.settings.semantic_threshold);
    const double expected =
        combine ? 0.5 * s_ge(i_cur, i_cand, 2) + 0.5 * s_ge(h_cur, h_cand, 2) : s_ge(i_cur, i_cand, 2);
    combined_cases += combine;
    unweighted_cases += !combine;

    const auto score = sim.score(image, cge::frame_view(cur.keypoints, cur.mask, cur.instances),
                                 cge::frame_view(cand.keypoints, cand.mask, cand.instances));
    INFO("trial " << trial);
    CHECK(score.similarity == Approx(expected).epsilon(1e-14));
    CHECK(score.used_edge_entropy == combine);
    CHECK(score.current.information_index == i_cur);
    CHECK(score.candidate.information_index == i_cand);
    CHECK(score.current.edge_entropy_bits == h_cur);
    CHECK(score.candidate.edge_entropy_bits == h_cand);
    CHECK(score.current.nodes == g_cur.num_nodes());
    CHECK(score.candidate.edges == g_cand.num_edges());
    CHECK(score.semantics.which == sem.which);
    CHECK(score.semantics.cosine == sem.cosine);
    // And combine() on the per-graph values gives the same score.
    CHECK(sim.combine(sim.entropies(g_cur), sim.entropies(g_cand), sem).similarity == score.similarity);
    // Swapping the frames swaps the roles and keeps the similarity.
    const auto swapped = sim.score(image, cge::frame_view(cand.keypoints, cand.mask, cand.instances),
                                   cge::frame_view(cur.keypoints, cur.mask, cur.instances));
    CHECK(swapped.similarity == score.similarity);
    CHECK(swapped.current.information_index == score.candidate.information_index);
  }
  CHECK(combined_cases > 5);
  CHECK(unweighted_cases > 5);
  CHECK(partner_mask_mattered > 5);
}

TEST_CASE("CGESimilarity::score of a frame with itself is 1", "[similarity]") {
  std::mt19937 rng(1001);
  const cge::ImageRegion<double> image;
  const cge::CGESimilarity<double> sim;
  for (int trial = 0; trial < 20; ++trial) {
    const Frame f = random_frame(rng, std::uniform_int_distribution<int>(2, 300)(rng), trial % 2);
    // The same content in another input order is the same frame.
    Frame g = f;
    std::shuffle(g.keypoints.begin(), g.keypoints.end(), rng);
    std::shuffle(g.instances.begin(), g.instances.end(), rng);
    const auto score = sim.score(image, cge::frame_view(f.keypoints, f.mask, f.instances),
                                 cge::frame_view(g.keypoints, g.mask, g.instances));
    CHECK(score.similarity == 1.0);
    CHECK(score.degree_similarity == 1.0);
    CHECK(score.edge_similarity == 1.0);
  }
  // Frames without masks through NoMask.
  const std::vector<P> kps{P(100, 100), P(120, 110), P(300, 200), P(320, 240), P(500, 400)};
  const std::vector<Instance> none;
  const cge::NoMask no_mask;
  const auto score = sim.score(image, cge::frame_view(kps, no_mask, none), cge::frame_view(kps, no_mask, none));
  CHECK(score.similarity == 1.0);
  CHECK(score.semantics.which == cge::SemanticCase::both_empty);
}

TEST_CASE("CGESimilarity::score names the frame whose graph is empty", "[similarity][errors]") {
  const cge::ImageRegion<double> image;
  const cge::CGESimilarity<double> sim;
  // Every keypoint of the current frame lies under its dynamic mask (x < 320), no instances.
  cge::BinaryMask left_half(640, 480);
  for (int row = 0; row < 480; ++row) {
    for (int col = 0; col < 320; ++col) left_half.at(col, row) = 1;
  }
  const std::vector<P> masked{P(100, 100), P(200, 300)};
  const std::vector<P> visible{P(400, 100), P(500, 300)};
  const std::vector<Instance> none;
  const cge::NoMask no_mask;
  // The candidate's keypoints are at x >= 320, so the current frame's mask does not hide them.
  CHECK_THROWS_WITH(sim.score(image, cge::frame_view(masked, left_half, none), cge::frame_view(visible, no_mask, none)),
                    Catch::Contains("current frame's graph has no nodes"));
  CHECK_THROWS_WITH(sim.score(image, cge::frame_view(visible, no_mask, none), cge::frame_view(masked, left_half, none)),
                    Catch::Contains("candidate frame's graph has no nodes"));
}
