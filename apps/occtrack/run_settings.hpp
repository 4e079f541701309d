// The settings a run was made with, as its result files record them. A results file should say everything
// that changes its numbers (the planner and its options, the safety layer and the predictor, Protocol v2's
// latency, lag, sensing noise and target observation), so that a JSON file read on its own can be compared
// with another and rerun. The one home of this record: `bench suite --json` and `run --json` write it.
#pragma once

#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"

namespace occtrack::app {

/// {planner: {...}, episode: {...}}: every PlannerOptions field and every EpisodeSettings field that changes
/// results, resolved (`--latency auto` as the number it measured; a sensor setting the scenario keeps is
/// null). `sensor_seeds`, for a run over several sensor draws (`bench suite --sensor-seeds`): recorded as
/// episode.sensor_seeds, with episode.sensor_seed null, instead of episode.seed.
nlohmann::json run_settings_json(const std::string& planner, const planners::PlannerOptions& options,
                                 const sim::EpisodeSettings& episode,
                                 const std::vector<std::uint64_t>& sensor_seeds = {});

/// A results file: `results_json` (io::suite_json or io::episode_json) with "created_by" for `command` and the
/// "settings" above added, as text (io::draws_json with the draws' `sensor_seeds`).
std::string results_with_settings(const std::string& results_json, const std::string& command,
                                  const std::string& planner, const planners::PlannerOptions& options,
                                  const sim::EpisodeSettings& episode,
                                  const std::vector<std::uint64_t>& sensor_seeds = {});

/// One line for a terminal, the same facts in words: "settings: planner cvae (seed 1), shield on, ...".
std::string run_settings_line(const std::string& planner, const planners::PlannerOptions& options,
                              const sim::EpisodeSettings& episode,
                              const std::vector<std::uint64_t>& sensor_seeds = {});

}  // namespace occtrack::app
