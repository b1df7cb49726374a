#pragma once
// The coefficients c_k that weight Delta(v, k) in the exponent E(v) = sum_k c_k Delta(v, k).
//
// Contract for a coefficient policy C used as DegreeDegreeEntropy<Scalar, C>:
//   double operator()(int k, int diameter) const     c_k for 1 <= k <= diameter
// It is called diameter times per graph, never in the inner loop, so a runtime switch costs nothing.

#include <cmath>
#include <stdexcept>
#include <utility>

namespace cge {

enum class CoefficientKind {
  exp,       ///< c_k = rho e^(1 - k): decreasing, the default (the paper's text lost the minus signs)
  linear,    ///< c_k = rho - k + 1
  constant,  ///< c_k = 1
};

/// The three schemes of docs/METHOD.md section 4, chosen at run time (what the command-line tool needs).
struct StandardCoefficients {
  CoefficientKind kind = CoefficientKind::exp;

  double operator()(int k, int diameter) const {
    switch (kind) {
      case CoefficientKind::exp:
        return diameter * std::exp(1.0 - k);
      case CoefficientKind::linear:
        return static_cast<double>(diameter - k + 1);
      case CoefficientKind::constant:
        return 1.0;
    }
    throw std::invalid_argument("StandardCoefficients: unknown CoefficientKind");
  }
};

/// Any callable double(int k, int diameter) as a coefficient policy.
template <typename F>
struct CustomCoefficients {
  F function;
  double operator()(int k, int diameter) const { return static_cast<double>(function(k, diameter)); }
};

template <typename F>
CustomCoefficients<F> custom_coefficients(F f) {
  return CustomCoefficients<F>{std::move(f)};
}

}  // namespace cge
