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

#include "cge/graph/graph.hpp"

namespace cge {

struct HopDiameter {
  std::int32_t diameter = 0;    ///< largest finite hop distance (0 without edges)
  std::int32_t components = 0;  ///< connected components, isolated nodes included
  std::int32_t searches = 0;    ///< breadth-first searches run (a cost figure, not a result)
};

/// Exact hop diameter and component count. An empty graph has diameter 0 and no component.
template <typename Scalar>
HopDiameter hop_diameter(const Graph<Scalar>& g) {
  const std::int32_t n = g.num_nodes();
  const std::size_t size = static_cast<std::size_t>(n);
  HopDiameter result;
  std::vector<std::int32_t> component(size, -1);
  std::vector<std::int32_t> distance(size, -1);
  std::vector<std::int32_t> lower(size, 0), upper(size, 0);
  std::vector<std::int32_t> members, queue;
  queue.reserve(size);

  // Distances from `source` within its component; returns its eccentricity.
  auto search = [&](std::int32_t source) {
    for (const std::int32_t w : members) distance[static_cast<std::size_t>(w)] = -1;
    distance[static_cast<std::size_t>(source)] = 0;
    queue.assign(1, source);
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::int32_t u = queue[head];
      for (const std::int32_t w : g.neighbors(u)) {
        if (distance[static_cast<std::size_t>(w)] < 0) {
          distance[static_cast<std::size_t>(w)] = distance[static_cast<std::size_t>(u)] + 1;
          queue.push_back(w);
        }
      }
    }
    ++result.searches;
    return distance[static_cast<std::size_t>(queue.back())];
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

}  // namespace cge
