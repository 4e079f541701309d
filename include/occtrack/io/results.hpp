// Machine-readable results (shared/spec/simulation.md, "Metrics"): one JSON object per episode with the
// spec's keys, a suite object {suite, planner, episodes, summary}, and the paper-style table.
#pragma once

#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"

namespace occtrack::io {

struct SuiteResult {
  std::string suite, planner;
  std::vector<core::EpisodeMetrics> episodes;
  /// Over the episodes: times and counts summed; success_rate the share of successful episodes;
  /// min_clearance_m and acceleration.min the minimum, maxima the maximum; acceleration.mean and the tracking
  /// distance weighted by duration; compute_ms.mean weighted by cycles, compute_ms.median the median of the
  /// episodes' medians, p99 and max the largest of the episodes'.
  core::EpisodeMetrics summary;
  double success_rate = 0.0;
};

SuiteResult summarize_suite(const std::string& suite, const std::string& planner,
                            const std::vector<core::EpisodeMetrics>& episodes);

std::string episode_json(const core::EpisodeMetrics& metrics, int indent = 2);
std::string suite_json(const SuiteResult& result, int indent = 2);

/// The paper's table (occlusion time / success rate, acceleration mean/min/max, computation time) with
/// collisions added; one row per result.
std::string suite_table(const std::vector<SuiteResult>& results);

}  // namespace occtrack::io
