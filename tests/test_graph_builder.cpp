// Tests of GraphBuilder (docs/METHOD.md section 3): a naive reference implementation written from
// the spec (node selection and the round-based edge construction, brute force over an adjacency
// matrix) compared with both neighbour-search policies; property tests for every property the
// spec lists; node selection; errors.
#include <rapidcheck/catch.h>
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cge/core/image_region.hpp"
#include "cge/core/mask.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/graph/neighbor_search.hpp"
#include "test_support.hpp"

namespace {

using P = Eigen::Vector2d;
using Image = cge::ImageRegion<double>;
using Instance = cge::SemanticInstance<double>;
using Settings = cge::GraphBuilderSettings<double>;
using GridBuilder = cge::GraphBuilder<double, cge::GridNeighborSearch<double>>;
using BruteBuilder = cge::GraphBuilder<double, cge::BruteForceNeighborSearch<double>>;
using cge::NodeKind;

using cge_test::invalid_argument_message;
using cge_test::is_connected;

/// The grid scan kernels this machine can run for Scalar coordinates.
template <typename Scalar>
std::vector<cge::GridScanKernel> available_scan_kernels() {
  std::vector<cge::GridScanKernel> kernels{cge::GridScanKernel::automatic, cge::GridScanKernel::portable};
  if (cge::GridNeighborSearch<Scalar>::scan_kernel_available(cge::GridScanKernel::avx512)) {
    kernels.push_back(cge::GridScanKernel::avx512);
  }
  return kernels;
}

Image make_image(double width, double height, P origin = P::Zero()) {
  Image img;
  img.width_px = width;
  img.height_px = height;
  img.origin_px = origin;
  return img;
}

Instance make_instance(double x, double y, int class_id, bool dynamic) {
  Instance inst;
  inst.centre_px = P(x, y);
  inst.class_id = class_id;
  inst.dynamic = dynamic;
  return inst;
}

// =============================================================================================
// Naive reference implementation of docs/METHOD.md section 3
// =============================================================================================

struct RefEdge {
  int u;
  int v;
  double weight;
  std::uint8_t round;  // 1, 2, ... or 0 (cge::kStrayJoin) for stray joins
};

struct RefGraph {
  std::vector<P> positions;
  std::vector<NodeKind> kinds;
  std::vector<RefEdge> edges;  // u < v, sorted by (u, v)
};

/// Node selection: stable features (in neither mask), dense patches replaced by their centre,
/// static semantic instances; sorted by (y, x, kind); exact duplicates merged (first kept).
/// Masks may be null (no dynamic objects) or empty.
void ref_nodes(const Image& img, const std::vector<P>& keypoints, const cge::BinaryMask* own,
               const cge::BinaryMask* partner, const std::vector<Instance>& instances, const Settings& s,
               RefGraph& out) {
  const int cols = s.patch_cols;
  const int rows = s.patch_rows;
  const double pw = img.width_px / cols;
  const double ph = img.height_px / rows;
  const int mask_w = static_cast<int>(std::lround(img.width_px));
  const int mask_h = static_cast<int>(std::lround(img.height_px));
  auto masked = [&](const cge::BinaryMask* m, const P& rel) {
    if (m == nullptr || m->pixels.empty()) return false;
    const int col = std::min(static_cast<int>(std::lround(rel.x())), mask_w - 1);
    const int row = std::min(static_cast<int>(std::lround(rel.y())), mask_h - 1);
    return m->pixels[static_cast<std::size_t>(row) * static_cast<std::size_t>(m->width) +
                     static_cast<std::size_t>(col)] != 0;
  };
  std::vector<std::vector<std::vector<P>>> patch(static_cast<std::size_t>(rows),
                                                 std::vector<std::vector<P>>(static_cast<std::size_t>(cols)));
  for (const P& kp : keypoints) {
    const P rel = kp - img.origin_px;
    if (masked(own, rel) || masked(partner, rel)) continue;
    // The patch whose half-open rectangle holds the point; the last column/row also holds the far border.
    int pc = 0;
    while (pc + 1 < cols && rel.x() >= (pc + 1) * pw) ++pc;
    int pr = 0;
    while (pr + 1 < rows && rel.y() >= (pr + 1) * ph) ++pr;
    patch[static_cast<std::size_t>(pr)][static_cast<std::size_t>(pc)].push_back(kp);
  }
  std::vector<std::tuple<double, double, int>> nodes;  // (y, x, kind)
  for (int pr = 0; pr < rows; ++pr) {
    for (int pc = 0; pc < cols; ++pc) {
      const auto& members = patch[static_cast<std::size_t>(pr)][static_cast<std::size_t>(pc)];
      if (static_cast<int>(members.size()) > s.dense_patch_threshold) {
        nodes.emplace_back(img.origin_px.y() + (pr + 0.5) * ph, img.origin_px.x() + (pc + 0.5) * pw,
                           static_cast<int>(NodeKind::representation));
      } else {
        for (const P& p : members) nodes.emplace_back(p.y(), p.x(), static_cast<int>(NodeKind::feature));
      }
    }
  }
  for (const Instance& inst : instances) {
    if (!inst.dynamic) nodes.emplace_back(inst.centre_px.y(), inst.centre_px.x(), static_cast<int>(NodeKind::semantic));
  }
  std::sort(nodes.begin(), nodes.end());
  out.positions.clear();
  out.kinds.clear();
  for (const auto& [y, x, kind] : nodes) {
    if (!out.positions.empty() && out.positions.back().x() == x && out.positions.back().y() == y) continue;
    out.positions.emplace_back(x, y);
    out.kinds.push_back(static_cast<NodeKind>(kind));
  }
}

/// Edge construction over nodes in canonical order, straight from the spec.
std::vector<RefEdge> ref_edges(const Image& img, const std::vector<P>& pts, const Settings& s) {
  const int n = static_cast<int>(pts.size());
  std::vector<RefEdge> edges;
  if (n < 2) return edges;
  const double R =
      s.radius_fraction_of_diagonal * std::sqrt(img.width_px * img.width_px + img.height_px * img.height_px);
  const double cap = s.capped_radius_multiple * R;
  auto d2 = [&](int a, int b) {
    const double dx = pts[static_cast<std::size_t>(a)].x() - pts[static_cast<std::size_t>(b)].x();
    const double dy = pts[static_cast<std::size_t>(a)].y() - pts[static_cast<std::size_t>(b)].y();
    return dx * dx + dy * dy;
  };
  std::vector<std::vector<char>> adj(static_cast<std::size_t>(n), std::vector<char>(static_cast<std::size_t>(n), 0));
  std::vector<char> flag(static_cast<std::size_t>(n), 0);
  auto joined = [&](int a, int b) -> char& { return adj[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)]; };
  auto add_edge = [&](int a, int b, std::uint8_t round) {
    joined(a, b) = joined(b, a) = 1;
    edges.push_back(RefEdge{std::min(a, b), std::max(a, b), std::sqrt(d2(a, b)), round});
  };

  // v0: nearest to the image centre (lowest index on ties).
  const P centre = img.origin_px + P(img.width_px / 2, img.height_px / 2);
  int v0 = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const double dx = pts[static_cast<std::size_t>(i)].x() - centre.x();
    const double dy = pts[static_cast<std::size_t>(i)].y() - centre.y();
    if (dx * dx + dy * dy < best) {
      best = dx * dx + dy * dy;
      v0 = i;
    }
  }
  flag[static_cast<std::size_t>(v0)] = 1;

  std::vector<int> centres{v0};
  for (int round = 1; !centres.empty(); ++round) {
    std::vector<int> next;
    for (const int c : centres) {
      // A search can only succeed when some node is not yet joined to c.
      bool any_free = false;
      for (int j = 0; j < n; ++j) any_free = any_free || (j != c && !joined(c, j));
      if (!any_free) continue;
      for (int t = 1;; ++t) {
        double r = R * std::pow(2.0, t - 1);
        const bool capped = round >= s.first_capped_round;
        if (capped) r = std::min(r, cap);
        bool created = false;
        for (int j = 0; j < n; ++j) {
          if (j == c || joined(c, j) || d2(c, j) > r * r) continue;
          add_edge(c, j, static_cast<std::uint8_t>(std::min(round, 255)));
          created = true;
          if (!flag[static_cast<std::size_t>(j)]) {
            flag[static_cast<std::size_t>(j)] = 1;
            next.push_back(j);
          }
        }
        if (created) break;
        if (capped && r >= cap) break;  // nothing new within the cap: no edge
      }
    }
    std::sort(next.begin(), next.end());
    centres = next;
  }

  // Stray nodes: nearest first, each to its nearest node already in the graph; ties by smaller
  // distance, then lower stray index, then lower target index.
  std::vector<char> in_graph(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    bool has_edge = false;
    for (int j = 0; j < n; ++j) has_edge = has_edge || joined(i, j);
    in_graph[static_cast<std::size_t>(i)] = (has_edge || i == v0) ? 1 : 0;
  }
  for (;;) {
    double best_d = std::numeric_limits<double>::infinity();
    int best_s = -1;
    int best_m = -1;
    for (int a = 0; a < n; ++a) {
      if (in_graph[static_cast<std::size_t>(a)]) continue;
      for (int m = 0; m < n; ++m) {
        if (!in_graph[static_cast<std::size_t>(m)]) continue;
        if (d2(a, m) < best_d) {  // strict: on ties the earlier (a, m) in lexicographic order stays
          best_d = d2(a, m);
          best_s = a;
          best_m = m;
        }
      }
    }
    if (best_s < 0) break;
    add_edge(best_s, best_m, cge::kStrayJoin);
    in_graph[static_cast<std::size_t>(best_s)] = 1;
  }
  std::sort(edges.begin(), edges.end(),
            [](const RefEdge& a, const RefEdge& b) { return std::tie(a.u, a.v) < std::tie(b.u, b.v); });
  return edges;
}

RefGraph ref_build(const Image& img, const std::vector<P>& keypoints, const cge::BinaryMask* own,
                   const cge::BinaryMask* partner, const std::vector<Instance>& instances, const Settings& s) {
  RefGraph g;
  ref_nodes(img, keypoints, own, partner, instances, s, g);
  g.edges = ref_edges(img, g.positions, s);
  return g;
}

/// Full equality of a built graph with the reference: nodes, kinds, edges with weights, rounds.
void require_same(const cge::Graph<double>& g, const RefGraph& ref) {
  REQUIRE(g.num_nodes() == static_cast<std::int32_t>(ref.positions.size()));
  REQUIRE(g.positions() == ref.positions);
  REQUIRE(g.kinds() == ref.kinds);
  REQUIRE(g.weighted());
  REQUIRE(g.num_edges() == static_cast<std::int32_t>(ref.edges.size()));
  REQUIRE(g.edge_rounds().size() == ref.edges.size());
  for (std::size_t i = 0; i < ref.edges.size(); ++i) {
    const auto& e = g.edges()[i];
    const RefEdge& r = ref.edges[i];
    INFO("edge " << i << ": built (" << e.u << ", " << e.v << ", " << e.weight << ", round " << int(g.edge_rounds()[i])
                 << "), reference (" << r.u << ", " << r.v << ", " << r.weight << ", round " << int(r.round) << ")");
    REQUIRE(e.u == r.u);
    REQUIRE(e.v == r.v);
    REQUIRE(e.weight == r.weight);
    REQUIRE(g.edge_rounds()[i] == r.round);
  }
}

// =============================================================================================
// Point-set generators (std::mt19937 with literal seeds)
// =============================================================================================

std::vector<P> uniform_points(std::mt19937& rng, int n, const Image& img) {
  std::uniform_real_distribution<double> ux(img.origin_px.x(), img.origin_px.x() + img.width_px);
  std::uniform_real_distribution<double> uy(img.origin_px.y(), img.origin_px.y() + img.height_px);
  std::vector<P> pts;
  for (int i = 0; i < n; ++i) pts.emplace_back(ux(rng), uy(rng));
  return pts;
}

P clamp_to(const Image& img, P p) {
  p.x() = std::min(std::max(p.x(), img.origin_px.x()), img.origin_px.x() + img.width_px);
  p.y() = std::min(std::max(p.y(), img.origin_px.y()), img.origin_px.y() + img.height_px);
  return p;
}

std::vector<P> clustered_points(std::mt19937& rng, int n, const Image& img, int clusters, double sigma) {
  const std::vector<P> centres = uniform_points(rng, clusters, img);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<P> pts;
  for (int i = 0; i < n; ++i) {
    const P& c = centres[static_cast<std::size_t>(std::uniform_int_distribution<int>(0, clusters - 1)(rng))];
    pts.push_back(clamp_to(img, c + P(noise(rng), noise(rng))));
  }
  return pts;
}

/// A big cluster around the image centre and small ones far away (more than 3R from it, R = 40):
/// the capped rounds cannot reach them, so they are joined as strays.
std::vector<P> far_cluster_points(std::mt19937& rng, const Image& img) {
  std::vector<P> pts;
  const P centre = img.origin_px + P(img.width_px / 2, img.height_px / 2);
  std::uniform_real_distribution<double> angle(0.0, 2 * 3.14159265358979);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int big = std::uniform_int_distribution<int>(20, 60)(rng);
  for (int i = 0; i < big; ++i) {
    const double a = angle(rng);
    const double r = 90.0 * std::sqrt(unit(rng));
    pts.push_back(clamp_to(img, centre + P(r * std::cos(a), r * std::sin(a))));
  }
  const P corners[] = {P(20, 20), P(img.width_px - 20, 20), P(20, img.height_px - 20),
                       P(img.width_px - 20, img.height_px - 20)};
  std::normal_distribution<double> noise(0.0, 4.0);
  for (const P& corner : corners) {
    const int count = std::uniform_int_distribution<int>(0, 5)(rng);
    for (int i = 0; i < count; ++i) pts.push_back(clamp_to(img, img.origin_px + corner + P(noise(rng), noise(rng))));
  }
  // A few lone points along the borders.
  for (int i = 0; i < 3; ++i) {
    pts.push_back(img.origin_px + P(std::uniform_real_distribution<double>(0, img.width_px)(rng), 0.0));
  }
  return pts;
}

/// Points on a coarse lattice (multiples of `step` px): duplicates and exactly tied distances.
std::vector<P> lattice_points(std::mt19937& rng, int n, const Image& img, double step) {
  const int nx = static_cast<int>(img.width_px / step);
  const int ny = static_cast<int>(img.height_px / step);
  std::vector<P> pts;
  for (int i = 0; i < n; ++i) {
    pts.push_back(img.origin_px + P(step * std::uniform_int_distribution<int>(0, nx)(rng),
                                    step * std::uniform_int_distribution<int>(0, ny)(rng)));
  }
  return pts;
}

cge::BinaryMask random_rect_mask(std::mt19937& rng, const Image& img, int rects) {
  const int w = static_cast<int>(std::lround(img.width_px));
  const int h = static_cast<int>(std::lround(img.height_px));
  cge::BinaryMask m(w, h);
  for (int k = 0; k < rects; ++k) {
    const int x0 = std::uniform_int_distribution<int>(0, w - 1)(rng);
    const int y0 = std::uniform_int_distribution<int>(0, h - 1)(rng);
    const int x1 = std::min(w, x0 + std::uniform_int_distribution<int>(1, w / 3)(rng));
    const int y1 = std::min(h, y0 + std::uniform_int_distribution<int>(1, h / 3)(rng));
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) m.at(x, y) = 1;
  }
  return m;
}

std::vector<Instance> random_instances(std::mt19937& rng, const Image& img, int count) {
  std::vector<Instance> out;
  for (const P& p : uniform_points(rng, count, img)) {
    out.push_back(make_instance(p.x(), p.y(), std::uniform_int_distribution<int>(0, 5)(rng), (rng() % 3) == 0));
  }
  return out;
}

}  // namespace

// =============================================================================================
// Hand-worked construction
// =============================================================================================

TEST_CASE("GraphBuilder: a hand-worked construction with growth, cap and a stray", "[builder][spec]") {
  // 640 x 480, R = 5% of 800 = 40 px. All nodes on y = 240, v0 = (320, 240) is the image centre.
  //   v0 (320)  A (330)  B (360)  C (390)  D (520)
  // Round 1: v0 joins A (10) and B (40 = R, inclusive).
  // Round 2 (centres A, B): A joins B (30); B joins C (30). C is new.
  // Round 3 (centre C, capped): nothing new within R; within 2R: A (60) and v0 (70).
  // No new centre: rounds end. D is 130 > 3R from C and was never reached: stray, joined to C.
  const Image img = make_image(640, 480);
  const std::vector<P> kps{P(520, 240), P(330, 240), P(390, 240), P(320, 240), P(360, 240)};
  for (int policy = 0; policy < 2; ++policy) {
    const cge::Graph<double> g = policy == 0 ? GridBuilder().build(img, kps) : BruteBuilder().build(img, kps);
    REQUIRE(GridBuilder().base_radius(img) == 40.0);
    REQUIRE(g.num_nodes() == 5);
    REQUIRE(g.positions() == std::vector<P>{P(320, 240), P(330, 240), P(360, 240), P(390, 240), P(520, 240)});
    const std::vector<cge::Edge<double>> expected{{0, 1, 10.0}, {0, 2, 40.0}, {0, 3, 70.0}, {1, 2, 30.0},
                                                  {1, 3, 60.0}, {2, 3, 30.0}, {3, 4, 130.0}};
    REQUIRE(g.edges() == expected);
    REQUIRE(g.edge_rounds() == std::vector<std::uint8_t>{1, 1, 3, 2, 3, 2, cge::kStrayJoin});
  }
}

TEST_CASE("GraphBuilder: the radius doubles until the first edge in uncapped rounds", "[builder][spec]") {
  // Two nodes 100 px apart with R = 40: attempts at 40 and 80 fail, 160 succeeds in round 1.
  const Image img = make_image(640, 480);
  const cge::Graph<double> g = GridBuilder().build(img, std::vector<P>{P(320, 240), P(420, 240)});
  REQUIRE(g.edges() == std::vector<cge::Edge<double>>{{0, 1, 100.0}});
  REQUIRE(g.edge_rounds() == std::vector<std::uint8_t>{1});
  // Round 2 is uncapped too: a second node far from everything but v0's partner is reached by growth.
  // v0 (320, 240) - A (330, 240) in round 1; A, in round 2, grows to 4R = 160 and finds B at 150.
  const cge::Graph<double> h = GridBuilder().build(img, std::vector<P>{P(320, 240), P(330, 240), P(480, 240)});
  REQUIRE(h.edges() == std::vector<cge::Edge<double>>{{0, 1, 10.0}, {1, 2, 150.0}});
  REQUIRE(h.edge_rounds() == std::vector<std::uint8_t>{1, 2});
  // Empty and single-node inputs.
  REQUIRE(GridBuilder().build(img, std::vector<P>{}).num_nodes() == 0);
  const cge::Graph<double> one = GridBuilder().build(img, std::vector<P>{P(3, 4)});
  REQUIRE(one.num_nodes() == 1);
  REQUIRE(one.num_edges() == 0);
}

// =============================================================================================
// Reference comparison
// =============================================================================================

TEST_CASE("GraphBuilder matches the naive reference with both neighbour searches", "[builder][oracle]") {
  std::mt19937 rng(5150);
  int stray_edges = 0;
  int capped_round_edges = 0;
  int dense_patches = 0;
  int merged_duplicates = 0;
  int exactly_r = 0;
  int masked_away = 0;
  const double fractions[] = {0.01, 0.03, 0.05, 0.1, 0.0625};
  for (int trial = 0; trial < 400; ++trial) {
    // Vary image size and origin.
    Image img = make_image(640, 480);
    if (trial % 7 == 3) img = make_image(320, 240, P(-100.5, 37.25));
    if (trial % 7 == 5) img = make_image(100, 100, P(1000, 2000));
    Settings s;
    s.radius_fraction_of_diagonal = fractions[trial % 5];
    s.dense_patch_threshold = std::uniform_int_distribution<int>(0, 3)(rng) == 0 ? 2 : 15;
    if (trial % 11 == 0) {
      s.patch_cols = 4;
      s.patch_rows = 3;
    }
    const int style = trial % 5;
    std::vector<P> kps;
    switch (style) {
      case 0:
        kps = uniform_points(rng, std::uniform_int_distribution<int>(0, 150)(rng), img);
        break;
      case 1:
        kps = clustered_points(rng, std::uniform_int_distribution<int>(1, 150)(rng), img,
                               std::uniform_int_distribution<int>(1, 5)(rng),
                               std::uniform_real_distribution<double>(2, 30)(rng));
        break;
      case 2:
        kps = far_cluster_points(rng, img);
        s.radius_fraction_of_diagonal = 0.05;
        break;
      case 3:
        kps = lattice_points(rng, std::uniform_int_distribution<int>(1, 150)(rng), img, img.width_px / 64);
        break;
      default:
        // Lattice of 10 px with R = 50 (fraction 1/16 of 800): many distances exactly R, 2R, 3R.
        img = make_image(640, 480);
        s.radius_fraction_of_diagonal = 0.0625;
        kps = lattice_points(rng, std::uniform_int_distribution<int>(1, 120)(rng), img, 10);
        break;
    }
    const bool with_masks = trial % 3 == 0;
    const cge::BinaryMask own = with_masks ? random_rect_mask(rng, img, 2) : cge::BinaryMask();
    const cge::BinaryMask partner = with_masks ? random_rect_mask(rng, img, 1) : cge::BinaryMask();
    const std::vector<Instance> inst = random_instances(rng, img, std::uniform_int_distribution<int>(0, 4)(rng));

    INFO("trial " << trial << ", style " << style << ", " << kps.size() << " keypoints, R fraction "
                  << s.radius_fraction_of_diagonal);
    const RefGraph ref = ref_build(img, kps, &own, &partner, inst, s);
    const cge::Graph<double> grid = GridBuilder(s).build(img, kps, own, partner, inst);
    const cge::Graph<double> brute = BruteBuilder(s).build(img, kps, own, partner, inst);
    require_same(grid, ref);
    require_same(brute, ref);
    REQUIRE(grid == brute);
    // Odd grid configurations: tiny cells, huge cells, a grid forced to coarsen.
    cge::GridNeighborSearch<double> small_cells;
    small_cells.cell_size_factor = 0.3;
    cge::GridNeighborSearch<double> coarse;
    coarse.cell_size_factor = 5;
    cge::GridNeighborSearch<double> few_cells;
    few_cells.max_cells = 4;
    REQUIRE(GridBuilder(s, small_cells).build(img, kps, own, partner, inst) == grid);
    REQUIRE(GridBuilder(s, coarse).build(img, kps, own, partner, inst) == grid);
    REQUIRE(GridBuilder(s, few_cells).build(img, kps, own, partner, inst) == grid);
    // Every scan kernel this machine runs, also with fine cells (queries of more rows than the
    // AVX-512 scan takes at once fall back to the portable loop).
    for (const cge::GridScanKernel kernel : available_scan_kernels<double>()) {
      INFO("scan kernel " << static_cast<int>(kernel));
      cge::GridNeighborSearch<double> ns;
      ns.scan_kernel = kernel;
      REQUIRE(GridBuilder(s, ns).build(img, kps, own, partner, inst) == grid);
      ns.cell_size_factor = 0.3;
      REQUIRE(GridBuilder(s, ns).build(img, kps, own, partner, inst) == grid);
    }

    // What the trials exercised.
    const double R = GridBuilder(s).base_radius(img);
    for (const RefEdge& e : ref.edges) {
      stray_edges += e.round == cge::kStrayJoin;
      capped_round_edges += e.round >= 3;
      exactly_r += e.weight == R;
    }
    for (NodeKind k : ref.kinds) dense_patches += k == NodeKind::representation;
    std::vector<P> sorted = kps;
    std::sort(sorted.begin(), sorted.end(),
              [](const P& a, const P& b) { return std::tie(a.y(), a.x()) < std::tie(b.y(), b.x()); });
    merged_duplicates += static_cast<int>(
        sorted.size() - static_cast<std::size_t>(std::unique(sorted.begin(), sorted.end()) - sorted.begin()));
    RefGraph no_masks;
    ref_nodes(img, kps, nullptr, nullptr, inst, s, no_masks);
    masked_away += no_masks.positions != ref.positions;
  }
  INFO("stray edges " << stray_edges << ", capped-round edges " << capped_round_edges << ", dense patches "
                      << dense_patches << ", duplicates " << merged_duplicates << ", edges of length exactly R "
                      << exactly_r << ", trials where masks mattered " << masked_away);
  CHECK(stray_edges > 50);
  CHECK(capped_round_edges > 1000);
  CHECK(dense_patches > 20);
  CHECK(merged_duplicates > 50);
  CHECK(exactly_r > 50);
  CHECK(masked_away > 30);
}

TEST_CASE("GraphBuilder: neighbour searches agree for extreme radii and grid settings", "[builder][oracle]") {
  // A tiny R (or cell factor) asks for an astronomically fine grid; GridNeighborSearch promises to
  // coarsen it to max_cells, and every policy must still give the reference graph.
  std::mt19937 rng(90210);
  const Image img = make_image(640, 480);
  const std::vector<P> kps = clustered_points(rng, 60, img, 3, 60.0);
  for (const double fraction : {1e-6, 1e-9, 1e-12, 1e-17, 1e-300, 5.0}) {
    Settings s;
    s.radius_fraction_of_diagonal = fraction;
    INFO("R fraction " << fraction);
    const RefGraph ref = ref_build(img, kps, nullptr, nullptr, {}, s);
    require_same(BruteBuilder(s).build(img, kps), ref);
    cge::Graph<double> grid;
    REQUIRE_NOTHROW(grid = GridBuilder(s).build(img, kps));
    require_same(grid, ref);
  }
  Settings s;
  const RefGraph ref = ref_build(img, kps, nullptr, nullptr, {}, s);
  for (const double factor : {1e-300, 1e-12, 0.0, -1.0, 1e12, 1e300}) {
    INFO("cell_size_factor " << factor);
    cge::GridNeighborSearch<double> ns;
    ns.cell_size_factor = factor;
    cge::Graph<double> grid;
    REQUIRE_NOTHROW(grid = GridBuilder(s, ns).build(img, kps));
    require_same(grid, ref);
  }
  for (const std::int64_t max_cells : {std::int64_t(0), std::int64_t(1), std::int64_t(2)}) {
    INFO("max_cells " << max_cells);
    cge::GridNeighborSearch<double> ns;
    ns.max_cells = max_cells;
    require_same(GridBuilder(s, ns).build(img, kps), ref);
  }
}

TEST_CASE("GraphBuilder::build_edges matches the reference on nodes given directly", "[builder][oracle]") {
  // build_edges takes canonical nodes from the caller: no patches, no masks.
  std::mt19937 rng(8086);
  const Image img = make_image(640, 480);
  for (int trial = 0; trial < 100; ++trial) {
    Settings s;
    s.radius_fraction_of_diagonal = std::uniform_real_distribution<double>(0.005, 0.2)(rng);
    s.capped_radius_multiple = trial % 2 == 0 ? 3.0 : 2.0;
    s.first_capped_round = trial % 4 == 1 ? 2 : 3;
    std::vector<P> pts = clustered_points(rng, std::uniform_int_distribution<int>(0, 200)(rng), img, 4, 40.0);
    std::sort(pts.begin(), pts.end(),
              [](const P& a, const P& b) { return std::tie(a.y(), a.x()) < std::tie(b.y(), b.x()); });
    pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
    cge::FrameNodes<double> nodes;
    nodes.positions = pts;
    nodes.kinds.assign(pts.size(), NodeKind::feature);
    RefGraph ref;
    ref.positions = pts;
    ref.kinds = nodes.kinds;
    ref.edges = ref_edges(img, pts, s);
    INFO("trial " << trial);
    require_same(GridBuilder(s).build_edges(img, nodes), ref);
    require_same(BruteBuilder(s).build_edges(img, nodes), ref);
  }
}

// =============================================================================================
// Property tests (rapidcheck): every property listed in docs/METHOD.md section 3
// =============================================================================================

namespace {

/// One frame drawn by rapidcheck: dyadic coordinates (multiples of 1/8 px), so translating by
/// integers is exact, and a dyadic R (1/64, 1/32, 1/16 or 1/8 of the 800 px diagonal).
struct Scene {
  Image image = make_image(640, 480);
  std::vector<P> keypoints;
  std::vector<Instance> instances;
  cge::BinaryMask own;
  cge::BinaryMask partner;
  Settings settings;
};

/// An integer uniform in [lo, hi) whatever rapidcheck's current size (inRange alone shrinks the range
/// at small sizes, which would crowd every early case into the image's top-left corner).
int uniform_int(int lo, int hi) { return *rc::gen::resize(100, rc::gen::inRange(lo, hi)); }

double draw_coordinate(int max_px) { return uniform_int(0, max_px * 8 + 1) / 8.0; }

Scene draw_scene() {
  Scene sc;
  sc.settings.radius_fraction_of_diagonal = *rc::gen::element(1.0 / 64, 1.0 / 32, 1.0 / 16, 1.0 / 8);
  sc.settings.dense_patch_threshold = *rc::gen::element(1, 3, 15);
  const int n = *rc::gen::inRange(0, 70);  // grows with rapidcheck's size
  const int style = uniform_int(0, 3);
  std::vector<P> centres;
  for (int k = 0; k < 3; ++k) centres.emplace_back(draw_coordinate(640), draw_coordinate(480));
  for (int i = 0; i < n; ++i) {
    P p;
    if (style == 0) {
      p = P(draw_coordinate(640), draw_coordinate(480));
    } else if (style == 1) {  // clusters: offsets of up to +-40 px around three centres
      const P& c = centres[static_cast<std::size_t>(uniform_int(0, 3))];
      p = clamp_to(sc.image, c + P(uniform_int(-320, 321) / 8.0, uniform_int(-320, 321) / 8.0));
    } else {  // coarse lattice: duplicates and tied distances
      p = P(16.0 * uniform_int(0, 41), 16.0 * uniform_int(0, 31));
    }
    sc.keypoints.push_back(p);
  }
  const int instances = uniform_int(0, 4);
  for (int i = 0; i < instances; ++i) {
    sc.instances.push_back(
        make_instance(draw_coordinate(640), draw_coordinate(480), uniform_int(0, 4), *rc::gen::arbitrary<bool>()));
  }
  // Rectangular dynamic objects in the own frame and in the partner frame, or none.
  for (cge::BinaryMask* mask : {&sc.own, &sc.partner}) {
    if (!*rc::gen::arbitrary<bool>()) continue;
    *mask = cge::BinaryMask(640, 480);
    const int x0 = uniform_int(0, 640);
    const int y0 = uniform_int(0, 480);
    const int x1 = std::min(640, x0 + uniform_int(1, 200));
    const int y1 = std::min(480, y0 + uniform_int(1, 200));
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) mask->at(x, y) = 255;
  }
  return sc;
}

template <typename Builder = GridBuilder>
cge::Graph<double> build_scene(const Scene& sc, const Builder& builder = Builder()) {
  Builder b = builder;
  b.settings = sc.settings;
  return b.build(sc.image, sc.keypoints, sc.own, sc.partner, sc.instances);
}

}  // namespace

TEST_CASE("GraphBuilder properties", "[builder][property]") {
  rc::prop("simple and connected", [] {
    const Scene sc = draw_scene();
    const cge::Graph<double> g = build_scene(sc);
    for (std::size_t i = 0; i < g.edges().size(); ++i) {
      RC_ASSERT(g.edges()[i].u < g.edges()[i].v);  // no self-loop
      if (i > 0) {
        RC_ASSERT(std::make_pair(g.edges()[i - 1].u, g.edges()[i - 1].v) <
                  std::make_pair(g.edges()[i].u, g.edges()[i].v));  // no repeated edge
      }
    }
    RC_ASSERT(is_connected(g));
    if (g.num_nodes() > 0) RC_ASSERT(g.num_edges() >= g.num_nodes() - 1);
  });

  rc::prop("edge count and degree sum agree", [] {
    const Scene sc = draw_scene();
    const cge::Graph<double> g = build_scene(sc);
    long degree_sum = 0;
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
      degree_sum += g.degree(v);
      RC_ASSERT(g.neighbors(v).size() == static_cast<std::size_t>(g.degree(v)));
    }
    RC_ASSERT(degree_sum == 2L * g.num_edges());
    RC_ASSERT(g.csr_adjacency().size() == 2 * g.edges().size());
    RC_ASSERT(g.edge_rounds().size() == g.edges().size());
  });

  rc::prop("invariant to input order", [] {
    const Scene sc = draw_scene();
    Scene shuffled = sc;
    std::mt19937 rng(*rc::gen::arbitrary<std::uint32_t>());
    std::shuffle(shuffled.keypoints.begin(), shuffled.keypoints.end(), rng);
    std::shuffle(shuffled.instances.begin(), shuffled.instances.end(), rng);
    RC_ASSERT(build_scene(shuffled) == build_scene(sc));
  });

  rc::prop("invariant to translating all points together with the image origin", [] {
    const Scene sc = draw_scene();
    const P t(uniform_int(-3000, 3001), uniform_int(-3000, 3001));
    Scene moved = sc;
    moved.image.origin_px += t;
    for (P& p : moved.keypoints) p += t;
    for (Instance& inst : moved.instances) inst.centre_px += t;
    const cge::Graph<double> a = build_scene(sc);
    const cge::Graph<double> b = build_scene(moved);
    RC_ASSERT(a.num_nodes() == b.num_nodes());
    for (std::size_t i = 0; i < a.positions().size(); ++i) RC_ASSERT(b.positions()[i] == a.positions()[i] + t);
    RC_ASSERT(a.kinds() == b.kinds());
    RC_ASSERT(a.edges() == b.edges());
    RC_ASSERT(a.edge_rounds() == b.edge_rounds());
  });

  rc::prop("grid and brute-force neighbour searches give identical graphs", [] {
    const Scene sc = draw_scene();
    cge::GridNeighborSearch<double> grid;
    grid.cell_size_factor = *rc::gen::element(0.25, 1.0, 2.5);
    grid.max_cells = *rc::gen::element<std::int64_t>(1, 16, 1 << 20);
    const cge::Graph<double> a = build_scene(sc, GridBuilder(sc.settings, grid));
    const cge::Graph<double> b = build_scene(sc, BruteBuilder());
    RC_ASSERT(a == b);
  });

  rc::prop("matches the naive reference implementation", [] {
    const Scene sc = draw_scene();
    const RefGraph ref = ref_build(sc.image, sc.keypoints, &sc.own, &sc.partner, sc.instances, sc.settings);
    const cge::Graph<double> g = build_scene(sc);
    RC_ASSERT(g.positions() == ref.positions);
    RC_ASSERT(g.kinds() == ref.kinds);
    RC_ASSERT(g.edges().size() == ref.edges.size());
    for (std::size_t i = 0; i < ref.edges.size(); ++i) {
      RC_ASSERT(g.edges()[i].u == ref.edges[i].u);
      RC_ASSERT(g.edges()[i].v == ref.edges[i].v);
      RC_ASSERT(g.edges()[i].weight == ref.edges[i].weight);
      RC_ASSERT(g.edge_rounds()[i] == ref.edges[i].round);
    }
  });
}

TEST_CASE("GraphBuilder property: capped rounds", "[builder][property]") {
  int cases_with_capped_edges = 0;
  int cases_with_long_stray_joins = 0;
  rc::prop("round >= 3 edges are no longer than 3R except stray joins", [&] {
    const Scene sc = draw_scene();
    const cge::Graph<double> g = build_scene(sc);
    const double R = GridBuilder(sc.settings).base_radius(sc.image);
    bool capped = false;
    bool long_stray = false;
    for (std::size_t i = 0; i < g.edges().size(); ++i) {
      const auto& e = g.edges()[i];
      const std::uint8_t round = g.edge_rounds()[i];
      // Every weight is the endpoints' Euclidean distance.
      RC_ASSERT(e.weight ==
                (g.positions()[static_cast<std::size_t>(e.u)] - g.positions()[static_cast<std::size_t>(e.v)]).norm());
      RC_ASSERT(round <= g.num_nodes());
      if (round != cge::kStrayJoin && round >= 3) {
        RC_ASSERT(e.weight <= 3 * R);
        capped = true;
      }
      long_stray = long_stray || (round == cge::kStrayJoin && e.weight > 3 * R);
    }
    cases_with_capped_edges += capped;
    cases_with_long_stray_joins += long_stray;
  });
  // The generator must produce what the property is about (counts include shrinking runs).
  CHECK(cases_with_capped_edges > 20);
  CHECK(cases_with_long_stray_joins > 5);
}

// =============================================================================================
// Node selection
// =============================================================================================

TEST_CASE("GraphBuilder node selection: dense patches, masks, semantic nodes, duplicates", "[builder][nodes]") {
  // 100 x 100 image, 10 x 10 patches of 10 px, N_th = 3 (a patch with 4 or more stable features is dense).
  const Image img = make_image(100, 100);
  Settings s;
  s.dense_patch_threshold = 3;
  const GridBuilder builder(s);

  std::vector<P> kps{
      // patch (col 2, row 3): 4 features -> dense -> representation point (25, 35)
      P(21, 31), P(22, 33), P(25, 35.5), P(29.5, 39.75),
      // patch (5, 5): 3 features -> stay
      P(51, 51), P(52, 52), P(53, 58),
      // patch (7, 7): a feature given twice -> one node
      P(70, 72), P(70, 72),
      // patch (1, 1): 5 features, 2 in the own mask and 1 in the partner mask -> 2 stable -> stay
      P(11, 11), P(12, 12), P(13, 13), P(14, 14), P(15, 15),
      // patch (8, 0): 4 features, but exactly 4 because a duplicate counts: dense (features, not positions)
      P(81, 1), P(81, 1), P(82, 2), P(83, 3)};
  cge::BinaryMask own(100, 100);
  own.at(11, 11) = 1;
  own.at(12, 12) = 1;
  cge::BinaryMask partner(100, 100);
  partner.at(13, 13) = 1;
  const std::vector<Instance> inst{
      make_instance(25, 35, 7, false),  // same position as the representation point: merged into it
      make_instance(80, 10, 3, false),  // static: a semantic node
      make_instance(90, 90, 0, true),   // dynamic: no node
      make_instance(12, 12, 4, false),  // static inside the own mask: still a node (masks filter features)
      make_instance(51, 51, 2, false),  // same position as a feature: merged into the feature
  };
  const cge::FrameNodes<double> nodes = builder.build_nodes(img, kps, own, partner, inst);
  const std::vector<P> expected_pos{P(85, 5),  P(80, 10), P(12, 12), P(14, 14), P(15, 15),
                                    P(25, 35), P(51, 51), P(52, 52), P(53, 58), P(70, 72)};
  const std::vector<NodeKind> expected_kind{
      NodeKind::representation, NodeKind::semantic, NodeKind::semantic, NodeKind::feature, NodeKind::feature,
      NodeKind::representation, NodeKind::feature,  NodeKind::feature,  NodeKind::feature, NodeKind::feature};
  REQUIRE(nodes.positions == expected_pos);
  REQUIRE(nodes.kinds == expected_kind);
  // build() uses exactly these nodes.
  const cge::Graph<double> g = builder.build(img, kps, own, partner, inst);
  REQUIRE(g.positions() == expected_pos);
  REQUIRE(g.kinds() == expected_kind);
  // Swapping the roles of the masks changes nothing: stability is "in neither mask".
  REQUIRE(builder.build(img, kps, partner, own, inst) == g);
  // Without masks, patch (1, 1) has 5 stable features and becomes dense.
  const cge::FrameNodes<double> unmasked = builder.build_nodes(img, kps, cge::NoMask{}, cge::NoMask{}, inst);
  REQUIRE(std::find(unmasked.positions.begin(), unmasked.positions.end(), P(15, 15)) != unmasked.positions.end());
  const auto rep = std::find(unmasked.positions.begin(), unmasked.positions.end(), P(15, 15));
  REQUIRE(unmasked.kinds[static_cast<std::size_t>(rep - unmasked.positions.begin())] == NodeKind::representation);
  REQUIRE(std::find(unmasked.positions.begin(), unmasked.positions.end(), P(14, 14)) == unmasked.positions.end());
  // Raising N_th to 5 keeps every feature of patch (1, 1) in the unmasked case.
  Settings loose = s;
  loose.dense_patch_threshold = 5;
  const cge::FrameNodes<double> kept = GridBuilder(loose).build_nodes(img, kps, cge::NoMask{}, cge::NoMask{}, {});
  for (const P& p : {P(11, 11), P(12, 12), P(13, 13), P(14, 14), P(15, 15)}) {
    REQUIRE(std::find(kept.positions.begin(), kept.positions.end(), p) != kept.positions.end());
  }
}

TEST_CASE("GraphBuilder node selection: mask lookup rounds to the nearest pixel", "[builder][nodes]") {
  const Image img = make_image(20, 20);
  Settings s;
  s.dense_patch_threshold = 100;
  cge::BinaryMask mask(20, 20);
  mask.at(10, 10) = 1;
  mask.at(19, 5) = 1;
  const std::vector<P> kps{P(10.4, 10.4), P(9.6, 9.6), P(10.6, 10.4), P(10.4, 9.4), P(20, 5), P(19.4, 5.2), P(18.4, 5)};
  const cge::FrameNodes<double> nodes = GridBuilder(s).build_nodes(img, kps, mask, cge::NoMask{}, {});
  // (10.4, 10.4) and (9.6, 9.6) -> pixel (10, 10): dynamic. (20, 5) on the far border -> last column (19, 5): dynamic.
  // (19.4, 5.2) -> (19, 5): dynamic. The others fall on unset pixels.
  REQUIRE(nodes.positions == std::vector<P>{P(18.4, 5), P(10.4, 9.4), P(10.6, 10.4)});
  // An empty BinaryMask means "no dynamic objects" and is accepted whatever the image size.
  REQUIRE(GridBuilder(s).build_nodes(img, kps, cge::BinaryMask(), cge::BinaryMask(), {}).positions.size() ==
          kps.size());
  // The largest double below 0.5 belongs to pixel 0, not 1 (x + 0.5 would round up to 1.0).
  cge::BinaryMask first_pixel(20, 20);
  first_pixel.at(0, 0) = 1;
  const double below_half = std::nextafter(0.5, 0.0);
  const std::vector<P> edge_kp{P(below_half, below_half)};
  CHECK(GridBuilder(s).build_nodes(img, edge_kp, first_pixel, cge::NoMask{}, {}).positions.empty());
}

TEST_CASE("GraphBuilder node selection: canonical order is (y, x, kind)", "[builder][nodes]") {
  std::mt19937 rng(1234);
  const Image img = make_image(640, 480);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<P> kps = lattice_points(rng, 200, img, 32);  // ties in y, in (y, x), and duplicates
    std::vector<Instance> inst;
    for (int i = 0; i < 10; ++i) {
      // Half of the instances sit exactly on keypoints: same (y, x), different kind.
      const P p = i % 2 == 0 ? kps[static_cast<std::size_t>(i)] : lattice_points(rng, 1, img, 32)[0];
      inst.push_back(make_instance(p.x(), p.y(), i, false));
    }
    Settings s;
    s.dense_patch_threshold = 4;
    const cge::FrameNodes<double> nodes = GridBuilder(s).build_nodes(img, kps, cge::NoMask{}, cge::NoMask{}, inst);
    REQUIRE(nodes.positions.size() == nodes.kinds.size());
    for (std::size_t i = 1; i < nodes.positions.size(); ++i) {
      const auto a = std::make_tuple(nodes.positions[i - 1].y(), nodes.positions[i - 1].x());
      const auto b = std::make_tuple(nodes.positions[i].y(), nodes.positions[i].x());
      REQUIRE(a < b);  // sorted, and no position twice
    }
    // Every semantic centre is a node (possibly of a lower kind when merged).
    for (const Instance& in : inst) {
      REQUIRE(std::find(nodes.positions.begin(), nodes.positions.end(), in.centre_px) != nodes.positions.end());
    }
  }
}

TEST_CASE("GraphBuilder node selection: canonical order with crowded rows", "[builder][nodes]") {
  // Many nodes on few pixel rows exercise the per-band sort for large bands (and duplicates in
  // them); the order must not depend on the input order.
  std::mt19937 rng(77);
  const Image img = make_image(640, 480);
  std::uniform_real_distribution<double> x(0, 640);
  std::vector<P> kps;
  for (int i = 0; i < 400; ++i) kps.emplace_back(std::floor(x(rng) * 4) / 4, i % 3 == 0 ? 100.0 : 100.5);
  Settings s;
  s.dense_patch_threshold = 1000;
  const cge::FrameNodes<double> nodes = GridBuilder(s).build_nodes(img, kps, cge::NoMask{}, cge::NoMask{}, {});
  std::vector<std::pair<double, double>> expected;
  for (const P& p : kps) expected.emplace_back(p.y(), p.x());
  std::sort(expected.begin(), expected.end());
  expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
  REQUIRE(nodes.positions.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    REQUIRE(nodes.positions[i] == P(expected[i].second, expected[i].first));
  }
  std::shuffle(kps.begin(), kps.end(), rng);
  REQUIRE(GridBuilder(s).build_nodes(img, kps, cge::NoMask{}, cge::NoMask{}, {}).positions == nodes.positions);
}

TEST_CASE("GraphBuilder: a reused workspace and output graph give the same graphs as fresh builds",
          "[builder][workspace]") {
  // One workspace and one output graph across frames of very different sizes, masks, instances
  // and settings: nothing of an earlier build may leak into a later one.
  std::mt19937 rng(4242);
  const Image img = make_image(640, 480);
  cge::GraphBuilderWorkspace<double, cge::GridNeighborSearch<double>> grid_ws;
  cge::GraphBuilderWorkspace<double, cge::BruteForceNeighborSearch<double>> brute_ws;
  cge::Graph<double> grid_out, brute_out;
  for (int trial = 0; trial < 60; ++trial) {
    const int n = std::uniform_int_distribution<int>(0, trial % 5 == 0 ? 900 : 120)(rng);
    const std::vector<P> kps = trial % 3 == 0 ? clustered_points(rng, n, img, 4, 12.0) : uniform_points(rng, n, img);
    const cge::BinaryMask own = random_rect_mask(rng, img, trial % 3);
    const cge::BinaryMask partner = random_rect_mask(rng, img, (trial + 1) % 3);
    const std::vector<Instance> inst = random_instances(rng, img, trial % 4);
    Settings s;
    s.dense_patch_threshold = std::uniform_int_distribution<int>(2, 30)(rng);
    s.radius_fraction_of_diagonal = std::uniform_real_distribution<double>(0.005, 0.08)(rng);
    const GridBuilder grid(s);
    const BruteBuilder brute(s);
    const cge::Graph<double> fresh = grid.build(img, kps, own, partner, inst);
    grid.build(img, kps, own, partner, inst, grid_out, grid_ws);
    brute.build(img, kps, own, partner, inst, brute_out, brute_ws);
    REQUIRE(grid_out == fresh);
    REQUIRE(brute_out == fresh);
    REQUIRE(grid_out.csr_offsets() == fresh.csr_offsets());
    REQUIRE(grid_out.csr_adjacency() == fresh.csr_adjacency());
  }
}

// =============================================================================================
// Errors
// =============================================================================================

TEST_CASE("GraphBuilder rejects invalid input with a message naming the problem", "[builder][errors]") {
  const Image img = make_image(100, 80);
  const GridBuilder builder;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();

  SECTION("nodes given to build_edges with kinds missing, or with a bad region") {
    cge::FrameNodes<double> nodes;
    nodes.positions = {P(10, 10), P(20, 20)};
    nodes.kinds = {NodeKind::feature};
    CHECK_THROWS_WITH(builder.build_edges(img, nodes), Catch::Contains("different numbers of positions and kinds"));
    nodes.kinds.push_back(NodeKind::feature);
    CHECK_THROWS_WITH(builder.build_edges(make_image(0, 80), nodes), Catch::Contains("width_px"));
  }
  SECTION("keypoint outside the image") {
    const std::vector<P> kps{P(1, 1), P(50, 40), P(100.5, 10)};
    CHECK_THAT(invalid_argument_message([&] { builder.build(img, kps); }),
               Catch::Contains("keypoint #2") && Catch::Contains("outside"));
    CHECK_THAT(invalid_argument_message([&] { builder.build(img, std::vector<P>{P(-0.25, 3)}); }),
               Catch::Contains("keypoint #0"));
    CHECK_THAT(invalid_argument_message([&] { builder.build(img, std::vector<P>{P(3, 80.001)}); }),
               Catch::Contains("keypoint #0"));
    // Translated image: (5, 5) is outside [10, 110) x [10, 90).
    CHECK_THAT(
        invalid_argument_message([&] { builder.build(make_image(100, 80, P(10, 10)), std::vector<P>{P(5, 5)}); }),
        Catch::Contains("keypoint #0"));
  }
  SECTION("keypoint not finite") {
    CHECK_THAT(invalid_argument_message([&] {
                 builder.build(img, std::vector<P>{P(1, 1), P(nan, 3)});
               }),
               Catch::Contains("keypoint #1") && Catch::Contains("not finite"));
    CHECK_THAT(invalid_argument_message([&] { builder.build(img, std::vector<P>{P(2, inf)}); }),
               Catch::Contains("keypoint #0"));
  }
  SECTION("semantic instance outside the image or not finite, dynamic or not") {
    CHECK_THAT(
        invalid_argument_message([&] {
          builder.build(img, std::vector<P>{P(1, 1)}, {make_instance(5, 5, 0, false), make_instance(200, 5, 0, true)});
        }),
        Catch::Contains("semantic instance #1"));
    CHECK_THAT(
        invalid_argument_message([&] { builder.build(img, std::vector<P>{}, {make_instance(nan, 5, 0, false)}); }),
        Catch::Contains("semantic instance #0"));
  }
  SECTION("mask of the wrong size") {
    const std::vector<P> kps{P(1, 1)};
    CHECK_THAT(invalid_argument_message([&] { builder.build(img, kps, cge::BinaryMask(99, 80), cge::NoMask{}, {}); }),
               Catch::Contains("own dynamic mask") && Catch::Contains("99 x 80") && Catch::Contains("100 x 80"));
    CHECK_THAT(invalid_argument_message(
                   [&] { builder.build(img, kps, cge::BinaryMask(100, 80), cge::BinaryMask(80, 100), {}); }),
               Catch::Contains("partner dynamic mask") && Catch::Contains("80 x 100"));
  }
  SECTION("bad image region") {
    CHECK_THAT(invalid_argument_message([&] { builder.build(make_image(0, 80), std::vector<P>{}); }),
               Catch::Contains("ImageRegion") && Catch::Contains("width_px"));
    CHECK_THAT(invalid_argument_message([&] { builder.build(make_image(100, nan), std::vector<P>{}); }),
               Catch::Contains("ImageRegion"));
    CHECK_THAT(invalid_argument_message([&] { builder.build(make_image(100, 80, P(inf, 0)), std::vector<P>{}); }),
               Catch::Contains("origin_px"));
  }
  SECTION("bad settings") {
    auto with = [&](auto change) {
      Settings s;
      change(s);
      return invalid_argument_message([&] { GridBuilder(s).build(img, std::vector<P>{P(1, 1), P(2, 2)}); });
    };
    CHECK_THAT(with([](Settings& s) { s.patch_cols = 0; }), Catch::Contains("patch_cols"));
    CHECK_THAT(with([](Settings& s) { s.patch_rows = -2; }), Catch::Contains("patch_rows"));
    CHECK_THAT(with([](Settings& s) { s.dense_patch_threshold = -1; }), Catch::Contains("dense_patch_threshold"));
    CHECK_THAT(with([](Settings& s) { s.radius_fraction_of_diagonal = 0; }),
               Catch::Contains("radius_fraction_of_diagonal"));
    CHECK_THAT(with([](Settings& s) { s.radius_fraction_of_diagonal = -0.05; }),
               Catch::Contains("radius_fraction_of_diagonal"));
    CHECK_THAT(with([&](Settings& s) { s.radius_fraction_of_diagonal = nan; }),
               Catch::Contains("radius_fraction_of_diagonal"));
    CHECK_THAT(with([&](Settings& s) { s.radius_fraction_of_diagonal = inf; }),
               Catch::Contains("radius_fraction_of_diagonal"));
    CHECK_THAT(with([](Settings& s) { s.capped_radius_multiple = 0.5; }), Catch::Contains("capped_radius_multiple"));
    CHECK_THAT(with([&](Settings& s) { s.capped_radius_multiple = nan; }), Catch::Contains("capped_radius_multiple"));
    CHECK_THAT(with([](Settings& s) { s.first_capped_round = 0; }), Catch::Contains("first_capped_round"));
  }
  SECTION("FrameNodes with different numbers of positions and kinds") {
    cge::FrameNodes<double> nodes;
    nodes.positions = {P(1, 1), P(2, 2)};
    nodes.kinds = {NodeKind::feature};
    CHECK_THAT(invalid_argument_message([&] { builder.build_edges(img, nodes); }), Catch::Contains("FrameNodes"));
  }
}

TEST_CASE("GridNeighborSearch scan kernels report the same points and distances", "[builder][oracle][kernel]") {
  // Direct check of the policy contract: every point within the radius but the query, once, with
  // d2 = squared_distance(query, point); float and double coordinates, radii hitting exact
  // lattice distances, queries near the border and beyond the point set.
  std::mt19937 rng(777);
  const auto check = [&](auto scalar_tag) {
    using S = decltype(scalar_tag);
    using Pt = Eigen::Matrix<S, 2, 1>;
    std::vector<Pt> pts;
    for (int i = 0; i < 400; ++i) {
      if (i % 2) {
        pts.emplace_back(static_cast<S>(std::uniform_real_distribution<double>(0, 640)(rng)),
                         static_cast<S>(std::uniform_real_distribution<double>(0, 480)(rng)));
      } else {  // lattice of 10 px: many distances of exactly 10, 20, 30 ...
        pts.emplace_back(static_cast<S>(10 * std::uniform_int_distribution<int>(0, 63)(rng)),
                         static_cast<S>(10 * std::uniform_int_distribution<int>(0, 47)(rng)));
      }
    }
    for (const S radius : {S(10), S(20), S(30), S(47.5), S(100), S(900)}) {
      std::vector<std::vector<std::pair<std::int32_t, S>>> expected(pts.size());
      for (std::size_t q = 0; q < pts.size(); ++q) {
        for (std::size_t j = 0; j < pts.size(); ++j) {
          if (j != q && cge::within_radius(pts[q], pts[j], radius)) {
            expected[q].push_back({static_cast<std::int32_t>(j), cge::squared_distance(pts[q], pts[j])});
          }
        }
      }
      for (const cge::GridScanKernel kernel : available_scan_kernels<S>()) {
        INFO("radius " << radius << ", kernel " << static_cast<int>(kernel) << ", float "
                       << (sizeof(S) == sizeof(float)));
        cge::GridNeighborSearch<S> grid;
        grid.scan_kernel = kernel;
        grid.build(pts, S(10));
        for (std::size_t q = 0; q < pts.size(); ++q) {
          std::vector<std::pair<std::int32_t, S>> got;
          grid.for_each_within(static_cast<std::int32_t>(q), radius, [&](std::int32_t j, S d2) {
            got.push_back({j, d2});
          });
          std::sort(got.begin(), got.end());
          REQUIRE(got == expected[q]);
        }
      }
    }
  };
  check(double{});
  check(float{});
}

TEST_CASE("GraphBuilder with float coordinates: every scan kernel gives the brute-force graph",
          "[builder][oracle][kernel]") {
  std::mt19937 rng(4321);
  using PF = Eigen::Vector2f;
  cge::ImageRegion<float> img;
  img.width_px = 640;
  img.height_px = 480;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<PF> kps;
    const int n = std::uniform_int_distribution<int>(1, 600)(rng);
    for (int i = 0; i < n; ++i) {
      kps.emplace_back(static_cast<float>(std::uniform_real_distribution<double>(0, 640)(rng)),
                       static_cast<float>(std::uniform_real_distribution<double>(0, 480)(rng)));
    }
    cge::GraphBuilderSettings<float> s;
    s.dense_patch_threshold = trial % 2 ? 15 : 1 << 30;
    s.radius_fraction_of_diagonal = trial % 3 ? 0.03f : 0.05f;
    const cge::Graph<float> brute = cge::GraphBuilder<float, cge::BruteForceNeighborSearch<float>>(s).build(img, kps);
    for (const cge::GridScanKernel kernel : available_scan_kernels<float>()) {
      INFO("trial " << trial << ", kernel " << static_cast<int>(kernel));
      cge::GridNeighborSearch<float> ns;
      ns.scan_kernel = kernel;
      REQUIRE(cge::GraphBuilder<float>(s, ns).build(img, kps) == brute);
    }
  }
}

TEST_CASE("GridNeighborSearch: scan kernel availability and an explicit request that cannot run",
          "[builder][kernel][errors]") {
  CHECK(cge::GridNeighborSearch<double>::scan_kernel_available(cge::GridScanKernel::automatic));
  CHECK(cge::GridNeighborSearch<double>::scan_kernel_available(cge::GridScanKernel::portable));
  // No vector kernel for long double coordinates: asking for one is an error, automatic falls back.
  CHECK_FALSE(cge::GridNeighborSearch<long double>::scan_kernel_available(cge::GridScanKernel::avx512));
  cge::GridNeighborSearch<long double> wide;
  wide.scan_kernel = cge::GridScanKernel::avx512;
  const std::vector<Eigen::Matrix<long double, 2, 1>> pts{{0.0L, 0.0L}, {1.0L, 0.0L}};
  CHECK_THAT(invalid_argument_message([&] { wide.build(pts, 1.0L); }), Catch::Contains("avx512"));
  wide.scan_kernel = cge::GridScanKernel::automatic;
  CHECK_NOTHROW(wide.build(pts, 1.0L));
  if (!cge::GridNeighborSearch<double>::scan_kernel_available(cge::GridScanKernel::avx512)) {
    cge::GridNeighborSearch<double> ns;
    ns.scan_kernel = cge::GridScanKernel::avx512;
    const std::vector<P> dpts{P(0, 0), P(1, 0)};
    CHECK_THAT(invalid_argument_message([&] { ns.build(dpts, 1.0); }), Catch::Contains("AVX-512"));
    WARN("skipped: no AVX-512 here, the avx512 scan kernel is not exercised");
  }
}
