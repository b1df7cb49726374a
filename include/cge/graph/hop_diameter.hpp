#pragma once
// The hop diameter of an unweighted graph: the largest finite shortest-path distance, exact,
// usually from a handful of breadth-first searches instead of one per node.
//
// Per connected component, eccentricity bounds are tightened by each search (Takes and Kosters'
// bounding-diameters scheme): a BFS from v with eccentricity e gives every node w
//   max(d(v, w), e - d(v, w)) <= ecc(w) <= e + d(v, w),
// and the component's diameter is found once the largest lower bound meets the largest upper
// bound. The next source alternates between the node with the largest upper bound and the one
// with the smallest lower bound, among the nodes whose eccentricity is not yet known; every search
// fixes its source's eccentricity, so the loop ends after at most |component| searches.
// Deterministic: ties go to the lowest node index.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/core/bits.hpp"
#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/graph.hpp"

namespace cge {

struct HopDiameter {
  std::int32_t diameter = 0;    ///< largest finite hop distance (0 without edges)
  std::int32_t components = 0;  ///< connected components, isolated nodes included
  std::int32_t searches = 0;    ///< breadth-first searches run (a cost figure, not a result)
};

namespace detail {

/// Breadth-first distances over neighbour lists.
template <typename Scalar>
class ListDistances {
 public:
  explicit ListDistances(const Graph<Scalar>& g) : g_(g) { queue_.reserve(static_cast<std::size_t>(g.num_nodes())); }

  /// distance[w] for every node w of the source's component (members: that component's nodes,
  /// the only entries it resets); returns the source's eccentricity.
  std::int32_t operator()(std::int32_t source, const std::vector<std::int32_t>& members,
                          std::vector<std::int32_t>& distance) {
    for (const std::int32_t w : members) distance[static_cast<std::size_t>(w)] = -1;
    distance[static_cast<std::size_t>(source)] = 0;
    queue_.assign(1, source);
    for (std::size_t head = 0; head < queue_.size(); ++head) {
      const std::int32_t u = queue_[head];
      for (const std::int32_t w : g_.neighbors(u)) {
        if (distance[static_cast<std::size_t>(w)] < 0) {
          distance[static_cast<std::size_t>(w)] = distance[static_cast<std::size_t>(u)] + 1;
          queue_.push_back(w);
        }
      }
    }
    return distance[static_cast<std::size_t>(queue_.back())];
  }

 private:
  const Graph<Scalar>& g_;
  std::vector<std::int32_t> queue_;
};

/// The same distances level by level on adjacency bitsets (cge/graph/adjacency_bitsets.hpp).
class BitsetDistances {
 public:
  explicit BitsetDistances(const AdjacencyBitsets& rows)
      : rows_(rows),
        visited_(rows.words(), 0),
        next_(rows.words(), 0),
        frontier_(rows.num_nodes()),
        level_(rows.num_nodes()) {}

  std::int32_t operator()(std::int32_t source, const std::vector<std::int32_t>&, std::vector<std::int32_t>& distance) {
    std::fill(visited_.begin(), visited_.end(), std::uint64_t{0});
    visited_[static_cast<std::size_t>(source) / 64] |= AdjacencyBitsets::bit(source);
    distance[static_cast<std::size_t>(source)] = 0;
    frontier_[0] = source;
    std::size_t frontier_size = 1;
    for (std::int32_t k = 1;; ++k) {
      const AdjacencyBitsets::Span touched = rows_.or_rows(frontier_.data(), frontier_size, next_.data());
      std::size_t level_size = 0;
      for (std::size_t w = touched.first; w < touched.end; ++w) {
        std::uint64_t fresh = next_[w] & ~visited_[w];
        next_[w] = 0;
        visited_[w] |= fresh;
        for (; fresh != 0; fresh &= fresh - 1) {
          const std::int32_t u = static_cast<std::int32_t>(w * 64 + static_cast<std::size_t>(lowest_bit(fresh)));
          distance[static_cast<std::size_t>(u)] = k;
          level_[level_size++] = u;
        }
      }
      if (level_size == 0) return k - 1;
      std::swap(frontier_, level_);
      frontier_size = level_size;
    }
  }

 private:
  const AdjacencyBitsets& rows_;
  std::vector<std::uint64_t> visited_, next_;  // next_ is all zero between levels
  std::vector<std::int32_t> frontier_, level_;
};

/// hop_diameter with a distance search (ListDistances or BitsetDistances: the same distances).
template <typename Scalar, typename Distances>
HopDiameter hop_diameter_with(const Graph<Scalar>& g, Distances& distances_from) {
  const std::int32_t n = g.num_nodes();
  const std::size_t size = static_cast<std::size_t>(n);
  HopDiameter result;
  std::vector<std::int32_t> component(size, -1);
  std::vector<std::int32_t> distance(size, -1);
  std::vector<std::int32_t> lower(size, 0), upper(size, 0);
  std::vector<std::int32_t> members;

  // Distances from `source` within its component; returns its eccentricity.
  auto search = [&](std::int32_t source) {
    ++result.searches;
    return distances_from(source, members, distance);
  };

  for (std::int32_t seed = 0; seed < n; ++seed) {
    if (component[static_cast<std::size_t>(seed)] >= 0) continue;
    // The component's members, in BFS order from its lowest node, then ascending.
    members.assign(1, seed);
    component[static_cast<std::size_t>(seed)] = result.components;
    for (std::size_t head = 0; head < members.size(); ++head) {
      for (const std::int32_t w : g.neighbors(members[head])) {
        if (component[static_cast<std::size_t>(w)] < 0) {
          component[static_cast<std::size_t>(w)] = result.components;
          members.push_back(w);
        }
      }
    }
    ++result.components;
    if (members.size() <= 2) {  // a node or an edge: nothing to search
      result.diameter = std::max(result.diameter, static_cast<std::int32_t>(members.size()) - 1);
      continue;
    }
    std::sort(members.begin(), members.end());
    for (const std::int32_t w : members) {
      lower[static_cast<std::size_t>(w)] = 0;
      upper[static_cast<std::size_t>(w)] = std::numeric_limits<std::int32_t>::max();
    }
    std::int32_t best_lower = 0;  // the component's diameter is at least this
    bool pick_largest_upper = true;
    for (;;) {
      // The next source among the nodes whose eccentricity is still open.
      std::int32_t source = -1;
      for (const std::int32_t w : members) {
        const std::size_t sw = static_cast<std::size_t>(w);
        if (lower[sw] == upper[sw]) continue;
        if (source < 0) {
          source = w;
          continue;
        }
        const std::size_t ss = static_cast<std::size_t>(source);
        if (pick_largest_upper ? upper[sw] > upper[ss] : lower[sw] < lower[ss]) source = w;
      }
      if (source < 0) break;  // every eccentricity known
      pick_largest_upper = !pick_largest_upper;
      const std::int32_t ecc = search(source);
      std::int32_t best_upper = 0;
      for (const std::int32_t w : members) {
        const std::size_t sw = static_cast<std::size_t>(w);
        const std::int32_t d = distance[sw];
        lower[sw] = std::max(lower[sw], std::max(d, ecc - d));
        upper[sw] = std::min(upper[sw], ecc + d);
        best_lower = std::max(best_lower, lower[sw]);
        best_upper = std::max(best_upper, upper[sw]);
      }
      if (best_lower >= best_upper) break;
    }
    result.diameter = std::max(result.diameter, best_lower);
  }
  return result;
}

}  // namespace detail

/// Exact hop diameter and component count. An empty graph has diameter 0 and no component.
template <typename Scalar>
HopDiameter hop_diameter(const Graph<Scalar>& g) {
  detail::ListDistances<Scalar> distances(g);
  return detail::hop_diameter_with(g, distances);
}

/// The same, searching on g's adjacency bitsets (faster where AdjacencyBitsets::rows_pay).
template <typename Scalar>
HopDiameter hop_diameter(const Graph<Scalar>& g, const AdjacencyBitsets& rows) {
  detail::BitsetDistances distances(rows);
  return detail::hop_diameter_with(g, distances);
}

}  // namespace cge
