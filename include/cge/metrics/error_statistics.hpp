#pragma once
// Summary statistics of a list of errors, as the TUM RGB-D tools print them: root mean square,
// mean, median (the mean of the two middle values for an even count, as numpy.median), population
// standard deviation (numpy.std, divided by n), minimum and maximum.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace cge {
namespace metrics {

struct ErrorStatistics {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;  ///< population standard deviation (divided by count)
  double min = 0.0;
  double max = 0.0;
};

/// Statistics of a non-empty list of finite values; throws std::invalid_argument otherwise.
inline ErrorStatistics error_statistics(std::vector<double> values) {
  if (values.empty()) throw std::invalid_argument("error_statistics: no values");
  ErrorStatistics s;
  s.count = values.size();
  const double n = static_cast<double>(values.size());
  double sum = 0.0, sum_squares = 0.0;
  for (const double v : values) {
    if (!std::isfinite(v)) throw std::invalid_argument("error_statistics: a value is not finite");
    sum += v;
    sum_squares += v * v;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_squares / n);
  double deviations = 0.0;
  for (const double v : values) deviations += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(deviations / n);
  std::sort(values.begin(), values.end());
  s.min = values.front();
  s.max = values.back();
  const std::size_t mid = values.size() / 2;
  s.median = values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  return s;
}

}  // namespace metrics
}  // namespace cge
