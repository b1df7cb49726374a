#pragma once
// Bag-of-words vectors, the L1 score, and the direct index (feature vector).
//
// A BowVector is sparse: (word id, weight) entries sorted by word id, each word once, weights > 0.
// Vocabulary::transform returns it L1-normalised (weights sum to 1).
//
// L1 score (Nister and Stewenius; DBoW2's default): s(v1, v2) = 1 - 0.5 |v1/|v1|_1 - v2/|v2|_1|_1, in
// [0, 1], 1 for vectors with the same direction, 0 for vectors without a common word. For
// normalised a, b with non-negative weights it equals sum over common words of min(a_w, b_w), which
// is how the inverted-index database computes it from the common words alone.

#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace cge {
namespace bow {

using WordId = std::uint32_t;
using NodeId = std::uint32_t;

struct BowEntry {
  WordId word = 0;
  double weight = 0;
};

using BowVector = std::vector<BowEntry>;

/// Direct index: for each vocabulary node at a chosen level, the indices of the features whose
/// descent passed through it (ascending), keyed by node id. Lets a matcher compare only features
/// that fell into the same branch.
using FeatureVector = std::map<NodeId, std::vector<int>>;

/// Sum of the weights (all are non-negative).
inline double l1_norm(const BowVector& v) {
  double s = 0;
  for (const BowEntry& e : v) s += std::fabs(e.weight);
  return s;
}

/// Scales v so its weights sum to 1 (an empty or all-zero vector stays as it is).
inline void l1_normalise(BowVector& v) {
  const double n = l1_norm(v);
  if (n > 0) {
    for (BowEntry& e : v) e.weight /= n;
  }
}

/// Throws std::invalid_argument unless v is sorted by strictly increasing word id with finite,
/// non-negative weights; `what` names the vector in the message.
inline void check_bow_vector(const BowVector& v, const char* what) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!(std::isfinite(v[i].weight) && v[i].weight >= 0)) {
      throw std::invalid_argument(std::string(what) + ": weight of word " + std::to_string(v[i].word) +
                                  " is negative or not finite");
    }
    if (i > 0 && v[i].word <= v[i - 1].word) {
      throw std::invalid_argument(std::string(what) + ": word ids are not strictly increasing at entry " +
                                  std::to_string(i));
    }
  }
}

/// s = 1 - 0.5 |a/|a| - b/|b||_1, from the definition (both vectors are normalised here, so the
/// inputs need not be). 0 when either vector is empty.
inline double l1_score(const BowVector& a, const BowVector& b) {
  const double na = l1_norm(a);
  const double nb = l1_norm(b);
  if (!(na > 0) || !(nb > 0)) return 0;
  double diff = 0;
  std::size_t i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && a[i].word < b[j].word)) {
      diff += a[i++].weight / na;
    } else if (i == a.size() || b[j].word < a[i].word) {
      diff += b[j++].weight / nb;
    } else {
      diff += std::fabs(a[i++].weight / na - b[j++].weight / nb);
    }
  }
  const double s = 1 - 0.5 * diff;
  return s < 0 ? 0 : s;  // rounding can leave -1e-17 for disjoint vectors
}

/// Number of words present in both vectors.
inline int common_words(const BowVector& a, const BowVector& b) {
  int n = 0;
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i].word < b[j].word) {
      ++i;
    } else if (b[j].word < a[i].word) {
      ++j;
    } else {
      ++n;
      ++i;
      ++j;
    }
  }
  return n;
}

}  // namespace bow
}  // namespace cge
