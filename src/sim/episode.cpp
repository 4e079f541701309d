#include "occtrack/sim/episode.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

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
  core::EpisodeMetrics& m = result.metrics;
  m.scenario = scenario.name;
  m.planner = planner.name();
  m.min_clearance_m = INFINITY;
  m.acceleration.min = INFINITY;

  Vec2 position = scenario.robot_position, velocity = scenario.robot_velocity;
  Vec2 command = velocity, pending_command = velocity;
  int pending_at = -1;  // physics step at which pending_command takes effect
  bool in_collision = false;
  double accel_sum = 0, distance_sum = 0;
  int in_band = 0;
  std::vector<double> compute;
  compute.reserve(steps / plan_every + 1);
  const double sensor_range = scenario.sensor.range;
  int next_progress = 0;

  for (int step = 0; step <= steps; ++step) {
    const double t = step * dt;
    const Vec2 target = world.target_position(t);

    // Metrics of the current state (exact geometry, physics-step resolution).
    const double clearance = world.clearance(position, t) - scenario.robot_radius;
    m.min_clearance_m = std::min(m.min_clearance_m, clearance);
    const bool colliding = clearance < 0.0;
    const bool occluded = world.segment_blocked(position, target, t);
    const double distance = (target - position).norm();
    if (step < steps) {
      if (colliding) m.collision_time_s += dt;
      if (occluded) m.occlusion_time_s += dt;
      if (distance > sensor_range) m.target_out_of_range_s += dt;
      distance_sum += distance;
      in_band += distance >= settings.band.min && distance <= settings.band.max;
    }
    if (colliding && !in_collision) ++m.collisions;
    in_collision = colliding;
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
      planners::PlannerOutput out = planner.plan(input);
      ++m.cycles;
      compute.push_back(out.compute_ms);
      Vec2 next = out.command_velocity;
      if (!out.ok || !next.allFinite()) {
        ++m.planner_failures;
        next = Vec2::Zero();  // brake: never pass a non-finite command on
      }
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
    const double accel = change.norm() / dt;
    accel_sum += accel;
    m.acceleration.min = std::min(m.acceleration.min, accel);
    m.acceleration.max = std::max(m.acceleration.max, accel);

    if (progress && step >= next_progress) {
      progress(double(step) / steps);
      next_progress = step + static_cast<int>(std::round(1.0 / dt));
    }
  }
  const int counted = std::max(1, steps);
  m.duration_s = steps * dt;
  m.success = m.occlusion_time_s == 0.0;
  m.acceleration.mean = accel_sum / counted;
  if (!std::isfinite(m.acceleration.min)) m.acceleration.min = 0;
  m.compute_ms = core::summarize_timings(compute);
  m.tracking_distance_mean_m = distance_sum / counted;
  m.tracking_in_band_share = double(in_band) / counted;
  if (progress) progress(1.0);
  return result;
}

}  // namespace occtrack::sim
