#pragma once
// Block BFS: the portable kernel of shortest_path_degree_sums (docs/METHOD.md section 4). The BFS
// dynamic programme runs from a block of 64 sources at once, one bit per source ("lane"), with
// the values of every (node, source) kept in one node-indexed block of 64 lanes: one word
// operation finds, for an arc, every source of the block that uses it as a shortest-path step.
// Also the grouping of sources into blocks, which the AVX-512 block kernel shares.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/core/bits.hpp"
#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/kernels/mean_rescale.hpp"
#include "cge/graph/graph.hpp"

namespace cge {
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
class BlockBfsDegreeSums {
 public:
  explicit BlockBfsDegreeSums(const Graph<Scalar>& g)
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
  /// TieMode::mean: scales the lanes_to_rescale of this level by mean_rescale_factor().
  void rescale_large_counts(std::uint64_t active_lanes, const double* level_max_count) {
    const std::uint64_t large = lanes_to_rescale(active_lanes, level_max_count);
    if (!large) return;
    const double factor = mean_rescale_factor();
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

}  // namespace detail
}  // namespace cge
