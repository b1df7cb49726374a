#pragma once
// What the degree-degree entropy tests share (docs/METHOD.md section 4): small graphs and graph
// families (tie-rich, disconnected, frame-like, huge path counts), and the oracles that do not
// share code with the library: Delta by enumerating every shortest path, Delta by a scalar BFS in
// long double, and E, H, I by the direct formula alpha^E in long double. The bit-exact reference
// the kernels are held to is a library header (cge/entropy/reference_degree_degree_entropy.hpp),
// itself checked against these oracles in test_reference_degree_degree_entropy.cpp.

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
#include <string>
#include <utility>
#include <vector>

#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/kernels/single_source_bfs.hpp"
#include "cge/entropy/kernels/single_source_bitset_bfs.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/graph/hop_diameter.hpp"
#include "test_support.hpp"

namespace dde_test {

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

inline cge::Graph<double> to_graph(const SmallGraph& s) {
  std::vector<cge::Edge<double>> e;
  for (const auto& [u, v] : s.edges) e.push_back(cge::Edge<double>{u, v, 1.0});
  return cge::Graph<double>::from_edges(s.n, e, false);
}

inline SmallGraph path_graph(int n) {
  SmallGraph g{"P" + std::to_string(n), n, {}};
  for (int i = 0; i + 1 < n; ++i) g.edges.push_back({i, i + 1});
  return g;
}

inline SmallGraph cycle_graph(int n) {
  SmallGraph g = path_graph(n);
  g.name = "C" + std::to_string(n);
  g.edges.push_back({n - 1, 0});
  return g;
}

inline SmallGraph complete_graph(int n) {
  SmallGraph g{"K" + std::to_string(n), n, {}};
  for (int u = 0; u < n; ++u)
    for (int v = u + 1; v < n; ++v) g.edges.push_back({u, v});
  return g;
}

inline SmallGraph complete_bipartite(int a, int b) {
  SmallGraph g{"K" + std::to_string(a) + "," + std::to_string(b), a + b, {}};
  for (int u = 0; u < a; ++u)
    for (int v = 0; v < b; ++v) g.edges.push_back({u, a + v});
  return g;
}

inline SmallGraph grid_graph(int rows, int cols) {
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

inline SmallGraph hypercube3() {
  SmallGraph g{"Q3", 8, {}};
  for (int u = 0; u < 8; ++u)
    for (int b = 0; b < 3; ++b) {
      const int v = u ^ (1 << b);
      if (u < v) g.edges.push_back({u, v});
    }
  return g;
}

inline SmallGraph petersen() {
  SmallGraph g{"Petersen", 10, {}};
  for (int i = 0; i < 5; ++i) {
    g.edges.push_back({i, (i + 1) % 5});          // outer cycle
    g.edges.push_back({i, i + 5});                // spokes
    g.edges.push_back({5 + i, 5 + (i + 2) % 5});  // inner pentagram
  }
  return g;
}

inline SmallGraph wheel(int rim) {
  SmallGraph g = cycle_graph(rim);
  g.name = "W" + std::to_string(rim);
  g.n = rim + 1;
  for (int i = 0; i < rim; ++i) g.edges.push_back({rim, i});
  return g;
}

inline SmallGraph disjoint_union(const SmallGraph& a, const SmallGraph& b) {
  SmallGraph g{a.name + "+" + b.name, a.n + b.n, a.edges};
  for (const auto& [u, v] : b.edges) g.edges.push_back({u + a.n, v + a.n});
  return g;
}

inline SmallGraph isolated(int n) { return SmallGraph{"I" + std::to_string(n), n, {}}; }

/// Node v becomes perm[v].
inline SmallGraph relabel(const SmallGraph& g, const std::vector<int>& perm) {
  SmallGraph out{g.name + "(relabelled)", g.n, {}};
  for (const auto& [u, v] : g.edges)
    out.edges.push_back({perm[static_cast<std::size_t>(u)], perm[static_cast<std::size_t>(v)]});
  return out;
}

inline SmallGraph random_gnp(std::mt19937& rng, int n, double p, const std::string& tag) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SmallGraph g{tag + "-G(" + std::to_string(n) + "," + std::to_string(p) + ")", n, {}};
  for (int u = 0; u < n; ++u)
    for (int v = u + 1; v < n; ++v)
      if (unit(rng) < p) g.edges.push_back({u, v});
  return g;
}

/// Random tree plus extra random edges: connected.
inline SmallGraph random_connected(std::mt19937& rng, int n, int extra, const std::string& tag) {
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
inline SmallGraph with_random_chords(std::mt19937& rng, const SmallGraph& base, int chords) {
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

inline std::vector<int> random_permutation(std::mt19937& rng, int n) {
  std::vector<int> perm(static_cast<std::size_t>(n));
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  return perm;
}

/// Structured families (tie-rich, regular, disconnected) followed by `random_count` random graphs.
inline std::vector<SmallGraph> small_graph_zoo(int random_count) {
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

inline bool close(LD actual, LD expected, LD rel) {
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

inline OracleTable oracle_delta(const SmallGraph& g, TieMode mode) {
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
/// docs/METHOD.md section 4 with one plain BFS per source, in long double.
inline OracleTable scalar_bfs_delta(const SmallGraph& g, TieMode mode) {
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

inline void require_table_matches(const cge::DegreeSumTable& table, const OracleTable& expected) {
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

inline OracleEntropy oracle_entropy(const OracleTable& t, const std::function<LD(int, int)>& coefficient, bool normalise,
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

inline LD exp_coefficient(int k, int rho) { return static_cast<LD>(rho) * std::exp(LD(1) - LD(k)); }
inline LD linear_coefficient(int k, int rho) { return static_cast<LD>(rho - k + 1); }
inline LD constant_coefficient(int, int) { return 1; }

/// A custom coefficient policy for the tests: increasing in k, depending on rho.
struct RampCoefficient {
  double operator()(int k, int rho) const { return 0.5 * k + 1.0 / (1.0 + rho); }
};
inline LD ramp_coefficient(int k, int rho) { return LD(0.5) * k + LD(1) / (LD(1) + rho); }

inline const char* tie_name(TieMode m) {
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

inline const TieMode kTieModes[] = {TieMode::all, TieMode::mean, TieMode::min};

template <typename Entropy>
inline void check_against_oracle(const Entropy& dde, const cge::Graph<double>& g, const OracleTable& table,
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
inline std::vector<cge::DegreeSumKernel> available_kernels() {
  std::vector<cge::DegreeSumKernel> kernels{cge::DegreeSumKernel::automatic, cge::DegreeSumKernel::portable};
  if (cge::degree_sum_kernel_available(cge::DegreeSumKernel::avx512)) kernels.push_back(cge::DegreeSumKernel::avx512);
  return kernels;
}

inline const char* kernel_name(cge::DegreeSumKernel k) {
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

/// Bit for bit, including the signs of zeros (infinities and NaNs compare by their bits too).
inline bool same_bits(const cge::DegreeSumTable& a, const cge::DegreeSumTable& b) {
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

inline SmallGraph star_of_cliques(int cliques, int size) {
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
inline SmallGraph geometric_graph(int n, std::uint32_t seed) {
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
inline SmallGraph decorated_grid(int rows, int cols, bool king) {
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

inline SmallGraph diamond_chain(int width, int diamonds) {
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

/// A single-source kernel for g with what it needs beside it (the bitset kernel's rows).
template <TieMode Mode, template <TieMode, typename> class Kernel>
struct KernelFor;

template <TieMode Mode>
struct KernelFor<Mode, cge::detail::SingleSourceBfsDegreeSums> {
  explicit KernelFor(const cge::Graph<double>& g) : sums(g) {}
  cge::detail::SingleSourceBfsDegreeSums<Mode, double> sums;
};

template <TieMode Mode>
struct KernelFor<Mode, cge::detail::SingleSourceBitsetBfsDegreeSums> {
  explicit KernelFor(const cge::Graph<double>& g) : rows(g), sums(g, rows) {}
  cge::AdjacencyBitsets rows;
  cge::detail::SingleSourceBitsetBfsDegreeSums<Mode, double> sums;
};

/// The table a single-source kernel (SingleSourceBfsDegreeSums by default) gives when never stopped,
/// source by source.
template <TieMode Mode, template <TieMode, typename> class Kernel = cge::detail::SingleSourceBfsDegreeSums>
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

inline cge::DegreeSumTable single_source_table(const cge::Graph<double>& g, TieMode mode) {
  return cge::detail::with_tie_mode(mode, [&](auto m) { return single_source_table<decltype(m)::value>(g); });
}

/// Adds `count` twins of random nodes: each copies its original's neighbours, and is joined to the
/// original (a true twin) or not (a false twin); then relabels at random so twins are scattered.
inline SmallGraph with_planted_twins(std::mt19937& rng, const SmallGraph& base, int count) {
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

}  // namespace dde_test
