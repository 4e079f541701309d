#include "occtrack/sim/episode.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include "occtrack/core/robot_response.hpp"
#include "occtrack/core/timing.hpp"
#include "occtrack/sim/metrics.hpp"
#include "occtrack/sim/scenario_generator.hpp"
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
  else if (latency_ms && !(std::isfinite(*latency_ms) && *latency_ms >= 0.0))
    why << "latency_ms (" << *latency_ms << ") must be a finite number >= 0";
  else if (latency_ms && delay_by_compute)
    why << "latency_ms and delay_by_compute exclude each other (both delay the command)";
  else if (!(std::isfinite(compute_scale) && compute_scale > 0.0))
    why << "compute_scale (" << compute_scale << ") must be positive";
  else if (!(std::isfinite(tau) && tau >= 0.0))
    why << "tau (" << tau << ") must be a finite number >= 0";
  else if (beams && *beams < 1)
    why << "beams (" << *beams << ") must be at least 1";
  else if (lidar_noise && !(std::isfinite(*lidar_noise) && *lidar_noise >= 0.0))
    why << "lidar_noise (" << *lidar_noise << ") must be a finite number >= 0";
  else if (beam_dropout && !(*beam_dropout >= 0.0 && *beam_dropout <= 1.0))
    why << "beam_dropout (" << *beam_dropout << ") must be in [0, 1]";
  else if (!(std::isfinite(target_position_noise) && target_position_noise >= 0.0))
    why << "target_position_noise (" << target_position_noise << ") must be a finite number >= 0";
  else if (!(std::isfinite(target_velocity_noise) && target_velocity_noise >= 0.0))
    why << "target_velocity_noise (" << target_velocity_noise << ") must be a finite number >= 0";
  if (why.str().empty()) return true;
  if (error) *error = why.str();
  return false;
}

namespace {

/// Whole physics steps from t until a command computed at t applies: the latency rounded up (Protocol v2).
int latency_steps(const EpisodeSettings& settings) {
  if (!settings.latency_ms) return 0;
  return static_cast<int>(std::ceil(*settings.latency_ms / 1000.0 / settings.physics_step - 1e-9));
}

}  // namespace

planners::PlannerOptions planner_options_for(const EpisodeSettings& episode, planners::PlannerOptions options) {
  options.response_time = episode.tau;
  // The latency the robot lives with: a command applies at the first physics step at or after latency_ms, so
  // 15 ms acts as 20 at 10 ms steps. The lead and the safety layer's certificate are for that delay.
  options.latency = latency_steps(episode) * episode.physics_step;
  options.planning_period = episode.planning_period;
  options.accel_max = episode.robot_accel_max;
  return options;
}

namespace {

// Seeds of the v2 random streams, apart from the LiDAR noise stream (settings.seed itself), so that with the
// defaults no extra draw happens and v1 scans stay bit for bit what they were.
constexpr std::uint64_t kDropoutStream = 0x9e3779b97f4a7c15ULL;
constexpr std::uint64_t kTargetNoiseStream = 0xd1b54a32d192ed03ULL;

/// The scenario with the settings' sensor overrides (Protocol v2: beams, range noise, dropout).
core::Scenario sensed_scenario(const core::Scenario& scenario, const EpisodeSettings& settings) {
  core::Scenario s = scenario;
  if (settings.beams) s.sensor.beams = *settings.beams;
  if (settings.lidar_noise) s.sensor.noise = *settings.lidar_noise;
  if (settings.beam_dropout) s.sensor.dropout = *settings.beam_dropout;
  return s;
}

}  // namespace

EpisodeResult run_episode(const core::Scenario& scenario, planners::Planner& planner, const EpisodeSettings& settings,
                          const std::function<void(double)>& progress) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("episode settings: " + error);
  World world(sensed_scenario(scenario, settings));
  world.seed_dropout(settings.seed ^ kDropoutStream);
  planner.use_prior(scenario);
  planner.reset();
  std::mt19937_64 rng(settings.seed);
  std::mt19937_64 target_rng(settings.seed ^ kTargetNoiseStream);
  std::normal_distribution<double> gaussian(0.0, 1.0);

  const double dt = settings.physics_step;
  const int steps = static_cast<int>(std::floor(scenario.duration / dt + 1e-9));
  const int plan_every = static_cast<int>(std::lround(settings.planning_period / dt));
  const int snapshot_every =
      settings.snapshots > 0 ? std::max(plan_every, steps / settings.snapshots / plan_every * plan_every) : 0;
  const int delay_steps = latency_steps(settings);
  // Velocity lag (Protocol v2): the exact solution of dv/dt = (command - v) / tau over one step, the
  // acceleration bound applied after it.
  const core::RobotResponse response{settings.tau, settings.robot_accel_max, dt};
  const double lag = response.lag(), limit = response.limit();
  const double sensor_range = world.scenario().sensor.range;

  EpisodeResult result;
  EpisodeMetricsAccumulator metrics(scenario.name, planner.name(), dt, scenario.sensor.range, settings.band,
                                    steps / plan_every + 1);

  Vec2 position = scenario.robot_position, velocity = scenario.robot_velocity;
  Vec2 command = velocity, pending_command = velocity;
  int pending_at = -1;  // physics step at which pending_command takes effect
  int next_cycle = 0;   // physics step of the next planning cycle
  int next_snapshot = snapshot_every;
  int next_progress = 0;
  // The target estimate the planner receives (line_of_sight: the last one) and when it was measured.
  Vec2 estimate_position = Vec2::Zero(), estimate_velocity = Vec2::Zero();
  double estimate_time = -std::numeric_limits<double>::infinity();
  planners::PlannerOutput out;
  auto apply_pending = [&](int step) {
    if (pending_at >= 0 && step >= pending_at) {
      command = pending_command;
      pending_at = -1;
    }
  };

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

    // A latency's command due now applies before a cycle that starts now replaces it.
    if (settings.latency_ms) apply_pending(step);

    // Planning cycle.
    if (step == next_cycle) {
      const core::Scan scan = world.scan(position, t, rng);
      planners::PlannerInput input;
      input.time = t;
      input.robot_position = position;
      input.robot_velocity = velocity;
      const bool fresh = settings.target_observation == TargetObservation::always ||
                         (!occluded && (target - position).norm() <= sensor_range);
      if (fresh) {
        estimate_position = target;
        estimate_velocity = world.target_velocity(t);
        // Target noise (Protocol v2) from its own stream, drawn only when asked for.
        if (settings.target_position_noise > 0.0) {
          const double x = gaussian(target_rng), y = gaussian(target_rng);
          estimate_position += settings.target_position_noise * Vec2(x, y);
        }
        if (settings.target_velocity_noise > 0.0) {
          const double x = gaussian(target_rng), y = gaussian(target_rng);
          estimate_velocity += settings.target_velocity_noise * Vec2(x, y);
        }
        estimate_time = t;
      }
      if (std::isfinite(estimate_time)) {
        input.target_position = estimate_position;
        input.target_velocity = estimate_velocity;
        input.target_age = fresh ? 0.0 : t - estimate_time;
      } else {  // never observed: the estimate means nothing; the robot's own place keeps a careless planner still
        input.target_position = position;
        input.target_velocity = Vec2::Zero();
        input.target_age = std::numeric_limits<double>::infinity();
      }
      input.scan = &scan;
      planner.plan(input, out);  // `out` is reused from cycle to cycle: its storage is not reallocated
      Vec2 next = out.command_velocity;
      const bool failed = !out.ok || !next.allFinite();
      metrics.add_cycle(out.compute_ms, failed);
      metrics.add_safety(out.safety, out.beyond_envelope);
      if (failed) next = Vec2::Zero();  // brake: never pass a non-finite command on
      if (settings.latency_ms) {
        // Protocol v2: the command applies L after the scan; the next cycle starts at the first planning
        // tick at or after that (and at the earliest one period on, as in v1).
        pending_command = next;
        pending_at = step + delay_steps;
        next_cycle = std::max(step + plan_every, (step + delay_steps + plan_every - 1) / plan_every * plan_every);
      } else if (settings.delay_by_compute) {
        pending_command = next;
        pending_at = step + static_cast<int>(std::ceil(out.compute_ms / 1000.0 / dt - 1e-9));
        next_cycle = step + plan_every;
      } else {
        command = next;
        next_cycle = step + plan_every;
      }
      if (settings.record_cycles) {  // copies: the snapshot below may take the plan, and `out` is reused
        const auto first = out.candidates.begin();
        const auto kept =
            static_cast<std::ptrdiff_t>(std::min(out.candidates.size(), core::CycleRecord::kMaxCandidates));
        const char* safety = out.safety == planners::SafetyAction::off ? "" : planners::to_string(out.safety);
        result.trace.cycles.push_back({t, position, scan, out.plan, {first, first + kept}, next, safety});
      }
      if (snapshot_every > 0 && step >= next_snapshot &&
          static_cast<int>(result.trace.snapshots.size()) < settings.snapshots) {
        result.trace.snapshots.push_back({t, position, target, std::move(out.plan), std::move(out.candidates)});
      }
      if (snapshot_every > 0 && step >= next_snapshot) next_snapshot = (step / snapshot_every + 1) * snapshot_every;
    }
    apply_pending(step);

    // Robot: velocity follows the command (through the lag when tau > 0) under the acceleration bound;
    // position integrates it.
    const Vec2 change = core::velocity_change(velocity, command, lag, limit);
    velocity += change;
    position += velocity * dt;
    metrics.add_acceleration(change.norm() / dt);

    if (progress && step >= next_progress) {
      progress(double(step) / steps);
      next_progress = step + static_cast<int>(std::round(1.0 / dt));
    }
  }
  result.metrics = metrics.finish();
  result.metrics.latency_ms = settings.latency_ms.value_or(0.0);
  result.metrics.compute_scale = settings.compute_scale;
  if (progress) progress(1.0);
  return result;
}

double median_cycle_ms(planners::Planner& planner, const std::vector<core::Scenario>& scenarios,
                       const EpisodeSettings& settings, int cycles) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("episode settings: " + error);
  if (scenarios.empty()) throw std::invalid_argument("median_cycle_ms: no scenarios");
  if (cycles < 1) throw std::invalid_argument("median_cycle_ms: cycles (" + std::to_string(cycles) + ") must be >= 1");
  constexpr double kLeash = 2.0;  // m: the replayed robot stays at most this far behind the target
  const double dt = settings.physics_step;
  const int plan_every = static_cast<int>(std::lround(settings.planning_period / dt));
  const int n = static_cast<int>(scenarios.size());
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(cycles));
  planners::PlannerOutput out;
  planner.reset();
  for (int i = 0; i < n && i < cycles; ++i) {
    // Cycles spread over the scenarios (the first ones take the remainder), and evenly over each one's
    // planning ticks, so that the scans cover each world rather than its first seconds.
    const int count = cycles / n + (i < cycles % n ? 1 : 0);
    const core::Scenario& scenario = scenarios[static_cast<std::size_t>(i)];
    World world(sensed_scenario(scenario, settings));
    world.seed_dropout(settings.seed ^ kDropoutStream);
    std::mt19937_64 rng(settings.seed);
    planner.use_prior(scenario);
    planner.reset();
    const int ticks = std::max(1, static_cast<int>(std::floor(scenario.duration / dt + 1e-9)) / plan_every);
    Vec2 position = scenario.robot_position, velocity = scenario.robot_velocity;
    int step = 0;
    for (int k = 0; k < count; ++k) {
      const int cycle_step = static_cast<int>((static_cast<long>(k) * ticks) / count) * plan_every;
      // The leash: the robot moves only when the target gets more than kLeash away, straight towards it.
      for (; step < cycle_step; ++step) {
        const Vec2 next = leash_position(position, world.target_position((step + 1) * dt), kLeash);
        velocity = (next - position) / dt;
        position = next;
      }
      const double t = step * dt;
      const core::Scan scan = world.scan(position, t, rng);
      planners::PlannerInput input;
      input.time = t;
      input.robot_position = position;
      input.robot_velocity = velocity;
      input.target_position = world.target_position(t);
      input.target_velocity = world.target_velocity(t);
      input.scan = &scan;
      planner.plan(input, out);
      times.push_back(out.compute_ms);
    }
  }
  planner.reset();
  return core::summarize_timings(std::move(times)).median;
}

}  // namespace occtrack::sim
