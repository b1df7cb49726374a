#pragma once
// DegreeDegreeEntropy: the degree-degree association entropy of an unweighted graph and its
// information index (ALGORITHMS.md section 4).
//
//   E(v) = sum_{k=1..rho} c_k Delta(v, k)        exponent (coefficient policy, tie mode)
//   f(v) = alpha^E(v), p(v) = f(v) / sum f        evaluated as a log-domain softmax, never alpha^E
//   H    = -sum p log2 p                          bits
//   I    = lambda (log2 |V| - H)                  information index
//
// Cost O(|V| |E|) time, O(|V| rho) memory. Deterministic: the result depends only on the graph's
// structure (not node numbering) and the settings. Disconnected input: rho is the largest finite
// distance and unreachable pairs are ignored (result.connected tells). Empty graph: throws.

#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "cge/core/concepts.hpp"
#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/entropy/softmax_entropy.hpp"
#include "cge/graph/graph.hpp"

namespace cge {

template <typename Scalar>
struct DegreeDegreeSettings {
  Scalar alpha = Scalar(0.5);   ///< base of the functional alpha^E, > 0 (paper: 0.5)
  Scalar lambda = Scalar(1);    ///< scale of the information index, > 0 (paper: 1)
  TieMode ties = TieMode::all;  ///< how tied shortest paths count (all = multiplicity)
};

template <typename Scalar>
struct DegreeDegreeResult {
  std::vector<Scalar> exponents;  ///< E(v) per node, after the scaling policy
  Scalar entropy_bits = 0;        ///< H
  Scalar max_entropy_bits = 0;    ///< log2 |V|
  Scalar information_index = 0;   ///< I = lambda (log2 |V| - H)
  std::int32_t diameter = 0;      ///< rho, the largest finite hop distance
  bool connected = true;
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

  /// The index alone (what CGESimilarity compares).
  template <typename GraphScalar>
  Scalar information_index(const Graph<GraphScalar>& g) const {
    return compute(g).information_index;
  }

  /// The second half, for callers that already hold the Delta table (studies of alpha, lambda,
  /// coefficient schemes on one graph without repeating the O(|V||E|) part).
  Result from_table(const DegreeSumTable& table) const {
    validate();
    const std::int32_t n = table.num_nodes;
    if (n == 0) throw std::invalid_argument("degree-degree entropy: the graph has no nodes");
    const std::int32_t rho = table.diameter;
    std::vector<double> c(static_cast<std::size_t>(rho) + 1, 0.0);
    for (std::int32_t k = 1; k <= rho; ++k) c[static_cast<std::size_t>(k)] = coefficients(k, rho);

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
    const double h = softmax_entropy_bits(log_f);
    const double h_max = std::log2(static_cast<double>(n));

    Result r;
    r.exponents.assign(exponent.begin(), exponent.end());
    r.entropy_bits = static_cast<Scalar>(h);
    r.max_entropy_bits = static_cast<Scalar>(h_max);
    r.information_index = static_cast<Scalar>(static_cast<double>(settings.lambda) * (h_max - h));
    r.diameter = rho;
    r.connected = table.connected;
    return r;
  }

 private:
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
  }
};

}  // namespace cge
