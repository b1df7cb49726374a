#pragma once
// A compact, immutable, simple undirected graph: node positions and kinds, edges with weights,
// and adjacency in compressed sparse row (CSR) form.
//
// Canonical form: edges are stored with u < v, sorted by (u, v); each node's neighbour list is
// sorted ascending. Two graphs with the same nodes and edge set therefore compare equal member by
// member, which is what the property tests and the "all neighbour-search policies give identical
// graphs" guarantee rely on.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace cge {

template <typename S, typename NS>
class GraphBuilder;

/// What a node of a frame graph stands for (docs/METHOD.md section 3).
enum class NodeKind : std::uint8_t {
  feature = 0,         ///< a stable feature point outside dense patches
  representation = 1,  ///< the centre of a dense patch, standing for its features
  semantic = 2,        ///< the centre of a static semantic instance
};

/// Half-open view of a contiguous run of node indices (C++17 has no std::span).
struct IndexSpan {
  const std::int32_t* first = nullptr;
  const std::int32_t* last = nullptr;
  const std::int32_t* begin() const { return first; }
  const std::int32_t* end() const { return last; }
  std::size_t size() const { return static_cast<std::size_t>(last - first); }
  bool empty() const { return first == last; }
  std::int32_t operator[](std::size_t i) const { return first[i]; }
};

/// An undirected edge, u < v in a canonical graph.
template <typename Scalar>
struct Edge {
  std::int32_t u = 0;
  std::int32_t v = 0;
  Scalar weight = Scalar(1);  ///< pixel length for frame graphs; 1 for unweighted input
  friend bool operator==(const Edge& a, const Edge& b) { return a.u == b.u && a.v == b.v && a.weight == b.weight; }
  friend bool operator!=(const Edge& a, const Edge& b) { return !(a == b); }
};

/// How an edge of a frame graph came to be (for property tests and studies of the construction).
/// Round numbers start at 1; kStrayJoin marks the edges that connect stray nodes afterwards.
constexpr std::uint8_t kStrayJoin = 0;

template <typename Scalar>
class Graph {
 public:
  using Point = Eigen::Matrix<Scalar, 2, 1>;

  Graph() = default;

  /// Builds a canonical graph from an edge list. Endpoint order and edge order do not matter.
  /// Throws std::invalid_argument on an index out of range, a self-loop, a repeated edge, or a
  /// negative or non-finite weight; the message names the offending edge by its position in `edges`.
  /// `positions` and `kinds` may be empty (abstract graphs) or have num_nodes entries.
  /// `edge_rounds`, if not empty, is parallel to `edges` and is reordered with them.
  static Graph from_edges(std::int32_t num_nodes, std::vector<Edge<Scalar>> edges, bool weighted,
                          std::vector<Point> positions = {}, std::vector<NodeKind> kinds = {},
                          std::vector<std::uint8_t> edge_rounds = {}) {
    if (num_nodes < 0) throw std::invalid_argument("Graph: negative node count");
    if (!positions.empty() && positions.size() != static_cast<std::size_t>(num_nodes)) {
      throw std::invalid_argument("Graph: positions must be empty or one per node");
    }
    if (!kinds.empty() && kinds.size() != static_cast<std::size_t>(num_nodes)) {
      throw std::invalid_argument("Graph: kinds must be empty or one per node");
    }
    if (!edge_rounds.empty() && edge_rounds.size() != edges.size()) {
      throw std::invalid_argument("Graph: edge_rounds must be empty or one per edge");
    }
    for (std::size_t i = 0; i < edges.size(); ++i) {
      Edge<Scalar>& e = edges[i];
      if (e.u < 0 || e.v < 0 || e.u >= num_nodes || e.v >= num_nodes) {
        throw std::invalid_argument(describe(i, e) + " has an endpoint outside [0, " + std::to_string(num_nodes) + ")");
      }
      if (e.u == e.v) throw std::invalid_argument(describe(i, e) + " is a self-loop");
      if (!std::isfinite(e.weight) || e.weight < 0) {
        throw std::invalid_argument(describe(i, e) + " has a negative or non-finite weight");
      }
      if (e.u > e.v) std::swap(e.u, e.v);
    }
    // Sort (u, v) keys with the original position as tie-break, so edge_rounds can follow.
    struct Keyed {
      std::uint64_t key;
      std::size_t index;
    };
    std::vector<Keyed> order(edges.size());
    for (std::size_t i = 0; i < edges.size(); ++i) {
      order[i] = Keyed{(static_cast<std::uint64_t>(edges[i].u) << 32) | static_cast<std::uint32_t>(edges[i].v), i};
    }
    std::sort(order.begin(), order.end(),
              [](const Keyed& a, const Keyed& b) { return a.key != b.key ? a.key < b.key : a.index < b.index; });
    Graph g;
    g.num_nodes_ = num_nodes;
    g.weighted_ = weighted;
    g.positions_ = std::move(positions);
    g.kinds_ = std::move(kinds);
    g.edges_.reserve(edges.size());
    if (!edge_rounds.empty()) g.edge_rounds_.reserve(edges.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
      const Edge<Scalar>& e = edges[order[k].index];
      if (k > 0 && order[k].key == order[k - 1].key) {
        throw std::invalid_argument(describe(order[k].index, e) + " repeats " +
                                    describe(order[k - 1].index, edges[order[k - 1].index]));
      }
      g.edges_.push_back(e);
      if (!edge_rounds.empty()) g.edge_rounds_.push_back(edge_rounds[order[k].index]);
    }
    g.build_csr();
    return g;
  }

  std::int32_t num_nodes() const { return num_nodes_; }
  std::int32_t num_edges() const { return static_cast<std::int32_t>(edges_.size()); }
  bool empty() const { return num_nodes_ == 0; }
  /// True when the weights are meaningful (pixel lengths, or given in the input).
  bool weighted() const { return weighted_; }

  std::int32_t degree(std::int32_t v) const { return offsets_[v + 1] - offsets_[v]; }
  IndexSpan neighbors(std::int32_t v) const {
    return IndexSpan{adjacency_.data() + offsets_[v], adjacency_.data() + offsets_[v + 1]};
  }

  const std::vector<Edge<Scalar>>& edges() const { return edges_; }
  /// CSR row offsets (num_nodes + 1 entries) and concatenated sorted neighbour lists.
  const std::vector<std::int32_t>& csr_offsets() const { return offsets_; }
  const std::vector<std::int32_t>& csr_adjacency() const { return adjacency_; }
  /// Node positions in pixels and node kinds; empty for abstract graphs.
  const std::vector<Point>& positions() const { return positions_; }
  const std::vector<NodeKind>& kinds() const { return kinds_; }
  /// Per edge (parallel to edges()): the construction round that made it, or kStrayJoin.
  /// Empty for graphs not made by GraphBuilder.
  const std::vector<std::uint8_t>& edge_rounds() const { return edge_rounds_; }

  friend bool operator==(const Graph& a, const Graph& b) {
    return a.num_nodes_ == b.num_nodes_ && a.weighted_ == b.weighted_ && a.edges_ == b.edges_ &&
           a.positions_ == b.positions_ && a.kinds_ == b.kinds_ && a.edge_rounds_ == b.edge_rounds_;
  }
  friend bool operator!=(const Graph& a, const Graph& b) { return !(a == b); }

 private:
  // GraphBuilder emits canonical CSR directly (no edge sort); it is the only unchecked producer.
  template <typename S, typename NS>
  friend class GraphBuilder;

  static std::string describe(std::size_t index, const Edge<Scalar>& e) {
    std::ostringstream s;
    s << "edge #" << index << " (" << e.u << ", " << e.v << ")";
    return s.str();
  }

  void build_csr() {
    offsets_.assign(static_cast<std::size_t>(num_nodes_) + 1, 0);
    for (const auto& e : edges_) {
      ++offsets_[e.u + 1];
      ++offsets_[e.v + 1];
    }
    for (std::int32_t v = 0; v < num_nodes_; ++v) offsets_[v + 1] += offsets_[v];
    adjacency_.resize(edges_.size() * 2);
    std::vector<std::int32_t> fill(offsets_.begin(), offsets_.end() - 1);
    // Edges are sorted by (u, v). For node x the first pass appends the smaller endpoints w < x of
    // edges (w, x) in increasing w, the second the larger endpoints of edges (x, v) in increasing v:
    // every list comes out sorted without a sort.
    for (const auto& e : edges_) adjacency_[fill[e.v]++] = e.u;
    for (const auto& e : edges_) adjacency_[fill[e.u]++] = e.v;
  }

  std::int32_t num_nodes_ = 0;
  bool weighted_ = false;
  std::vector<Point> positions_;
  std::vector<NodeKind> kinds_;
  std::vector<Edge<Scalar>> edges_;
  std::vector<std::uint8_t> edge_rounds_;
  std::vector<std::int32_t> offsets_{0};
  std::vector<std::int32_t> adjacency_;
};

}  // namespace cge
