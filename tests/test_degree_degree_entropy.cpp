// Tests of DegreeDegreeEntropy (docs/METHOD.md section 4): compute() against the direct formula
// alpha^E in long double, the worked values of the specification, invariance under relabelling,
// numerics on SLAM-sized graphs and beyond the range of double, edge cases and errors, equal
// exponents of twins, and compute_index() (the bounded search) against compute() and against its
// definition, the entropy of the nodes within G of the heaviest.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/entropy/softmax_entropy.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/graph/twin_classes.hpp"
#include "degree_entropy_test_support.hpp"

using namespace dde_test;

namespace {

/// The entropy of the nodes whose log weight is within g of the heaviest, from full exponents
/// (the definition compute_index() implements), in ascending node order.
double entropy_of_heavy_nodes(const std::vector<double>& exponents, double alpha, double g) {
  const double log_alpha = std::log(alpha);
  double top = -std::numeric_limits<double>::infinity();
  for (const double e : exponents) top = std::max(top, e * log_alpha);
  std::vector<double> kept;
  for (const double e : exponents) {
    if (e * log_alpha - top >= -g) kept.push_back(e * log_alpha);
  }
  return cge::softmax_entropy_bits(kept);
}

}  // namespace

TEST_CASE("DegreeDegreeEntropy::compute agrees with the direct formula on small graphs", "[dde][oracle]") {
  const std::vector<SmallGraph> zoo = small_graph_zoo(120);
  const LD alphas[] = {0.5L, 0.9L, 2.0L};
  const LD lambdas[] = {1.0L, 2.5L};
  const cge::ScalingKind scalings[] = {cge::ScalingKind::raw, cge::ScalingKind::normalised_mean};
  const std::pair<cge::CoefficientKind, LD (*)(int, int)> standard[] = {
      {cge::CoefficientKind::exp, &exp_coefficient},
      {cge::CoefficientKind::linear, &linear_coefficient},
      {cge::CoefficientKind::constant, &constant_coefficient}};
  long long checked = 0;
  for (const SmallGraph& sg : zoo) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      const OracleTable table = oracle_delta(sg, mode);
      for (const LD alpha : alphas) {
        for (const LD lambda : lambdas) {
          for (const cge::ScalingKind scaling : scalings) {
            INFO("graph " << sg.name << ", ties " << tie_name(mode) << ", alpha " << static_cast<double>(alpha)
                          << ", lambda " << static_cast<double>(lambda) << ", normalised "
                          << (scaling == cge::ScalingKind::normalised_mean));
            cge::DegreeDegreeSettings<double> settings;
            settings.alpha = static_cast<double>(alpha);
            settings.lambda = static_cast<double>(lambda);
            settings.ties = mode;
            for (const auto& [kind, oracle_coefficient] : standard) {
              INFO("coefficients " << static_cast<int>(kind));
              cge::DegreeDegreeEntropy<double> dde(settings, cge::StandardCoefficients{kind},
                                                   cge::ExponentScaling{scaling});
              check_against_oracle(dde, g, table, oracle_coefficient);
              ++checked;
            }
            INFO("custom coefficients");
            cge::DegreeDegreeEntropy<double, cge::CustomCoefficients<RampCoefficient>> custom(
                settings, cge::custom_coefficients(RampCoefficient{}), cge::ExponentScaling{scaling});
            check_against_oracle(custom, g, table, &ramp_coefficient);
            ++checked;
          }
        }
      }
    }
  }
  CHECK(checked > 20000);
}

TEST_CASE("DegreeDegreeEntropy: compute equals from_table of the same Delta table", "[dde]") {
  std::mt19937 rng(99);
  for (int trial = 0; trial < 30; ++trial) {
    const SmallGraph sg = random_connected(rng, 30, 40, "t");
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      cge::DegreeDegreeSettings<double> s;
      s.ties = mode;
      s.alpha = 0.7;
      const cge::DegreeDegreeEntropy<double> dde(s);
      const auto a = dde.compute(g);
      const auto b = dde.from_table(cge::shortest_path_degree_sums(g, mode));
      REQUIRE(a.exponents == b.exponents);
      REQUIRE(a.entropy_bits == b.entropy_bits);
      REQUIRE(a.information_index == b.information_index);
      REQUIRE(dde.information_index(g) == a.information_index);
    }
  }
}

// Worked values of docs/METHOD.md section 4 (exp coefficients, log2, lambda = 1).
TEST_CASE("worked values: star K_{1,4}", "[dde][spec]") {
  const cge::Graph<double> g = to_graph(complete_bipartite(1, 4));  // node 0 is the centre
  const cge::StandardCoefficients c;
  REQUIRE(c(1, 2) == Approx(2.0).epsilon(1e-15));
  REQUIRE(c(2, 2) == Approx(2.0 / std::exp(1.0)).epsilon(1e-15));

  cge::DegreeDegreeSettings<double> s;
  s.alpha = 0.5;
  const auto r = cge::DegreeDegreeEntropy<double>(s).compute(g);
  REQUIRE(r.diameter == 2);
  REQUIRE(r.connected);
  REQUIRE(r.exponents[0] == Approx(24.0).epsilon(1e-12));
  for (int leaf = 1; leaf <= 4; ++leaf)
    REQUIRE(r.exponents[static_cast<std::size_t>(leaf)] == Approx(19.2436598821719).epsilon(1e-12));
  REQUIRE(r.entropy_bits == Approx(2.05687613876156).epsilon(1e-12));
  REQUIRE(r.information_index == Approx(0.2650519561258).epsilon(1e-12));
  // The default settings are the specification's (alpha 0.5, lambda 1, exp coefficients, all ties;
  // the paper gives no value for alpha or lambda).
  REQUIRE(cge::DegreeDegreeEntropy<double>().information_index(g) == Approx(0.2650519561258).epsilon(1e-12));
}

TEST_CASE("worked values: path P5", "[dde][spec]") {
  const cge::Graph<double> g = to_graph(path_graph(5));
  const double expected_e[] = {6.41115544457513, 4.54134113294645, 2.94303552937154, 4.54134113294645,
                               6.41115544457513};
  cge::DegreeDegreeSettings<double> s;
  s.alpha = 0.5;
  const auto half = cge::DegreeDegreeEntropy<double>(s).compute(g);
  REQUIRE(half.diameter == 4);
  for (std::size_t v = 0; v < 5; ++v) REQUIRE(half.exponents[v] == Approx(expected_e[v]).epsilon(1e-12));
  REQUIRE(half.entropy_bits == Approx(1.79447339502927).epsilon(1e-12));
  REQUIRE(half.information_index == Approx(0.527454699858088).epsilon(1e-12));
  s.alpha = 2;
  const auto two = cge::DegreeDegreeEntropy<double>(s).compute(g);
  REQUIRE(two.information_index == Approx(0.415966219967475).epsilon(1e-12));
  // P5 has no ties: the three tie modes give the same exponents.
  for (const TieMode mode : kTieModes) {
    s.ties = mode;
    const auto r = cge::DegreeDegreeEntropy<double>(s).compute(g);
    for (std::size_t v = 0; v < 5; ++v) REQUIRE(r.exponents[v] == Approx(expected_e[v]).epsilon(1e-12));
  }
}

TEST_CASE("worked values: Petersen graph has Delta = 0 and I = 0 for any alpha", "[dde][spec]") {
  const cge::Graph<double> g = to_graph(petersen());
  for (const TieMode mode : kTieModes) {
    const cge::DegreeSumTable t = cge::shortest_path_degree_sums(g, mode);
    REQUIRE(t.diameter == 2);
    for (double x : t.values) REQUIRE(x == 0.0);
  }
  for (const double alpha : {0.1, 0.5, 0.9, 0.99, 1.0, 2.0, 7.5}) {
    for (const double lambda : {1.0, 2.5}) {
      INFO("alpha " << alpha << ", lambda " << lambda);
      cge::DegreeDegreeSettings<double> s;
      s.alpha = alpha;
      s.lambda = lambda;
      const auto r = cge::DegreeDegreeEntropy<double>(s).compute(g);
      REQUIRE(r.information_index == Approx(0.0).margin(1e-12));
      REQUIRE(r.entropy_bits == Approx(std::log2(10.0)).epsilon(1e-14));
    }
  }
}

TEST_CASE("DegreeDegreeEntropy is invariant under relabelling of nodes", "[dde][invariance]") {
  std::mt19937 rng(4242);
  std::vector<SmallGraph> graphs;
  for (int i = 0; i < 25; ++i)
    graphs.push_back(random_connected(rng, std::uniform_int_distribution<int>(2, 60)(rng), 50, "c"));
  for (int i = 0; i < 10; ++i)
    graphs.push_back(random_gnp(rng, std::uniform_int_distribution<int>(2, 40)(rng), 0.06, "d"));
  graphs.push_back(grid_graph(6, 7));
  graphs.push_back(with_random_chords(rng, grid_graph(5, 8), 6));
  graphs.push_back(complete_bipartite(5, 9));
  for (const SmallGraph& sg : graphs) {
    const std::vector<int> perm = random_permutation(rng, sg.n);
    const cge::Graph<double> g = to_graph(sg);
    const cge::Graph<double> h = to_graph(relabel(sg, perm));
    for (const TieMode mode : kTieModes) {
      for (const double alpha : {0.5, 0.9, 2.0}) {
        for (const cge::ScalingKind scaling : {cge::ScalingKind::raw, cge::ScalingKind::normalised_mean}) {
          INFO("graph " << sg.name << ", ties " << tie_name(mode) << ", alpha " << alpha);
          cge::DegreeDegreeSettings<double> s;
          s.alpha = alpha;
          s.ties = mode;
          const cge::DegreeDegreeEntropy<double> dde(s, cge::StandardCoefficients{}, cge::ExponentScaling{scaling});
          const auto a = dde.compute(g);
          const auto b = dde.compute(h);
          REQUIRE(a.diameter == b.diameter);
          REQUIRE(a.connected == b.connected);
          for (int v = 0; v < sg.n; ++v) {
            REQUIRE(close(b.exponents[static_cast<std::size_t>(perm[static_cast<std::size_t>(v)])],
                          a.exponents[static_cast<std::size_t>(v)], 1e-12L));
          }
          REQUIRE(close(b.entropy_bits, a.entropy_bits, 1e-12L));
          REQUIRE(close(b.information_index, a.information_index, 1e-12L));
        }
      }
    }
  }
}

TEST_CASE("DegreeDegreeEntropy stays finite and in range on 3000-node geometric graphs", "[dde][numerics]") {
  // A random geometric graph from the frame-graph construction: 3000 random points in 640 x 480,
  // no dense patches.
  const int n = 3000;
  std::mt19937 rng(314159);
  std::uniform_real_distribution<double> ux(0.0, 640.0);
  std::uniform_real_distribution<double> uy(0.0, 480.0);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < n; ++i) points.emplace_back(ux(rng), uy(rng));
  cge::GraphBuilderSettings<double> bs;
  bs.dense_patch_threshold = 1 << 30;
  // R for pi R^2 n / area = 3; the construction's radius growth (2R, 3R, ...) adds edges on top,
  // which brings the mean degree to about 7.
  const double radius = std::sqrt(3.0 * 640.0 * 480.0 / (3.14159265358979 * n));
  bs.radius_fraction_of_diagonal = radius / 800.0;
  const cge::Graph<double> g = cge::GraphBuilder<double>(bs).build(cge::ImageRegion<double>{}, points);
  REQUIRE(g.num_nodes() == n);
  REQUIRE(is_connected(g));
  const double mean_degree = 2.0 * g.num_edges() / n;
  INFO("mean degree " << mean_degree);
  REQUIRE(mean_degree > 5.0);
  REQUIRE(mean_degree < 10.0);

  const double log2n = std::log2(static_cast<double>(n));
  // One O(|V||E|) table (the default tie mode); every (alpha, scaling, lambda) reuses it.
  const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, TieMode::all);
  REQUIRE(table.connected);
  REQUIRE(table.diameter > 10);
  for (const double x : table.values) REQUIRE(std::isfinite(x));
  for (const double alpha : {0.5, 0.9, 0.99, 2.0}) {
    for (const cge::ScalingKind scaling : {cge::ScalingKind::raw, cge::ScalingKind::normalised_mean}) {
      for (const double lambda : {1.0, 2.5}) {
        INFO("alpha " << alpha << ", normalised " << (scaling == cge::ScalingKind::normalised_mean) << ", lambda "
                      << lambda);
        cge::DegreeDegreeSettings<double> s;
        s.alpha = alpha;
        s.lambda = lambda;
        const cge::DegreeDegreeEntropy<double> dde(s, cge::StandardCoefficients{}, cge::ExponentScaling{scaling});
        const auto r = dde.from_table(table);
        REQUIRE(r.exponents.size() == static_cast<std::size_t>(n));
        for (const double e : r.exponents) REQUIRE(std::isfinite(e));
        INFO("H = " << r.entropy_bits << ", I = " << r.information_index
                    << ", max E = " << *std::max_element(r.exponents.begin(), r.exponents.end()));
        REQUIRE(std::isfinite(r.entropy_bits));
        REQUIRE(std::isfinite(r.information_index));
        REQUIRE(r.entropy_bits >= 0.0);
        REQUIRE(r.entropy_bits <= log2n + 1e-9);
        REQUIRE(r.max_entropy_bits == Approx(log2n).epsilon(1e-15));
        REQUIRE(r.information_index == Approx(lambda * (log2n - r.entropy_bits)).epsilon(1e-12).margin(1e-12));
        REQUIRE(r.information_index >= -1e-9);
        REQUIRE(r.diameter == table.diameter);
      }
    }
  }
}

TEST_CASE("DegreeDegreeEntropy: exponents far beyond the range of alpha^E", "[dde][numerics]") {
  // Star K_{1,m}: E(centre) = 2 m (m - 1) and E(leaf) = 2 (m - 1) + (2 / e) (m - 1) 2 (m - 1), so
  // E(centre) - E(leaf) is about 8e4 for m = 400 and alpha^E underflows/overflows any float type.
  const int m = 400;
  const cge::Graph<double> g = to_graph(complete_bipartite(1, m));
  cge::DegreeDegreeSettings<double> s;
  s.alpha = 0.5;  // leaves dominate: the centre's weight relative to a leaf is 2^-(8e4)
  const auto small_alpha = cge::DegreeDegreeEntropy<double>(s).compute(g);
  const double ec = 2.0 * m * (m - 1);
  const double el = 2.0 * (m - 1) + 2.0 / std::exp(1.0) * (m - 1) * 2.0 * (m - 1);
  REQUIRE(small_alpha.exponents[0] == Approx(ec).epsilon(1e-12));
  REQUIRE(small_alpha.exponents[1] == Approx(el).epsilon(1e-12));
  REQUIRE(ec - el > 5e4);
  REQUIRE(small_alpha.entropy_bits == Approx(std::log2(static_cast<double>(m))).epsilon(1e-13));
  s.alpha = 2;  // the centre takes all the mass
  const auto big_alpha = cge::DegreeDegreeEntropy<double>(s).compute(g);
  REQUIRE(big_alpha.entropy_bits == Approx(0.0).margin(1e-12));
  REQUIRE(big_alpha.information_index == Approx(std::log2(static_cast<double>(m + 1))).epsilon(1e-14));
}

TEST_CASE("DegreeDegreeEntropy: path counts beyond the range of double", "[dde][numerics]") {
  // A chain of 345 "diamonds" of width 8: 8^345 = 2^1035 shortest paths between the chain's ends.
  // TieMode::all must say so (std::overflow_error), never return a silently wrong entropy;
  // TieMode::min needs no counts and must stay exact.
  const int width = 8;
  const int diamonds = 345;
  SmallGraph sg{"diamond chain", 1, {}};
  for (int i = 0; i < diamonds; ++i) {
    const int junction = sg.n - 1;
    const int next = sg.n + width;
    for (int m = 0; m < width; ++m) {
      sg.edges.push_back({junction, sg.n + m});
      sg.edges.push_back({sg.n + m, next});
    }
    sg.n += width + 1;
  }
  const cge::Graph<double> g = to_graph(sg);
  cge::DegreeDegreeSettings<double> s;
  s.ties = TieMode::all;
  CHECK_THROWS_AS(cge::DegreeDegreeEntropy<double>(s).compute(g), std::overflow_error);
  s.ties = TieMode::min;
  const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, TieMode::min);
  require_table_matches(table, scalar_bfs_delta(sg, TieMode::min));
  const auto r = cge::DegreeDegreeEntropy<double>(s).from_table(table);
  CHECK(std::isfinite(r.entropy_bits));
  CHECK(std::isfinite(r.information_index));

  // TieMode::mean needs only S / N, so it must not overflow either. The scalar reference keeps
  // its counts in long double, which holds 2^1035 where long double is wider than double.
  s.ties = TieMode::mean;
  const cge::DegreeSumTable mean_table = cge::shortest_path_degree_sums(g, TieMode::mean);
  const auto r_mean = cge::DegreeDegreeEntropy<double>(s).from_table(mean_table);
  CHECK(std::isfinite(r_mean.entropy_bits));
  CHECK(std::isfinite(r_mean.information_index));
  if (std::numeric_limits<LD>::max_exponent > 1100) {
    require_table_matches(mean_table, scalar_bfs_delta(sg, TieMode::mean));
  } else {
    WARN("long double has no wider range than double here: mean-mode values not checked against the reference");
  }
}

TEST_CASE("DegreeDegreeEntropy edge cases", "[dde][errors]") {
  const cge::DegreeDegreeEntropy<double> dde;
  SECTION("empty graph") {
    const cge::Graph<double> empty;
    CHECK_THROWS_AS(dde.compute(empty), std::invalid_argument);
    CHECK_THROWS_AS(cge::shortest_path_degree_sums(empty), std::invalid_argument);
    CHECK_THROWS_AS(dde.from_table(cge::DegreeSumTable{}), std::invalid_argument);
    CHECK_THROWS_AS(dde.compute(cge::Graph<double>::from_edges(0, {}, false)), std::invalid_argument);
  }
  SECTION("one node") {
    const auto r = dde.compute(cge::Graph<double>::from_edges(1, {}, false));
    CHECK(r.entropy_bits == 0.0);
    CHECK(r.information_index == 0.0);
    CHECK(r.diameter == 0);
    CHECK(r.connected);
    REQUIRE(r.exponents.size() == 1);
    CHECK(r.exponents[0] == 0.0);
  }
  SECTION("isolated nodes: disconnected, diameter 0, uniform distribution") {
    const auto r = dde.compute(cge::Graph<double>::from_edges(4, {}, false));
    CHECK_FALSE(r.connected);
    CHECK(r.diameter == 0);
    CHECK(r.entropy_bits == Approx(2.0).epsilon(1e-15));
    CHECK(r.information_index == Approx(0.0).margin(1e-15));
  }
  SECTION("disconnected: diameter is the largest finite distance") {
    // P3 + P6 + an isolated node: largest finite distance 5 (inside P6).
    const SmallGraph sg = disjoint_union(path_graph(3), disjoint_union(path_graph(6), isolated(1)));
    const auto r = dde.compute(to_graph(sg));
    CHECK_FALSE(r.connected);
    CHECK(r.diameter == 5);
    const auto t = cge::shortest_path_degree_sums(to_graph(sg));
    CHECK(t.eccentricity(0) == 2);
    CHECK(t.eccentricity(3) == 5);
    CHECK(t.eccentricity(9) == 0);
    CHECK(std::isfinite(r.entropy_bits));
    // A connected graph reports connected.
    CHECK(dde.compute(to_graph(path_graph(4))).connected);
  }
  SECTION("invalid alpha and lambda") {
    const cge::Graph<double> g = to_graph(path_graph(4));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    for (const double alpha : {0.0, -0.5, nan, inf}) {
      INFO("alpha " << alpha);
      cge::DegreeDegreeSettings<double> s;
      s.alpha = alpha;
      const cge::DegreeDegreeEntropy<double> bad(s);
      CHECK_THROWS_AS(bad.compute(g), std::invalid_argument);
      CHECK_THROWS_WITH(bad.compute(g), Catch::Contains("alpha"));
      CHECK_THROWS_AS(bad.from_table(cge::shortest_path_degree_sums(g)), std::invalid_argument);
    }
    for (const double lambda : {0.0, -1.0, nan, inf}) {
      INFO("lambda " << lambda);
      cge::DegreeDegreeSettings<double> s;
      s.lambda = lambda;
      const cge::DegreeDegreeEntropy<double> bad(s);
      CHECK_THROWS_AS(bad.compute(g), std::invalid_argument);
      CHECK_THROWS_WITH(bad.compute(g), Catch::Contains("lambda"));
    }
  }
}

TEST_CASE("twins have the same exponent in every tie mode (the swap is an automorphism)", "[dde][twins]") {
  std::mt19937 rng(1414);
  std::vector<SmallGraph> graphs;
  for (int i = 0; i < 40; ++i) {
    graphs.push_back(with_planted_twins(rng, random_connected(rng, 20 + i, 10 + i, "t" + std::to_string(i)), 8));
  }
  graphs.push_back(with_planted_twins(rng, geometric_graph(400, 29), 60));
  graphs.push_back(star_of_cliques(5, 6));
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    const cge::TwinClasses twins = cge::twin_classes(g);
    for (const TieMode mode : kTieModes) {
      INFO(sg.name << ", ties " << tie_name(mode));
      cge::DegreeDegreeSettings<double> s;
      s.ties = mode;
      const auto full = cge::DegreeDegreeEntropy<double>(s).compute(g);
      for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
        const double mine = full.exponents[static_cast<std::size_t>(v)];
        const double theirs =
            full.exponents[static_cast<std::size_t>(twins.representative[static_cast<std::size_t>(v)])];
        REQUIRE(mine == Approx(theirs).epsilon(1e-12));
      }
    }
  }
}

TEST_CASE("compute_index agrees with compute on H, I, diameter and connectivity", "[dde][index]") {
  std::vector<SmallGraph> graphs = small_graph_zoo(120);
  std::mt19937 rng(777);
  graphs.push_back(geometric_graph(400, 21));
  graphs.push_back(geometric_graph(900, 22));
  graphs.push_back(decorated_grid(15, 15, false));
  graphs.push_back(star_of_cliques(4, 7));
  graphs.push_back(disjoint_union(geometric_graph(200, 23), random_gnp(rng, 60, 0.03, "sparse")));
  for (int i = 0; i < 20; ++i) {  // twins: searched once per class
    graphs.push_back(with_planted_twins(rng, random_connected(rng, 30 + i, 15, "tw" + std::to_string(i)), 10));
  }
  graphs.push_back(with_planted_twins(rng, geometric_graph(300, 24), 50));
  const cge::CoefficientKind kinds[] = {cge::CoefficientKind::exp, cge::CoefficientKind::linear,
                                        cge::CoefficientKind::constant};
  int pruned_graphs = 0;
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    if (g.num_nodes() == 0) continue;
    for (const TieMode mode : kTieModes) {
      for (const double alpha : {0.2, 0.5, 0.9, 0.99}) {
        for (const cge::CoefficientKind kind : kinds) {
          cge::DegreeDegreeSettings<double> s;
          s.ties = mode;
          s.alpha = alpha;
          s.lambda = 1.5;
          const cge::DegreeDegreeEntropy<double> dde(s, cge::StandardCoefficients{kind});
          INFO(sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode) << ", alpha " << alpha);
          const auto full = dde.compute(g);
          const auto index = dde.compute_index(g);
          REQUIRE(index.diameter == full.diameter);
          REQUIRE(index.connected == full.connected);
          REQUIRE(index.max_entropy_bits == full.max_entropy_bits);
          REQUIRE(index.entropy_bits == Approx(full.entropy_bits).margin(1e-12));
          REQUIRE(index.information_index == Approx(full.information_index).margin(1e-12));
          REQUIRE(dde.information_index(g) == index.information_index);
          REQUIRE(index.exponents.empty());
          REQUIRE(index.exponents_evaluated >= 1);
          REQUIRE(index.exponents_evaluated <= g.num_nodes());
          if (index.exponents_evaluated < g.num_nodes()) ++pruned_graphs;
        }
      }
    }
  }
  CHECK(pruned_graphs > 100);  // the bounded search did leave nodes out
}

TEST_CASE("compute_index: exactly the entropy of the nodes within G of the heaviest, within the bound",
          "[dde][index]") {
  // With a small G many nodes sit near the cut, so a wrong cut or a lost node shows.
  std::vector<SmallGraph> graphs;
  std::mt19937 rng(99);
  for (int i = 0; i < 30; ++i) graphs.push_back(random_connected(rng, 40 + i, 20 + i, "r" + std::to_string(i)));
  graphs.push_back(geometric_graph(300, 5));
  graphs.push_back(decorated_grid(10, 12, true));
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      for (const double cut : {1.0, 3.0, 10.0}) {
        for (const double alpha : {0.5, 0.95}) {
          cge::DegreeDegreeSettings<double> s;
          s.ties = mode;
          s.alpha = alpha;
          s.negligible_log_weight = cut;
          const cge::DegreeDegreeEntropy<double> dde(s);
          INFO(sg.name << ", ties " << tie_name(mode) << ", G " << cut << ", alpha " << alpha);
          const auto full = dde.compute(g);
          const auto index = dde.compute_index(g);
          REQUIRE(index.entropy_bits == Approx(entropy_of_heavy_nodes(full.exponents, alpha, cut)).margin(1e-13));
          // The documented bound on what leaving nodes out changes.
          const double log_alpha = std::log(alpha);
          double top = -std::numeric_limits<double>::infinity();
          for (const double e : full.exponents) top = std::max(top, e * log_alpha);
          int left_out = 0;
          for (const double e : full.exponents) left_out += e * log_alpha - top < -cut;
          const double n = static_cast<double>(g.num_nodes());
          const double bound = left_out * std::exp(-cut) * (1.0 + cut + std::log(n)) / std::log(2.0);
          REQUIRE(std::fabs(index.entropy_bits - full.entropy_bits) <= bound + 1e-12);
        }
      }
    }
  }
}

TEST_CASE("compute_index falls back to every node where the bound does not apply", "[dde][index]") {
  const cge::Graph<double> g = to_graph(geometric_graph(200, 8));
  const auto same_as_compute = [&](const auto& dde) {
    const auto full = dde.compute(g);
    const auto index = dde.compute_index(g);
    CHECK(index.entropy_bits == full.entropy_bits);
    CHECK(index.information_index == full.information_index);
    CHECK(index.diameter == full.diameter);
    CHECK(index.exponents.empty());
    CHECK(index.exponents_evaluated == g.num_nodes());
  };
  cge::DegreeDegreeSettings<double> s;
  SECTION("alpha >= 1: the heavy nodes are those of large E") {
    s.alpha = 1.0;
    same_as_compute(cge::DegreeDegreeEntropy<double>(s));
    s.alpha = 2.0;
    same_as_compute(cge::DegreeDegreeEntropy<double>(s));
  }
  SECTION("exponents scaled by their mean need every exponent") {
    cge::ExponentScaling scaling;
    scaling.kind = cge::ScalingKind::normalised_mean;
    same_as_compute(cge::DegreeDegreeEntropy<double>(s, cge::StandardCoefficients{}, scaling));
  }
  SECTION("a negative coefficient breaks the monotone partial sums") {
    const auto coefficients = cge::custom_coefficients([](int k, int) { return k == 2 ? -0.5 : 1.0; });
    same_as_compute(cge::DegreeDegreeEntropy<double, decltype(coefficients)>(s, coefficients));
  }
  SECTION("G = +infinity asks for every node") {
    s.negligible_log_weight = std::numeric_limits<double>::infinity();
    same_as_compute(cge::DegreeDegreeEntropy<double>(s));
  }
}

TEST_CASE("compute_index: settings and input errors", "[dde][index][errors]") {
  const cge::Graph<double> g = to_graph(path_graph(5));
  for (const double bad : {0.5, 0.0, -3.0, std::numeric_limits<double>::quiet_NaN()}) {
    cge::DegreeDegreeSettings<double> s;
    s.negligible_log_weight = bad;
    const std::string message =
        cge_test::invalid_argument_message([&] { cge::DegreeDegreeEntropy<double>(s).compute_index(g); });
    CHECK_THAT(message, Catch::Contains("negligible_log_weight"));
    CHECK_THROWS_AS(cge::DegreeDegreeEntropy<double>(s).compute(g), std::invalid_argument);
  }
  CHECK_THROWS_AS(cge::DegreeDegreeEntropy<double>().compute_index(cge::Graph<double>{}), std::invalid_argument);
  const auto one = cge::DegreeDegreeEntropy<double>().compute_index(cge::Graph<double>::from_edges(1, {}, false));
  CHECK(one.entropy_bits == 0.0);
  CHECK(one.information_index == 0.0);
  CHECK(one.connected);
  // Worked value through the bounded path: P5 at alpha 0.5.
  CHECK(cge::DegreeDegreeEntropy<double>().compute_index(g).information_index ==
        Approx(0.527454699858088).epsilon(1e-12));
}

TEST_CASE("compute_index on path counts beyond the range of double", "[dde][index][numerics]") {
  // TieMode::all overflows on the chain's long paths. compute() reports it; compute_index() reports
  // it too when a search it needs reaches an overflowing level, and never returns a non-finite value.
  const cge::Graph<double> g = to_graph(diamond_chain(8, 345));
  cge::DegreeDegreeSettings<double> s;
  s.ties = TieMode::all;
  const cge::DegreeDegreeEntropy<double> dde(s);
  CHECK_THROWS_AS(dde.compute(g), std::overflow_error);
  CHECK_THROWS_AS(dde.compute_index(g), std::overflow_error);
  for (const TieMode mode : {TieMode::mean, TieMode::min}) {
    s.ties = mode;
    const auto full = cge::DegreeDegreeEntropy<double>(s).compute(g);
    const auto index = cge::DegreeDegreeEntropy<double>(s).compute_index(g);
    CHECK(std::isfinite(index.information_index));
    CHECK(index.information_index == Approx(full.information_index).margin(1e-12));
  }
}
