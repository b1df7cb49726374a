#pragma once
// Timestamp association of two trajectories, exactly as the TUM RGB-D tool associate.py does it:
//   1. candidates: every pair (a, b), a from the first list, b from the second, with
//      |a - (b + offset)| < max_difference (strict);
//   2. candidates sorted by (|a - (b + offset)|, a, b), ascending;
//   3. greedy: a candidate is taken when neither a nor b has been taken before (each stamp is
//      used at most once);
//   4. the matches sorted by a.
// The first list is the ground truth in evaluate_ate.py. Both lists must be finite and strictly
// increasing (as the TUM reader guarantees); the candidates are found by a sorted window scan
// instead of the tool's all-pairs loop, which gives the same set.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "cge/metrics/trajectory.hpp"

namespace cge {
namespace metrics {

struct AssociationSettings {
  double offset_s = 0.0;           ///< added to the second list's stamps before comparing, seconds
  double max_difference_s = 0.02;  ///< a pair must differ by less than this, seconds, > 0 (TUM default)
};

/// One associated pair: indices into the first and the second list.
struct TimestampMatch {
  std::size_t first = 0;
  std::size_t second = 0;
};

/// Associates two strictly increasing timestamp lists; see the file comment. Throws
/// std::invalid_argument for bad settings or lists.
inline std::vector<TimestampMatch> associate(const std::vector<double>& first_s, const std::vector<double>& second_s,
                                             const AssociationSettings& settings = {}) {
  if (!(std::isfinite(settings.max_difference_s) && settings.max_difference_s > 0)) {
    throw std::invalid_argument("associate: max_difference_s must be finite and > 0");
  }
  if (!std::isfinite(settings.offset_s)) throw std::invalid_argument("associate: offset_s must be finite");
  require_increasing_timestamps(first_s, "associate: first list");
  require_increasing_timestamps(second_s, "associate: second list");

  const double md = settings.max_difference_s;
  std::vector<double> shifted(second_s.size());  // b + offset, non-decreasing
  for (std::size_t j = 0; j < second_s.size(); ++j) shifted[j] = second_s[j] + settings.offset_s;

  struct Candidate {
    double difference;
    std::size_t first;
    std::size_t second;
  };
  std::vector<Candidate> candidates;
  for (std::size_t i = 0; i < first_s.size(); ++i) {
    const double a = first_s[i];
    // A window twice as wide as needed, so rounding at its ends cannot drop a candidate; the
    // exact test below decides.
    std::size_t j =
        static_cast<std::size_t>(std::lower_bound(shifted.begin(), shifted.end(), a - 2 * md) - shifted.begin());
    for (; j < shifted.size() && shifted[j] <= a + 2 * md; ++j) {
      const double difference = std::abs(a - shifted[j]);
      if (difference < md) candidates.push_back({difference, i, j});
    }
  }
  // Stamps increase, so ordering by index equals the tool's ordering by stamp value.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& l, const Candidate& r) {
    if (l.difference != r.difference) return l.difference < r.difference;
    if (l.first != r.first) return l.first < r.first;
    return l.second < r.second;
  });

  std::vector<char> first_used(first_s.size(), 0), second_used(second_s.size(), 0);
  std::vector<TimestampMatch> matches;
  for (const Candidate& c : candidates) {
    if (first_used[c.first] || second_used[c.second]) continue;
    first_used[c.first] = 1;
    second_used[c.second] = 1;
    matches.push_back({c.first, c.second});
  }
  std::sort(matches.begin(), matches.end(),
            [](const TimestampMatch& l, const TimestampMatch& r) { return l.first < r.first; });
  return matches;
}

/// Associates the poses of two trajectories by their timestamps (first = ground truth in ATE).
inline std::vector<TimestampMatch> associate(const Trajectory& first, const Trajectory& second,
                                             const AssociationSettings& settings = {}) {
  return associate(timestamps(first), timestamps(second), settings);
}

}  // namespace metrics
}  // namespace cge
