#pragma once
// Shannon entropy (bits) of the distribution p_i = exp(l_i) / sum_j exp(l_j), from the logs l_i.
// Works in the log domain (log-sum-exp), so weights like 0.5^30000 that underflow double are
// handled exactly: the largest log is subtracted before exponentiating.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace cge {

/// What every degree-degree path reports when an exponent E(v) is not finite.
[[noreturn]] inline void throw_exponent_not_finite() {
  throw std::overflow_error(
      "degree-degree entropy: an exponent is not finite (path multiplicities overflowed double); "
      "use TieMode::mean or TieMode::min for this graph");
}

/// H = -sum p_i log2 p_i. Throws std::overflow_error when a log weight is not finite (an exponent
/// that overflowed double upstream), std::invalid_argument for an empty input.
inline double softmax_entropy_bits(const std::vector<double>& log_weights) {
  if (log_weights.empty()) throw std::invalid_argument("softmax_entropy_bits: no weights");
  double top = log_weights[0];
  for (double l : log_weights) {
    if (!std::isfinite(l)) throw_exponent_not_finite();
    top = std::max(top, l);
  }
  // With shifted logs s_i = l_i - top <= 0 and Z = sum e^{s_i} >= 1:
  // H = log2 Z - (1 / ln 2) sum (e^{s_i} / Z) s_i. Terms with e^{s_i} = 0 contribute exactly 0.
  double z = 0.0;
  double weighted = 0.0;
  for (double l : log_weights) {
    const double s = l - top;
    const double e = std::exp(s);
    z += e;
    weighted += e * s;
  }
  const double h = std::log2(z) - weighted / (z * std::log(2.0));
  return h;
}

}  // namespace cge
