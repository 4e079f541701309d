// The boundary between the ROS 1 code and occtrack. ROS 1's message headers need C++17 or older (their
// std::allocator<void>::rebind was removed in C++20) and occtrack's headers need C++20, so no translation unit
// can include both: the nodes (C++17) see occtrack only through this header, which includes neither, and
// bridge.cpp (C++20) implements it over planners::Tracker and sim::World.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "occtrack/core/scan.hpp"

namespace occtrack::ros_adapter {

using Vec2 = Eigen::Vector2d;  // occtrack's core::Vec2

/// The planners::TrackerSettings (and PlannerOptions) fields the node takes as parameters.
struct TrackerConfig {
  std::string planner, model;
  int batch = 0;
  bool shield = false, predictor = false;
  double passive_turn = 0.0, standoff = 0.0;  // the safety layer's assumptions about moving obstacles
  double moving_speed_max = 0.0;              // m/s, the fastest the safety layer assumes they go
  double tracking_weight = 0.0;         // the ranking's (PlannerOptions: 0 is the planner's default)
  std::optional<double> moving_reach;  // the ranking's (PlannerOptions: unset is the planner's default)
  double planning_period = 0.0, accel_max = 0.0, response_time = 0.0, latency = 0.0;
  double target_timeout = 0.0, scan_timeout = 0.0, robot_timeout = 0.0, future_tolerance = 0.0;
  double min_valid_share = 0.0, max_invalid_gap = 0.0;
};
/// planners::TrackerSettings' defaults (safety layer on, planner cvae, ...), the parameters' defaults.
TrackerConfig default_tracker_config();
/// What the planner of `config` will rank and assume, with each planner's own defaults resolved
/// (planners::describe_ranking_and_layer), e.g. "tracking weight 5, moving reach 1 s, standoff 0.5 s, moving
/// obstacles up to 1 m/s".
std::string describe_settings(const TrackerConfig& config);

/// A position and velocity (world frame) measured at `stamp` (s).
struct Stamped {
  Vec2 position = Vec2::Zero();
  Vec2 velocity = Vec2::Zero();
  double stamp = 0.0;
};

/// One step's result; the references stay valid until the next step.
struct TrackerStep {
  Vec2 command = Vec2::Zero();  ///< world frame, finite, zero when stopped
  bool stopped = false;
  const std::string* reason = nullptr;                       ///< empty while tracking
  const std::vector<Vec2>* plan = nullptr;                   ///< world frame
  const std::vector<std::vector<Vec2>>* candidates = nullptr;
  /// The safety layer's estimates show moving obstacles faster than it assumes (~moving_speed_max).
  bool beyond_envelope = false;
};

/// planners::Tracker (see its header for the rules).
class TrackerBridge {
 public:
  /// Throws std::invalid_argument naming the setting (as the Tracker does).
  explicit TrackerBridge(const TrackerConfig& config);
  ~TrackerBridge();
  const TrackerStep& step(double now, const Stamped& robot, const Stamped& target, const core::Scan* scan);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// sim::World on a scenario file, and the robot's response to commands (core::velocity_change).
class WorldBridge {
 public:
  /// Throws io::InputError (a std::runtime_error) naming the file and key for an unusable scenario.
  explicit WorldBridge(const std::string& scenario_file);
  ~WorldBridge();
  std::string name() const;
  int beams() const;
  double robot_radius() const;
  Vec2 robot_start() const;
  Vec2 robot_start_velocity() const;
  /// The LiDAR from `position` at world time t (world orientation, beams from angle 0), into `out`.
  void scan(const Vec2& position, double t, core::Scan& out);
  Vec2 target_position(double t) const;
  Vec2 target_velocity(double t) const;
  /// Whether the segment a-b touches an obstacle at time t (line of sight blocked).
  bool blocked(const Vec2& a, const Vec2& b, double t);
  /// Distance from p to the nearest obstacle at time t (negative inside).
  double clearance(const Vec2& p, double t);
  /// The robot's velocity after one step of dt towards `command`, acceleration-bounded (no lag).
  static Vec2 follow(const Vec2& velocity, const Vec2& command, double accel_max, double dt);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::ros_adapter
