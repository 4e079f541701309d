// Uses the installed occtrack: reads a scenario, runs a short episode with the follower and one planning
// cycle by hand, and prints what it got. Exit status 0 only when both look right.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer SCENARIO\n");
    return 2;
  }
  occtrack::core::Scenario scenario = occtrack::io::read_scenario(argv[1]);
  scenario.duration = 5.0;
  auto planner = occtrack::planners::make_planner("follower");
  const occtrack::sim::EpisodeResult result = occtrack::sim::run_episode(scenario, *planner, {});
  std::printf("episode: %s, %.1f s, %d collisions, hidden %.2f s\n", result.metrics.scenario.c_str(),
              result.metrics.duration_s, result.metrics.collisions, result.metrics.occlusion_time_s);

  occtrack::core::Scan scan;
  scan.angle_increment = 2.0 * std::numbers::pi / 360.0;
  scan.ranges.assign(360, INFINITY);
  occtrack::planners::PlannerInput input;
  input.target_position = {3.0, 0.0};
  input.scan = &scan;
  const occtrack::planners::PlannerOutput out = planner->plan(input);
  std::printf("command: %.3f %.3f\n", out.command_velocity.x(), out.command_velocity.y());
  return result.metrics.duration_s > 4.9 && out.command_velocity.allFinite() && out.command_velocity.x() > 0.0 ? 0 : 1;
}
