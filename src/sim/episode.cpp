#include "occtrack/sim/episode.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "occtrack/sim/metrics.hpp"
#include "occtrack/sim/world.hpp"

namespace occtrack::sim {

bool EpisodeSettings::validate(std::string* error) const {
  std::ostringstream why;
  if (!(physics_step > 0.0 && std::isfinite(physics_step)))
    why << "physics_step (" << physics_step << ") must be positive";
  else if (!(planning_period >= physics_step && std::isfinite(planning_period)))
    why << "planning_period (" << planning_period << ") must be at least physics_step (" << physics_step << ")";
  else if (std::abs(planning_period / physics_step - std::round(planning_period / physics_step)) > 1e-9)
    why << "planning_period (" << planning_period << ") must be a multiple of physics_step (" << physics_step << ")";
  else if (!(robot_accel_max > 0.0 && std::isfinite(robot_accel_max)))
    why << "robot_accel_max (" << robot_accel_max << ") must be positive";
  else if (snapshots < 0)
    why << "snapshots (" << snapshots << ") must not be negative";
  else if (trace_stride < 1)
    why << "trace_stride (" << trace_stride << ") must be at least 1";
  else if (!(band.min <= band.reference && band.reference <= band.max))
    why << "band: min <= reference <= max is required";
  if (why.str().empty()) return true;
  if (error) *error = why.str();
  return false;
}

EpisodeResult run_episode(const core::Scenario& scenario, planners::Planner& planner, const EpisodeSettings& settings,
                          const std::function<void(double)>& progress) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("episode settings: " + error);
  World world(scenario);
  planner.reset();
  std::mt19937_64 rng(settings.seed);

  const double dt = settings.physics_step;
  const int steps = static_cast<int>(std::floor(scenario.duration / dt + 1e-9));
  const int plan_every = static_cast<int>(std::lround(settings.planning_period / dt));
  const int snapshot_every =
      settings.snapshots > 0 ? std::max(plan_every, steps / settings.snapshots / plan_every * plan_every) : 0;

  EpisodeResult result;
  EpisodeMetricsAccumulator metrics(scenario.name, planner.name(), dt, scenario.sensor.range, settings.band,
                                    steps / plan_every + 1);

  Vec2 position = scenario.robot_position, velocity = scenario.robot_velocity;
  Vec2 command = velocity, pending_command = velocity;
  int pending_at = -1;  // physics step at which pending_command takes effect
  int next_progress = 0;
  planners::PlannerOutput out;

  for (int step = 0; step <= steps; ++step) {
    const double t = step * dt;
    const Vec2 target = world.target_position(t);

    // Metrics of the current state (exact geometry, physics-step resolution).
    const double clearance = world.clearance(position, t) - scenario.robot_radius;
    const bool occluded = world.segment_blocked(position, target, t);
    metrics.add_state(clearance, occluded, (target - position).norm(), step == steps);
    if (step % settings.trace_stride == 0) {
      result.trace.time.push_back(t);
      result.trace.robot.push_back(position);
      result.trace.target.push_back(target);
      result.trace.occluded.push_back(occluded);
    }
    if (step == steps) break;

    // Planning cycle.
    if (step % plan_every == 0) {
      const core::Scan scan = world.scan(position, t, rng);
      planners::PlannerInput input;
      input.time = t;
      input.robot_position = position;
      input.robot_velocity = velocity;
      input.target_position = target;
      input.target_velocity = world.target_velocity(t);
      input.scan = &scan;
      planner.plan(input, out);  // `out` is reused from cycle to cycle: its storage is not reallocated
      Vec2 next = out.command_velocity;
      const bool failed = !out.ok || !next.allFinite();
      metrics.add_cycle(out.compute_ms, failed);
      if (failed) next = Vec2::Zero();  // brake: never pass a non-finite command on
      if (settings.delay_by_compute) {
        pending_command = next;
        pending_at = step + static_cast<int>(std::ceil(out.compute_ms / 1000.0 / dt - 1e-9));
      } else {
        command = next;
      }
      if (snapshot_every > 0 && step % snapshot_every == 0 && step > 0 &&
          static_cast<int>(result.trace.snapshots.size()) < settings.snapshots) {
        result.trace.snapshots.push_back({t, position, target, std::move(out.plan), std::move(out.candidates)});
      }
    }
    if (pending_at >= 0 && step >= pending_at) {
      command = pending_command;
      pending_at = -1;
    }

    // Robot: velocity follows the command under the acceleration bound; position integrates it.
    Vec2 change = command - velocity;
    const double limit = settings.robot_accel_max * dt;
    if (change.norm() > limit) change *= limit / change.norm();
    velocity += change;
    position += velocity * dt;
    metrics.add_acceleration(change.norm() / dt);

    if (progress && step >= next_progress) {
      progress(double(step) / steps);
      next_progress = step + static_cast<int>(std::round(1.0 / dt));
    }
  }
  result.metrics = metrics.finish();
  if (progress) progress(1.0);
  return result;
}

}  // namespace occtrack::sim
