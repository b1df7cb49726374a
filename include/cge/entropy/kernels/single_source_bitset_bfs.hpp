#pragma once
// Single-source BFS on adjacency bitsets: Delta(s, k) of one source, level by level, the same
// computation as SingleSourceBfsDegreeSums (single_source_bfs.hpp), with the same interface and the same
// floating-point operations in the same order, so its rows are bit for bit that kernel's.
//
// Why a second kernel. On the small dense graphs a frame gives (a few hundred nodes, mean degree
// about 14, many cliques) most arcs a BFS scans lead back to a level it has already finished. Here
// the next level is found as (OR of the frontier's rows) AND NOT visited (AdjacencyBitsets, one
// word operation per 64 nodes), and each new node pulls its predecessors from (its row AND
// frontier), which lists them in ascending order: only the arcs between consecutive levels are
// touched, and the levels come out sorted without a sort. Words are touched only within the
// spans of the rows and of the frontier. It pays where AdjacencyBitsets::rows_pay.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/core/bits.hpp"
#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/kernels/mean_rescale.hpp"
#include "cge/entropy/kernels/single_source_bfs.hpp"
#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/graph.hpp"

namespace cge {
namespace detail {

template <TieMode Mode, typename Scalar>
class SingleSourceBitsetBfsDegreeSums : public SingleSourceLevel<Mode> {
 public:
  /// rows: the adjacency bitsets of g, which must outlive this object.
  SingleSourceBitsetBfsDegreeSums(const Graph<Scalar>& g, const AdjacencyBitsets& rows)
      : SingleSourceLevel<Mode>(static_cast<std::size_t>(g.num_nodes())),
        rows_(rows),
        degree_(static_cast<std::size_t>(g.num_nodes())),
        visited_(rows.words(), 0),
        frontier_bits_(rows.words(), 0),
        next_bits_(rows.words(), 0),
        frontier_(static_cast<std::size_t>(g.num_nodes())),
        next_(static_cast<std::size_t>(g.num_nodes())) {
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) degree_[static_cast<std::size_t>(v)] = g.degree(v);
  }

  /// As SingleSourceBfsDegreeSums::run: after each level k = 1, 2, ... it calls on_level(k, Delta(source, k))
  /// and stops when that returns false; returns the last level computed. Inside on_level,
  /// level_begin() .. level_end() and node_term(u) (SingleSourceLevel) describe level k.
  template <typename OnLevel>
  std::int32_t run(std::int32_t source, OnLevel&& on_level) {
    const std::size_t words = rows_.words();
    const double* const degree = degree_.data();
    double* const count = this->count_.data();
    double* const sum = this->sum_.data();
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
    visited[s / 64] |= AdjacencyBitsets::bit(source);
    frontier_bits[s / 64] |= AdjacencyBitsets::bit(source);
    count[s] = 1.0;
    sum[s] = 0.0;
    frontier[0] = source;
    std::size_t frontier_size = 1;
    for (std::int32_t k = 1;; ++k) {
      // Words the frontier occupies and those its neighbours can occupy.
      const AdjacencyBitsets::Span occupied = words_of(frontier, frontier_size);
      const std::size_t frontier_first = occupied.first, frontier_end = occupied.end;
      const AdjacencyBitsets::Span touched = rows_.or_rows(frontier, frontier_size, next_bits);
      const std::size_t next_first = touched.first, next_end = touched.end;
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
          const AdjacencyBitsets::Span span = rows_.span(u);
          const std::uint64_t* row = rows_.stored_row(u);
          double count_u = 0.0;
          double sum_u = start;
          const std::size_t first = std::max(span.first, frontier_first);
          const std::size_t end = std::min(span.end, frontier_end);
          for (std::size_t pw = first; pw < end; ++pw) {
            for (std::uint64_t preds = row[pw - span.first] & frontier_bits[pw]; preds != 0; preds &= preds - 1) {
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
      this->level_nodes_ = frontier;
      this->level_size_ = frontier_size;
      if (!on_level(k, layer)) {
        const AdjacencyBitsets::Span level = words_of(frontier, frontier_size);
        std::fill(frontier_bits + level.first, frontier_bits + level.end, std::uint64_t{0});
        return k;
      }
    }
  }

 private:
  /// The words that hold the bits of nodes[0 .. count), ascending and count >= 1.
  static AdjacencyBitsets::Span words_of(const std::int32_t* nodes, std::size_t count) {
    return {static_cast<std::size_t>(nodes[0]) / 64, static_cast<std::size_t>(nodes[count - 1]) / 64 + 1};
  }

  const AdjacencyBitsets& rows_;
  std::vector<double> degree_;
  std::vector<std::uint64_t> visited_, frontier_bits_, next_bits_;
  std::vector<std::int32_t> frontier_, next_;  // one level each, ascending
};

}  // namespace detail
}  // namespace cge
