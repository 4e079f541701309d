// One closed-loop episode (shared/spec/simulation.md): fixed physics step, a planning cycle every planning
// period, a holonomic robot that follows the commanded velocity under an acceleration bound, and the
// metrics of the spec measured with exact geometry at every physics step.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"
#include "occtrack/core/scenario.hpp"
#include "occtrack/core/tracking.hpp"
#include "occtrack/planners/planner.hpp"

namespace occtrack::sim {

using core::Vec2;

/// Protocol v2: what the planner learns of the target (shared/spec/simulation.md, "Target visibility").
enum class TargetObservation {
  always,         ///< v1 and the paper: the current state every cycle
  line_of_sight,  ///< a fresh estimate only while the line of sight is clear and in sensor range
};

struct EpisodeSettings {
  double physics_step = 0.01;     ///< seconds
  double planning_period = 0.05;  ///< seconds (20 Hz); a multiple of physics_step
  double robot_accel_max = 2.0;   ///< m/s^2: how fast the robot's velocity can follow the command
  /// When true, a cycle's command takes effect only after its measured computation time (rounded up to
  /// physics steps), for real-time studies. Off by default, so that results do not depend on the machine.
  bool delay_by_compute = false;
  std::uint64_t seed = 1;         ///< sensor noise

  // Protocol v2 (shared/spec/simulation.md). The defaults are v1: v1 results reproduce bit for bit.
  /// Latency L in ms: a cycle's command takes effect L after the scan it used and the next cycle starts at
  /// the first planning tick at or after that. nullopt: none (v1). `auto` is resolved before the run
  /// (median_cycle_ms times compute_scale) and lands here as a number.
  std::optional<double> latency_ms;
  double compute_scale = 1.0;   ///< recorded with the results; `auto` latency is scaled by it
  double tau = 0.0;             ///< s, first-order lag of the robot's velocity behind the command (0: none)
  std::optional<int> beams;     ///< override the scenario's sensor.beams
  std::optional<double> lidar_noise;   ///< m, override the scenario's sensor.noise
  std::optional<double> beam_dropout;  ///< override the scenario's sensor.dropout, in [0, 1]
  double target_position_noise = 0.0;  ///< m, Gaussian noise on the target position the planner receives
  double target_velocity_noise = 0.0;  ///< m/s, on the velocity
  TargetObservation target_observation = TargetObservation::always;

  core::TrackingBand band;        ///< for the in-band share
  int snapshots = 6;              ///< plans (with candidates) kept for figures, evenly over the episode
  int trace_stride = 5;           ///< keep every n-th physics step in the trace (figures, JSON)
  /// Keep every planning cycle's scan, plan and candidates in Trace::cycles (HTML replays). Off by default:
  /// nothing is copied and the results are the same either way.
  bool record_cycles = false;

  bool validate(std::string* error = nullptr) const;
};

struct EpisodeResult {
  core::EpisodeMetrics metrics;
  core::Trace trace;
};

/// `options` for a planner driving a robot under `episode`: the response time is the robot's lag (tau), and the
/// safety layer learns the command latency (as it acts: rounded up to whole physics steps), the planning period
/// and the acceleration bound. The one home of this mapping; the command line and the tests call it.
planners::PlannerOptions planner_options_for(const EpisodeSettings& episode, planners::PlannerOptions options = {});

/// Runs the scenario to its duration with the planner (reset first). `progress`, when given, is called with
/// the fraction done about once per simulated second. Throws std::invalid_argument for invalid settings.
EpisodeResult run_episode(const core::Scenario& scenario, planners::Planner& planner, const EpisodeSettings& settings,
                          const std::function<void(double)>& progress = {});

/// The planner's median cycle time (ms) on this machine, measured on scans replayed from the scenarios (a
/// robot on a 2 m leash behind each target, `cycles` planning cycles in all, spread over the scenarios), for
/// latency `auto`. The planner is reset first and after.
double median_cycle_ms(planners::Planner& planner, const std::vector<core::Scenario>& scenarios,
                       const EpisodeSettings& settings, int cycles = 100);

}  // namespace occtrack::sim
