#pragma once
// DegreeDegreeEntropy: the degree-degree association entropy of an unweighted graph and its
// information index (docs/METHOD.md section 4).
//
//   E(v) = sum_{k=1..rho} c_k Delta(v, k)        exponent (coefficient policy, tie mode)
//   f(v) = alpha^E(v), p(v) = f(v) / sum f        evaluated as a log-domain softmax, never alpha^E
//   H    = -sum p log2 p                          bits
//   I    = lambda (log2 |V| - H)                  information index
//
// compute() costs O(|V| |E|) time, O(|V| rho) memory. compute_index() (and information_index())
// gives H and I without the per-node exponents; for alpha < 1 with raw exponents and non-negative
// coefficients it completes E(v) only for the nodes that carry weight (kernels/weight_bounded_entropy.hpp:
// the nodes it leaves out weigh less than e^-100 of the heaviest, which moves H by under
// |V| 2e-41 bits; twins are searched once): 3-4x faster at 1000 nodes, little on dense 300-node
// graphs (docs/BENCHMARK.md).
// Deterministic: the result depends only on the graph's structure (not node numbering) and the
// settings. Disconnected input: rho is the largest finite distance and unreachable pairs are
// ignored (result.connected tells). Empty graph: throws.

#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "cge/core/concepts.hpp"
#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/kernels/weight_bounded_entropy.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/entropy/softmax_entropy.hpp"
#include "cge/graph/adjacency_bitsets.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/hop_diameter.hpp"

namespace cge {

template <typename Scalar>
struct DegreeDegreeSettings {
  /// Base of the functional alpha^E, > 0 (ours, the specification's 0.5; the paper gives no value:
  /// alpha < 1 gives the nodes with the smallest degree-difference sums the most weight).
  Scalar alpha = Scalar(0.5);
  /// Scale of the information index, > 0 (ours: 1 keeps I in bits; the paper gives no value).
  Scalar lambda = Scalar(1);
  /// How tied shortest paths count: all (multiplicity, the specification's default). The paper
  /// chooses one path, "the case where v has the shortest total path": closest to TieMode::min
  /// (its effect on loop closing is measured in docs/LOOP_CLOSING.md).
  TieMode ties = TieMode::all;
  /// G, natural-log units: compute_index() leaves out nodes whose weight f(v) is below e^-G times
  /// the largest, which moves H by at most |V| e^-G (1 + G + ln|V|) / ln 2 bits. At least 1;
  /// +infinity evaluates every node. compute() never leaves any out.
  double negligible_log_weight = 100.0;
};

template <typename Scalar>
struct DegreeDegreeResult {
  std::vector<Scalar> exponents;  ///< E(v) per node, after the scaling policy
  Scalar entropy_bits = 0;        ///< H
  Scalar max_entropy_bits = 0;    ///< log2 |V|
  Scalar information_index = 0;   ///< I = lambda (log2 |V| - H)
  std::int32_t diameter = 0;      ///< rho, the largest finite hop distance
  bool connected = true;
  std::int32_t exponents_evaluated = 0;  ///< nodes whose E(v) is known in full, twins included (compute(): all)
};

template <typename Scalar = double, typename Coefficients = StandardCoefficients, typename Scaling = ExponentScaling>
class DegreeDegreeEntropy {
 public:
  static_assert(std::is_floating_point<Scalar>::value, "Scalar must be a floating-point type");
#if CGE_HAS_CONCEPTS
  static_assert(CoefficientPolicy<Coefficients>,
                "Coefficients must satisfy the contract in cge/entropy/coefficients.hpp");
  static_assert(ExponentScalingPolicy<Scaling>,
                "Scaling must satisfy the contract in cge/entropy/exponent_scaling.hpp");
#endif
  using Settings = DegreeDegreeSettings<Scalar>;
  using Result = DegreeDegreeResult<Scalar>;

  Settings settings;
  Coefficients coefficients;
  Scaling scaling;

  DegreeDegreeEntropy() = default;
  explicit DegreeDegreeEntropy(const Settings& s, Coefficients c = Coefficients(), Scaling x = Scaling())
      : settings(s), coefficients(std::move(c)), scaling(std::move(x)) {}

  /// Everything at once. Accumulation is in double for every Scalar.
  template <typename GraphScalar>
  Result compute(const Graph<GraphScalar>& g) const {
    validate();
    return from_table(shortest_path_degree_sums(g, settings.ties));
  }

  /// H, I, rho and connectivity without the per-node exponents (`exponents` is left empty). With
  /// alpha < 1, the raw ExponentScaling and coefficients c_k >= 0, exponents are completed only for
  /// the nodes within negligible_log_weight of the heaviest (see the settings); otherwise this is
  /// compute() without the exponents. It can succeed where compute() reports overflow: a node
  /// whose path counts overflow after its search was cut weighs nothing.
  template <typename GraphScalar>
  Result compute_index(const Graph<GraphScalar>& g) const {
    validate();
    detail::require_nodes(g.num_nodes());
    if (!bounded_search_applies()) return without_exponents(compute(g));
    // Bitset rows serve the diameter's and the index's searches where they pay.
    const std::optional<AdjacencyBitsets> rows = AdjacencyBitsets::if_rows_pay(g);
    const HopDiameter d = rows ? hop_diameter(g, *rows) : hop_diameter(g);
    const std::vector<double> c = coefficient_table(d.diameter);
    for (std::size_t k = 1; k < c.size(); ++k) {
      if (!(c[k] >= 0.0) || !std::isfinite(c[k])) return without_exponents(compute(g));
    }
    const double log_alpha = std::log(static_cast<double>(settings.alpha));
    const double negligible = settings.negligible_log_weight;
    const detail::WeightBoundedEntropy bounded = detail::with_tie_mode(settings.ties, [&](auto mode) {
      return detail::weight_bounded_entropy<decltype(mode)::value>(g, rows ? &*rows : nullptr, c, log_alpha,
                                                                   negligible);
    });
    return entropy_result(bounded.entropy_bits, g.num_nodes(), d.diameter, d.components == 1,
                          bounded.exponents_evaluated);
  }

  /// The index alone (what CGESimilarity compares): compute_index(g).information_index.
  template <typename GraphScalar>
  Scalar information_index(const Graph<GraphScalar>& g) const {
    return compute_index(g).information_index;
  }

  /// The second half, for callers that already hold the Delta table (studies of alpha, lambda,
  /// coefficient schemes on one graph without repeating the O(|V||E|) part).
  Result from_table(const DegreeSumTable& table) const {
    validate();
    const std::int32_t n = table.num_nodes;
    detail::require_nodes(n);
    const std::int32_t rho = table.diameter;
    const std::vector<double> c = coefficient_table(rho);

    std::vector<double> exponent(static_cast<std::size_t>(n), 0.0);
    for (std::int32_t v = 0; v < n; ++v) {
      const std::int32_t ecc = table.eccentricity(v);
      const double* row = table.values.data() + table.row_offsets[static_cast<std::size_t>(v)];
      double e = 0.0;
      for (std::int32_t k = 1; k <= ecc; ++k) e += c[static_cast<std::size_t>(k)] * row[k - 1];
      exponent[static_cast<std::size_t>(v)] = e;
    }
    scaling(exponent);

    const double log_alpha = std::log(static_cast<double>(settings.alpha));
    std::vector<double> log_f(exponent.size());
    for (std::size_t v = 0; v < exponent.size(); ++v) log_f[v] = exponent[v] * log_alpha;
    Result r = entropy_result(softmax_entropy_bits(log_f), n, rho, table.connected, n);
    r.exponents.assign(exponent.begin(), exponent.end());
    return r;
  }

 private:
  /// H, log2 |V| and I = lambda (log2 |V| - H) in one place for compute() and compute_index().
  Result entropy_result(double h, std::int32_t n, std::int32_t rho, bool connected, std::int32_t evaluated) const {
    const double h_max = std::log2(static_cast<double>(n));
    Result r;
    r.entropy_bits = static_cast<Scalar>(h);
    r.max_entropy_bits = static_cast<Scalar>(h_max);
    r.information_index = static_cast<Scalar>(static_cast<double>(settings.lambda) * (h_max - h));
    r.diameter = rho;
    r.connected = connected;
    r.exponents_evaluated = evaluated;
    return r;
  }

  /// c[k] = c_k for k = 1..rho; c[0] is unused.
  std::vector<double> coefficient_table(std::int32_t rho) const {
    std::vector<double> c(static_cast<std::size_t>(rho) + 1, 0.0);
    for (std::int32_t k = 1; k <= rho; ++k) c[static_cast<std::size_t>(k)] = coefficients(k, rho);
    return c;
  }

  /// The bounded search needs alpha < 1 (the heavy nodes are those of small E) and exponents as
  /// defined (a scaling by their mean needs every one of them).
  bool bounded_search_applies() const {
    if (!(settings.alpha < Scalar(1)) || std::isinf(settings.negligible_log_weight)) return false;
    if constexpr (std::is_same<Scaling, ExponentScaling>::value) {
      return scaling.kind == ScalingKind::raw;
    } else {
      return false;
    }
  }

  static Result without_exponents(Result r) {
    r.exponents.clear();
    r.exponents.shrink_to_fit();
    return r;
  }

  void validate() const {
    if (!(settings.alpha > 0) || !std::isfinite(settings.alpha)) {
      std::ostringstream msg;
      msg << "DegreeDegreeSettings: alpha must be finite and positive, got " << settings.alpha;
      throw std::invalid_argument(msg.str());
    }
    if (!(settings.lambda > 0) || !std::isfinite(settings.lambda)) {
      std::ostringstream msg;
      msg << "DegreeDegreeSettings: lambda must be finite and positive, got " << settings.lambda;
      throw std::invalid_argument(msg.str());
    }
    if (!(settings.negligible_log_weight >= 1.0)) {
      std::ostringstream msg;
      msg << "DegreeDegreeSettings: negligible_log_weight must be at least 1 (or +infinity), got "
          << settings.negligible_log_weight;
      throw std::invalid_argument(msg.str());
    }
  }
};

}  // namespace cge
