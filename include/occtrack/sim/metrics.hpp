// The metrics of shared/spec/simulation.md ("Metrics"): one episode's, accumulated state by state and cycle
// by cycle while it runs (sim/episode.cpp), and a suite's summary over its episodes. io/results.hpp writes
// both as JSON and as the paper's table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"
#include "occtrack/core/tracking.hpp"
#include "occtrack/planners/planner.hpp"

namespace occtrack::sim {

/// One episode's metrics, fed in the order the episode runs. Times add one physics step for every state
/// but the last (a state stands for the step that follows it); the last state counts for the minimum
/// clearance and for a collision that begins there, as every state does.
class EpisodeMetricsAccumulator {
 public:
  /// `sensor_range` (m): beyond it the target is out of range; `band`: the tracking band of the in-band
  /// share; `expected_cycles`: room reserved for the cycles' computation times.
  EpisodeMetricsAccumulator(const std::string& scenario, const std::string& planner, double physics_step,
                            double sensor_range, const core::TrackingBand& band, int expected_cycles = 0);

  /// The robot's state at one physics step: `clearance` between the robot's disk and the nearest obstacle
  /// (negative: overlap), whether the line of sight to the target is blocked, the distance to the target.
  /// `last`: the episode's final state, which spans no step.
  void add_state(double clearance, bool occluded, double distance, bool last);
  /// One planning cycle: its computation time, and whether the planner gave no usable command.
  void add_cycle(double compute_ms, bool failed);
  /// What the safety layer did with the cycle's command (nothing counted for SafetyAction::off), and whether
  /// it saw moving obstacles faster than it assumes (PlannerOutput::beyond_envelope).
  void add_safety(planners::SafetyAction action, bool beyond_envelope = false);
  /// The norm of the robot's realised acceleration over one physics step (m/s^2).
  void add_acceleration(double norm);

  /// The metrics so far: sums become means over the steps, the cycle times a summary.
  core::EpisodeMetrics finish() const;

 private:
  core::EpisodeMetrics m_;
  double physics_step_, sensor_range_;
  core::TrackingBand band_;
  int steps_ = 0;  // states that span a step
  bool in_collision_ = false;
  bool in_occlusion_ = false;   // the previous step's line of sight was blocked
  double occlusion_spell_ = 0;  // s, length of the current spell of lost sight
  double acceleration_sum_ = 0.0, distance_sum_ = 0.0;
  int in_band_ = 0;
  std::vector<double> compute_ms_;
};

/// A suite's summary over its episodes (see core::SuiteResult for how each metric is combined; Protocol v2's:
/// occlusion stretches summed, the longest the longest of any episode, latency and compute scale those of the
/// first episode, which all of a suite's episodes share).
core::SuiteResult summarize_suite(const std::string& suite, const std::string& planner,
                                  const std::vector<core::EpisodeMetrics>& episodes);

/// How a suite's figures spread over runs at several sensor seeds: `draws[i]` is the suite run at
/// `sensor_seeds[i]` (all with the same suite and planner). Throws std::invalid_argument when there are no
/// draws, the two lists differ in length, a seed repeats, or the draws are of different suites or planners.
core::DrawsResult summarize_draws(const std::vector<std::uint64_t>& sensor_seeds,
                                  const std::vector<core::SuiteResult>& draws);

}  // namespace occtrack::sim
