// The rules every target path of the scenario generator keeps, and the robot's start (private to src/sim/:
// target_path.cpp's smooth operator and teleop_path.cpp's joystick operator share them, so both modes keep the
// same clearances by the same arithmetic). Compiled without fused multiply-adds (generator_support.hpp).
#pragma once

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "occtrack/core/scenario.hpp"
#include "occtrack/sim/geometry.hpp"
#include "occtrack/sim/scenario_generator.hpp"
#include "occtrack/sim/world.hpp"

namespace occtrack::sim::generator {

class TargetChecks {
 public:
  /// `world`: generate_world's output (or any obstacles-only scenario); its area is the settings' area, around
  /// (area_center_x, area_center_y).
  TargetChecks(const core::Scenario& world, const TargetSettings& t);

  /// The static obstacles, shifted by `shift` (FreeSpace wants its area centred on the origin).
  static std::vector<Shape> static_shapes(const core::Scenario& world, const Vec2& shift = Vec2::Zero());

  const std::vector<Shape>& statics() const { return statics_; }
  bool has_moving() const { return !moving_index_.empty(); }
  /// p relative to the area's centre.
  Vec2 local(const Vec2& p) const { return p - center_; }
  double half_w() const { return half_w_; }  ///< half the area's width, less area_margin
  double half_h() const { return half_h_; }

  /// Whether the target's disk swept along a-b keeps static_clearance (+ extra) from every static obstacle
  /// (exact) and a, b lie inside the area (less extra).
  bool static_clear(const Vec2& a, const Vec2& b, double extra = 0.0) const;
  /// Whether the target going from a (time t0) to b (time t1) keeps moving_clearance (+ extra) from every
  /// moving obstacle, checked every 0.025 s (the tests check every 0.05 s).
  bool moving_clear(const Vec2& a, const Vec2& b, double t0, double t1, double extra = 0.0);

  /// robot_distance behind `target` against `heading`, rounded.
  Vec2 robot_behind(const Vec2& target, double heading) const;
  /// Inside the area, clear of every obstacle by robot_clearance at t = 0, and seeing the target.
  bool robot_fits(const Vec2& robot, const Vec2& target);
  /// The robot's start robot_distance behind the target's start, opposite the way the target first moves
  /// (its first point 0.5 m from the start, else `heading`), turned by 0.1 rad at a time, either way, up to
  /// `widest_turn` rad when that spot is taken; false when none fits.
  bool place_robot(const std::vector<Vec2>& path, double heading, Vec2& robot, double widest_turn = 0.6);

 private:
  const TargetSettings& t_;
  World world_;
  std::vector<Shape> statics_;
  std::vector<std::size_t> moving_index_;
  Vec2 center_;
  double half_w_, half_h_;
};

/// An episode as both operators write it: the world's obstacles, the settings' duration, radii and sensor, the
/// target's waypoints, the robot at rest at `robot`.
core::Scenario episode_scenario(const core::Scenario& world, const TargetSettings& t, const std::string& name,
                                std::vector<core::TargetWaypoint> target, const Vec2& robot);

/// How both operators make a path: one waypoint step at a time from op.start(), `steps` steps, then the robot's
/// start (op.place_robot). At a dead end (op.step false) it backs up 4 steps, 2 more for each failure in a
/// row there, plus op.extra_back(the last state) (asked once per dead end), and has the operator draw again
/// from there (op.resume(state, its time): false when no goal can be reached); it starts over where the start
/// itself is a trap (more than 8 failures in a row back to it) or no robot start fits, and throws
/// std::runtime_error after max_backtracks dead ends or 100 robot misses.
template <class State, class Op>
std::vector<State> drive_path(Op& op, int steps, const TargetSettings& t, Vec2& robot_start) {
  std::vector<State> states;
  int backtracks = 0, failures_in_a_row = 0, failed_at = -1, robot_misses = 0;
  while (true) {
    if (states.empty()) states.push_back(op.start());
    const int k = static_cast<int>(states.size()) - 1;
    if (k == steps) {
      if (op.place_robot(states, robot_start)) return states;
      if (++robot_misses > 100) throw std::runtime_error("generate_episode: found no start for the robot");
      states.clear();  // no free spot behind the target with a view of it: start elsewhere
      continue;
    }
    State next = states.back();
    if (op.step(next, k)) {
      states.push_back(std::move(next));
      if (k >= failed_at) failures_in_a_row = 0;  // past the dead end
      continue;
    }
    const int extra = op.extra_back(states.back());
    if (++backtracks > t.max_backtracks)
      throw std::runtime_error("generate_episode: gave up after " + std::to_string(t.max_backtracks) +
                               " dead ends; the world is too crowded for the target's clearances");
    ++failures_in_a_row;
    failed_at = std::max(failed_at, k);
    const int back = std::min(k, 4 + 2 * failures_in_a_row + extra);
    states.resize(static_cast<std::size_t>(k - back + 1));
    if (k - back == 0 && failures_in_a_row > 8) {
      states.clear();  // the start itself is a trap: draw a new one
      continue;
    }
    if (!op.resume(states.back(), (k - back) * t.waypoint_period)) states.clear();
  }
}

// Following a route (cell centres from free_space.hpp, in world coordinates): both operators steer along it.

/// Moves `index` to the route point nearest `p`, searching up to 40 points forward (never back); its distance.
double advance_on_route(const std::vector<Vec2>& route, std::size_t& index, const Vec2& p);
/// The direction from `p` to the route point `lookahead` metres (along the route) beyond point `index`;
/// `fallback` when p is on it.
double route_heading(const std::vector<Vec2>& route, std::size_t index, const Vec2& p, double lookahead,
                     double fallback);

}  // namespace occtrack::sim::generator
