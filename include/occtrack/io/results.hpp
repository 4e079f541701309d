// Machine-readable results (shared/spec/simulation.md, "Metrics"): one JSON object per episode with the
// spec's keys, a suite object {suite, planner, episodes, summary}, and the paper-style table. The metrics
// themselves are measured and summarised by sim/metrics.hpp.
#pragma once

#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"

namespace occtrack::io {

std::string episode_json(const core::EpisodeMetrics& metrics, int indent = 2);
std::string suite_json(const core::SuiteResult& result, int indent = 2);

/// The paper's table (occlusion time / success rate, acceleration mean/min/max, computation time) with
/// collisions added; one row per result.
std::string suite_table(const std::vector<core::SuiteResult>& results);

}  // namespace occtrack::io
