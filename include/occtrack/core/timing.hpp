// Summaries of measured times (planning cycles, solves, training steps). One rule for every report in
// occtrack: the median of an even count is the mean of the two middle values; p99 is the nearest-rank
// percentile, the ceil(0.99 n)-th smallest value.
#pragma once

#include <vector>

namespace occtrack::core {

struct TimingSummary {
  double mean = 0, median = 0, p99 = 0, max = 0, min = 0;
  int count = 0;
};

/// The nearest-rank percentile of `sorted` (ascending, not empty): the ceil(q n)-th smallest value, the
/// smallest for q = 0. The one percentile rule of occtrack's reports (timings here, sim/path_stats.hpp).
double nearest_rank(const std::vector<double>& sorted, double q);

/// The summary of `values` (any unit; the summary keeps it). All zero for an empty list.
TimingSummary summarize_timings(std::vector<double> values);

}  // namespace occtrack::core
