// Tests of the degree-degree association entropy (ALGORITHMS.md section 4):
// shortest_path_degree_sums against an independent path-enumeration oracle, DegreeDegreeEntropy
// against a naive direct formula, the worked values of the spec, invariance under relabelling,
// numerics on SLAM-sized graphs, edge cases, and the sweep's kernels (portable and AVX-512) against
// each other and against an ordered scalar reference, bit for bit.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cge/entropy/bitset_single_source_degree_sums.hpp"
#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/entropy/single_source_degree_sums.hpp"
#include "cge/entropy/softmax_entropy.hpp"
#include "cge/entropy/weight_bounded_entropy.hpp"
#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/graph/hop_diameter.hpp"
#include "cge/graph/twin_classes.hpp"
#include "test_support.hpp"

namespace {

using cge::TieMode;
using LD = long double;

// ---------------------------------------------------------------------------------------------
// Small test graphs
// ---------------------------------------------------------------------------------------------

struct SmallGraph {
  std::string name;
  int n = 0;
  std::vector<std::pair<int, int>> edges;
};

cge::Graph<double> to_graph(const SmallGraph& s) {
  std::vector<cge::Edge<double>> e;
  for (const auto& [u, v] : s.edges) e.push_back(cge::Edge<double>{u, v, 1.0});
  return cge::Graph<double>::from_edges(s.n, e, false);
}

SmallGraph path_graph(int n) {
  SmallGraph g{"P" + std::to_string(n), n, {}};
  for (int i = 0; i + 1 < n; ++i) g.edges.push_back({i, i + 1});
  return g;
}

SmallGraph cycle_graph(int n) {
  SmallGraph g = path_graph(n);
  g.name = "C" + std::to_string(n);
  g.edges.push_back({n - 1, 0});
  return g;
}

SmallGraph complete_graph(int n) {
  SmallGraph g{"K" + std::to_string(n), n, {}};
  for (int u = 0; u < n; ++u)
    for (int v = u + 1; v < n; ++v) g.edges.push_back({u, v});
  return g;
}

SmallGraph complete_bipartite(int a, int b) {
  SmallGraph g{"K" + std::to_string(a) + "," + std::to_string(b), a + b, {}};
  for (int u = 0; u < a; ++u)
    for (int v = 0; v < b; ++v) g.edges.push_back({u, a + v});
  return g;
}

SmallGraph grid_graph(int rows, int cols) {
  SmallGraph g{"grid" + std::to_string(rows) + "x" + std::to_string(cols), rows * cols, {}};
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int v = r * cols + c;
      if (c + 1 < cols) g.edges.push_back({v, v + 1});
      if (r + 1 < rows) g.edges.push_back({v, v + cols});
    }
  }
  return g;
}

SmallGraph hypercube3() {
  SmallGraph g{"Q3", 8, {}};
  for (int u = 0; u < 8; ++u)
    for (int b = 0; b < 3; ++b) {
      const int v = u ^ (1 << b);
      if (u < v) g.edges.push_back({u, v});
    }
  return g;
}

SmallGraph petersen() {
  SmallGraph g{"Petersen", 10, {}};
  for (int i = 0; i < 5; ++i) {
    g.edges.push_back({i, (i + 1) % 5});          // outer cycle
    g.edges.push_back({i, i + 5});                // spokes
    g.edges.push_back({5 + i, 5 + (i + 2) % 5});  // inner pentagram
  }
  return g;
}

SmallGraph wheel(int rim) {
  SmallGraph g = cycle_graph(rim);
  g.name = "W" + std::to_string(rim);
  g.n = rim + 1;
  for (int i = 0; i < rim; ++i) g.edges.push_back({rim, i});
  return g;
}

SmallGraph disjoint_union(const SmallGraph& a, const SmallGraph& b) {
  SmallGraph g{a.name + "+" + b.name, a.n + b.n, a.edges};
  for (const auto& [u, v] : b.edges) g.edges.push_back({u + a.n, v + a.n});
  return g;
}

SmallGraph isolated(int n) { return SmallGraph{"I" + std::to_string(n), n, {}}; }

/// Node v becomes perm[v].
SmallGraph relabel(const SmallGraph& g, const std::vector<int>& perm) {
  SmallGraph out{g.name + "(relabelled)", g.n, {}};
  for (const auto& [u, v] : g.edges)
    out.edges.push_back({perm[static_cast<std::size_t>(u)], perm[static_cast<std::size_t>(v)]});
  return out;
}

SmallGraph random_gnp(std::mt19937& rng, int n, double p, const std::string& tag) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SmallGraph g{tag + "-G(" + std::to_string(n) + "," + std::to_string(p) + ")", n, {}};
  for (int u = 0; u < n; ++u)
    for (int v = u + 1; v < n; ++v)
      if (unit(rng) < p) g.edges.push_back({u, v});
  return g;
}

/// Random tree plus extra random edges: connected.
SmallGraph random_connected(std::mt19937& rng, int n, int extra, const std::string& tag) {
  SmallGraph g{tag + "-conn(" + std::to_string(n) + "," + std::to_string(extra) + ")", n, {}};
  std::vector<std::vector<bool>> adj(static_cast<std::size_t>(n),
                                     std::vector<bool>(static_cast<std::size_t>(n), false));
  auto add = [&](int u, int v) {
    if (u == v || adj[static_cast<std::size_t>(u)][static_cast<std::size_t>(v)]) return;
    adj[static_cast<std::size_t>(u)][static_cast<std::size_t>(v)] =
        adj[static_cast<std::size_t>(v)][static_cast<std::size_t>(u)] = true;
    g.edges.push_back({u, v});
  };
  for (int v = 1; v < n; ++v) add(v, std::uniform_int_distribution<int>(0, v - 1)(rng));
  for (int i = 0; i < extra && n > 1; ++i) {
    add(std::uniform_int_distribution<int>(0, n - 1)(rng), std::uniform_int_distribution<int>(0, n - 1)(rng));
  }
  return g;
}

/// A tie-rich base graph with a few random chords, so degrees differ while ties stay plentiful.
SmallGraph with_random_chords(std::mt19937& rng, const SmallGraph& base, int chords) {
  SmallGraph g = base;
  g.name += "+chords";
  for (int i = 0; i < chords; ++i) {
    const int u = std::uniform_int_distribution<int>(0, g.n - 1)(rng);
    const int v = std::uniform_int_distribution<int>(0, g.n - 1)(rng);
    if (u == v) continue;
    const bool exists = std::any_of(g.edges.begin(), g.edges.end(), [&](const std::pair<int, int>& e) {
      return (e.first == u && e.second == v) || (e.first == v && e.second == u);
    });
    if (!exists) g.edges.push_back({u, v});
  }
  return g;
}

std::vector<int> random_permutation(std::mt19937& rng, int n) {
  std::vector<int> perm(static_cast<std::size_t>(n));
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  return perm;
}

/// Structured families (tie-rich, regular, disconnected) followed by `random_count` random graphs.
std::vector<SmallGraph> small_graph_zoo(int random_count) {
  std::vector<SmallGraph> zoo;
  for (int n = 1; n <= 12; ++n) zoo.push_back(path_graph(n));
  for (int n = 3; n <= 12; ++n) zoo.push_back(cycle_graph(n));
  for (int n = 2; n <= 8; ++n) zoo.push_back(complete_graph(n));
  for (int a = 1; a <= 6; ++a)
    for (int b = a; a + b <= 12; ++b) zoo.push_back(complete_bipartite(a, b));
  for (int r = 2; r <= 4; ++r)
    for (int c = r; r * c <= 12; ++c) zoo.push_back(grid_graph(r, c));
  zoo.push_back(hypercube3());
  zoo.push_back(petersen());
  for (int rim = 3; rim <= 11; rim += 2) zoo.push_back(wheel(rim));
  zoo.push_back(isolated(1));
  zoo.push_back(isolated(5));
  zoo.push_back(disjoint_union(cycle_graph(4), path_graph(3)));
  zoo.push_back(disjoint_union(complete_bipartite(2, 3), isolated(1)));
  zoo.push_back(disjoint_union(grid_graph(2, 3), complete_graph(4)));
  zoo.push_back(disjoint_union(path_graph(5), disjoint_union(path_graph(2), isolated(2))));
  zoo.push_back(disjoint_union(isolated(1), complete_bipartite(1, 4)));

  std::mt19937 rng(20240611);
  for (int i = 0; i < random_count; ++i) {
    const int n = std::uniform_int_distribution<int>(1, 12)(rng);
    const std::string tag = "r" + std::to_string(i);
    switch (i % 5) {
      case 0:  // sparse, often disconnected
        zoo.push_back(random_gnp(rng, n, std::uniform_real_distribution<double>(0.05, 0.3)(rng), tag));
        break;
      case 1:  // dense
        zoo.push_back(random_gnp(rng, n, std::uniform_real_distribution<double>(0.3, 0.9)(rng), tag));
        break;
      case 2:
        zoo.push_back(random_connected(rng, n, std::uniform_int_distribution<int>(0, 2 * n)(rng), tag));
        break;
      case 3: {  // relabelled tie-rich family with chords
        const int pick = std::uniform_int_distribution<int>(0, 3)(rng);
        SmallGraph base = pick == 0   ? grid_graph(3, 4)
                          : pick == 1 ? complete_bipartite(std::uniform_int_distribution<int>(1, 5)(rng), 6)
                          : pick == 2 ? hypercube3()
                                      : cycle_graph(std::max(3, n));
        base = with_random_chords(rng, base, std::uniform_int_distribution<int>(0, 3)(rng));
        SmallGraph g = relabel(base, random_permutation(rng, base.n));
        g.name = tag + "-" + base.name;
        zoo.push_back(g);
        break;
      }
      default: {  // two random components
        const int a = std::uniform_int_distribution<int>(1, 6)(rng);
        const int b = std::uniform_int_distribution<int>(1, 6)(rng);
        SmallGraph g = disjoint_union(random_connected(rng, a, a, tag), random_gnp(rng, b, 0.5, tag));
        g = relabel(g, random_permutation(rng, g.n));
        g.name = tag + "-union";
        zoo.push_back(g);
        break;
      }
    }
  }
  return zoo;
}

bool close(LD actual, LD expected, LD rel) {
  return std::abs(actual - expected) <= rel * std::max<LD>(1, std::abs(expected));
}

// ---------------------------------------------------------------------------------------------
// Oracle: Delta(s, k) by enumerating every shortest path explicitly (no dynamic programme)
// ---------------------------------------------------------------------------------------------

struct OracleTable {
  int n = 0;
  int diameter = 0;
  bool connected = true;
  std::vector<int> eccentricity;
  std::vector<std::vector<LD>> delta;  // delta[s][k - 1], k = 1..eccentricity[s]
};

OracleTable oracle_delta(const SmallGraph& g, TieMode mode) {
  const int n = g.n;
  const auto N = static_cast<std::size_t>(n);
  std::vector<std::vector<int>> adj(N, std::vector<int>(N, 0));
  for (const auto& [u, v] : g.edges)
    adj[static_cast<std::size_t>(u)][static_cast<std::size_t>(v)] =
        adj[static_cast<std::size_t>(v)][static_cast<std::size_t>(u)] = 1;
  std::vector<int> deg(N, 0);
  for (std::size_t u = 0; u < N; ++u)
    for (std::size_t v = 0; v < N; ++v) deg[u] += adj[u][v];
  // Hop distances by Floyd-Warshall.
  const int inf = 1 << 20;
  std::vector<std::vector<int>> dist(N, std::vector<int>(N, inf));
  for (std::size_t u = 0; u < N; ++u) {
    dist[u][u] = 0;
    for (std::size_t v = 0; v < N; ++v)
      if (adj[u][v]) dist[u][v] = 1;
  }
  for (std::size_t m = 0; m < N; ++m)
    for (std::size_t u = 0; u < N; ++u)
      for (std::size_t v = 0; v < N; ++v) dist[u][v] = std::min(dist[u][v], dist[u][m] + dist[m][v]);

  OracleTable t;
  t.n = n;
  t.eccentricity.assign(N, 0);
  t.delta.assign(N, {});
  for (std::size_t s = 0; s < N; ++s) {
    // A walk s = u_0, ..., u_k is a shortest path iff dist(s, u_t) = t for every t; enumerate them
    // all by depth-first search and record every path's degree-difference sum at its end node.
    std::vector<std::vector<LD>> sums(N);
    std::function<void(std::size_t, LD)> dfs = [&](std::size_t u, LD sum) {
      sums[u].push_back(sum);
      for (std::size_t w = 0; w < N; ++w) {
        if (adj[u][w] && dist[s][w] == dist[s][u] + 1) dfs(w, sum + std::abs(LD(deg[u]) - LD(deg[w])));
      }
    };
    dfs(s, 0);
    int ecc = 0;
    for (std::size_t v = 0; v < N; ++v) {
      if (dist[s][v] >= inf) {
        t.connected = false;
        REQUIRE(sums[v].empty());
      } else {
        ecc = std::max(ecc, dist[s][v]);
        REQUIRE_FALSE(sums[v].empty());
      }
    }
    t.eccentricity[s] = ecc;
    t.diameter = std::max(t.diameter, ecc);
    t.delta[s].assign(static_cast<std::size_t>(ecc), 0);
    for (std::size_t v = 0; v < N; ++v) {
      if (v == s || dist[s][v] >= inf) continue;
      const std::vector<LD>& list = sums[v];
      LD contribution = 0;
      switch (mode) {
        case TieMode::all:
          for (LD x : list) contribution += x;
          break;
        case TieMode::mean:
          for (LD x : list) contribution += x;
          contribution /= static_cast<LD>(list.size());
          break;
        case TieMode::min:
          contribution = *std::min_element(list.begin(), list.end());
          break;
      }
      t.delta[s][static_cast<std::size_t>(dist[s][v] - 1)] += contribution;
    }
  }
  return t;
}

/// A second, scalar reference for graphs too large to enumerate paths: the recurrence of
/// ALGORITHMS.md section 4 with one plain BFS per source, in long double.
OracleTable scalar_bfs_delta(const SmallGraph& g, TieMode mode) {
  const auto N = static_cast<std::size_t>(g.n);
  std::vector<std::vector<int>> adj(N);
  for (const auto& [u, v] : g.edges) {
    adj[static_cast<std::size_t>(u)].push_back(v);
    adj[static_cast<std::size_t>(v)].push_back(u);
  }
  OracleTable t;
  t.n = g.n;
  t.eccentricity.assign(N, 0);
  t.delta.assign(N, {});
  for (std::size_t s = 0; s < N; ++s) {
    std::vector<int> dist(N, -1);
    std::vector<LD> count(N, 0), sum(N, 0), best(N, std::numeric_limits<LD>::infinity());
    std::vector<std::size_t> order{s};
    dist[s] = 0;
    count[s] = 1;
    best[s] = 0;
    for (std::size_t head = 0; head < order.size(); ++head) {
      const std::size_t u = order[head];
      for (const int wi : adj[u]) {
        const auto w = static_cast<std::size_t>(wi);
        if (dist[w] < 0) {
          dist[w] = dist[u] + 1;
          order.push_back(w);
        }
        if (dist[w] == dist[u] + 1) {
          const LD diff = std::abs(LD(adj[u].size()) - LD(adj[w].size()));
          count[w] += count[u];
          sum[w] += sum[u] + count[u] * diff;
          best[w] = std::min(best[w], best[u] + diff);
        }
      }
    }
    if (order.size() < N) t.connected = false;
    const int ecc = dist[order.back()];
    t.eccentricity[s] = ecc;
    t.diameter = std::max(t.diameter, ecc);
    t.delta[s].assign(static_cast<std::size_t>(ecc), 0);
    for (const std::size_t v : order) {
      if (v == s) continue;
      const LD x = mode == TieMode::all ? sum[v] : mode == TieMode::mean ? sum[v] / count[v] : best[v];
      t.delta[s][static_cast<std::size_t>(dist[v] - 1)] += x;
    }
  }
  return t;
}

void require_table_matches(const cge::DegreeSumTable& table, const OracleTable& expected) {
  REQUIRE(table.num_nodes == expected.n);
  REQUIRE(table.diameter == expected.diameter);
  REQUIRE(table.connected == expected.connected);
  // Compare every value, but assert once (millions of Catch assertions would dominate the run time).
  long long mismatches = 0;
  std::string first;
  for (int s = 0; s < expected.n; ++s) {
    REQUIRE(table.eccentricity(s) == expected.eccentricity[static_cast<std::size_t>(s)]);
    for (int k = 1; k <= expected.eccentricity[static_cast<std::size_t>(s)]; ++k) {
      const LD want = expected.delta[static_cast<std::size_t>(s)][static_cast<std::size_t>(k - 1)];
      if (!close(table.delta(s, k), want, 1e-12L) && mismatches++ == 0) {
        first = "Delta(" + std::to_string(s) + ", " + std::to_string(k) + ") = " + std::to_string(table.delta(s, k)) +
                ", reference " + std::to_string(static_cast<double>(want));
      }
    }
  }
  INFO("first mismatch: " << first);
  REQUIRE(mismatches == 0);
}

// ---------------------------------------------------------------------------------------------
// Oracle: E, H, I by the direct formula alpha^E in long double
// ---------------------------------------------------------------------------------------------

struct OracleEntropy {
  std::vector<LD> exponents;
  LD entropy = 0;
  LD index = 0;
};

OracleEntropy oracle_entropy(const OracleTable& t, const std::function<LD(int, int)>& coefficient, bool normalise,
                             LD alpha, LD lambda) {
  OracleEntropy out;
  const int rho = t.diameter;
  for (int v = 0; v < t.n; ++v) {
    LD e = 0;
    for (int k = 1; k <= t.eccentricity[static_cast<std::size_t>(v)]; ++k) {
      e += coefficient(k, rho) * t.delta[static_cast<std::size_t>(v)][static_cast<std::size_t>(k - 1)];
    }
    out.exponents.push_back(e);
  }
  if (normalise) {
    LD mean = 0;
    for (LD e : out.exponents) mean += e;
    mean /= static_cast<LD>(t.n);
    if (mean > 0) {
      for (LD& e : out.exponents) e /= mean;
    }
  }
  std::vector<LD> f;
  LD z = 0;
  for (LD e : out.exponents) {
    f.push_back(std::pow(alpha, e));
    z += f.back();
  }
  // The direct formula is only trusted while it neither overflows nor underflows.
  REQUIRE(std::isfinite(z));
  REQUIRE(z > 0);
  for (LD fv : f) REQUIRE(std::isnormal(fv));
  LD h = 0;
  for (LD fv : f) {
    const LD p = fv / z;
    if (p > 0) h -= p * std::log2(p);
  }
  out.entropy = h;
  out.index = lambda * (std::log2(static_cast<LD>(t.n)) - h);
  return out;
}

LD exp_coefficient(int k, int rho) { return static_cast<LD>(rho) * std::exp(LD(1) - LD(k)); }
LD linear_coefficient(int k, int rho) { return static_cast<LD>(rho - k + 1); }
LD constant_coefficient(int, int) { return 1; }

/// A custom coefficient policy for the tests: increasing in k, depending on rho.
struct RampCoefficient {
  double operator()(int k, int rho) const { return 0.5 * k + 1.0 / (1.0 + rho); }
};
LD ramp_coefficient(int k, int rho) { return LD(0.5) * k + LD(1) / (LD(1) + rho); }

const char* tie_name(TieMode m) {
  switch (m) {
    case TieMode::all:
      return "all";
    case TieMode::mean:
      return "mean";
    case TieMode::min:
      return "min";
  }
  return "?";
}

const TieMode kTieModes[] = {TieMode::all, TieMode::mean, TieMode::min};

template <typename Entropy>
void check_against_oracle(const Entropy& dde, const cge::Graph<double>& g, const OracleTable& table,
                          const std::function<LD(int, int)>& coefficient) {
  const bool normalise = dde.scaling.kind == cge::ScalingKind::normalised_mean;
  const OracleEntropy expected = oracle_entropy(table, coefficient, normalise, dde.settings.alpha, dde.settings.lambda);
  const auto r = dde.compute(g);
  REQUIRE(r.exponents.size() == expected.exponents.size());
  for (std::size_t v = 0; v < r.exponents.size(); ++v) {
    INFO("node " << v << ": E = " << r.exponents[v] << ", oracle " << static_cast<double>(expected.exponents[v]));
    REQUIRE(close(r.exponents[v], expected.exponents[v], 1e-12L));
  }
  INFO("H = " << r.entropy_bits << ", oracle " << static_cast<double>(expected.entropy)
              << "; I = " << r.information_index << ", oracle " << static_cast<double>(expected.index));
  REQUIRE(close(r.entropy_bits, expected.entropy, 1e-12L));
  REQUIRE(close(r.information_index, expected.index, 1e-12L));
  REQUIRE(r.max_entropy_bits == Approx(std::log2(static_cast<double>(table.n))).epsilon(1e-15));
  REQUIRE(r.diameter == table.diameter);
  REQUIRE(r.connected == table.connected);
}

using cge_test::is_connected;

// ---------------------------------------------------------------------------------------------
// The sweep's kernels
// ---------------------------------------------------------------------------------------------

/// The kernels this machine can run (automatic and portable always; avx512 where the CPU has it).
std::vector<cge::DegreeSumKernel> available_kernels() {
  std::vector<cge::DegreeSumKernel> kernels{cge::DegreeSumKernel::automatic, cge::DegreeSumKernel::portable};
  if (cge::degree_sum_kernel_available(cge::DegreeSumKernel::avx512)) kernels.push_back(cge::DegreeSumKernel::avx512);
  return kernels;
}

const char* kernel_name(cge::DegreeSumKernel k) {
  switch (k) {
    case cge::DegreeSumKernel::automatic:
      return "automatic";
    case cge::DegreeSumKernel::portable:
      return "portable";
    case cge::DegreeSumKernel::avx512:
      return "avx512";
  }
  return "?";
}

/// a * b rounded on its own: a fused multiply-add would round a * b + c only once.
double separate_product(double a, double b) {
  volatile double product = a * b;
  return product;
}

/// The documented floating-point order, one plain BFS per source, in double: for a node, its
/// predecessors in ascending node order, S += (S_p + N_p * diff) with the product rounded on its
/// own; Delta(s, k) over the nodes at distance k in ascending order; TieMode::mean scales a
/// source's level by 2^-512 when its largest count passes 2^512. Every kernel must agree with it
/// bit for bit.
cge::DegreeSumTable ordered_reference(const SmallGraph& g, TieMode mode) {
  const auto N = static_cast<std::size_t>(g.n);
  std::vector<std::vector<int>> adj(N);
  for (const auto& [u, v] : g.edges) {
    adj[static_cast<std::size_t>(u)].push_back(v);
    adj[static_cast<std::size_t>(v)].push_back(u);
  }
  for (auto& list : adj) std::sort(list.begin(), list.end());
  cge::DegreeSumTable t;
  t.num_nodes = g.n;
  t.row_offsets.assign(N + 1, 0);
  std::vector<std::vector<double>> rows(N);
  for (std::size_t s = 0; s < N; ++s) {
    std::vector<int> dist(N, -1);
    std::vector<double> count(N, 0.0), sum(N, mode == TieMode::min ? std::numeric_limits<double>::infinity() : 0.0);
    dist[s] = 0;
    count[s] = 1.0;
    sum[s] = 0.0;
    std::vector<std::size_t> level{s};
    std::size_t reached = 1;
    for (int k = 1;; ++k) {
      std::vector<std::size_t> next;
      for (const std::size_t p : level)
        for (const int w : adj[p])
          if (dist[static_cast<std::size_t>(w)] < 0) {
            dist[static_cast<std::size_t>(w)] = k;
            next.push_back(static_cast<std::size_t>(w));
          }
      if (next.empty()) break;
      std::sort(next.begin(), next.end());
      double layer = 0.0, max_count = 0.0;
      for (const std::size_t u : next) {
        for (const int pi : adj[u]) {  // ascending
          const auto p = static_cast<std::size_t>(pi);
          if (dist[p] != k - 1) continue;
          const double diff = std::fabs(static_cast<double>(adj[p].size()) - static_cast<double>(adj[u].size()));
          if (mode == TieMode::min) {
            sum[u] = std::min(sum[u], sum[p] + diff);
          } else {
            count[u] += count[p];
            sum[u] += sum[p] + separate_product(count[p], diff);
          }
        }
        layer += mode == TieMode::mean ? sum[u] / count[u] : sum[u];
        max_count = std::max(max_count, count[u]);
      }
      if (mode == TieMode::mean && max_count > std::ldexp(1.0, 512)) {
        for (const std::size_t u : next) {
          count[u] *= std::ldexp(1.0, -512);
          sum[u] *= std::ldexp(1.0, -512);
        }
      }
      rows[s].push_back(layer);
      reached += next.size();
      level = next;
    }
    if (reached < N) t.connected = false;
  }
  for (std::size_t s = 0; s < N; ++s) {
    t.values.insert(t.values.end(), rows[s].begin(), rows[s].end());
    t.row_offsets[s + 1] = static_cast<std::int64_t>(t.values.size());
    t.diameter = std::max(t.diameter, static_cast<std::int32_t>(rows[s].size()));
  }
  return t;
}

/// Bit for bit, including the signs of zeros (infinities and NaNs compare by their bits too).
bool same_bits(const cge::DegreeSumTable& a, const cge::DegreeSumTable& b) {
  if (a.num_nodes != b.num_nodes || a.diameter != b.diameter || a.connected != b.connected ||
      a.row_offsets != b.row_offsets || a.values.size() != b.values.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    std::uint64_t x = 0, y = 0;
    std::memcpy(&x, &a.values[i], sizeof x);
    std::memcpy(&y, &b.values[i], sizeof y);
    if (x != y) return false;
  }
  return true;
}

SmallGraph star_of_cliques(int cliques, int size) {
  // A hub joined to every node of several cliques: degrees from size to cliques * size.
  SmallGraph g{"star-of-cliques", 1 + cliques * size, {}};
  for (int c = 0; c < cliques; ++c) {
    const int base = 1 + c * size;
    for (int i = 0; i < size; ++i) {
      g.edges.push_back({0, base + i});
      for (int j = i + 1; j < size; ++j) g.edges.push_back({base + i, base + j});
    }
  }
  return g;
}

/// Frame-like graphs: what GraphBuilder makes of random points (mean degree about 8).
SmallGraph geometric_graph(int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0.0, 640.0), uy(0.0, 480.0);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < n; ++i) points.emplace_back(ux(rng), uy(rng));
  cge::GraphBuilderSettings<double> bs;
  bs.dense_patch_threshold = 1 << 30;
  bs.radius_fraction_of_diagonal = std::sqrt(6.0 * 640.0 * 480.0 / (3.14159265358979 * n)) / 800.0;
  const cge::Graph<double> built = cge::GraphBuilder<double>(bs).build(cge::ImageRegion<double>{}, points);
  SmallGraph g{"geometric" + std::to_string(n), n, {}};
  for (const auto& e : built.edges()) g.edges.push_back({e.u, e.v});
  return g;
}

/// A grid (with king's moves: also the diagonals) with pendant leaves on a regular pattern of
/// nodes: grid-many shortest paths (about C(rows + cols, rows) between corners; a node has up to
/// three predecessors with king's moves) and degree differences of 1 to 8 (leaves add no shortcut).
SmallGraph decorated_grid(int rows, int cols, bool king) {
  SmallGraph g = grid_graph(rows, cols);
  g.name = std::string("decorated ") + (king ? "king " : "") + g.name;
  if (king) {
    for (int r = 0; r + 1 < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        if (c + 1 < cols) g.edges.push_back({r * cols + c, (r + 1) * cols + c + 1});
        if (c > 0) g.edges.push_back({r * cols + c, (r + 1) * cols + c - 1});
      }
    }
  }
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if ((r * 7 + c * 3) % 5 != 0) continue;
      for (int leaf = 0; leaf < 1 + (r + c) % 4; ++leaf) g.edges.push_back({r * cols + c, g.n++});
    }
  }
  return g;
}

SmallGraph diamond_chain(int width, int diamonds) {
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
  return sg;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

TEST_CASE("shortest_path_degree_sums agrees with shortest-path enumeration on small graphs", "[dde][oracle]") {
  const std::vector<SmallGraph> zoo = small_graph_zoo(400);
  int disconnected = 0;
  long long nonzero_values = 0;
  for (const SmallGraph& sg : zoo) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO("graph " << sg.name << " (" << sg.n << " nodes, " << sg.edges.size() << " edges), ties " << tie_name(mode));
      const OracleTable expected = oracle_delta(sg, mode);
      const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, mode);
      REQUIRE(table.num_nodes == sg.n);
      REQUIRE(table.diameter == expected.diameter);
      REQUIRE(table.connected == expected.connected);
      REQUIRE(table.row_offsets.size() == static_cast<std::size_t>(sg.n) + 1);
      for (int s = 0; s < sg.n; ++s) {
        REQUIRE(table.eccentricity(s) == expected.eccentricity[static_cast<std::size_t>(s)]);
        for (int k = 1; k <= expected.eccentricity[static_cast<std::size_t>(s)]; ++k) {
          const LD want = expected.delta[static_cast<std::size_t>(s)][static_cast<std::size_t>(k - 1)];
          INFO("Delta(" << s << ", " << k << ") = " << table.delta(s, k) << ", oracle " << static_cast<double>(want));
          REQUIRE(close(table.delta(s, k), want, 1e-12L));
          if (want != 0) ++nonzero_values;
        }
        // Beyond the eccentricity (and for k = 0) delta() reads 0.
        REQUIRE(table.delta(s, 0) == 0.0);
        REQUIRE(table.delta(s, expected.eccentricity[static_cast<std::size_t>(s)] + 1) == 0.0);
      }
      if (!expected.connected && mode == TieMode::all) ++disconnected;
    }
  }
  // The zoo must exercise what it claims to: disconnected inputs and non-trivial sums.
  CHECK(zoo.size() > 450);
  CHECK(disconnected > 50);
  CHECK(nonzero_values > 10000);
}

TEST_CASE("tie modes differ where paths tie with different sums", "[dde][oracle]") {
  // K_{1,2} glued: 0 - {1, 2} - 3 with 1 also joined to a pendant 4. Node 3 is reached from 0 by two
  // shortest paths through nodes of different degree, so the three tie modes must disagree.
  const SmallGraph sg{"diamond+pendant", 5, {{0, 1}, {0, 2}, {1, 3}, {2, 3}, {1, 4}}};
  // degrees: 0:2, 1:3, 2:2, 3:2, 4:1. Paths 0-1-3: 1 + 1 = 2; 0-2-3: 0 + 0 = 0.
  const cge::Graph<double> g = to_graph(sg);
  const auto all = cge::shortest_path_degree_sums(g, TieMode::all);
  const auto mean = cge::shortest_path_degree_sums(g, TieMode::mean);
  const auto min = cge::shortest_path_degree_sums(g, TieMode::min);
  // Distance 2 from 0: node 3 (sums 2 and 0) and node 4 via 0-1-4 (1 + 2 = 3).
  REQUIRE(all.delta(0, 2) == 5.0);
  REQUIRE(mean.delta(0, 2) == 4.0);
  REQUIRE(min.delta(0, 2) == 3.0);
  // Distance 1 from 0: nodes 1 (|2-3| = 1) and 2 (0): no ties, all modes agree.
  REQUIRE(all.delta(0, 1) == 1.0);
  REQUIRE(mean.delta(0, 1) == 1.0);
  REQUIRE(min.delta(0, 1) == 1.0);
}

TEST_CASE("shortest_path_degree_sums agrees with path enumeration beyond one block of 64 sources", "[dde][oracle]") {
  // The sweep runs 64 sources at a time: sizes around multiples of 64, and components that a
  // block straddles.
  std::mt19937 rng(6464);
  std::vector<SmallGraph> graphs;
  for (const int n : {63, 64, 65, 100, 127, 128, 129, 150}) {
    graphs.push_back(random_connected(rng, n, n / 5, "big"));
  }
  graphs.push_back(grid_graph(8, 9));
  graphs.push_back(relabel(grid_graph(7, 10), random_permutation(rng, 70)));
  graphs.push_back(complete_bipartite(3, 70));
  {
    SmallGraph g = disjoint_union(random_connected(rng, 40, 10, "a"),
                                  disjoint_union(random_connected(rng, 50, 8, "b"), isolated(3)));
    graphs.push_back(relabel(g, random_permutation(rng, g.n)));
  }
  graphs.push_back(random_gnp(rng, 130, 0.012, "sparse"));  // many small components
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO("graph " << sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode));
      require_table_matches(cge::shortest_path_degree_sums(g, mode), oracle_delta(sg, mode));
    }
  }
}

TEST_CASE("shortest_path_degree_sums agrees with a scalar BFS on larger tie-rich graphs", "[dde][oracle]") {
  std::mt19937 rng(31337);
  std::vector<SmallGraph> graphs;
  graphs.push_back(grid_graph(18, 20));
  graphs.push_back(with_random_chords(rng, grid_graph(15, 15), 20));
  graphs.push_back(relabel(complete_bipartite(20, 45), random_permutation(rng, 65)));
  graphs.push_back(random_connected(rng, 300, 150, "c"));
  {
    SmallGraph g = disjoint_union(grid_graph(9, 9), disjoint_union(random_connected(rng, 120, 60, "d"), isolated(5)));
    graphs.push_back(relabel(g, random_permutation(rng, g.n)));
  }
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO("graph " << sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode));
      require_table_matches(cge::shortest_path_degree_sums(g, mode), scalar_bfs_delta(sg, mode));
    }
  }
  // The scalar reference itself agrees with path enumeration on the small zoo.
  for (const SmallGraph& sg : small_graph_zoo(60)) {
    for (const TieMode mode : kTieModes) {
      const OracleTable a = oracle_delta(sg, mode);
      const OracleTable b = scalar_bfs_delta(sg, mode);
      REQUIRE(a.diameter == b.diameter);
      for (int v = 0; v < sg.n; ++v) {
        for (std::size_t k = 0; k < a.delta[static_cast<std::size_t>(v)].size(); ++k) {
          REQUIRE(close(b.delta[static_cast<std::size_t>(v)][k], a.delta[static_cast<std::size_t>(v)][k], 1e-15L));
        }
      }
    }
  }
}

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

// ---------------------------------------------------------------------------------------------
// Worked values of ALGORITHMS.md section 4 (exp coefficients, log2, lambda = 1)
// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------

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

TEST_CASE("softmax_entropy_bits works in the log domain", "[dde][numerics]") {
  // Two equal weights: 1 bit, however small the weights are.
  CHECK(cge::softmax_entropy_bits({-1e5, -1e5}) == Approx(1.0).epsilon(1e-15));
  CHECK(cge::softmax_entropy_bits({-2e5, -1e5, -1e5, -3e5}) == Approx(1.0).epsilon(1e-15));
  CHECK(cge::softmax_entropy_bits({1e5, 1e5, 1e5, 1e5}) == Approx(2.0).epsilon(1e-15));
  // e^-1e5 against e^-2e5: all mass on the first, H = 0 (the second term is e^-1e5 log e^-1e5).
  const double h = cge::softmax_entropy_bits({-1e5, -2e5});
  CHECK(std::isfinite(h));
  CHECK(h == Approx(0.0).margin(1e-300));
  // p = (1/4, 3/4) encoded with an enormous common offset: H = 2 - (3/4) log2 3.
  const double offset = -1e5;
  CHECK(cge::softmax_entropy_bits({offset, offset + std::log(3.0)}) ==
        Approx(2.0 - 0.75 * std::log2(3.0)).epsilon(1e-9));
  // Against the plain formula where the plain formula works.
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<double> logs(static_cast<std::size_t>(1 + trial % 17));
    for (double& l : logs) l = u(rng);
    LD z = 0;
    for (double l : logs) z += std::exp(static_cast<LD>(l));
    LD expected = 0;
    for (double l : logs) {
      const LD p = std::exp(static_cast<LD>(l)) / z;
      expected -= p * std::log2(p);
    }
    CHECK(close(cge::softmax_entropy_bits(logs), expected, 1e-13L));
  }
  CHECK(cge::softmax_entropy_bits({42.0}) == 0.0);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({}), std::invalid_argument);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({0.0, std::numeric_limits<double>::infinity()}), std::overflow_error);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({0.0, -std::numeric_limits<double>::infinity()}), std::overflow_error);
  CHECK_THROWS_AS(cge::softmax_entropy_bits({std::numeric_limits<double>::quiet_NaN()}), std::overflow_error);
}

// ---------------------------------------------------------------------------------------------
// Kernels of the sweep
// ---------------------------------------------------------------------------------------------

TEST_CASE("degree sum kernels: each available kernel agrees with path enumeration", "[dde][oracle][kernel]") {
  if (!cge::degree_sum_kernel_available(cge::DegreeSumKernel::avx512)) {
    WARN("skipped for the avx512 kernel: this CPU or build cannot run it; the portable kernel is checked");
  }
  std::vector<SmallGraph> zoo = small_graph_zoo(150);
  std::mt19937 rng(515);
  for (const int n : {63, 64, 65, 129}) zoo.push_back(random_connected(rng, n, n / 4, "block"));
  for (const SmallGraph& sg : zoo) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      const OracleTable expected = oracle_delta(sg, mode);
      for (const cge::DegreeSumKernel kernel : available_kernels()) {
        INFO("kernel " << kernel_name(kernel) << ", graph " << sg.name << ", ties " << tie_name(mode));
        require_table_matches(cge::shortest_path_degree_sums(g, mode, kernel), expected);
      }
    }
  }
}

TEST_CASE("degree sum kernels: bit for bit equal to an ordered scalar reference and to each other", "[dde][kernel]") {
  std::mt19937 rng(2718);
  std::vector<SmallGraph> graphs;
  graphs.push_back(geometric_graph(300, 11));
  graphs.push_back(geometric_graph(700, 12));  // 11 blocks of 64 sources
  graphs.push_back(grid_graph(20, 20));        // ties everywhere
  graphs.push_back(with_random_chords(rng, grid_graph(12, 15), 12));
  // Many lanes per node and per predecessor: more than 16 and more than 32 of the 64.
  graphs.push_back(complete_bipartite(3, 70));
  graphs.push_back(relabel(complete_bipartite(20, 110), random_permutation(rng, 130)));
  graphs.push_back(star_of_cliques(6, 9));  // degrees up to 54
  {
    SmallGraph g = disjoint_union(grid_graph(7, 9), disjoint_union(random_connected(rng, 90, 30, "d"), isolated(4)));
    graphs.push_back(relabel(g, random_permutation(rng, g.n)));  // blocks straddle components
  }
  graphs.push_back(random_gnp(rng, 200, 0.012, "sparse"));  // many small components
  // Path counts far beyond 2^53 with many significant bits (6^120, 7^100, about C(70, 35)), times
  // degree differences that are not powers of two (10, 12, 3, 5, ...): products and sums round, so
  // a fused multiply-add or another order of three or more predecessors shows (both checked by
  // planting them in the kernel).
  graphs.push_back(diamond_chain(6, 120));
  graphs.push_back(diamond_chain(7, 100));
  graphs.push_back(decorated_grid(36, 36, false));
  graphs.push_back(decorated_grid(36, 36, true));
  for (int i = 0; i < 20; ++i) {
    graphs.push_back(random_gnp(rng, std::uniform_int_distribution<int>(2, 160)(rng),
                                std::uniform_real_distribution<double>(0.01, 0.3)(rng), "r" + std::to_string(i)));
  }
  long long compared = 0;
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      const cge::DegreeSumTable expected = ordered_reference(sg, mode);
      for (const cge::DegreeSumKernel kernel : available_kernels()) {
        INFO("kernel " << kernel_name(kernel) << ", graph " << sg.name << " (" << sg.n << " nodes), ties "
                       << tie_name(mode));
        const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, mode, kernel);
        REQUIRE(same_bits(table, expected));
        compared += static_cast<long long>(table.values.size());
      }
    }
  }
  CHECK(compared > 100000);
}

TEST_CASE("degree sum kernels: graphs with float weights and DegreeDegreeEntropy<float>", "[dde][kernel]") {
  std::mt19937 rng(31);
  for (const SmallGraph& sg :
       {geometric_graph(200, 5), grid_graph(9, 11), complete_bipartite(4, 40), random_gnp(rng, 120, 0.03, "f")}) {
    std::vector<cge::Edge<float>> edges;
    for (const auto& [u, v] : sg.edges) edges.push_back(cge::Edge<float>{u, v, 1.0f});
    const cge::Graph<float> gf = cge::Graph<float>::from_edges(sg.n, edges, false);
    for (const TieMode mode : kTieModes) {
      const cge::DegreeSumTable expected = ordered_reference(sg, mode);
      cge::DegreeDegreeSettings<float> settings;
      settings.ties = mode;
      const cge::DegreeDegreeEntropy<float> dde(settings);
      const cge::DegreeDegreeResult<float> by_default = dde.compute(gf);
      for (const cge::DegreeSumKernel kernel : available_kernels()) {
        INFO("kernel " << kernel_name(kernel) << ", graph " << sg.name << ", ties " << tie_name(mode));
        const cge::DegreeSumTable table = cge::shortest_path_degree_sums(gf, mode, kernel);
        REQUIRE(same_bits(table, expected));
        const cge::DegreeDegreeResult<float> r = dde.from_table(table);
        REQUIRE(r.exponents == by_default.exponents);
        REQUIRE(r.entropy_bits == by_default.entropy_bits);
        REQUIRE(r.information_index == by_default.information_index);
      }
    }
  }
}

TEST_CASE("degree sum kernels: huge path counts (overflow, exact rescaling) behave the same",
          "[dde][kernel][numerics]") {
  // 8^345 = 2^1035 shortest paths: TieMode::all overflows to inf (and the entropy reports it),
  // TieMode::mean rescales whole levels by 2^-512, TieMode::min needs no counts.
  const SmallGraph sg = diamond_chain(8, 345);
  const cge::Graph<double> g = to_graph(sg);
  for (const TieMode mode : {TieMode::mean, TieMode::min}) {
    const cge::DegreeSumTable expected = ordered_reference(sg, mode);
    for (const cge::DegreeSumKernel kernel : available_kernels()) {
      INFO("kernel " << kernel_name(kernel) << ", ties " << tie_name(mode));
      REQUIRE(same_bits(cge::shortest_path_degree_sums(g, mode, kernel), expected));
    }
  }
  cge::DegreeDegreeSettings<double> all;
  all.ties = TieMode::all;
  for (const cge::DegreeSumKernel kernel : available_kernels()) {
    INFO("kernel " << kernel_name(kernel));
    const cge::DegreeSumTable table = cge::shortest_path_degree_sums(g, TieMode::all, kernel);
    CHECK_THROWS_AS(cge::DegreeDegreeEntropy<double>(all).from_table(table), std::overflow_error);
  }
}

TEST_CASE("degree sum kernels: availability and an explicit request that cannot run", "[dde][kernel][errors]") {
  CHECK(cge::degree_sum_kernel_available(cge::DegreeSumKernel::automatic));
  CHECK(cge::degree_sum_kernel_available(cge::DegreeSumKernel::portable));
  const cge::Graph<double> g = to_graph(path_graph(4));
  if (cge::degree_sum_kernel_available(cge::DegreeSumKernel::avx512)) {
    CHECK(same_bits(cge::shortest_path_degree_sums(g, TieMode::all, cge::DegreeSumKernel::avx512),
                    cge::shortest_path_degree_sums(g, TieMode::all, cge::DegreeSumKernel::portable)));
    WARN("skipped: the avx512 kernel runs here, so the error for an unavailable kernel is not exercised");
  } else {
    const std::string message = cge_test::invalid_argument_message(
        [&] { cge::shortest_path_degree_sums(g, TieMode::all, cge::DegreeSumKernel::avx512); });
    CHECK_THAT(message, Catch::Contains("avx512") && Catch::Contains("AVX-512"));
  }
  CHECK_THROWS_AS(cge::shortest_path_degree_sums(cge::Graph<double>{}, TieMode::all, cge::DegreeSumKernel::portable),
                  std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// compute_index(): the entropy without the per-node exponents, and its parts
// ---------------------------------------------------------------------------------------------

namespace {

/// Eccentricities by one plain BFS per node (-1 distances ignored) and the component count.
std::pair<int, int> brute_diameter_and_components(const SmallGraph& sg) {
  const cge::Graph<double> g = to_graph(sg);
  int diameter = 0;
  std::vector<int> component(static_cast<std::size_t>(sg.n), -1);
  int components = 0;
  for (int s = 0; s < sg.n; ++s) {
    std::vector<int> dist(static_cast<std::size_t>(sg.n), -1);
    std::vector<int> queue{s};
    dist[static_cast<std::size_t>(s)] = 0;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      for (const int w : g.neighbors(queue[h])) {
        if (dist[static_cast<std::size_t>(w)] < 0) {
          dist[static_cast<std::size_t>(w)] = dist[static_cast<std::size_t>(queue[h])] + 1;
          queue.push_back(w);
        }
      }
    }
    for (const int d : dist) diameter = std::max(diameter, d);
    if (component[static_cast<std::size_t>(s)] < 0) {
      for (const int w : queue) component[static_cast<std::size_t>(w)] = components;
      ++components;
    }
  }
  return {diameter, components};
}

/// A single-source kernel for g with what it needs beside it (the bitset kernel's rows).
template <TieMode Mode, template <TieMode, typename> class Kernel>
struct KernelFor;

template <TieMode Mode>
struct KernelFor<Mode, cge::detail::SingleSourceDegreeSums> {
  explicit KernelFor(const cge::Graph<double>& g) : sums(g) {}
  cge::detail::SingleSourceDegreeSums<Mode, double> sums;
};

template <TieMode Mode>
struct KernelFor<Mode, cge::detail::BitsetSingleSourceDegreeSums> {
  explicit KernelFor(const cge::Graph<double>& g) : rows(g), sums(g, rows) {}
  cge::AdjacencyBitsets rows;
  cge::detail::BitsetSingleSourceDegreeSums<Mode, double> sums;
};

/// The table a single-source kernel (SingleSourceDegreeSums by default) gives when never stopped,
/// source by source.
template <TieMode Mode, template <TieMode, typename> class Kernel = cge::detail::SingleSourceDegreeSums>
cge::DegreeSumTable single_source_table(const cge::Graph<double>& g) {
  cge::DegreeSumTable t;
  t.num_nodes = g.num_nodes();
  t.row_offsets.assign(static_cast<std::size_t>(g.num_nodes()) + 1, 0);
  KernelFor<Mode, Kernel> kernel(g);
  auto& sums = kernel.sums;
  for (std::int32_t s = 0; s < g.num_nodes(); ++s) {
    std::int32_t expected_level = 1;
    const std::int32_t ecc = sums.run(s, [&](std::int32_t k, double delta) {
      REQUIRE(k == expected_level++);
      t.values.push_back(delta);
      return true;
    });
    REQUIRE(ecc == expected_level - 1);
    t.row_offsets[static_cast<std::size_t>(s) + 1] = static_cast<std::int64_t>(t.values.size());
    t.diameter = std::max(t.diameter, ecc);
  }
  t.connected = cge::hop_diameter(g).components <= 1;
  return t;
}

cge::DegreeSumTable single_source_table(const cge::Graph<double>& g, TieMode mode) {
  return cge::detail::with_tie_mode(mode, [&](auto m) { return single_source_table<decltype(m)::value>(g); });
}

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

/// Adds `count` twins of random nodes: each copies its original's neighbours, and is joined to the
/// original (a true twin) or not (a false twin); then relabels at random so twins are scattered.
SmallGraph with_planted_twins(std::mt19937& rng, const SmallGraph& base, int count) {
  SmallGraph g = base;
  g.name += "+twins";
  if (base.n == 0) return g;
  for (int i = 0; i < count; ++i) {
    const int original = std::uniform_int_distribution<int>(0, g.n - 1)(rng);
    const int twin = g.n++;
    std::vector<std::pair<int, int>> added;
    for (const auto& [u, v] : g.edges) {
      if (u == original) added.push_back({twin, v});
      if (v == original) added.push_back({u, twin});
    }
    if (std::uniform_int_distribution<int>(0, 1)(rng) == 1) added.push_back({original, twin});
    g.edges.insert(g.edges.end(), added.begin(), added.end());
  }
  return relabel(g, random_permutation(rng, g.n));
}

/// The twin classes by definition: for every pair, compare the neighbour sets (open, and closed
/// for adjacent pairs); a node's representative is the smallest node it shares either with.
std::vector<std::int32_t> brute_twin_representatives(const SmallGraph& sg) {
  std::vector<std::set<int>> open(static_cast<std::size_t>(sg.n));
  for (const auto& [u, v] : sg.edges) {
    open[static_cast<std::size_t>(u)].insert(v);
    open[static_cast<std::size_t>(v)].insert(u);
  }
  std::vector<std::int32_t> representative(static_cast<std::size_t>(sg.n));
  for (int v = 0; v < sg.n; ++v) {
    representative[static_cast<std::size_t>(v)] = v;
    for (int u = 0; u < v; ++u) {
      std::set<int> closed_u = open[static_cast<std::size_t>(u)], closed_v = open[static_cast<std::size_t>(v)];
      closed_u.insert(u);
      closed_v.insert(v);
      if (open[static_cast<std::size_t>(u)] == open[static_cast<std::size_t>(v)] || closed_u == closed_v) {
        representative[static_cast<std::size_t>(v)] = u;
        break;
      }
    }
  }
  return representative;
}

}  // namespace

TEST_CASE("hop_diameter equals the largest BFS eccentricity, with the component count", "[dde][diameter]") {
  std::vector<SmallGraph> graphs = small_graph_zoo(300);
  std::mt19937 rng(4242);
  graphs.push_back(geometric_graph(300, 3));
  graphs.push_back(geometric_graph(600, 4));
  graphs.push_back(grid_graph(15, 23));
  graphs.push_back(decorated_grid(12, 12, true));
  graphs.push_back(diamond_chain(3, 40));
  graphs.push_back(star_of_cliques(5, 6));
  for (int i = 0; i < 40; ++i) {
    const int n = std::uniform_int_distribution<int>(2, 200)(rng);
    graphs.push_back(
        random_gnp(rng, n, std::uniform_real_distribution<double>(0.005, 0.1)(rng), "d" + std::to_string(i)));
    graphs.push_back(random_connected(rng, n, std::uniform_int_distribution<int>(0, n)(rng), "c" + std::to_string(i)));
  }
  for (const SmallGraph& sg : graphs) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    const auto [diameter, components] = brute_diameter_and_components(sg);
    const cge::Graph<double> g = to_graph(sg);
    const cge::HopDiameter d = cge::hop_diameter(g);
    REQUIRE(d.diameter == diameter);
    REQUIRE(d.components == components);
    CHECK(d.searches <= sg.n);
    const cge::HopDiameter on_bitsets = cge::hop_diameter(g, cge::AdjacencyBitsets(g));
    REQUIRE(on_bitsets.diameter == diameter);
    REQUIRE(on_bitsets.components == components);
    REQUIRE(on_bitsets.searches == d.searches);  // the same distances, so the same sources
  }
  const cge::HopDiameter empty = cge::hop_diameter(cge::Graph<double>{});
  CHECK(empty.diameter == 0);
  CHECK(empty.components == 0);
  // Few searches where the bounds work: a long path needs only its two ends and a middle node.
  CHECK(cge::hop_diameter(to_graph(path_graph(500))).searches <= 3);
}

TEST_CASE("SingleSourceDegreeSums: bit for bit the ordered reference, and stops when asked", "[dde][kernel]") {
  std::mt19937 rng(31337);
  std::vector<SmallGraph> graphs = small_graph_zoo(60);
  graphs.push_back(geometric_graph(300, 11));
  graphs.push_back(with_random_chords(rng, grid_graph(12, 15), 12));
  graphs.push_back(star_of_cliques(6, 9));
  graphs.push_back(diamond_chain(6, 120));  // products and sums that round
  graphs.push_back(diamond_chain(8, 345));  // TieMode::mean rescales, TieMode::all overflows
  graphs.push_back(decorated_grid(20, 20, true));
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    for (const TieMode mode : kTieModes) {
      INFO(sg.name << " (" << sg.n << " nodes), ties " << tie_name(mode));
      REQUIRE(same_bits(single_source_table(g, mode), ordered_reference(sg, mode)));
    }
  }
  // A run stopped after level 2 makes no further call, returns 2, and leaves the next run intact.
  const SmallGraph sg = grid_graph(6, 7);
  const cge::Graph<double> g = to_graph(sg);
  cge::detail::SingleSourceDegreeSums<TieMode::all, double> sums(g);
  int calls = 0;
  CHECK(sums.run(0, [&](std::int32_t k, double) {
    ++calls;
    return k < 2;
  }) == 2);
  CHECK(calls == 2);
  CHECK(same_bits(single_source_table(g, TieMode::all), ordered_reference(sg, TieMode::all)));
}

namespace {

/// Layers of `width` nodes, each node joined to 2..4 random nodes of the layer before: path counts
/// pass 2^53 after a few dozen layers and differ from node to node, so sums round and the order in
/// which a node adds its predecessors shows in the last bits (with integer-exact values any order
/// gives the same bits, and an order test could not fail).
SmallGraph random_layered(std::mt19937& rng, int layers, int width) {
  SmallGraph g{"layered " + std::to_string(layers) + "x" + std::to_string(width), layers * width, {}};
  std::uniform_int_distribution<int> pick(0, width - 1), fan(2, 4);
  for (int layer = 1; layer < layers; ++layer) {
    for (int i = 0; i < width; ++i) {
      std::set<int> preds;
      const int want = fan(rng);
      while (static_cast<int>(preds.size()) < want) preds.insert(pick(rng));
      for (const int p : preds) g.edges.push_back({(layer - 1) * width + p, layer * width + i});
    }
  }
  return g;
}

/// Graphs for the single-source kernels: the zoo, the tie-rich families, huge counts, and node
/// orders that give the bitset kernel both short rows (GraphBuilder's canonical order) and rows
/// that span every word (a random relabelling), with more than 64 nodes and isolated nodes.
std::vector<SmallGraph> single_source_graphs(std::mt19937& rng) {
  std::vector<SmallGraph> graphs = small_graph_zoo(60);
  graphs.push_back(geometric_graph(300, 11));
  graphs.push_back(relabel(geometric_graph(200, 12), random_permutation(rng, 200)));
  graphs.push_back(with_random_chords(rng, grid_graph(12, 15), 12));
  graphs.push_back(star_of_cliques(6, 9));
  graphs.push_back(diamond_chain(6, 120));  // products and sums that round
  graphs.push_back(diamond_chain(8, 345));  // TieMode::mean rescales, TieMode::all overflows
  graphs.push_back(decorated_grid(20, 20, true));
  graphs.push_back(disjoint_union(geometric_graph(150, 13), isolated(70)));
  graphs.push_back(random_layered(rng, 60, 5));
  graphs.push_back(relabel(random_layered(rng, 50, 6), random_permutation(rng, 300)));
  return graphs;
}

/// Runs every source of g twice with the kernel, in random order: first stopped after a random
/// level (its deltas so far must be the reference row's), then in full (the whole row). A stopped
/// run must leave nothing behind that changes a later one.
template <TieMode Mode, template <TieMode, typename> class Kernel>
void require_stopped_runs_match(std::mt19937& rng, const cge::Graph<double>& g, const cge::DegreeSumTable& ref) {
  KernelFor<Mode, Kernel> kernel(g);
  auto& sums = kernel.sums;
  const std::vector<int> sources = random_permutation(rng, g.num_nodes());
  for (const int s : sources) {
    const std::int32_t ecc = ref.eccentricity(s);
    const std::int32_t stop = std::uniform_int_distribution<std::int32_t>(1, std::max(ecc, 1))(rng);
    std::int32_t calls = 0;
    const std::int32_t last = sums.run(s, [&](std::int32_t k, double delta) {
      ++calls;
      REQUIRE(k <= ecc);
      REQUIRE(std::memcmp(&delta, &ref.values[static_cast<std::size_t>(ref.row_offsets[s] + k - 1)], sizeof delta) ==
              0);
      return k < stop;
    });
    REQUIRE(last == std::min(stop, ecc));
    REQUIRE(calls == last);
    std::int32_t full_calls = 0;
    REQUIRE(sums.run(s, [&](std::int32_t k, double delta) {
      ++full_calls;
      REQUIRE(std::memcmp(&delta, &ref.values[static_cast<std::size_t>(ref.row_offsets[s] + k - 1)], sizeof delta) ==
              0);
      return true;
    }) == ecc);
    REQUIRE(full_calls == ecc);
  }
}

template <TieMode Mode>
void require_bitset_kernel_matches(std::mt19937& rng, const SmallGraph& sg) {
  const cge::Graph<double> g = to_graph(sg);
  const cge::DegreeSumTable ref = ordered_reference(sg, Mode);
  REQUIRE(same_bits(single_source_table<Mode, cge::detail::BitsetSingleSourceDegreeSums>(g), ref));
  require_stopped_runs_match<Mode, cge::detail::BitsetSingleSourceDegreeSums>(rng, g, ref);
  require_stopped_runs_match<Mode, cge::detail::SingleSourceDegreeSums>(rng, g, ref);
}

/// Hop distances from every node by plain BFS (-1: unreachable).
std::vector<std::vector<int>> all_distances(const SmallGraph& sg) {
  std::vector<std::vector<int>> adj(static_cast<std::size_t>(sg.n));
  for (const auto& [u, v] : sg.edges) {
    adj[static_cast<std::size_t>(u)].push_back(v);
    adj[static_cast<std::size_t>(v)].push_back(u);
  }
  std::vector<std::vector<int>> dist(static_cast<std::size_t>(sg.n),
                                     std::vector<int>(static_cast<std::size_t>(sg.n), -1));
  for (int s = 0; s < sg.n; ++s) {
    std::vector<int>& d = dist[static_cast<std::size_t>(s)];
    std::vector<int> queue{s};
    d[static_cast<std::size_t>(s)] = 0;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      for (const int w : adj[static_cast<std::size_t>(queue[h])]) {
        if (d[static_cast<std::size_t>(w)] < 0) {
          d[static_cast<std::size_t>(w)] = d[static_cast<std::size_t>(queue[h])] + 1;
          queue.push_back(w);
        }
      }
    }
  }
  return dist;
}

/// During every level of every source: level_begin()..level_end() are exactly the nodes at that
/// distance, ascending; Delta(s, k) is their node terms summed in that order, bit for bit; and the
/// term of (s, u) equals the term of (u, s), the symmetry weight_bounded_entropy builds on.
template <TieMode Mode, template <TieMode, typename> class Kernel>
void require_levels_and_symmetric_terms(const SmallGraph& sg) {
  const cge::Graph<double> g = to_graph(sg);
  const std::vector<std::vector<int>> dist = all_distances(sg);
  const std::size_t n = static_cast<std::size_t>(sg.n);
  std::vector<double> term(n * n, -1.0);
  KernelFor<Mode, Kernel> kernel(g);
  auto& sums = kernel.sums;
  for (int s = 0; s < sg.n; ++s) {
    sums.run(s, [&](std::int32_t k, double delta) {
      std::vector<std::int32_t> expected;
      for (int u = 0; u < sg.n; ++u) {
        if (dist[static_cast<std::size_t>(s)][static_cast<std::size_t>(u)] == k) expected.push_back(u);
      }
      REQUIRE(std::vector<std::int32_t>(sums.level_begin(), sums.level_end()) == expected);
      double layer = 0.0;
      for (const std::int32_t u : expected) {
        const double t = sums.node_term(u);
        layer += t;
        term[static_cast<std::size_t>(s) * n + static_cast<std::size_t>(u)] = t;
      }
      REQUIRE(std::memcmp(&layer, &delta, sizeof layer) == 0);
      return true;
    });
  }
  for (std::size_t s = 0; s < n; ++s) {
    for (std::size_t u = 0; u < n; ++u) {
      if (dist[s][u] <= 0) continue;
      INFO("pair " << s << ", " << u);
      REQUIRE(term[s * n + u] == Approx(term[u * n + s]).epsilon(1e-13));
    }
  }
}

}  // namespace

TEST_CASE("BitsetSingleSourceDegreeSums: bit for bit the ordered reference, stopped anywhere", "[dde][kernel]") {
  std::mt19937 rng(4242);
  for (const SmallGraph& sg : single_source_graphs(rng)) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    require_bitset_kernel_matches<TieMode::all>(rng, sg);
    require_bitset_kernel_matches<TieMode::mean>(rng, sg);
    require_bitset_kernel_matches<TieMode::min>(rng, sg);
  }
}

TEST_CASE("single-source kernels: the level lists, and node terms symmetric in the pair", "[dde][kernel]") {
  std::mt19937 rng(5151);
  std::vector<SmallGraph> graphs = small_graph_zoo(30);
  graphs.push_back(geometric_graph(150, 14));
  graphs.push_back(relabel(geometric_graph(120, 15), random_permutation(rng, 120)));
  graphs.push_back(decorated_grid(8, 9, true));
  graphs.push_back(with_planted_twins(rng, star_of_cliques(3, 5), 4));
  for (const SmallGraph& sg : graphs) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    require_levels_and_symmetric_terms<TieMode::all, cge::detail::SingleSourceDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::mean, cge::detail::SingleSourceDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::min, cge::detail::SingleSourceDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::all, cge::detail::BitsetSingleSourceDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::mean, cge::detail::BitsetSingleSourceDegreeSums>(sg);
    require_levels_and_symmetric_terms<TieMode::min, cge::detail::BitsetSingleSourceDegreeSums>(sg);
  }
}

TEST_CASE("AdjacencyBitsets: the rows are the neighbour sets, and pay on short rows only", "[dde][kernel]") {
  std::mt19937 rng(6161);
  const SmallGraph built = geometric_graph(1000, 16);
  const SmallGraph shuffled = relabel(built, random_permutation(rng, built.n));
  CHECK(cge::AdjacencyBitsets::rows_pay(to_graph(built)));
  CHECK_FALSE(cge::AdjacencyBitsets::rows_pay(to_graph(shuffled)));
  CHECK_FALSE(cge::AdjacencyBitsets::rows_pay(cge::Graph<double>{}));
  for (const SmallGraph& sg : {built, shuffled, disjoint_union(star_of_cliques(3, 30), isolated(70))}) {
    const cge::Graph<double> g = to_graph(sg);
    const cge::AdjacencyBitsets rows(g);
    REQUIRE(rows.words() == (static_cast<std::size_t>(sg.n) + 63) / 64);
    std::size_t stored = 0;
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
      std::set<std::int32_t> expected(g.neighbors(v).begin(), g.neighbors(v).end());
      std::set<std::int32_t> found;
      const cge::AdjacencyBitsets::Span span = rows.span(v);
      for (std::size_t w = span.first; w < span.end; ++w) {
        for (int b = 0; b < 64; ++b) {
          if ((rows.stored_row(v)[w - span.first] >> b) & 1u)
            found.insert(static_cast<std::int32_t>(w * 64 + static_cast<std::size_t>(b)));
        }
      }
      REQUIRE(found == expected);
      if (!expected.empty()) {  // the span is tight: its first and last words hold a neighbour
        REQUIRE(span.first == static_cast<std::size_t>(*expected.begin()) / 64);
        REQUIRE(span.end == static_cast<std::size_t>(*expected.rbegin()) / 64 + 1);
      } else {
        REQUIRE(span.end == span.first);
      }
      stored += span.end - span.first;
    }
    REQUIRE(rows.stored_words() == stored);
  }
}

namespace {

template <TieMode Mode>
void require_kernels_agree_on_bounded_entropy(const cge::Graph<double>& g, const std::vector<double>& c, double alpha,
                                              double cut, int& graphs_with_skips) {
  using cge::detail::BitsetSingleSourceDegreeSums;
  using cge::detail::SingleSourceDegreeSums;
  const double log_alpha = std::log(alpha);
  KernelFor<Mode, SingleSourceDegreeSums> list_kernel(g);
  KernelFor<Mode, BitsetSingleSourceDegreeSums> bitset_kernel(g);
  const auto list = cge::detail::weight_bounded_entropy_with(g, list_kernel.sums, c, log_alpha, cut);
  const auto bits = cge::detail::weight_bounded_entropy_with(g, bitset_kernel.sums, c, log_alpha, cut);
  REQUIRE(std::memcmp(&list.entropy_bits, &bits.entropy_bits, sizeof(double)) == 0);
  REQUIRE(list.exponents_evaluated == bits.exponents_evaluated);
  REQUIRE(list.searches_skipped == bits.searches_skipped);
  graphs_with_skips += list.searches_skipped > 0;
}

}  // namespace

TEST_CASE("weight_bounded_entropy: the same bits with either kernel; other searches' terms skip searches",
          "[dde][index]") {
  // What the result must be is the [index] definition test's business (through compute_index);
  // here: the kernel changes nothing, and the bound from other searches' terms does skip searches.
  std::mt19937 rng(7373);
  std::vector<SmallGraph> graphs;
  for (int i = 0; i < 20; ++i) graphs.push_back(random_connected(rng, 60 + 5 * i, 40 + 3 * i, "r" + std::to_string(i)));
  graphs.push_back(geometric_graph(300, 17));
  graphs.push_back(geometric_graph(600, 18));
  graphs.push_back(with_planted_twins(rng, geometric_graph(250, 19), 40));
  graphs.push_back(decorated_grid(12, 12, true));
  int graphs_with_skips = 0;
  for (const SmallGraph& sg : graphs) {
    const cge::Graph<double> g = to_graph(sg);
    const cge::HopDiameter d = cge::hop_diameter(g);
    std::vector<double> c(static_cast<std::size_t>(d.diameter) + 1, 0.0);
    for (std::int32_t k = 1; k <= d.diameter; ++k) c[static_cast<std::size_t>(k)] = d.diameter * std::exp(1.0 - k);
    for (const double alpha : {0.5, 0.95}) {
      for (const double cut : {3.0, 100.0}) {
        INFO(sg.name << ", alpha " << alpha << ", G " << cut);
        require_kernels_agree_on_bounded_entropy<TieMode::all>(g, c, alpha, cut, graphs_with_skips);
        require_kernels_agree_on_bounded_entropy<TieMode::mean>(g, c, alpha, cut, graphs_with_skips);
        require_kernels_agree_on_bounded_entropy<TieMode::min>(g, c, alpha, cut, graphs_with_skips);
      }
    }
  }
  CHECK(graphs_with_skips > 30);
}

TEST_CASE("twin_classes: the nodes with equal open or closed neighbourhoods, by pairwise comparison", "[dde][twins]") {
  std::mt19937 rng(2718);
  std::vector<SmallGraph> graphs = small_graph_zoo(150);
  const std::size_t plain = graphs.size();
  for (std::size_t i = 0; i < plain; ++i) {
    graphs.push_back(with_planted_twins(rng, graphs[i], std::uniform_int_distribution<int>(1, 6)(rng)));
  }
  graphs.push_back(star_of_cliques(4, 7));
  graphs.push_back(with_planted_twins(rng, geometric_graph(300, 17), 40));
  int with_twins = 0;
  for (const SmallGraph& sg : graphs) {
    INFO(sg.name << " (" << sg.n << " nodes)");
    const std::vector<std::int32_t> expected = brute_twin_representatives(sg);
    const cge::TwinClasses twins = cge::twin_classes(to_graph(sg));
    REQUIRE(twins.representative == expected);
    std::int32_t classes = 0;
    for (std::int32_t v = 0; v < sg.n; ++v) classes += expected[static_cast<std::size_t>(v)] == v;
    REQUIRE(twins.num_classes == classes);
    with_twins += classes < sg.n;
  }
  CHECK(with_twins > 150);  // the planted ones at least
  CHECK(cge::twin_classes(cge::Graph<double>{}).num_classes == 0);
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
