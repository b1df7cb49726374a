#pragma once
// Single-source BFS on neighbour lists: Delta(s, k) of one source, level by level, with a caller
// that may stop after any level (what DegreeDegreeEntropy::compute_index needs: a search is cut as
// soon as its node weighs nothing). The BFS dynamic programme of shortest_path_degree_sums.hpp for
// a single source (docs/METHOD.md section 4).
//
// It performs the documented floating-point operations in the documented order (a node sums its
// predecessors in ascending node order, the product N_p |d(p) - d(u)| rounded on its own in the
// portable build; Delta(s, k) sums the nodes at distance k in ascending order; TieMode::mean
// rescales a level by 2^-512 when its largest count passes 2^512), so a row it completes equals
// the table's row bit for bit where the portable kernel's does. Work is proportional to the part
// of the graph visited before the caller stops, not to |V|: state is reset by a generation stamp.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/kernels/mean_rescale.hpp"
#include "cge/graph/graph.hpp"

namespace cge {
namespace detail {

/// What a single-source kernel exposes during its on_level calls: the level's nodes and their terms.
/// The kernels (SingleSourceBfsDegreeSums, SingleSourceBitsetBfsDegreeSums) keep N and S here.
template <TieMode Mode>
class SingleSourceLevel {
 public:
  /// During on_level: the nodes at distance k from the source, in ascending order.
  const std::int32_t* level_begin() const { return level_nodes_; }
  const std::int32_t* level_end() const { return level_nodes_ + level_size_; }

  /// During on_level, for a node u of level k: its term of Delta(source, k), i.e. S[u] (TieMode::all),
  /// S[u] / N[u] (TieMode::mean) or M[u] (TieMode::min). Every one of these is symmetric in the
  /// pair (source, u): a shortest path read backwards is a shortest path with the same degree steps.
  double node_term(std::int32_t u) const {
    const std::size_t i = static_cast<std::size_t>(u);
    return Mode == TieMode::mean ? sum_[i] / count_[i] : sum_[i];
  }

 protected:
  explicit SingleSourceLevel(std::size_t num_nodes) : count_(num_nodes, 0.0), sum_(num_nodes, 0.0) {}

  std::vector<double> count_, sum_;            // N and S (or M) of the nodes reached
  const std::int32_t* level_nodes_ = nullptr;  // the level of the current on_level call
  std::size_t level_size_ = 0;
};

template <TieMode Mode, typename Scalar>
class SingleSourceBfsDegreeSums : public SingleSourceLevel<Mode> {
 public:
  explicit SingleSourceBfsDegreeSums(const Graph<Scalar>& g)
      : SingleSourceLevel<Mode>(static_cast<std::size_t>(g.num_nodes())),
        offsets_(g.csr_offsets().data()),
        adjacency_(g.csr_adjacency().data()),
        degree_(static_cast<std::size_t>(g.num_nodes())),
        stamp_(static_cast<std::size_t>(g.num_nodes()), 0),
        level_(static_cast<std::size_t>(g.num_nodes()), 0),
        frontier_(static_cast<std::size_t>(g.num_nodes())),
        next_(static_cast<std::size_t>(g.num_nodes())) {
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) degree_[static_cast<std::size_t>(v)] = g.degree(v);
  }

  /// Runs from `source`. After each level k = 1, 2, ... it calls on_level(k, Delta(source, k));
  /// when that returns false the run stops. Returns the last level computed: the eccentricity of
  /// the source when on_level never stopped it. Inside on_level, level_begin() .. level_end() and
  /// node_term(u) describe level k.
  template <typename OnLevel>
  std::int32_t run(std::int32_t source, OnLevel&& on_level) {
    next_generation();
    // Locals, so that the stores below cannot be taken to alias the members (they would be
    // reloaded after every store otherwise).
    const std::int32_t* const offsets = offsets_;
    const std::int32_t* const adjacency = adjacency_;
    const double* const degree = degree_.data();
    std::uint32_t* const stamp = stamp_.data();
    std::int32_t* const level = level_.data();
    double* const count = this->count_.data();
    double* const sum = this->sum_.data();
    std::int32_t* frontier = frontier_.data();
    std::int32_t* next = next_.data();
    const std::uint32_t generation = generation_;
    const double start = Mode == TieMode::min ? std::numeric_limits<double>::infinity() : 0.0;

    const std::size_t s = static_cast<std::size_t>(source);
    stamp[s] = generation;
    level[s] = 0;
    count[s] = 1.0;
    sum[s] = 0.0;
    frontier[0] = source;
    std::size_t frontier_size = 1;
    for (std::int32_t k = 1;; ++k) {
      // One pass over the frontier's arcs p -> u, p ascending: a node seen for the first time
      // joins level k; every arc into a level-k node is a predecessor arc.
      std::size_t next_size = 0;
      for (std::size_t f = 0; f < frontier_size; ++f) {
        const std::int32_t p = frontier[f];
        const std::size_t sp = static_cast<std::size_t>(p);
        const double count_p = count[sp], sum_p = sum[sp], degree_p = degree[sp];
        for (std::int32_t e = offsets[p], end = offsets[p + 1]; e < end; ++e) {
          const std::size_t u = static_cast<std::size_t>(adjacency[e]);
          if (stamp[u] != generation) {
            stamp[u] = generation;
            level[u] = k;
            count[u] = 0.0;
            sum[u] = start;
            next[next_size++] = adjacency[e];
          } else if (level[u] != k) {
            continue;
          }
          const double diff = std::fabs(degree_p - degree[u]);
          if (Mode == TieMode::min) {
            sum[u] = std::min(sum[u], sum_p + diff);
          } else {
            count[u] += count_p;
            sum[u] += sum_p + count_p * diff;
          }
        }
      }
      if (next_size == 0) return k - 1;
      std::sort(next, next + next_size);
      double layer = 0.0;
      double max_count = 0.0;
      for (std::size_t i = 0; i < next_size; ++i) {
        const std::size_t u = static_cast<std::size_t>(next[i]);
        layer += Mode == TieMode::mean ? sum[u] / count[u] : sum[u];
        if (Mode == TieMode::mean) max_count = std::max(max_count, count[u]);
      }
      if (Mode == TieMode::mean && mean_level_needs_rescale(max_count)) {
        const double factor = mean_rescale_factor();
        for (std::size_t i = 0; i < next_size; ++i) {
          count[static_cast<std::size_t>(next[i])] *= factor;
          sum[static_cast<std::size_t>(next[i])] *= factor;
        }
      }
      this->level_nodes_ = next;
      this->level_size_ = next_size;
      if (!on_level(k, layer)) return k;
      std::swap(frontier, next);
      frontier_size = next_size;
    }
  }

 private:
  void next_generation() {
    if (++generation_ == 0) {  // wrapped: clear the stamps once every 2^32 runs
      std::fill(stamp_.begin(), stamp_.end(), 0u);
      generation_ = 1;
    }
  }

  const std::int32_t* offsets_;
  const std::int32_t* adjacency_;
  std::vector<double> degree_;
  std::vector<std::uint32_t> stamp_;           // == generation_: reached by the current run
  std::vector<std::int32_t> level_;            // distance from the current source, where stamped
  std::vector<std::int32_t> frontier_, next_;  // one level each (|V| entries)
  std::uint32_t generation_ = 0;
};

}  // namespace detail
}  // namespace cge
