#pragma once
// Delta(s, k) of one source, level by level, on adjacency bitsets: the same computation as
// SingleSourceDegreeSums (single_source_degree_sums.hpp), with the same interface and the same
// floating-point operations in the same order, so its rows are bit for bit that kernel's.
//
// Why a second kernel. On the small dense graphs a frame gives (a few hundred nodes, mean degree
// about 14, many cliques) most arcs a BFS scans lead back to a level it has already finished. Here
// the next level is found as (OR of the frontier's neighbour rows) AND NOT visited, one word
// operation per 64 nodes, and each new node pulls its predecessors from (its row AND frontier),
// which lists them in ascending order: only the arcs between consecutive levels are touched, and
// the levels come out sorted without a sort. A search costs about 2 |V| / 64 word operations per
// node it reaches plus its predecessor arcs, against the neighbour-list kernel's degree arcs per
// node, so it pays on graphs where |V| / 64 is small next to the mean degree
// (`bitset_kernel_pays`). Memory: |V|^2 / 8 bytes of rows.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/core/bits.hpp"
#include "cge/entropy/bit_parallel_degree_sums.hpp"
#include "cge/entropy/degree_sum_table.hpp"
#include "cge/graph/graph.hpp"

namespace cge {
namespace detail {

/// Words of 64 bits a node's adjacency row takes in BitsetSingleSourceDegreeSums.
inline std::size_t bitset_row_words(std::int32_t num_nodes) {
  return (static_cast<std::size_t>(num_nodes) + 63) / 64;
}

/// The words [first, end) of node v's adjacency row that hold its neighbours (empty without any).
struct RowSpan {
  std::size_t first = 0, end = 0;
};

template <typename Scalar>
RowSpan row_span(const Graph<Scalar>& g, std::int32_t v) {
  RowSpan span;
  bool any = false;
  std::int32_t lowest = 0, highest = 0;
  for (const std::int32_t u : g.neighbors(v)) {
    lowest = any ? std::min(lowest, u) : u;
    highest = any ? std::max(highest, u) : u;
    any = true;
  }
  if (any) span = {static_cast<std::size_t>(lowest) / 64, static_cast<std::size_t>(highest) / 64 + 1};
  return span;
}

/// Whether BitsetSingleSourceDegreeSums is the faster kernel for g: when its rows, word spans from
/// a node's lowest to its highest neighbour, hold no more words than the graph has arcs. Node
/// orders that keep neighbours close (the canonical (y, x) order of GraphBuilder) give spans of a
/// few words. Both kernels give the same bits; this only picks the faster one (docs/BENCHMARK.md),
/// and it bounds the rows' memory by 8 bytes per arc.
template <typename Scalar>
bool bitset_kernel_pays(const Graph<Scalar>& g) {
  std::int64_t span_words = 0;
  for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
    const RowSpan span = row_span(g, v);
    span_words += static_cast<std::int64_t>(span.end - span.first);
  }
  return g.num_nodes() > 0 && span_words <= 2 * static_cast<std::int64_t>(g.num_edges());
}

template <TieMode Mode, typename Scalar>
class BitsetSingleSourceDegreeSums {
 public:
  explicit BitsetSingleSourceDegreeSums(const Graph<Scalar>& g)
      : words_(bitset_row_words(g.num_nodes())),
        degree_(static_cast<std::size_t>(g.num_nodes())),
        count_(static_cast<std::size_t>(g.num_nodes()), 0.0),
        sum_(static_cast<std::size_t>(g.num_nodes()), 0.0),
        visited_(words_, 0),
        frontier_bits_(words_, 0),
        next_bits_(words_, 0),
        frontier_(static_cast<std::size_t>(g.num_nodes())),
        next_(static_cast<std::size_t>(g.num_nodes())),
        row_first_(static_cast<std::size_t>(g.num_nodes()), 0),
        row_end_(static_cast<std::size_t>(g.num_nodes()), 0),
        row_base_(static_cast<std::size_t>(g.num_nodes()), 0) {
    std::size_t packed = 0;
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
      const std::size_t sv = static_cast<std::size_t>(v);
      degree_[sv] = g.degree(v);
      const RowSpan span = row_span(g, v);
      row_first_[sv] = span.first;
      row_end_[sv] = span.end;
      row_base_[sv] = static_cast<std::ptrdiff_t>(packed) - static_cast<std::ptrdiff_t>(span.first);
      packed += span.end - span.first;
    }
    rows_.assign(packed, 0);
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
      for (const std::int32_t u : g.neighbors(v)) rows_[word_index(v, static_cast<std::size_t>(u) / 64)] |= bit(u);
    }
  }

  /// As SingleSourceDegreeSums::run: after each level k = 1, 2, ... it calls on_level(k, Delta(source, k))
  /// and stops when that returns false; returns the last level computed. Inside on_level,
  /// level_begin() .. level_end() and node_term(u) describe level k.
  template <typename OnLevel>
  std::int32_t run(std::int32_t source, OnLevel&& on_level) {
    const std::size_t words = words_;
    const std::size_t* const row_first = row_first_.data();
    const std::size_t* const row_end = row_end_.data();
    const double* const degree = degree_.data();
    double* const count = count_.data();
    double* const sum = sum_.data();
    std::uint64_t* const visited = visited_.data();
    std::uint64_t* frontier_bits = frontier_bits_.data();
    std::uint64_t* next_bits = next_bits_.data();
    std::int32_t* frontier = frontier_.data();
    std::int32_t* next = next_.data();
    const double start = Mode == TieMode::min ? std::numeric_limits<double>::infinity() : 0.0;

    // Invariant between levels: frontier_bits and next_bits are zero outside the words the
    // frontier's nodes occupy, and next_bits is zero everywhere.
    std::fill(visited, visited + words, std::uint64_t{0});
    const std::size_t s = static_cast<std::size_t>(source);
    visited[s / 64] |= bit(source);
    frontier_bits[s / 64] |= bit(source);
    count[s] = 1.0;
    sum[s] = 0.0;
    frontier[0] = source;
    std::size_t frontier_size = 1;
    for (std::int32_t k = 1;; ++k) {
      // Words the frontier occupies (its nodes are ascending) and those its neighbours can occupy.
      const std::size_t frontier_first = static_cast<std::size_t>(frontier[0]) / 64;
      const std::size_t frontier_end = static_cast<std::size_t>(frontier[frontier_size - 1]) / 64 + 1;
      std::size_t next_first = words, next_end = 0;
      for (std::size_t f = 0; f < frontier_size; ++f) {
        const std::size_t p = static_cast<std::size_t>(frontier[f]);
        const std::uint64_t* row = rows_.data() + row_base_[p];  // row[w] for w in [row_first[p], row_end[p])
        for (std::size_t w = row_first[p]; w < row_end[p]; ++w) next_bits[w] |= row[w];
        next_first = std::min(next_first, row_first[p]);
        next_end = std::max(next_end, row_end[p]);
      }
      std::uint64_t any = 0;
      for (std::size_t w = next_first; w < next_end; ++w) {
        next_bits[w] &= ~visited[w];
        visited[w] |= next_bits[w];
        any |= next_bits[w];
      }
      if (any == 0) {
        std::fill(frontier_bits + frontier_first, frontier_bits + frontier_end, std::uint64_t{0});
        return k - 1;
      }

      // Level k in ascending order; each node sums its predecessors in ascending order, as the
      // neighbour-list kernel does after its sort.
      std::size_t next_size = 0;
      double layer = 0.0;
      double max_count = 0.0;
      for (std::size_t w = next_first; w < next_end; ++w) {
        for (std::uint64_t pending = next_bits[w]; pending != 0; pending &= pending - 1) {
          const std::int32_t u = static_cast<std::int32_t>(w * 64 + static_cast<std::size_t>(lowest_bit(pending)));
          const std::size_t su = static_cast<std::size_t>(u);
          const double degree_u = degree[su];
          const std::uint64_t* row = rows_.data() + row_base_[su];
          double count_u = 0.0;
          double sum_u = start;
          const std::size_t first = std::max(row_first[su], frontier_first);
          const std::size_t end = std::min(row_end[su], frontier_end);
          for (std::size_t pw = first; pw < end; ++pw) {
            for (std::uint64_t preds = row[pw] & frontier_bits[pw]; preds != 0; preds &= preds - 1) {
              const std::size_t p = pw * 64 + static_cast<std::size_t>(lowest_bit(preds));
              const double diff = std::fabs(degree[p] - degree_u);
              if (Mode == TieMode::min) {
                sum_u = std::min(sum_u, sum[p] + diff);
              } else {
                count_u += count[p];
                sum_u += sum[p] + count[p] * diff;
              }
            }
          }
          count[su] = count_u;
          sum[su] = sum_u;
          next[next_size++] = u;
          layer += Mode == TieMode::mean ? sum_u / count_u : sum_u;
          if (Mode == TieMode::mean) max_count = std::max(max_count, count_u);
        }
      }
      if (Mode == TieMode::mean && mean_level_needs_rescale(max_count)) {
        const double factor = mean_rescale_factor();
        for (std::size_t i = 0; i < next_size; ++i) {
          count[static_cast<std::size_t>(next[i])] *= factor;
          sum[static_cast<std::size_t>(next[i])] *= factor;
        }
      }
      // The finished frontier's bits are cleared, so the swapped buffer is all zero again.
      std::fill(frontier_bits + frontier_first, frontier_bits + frontier_end, std::uint64_t{0});
      std::swap(frontier, next);
      std::swap(frontier_bits, next_bits);
      frontier_size = next_size;
      level_nodes_ = frontier;
      level_size_ = frontier_size;
      if (!on_level(k, layer)) {
        const std::size_t level_first = static_cast<std::size_t>(frontier[0]) / 64;
        const std::size_t level_end = static_cast<std::size_t>(frontier[frontier_size - 1]) / 64 + 1;
        std::fill(frontier_bits + level_first, frontier_bits + level_end, std::uint64_t{0});
        return k;
      }
    }
  }

  /// During on_level: the nodes at distance k from the source, in ascending order.
  const std::int32_t* level_begin() const { return level_nodes_; }
  const std::int32_t* level_end() const { return level_nodes_ + level_size_; }

  /// During on_level, for a node u of level k: its term of Delta(source, k), as
  /// SingleSourceDegreeSums::node_term.
  double node_term(std::int32_t u) const {
    const std::size_t i = static_cast<std::size_t>(u);
    return Mode == TieMode::mean ? sum_[i] / count_[i] : sum_[i];
  }

 private:
  static std::uint64_t bit(std::int32_t node) { return std::uint64_t{1} << (static_cast<unsigned>(node) % 64); }

  std::size_t word_index(std::int32_t v, std::size_t w) const {
    return static_cast<std::size_t>(row_base_[static_cast<std::size_t>(v)] + static_cast<std::ptrdiff_t>(w));
  }

  std::size_t words_;
  std::vector<double> degree_;
  std::vector<double> count_, sum_;  // N and S (or M) of the nodes reached
  std::vector<std::uint64_t> visited_, frontier_bits_, next_bits_;
  std::vector<std::int32_t> frontier_, next_;  // one level each, ascending
  // Node v's neighbours are the bits of words [row_first_[v], row_end_[v]) of its row, stored
  // packed: word w at rows_[row_base_[v] + w].
  std::vector<std::size_t> row_first_, row_end_;
  std::vector<std::ptrdiff_t> row_base_;
  std::vector<std::uint64_t> rows_;
  const std::int32_t* level_nodes_ = nullptr;
  std::size_t level_size_ = 0;
};

}  // namespace detail
}  // namespace cge
