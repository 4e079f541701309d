#include "occtrack/core/timing.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>

namespace occtrack::core {

double nearest_rank(const std::vector<double>& sorted, double q) {
  const std::size_t n = sorted.size();
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
  return sorted[std::min(n, std::max<std::size_t>(rank, 1)) - 1];
}

TimingSummary summarize_timings(std::vector<double> values) {
  TimingSummary t;
  if (values.empty()) return t;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  t.count = static_cast<int>(n);
  t.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  t.p99 = nearest_rank(values, 0.99);
  t.min = values.front();
  t.max = values.back();
  t.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(n);
  return t;
}

}  // namespace occtrack::core
