#pragma once
// Adjacency rows as bitsets over node indices, for breadth-first searches on small dense graphs:
// a BFS level is then (OR of the frontier's rows) AND NOT visited, one word operation per 64
// nodes, and a node's neighbours in a set are (its row AND the set), listed in ascending order.
//
// A row is stored only over the words from its lowest to its highest neighbour, so memory and
// work follow how far apart neighbours are in the node order. GraphBuilder's canonical (y, x)
// order keeps neighbours close (a few words per row on frame graphs); a random order spreads
// every row over |V| / 64 words, where neighbour lists are faster (`rows_pay`).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "cge/graph/graph.hpp"

namespace cge {

class AdjacencyBitsets {
 public:
  /// The words [first, end) of a node's row that hold its neighbours (empty without any).
  struct Span {
    std::size_t first = 0, end = 0;
  };

  AdjacencyBitsets() = default;

  template <typename Scalar>
  explicit AdjacencyBitsets(const Graph<Scalar>& g) : AdjacencyBitsets(g, spans_of(g)) {}

  /// g's rows where they pay (rows_pay), else nothing; the spans are found once for both.
  template <typename Scalar>
  static std::optional<AdjacencyBitsets> if_rows_pay(const Graph<Scalar>& g) {
    std::vector<Span> spans = spans_of(g);
    if (!spans_pay(spans, g.num_edges())) return std::nullopt;
    return AdjacencyBitsets(g, std::move(spans));
  }

  /// Words of a full row: one bit per node.
  std::size_t words() const { return words_; }
  std::size_t num_nodes() const { return spans_.size(); }
  /// Words stored for all rows together.
  std::size_t stored_words() const { return bits_.size(); }

  const Span& span(std::int32_t v) const { return spans_[static_cast<std::size_t>(v)]; }
  /// The stored words of v's row: element i is word span(v).first + i.
  const std::uint64_t* stored_row(std::int32_t v) const { return bits_.data() + offset_[static_cast<std::size_t>(v)]; }

  /// ORs the rows of nodes[0 .. count) into bits (words() words) and returns the words that can
  /// have changed: the union of their spans (empty for no nodes or no neighbours).
  Span or_rows(const std::int32_t* nodes, std::size_t count, std::uint64_t* bits) const {
    Span touched{words_, 0};
    for (std::size_t i = 0; i < count; ++i) {
      const Span s = span(nodes[i]);
      const std::uint64_t* row = stored_row(nodes[i]);
      for (std::size_t w = s.first; w < s.end; ++w) bits[w] |= row[w - s.first];
      if (s.first < s.end) {
        touched.first = std::min(touched.first, s.first);
        touched.end = std::max(touched.end, s.end);
      }
    }
    if (touched.end == 0) touched.first = 0;
    return touched;
  }

  /// The bit of node v within its word (word v / 64).
  static std::uint64_t bit(std::int32_t v) { return std::uint64_t{1} << (static_cast<unsigned>(v) % 64); }

  template <typename Scalar>
  static Span row_span(const Graph<Scalar>& g, std::int32_t v) {
    Span span;
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

  /// Whether searches on these rows beat neighbour lists on g: when the rows' spans hold no more
  /// words than the graph has arcs. That bounds the rows' memory by 8 bytes per arc, and a search
  /// then touches about as many words per node as a list search touches arcs, at a fraction of
  /// the cost per word (docs/BENCHMARK.md).
  template <typename Scalar>
  static bool rows_pay(const Graph<Scalar>& g) {
    return spans_pay(spans_of(g), g.num_edges());
  }

 private:
  template <typename Scalar>
  AdjacencyBitsets(const Graph<Scalar>& g, std::vector<Span> spans)
      : words_((static_cast<std::size_t>(g.num_nodes()) + 63) / 64),
        spans_(std::move(spans)),
        offset_(spans_.size(), 0) {
    std::size_t stored = 0;
    for (std::size_t v = 0; v < spans_.size(); ++v) {
      offset_[v] = stored;
      stored += spans_[v].end - spans_[v].first;
    }
    bits_.assign(stored, 0);
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) {
      const std::size_t sv = static_cast<std::size_t>(v);
      for (const std::int32_t u : g.neighbors(v)) {
        bits_[offset_[sv] + static_cast<std::size_t>(u) / 64 - spans_[sv].first] |= bit(u);
      }
    }
  }

  template <typename Scalar>
  static std::vector<Span> spans_of(const Graph<Scalar>& g) {
    std::vector<Span> spans(static_cast<std::size_t>(g.num_nodes()));
    for (std::int32_t v = 0; v < g.num_nodes(); ++v) spans[static_cast<std::size_t>(v)] = row_span(g, v);
    return spans;
  }

  static bool spans_pay(const std::vector<Span>& spans, std::int64_t num_edges) {
    std::int64_t span_words = 0;
    for (const Span& s : spans) span_words += static_cast<std::int64_t>(s.end - s.first);
    return !spans.empty() && span_words <= 2 * num_edges;
  }

  std::size_t words_ = 0;
  std::vector<Span> spans_;
  std::vector<std::size_t> offset_;  // v's stored words start at bits_[offset_[v]]
  std::vector<std::uint64_t> bits_;
};

}  // namespace cge
