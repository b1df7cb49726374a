#pragma once
// Delta(v, k) of ALGORITHMS.md section 4: over the shortest paths of length k that start at v, the
// sums of absolute degree differences along the path, computed exactly in O(|V| |E|) by one BFS
// dynamic programme per source, without listing paths.
//
// For a source s and every node u (predecessors p of u have dist(p) = dist(u) - 1):
//   N[u] = sum_p N[p]                               number of shortest s-u paths
//   S[u] = sum_p (S[p] + N[p] |d(p) - d(u)|)        sum over those paths of their degree sums
//   M[u] = min_p (M[p] + |d(p) - d(u)|)             smallest degree sum over those paths
// and Delta(s, k) sums, over the nodes u at distance k, S[u] (TieMode::all), S[u] / N[u]
// (TieMode::mean) or M[u] (TieMode::min). All three depend only on the graph, never on node
// numbering. N and S are kept in double: path counts grow exponentially on tie-rich graphs.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "cge/graph/graph.hpp"

namespace cge {

/// How several shortest paths between the same two nodes count in Delta.
enum class TieMode {
  all,   ///< every shortest path counts with its own sum (multiplicity; the default)
  mean,  ///< one averaged path per end node: the mean sum over its shortest paths
  min,   ///< one path per end node: the shortest path with the smallest sum
};

/// Delta(s, k) for every source s and k = 1..eccentricity(s), stored row by row.
struct DegreeSumTable {
  std::int32_t num_nodes = 0;
  std::int32_t diameter = 0;  ///< largest finite hop distance
  bool connected = true;      ///< false when some pair of nodes is unreachable
  std::vector<std::int64_t> row_offsets;  ///< num_nodes + 1 entries into values
  std::vector<double> values;             ///< row s holds Delta(s, 1), ..., Delta(s, ecc(s))

  std::int32_t eccentricity(std::int32_t s) const {
    return static_cast<std::int32_t>(row_offsets[static_cast<std::size_t>(s) + 1] - row_offsets[static_cast<std::size_t>(s)]);
  }
  /// Delta(s, k) for k >= 1; 0 beyond the eccentricity of s.
  double delta(std::int32_t s, std::int32_t k) const {
    if (k < 1 || k > eccentricity(s)) return 0.0;
    return values[static_cast<std::size_t>(row_offsets[static_cast<std::size_t>(s)] + k - 1)];
  }
};

namespace detail {

/// Scratch arrays of one BFS, reused across sources.
struct BfsScratch {
  std::vector<std::int32_t> dist;
  std::vector<std::int32_t> queue;
  std::vector<double> count;  // N
  std::vector<double> sum;    // S (all, mean) or M (min)
  std::vector<double> degree;
  explicit BfsScratch(std::int32_t n)
      : dist(static_cast<std::size_t>(n), -1), queue(static_cast<std::size_t>(n)), count(static_cast<std::size_t>(n)),
        sum(static_cast<std::size_t>(n)), degree(static_cast<std::size_t>(n)) {}
};

/// One BFS from s; appends Delta(s, 1..ecc(s)) to `layers` and returns how many nodes it reached.
template <TieMode Mode, typename Scalar>
std::int32_t degree_sums_from(const Graph<Scalar>& g, std::int32_t s, BfsScratch& w, std::vector<double>& layers) {
  const std::int32_t* offsets = g.csr_offsets().data();
  const std::int32_t* adjacency = g.csr_adjacency().data();
  std::int32_t* dist = w.dist.data();
  std::int32_t* queue = w.queue.data();
  double* count = w.count.data();
  double* sum = w.sum.data();
  const double* degree = w.degree.data();

  layers.clear();
  dist[s] = 0;
  count[s] = 1.0;
  sum[s] = 0.0;
  queue[0] = s;
  std::int32_t head = 0;
  std::int32_t tail = 1;
  std::int32_t layer = 0;
  double layer_sum = 0.0;
  while (head < tail) {
    const std::int32_t u = queue[head++];
    const std::int32_t du = dist[u];
    if (du != layer) {  // BFS order: layers arrive one after another
      if (layer > 0) layers.push_back(layer_sum);
      layer = du;
      layer_sum = 0.0;
    }
    const double nu = count[u];
    const double su = sum[u];
    if (Mode == TieMode::all) layer_sum += su;
    if (Mode == TieMode::mean) layer_sum += su / nu;
    if (Mode == TieMode::min) layer_sum += su;
    const double deg_u = degree[u];
    const std::int32_t next = du + 1;
    for (std::int32_t e = offsets[u], end = offsets[u + 1]; e < end; ++e) {
      const std::int32_t v = adjacency[e];
      std::int32_t dv = dist[v];
      if (dv < 0) {
        dist[v] = dv = next;
        queue[tail++] = v;
        count[v] = 0.0;
        sum[v] = Mode == TieMode::min ? std::numeric_limits<double>::infinity() : 0.0;
      }
      if (dv == next) {
        const double diff = std::fabs(deg_u - degree[v]);
        if (Mode == TieMode::min) {
          sum[v] = std::min(sum[v], su + diff);
        } else {
          count[v] += nu;
          sum[v] += su + nu * diff;
        }
      }
    }
  }
  if (layer > 0) layers.push_back(layer_sum);
  for (std::int32_t i = 0; i < tail; ++i) dist[queue[i]] = -1;
  return tail;
}

template <TieMode Mode, typename Scalar>
void fill_table(const Graph<Scalar>& g, DegreeSumTable& table) {
  const std::int32_t n = g.num_nodes();
  BfsScratch scratch(n);
  for (std::int32_t v = 0; v < n; ++v) scratch.degree[static_cast<std::size_t>(v)] = g.degree(v);
  std::vector<double> layers;
  layers.reserve(static_cast<std::size_t>(n));
  table.row_offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  for (std::int32_t s = 0; s < n; ++s) {
    const std::int32_t reached = degree_sums_from<Mode>(g, s, scratch, layers);
    if (reached < n) table.connected = false;
    table.values.insert(table.values.end(), layers.begin(), layers.end());
    table.row_offsets[static_cast<std::size_t>(s) + 1] = static_cast<std::int64_t>(table.values.size());
    table.diameter = std::max(table.diameter, static_cast<std::int32_t>(layers.size()));
  }
}

}  // namespace detail

/// Delta(s, k) for every source and distance. Throws std::invalid_argument on an empty graph.
template <typename Scalar>
DegreeSumTable shortest_path_degree_sums(const Graph<Scalar>& g, TieMode ties = TieMode::all) {
  if (g.num_nodes() == 0) throw std::invalid_argument("degree-degree entropy: the graph has no nodes");
  DegreeSumTable table;
  table.num_nodes = g.num_nodes();
  switch (ties) {
    case TieMode::all: detail::fill_table<TieMode::all>(g, table); break;
    case TieMode::mean: detail::fill_table<TieMode::mean>(g, table); break;
    case TieMode::min: detail::fill_table<TieMode::min>(g, table); break;
  }
  return table;
}

}  // namespace cge
