#pragma once
// The entropy H of p(v) = alpha^E(v) / sum alpha^E for alpha < 1 (docs/METHOD.md section 4),
// computing E(v) = sum_k c_k Delta(v, k) in full only for the nodes that carry weight.
//
// Why it is safe. With c_k >= 0 every term is >= 0, so the partial sums of E(v) over
// k = 1, 2, ... only grow (in floating point too: adding a non-negative number never rounds
// down). A node whose partial sum passes E_min + G / |ln alpha| has log weight
// s_v = (E(v) - E_min) ln alpha < -G against the heaviest node, and its search stops there.
// Leaving out a set R of such nodes moves H by at most
//   |R| e^-G (1 + G + ln |V|) / ln 2   bits
// (the normaliser changes by at most |R| e^-G and the weighted log sum by at most |R| G e^-G,
// since t e^-t falls for t > 1). With G = 100 that is below |V| 2e-41 bits: far under the
// rounding of the full sum. The result is defined as the entropy of the nodes with s_v >= -G,
// summed in ascending node order, so it does not depend on the search order below.
//
// Terms from other searches. E(v) = sum over u != v of c_{d(v,u)} T(v, u), where T(v, u) is u's
// term of Delta(v, d(v, u)) (S, S / N or the minimum, by tie mode) and T(v, u) = T(u, v): a
// shortest path read backwards is one, with the same degree steps. So every search from s hands
// each node u it reaches a term of E(u), and the whole twin class of s hands u that term times
// the class size (swapping s with a twin fixes u). Before v's search, its first term plus what
// earlier searches handed it from distance 2 or more is a lower bound of E(v), and v is not
// searched at all when that passes the cut. Because the bound adds the same terms in another
// order, it may round above v's own sum by a few ulps; it decides only with the margin
// kAssembledBoundSafety, so a node is never left out that its own search would keep. On the
// benchmark's second frame graph 150 of 280 searches are skipped this way. (Keeping the handed
// terms per distance, to bound the rest of E(v) during v's search too, saved another 3 to 6 % of
// the time and cost |V| rho doubles: not kept.)
//
// Search order. Twins (cge/graph/twin_classes.hpp) have equal exponents, so one search serves a
// whole class: only class representatives are searched, and every member takes its
// representative's result (in exact arithmetic the same number; a member's own search could differ
// in the last bits, as sums taken in another order do). Representatives are taken in ascending
// order of their first term c_1 Delta(v, 1) (a lower bound of E(v)), each searched alone and
// stopped at the level where its partial sum passes the cut; the running minimum of the completed
// exponents tightens the cut, and once a source's first term alone passes it, so do all later
// ones. On frame-like graphs with raw exponents (E in the thousands) most searches stop after a
// few levels. Slower, measured: running the survivors in the 64-source block kernels with lanes
// dropped at the cut (the blocks complete more sources before the cut tightens), and a best-first
// order with saved, resumable searches (it reaches the smallest exponent first and visits up to a
// third fewer arcs, but saving and resuming cost more than that saves).
//
// Kernel. Each search runs on adjacency bitsets where they pay (AdjacencyBitsets::rows_pay:
// GraphBuilder's graphs), else on the neighbour lists; both give the same bits.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cge/entropy/degree_sum_table.hpp"
#include "cge/entropy/kernels/single_source_bfs.hpp"
#include "cge/entropy/kernels/single_source_bitset_bfs.hpp"
#include "cge/entropy/softmax_entropy.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/twin_classes.hpp"

namespace cge {
namespace detail {

struct WeightBoundedEntropy {
  double entropy_bits = 0;
  std::int32_t exponents_evaluated = 0;  ///< nodes whose E(v) was completed (a twin counts with its class)
  std::int32_t searches_skipped = 0;     ///< representatives left out by other searches' terms alone
};

/// Relative safety factor of a lower bound assembled from other searches' terms. Such a bound sums
/// the same positive terms as E(v) in another order, so it can exceed the E(v) that v's own search
/// would compute by a few hundred ulps (about depth x degree rounding steps); 1e-9 leaves a factor
/// of more than 1000 on graphs of 3000 nodes and diameter 100, so a node is left out only where its
/// own search would have left it out too.
constexpr double kAssembledBoundSafety = 1e-9;

/// Whether a lower bound of E(v) assembled from other searches' terms passes the cut for certain.
inline bool exceeds_cut(double assembled_bound, double cut) {
  return assembled_bound * (1.0 - kAssembledBoundSafety) > cut;
}

/// The search below with a single-source kernel for g (SingleSourceBfsDegreeSums or
/// SingleSourceBitsetBfsDegreeSums: the same bits, different speeds).
template <typename Sums, typename Scalar>
WeightBoundedEntropy weight_bounded_entropy_with(const Graph<Scalar>& g, Sums& sums,
                                                 const std::vector<double>& coefficients, double log_alpha,
                                                 double negligible_log_weight) {
  const std::int32_t n = g.num_nodes();
  const std::size_t size = static_cast<std::size_t>(n);
  const TwinClasses twins = twin_classes(g);
  std::vector<std::int32_t> order;
  order.reserve(static_cast<std::size_t>(twins.num_classes));
  std::vector<double> class_size(size, 0.0);  // at each representative
  for (std::int32_t v = 0; v < n; ++v) {
    const std::int32_t r = twins.representative[static_cast<std::size_t>(v)];
    if (r == v) order.push_back(v);
    class_size[static_cast<std::size_t>(r)] += 1.0;
  }
  // c_1 Delta(v, 1) of the representatives: at level 1 every tie mode holds |d(v) - d(u)| at each
  // neighbour u, summed in ascending order as a level is summed, so this is the search's first
  // partial sum.
  std::vector<double> first_term(size, 0.0);
  if (coefficients.size() > 1) {
    for (const std::int32_t v : order) {
      double delta = 0.0;
      for (const std::int32_t u : g.neighbors(v)) {
        delta += std::fabs(static_cast<double>(g.degree(v)) - static_cast<double>(g.degree(u)));
      }
      first_term[static_cast<std::size_t>(v)] = 0.0 + coefficients[1] * delta;
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return first_term[static_cast<std::size_t>(a)] < first_term[static_cast<std::size_t>(b)];
  });

  // A partial exponent above cut_offset past the smallest complete one weighs less than e^-G.
  const double cut_offset = negligible_log_weight / -log_alpha;
  double smallest = std::numeric_limits<double>::infinity();
  std::vector<double> exponent(size, 0.0);
  std::vector<std::uint8_t> complete(size, 0);
  WeightBoundedEntropy result;
  // handed[u]: the terms of E(u) that the searches so far handed u from distance 2 or more (see
  // "Terms from other searches" above); distance 1 is in first_term.
  std::vector<double> handed(size, 0.0);
  for (const std::int32_t s : order) {
    const std::size_t source = static_cast<std::size_t>(s);
    if (first_term[source] > smallest + cut_offset) break;
    if (exceeds_cut(first_term[source] + handed[source], smallest + cut_offset)) {
      ++result.searches_skipped;
      continue;
    }
    const double weight = class_size[source];
    double e = 0.0;
    bool cut = false;
    sums.run(s, [&](std::int32_t k, double delta) {
      const double c = coefficients[static_cast<std::size_t>(k)];
      e += c * delta;
      if (!std::isfinite(e)) throw_exponent_not_finite();
      if (k >= 2) {
        for (const std::int32_t* u = sums.level_begin(); u != sums.level_end(); ++u) {
          handed[static_cast<std::size_t>(*u)] += weight * c * sums.node_term(*u);
        }
      }
      cut = e > smallest + cut_offset;
      return !cut;
    });
    if (cut) continue;
    exponent[source] = e;
    complete[source] = 1;
    smallest = std::min(smallest, e);
  }
  for (std::size_t v = 0; v < size; ++v) {
    const std::size_t r = static_cast<std::size_t>(twins.representative[v]);
    exponent[v] = exponent[r];
    complete[v] = complete[r];
    result.exponents_evaluated += complete[v];
  }

  const double top = smallest * log_alpha;
  std::vector<double> log_weights;
  for (std::size_t v = 0; v < size; ++v) {
    if (!complete[v]) continue;
    const double log_weight = exponent[v] * log_alpha;
    if (log_weight - top >= -negligible_log_weight) log_weights.push_back(log_weight);
  }
  result.entropy_bits = softmax_entropy_bits(log_weights);
  return result;
}

/// coefficients[k] = c_k for k = 1..diameter (index 0 unused), all finite and >= 0; log_alpha < 0;
/// negligible_log_weight = G >= 1 (+infinity evaluates every node). rows: g's adjacency bitsets,
/// where they pay (AdjacencyBitsets::rows_pay), else nullptr for the neighbour-list kernel.
template <TieMode Mode, typename Scalar>
WeightBoundedEntropy weight_bounded_entropy(const Graph<Scalar>& g, const AdjacencyBitsets* rows,
                                            const std::vector<double>& coefficients, double log_alpha,
                                            double negligible_log_weight) {
  if (rows != nullptr) {
    SingleSourceBitsetBfsDegreeSums<Mode, Scalar> sums(g, *rows);
    return weight_bounded_entropy_with(g, sums, coefficients, log_alpha, negligible_log_weight);
  }
  SingleSourceBfsDegreeSums<Mode, Scalar> sums(g);
  return weight_bounded_entropy_with(g, sums, coefficients, log_alpha, negligible_log_weight);
}

}  // namespace detail
}  // namespace cge
