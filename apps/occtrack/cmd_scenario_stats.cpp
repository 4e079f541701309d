// occtrack scenario stats FILE|DIR [--json]
//
// The target's motion statistics of scenario files (sim/path_stats.hpp has the definitions; scenarios/README.md,
// "Tele-operated target motion", compares them with the recorded tele-operation): duration, path length, speed
// mean/p90/max, acceleration p50/p90/p99, heading-rate p50/p90/p99. A folder: every *.yaml in it, sorted by
// name, one line each, then a line for all of them together (their samples joined).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "commands.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/sim/path_stats.hpp"
#include "suite_runner.hpp"

namespace occtrack::app {

namespace {

struct StatsOptions {
  std::string path;
  bool json = false;
};

nlohmann::json stats_json(const std::string& name, const sim::PathStats& s) {
  return {{"file", name},
          {"duration_s", s.duration},
          {"path_m", s.length},
          {"speed_mps", {{"mean", s.speed_mean}, {"p90", s.speed_p90}, {"max", s.speed_max}}},
          {"acceleration_mps2", {{"p50", s.acceleration_p50}, {"p90", s.acceleration_p90}, {"p99", s.acceleration_p99}}},
          {"heading_rate_radps",
           {{"p50", s.heading_rate_p50}, {"p90", s.heading_rate_p90}, {"p99", s.heading_rate_p99}}},
          {"speed_samples", s.speed_samples},
          {"heading_samples", s.heading_samples}};
}

void print_row(const std::string& name, const sim::PathStats& s) {
  std::printf("%-32s %8.1f %8.1f   %5.2f %5.2f %5.2f   %5.2f %5.2f %5.2f   %5.2f %5.2f %5.2f\n", name.c_str(),
              s.duration, s.length, s.speed_mean, s.speed_p90, s.speed_max, s.acceleration_p50, s.acceleration_p90,
              s.acceleration_p99, s.heading_rate_p50, s.heading_rate_p90, s.heading_rate_p99);
}

int run_stats(const StatsOptions& o) {
  const std::vector<std::filesystem::path> files = app::file_or_scenario_files(o.path);
  sim::PathSamples all;
  nlohmann::json rows = nlohmann::json::array();
  if (!o.json)
    std::printf("%-32s %8s %8s   %-17s   %-17s   %-17s\n%-32s %8s %8s   %-17s   %-17s   %-17s\n", "file", "duration",
                "path", "speed m/s", "accel m/s^2", "heading rate rad/s", "", "s", "m", " mean   p90   max",
                "  p50   p90   p99", "  p50   p90   p99");
  for (const std::filesystem::path& file : files) {
    const core::Scenario scenario = io::read_scenario(file.string());  // names the file when refused
    const sim::PathSamples samples = sim::sample_path(scenario.target);
    all.append(samples);
    const sim::PathStats stats = sim::summarize_path(samples);
    if (o.json) rows.push_back(stats_json(file.filename().string(), stats));
    else print_row(file.filename().string(), stats);
  }
  if (o.json) {
    nlohmann::json out = {{"sample_period_s", sim::kPathSamplePeriod},
                          {"moving_speed_mps", sim::kMovingSpeed},
                          {"files", rows}};
    if (files.size() > 1) out["all"] = stats_json("all", sim::summarize_path(all));
    std::cout << out.dump(2) << "\n";
  } else if (files.size() > 1) {
    print_row("all (" + std::to_string(files.size()) + " files)", sim::summarize_path(all));
  }
  return kExitOk;
}

}  // namespace

void add_scenario_stats_command(CLI::App& scenario, int& exit_code) {
  auto [cmd, o] = add_command<StatsOptions>(
      scenario, "stats",
      "The target's motion statistics of a scenario file, or of every *.yaml in a folder and all together: path "
      "sampled every 0.1 s; speed mean/p90/max, acceleration p50/p90/p99, heading-rate p50/p90/p99 (nearest-rank "
      "percentiles; heading rates where the target moves faster than 0.05 m/s). Definitions: scenarios/README.md");
  cmd->add_option("path", o->path, "Scenario file, or a folder of them")->required();
  cmd->add_flag("--json", o->json, "Print JSON instead of a table");
  set_command_body(cmd, exit_code, [o] { return run_stats(*o); });
}

}  // namespace occtrack::app
