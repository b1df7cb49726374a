#pragma once
// Delta(v, k) of ALGORITHMS.md section 4: over the shortest paths of length k that start at v, the
// sums of absolute degree differences along the path, computed exactly in O(|V| |E|) by a BFS
// dynamic programme from every source, without listing paths.
//
// For a source s and every node u (predecessors p of u have dist(p) = dist(u) - 1):
//   N[u] = sum_p N[p]                               number of shortest s-u paths
//   S[u] = sum_p (S[p] + N[p] |d(p) - d(u)|)        sum over those paths of their degree sums
//   M[u] = min_p (M[p] + |d(p) - d(u)|)             smallest degree sum over those paths
// and Delta(s, k) sums, over the nodes u at distance k, S[u] (TieMode::all), S[u] / N[u]
// (TieMode::mean) or M[u] (TieMode::min). All three depend only on the graph, never on node
// numbering (up to floating-point rounding, as relabelling changes the summation order).
// N and S are kept in double: path counts grow exponentially on tie-rich graphs.
// The sweep runs 64 sources at once, one bit per source (see BitParallelDegreeSums): the same
// O(|V| |E|) arithmetic, but the BFS bookkeeping costs one word operation per 64 sources.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "cge/core/bits.hpp"
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
  std::int32_t diameter = 0;              ///< largest finite hop distance
  bool connected = true;                  ///< false when some pair of nodes is unreachable
  std::vector<std::int64_t> row_offsets;  ///< num_nodes + 1 entries into values
  std::vector<double> values;             ///< row s holds Delta(s, 1), ..., Delta(s, ecc(s))

  std::int32_t eccentricity(std::int32_t s) const {
    return static_cast<std::int32_t>(row_offsets[static_cast<std::size_t>(s) + 1] -
                                     row_offsets[static_cast<std::size_t>(s)]);
  }
  /// Delta(s, k) for k >= 1; 0 beyond the eccentricity of s.
  double delta(std::int32_t s, std::int32_t k) const {
    if (k < 1 || k > eccentricity(s)) return 0.0;
    return values[static_cast<std::size_t>(row_offsets[static_cast<std::size_t>(s)] + k - 1)];
  }
};

namespace detail {

/// Groups the nodes into blocks of up to 64 sources that lie close together in the graph (a BFS
/// ball grown from the lowest unassigned node), so that the blocks' BFS frontiers overlap and the
/// bit-parallel sweep wastes few words. Deterministic; the result values do not depend on it.
template <typename Scalar>
std::vector<std::int32_t> local_source_order(const Graph<Scalar>& g) {
  const std::int32_t n = g.num_nodes();
  std::vector<std::int32_t> order;
  order.reserve(static_cast<std::size_t>(n));
  std::vector<std::uint8_t> assigned(static_cast<std::size_t>(n), 0);
  std::vector<std::int32_t> seen_at(static_cast<std::size_t>(n), -1);
  std::vector<std::int32_t> queue;
  std::int32_t next_seed = 0;
  for (std::int32_t block = 0; static_cast<std::int32_t>(order.size()) < n; ++block) {
    while (assigned[static_cast<std::size_t>(next_seed)]) ++next_seed;
    std::size_t taken = 0;
    queue.assign(1, next_seed);
    seen_at[static_cast<std::size_t>(next_seed)] = block;
    for (std::size_t head = 0; head < queue.size() && taken < 64; ++head) {
      const std::int32_t u = queue[head];
      if (!assigned[static_cast<std::size_t>(u)]) {
        assigned[static_cast<std::size_t>(u)] = 1;
        order.push_back(u);
        ++taken;
      }
      for (const std::int32_t v : g.neighbors(u)) {
        if (seen_at[static_cast<std::size_t>(v)] != block) {
          seen_at[static_cast<std::size_t>(v)] = block;
          queue.push_back(v);
        }
      }
    }
  }
  return order;
}

/// Delta rows of up to 64 sources at once. Level-synchronous BFS with one bit per source:
///   reach_k[u] = (OR over neighbours p of reach_{k-1}[p]) & ~visited[u]
/// and, for each arc p -> u, the sources for which p is a shortest-path predecessor of u are
/// exactly the bits of reach_{k-1}[p] & ~visited[u] (visited holding levels below k); only those
/// (source, arc) pairs do arithmetic. For a fixed source each node accumulates over its
/// predecessors in ascending order, so the floating-point result is the same whatever block the
/// source is in.
template <TieMode Mode, typename Scalar>
class BitParallelDegreeSums {
 public:
  explicit BitParallelDegreeSums(const Graph<Scalar>& g)
      : g_(g),
        n_(g.num_nodes()),
        previous_(static_cast<std::size_t>(n_), 0),
        current_(static_cast<std::size_t>(n_), 0),
        visited_(static_cast<std::size_t>(n_), 0),
        values_(static_cast<std::size_t>(n_) * 64),
        degree_(static_cast<std::size_t>(n_)),
        touched_((static_cast<std::size_t>(n_) + 63) / 64, 0) {
    for (std::int32_t v = 0; v < n_; ++v) degree_[static_cast<std::size_t>(v)] = g.degree(v);
    frontier_.reserve(static_cast<std::size_t>(n_));
    next_frontier_.reserve(static_cast<std::size_t>(n_));
  }

  /// Runs the sources (at most 64); rows[i] receives Delta(sources[i], 1..ecc). Returns the number
  /// of (source, node) pairs reached.
  std::int64_t run(const std::int32_t* sources, int lanes, std::vector<std::vector<double>>& rows) {
    const std::int32_t* offsets = g_.csr_offsets().data();
    const std::int32_t* adjacency = g_.csr_adjacency().data();
    // previous_ and current_ are all zero between runs; visited_ is reset from the reached nodes.
    std::fill(visited_.begin(), visited_.end(), 0);
    frontier_.clear();
    for (int i = 0; i < lanes; ++i) {
      const std::size_t s = static_cast<std::size_t>(sources[i]);
      const std::uint64_t bit = std::uint64_t(1) << i;
      if (!previous_[s]) frontier_.push_back(sources[i]);
      previous_[s] |= bit;
      visited_[s] |= bit;
      values_[s * 64 + static_cast<std::size_t>(i)] = Values{1.0, 0.0};
      rows[static_cast<std::size_t>(i)].clear();
    }
    std::sort(frontier_.begin(), frontier_.end());
    std::int64_t reached = lanes;
    double layer[64];
    double level_max_count[64];
    while (!frontier_.empty()) {
      // One pass over the frontier's arcs p -> u. The lanes that reach u at this level through p
      // are previous[p] & ~visited[u] (visited holds the earlier levels only), so p is their
      // predecessor: initialise the lanes new at u, then accumulate. The frontier is in ascending
      // order, so every (node, lane) sums its predecessors in ascending order, whatever block
      // the lane is in. The touched bitmap lists the next frontier in ascending order.
      for (const std::int32_t p : frontier_) {
        const std::uint64_t from_p = previous_[static_cast<std::size_t>(p)];
        const double deg_p = degree_[static_cast<std::size_t>(p)];
        const Values* at_p = &values_[static_cast<std::size_t>(p) * 64];
        for (std::int32_t e = offsets[p], end = offsets[p + 1]; e < end; ++e) {
          const std::size_t u = static_cast<std::size_t>(adjacency[e]);
          std::uint64_t pred = from_p & ~visited_[u];
          if (!pred) continue;
          Values* at_u = &values_[u * 64];
          for (std::uint64_t fresh = pred & ~current_[u]; fresh; fresh &= fresh - 1) {
            at_u[lowest_bit(fresh)] = Values{0.0, Mode == TieMode::min ? std::numeric_limits<double>::infinity() : 0.0};
          }
          current_[u] |= pred;
          touched_[u >> 6] |= std::uint64_t(1) << (u & 63);
          const double diff = std::fabs(deg_p - degree_[u]);
          for (; pred; pred &= pred - 1) {
            const int i = lowest_bit(pred);
            if (Mode == TieMode::min) {
              at_u[i].sum = std::min(at_u[i].sum, at_p[i].sum + diff);
            } else {
              at_u[i].count += at_p[i].count;
              at_u[i].sum += at_p[i].sum + at_p[i].count * diff;
            }
          }
        }
      }
      next_frontier_.clear();
      for (std::size_t w = 0; w < touched_.size(); ++w) {
        for (std::uint64_t bits = touched_[w]; bits; bits &= bits - 1) {
          next_frontier_.push_back(static_cast<std::int32_t>(w * 64 + static_cast<std::size_t>(lowest_bit(bits))));
        }
        touched_[w] = 0;
      }
      if (next_frontier_.empty()) break;

      std::uint64_t active_lanes = 0;
      for (int i = 0; i < lanes; ++i) {
        layer[i] = 0.0;
        level_max_count[i] = 0.0;
      }
      for (const std::int32_t u : next_frontier_) {
        const std::uint64_t here = current_[static_cast<std::size_t>(u)];
        visited_[static_cast<std::size_t>(u)] |= here;
        active_lanes |= here;
        const Values* at_u = &values_[static_cast<std::size_t>(u) * 64];
        for (std::uint64_t m = here; m; m &= m - 1) {
          const int i = lowest_bit(m);
          ++reached;
          layer[i] += Mode == TieMode::mean ? at_u[i].sum / at_u[i].count : at_u[i].sum;
          if (Mode == TieMode::mean) level_max_count[i] = std::max(level_max_count[i], at_u[i].count);
        }
      }
      if (Mode == TieMode::mean) rescale_large_counts(active_lanes, level_max_count);
      for (std::uint64_t m = active_lanes; m; m &= m - 1) {
        const int i = lowest_bit(m);
        rows[static_cast<std::size_t>(i)].push_back(layer[i]);
      }
      for (const std::int32_t p : frontier_) previous_[static_cast<std::size_t>(p)] = 0;
      previous_.swap(current_);
      frontier_.swap(next_frontier_);
    }
    for (const std::int32_t p : frontier_) previous_[static_cast<std::size_t>(p)] = 0;
    return reached;
  }

 private:
  /// TieMode::mean needs only the ratio S / N, and every later level is linear in this one, so a
  /// lane whose path counts grow huge has this whole level scaled by 2^-512: exact (a power of
  /// two), and N never overflows however tie-rich the graph. TieMode::all needs the true sums and
  /// reports overflow instead.
  void rescale_large_counts(std::uint64_t active_lanes, const double* level_max_count) {
    const double threshold = std::ldexp(1.0, 512);
    const double factor = std::ldexp(1.0, -512);
    std::uint64_t large = 0;
    for (std::uint64_t m = active_lanes; m; m &= m - 1) {
      const int i = lowest_bit(m);
      if (level_max_count[i] > threshold) large |= std::uint64_t(1) << i;
    }
    if (!large) return;
    for (const std::int32_t u : next_frontier_) {
      Values* at_u = &values_[static_cast<std::size_t>(u) * 64];
      for (std::uint64_t m = current_[static_cast<std::size_t>(u)] & large; m; m &= m - 1) {
        const int i = lowest_bit(m);
        at_u[i].count *= factor;
        at_u[i].sum *= factor;
      }
    }
  }

  struct Values {
    double count;  // N: number of shortest paths (unused by TieMode::min)
    double sum;    // S: sum of their degree sums, or M: the smallest degree sum
  };
  const Graph<Scalar>& g_;
  std::int32_t n_;
  std::vector<std::uint64_t> previous_, current_, visited_;  // one bit per lane
  std::vector<Values> values_;                               // [node][lane]
  std::vector<double> degree_;
  std::vector<std::uint64_t> touched_;  // bitmap over nodes
  std::vector<std::int32_t> frontier_, next_frontier_;
};

template <TieMode Mode, typename Scalar>
void fill_table(const Graph<Scalar>& g, DegreeSumTable& table) {
  const std::int32_t n = g.num_nodes();
  const std::vector<std::int32_t> order = local_source_order(g);
  BitParallelDegreeSums<Mode, Scalar> sweep(g);
  std::vector<std::vector<double>> rows_by_source(static_cast<std::size_t>(n));
  std::vector<std::vector<double>> block_rows(64);
  for (std::size_t first = 0; first < order.size(); first += 64) {
    const int lanes = static_cast<int>(std::min<std::size_t>(64, order.size() - first));
    const std::int64_t reached = sweep.run(order.data() + first, lanes, block_rows);
    if (reached < static_cast<std::int64_t>(lanes) * n) table.connected = false;
    for (int i = 0; i < lanes; ++i)
      rows_by_source[static_cast<std::size_t>(order[first + static_cast<std::size_t>(i)])].swap(
          block_rows[static_cast<std::size_t>(i)]);
  }
  table.row_offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  for (std::int32_t s = 0; s < n; ++s) {
    const std::vector<double>& row = rows_by_source[static_cast<std::size_t>(s)];
    table.values.insert(table.values.end(), row.begin(), row.end());
    table.row_offsets[static_cast<std::size_t>(s) + 1] = static_cast<std::int64_t>(table.values.size());
    table.diameter = std::max(table.diameter, static_cast<std::int32_t>(row.size()));
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
    case TieMode::all:
      detail::fill_table<TieMode::all>(g, table);
      break;
    case TieMode::mean:
      detail::fill_table<TieMode::mean>(g, table);
      break;
    case TieMode::min:
      detail::fill_table<TieMode::min>(g, table);
      break;
  }
  return table;
}

}  // namespace cge
