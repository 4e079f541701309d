// A scenario from a recorded target path: a world's obstacles and sensor (a paper's world or any scenario
// file's), the recording as the target's timed path, and the robot's start placed by the generator's rule.
// `occtrack scenario import` is its front end; io/target_path.hpp reads the recording.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "occtrack/core/scenario.hpp"

namespace occtrack::sim {

struct RecordedPathSettings {
  /// s, the stretch of the recording to use, in its own clock (after the time scale): samples with from <= t
  /// <= to. The stretch's first sample becomes t = 0, which is also t = 0 of the world's moving obstacles.
  double from = -std::numeric_limits<double>::infinity();
  double to = std::numeric_limits<double>::infinity();
  /// s between waypoints: the path is resampled by linear interpolation (the generator's tele-operated paths
  /// use 0.1 s). 0 keeps every sample (a 100 Hz recording's position noise then reaches the target's
  /// observed velocity undamped).
  double period = 0.1;
  /// The recording's frame in the world's: a sample at p is placed at R(rotation) p + offset (rotation in
  /// rad, counter-clockwise; offset in m). For a recording made in another frame, e.g. a robot's odometry
  /// frame whose origin and heading in the world are known. Applied before anything else.
  double rotation = 0.0;
  core::Vec2 offset = core::Vec2::Zero();
  /// Where the robot starts (at rest). Unset: robot_distance behind the target's first position, opposite
  /// the way the target first moves, turned by up to 0.6 rad where that spot is taken, at least
  /// robot_clearance from every obstacle and in sight of the target (the generator's rule); where none of
  /// those fits, the first that does at the same distance turning further, 0.1 rad at a time, up to ahead.
  std::optional<core::Vec2> robot_start;
  double robot_distance = 2.0;   ///< m
  double robot_clearance = 0.5;  ///< m
  int decimals = 4;              ///< positions are rounded to this many decimal places (0: not rounded)

  bool validate(std::string* error = nullptr) const;
};

/// What the made scenario holds that a user should know before running it.
struct RecordedPathReport {
  int samples_used = 0;             ///< recording samples within the stretch
  double top_speed = 0.0;           ///< m/s, between consecutive waypoints
  /// s of the path (checked every 0.05 s, or duration / 1e6 when longer) during which the target's disk
  /// overlaps an obstacle (the recording does not belong to this world, or its frame differs), and when that
  /// first happens (NaN: never).
  double overlap_time = 0.0;
  double first_overlap = std::numeric_limits<double>::quiet_NaN();
  bool robot_sees_target = true;    ///< at t = 0 (a given robot_start need not)
  double robot_clearance = 0.0;     ///< m, the robot's disk from the nearest obstacle at t = 0
};

/// The scenario: `world`'s obstacles, sensor and radii, `samples` (times strictly increasing, any origin)
/// within the settings' stretch as the target's path from t = 0, the duration its last waypoint's time, the
/// robot as the settings say, named `name`. Throws std::invalid_argument for invalid settings or samples (not
/// finite, times not strictly increasing, a coordinate beyond 1e6 m once placed by the frame), and
/// std::runtime_error when the stretch holds less than two waypoints or would make more than a million, when
/// no robot start fits, or when a given one overlaps an obstacle.
core::Scenario scenario_from_recorded_path(const core::Scenario& world,
                                           const std::vector<core::TargetWaypoint>& samples,
                                           const RecordedPathSettings& settings, const std::string& name,
                                           RecordedPathReport* report = nullptr);

}  // namespace occtrack::sim
