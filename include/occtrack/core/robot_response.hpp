// How the robot's velocity follows its command (shared/spec/simulation.md, "Protocol v2", robot response):
// the one home of the formula, used by the simulator and by the safety layer's certification.
//
// Over a step dt the velocity moves towards the command by the exact solution of dv/dt = (command - v) / tau
// (tau 0: at once), and the change is then clipped to accel_max * dt.
#pragma once

#include <cmath>

#include "occtrack/core/geometry.hpp"

namespace occtrack::core {

struct RobotResponse {
  double tau = 0.0;        ///< s, first-order lag of the velocity behind the command (0: none, as v1)
  double accel_max = 2.0;  ///< m/s^2
  double dt = 0.01;        ///< s, integration step

  /// The share of the gap to the command closed in one step (1 without lag).
  double lag() const { return tau > 0.0 ? -std::expm1(-dt / tau) : 1.0; }
  /// The largest velocity change in one step.
  double limit() const { return accel_max * dt; }
};

/// The velocity change of one step, given lag() and limit() of the response.
inline Vec2 velocity_change(const Vec2& velocity, const Vec2& command, double lag, double limit) {
  Vec2 change = command - velocity;
  change *= lag;  // exactly the change itself when lag is 1 (no lag)
  const double squared = change.squaredNorm();
  // Well inside the limit, no square root (root_clearly_below): the answer comparing the root gives. The root
  // sat on the chain of dependent operations of each step (the certifier integrates hundreds of steps per
  // manoeuvre), and the limit binds only early in a manoeuvre.
  if (root_clearly_below(squared, limit)) return change;
  const double size = std::sqrt(squared);  // change.norm()
  if (size > limit) change *= limit / size;
  return change;
}

}  // namespace occtrack::core
