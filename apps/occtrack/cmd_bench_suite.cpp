// occtrack bench suite SUITE --planner NAME [--jobs J] [--json FILE] [--svg-dir DIR]
//
// Runs every scenario of a suite (a folder of YAML files, or a name under scenarios/) with a planner, J
// episodes at a time, and prints the paper-style table. Each episode's planner runs single-threaded unless
// --threads says otherwise, so that computation times stay comparable.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <thread>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/io/results.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/io/svg.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/metrics.hpp"

namespace fs = std::filesystem;

namespace occtrack::app {

namespace {

struct SuiteOptions {
  std::string suite, json_path, svg_dir;
  int jobs = 1;
  EpisodeCliOptions episode;
};

fs::path resolve_suite(const std::string& suite) {
  if (fs::is_directory(suite)) return suite;
  if (fs::is_directory(fs::path("scenarios") / suite)) return fs::path("scenarios") / suite;
  throw std::runtime_error("suite \"" + suite + "\": no such folder (nor scenarios/" + suite + ")");
}

int run(const SuiteOptions& o) {
  const fs::path folder = resolve_suite(o.suite);
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().extension() == ".yaml" || entry.path().extension() == ".yml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error(folder.string() + ": no scenario files (*.yaml)");
  std::vector<core::Scenario> scenarios;
  for (const auto& f : files) scenarios.push_back(io::read_scenario(f.string()));  // refuse bad files up front
  planners::make_planner(o.episode.planner, o.episode.planner_options);             // and an unknown planner
  if (!o.svg_dir.empty()) fs::create_directories(o.svg_dir);

  const std::string suite_name = folder.filename().string();
  std::vector<core::EpisodeMetrics> metrics(scenarios.size());
  std::atomic<std::size_t> next{0};
  std::atomic<int> done{0};
  std::mutex print;
  std::string failure;
  auto worker = [&]() {
    for (std::size_t i = next++; i < scenarios.size(); i = next++) {
      try {
        auto planner = planners::make_planner(o.episode.planner, o.episode.planner_options);
        const sim::EpisodeResult r = sim::run_episode(scenarios[i], *planner, o.episode.settings());
        metrics[i] = r.metrics;
        if (!o.svg_dir.empty()) {
          std::ofstream svg(fs::path(o.svg_dir) / (scenarios[i].name + "." + planner->name() + ".svg"));
          svg << io::episode_svg(scenarios[i], r.trace, r.metrics);
        }
        const std::lock_guard<std::mutex> lock(print);
        const auto& m = r.metrics;
        std::fprintf(stderr, "[%d/%zu] %s: occlusion %.1f s, collisions %d, compute median %.1f ms\n", ++done,
                     scenarios.size(), m.scenario.c_str(), m.occlusion_time_s, m.collisions, m.compute_ms.median);
      } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> lock(print);
        failure = scenarios[i].name + ": " + e.what();
      }
    }
  };
  std::vector<std::thread> threads;
  const int jobs = std::max(1, std::min<int>(o.jobs, static_cast<int>(scenarios.size())));
  for (int j = 0; j < jobs; ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (!failure.empty()) throw std::runtime_error(failure);

  const core::SuiteResult result = sim::summarize_suite(suite_name, o.episode.planner, metrics);
  std::cout << io::suite_table({result});
  if (!o.json_path.empty() && !write_text_file("occtrack bench suite", o.json_path, io::suite_json(result) + "\n"))
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
  cmd->add_option("--json", o->json_path, "Write {suite, planner, episodes, summary} as JSON");
  cmd->add_option("--svg-dir", o->svg_dir, "Write one figure per episode into this folder");
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
