// A tracking scenario (shared/spec/simulation.md, "Scenario files"): the world, the robot's start, the
// target's timed path and the sensor. Plain data; io/scenario.hpp reads and writes it, sim/ runs it.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace occtrack::core {

using Vec2 = Eigen::Vector2d;

struct ObstacleSpec {
  enum class Shape { circle, box };
  Shape shape = Shape::circle;
  Vec2 center = Vec2::Zero();  ///< Position at t = 0.
  double radius = 0.0;         ///< circle: metres.
  Vec2 size = Vec2::Zero();    ///< box: full extent along its own x and y axes, metres.
  double yaw = 0.0;            ///< box: rotation, radians.
  /// Moving obstacles: the shape is carried along this polyline back and forth at `speed` (m/s), by the
  /// offset path(s) - path[0], so that at t = 0 it sits at `center`. Empty: the obstacle is static.
  std::vector<Vec2> path;
  double speed = 0.0;

  bool moving() const { return path.size() >= 2 && speed > 0.0; }
};

struct TargetWaypoint {
  double time = 0.0;  ///< Seconds, strictly increasing along the path.
  Vec2 position = Vec2::Zero();
};

struct SensorSpec {
  int beams = 720;       ///< Evenly over 360 degrees, starting at angle 0 (+x).
  double range = 10.0;   ///< Metres; no return beyond.
  double noise = 0.0;    ///< Standard deviation of additive range noise, metres.
  double dropout = 0.0;  ///< Probability that a beam returns nothing (Protocol v2), in [0, 1].
};

struct Scenario {
  std::string name;
  double duration = 0.0;  ///< Simulated seconds.
  std::vector<ObstacleSpec> obstacles;
  Vec2 robot_position = Vec2::Zero();
  Vec2 robot_velocity = Vec2::Zero();
  double robot_radius = 0.25;
  double target_radius = 0.25;
  std::vector<TargetWaypoint> target;  ///< Linear between waypoints, held after the last.
  SensorSpec sensor;
};

}  // namespace occtrack::core
