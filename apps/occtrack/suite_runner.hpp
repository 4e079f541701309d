// Running a suite's episodes, J at a time: the one home of `occtrack bench suite` and `occtrack bench paper`.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"
#include "occtrack/core/scenario.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"

namespace occtrack::app {

/// The scenario files (*.yaml, *.yml) directly in `folder`, sorted by name: the one rule for which files a
/// folder of scenarios holds (`bench suite`, `bench paper`, `scenario stats`). Throws when there are none.
std::vector<std::filesystem::path> scenario_files(const std::filesystem::path& folder);
/// `path` itself when it is a file, else scenario_files(path) (`scenario stats`, `scenario predict`).
/// Throws std::invalid_argument when it does not exist.
std::vector<std::filesystem::path> file_or_scenario_files(const std::string& path);

/// A suite's scenarios, sorted by file name, and the suite's name (its folder's).
struct Suite {
  std::string name;
  std::vector<core::Scenario> scenarios;
};

/// The suite `suite` names: a folder, or a name under scenarios/. Reads every *.yaml / *.yml file up front, so
/// that a bad file is refused before anything runs. `episodes` > 0 keeps only the first that many scenarios.
/// Throws for a missing folder, a folder without scenario files, or a bad file.
Suite load_suite(const std::string& suite, int episodes = 0);

struct SuiteRunOptions {
  std::string planner;                      ///< a name make_planner knows
  planners::PlannerOptions planner_options;
  /// The episodes' settings; a latency of `auto` must already be resolved to a number (the same for every
  /// episode, so that the run is deterministic once it is known).
  sim::EpisodeSettings settings;
  int jobs = 1;                             ///< episodes run at the same time
  std::string svg_dir;                      ///< non-empty: one figure per episode into this folder
  /// non-empty: one HTML replay per episode into this folder, and index.html linking them (the episodes
  /// then record their planning cycles, sim::EpisodeSettings::record_cycles)
  std::string html_dir;
  std::string progress_label;               ///< put in front of each episode's progress line
};

/// Runs every scenario of `suite` with a fresh planner each, `o.jobs` at a time, printing one progress line per
/// finished episode on standard error, and summarises them (sim::summarize_suite) under `o.planner`. Throws
/// the first episode's error ("<scenario>: <what>") once the others have finished.
core::SuiteResult run_suite(const Suite& suite, const SuiteRunOptions& o);

}  // namespace occtrack::app
