// occtrack bench suite SUITE --planner NAME [--jobs J] [--json FILE] [--svg-dir DIR] [--html-dir DIR]
//                       [--sensor-seeds LIST] [episode options]
//
// Runs every scenario of a suite (a folder of YAML files, or a name under scenarios/) with a planner, J
// episodes at a time (suite_runner.hpp), and prints the paper-style table. Each episode's planner runs
// single-threaded unless --threads says otherwise, so that computation times stay comparable. `--latency auto`
// is measured once, before the episodes, and held fixed for all of them. With --sensor-seeds it runs the suite
// once per seed of the simulated sensors, one draw after another, and prints how the figures spread over those
// noise draws (sim::summarize_draws).
#include <cstdint>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/io/results.hpp"
#include "occtrack/sim/metrics.hpp"
#include "run_settings.hpp"
#include "sensor_seeds.hpp"
#include "suite_runner.hpp"

namespace occtrack::app {

namespace {

struct SuiteOptions {
  std::string suite, json_path, svg_dir, html_dir;
  std::vector<std::string> sensor_seeds;  ///< items "S" or "A-B"; empty: one run at --sensor-seed
  int jobs = 1;
  EpisodeCliOptions episode;
};

int run_draws(const SuiteOptions& o, const std::vector<std::uint64_t>& seeds, const Suite& suite,
              SuiteRunOptions run) {
  std::cout << run_settings_line(run.planner, run.planner_options, run.settings, seeds) << std::endl;
  const std::string svg_dir = run.svg_dir, html_dir = run.html_dir;
  std::vector<core::SuiteResult> draws;
  for (const std::uint64_t seed : seeds) {
    run.settings.seed = seed;
    run.progress_label = "sensor seed " + std::to_string(seed) + " ";
    // One folder of figures and replays per draw, so that the draws do not overwrite each other's.
    if (!svg_dir.empty()) run.svg_dir = svg_dir + "/sensor-seed-" + std::to_string(seed);
    if (!html_dir.empty()) run.html_dir = html_dir + "/sensor-seed-" + std::to_string(seed);
    draws.push_back(run_suite(suite, run));
    warn_seen_beyond_the_envelope(draws.back().summary, run.planner_options);
  }
  const core::DrawsResult result = sim::summarize_draws(seeds, draws);
  std::cout << io::draws_table(result);
  if (!o.json_path.empty() &&
      !write_text_file("occtrack bench suite", o.json_path,
                       results_with_settings(io::draws_json(result), "bench suite", run.planner, run.planner_options,
                                             run.settings, seeds)))
    return kExitInputError;
  return kExitOk;
}

int run(const SuiteOptions& o) {
  const std::vector<std::uint64_t> seeds = expand_sensor_seeds(o.sensor_seeds);  // a repeat is refused before loading
  const Suite suite = load_suite(o.suite);                                // refuse bad files up front
  planners::make_planner(o.episode.planner, o.episode.planner_settings());  // and an unknown planner
  SuiteRunOptions run;
  run.planner = o.episode.planner;
  run.settings = resolve_episode_settings(o.episode, suite.scenarios);  // before the episodes, not among them
  run.planner_options = o.episode.planner_settings(&run.settings);
  run.jobs = o.jobs;
  run.svg_dir = o.svg_dir;
  run.html_dir = o.html_dir;
  if (!seeds.empty()) return run_draws(o, seeds, suite, run);
  std::cout << run_settings_line(run.planner, run.planner_options, run.settings) << "\n";
  const core::SuiteResult result = run_suite(suite, run);
  std::cout << io::suite_table({result});
  warn_seen_beyond_the_envelope(result.summary, run.planner_options);
  if (!o.json_path.empty() &&
      !write_text_file("occtrack bench suite", o.json_path,
                       results_with_settings(io::suite_json(result), "bench suite", run.planner, run.planner_options,
                                             run.settings)))
    return kExitInputError;
  return kExitOk;
}

}  // namespace

void add_bench_suite_command(CLI::App& bench, int& exit_code) {
  auto [cmd, o] =
      add_command<SuiteOptions>(bench, "suite", "Run a benchmark suite with a planner and print the paper's table");
  cmd->add_option("suite", o->suite, "Suite folder, or a name under scenarios/ (e.g. static-1ms)")->required();
  add_episode_options(cmd, o->episode);
  add_sensor_seeds_option(cmd, o->sensor_seeds,
                          "Run the suite once per sensor seed (LIST: 1-10, 1,4,7 or 2-4,9) and print how its figures "
                          "spread over these noise draws (mean, sd, least, largest); --json then holds every draw")
      ->excludes(cmd->get_option("--sensor-seed"));
  add_bounded_option(cmd, "--jobs", o->jobs, "Episodes run at the same time", 1, 256);
  cmd->add_option("--json", o->json_path,
                  "Write {suite, planner, episodes, summary, settings, created_by} as JSON (with --sensor-seeds: "
                  "{suite, planner, sensor_seeds, draws, over_draws, settings, created_by})");
  cmd->add_option("--svg-dir", o->svg_dir, "Write one figure per episode into this folder");
  cmd->add_option("--html-dir", o->html_dir,
                  "Write one animated HTML replay per episode into this folder, and index.html linking them");
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
