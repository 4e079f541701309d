// AutoChaser's planning cycle: predict the target over the horizon, build the viewpoint layers, search them,
// smooth the waypoints in corridors, command the path's first velocity (shared/reference/paper_setup.md).
#include "occtrack/planners/autochaser.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "../core/settings_checker.hpp"
#include "cycle.hpp"
#include "occtrack/sim/world.hpp"

namespace occtrack::planners {

bool AutoChaserSettings::validate(std::string* error) const {
  occtrack::detail::SettingsChecker c;
  c.positive(field_resolution, "field_resolution");
  c.positive(field_truncation, "field_truncation");
  c.positive(horizon, "horizon");
  c.require(layers >= 1, "layers (", layers, ") must be at least 1");
  c.require(waypoints >= 0, "waypoints (", waypoints, ") must be >= 0");
  c.positive(grid_resolution, "grid_resolution");
  c.non_negative(safe_radius, "safe_radius");
  c.non_negative(distance_min, "distance_min");
  c.positive(distance_max, "distance_max");
  c.require(distance_min < distance_max, "distance_min (", distance_min, ") must be less than distance_max (",
            distance_max, ")");
  c.non_negative(visibility_min, "visibility_min");
  c.positive(connect_distance, "connect_distance");
  c.non_negative(visibility_weight, "visibility_weight");
  c.non_negative(distance_weight, "distance_weight");
  c.non_negative(distance_desired, "distance_desired");
  c.require(degree >= 3 && degree <= 12, "degree (", degree, ") must lie in [3, 12]");
  c.positive(waypoint_weight, "waypoint_weight");
  c.require(corridor_points >= 0, "corridor_points (", corridor_points, ") must be >= 0");
  c.positive(corridor_half_width, "corridor_half_width");
  c.positive(speed_max, "speed_max");
  c.positive(accel_max, "accel_max");
  c.positive(command_window, "command_window");
  c.non_negative(replan_period, "replan_period");
  c.non_negative(response_time, "response_time");
  c.non_negative(follow_tolerance, "follow_tolerance");
  c.require(plan_points >= 2, "plan_points (", plan_points, ") must be at least 2");
  return c.done(error);
}

struct AutoChaser::Impl {
  AutoChaserSettings s;
  autochaser::DistanceField field;
  std::unique_ptr<sim::World> prior;  // the target's true path, for waypoints > 0
  PlanRecord record;                  // never valid: AutoChaser has no coefficients xi
  std::vector<autochaser::Layer> layers;
  autochaser::ViewpointPath viewpoints;
  autochaser::SmoothPath path;
  bool have_path = false;     // path is the last smooth path, started at path_start
  double path_start = 0.0;
  bool have_previous = false;  // the last cycle's robot velocity, for the start acceleration
  double previous_time = 0.0;
  Vec2 previous_velocity = Vec2::Zero();

  explicit Impl(const AutoChaserSettings& settings)
      : s(occtrack::detail::checked(settings, "autochaser")), field() {}
};

AutoChaser::AutoChaser(const AutoChaserSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
AutoChaser::~AutoChaser() = default;

std::string AutoChaser::name() const {
  return impl_->s.waypoints > 0 ? "autochaser-wp" + std::to_string(impl_->s.waypoints) : "autochaser";
}

void AutoChaser::reset() {
  impl_->record.valid = false;
  impl_->have_path = false;
  impl_->have_previous = false;
  impl_->viewpoints = {};
}

void AutoChaser::use_prior(const core::Scenario& scenario) {
  impl_->field = autochaser::DistanceField(scenario, impl_->s.field_resolution, impl_->s.field_truncation);
  impl_->prior = impl_->s.waypoints > 0 ? std::make_unique<sim::World>(scenario) : nullptr;
}

const PlanRecord& AutoChaser::last_record() const { return impl_->record; }
const autochaser::DistanceField& AutoChaser::field() const { return impl_->field; }
const autochaser::ViewpointPath& AutoChaser::last_viewpoints() const { return impl_->viewpoints; }

namespace {

/// The command of a path at time t0 on it: its mean velocity over the window, within accel_max * window of
/// the robot's velocity and within speed_max; zero when not finite.
Vec2 path_command(const autochaser::SmoothPath& path, double t0, const Vec2& robot_velocity,
                  const AutoChaserSettings& s) {
  // A lagging robot (response time tau) tracks the path when commanded its velocity tau ahead
  // (docs/protocol_v2.md); tau = 0 is the path's first window.
  const double lead = std::min(s.response_time, std::max(0.0, path.duration() - t0 - s.command_window));
  Vec2 command = (path.derivative(t0 + lead + s.command_window, 0) - path.derivative(t0 + lead, 0)) / s.command_window;
  const Vec2 change = command - robot_velocity;
  const double change_max = s.accel_max * (s.command_window + s.response_time);
  if (change.norm() > change_max) command = robot_velocity + change * (change_max / change.norm());
  if (command.norm() > s.speed_max) command *= s.speed_max / command.norm();
  return command.allFinite() ? command : Vec2::Zero();
}

void fill_plan(const autochaser::SmoothPath& path, double t0, int points, std::vector<Vec2>& plan) {
  plan.resize(points);
  const double span = path.duration() - t0;
  for (int k = 0; k < points; ++k) plan[k] = path.derivative(t0 + span * k / (points - 1), 0);
}

}  // namespace

void AutoChaser::plan(const PlannerInput& input, PlannerOutput& out) {
  const detail::CycleClock clock;
  Impl& m = *impl_;
  const AutoChaserSettings& s = m.s;
  out.ok = true;
  out.message.clear();
  out.resize_candidates(0);
  if (!input.robot_position.allFinite() || !input.robot_velocity.allFinite() || !std::isfinite(input.time))
    return detail::brake(out, m.record, clock, "autochaser: planner input: robot state is not finite");
  const bool true_future = s.waypoints > 0 && m.prior != nullptr;
  if (!true_future) {
    if (std::isnan(input.target_age) || input.target_age < 0.0)
      return detail::brake(out, m.record, clock, "autochaser: planner input: target_age must be >= 0");
    if (input.target_age == std::numeric_limits<double>::infinity()) {
      // Never observed: nothing to predict from; hold still (not a failure of the planner).
      detail::brake(out, m.record, clock, "autochaser: target never observed, holding still");
      out.ok = true;
      return;
    }
    if (!input.target_position.allFinite() || !input.target_velocity.allFinite())
      return detail::brake(out, m.record, clock, "autochaser: planner input: target state is not finite");
  }
  // The start acceleration, from the velocity of the previous cycle (odometry gives no acceleration).
  Vec2 acceleration = Vec2::Zero();
  const double dt = input.time - m.previous_time;
  if (m.have_previous && dt > 1e-6 && dt < 0.5) {
    acceleration = (input.robot_velocity - m.previous_velocity) / dt;
    if (acceleration.norm() > s.accel_max) acceleration *= s.accel_max / acceleration.norm();
  }
  m.have_previous = true;
  m.previous_time = input.time;
  m.previous_velocity = input.robot_velocity;

  // Hold mode (replan_period > 0, the original's 2.9 s): follow the held path until it is due.
  // The last smooth path at this time, when there is one and it lasts beyond the command window.
  const auto follow_last_path = [&] {
    const double t0 = input.time - m.path_start;
    if (!m.have_path || t0 < 0.0 || t0 + s.command_window > m.path.duration()) return false;
    out.command_velocity = path_command(m.path, t0, input.robot_velocity, s);
    fill_plan(m.path, t0, s.plan_points, out.plan);
    detail::finish(out, clock);
    return true;
  };
  if (s.replan_period > 0.0 && input.time - m.path_start < s.replan_period && follow_last_path()) return;

  // Target prediction at the layers' times l H / L.
  const int L = s.layers;
  const double spacing = s.horizon / L;
  m.layers.resize(L);
  for (int l = 1; l <= L; ++l) {
    Vec2 target;
    if (true_future) {
      // N points of the true future over the horizon; layer l takes the first at or after l H / L.
      const int i = static_cast<int>(std::ceil(static_cast<double>(l) * s.waypoints / L - 1e-9));
      target = m.prior->target_position(input.time + i * s.horizon / s.waypoints);
    } else {
      // Constant velocity from the estimate's own time (target_age seconds ago).
      target = input.target_position + input.target_velocity * (input.target_age + l * spacing);
    }
    m.layers[l - 1] = autochaser::make_layer(m.field, s, target);
  }
  m.viewpoints = autochaser::search_viewpoints(m.field, s, input.robot_position, m.layers, spacing);
  if (m.viewpoints.layers_reached == 0) {
    // No viewpoint within reach of an edge (a target far ahead, e.g. predicted from a stale estimate): head
    // for the best of those in clear straight line, at whatever distance; the command's speed cap applies.
    AutoChaserSettings unlimited = s;
    unlimited.connect_distance = std::numeric_limits<double>::infinity();
    m.viewpoints = autochaser::search_viewpoints(m.field, unlimited, input.robot_position, m.layers, spacing);
  }
  if (m.viewpoints.layers_reached == 0) {
    // No visible, reachable viewpoint at all (the predicted target near an obstacle, or the robot boxed in):
    // keep to the last path while it lasts, as the original does between replans; brake after that.
    const char* why = "autochaser: no viewpoint of the first layer is reachable";
    out.message = std::string(why) + "; following the last path";
    if (follow_last_path()) return;
    return detail::brake(out, m.record, clock, why);
  }

  // The start velocity and acceleration: the last path's at this time while the robot keeps close to it
  // (within follow_tolerance), so that a robot that lags its command (tau) does not drag every new path
  // down to its own lagging state; the measured ones otherwise.
  Vec2 velocity = input.robot_velocity;
  const double t_last = input.time - m.path_start;
  if (m.have_path && t_last >= 0.0 && t_last <= m.path.duration() &&
      (m.path.derivative(t_last, 1) - velocity).norm() < s.follow_tolerance) {
    velocity = m.path.derivative(t_last, 1);
    acceleration = m.path.derivative(t_last, 2);
  }
  std::string error;
  if (autochaser::smooth_path(s, input.robot_position, velocity, acceleration, m.viewpoints.waypoints,
                              spacing, m.path, &error)) {
    out.command_velocity = path_command(m.path, 0.0, input.robot_velocity, s);
    fill_plan(m.path, 0.0, s.plan_points, out.plan);
    m.have_path = true;
    m.path_start = input.time;
  } else {
    // No smooth path: head straight for the first viewpoint, reaching it at its layer's time.
    autochaser::SmoothPath line;
    line.degree = 1;
    line.segments = 1;
    line.segment_duration = spacing;
    line.coefficients.resize(2, 2);
    line.coefficients << input.robot_position, m.viewpoints.waypoints.front() - input.robot_position;
    out.command_velocity = path_command(line, 0.0, input.robot_velocity, s);
    fill_plan(line, 0.0, s.plan_points, out.plan);
    out.message = "autochaser: " + error + "; heading straight for the first viewpoint";
    m.have_path = false;
  }
  // The viewpoints, robot first, for figures.
  out.resize_candidates(1);
  out.candidates[0].assign(1, input.robot_position);
  out.candidates[0].insert(out.candidates[0].end(), m.viewpoints.waypoints.begin(), m.viewpoints.waypoints.end());
  detail::finish(out, clock);
}

}  // namespace occtrack::planners
