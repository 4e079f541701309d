// Motion statistics of a target's path (`occtrack scenario stats`, scenarios/README.md "Tele-operated target
// motion"), in the form of the recorded tele-operation table of shared/reference/paper_setup.md.
//
// Definitions. The path (linear between waypoints, whatever their spacing: generated 0.1 s, recorded 44 Hz)
// is sampled every h = 0.1 s from its first waypoint's time to its last: p_0, p_1, ..., p_N.
//   - duration: last waypoint's time minus the first's; path length: sum of |p_k+1 - p_k|.
//   - velocity v_k = (p_k+1 - p_k) / h and speed |v_k|, k = 0..N-1 (all samples, standing still included).
//   - acceleration |v_k+1 - v_k| / h, k = 0..N-2 (all samples).
//   - heading rate |wrap(angle(v_k+1) - angle(v_k))| / h, with the wrapped angle in [-pi, pi), over the pairs
//     where the target moves: both speeds above kMovingSpeed = 0.05 m/s (the direction of a standing target
//     is noise).
//   - percentiles are nearest rank (core::nearest_rank: the ceil(q n)-th smallest value), p50 included.
// Several paths together: their sample lists are joined (pairs never straddle two paths).
#pragma once

#include <vector>

#include "occtrack/core/scenario.hpp"

namespace occtrack::sim {

inline constexpr double kPathSamplePeriod = 0.1;  ///< s, h above
inline constexpr double kMovingSpeed = 0.05;      ///< m/s, heading rates only where both speeds exceed this

/// The raw samples of one or more paths (units: s, m, m/s, m/s^2, rad/s).
struct PathSamples {
  double duration = 0.0;
  double length = 0.0;
  std::vector<double> speed, acceleration, heading_rate;

  /// Adds another path's samples.
  void append(const PathSamples& other);
};

/// The samples of `path` (a scenario's target waypoints, times strictly increasing). Fewer than two
/// waypoints: no samples.
PathSamples sample_path(const std::vector<core::TargetWaypoint>& path);

struct PathStats {
  double duration = 0.0, length = 0.0;
  double speed_mean = 0.0, speed_p90 = 0.0, speed_max = 0.0;
  double acceleration_p50 = 0.0, acceleration_p90 = 0.0, acceleration_p99 = 0.0;
  double heading_rate_p50 = 0.0, heading_rate_p90 = 0.0, heading_rate_p99 = 0.0;
  int speed_samples = 0, heading_samples = 0;
};

/// The statistics of the samples (zero where a list is empty).
PathStats summarize_path(const PathSamples& samples);
inline PathStats path_stats(const core::Scenario& scenario) { return summarize_path(sample_path(scenario.target)); }

}  // namespace occtrack::sim
