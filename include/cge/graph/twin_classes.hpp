#pragma once
// Twin classes of an undirected simple graph: nodes with the same neighbours.
//
// u and v are true twins when their closed neighbourhoods are equal (N[u] = N[v]: adjacent, same
// other neighbours) and false twins when their open neighbourhoods are equal (N(u) = N(v): not
// adjacent). Either way, swapping u and v is an automorphism of the graph, so every quantity
// defined by the structure alone (hop distances, shortest-path counts, Delta(v, k) of
// docs/METHOD.md section 4 in every tie mode) is the same for both. A node with a true twin has no
// false twin, so the two relations together partition the nodes.
//
// Frame graphs have many: the round-based radius search joins a centre to every node within R,
// and a tight cluster of features becomes a clique whose members see the same nodes (the
// benchmark's second frame: 340 nodes in 288 classes, one class of 6 among the lightest nodes).
//
// O(|V| + |E|) expected, plus a sort of |V| keys; deterministic (hashes only group candidates,
// members are compared exactly). The representative of a class is its smallest node index.

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "cge/core/splitmix64.hpp"
#include "cge/graph/graph.hpp"

namespace cge {

struct TwinClasses {
  /// representative[v]: the smallest node index with the same closed or open neighbourhood as v
  /// (v itself when it has no twin).
  std::vector<std::int32_t> representative;
  std::int32_t num_classes = 0;
};

namespace detail {

/// Whether the neighbour lists of a and b (sorted ascending), each with its own node added when
/// `closed`, hold the same nodes.
template <typename Scalar>
bool same_neighbourhood(const Graph<Scalar>& g, std::int32_t a, std::int32_t b, bool closed) {
  const IndexSpan na = g.neighbors(a), nb = g.neighbors(b);
  if (na.size() != nb.size()) return false;
  if (!closed) return std::equal(na.begin(), na.end(), nb.begin());
  // N(a) + {a} == N(b) + {b} with a != b: a and b adjacent, and the rest equal.
  if (!std::binary_search(na.begin(), na.end(), b)) return false;
  std::size_t i = 0, j = 0;
  while (i < na.size() || j < nb.size()) {
    const std::int32_t x = i < na.size() ? na[i] : INT32_MAX;
    const std::int32_t y = j < nb.size() ? nb[j] : INT32_MAX;
    if (x == b) { ++i; continue; }  // b's own entry in N[b]
    if (y == a) { ++j; continue; }
    if (x != y) return false;
    ++i;
    ++j;
  }
  return true;
}

}  // namespace detail

template <typename Scalar>
TwinClasses twin_classes(const Graph<Scalar>& g) {
  const std::int32_t n = g.num_nodes();
  const std::size_t size = static_cast<std::size_t>(n);
  TwinClasses result;
  result.representative.resize(size);
  std::iota(result.representative.begin(), result.representative.end(), 0);

  // Order-independent hashes of N(v) and N[v]: sums of mixed node indices.
  std::vector<std::uint64_t> open_hash(size), closed_hash(size);
  for (std::int32_t v = 0; v < n; ++v) {
    std::uint64_t h = 0;
    for (const std::int32_t u : g.neighbors(v)) h += splitmix64(static_cast<std::uint64_t>(u));
    open_hash[static_cast<std::size_t>(v)] = h;
    closed_hash[static_cast<std::size_t>(v)] = h + splitmix64(static_cast<std::uint64_t>(v));
  }
  std::vector<std::int32_t> order(size);
  for (const bool closed : {true, false}) {
    const std::vector<std::uint64_t>& hash = closed ? closed_hash : open_hash;
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
      const std::uint64_t ha = hash[static_cast<std::size_t>(a)], hb = hash[static_cast<std::size_t>(b)];
      return ha != hb ? ha < hb : a < b;
    });
    // Within a run of equal hashes (ascending node index), each node joins the first earlier
    // node it really shares its neighbourhood with; that node is the smallest of the class.
    for (std::size_t first = 0; first < size;) {
      std::size_t last = first + 1;
      while (last < size && hash[static_cast<std::size_t>(order[last])] == hash[static_cast<std::size_t>(order[first])]) ++last;
      for (std::size_t i = first + 1; i < last; ++i) {
        const std::int32_t v = order[i];
        if (result.representative[static_cast<std::size_t>(v)] != v) continue;
        for (std::size_t j = first; j < i; ++j) {
          const std::int32_t u = order[j];
          if (result.representative[static_cast<std::size_t>(u)] != u) continue;
          if (detail::same_neighbourhood(g, u, v, closed)) {
            result.representative[static_cast<std::size_t>(v)] = u;
            break;
          }
        }
      }
      first = last;
    }
  }
  for (std::int32_t v = 0; v < n; ++v) result.num_classes += result.representative[static_cast<std::size_t>(v)] == v;
  return result;
}

}  // namespace cge
