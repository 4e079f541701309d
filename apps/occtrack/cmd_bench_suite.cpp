// occtrack bench suite SUITE --planner NAME [--jobs J] [--json FILE] [--svg-dir DIR] [--html-dir DIR]
//                       [episode options]
//
// Runs every scenario of a suite (a folder of YAML files, or a name under scenarios/) with a planner, J
// episodes at a time (suite_runner.hpp), and prints the paper-style table. Each episode's planner runs
// single-threaded unless --threads says otherwise, so that computation times stay comparable. `--latency auto`
// is measured once, before the episodes, and held fixed for all of them.
#include <iostream>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/io/results.hpp"
#include "run_settings.hpp"
#include "suite_runner.hpp"

namespace occtrack::app {

namespace {

struct SuiteOptions {
  std::string suite, json_path, svg_dir, html_dir;
  int jobs = 1;
  EpisodeCliOptions episode;
};

int run(const SuiteOptions& o) {
  const Suite suite = load_suite(o.suite);                                // refuse bad files up front
  planners::make_planner(o.episode.planner, o.episode.planner_settings());  // and an unknown planner
  SuiteRunOptions run;
  run.planner = o.episode.planner;
  run.settings = resolve_episode_settings(o.episode, suite.scenarios);  // before the episodes, not among them
  run.planner_options = o.episode.planner_settings(&run.settings);
  run.jobs = o.jobs;
  run.svg_dir = o.svg_dir;
  run.html_dir = o.html_dir;
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
  add_bounded_option(cmd, "--jobs", o->jobs, "Episodes run at the same time", 1, 256);
  cmd->add_option("--json", o->json_path, "Write {suite, planner, episodes, summary, settings, created_by} as JSON");
  cmd->add_option("--svg-dir", o->svg_dir, "Write one figure per episode into this folder");
  cmd->add_option("--html-dir", o->html_dir,
                  "Write one animated HTML replay per episode into this folder, and index.html linking them");
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
