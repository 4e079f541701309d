// A middleware-free tracking API (issue 13): one call per planning cycle with what a robot's drivers deliver
// (odometry, a target estimate, a LiDAR scan, each with its stamp), one velocity command back. It checks the
// inputs before any planner sees them and stops the robot, saying why, when they cannot be trusted. The ROS 1
// node (ros/, docs/ros.md) is a thin adapter over it; a ROS 2 node or any other middleware would be another.
//
//   planners::TrackerSettings settings;         // planner "cvae", safety layer on
//   planners::Tracker tracker(settings);        // throws std::invalid_argument naming the setting
//   const auto& out = tracker.step(now, robot, target, &scan);
//   send(out.command);                          // world frame; zero when out.stopped (out.reason says why)
//
// Rules (each a stop: zero command, stopped = true, a reason; step() never throws, never returns NaN):
// - robot: a non-finite position, velocity or stamp, or odometry older than robot_timeout;
// - target: a non-finite position, velocity or stamp, an estimate older than target_timeout;
// - scan: missing, empty, a non-finite or zero angle_increment, a field of view over a full turn, a bad
//   range_max or stamp, older than scan_timeout, fewer than min_valid_share usable beams, or a run of unusable
//   beams spanning more than max_invalid_gap;
// - any stamp ahead of `now` by more than future_tolerance (clocks out of step);
// - the planner braked (PlannerOutput::ok false; its message is the reason).
//
// Unusable beams (NaN, -infinity, zero or negative ranges) in a scan that passes these checks are never read
// as free space: each run of them takes the range of the nearer of the two usable beams around it, the
// safety layer's own rule that the space between two beams is free only to the smaller of their ranges
// (docs/safety.md, "Known free space"). So a dropped beam in a wall still shows the wall. Where both
// neighbours show no return within range, the run shows none either: an obstacle could hide there only if it
// fits within max_invalid_gap, the same blind spot as between any two adjacent beams at coarser resolution.
// (Perception alone would read NaN as "no return", and the safety layer as "nothing known free", which stops
// the robot for a single dropped beam.)
//
// Times are seconds on any clock (ROS time, steady clock), the same for every stamp and `now`; internally they
// are taken relative to the first step, so that large epochs lose no precision. A clock that jumps backwards
// resets the planner, as at an episode start.
#pragma once

#include <memory>
#include <string>

#include "occtrack/core/scan.hpp"
#include "occtrack/planners/planner.hpp"

namespace occtrack::planners {

struct TrackerSettings {
  std::string planner = "cvae";  ///< a name of planner_names()
  /// The planner's options. The safety layer (options.shield) is ON here, unlike PlannerOptions' default
  /// (which keeps the benchmarks' planners bare): a robot should only get certified commands.
  /// options.planning_period should be the period at which step() is called.
  PlannerOptions options = [] {
    PlannerOptions o;
    o.shield = true;
    return o;
  }();
  double target_timeout = 0.5;    ///< s: an older target estimate stops the robot
  double scan_timeout = 0.5;      ///< s: an older scan stops the robot
  double robot_timeout = 0.5;     ///< s: older odometry stops the robot
  double future_tolerance = 0.1;  ///< s: how far a stamp may lie ahead of `now` (clock skew between machines)
  double min_valid_share = 0.5;   ///< share of a scan's beams that must be usable (0, 1]
  double max_invalid_gap = 0.1;   ///< rad: widest span between the usable beams around a run of unusable ones

  /// True when every field is usable; otherwise false with *error naming the field and the rule
  /// ("target_timeout must be a positive number, got 0").
  bool validate(std::string* error = nullptr) const;
};

/// The robot's state from odometry, world frame.
struct RobotState {
  Vec2 position = Vec2::Zero();
  Vec2 velocity = Vec2::Zero();
  double stamp = 0.0;  ///< s, when it was measured
};

/// The target estimate from a tracker or detector, world frame.
struct TargetEstimate {
  Vec2 position = Vec2::Zero();
  Vec2 velocity = Vec2::Zero();
  double stamp = 0.0;  ///< s, when it was measured; the planner extrapolates it to `now`
};

struct TrackerOutput {
  Vec2 command = Vec2::Zero();  ///< world-frame velocity; always finite, zero when stopped
  bool stopped = false;         ///< true: the command is zero because of `reason`
  std::string reason;           ///< empty while tracking
  PlannerOutput planner;        ///< the plan and candidates (world frame); empty when the inputs were refused
};

class Tracker {
 public:
  /// Throws std::invalid_argument "tracker: <validate's message>" for unusable settings, and
  /// "tracker: planner: <why>" when the planner cannot be built (unknown name, unreadable model file).
  explicit Tracker(const TrackerSettings& settings);
  ~Tracker();
  Tracker(Tracker&&) noexcept;
  Tracker& operator=(Tracker&&) noexcept;

  const TrackerSettings& settings() const;
  /// Forgets the planner's state (warm starts, obstacle tracks), as at an episode start.
  void reset();

  /// One planning cycle at time `now` (see the header comment for the rules). `scan` may be null (missing);
  /// its angles are in the world frame's orientation (core::Scan). The result is valid until the next call;
  /// its storage is reused from call to call.
  const TrackerOutput& step(double now, const RobotState& robot, const TargetEstimate& target,
                            const core::Scan* scan) noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::planners
