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
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/io/results.hpp"
#include "occtrack/sim/metrics.hpp"
#include "run_settings.hpp"
#include "suite_runner.hpp"

namespace occtrack::app {

namespace {

struct SuiteOptions {
  std::string suite, json_path, svg_dir, html_dir;
  std::vector<std::string> sensor_seeds;  ///< items "S" or "A-B"; empty: one run at --sensor-seed
  int jobs = 1;
  EpisodeCliOptions episode;
};

constexpr std::size_t kMaxDraws = 1000;

std::uint64_t seed_number(const std::string& text) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 19)
    throw std::invalid_argument("\"" + text + "\" is not a seed (an integer >= 0 of at most 19 digits)");
  return std::stoull(text);
}

/// One item of --sensor-seeds, "S" or "A-B", as its first and last seed. Throws std::invalid_argument with
/// the rule broken.
std::pair<std::uint64_t, std::uint64_t> seed_range(const std::string& item) {
  const std::size_t dash = item.find('-');
  const std::uint64_t first = seed_number(item.substr(0, dash));
  const std::uint64_t last = dash == std::string::npos ? first : seed_number(item.substr(dash + 1));
  if (last < first) throw std::invalid_argument("the range " + item + " runs backwards");
  return {first, last};
}

std::string seed_item_rule(const std::string& item) {
  try {
    seed_range(item);
    return "";
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
}

/// The seeds the items name, in the order written. Throws std::invalid_argument on a repeated seed or more
/// than kMaxDraws of them.
std::vector<std::uint64_t> expand_seeds(const std::vector<std::string>& items) {
  std::vector<std::uint64_t> seeds;
  std::set<std::uint64_t> seen;
  for (const auto& item : items) {
    const auto [first, last] = seed_range(item);
    for (std::uint64_t s = first;; ++s) {
      if (!seen.insert(s).second) throw std::invalid_argument("--sensor-seeds: seed " + std::to_string(s) +
                                                              " is given twice");
      seeds.push_back(s);
      if (seeds.size() > kMaxDraws)
        throw std::invalid_argument("--sensor-seeds: more than " + std::to_string(kMaxDraws) + " seeds");
      if (s == last) break;
    }
  }
  return seeds;
}

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
  const std::vector<std::uint64_t> seeds = expand_seeds(o.sensor_seeds);  // a repeat is refused before loading
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
  cmd->add_option("--sensor-seeds", o->sensor_seeds,
                  "Run the suite once per sensor seed (LIST: 1-10, 1,4,7 or 2-4,9) and print how its figures spread "
                  "over these noise draws (mean, sd, least, largest); --json then holds every draw")
      ->delimiter(',')
      ->check(episode_cli::validator(seed_item_rule, "LIST"))
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
