#pragma once
// The semantic pre-judgment of docs/METHOD.md section 6: do two frames show the same static
// semantic layout? X = counts per class of the static instances; S_cos_x = X_a.X_b / (|X_a||X_b|).

#include <cmath>
#include <map>
#include <vector>

#include "cge/core/semantic_instance.hpp"

namespace cge {

enum class SemanticCase {
  both_empty,  ///< neither frame has static instances: use the unweighted index only
  one_empty,   ///< exactly one frame has static instances: the structure changed, combine both
  compared,    ///< both have some: decide by the cosine against the threshold
};

struct SemanticComparison {
  SemanticCase which = SemanticCase::both_empty;
  double cosine = 0.0;  ///< S_cos_x; 0 unless which == compared
};

/// Counts of static instances per class id, ordered by class id.
template <typename Scalar>
std::map<int, int> static_class_counts(const std::vector<SemanticInstance<Scalar>>& instances) {
  std::map<int, int> counts;
  for (const auto& inst : instances) {
    if (!inst.dynamic) ++counts[inst.class_id];
  }
  return counts;
}

template <typename Scalar>
SemanticComparison compare_semantics(const std::vector<SemanticInstance<Scalar>>& a,
                                     const std::vector<SemanticInstance<Scalar>>& b) {
  const std::map<int, int> xa = static_class_counts(a);
  const std::map<int, int> xb = static_class_counts(b);
  SemanticComparison out;
  if (xa.empty() && xb.empty()) return out;
  if (xa.empty() || xb.empty()) {
    out.which = SemanticCase::one_empty;
    return out;
  }
  double dot = 0.0, na = 0.0, nb = 0.0;
  for (const auto& [cls, count] : xa) {
    na += double(count) * count;
    const auto it = xb.find(cls);
    if (it != xb.end()) dot += double(count) * it->second;
  }
  for (const auto& kv : xb) nb += double(kv.second) * kv.second;
  out.which = SemanticCase::compared;
  // One square root of the exact integer product, so that proportional count vectors (the same
  // layout) give exactly 1. (sqrt(na) * sqrt(nb) can round up: sqrt(5) * sqrt(5) > 5 made identical
  // layouts score 1 - 2^-52, below a threshold of 1.)
  out.cosine = dot / std::sqrt(na * nb);
  return out;
}

}  // namespace cge
