#pragma once
// NearestTwo: the best and second-best Hamming distance seen in a descriptor search, and the ratio
// test on them. Every descriptor search of the pipeline (projection matching, triangulation
// matching, brute-force two-nearest search) accumulates its candidates here, so they share one
// tie rule and one acceptance test.

#include <climits>

namespace cge {
namespace slam {

struct NearestTwo {
  int best = INT_MAX;     ///< smallest distance seen, bits (INT_MAX: none)
  int second = INT_MAX;   ///< second smallest, from another candidate (INT_MAX: none)
  int best_index = -1;    ///< candidate of `best`, -1: none
  int second_index = -1;  ///< candidate of `second`, -1: none

  /// One candidate. On equal distances the earlier candidate stays ahead (stable in visiting order).
  void add(int index, int distance) {
    if (distance < best) {
      second = best;
      second_index = best_index;
      best = distance;
      best_index = index;
    } else if (distance < second) {
      second = distance;
      second_index = index;
    }
  }

  /// Whether the best candidate is a match: within max_distance bits and, when a second candidate
  /// exists, closer than `ratio` times its distance (Lowe's ratio test, in double precision).
  bool passes(int max_distance, double ratio) const {
    if (best_index < 0 || best > max_distance) return false;
    return second == INT_MAX || best < ratio * second;
  }
};

}  // namespace slam
}  // namespace cge
