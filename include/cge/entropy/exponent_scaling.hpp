#pragma once
// How the exponents E(v) are scaled before the functional f(v) = alpha^E(v).
//
// On SLAM-sized graphs E(v) reaches 1e3..1e5, so with alpha = 0.5 the raw functional puts almost
// all mass on one or two nodes (H ~ 0, I ~ lambda log2|V|). The normalised scaling divides by the
// mean exponent so that alpha acts on a dimensionless spread. Which one discriminates loops better
// is measured by the loop-closure evaluation, not assumed.
//
// Contract for a scaling policy X used as DegreeDegreeEntropy<Scalar, C, X>:
//   void operator()(std::vector<double>& exponents) const     rescale in place

#include <stdexcept>
#include <vector>

namespace cge {

enum class ScalingKind {
  raw,              ///< E(v) as defined (the paper)
  normalised_mean,  ///< E(v) / mean_v E(v); unchanged when the mean is 0 (all E are 0 then)
};

struct ExponentScaling {
  ScalingKind kind = ScalingKind::raw;

  void operator()(std::vector<double>& exponents) const {
    switch (kind) {
      case ScalingKind::raw:
        return;
      case ScalingKind::normalised_mean: {
        if (exponents.empty()) return;
        double total = 0.0;
        for (double e : exponents) total += e;
        const double mean = total / static_cast<double>(exponents.size());
        if (mean > 0.0) {
          for (double& e : exponents) e /= mean;
        }
        return;
      }
    }
    throw std::invalid_argument("ExponentScaling: unknown ScalingKind");
  }
};

}  // namespace cge
