// occtrack run SCENARIO --planner NAME [--svg FILE] [--html FILE] [--json FILE]
//
// Runs one closed-loop episode with a progress display and prints its metrics.
#include <cstdio>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/io/html_replay.hpp"
#include "occtrack/io/results.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/io/svg.hpp"
#include "occtrack/sim/episode.hpp"
#include "run_settings.hpp"

namespace occtrack::app {

namespace {

struct RunOptions {
  std::string scenario_path, svg_path, html_path, json_path;
  EpisodeCliOptions episode;
};

constexpr const char* kWho = "occtrack run";

int run(const RunOptions& o) {
  const core::Scenario scenario = io::read_scenario(o.scenario_path);
  // --latency auto is measured here, once, before the episode (Protocol v2); a bad planner name fails there,
  // before anything is measured, or just below.
  sim::EpisodeSettings settings = resolve_episode_settings(o.episode, {scenario});
  settings.record_cycles = !o.html_path.empty();  // the replay shows every cycle's scan and plans
  const planners::PlannerOptions options = o.episode.planner_settings(&settings);
  auto planner = planners::make_planner(o.episode.planner, options);
  std::printf("%s\n", run_settings_line(o.episode.planner, options, settings).c_str());
  Progress progress(scenario.name + " (" + planner->name() + ")");
  const sim::EpisodeResult result =
      sim::run_episode(scenario, *planner, settings, [&](double f) { progress.update(f); });
  const auto& m = result.metrics;
  std::printf("%s with %s: %.1f s simulated\n", m.scenario.c_str(), m.planner.c_str(), m.duration_s);
  std::printf("  occlusion time   %.2f s (%s)\n", m.occlusion_time_s, m.success ? "success" : "occluded");
  std::printf("  collisions       %d (%.2f s in collision, min clearance %.2f m)\n", m.collisions,
              m.collision_time_s, m.min_clearance_m);
  std::printf("  acceleration     mean %.2f, min %.2f, max %.2f m/s^2\n", m.acceleration.mean, m.acceleration.min,
              m.acceleration.max);
  std::printf("  compute          median %.2f, p99 %.2f, max %.2f ms per cycle (%d cycles, %d failed)\n",
              m.compute_ms.median, m.compute_ms.p99, m.compute_ms.max, m.cycles, m.planner_failures);
  if (m.latency_ms > 0.0 || m.occlusion_stretches > 0)
    std::printf("  latency          %.1f ms (compute scale %g); sight lost %d times, the longest for %.2f s\n",
                m.latency_ms, m.compute_scale, m.occlusion_stretches, m.longest_occlusion_s);
  if (m.shield.total() > 0)
    std::printf("  safety layer     cycles: %d plan, %d alternative (lower-ranked, slowed or slid), %d stop, "
                "%d evasive, %d best effort, %d full brake\n",
                m.shield.plan, m.shield.alternative, m.shield.stop, m.shield.evasive, m.shield.best_effort,
                m.shield.brake);
  std::printf("  tracking         mean distance %.2f m, %.0f%% of the time in [%.1f, %.1f] m; target out of range "
              "%.1f s\n",
              m.tracking_distance_mean_m, 100.0 * m.tracking_in_band_share, settings.band.min, settings.band.max,
              m.target_out_of_range_s);
  warn_seen_beyond_the_envelope(m, options);
  bool ok = true;
  if (!o.json_path.empty())
    ok = write_text_file(kWho, o.json_path,
                         results_with_settings(io::episode_json(m), "run", o.episode.planner, options, settings)) &&
         ok;
  if (!o.svg_path.empty()) {
    ok = write_text_file(kWho, o.svg_path, io::episode_svg(scenario, result.trace, m)) && ok;
    if (ok) std::printf("  figure           %s\n", o.svg_path.c_str());
  }
  if (!o.html_path.empty()) {
    ok = write_text_file(kWho, o.html_path, io::episode_html(scenario, result.trace, m)) && ok;
    if (ok) std::printf("  replay           %s\n", o.html_path.c_str());
  }
  return ok ? kExitOk : kExitInputError;
}

}  // namespace

void add_run_command(CLI::App& app, int& exit_code) {
  auto [cmd, o] = add_command<RunOptions>(app, "run", "Run one closed-loop tracking episode and print its metrics");
  cmd->add_option("scenario", o->scenario_path, "Scenario file (occtrack.scenario.v1 YAML)")->required();
  add_episode_options(cmd, o->episode);
  cmd->add_option("--svg", o->svg_path, "Write a top-down figure of the episode");
  cmd->add_option("--html", o->html_path,
                  "Write an animated replay of the episode: one self-contained HTML page (scan, plans, metrics)");
  cmd->add_option("--json", o->json_path, "Write the episode's metrics, with the settings of the run, as JSON");
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
