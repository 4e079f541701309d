// One closed-loop episode (shared/spec/simulation.md): fixed physics step, a planning cycle every planning
// period, a holonomic robot that follows the commanded velocity under an acceleration bound, and the
// metrics of the spec measured with exact geometry at every physics step.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"
#include "occtrack/core/scenario.hpp"
#include "occtrack/core/tracking.hpp"
#include "occtrack/planners/planner.hpp"

namespace occtrack::sim {

using core::Vec2;

struct EpisodeSettings {
  double physics_step = 0.01;     ///< seconds
  double planning_period = 0.05;  ///< seconds (20 Hz); a multiple of physics_step
  double robot_accel_max = 2.0;   ///< m/s^2: how fast the robot's velocity can follow the command
  /// When true, a cycle's command takes effect only after its measured computation time (rounded up to
  /// physics steps), for real-time studies. Off by default, so that results do not depend on the machine.
  bool delay_by_compute = false;
  std::uint64_t seed = 1;         ///< sensor noise
  core::TrackingBand band;        ///< for the in-band share
  int snapshots = 6;              ///< plans (with candidates) kept for figures, evenly over the episode
  int trace_stride = 5;           ///< keep every n-th physics step in the trace (figures, JSON)

  bool validate(std::string* error = nullptr) const;
};

struct EpisodeResult {
  core::EpisodeMetrics metrics;
  core::Trace trace;
};

/// Runs the scenario to its duration with the planner (reset first). `progress`, when given, is called with
/// the fraction done about once per simulated second. Throws std::invalid_argument for invalid settings.
EpisodeResult run_episode(const core::Scenario& scenario, planners::Planner& planner, const EpisodeSettings& settings,
                          const std::function<void(double)>& progress = {});

}  // namespace occtrack::sim
