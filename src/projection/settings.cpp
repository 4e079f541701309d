#include "occtrack/projection/settings.hpp"

#include "../core/settings_checker.hpp"

#include <cmath>
#include <sstream>

namespace occtrack::projection {

namespace {

using Checker = occtrack::detail::SettingsChecker;

}  // namespace

bool Settings::validate(std::string* error) const {
  Checker c;
  c.require(degree >= 5 && degree <= 30, "degree (", degree,
            ") must be between 5 and 30: the initial guess meets six conditions per axis");
  c.require(steps >= 4 && steps <= 10000, "steps (", steps, ") must be between 4 and 10000");
  c.finite(horizon, "horizon");
  c.require(horizon > 0.0, "horizon (", horizon, ") must be positive");
  c.require(via_step_1 > 0 && via_step_1 < steps - 1, "via_step_1 (", via_step_1,
            ") must lie strictly inside the horizon, between 1 and steps - 2 (", steps - 2, ")");
  c.require(via_step_2 > via_step_1 && via_step_2 < steps - 1, "via_step_2 (", via_step_2,
            ") must be greater than via_step_1 (", via_step_1, ") and at most steps - 2 (", steps - 2, ")");
  c.require(batch >= 1 && batch <= 1000000, "batch (", batch, ") must be between 1 and 1000000");
  c.require(obstacles >= 0 && obstacles <= 100000, "obstacles (", obstacles, ") must be between 0 and 100000");
  c.require(iterations >= 1 && iterations <= 1000000, "iterations (", iterations,
            ") must be between 1 and 1000000");
  c.finite(obstacle_radius, "obstacle_radius");
  c.require(obstacle_radius > 0.0, "obstacle_radius (", obstacle_radius, ") must be positive");
  c.finite(speed_min, "speed_min");
  c.finite(speed_max, "speed_max");
  c.require(speed_min >= 0.0, "speed_min (", speed_min, ") must not be negative");
  c.require(speed_max > 0.0, "speed_max (", speed_max, ") must be positive");
  c.require(speed_min <= speed_max, "speed_min (", speed_min, ") must not exceed speed_max (", speed_max, ")");
  c.finite(accel_max, "accel_max");
  c.require(accel_max > 0.0, "accel_max (", accel_max, ") must be positive");
  const std::pair<const char*, double> weights[] = {{"rho.obstacle", rho.obstacle},
                                                     {"rho.velocity", rho.velocity},
                                                     {"rho.acceleration", rho.acceleration},
                                                     {"rho.tracking", rho.tracking},
                                                     {"rho.projection", rho.projection}};
  for (const auto& [name, value] : weights) {
    c.finite(value, name);
    c.require(value >= 0.0, name, " (", value, ") must not be negative");
  }
  c.require(rho.projection > 0.0, "rho.projection (", rho.projection,
            ") must be positive: it keeps the projection's KKT matrix invertible");
  c.require(threads >= 1 && threads <= 1024, "threads (", threads, ") must be between 1 and 1024");
  if (!c.ok() && error != nullptr) *error = c.message();
  return c.ok();
}

}  // namespace occtrack::projection
