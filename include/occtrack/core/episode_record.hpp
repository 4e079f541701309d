// What an episode leaves behind: its metrics (shared/spec/simulation.md, "Metrics") and a trace for
// figures; and a suite's episodes with their summary. Plain data, made by sim/episode and sim/metrics, read
// by io/results and io/svg.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "occtrack/core/scan.hpp"
#include "occtrack/core/scenario.hpp"
#include "occtrack/core/timing.hpp"

namespace occtrack::core {

struct Summary3 {
  double mean = 0, min = 0, max = 0;
};

/// Cycles by what the safety layer did (planners::SafetyAction; all zero without it).
struct ShieldCounts {
  int plan = 0, alternative = 0, stop = 0, evasive = 0, best_effort = 0, brake = 0;
  int total() const { return plan + alternative + stop + evasive + best_effort + brake; }
};

/// Per-episode metrics, with the spec's keys (io/results.hpp writes the JSON).
struct EpisodeMetrics {
  std::string scenario, planner;
  double duration_s = 0;
  double occlusion_time_s = 0;
  bool success = false;  ///< zero occlusion time
  int collisions = 0;    ///< entries of the robot disk into any obstacle
  double collision_time_s = 0;
  double min_clearance_m = 0;  ///< smallest distance between the robot disk and an obstacle (negative: overlap)
  Summary3 acceleration;       ///< realised acceleration norm, m/s^2
  TimingSummary compute_ms;    ///< per planning cycle
  double tracking_distance_mean_m = 0;
  double tracking_in_band_share = 0;
  double target_out_of_range_s = 0;  ///< target beyond the sensor's range
  int planner_failures = 0;          ///< cycles in which the planner returned no usable plan (the robot braked)
  int cycles = 0;
  // Protocol v2 (shared/spec/simulation.md): the run's latency (0 with latency none), the compute scale it
  // stands for, and how the lost sight was spread: separate spells and the longest one.
  double latency_ms = 0;
  double compute_scale = 1;
  int occlusion_stretches = 0;
  double longest_occlusion_s = 0;
  ShieldCounts shield;  ///< issue 11's safety layer; written to the JSON only when it ran
  /// Cycles in which the safety layer saw moving obstacles faster than it assumes (its moving_speed_max;
  /// planners::safety::SpeedWatch); written with `shield`.
  int beyond_envelope_cycles = 0;
};

/// A suite's episodes and their summary (sim::summarize_suite makes it, io/results.hpp writes it).
struct SuiteResult {
  std::string suite, planner;
  std::vector<EpisodeMetrics> episodes;
  /// Over the episodes: times and counts summed; success_rate the share of successful episodes;
  /// min_clearance_m and acceleration.min the minimum, maxima the maximum; acceleration.mean and the tracking
  /// distance weighted by duration; compute_ms.mean weighted by cycles, compute_ms.median the median of the
  /// episodes' medians, p99 and max the largest of the episodes'.
  EpisodeMetrics summary;
  double success_rate = 0.0;
};

/// One figure over a suite's runs at several draws of the simulated sensors' noise (sim::summarize_draws):
/// mean, sample standard deviation (n - 1; 0 for one draw), least and largest, and which draws (indices into
/// DrawsResult::draws, the first if several tie) gave the least and the largest.
struct Spread {
  double mean = 0, sd = 0, min = 0, max = 0;
  std::size_t min_at = 0, max_at = 0;
};

/// A suite run once per sensor seed (`occtrack bench suite --sensor-seeds`): each draw's result, and how the
/// suite's figures spread over the draws. One draw of the noise moves a suite's time hidden about as much as
/// a planner seed does (docs/results.md, "The sensors' noise draws").
struct DrawsResult {
  std::string suite, planner;
  std::vector<std::uint64_t> sensor_seeds;
  std::vector<SuiteResult> draws;  ///< one per seed, in the same order
  Spread occlusion_time_s;         ///< the suite's total time hidden, per draw
  Spread success_rate;
  Spread longest_occlusion_s;      ///< each draw's longest spell of lost sight
  Spread collisions;               ///< the suite's collisions, per draw
  int draws_with_collision = 0;
  double min_clearance_m = 0;      ///< the least over every draw's episodes
  int beyond_envelope_cycles = 0;  ///< summed over the draws
};

struct Snapshot {
  double time = 0;
  Vec2 robot = Vec2::Zero(), target = Vec2::Zero();
  std::vector<Vec2> plan;
  std::vector<std::vector<Vec2>> candidates;
};

/// One planning cycle as the planner saw and answered it, for replays (sim::EpisodeSettings::record_cycles).
struct CycleRecord {
  /// Candidates kept per cycle: the planner's first ones (ProjCem returns 24). Ten show the spread of the
  /// samples and keep a 150 s episode's HTML replay under ~10 MB (io/html_replay.hpp).
  static constexpr std::size_t kMaxCandidates = 10;

  double time = 0;
  Vec2 robot = Vec2::Zero();
  Scan scan;  ///< as the planner received it (world frame, from `robot`)
  std::vector<Vec2> plan;
  std::vector<std::vector<Vec2>> candidates;  ///< at most kMaxCandidates
  Vec2 command = Vec2::Zero();  ///< the velocity command sent (world frame; zero when the planner failed)
  /// What the safety layer did, as planners::to_string(SafetyAction) spells it ("plan", "evasive", ...; a
  /// string literal); empty without the layer.
  const char* safety = "";
};

/// What happened, for figures: every trace_stride-th physics step.
struct Trace {
  std::vector<double> time;
  std::vector<Vec2> robot, target;
  std::vector<char> occluded;  ///< the line of sight was blocked at that instant
  std::vector<Snapshot> snapshots;
  std::vector<CycleRecord> cycles;  ///< every planning cycle; empty unless record_cycles was set
};

}  // namespace occtrack::core
