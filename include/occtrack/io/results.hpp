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
/// A suite run at several sensor seeds: {suite, planner, sensor_seeds, draws: [suite_json's object with
/// "sensor_seed" added, ...], over_draws: {draws, occlusion_time_s: {mean, sd, min, max, min_seed, max_seed},
/// success_rate: {...}, longest_occlusion_s: {...}, collisions: {...}, draws_with_collision, min_clearance_m,
/// beyond_envelope_cycles}}.
std::string draws_json(const core::DrawsResult& result, int indent = 2);

/// The paper's table (occlusion time / success rate, acceleration mean/min/max, computation time) with
/// collisions added; one row per result.
std::string suite_table(const std::vector<core::SuiteResult>& results);
/// A suite over sensor draws: one row per draw (seed, time hidden / success, longest spell, collisions, least
/// clearance), then the mean, standard deviation, least and largest of each figure over the draws.
std::string draws_table(const core::DrawsResult& result);

}  // namespace occtrack::io
