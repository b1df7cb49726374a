#pragma once
// The degree-degree entropy written out plainly (docs/METHOD.md section 4): one breadth-first
// search per source, then the formula. It is the reading copy of what the fast kernels compute and
// the oracle the tests hold them to, bit for bit; it is O(|V| |E|) like them but several times
// slower, so the library never calls it.
//
// For a source s, every node u at hop distance k >= 1, and its predecessors p (the neighbours of u
// at distance k - 1 from s):
//   N[u] = sum_p N[p]                               number of shortest s-u paths
//   S[u] = sum_p (S[p] + N[p] |d(p) - d(u)|)        sum of their degree-difference sums
//   M[u] = min_p (M[p] + |d(p) - d(u)|)             smallest of those sums
// with N[s] = 1 and S[s] = M[s] = 0. Delta(s, k) sums over the nodes u at distance k the term
// S[u] (TieMode::all), S[u] / N[u] (TieMode::mean) or M[u] (TieMode::min). Then
//   E(v) = sum_{k=1..rho} c_k Delta(v, k),   p(v) = alpha^E(v) / sum_u alpha^E(u),
//   H = -sum_v p(v) log2 p(v),               I = lambda (log2 |V| - H).
//
// The floating-point order every kernel follows, and this code defines:
//   - a node adds its predecessors in ascending node order, the product N[p] |d(p) - d(u)| rounded
//     on its own before the additions (never fused into a multiply-add);
//   - Delta(s, k) adds the terms of the nodes at distance k in ascending node order;
//   - TieMode::mean: when a level's largest count N passes 2^512, the level's N and S are scaled
//     by 2^-512 (exact, and S / N is unchanged), so N never overflows;
//   - E(v) adds c_k Delta(v, k) for k = 1, 2, ... starting from 0.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/softmax_entropy.hpp"
#include "cge/graph/graph.hpp"

namespace cge {

namespace detail {

/// a * b rounded to double by itself: `volatile` keeps the compiler from fusing it with the
/// addition that follows (a fused multiply-add rounds once, and the kernels round twice).
inline double separately_rounded_product(double a, double b) {
  volatile double product = a * b;
  return product;
}

}  // namespace detail

/// Delta(s, k) for every source s and k = 1..eccentricity(s), by one plain BFS per source. The
/// same table, bit for bit, as shortest_path_degree_sums with any kernel.
template <typename Scalar>
DegreeSumTable reference_degree_sums(const Graph<Scalar>& g, TieMode ties = TieMode::all) {
  detail::require_nodes(g.num_nodes());
  const std::int32_t n = g.num_nodes();
  const std::size_t size = static_cast<std::size_t>(n);
  const double unreached_min = std::numeric_limits<double>::infinity();

  DegreeSumTable table;
  table.num_nodes = n;
  table.row_offsets.assign(size + 1, 0);
  for (std::int32_t s = 0; s < n; ++s) {
    std::vector<std::int32_t> distance(size, -1);
    std::vector<double> count(size, 0.0);
    std::vector<double> sum(size, ties == TieMode::min ? unreached_min : 0.0);
    distance[static_cast<std::size_t>(s)] = 0;
    count[static_cast<std::size_t>(s)] = 1.0;
    sum[static_cast<std::size_t>(s)] = 0.0;
    std::vector<std::int32_t> level{s};
    std::int32_t reached = 1;
    for (std::int32_t k = 1;; ++k) {
      // The nodes at distance k: unreached neighbours of level k - 1, in ascending order.
      std::vector<std::int32_t> next;
      for (const std::int32_t p : level) {
        for (const std::int32_t u : g.neighbors(p)) {
          if (distance[static_cast<std::size_t>(u)] < 0) {
            distance[static_cast<std::size_t>(u)] = k;
            next.push_back(u);
          }
        }
      }
      if (next.empty()) break;
      std::sort(next.begin(), next.end());

      double delta = 0.0;
      double largest_count = 0.0;
      for (const std::int32_t u : next) {
        const std::size_t su = static_cast<std::size_t>(u);
        for (const std::int32_t p : g.neighbors(u)) {  // ascending
          const std::size_t sp = static_cast<std::size_t>(p);
          if (distance[sp] != k - 1) continue;
          const double step = std::fabs(static_cast<double>(g.degree(p)) - static_cast<double>(g.degree(u)));
          if (ties == TieMode::min) {
            sum[su] = std::min(sum[su], sum[sp] + step);
          } else {
            count[su] += count[sp];
            sum[su] += sum[sp] + detail::separately_rounded_product(count[sp], step);
          }
        }
        delta += ties == TieMode::mean ? sum[su] / count[su] : sum[su];
        largest_count = std::max(largest_count, count[su]);
      }
      if (ties == TieMode::mean && largest_count > std::ldexp(1.0, 512)) {
        for (const std::int32_t u : next) {
          count[static_cast<std::size_t>(u)] *= std::ldexp(1.0, -512);
          sum[static_cast<std::size_t>(u)] *= std::ldexp(1.0, -512);
        }
      }
      table.values.push_back(delta);
      reached += static_cast<std::int32_t>(next.size());
      level = next;
    }
    if (reached < n) table.connected = false;
    table.row_offsets[static_cast<std::size_t>(s) + 1] = static_cast<std::int64_t>(table.values.size());
    table.diameter = std::max(table.diameter, table.eccentricity(s));
  }
  return table;
}

/// E(v) for every node, H, I, rho and connectivity from the reference table: what
/// DegreeDegreeEntropy::compute returns, bit for bit, for the same settings and policies.
template <typename Scalar, typename GraphScalar, typename Coefficients = StandardCoefficients,
          typename Scaling = ExponentScaling>
DegreeDegreeResult<Scalar> reference_degree_degree_entropy(const Graph<GraphScalar>& g,
                                                           const DegreeDegreeSettings<Scalar>& settings,
                                                           const Coefficients& coefficients = Coefficients(),
                                                           const Scaling& scaling = Scaling()) {
  const DegreeSumTable table = reference_degree_sums(g, settings.ties);
  const std::int32_t n = table.num_nodes;
  const std::int32_t rho = table.diameter;

  std::vector<double> exponent(static_cast<std::size_t>(n), 0.0);
  for (std::int32_t v = 0; v < n; ++v) {
    double e = 0.0;
    for (std::int32_t k = 1; k <= table.eccentricity(v); ++k) {
      e += static_cast<double>(coefficients(k, rho)) * table.delta(v, k);
    }
    exponent[static_cast<std::size_t>(v)] = e;
  }
  scaling(exponent);

  // log f(v) = E(v) ln alpha; the entropy of the normalised weights is taken in the log domain,
  // because alpha^E itself underflows double on graphs of a few hundred nodes.
  const double log_alpha = std::log(static_cast<double>(settings.alpha));
  std::vector<double> log_weight(exponent.size());
  for (std::size_t v = 0; v < exponent.size(); ++v) log_weight[v] = exponent[v] * log_alpha;
  const double h = softmax_entropy_bits(log_weight);
  const double h_max = std::log2(static_cast<double>(n));

  DegreeDegreeResult<Scalar> result;
  result.exponents.assign(exponent.begin(), exponent.end());
  result.entropy_bits = static_cast<Scalar>(h);
  result.max_entropy_bits = static_cast<Scalar>(h_max);
  result.information_index = static_cast<Scalar>(static_cast<double>(settings.lambda) * (h_max - h));
  result.diameter = rho;
  result.connected = table.connected;
  result.exponents_evaluated = n;
  return result;
}

}  // namespace cge
