// The occtrack side of the boundary (bridge.hpp), compiled as C++20 like the library.
#include "bridge.hpp"

#include <random>

#include "occtrack/core/robot_response.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/tracker.hpp"
#include "occtrack/sim/world.hpp"

namespace occtrack::ros_adapter {

TrackerConfig default_tracker_config() {
  const planners::TrackerSettings s;
  const planners::PlannerOptions& o = s.options;
  TrackerConfig c;
  c.planner = s.planner;
  c.model = o.model;
  c.batch = o.batch;
  c.shield = o.shield;
  c.predictor = o.predictor;
  c.passive_turn = o.passive_turn;
  c.standoff = o.standoff;
  c.moving_speed_max = o.moving_speed_max;
  c.tracking_weight = o.tracking_weight;
  c.moving_reach = o.moving_reach;
  c.planning_period = o.planning_period;
  c.accel_max = o.accel_max;
  c.response_time = o.response_time;
  c.latency = o.latency;
  c.target_timeout = s.target_timeout;
  c.scan_timeout = s.scan_timeout;
  c.robot_timeout = s.robot_timeout;
  c.future_tolerance = s.future_tolerance;
  c.min_valid_share = s.min_valid_share;
  c.max_invalid_gap = s.max_invalid_gap;
  return c;
}

namespace {
planners::TrackerSettings to_settings(const TrackerConfig& c) {
  planners::TrackerSettings s;
  planners::PlannerOptions& o = s.options;
  s.planner = c.planner;
  o.model = c.model;
  o.batch = c.batch;
  o.shield = c.shield;
  o.predictor = c.predictor;
  o.passive_turn = c.passive_turn;
  o.standoff = c.standoff;
  o.moving_speed_max = c.moving_speed_max;
  o.tracking_weight = c.tracking_weight;
  o.moving_reach = c.moving_reach;
  o.planning_period = c.planning_period;
  o.accel_max = c.accel_max;
  o.response_time = c.response_time;
  o.latency = c.latency;
  s.target_timeout = c.target_timeout;
  s.scan_timeout = c.scan_timeout;
  s.robot_timeout = c.robot_timeout;
  s.future_tolerance = c.future_tolerance;
  s.min_valid_share = c.min_valid_share;
  s.max_invalid_gap = c.max_invalid_gap;
  return s;
}
}  // namespace

std::string describe_settings(const TrackerConfig& config) {
  return planners::describe_ranking_and_layer(config.planner, to_settings(config).options);
}

struct TrackerBridge::Impl {
  planners::Tracker tracker;
  TrackerStep result;
};

TrackerBridge::TrackerBridge(const TrackerConfig& config)
    : impl_(std::make_unique<Impl>(Impl{planners::Tracker(to_settings(config)), {}})) {}
TrackerBridge::~TrackerBridge() = default;

const TrackerStep& TrackerBridge::step(double now, const Stamped& robot, const Stamped& target,
                                       const core::Scan* scan) {
  const planners::TrackerOutput& out = impl_->tracker.step(now, {robot.position, robot.velocity, robot.stamp},
                                                           {target.position, target.velocity, target.stamp}, scan);
  TrackerStep& r = impl_->result;
  r.command = out.command;
  r.stopped = out.stopped;
  r.reason = &out.reason;
  r.plan = &out.planner.plan;
  r.candidates = &out.planner.candidates;
  r.beyond_envelope = out.planner.beyond_envelope;
  return r;
}

struct WorldBridge::Impl {
  sim::World world;
  std::mt19937_64 rng{1};  // the scenario's range noise, if any
};

WorldBridge::WorldBridge(const std::string& scenario_file)
    : impl_(std::make_unique<Impl>(Impl{sim::World(io::read_scenario(scenario_file))})) {}
WorldBridge::~WorldBridge() = default;

std::string WorldBridge::name() const { return impl_->world.scenario().name; }
int WorldBridge::beams() const { return impl_->world.scenario().sensor.beams; }
double WorldBridge::robot_radius() const { return impl_->world.scenario().robot_radius; }
Vec2 WorldBridge::robot_start() const { return impl_->world.scenario().robot_position; }
Vec2 WorldBridge::robot_start_velocity() const { return impl_->world.scenario().robot_velocity; }
void WorldBridge::scan(const Vec2& position, double t, core::Scan& out) { impl_->world.scan(position, t, impl_->rng, out); }
Vec2 WorldBridge::target_position(double t) const { return impl_->world.target_position(t); }
Vec2 WorldBridge::target_velocity(double t) const { return impl_->world.target_velocity(t); }
bool WorldBridge::blocked(const Vec2& a, const Vec2& b, double t) { return impl_->world.segment_blocked(a, b, t); }
double WorldBridge::clearance(const Vec2& p, double t) { return impl_->world.clearance(p, t); }

Vec2 WorldBridge::follow(const Vec2& velocity, const Vec2& command, double accel_max, double dt) {
  return velocity + core::velocity_change(velocity, command, 1.0, accel_max * dt);
}

}  // namespace occtrack::ros_adapter
