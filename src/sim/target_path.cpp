// Target paths of the scenario generator (include/occtrack/sim/scenario_generator.hpp): a virtual
// tele-operator drives the target one waypoint period at a time.
//   - Intentions: a goal somewhere ahead in free space, reached along a shortest route on a grid of the free
//     space (src/sim/free_space.hpp), followed by pure pursuit with a slowly wandering heading error; a
//     cruising speed redrawn now and then; a stop now and then; slower through the route's sharp turns
//     (lateral-acceleration bound).
//   - Each step it tries the headings nearest the one it wants (within its turn-rate bound) and keeps the first
//     whose segment keeps the clearance from the static obstacles and from whose end braking in a straight
//     line would too; so braking straight on is always possible at the next step. Moving obstacles are checked
//     along the segment (hard) and a couple of seconds ahead (preferred); when one corners the target anyway,
//     the operator backs up a few steps and draws again.
//   - When the path is done, the robot is placed behind the target's start, opposite the way it first moves.
// Positions are rounded before they are checked, so the checks hold for exactly what is written.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "../core/no_fma.hpp"
#include "free_space.hpp"
#include "generator_support.hpp"
#include "target_checks.hpp"
#include "teleop_path.hpp"
#include "occtrack/sim/geometry.hpp"
#include "occtrack/sim/scenario_generator.hpp"
#include "occtrack/sim/world.hpp"

OCCTRACK_NO_FMA_CONTRACTION

namespace occtrack::sim {

namespace {

using core::direction;
using generator::FreeSpace;
using generator::inside_area;
using generator::Random;
using generator::round_to;
using generator::wrap_angle;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;

// Everything a step depends on, so that a dead end can back up to any earlier step.
struct Operator {
  Vec2 position = Vec2::Zero();
  double heading = 0.0;
  double speed = 0.0;
  double cruise_speed = 0.0;
  double next_speed_change = 0.0;  // s
  double next_stop = 0.0;          // s; when reached, the operator brakes to a stop
  bool braking = false;
  int stop_steps_left = 0;         // > 0 while standing still
  std::shared_ptr<const std::vector<Vec2>> route;  // towards the current goal (its last point)
  std::size_t route_index = 0;     // route point nearest the target, found moving forward only
  double goal_deadline = 0.0;      // s; a new goal after this
  double wander = 0.0;             // rad, slowly varying heading error
};

// A heading the operator may take this step, and how far it is from what the operator wants.
struct Candidate {
  double heading, cost;
};

class EpisodeMaker {
 public:
  // Route cells keep this much more than the required clearance, so that the route can be followed.
  static constexpr double kRouteMargin = 0.1;
  static constexpr double kCell = 0.1;

  EpisodeMaker(const core::Scenario& world, const TargetSettings& t, std::uint64_t seed)
      : t_(t),
        rng_(seed),
        checks_(world, t_),
        half_w_(checks_.half_w()),
        half_h_(checks_.half_h()),
        free_space_(checks_.statics(), half_w_, half_h_, t.target_radius + t.static_clearance, kRouteMargin, kCell) {
    for (const core::ObstacleSpec& o : world.obstacles)
      if (o.moving()) moving_paths_.push_back(o.path);
    steps_ = static_cast<int>(std::ceil(t.duration / t.waypoint_period - 1e-9));
  }

  core::Scenario make(const core::Scenario& world, const std::string& name) {
    Vec2 robot_start = Vec2::Zero();
    const std::vector<Operator> states = drive(robot_start);
    std::vector<core::TargetWaypoint> path;
    path.reserve(states.size());
    for (std::size_t k = 0; k < states.size(); ++k) path.push_back({time_of(static_cast<int>(k)), states[k].position});
    return generator::episode_scenario(world, t_, name, std::move(path), robot_start);
  }

 private:
  double time_of(int k) const { return k * t_.waypoint_period; }

  // The operator's states at every waypoint, and the robot's start (generator::drive_path calls the hooks below).
  std::vector<Operator> drive(Vec2& robot_start) {
    return generator::drive_path<Operator>(*this, steps_, t_, robot_start);
  }
  template <class State, class Op>
  friend std::vector<State> generator::drive_path(Op&, int, const TargetSettings&, Vec2&);
  static int extra_back(const Operator&) { return 0; }
  bool resume(Operator& o, double t) {
    o.wander = 0.0;
    return new_goal(o, t);
  }

  // --- Constraints (src/sim/target_checks.hpp).

  bool static_clear(const Vec2& a, const Vec2& b, double extra = 0.0) const { return checks_.static_clear(a, b, extra); }
  bool moving_clear(const Vec2& a, const Vec2& b, double t0, double t1, double extra = 0.0) {
    return checks_.moving_clear(a, b, t0, t1, extra);
  }

  // --- The operator's intentions.

  // A free goal the target can reach: usually somewhere ahead, between goal_distance_min and 2.5 times that
  // away, in a direction spread about the current heading (so that the path meanders on through the world
  // rather than shuttling between far corners); near a moving obstacle's lane with probability
  // moving_goal_share, so that the target crosses its way. False when none can be reached.
  bool new_goal(Operator& o, double t) {
    for (int attempt = 0; attempt < 300; ++attempt) {
      Vec2 g;
      if (!moving_paths_.empty() && rng_.chance(t_.moving_goal_share)) {
        const std::vector<Vec2>& lane = moving_paths_[rng_.index(moving_paths_.size())];
        const std::size_t j = 1 + rng_.index(lane.size() - 1);
        const Vec2 on_lane = lane[j - 1] + rng_.uniform() * (lane[j] - lane[j - 1]);
        g = on_lane + rng_.uniform(0.0, 2.5) * direction(rng_.uniform(-kPi, kPi));
      } else {
        // Ahead at first; any direction once the area's edge or the clutter rules out the first tries.
        const double spread = attempt < 100 ? 0.9 * rng_.normal() : rng_.uniform(-kPi, kPi);
        g = o.position + rng_.uniform(t_.goal_distance_min, 2.5 * t_.goal_distance_min) * direction(o.heading + spread);
      }
      if (!inside_area(g, half_w_, half_h_) || (g - o.position).norm() < t_.goal_distance_min || !free_space_.free(g))
        continue;
      if (set_route(o, g, t)) return true;
    }
    return false;
  }

  // A route from the target to `goal` and the time by which it should be there.
  bool set_route(Operator& o, const Vec2& goal, double t) {
    std::vector<Vec2> route = free_space_.route(o.position, goal);
    if (route.empty()) return false;
    double length = 0.0;
    for (std::size_t j = 1; j < route.size(); ++j) length += (route[j] - route[j - 1]).norm();
    o.route = std::make_shared<const std::vector<Vec2>>(std::move(route));
    o.route_index = 0;
    o.goal_deadline = t + 2.0 * length / std::max(o.cruise_speed, t_.min_speed) + 15.0;
    return true;
  }

  // The heading towards the route point `lookahead` metres (along the route) beyond the nearest one.
  double route_heading(const Operator& o, double lookahead) const {
    return generator::route_heading(*o.route, o.route_index, o.position, lookahead, o.heading);
  }

  // The speed at which the turns of the route over the next few metres stay within the lateral acceleration:
  // turning by an angle over a distance s at speed v takes a turn rate of about angle v / s <= a_lat / v.
  double corner_speed(const Operator& o) const {
    const std::vector<Vec2>& route = *o.route;
    double limit = kInfinity, along = 0.0;
    for (std::size_t j = o.route_index; j + 1 < route.size() && along < 4.0; ++j) {
      along += (route[j + 1] - route[j]).norm();
      if (along < 0.5) continue;
      const Vec2 to = route[j + 1] - o.position;
      const double turn = std::abs(wrap_angle(std::atan2(to.y(), to.x()) - o.heading));
      if (turn > 1e-3) limit = std::min(limit, std::sqrt(t_.lateral_acceleration * along / turn));
    }
    return limit;
  }

  // --- The start and the robot.

  Operator start() {
    const double dt = t_.waypoint_period;
    for (int attempt = 0; attempt < 100000; ++attempt) {
      Operator o;
      o.position = round_to(Vec2(rng_.uniform(-half_w_, half_w_), rng_.uniform(-half_h_, half_h_)), t_.decimals);
      o.heading = rng_.uniform(-kPi, kPi);
      if (!free_space_.free(o.position) || !static_clear(o.position, o.position, kRouteMargin)) continue;
      if (!moving_clear(o.position, o.position, 0.0, 4.0 * dt, 0.3)) continue;
      // A robot behind the target (along its first heading) must fit; place_robot settles where exactly.
      if (!robot_fits(robot_behind(o.position, o.heading), o.position)) continue;
      o.cruise_speed = rng_.rising(t_.min_speed, t_.max_speed);
      o.next_speed_change = rng_.uniform(t_.speed_change_min, t_.speed_change_max);
      o.next_stop = rng_.uniform(t_.stop_interval_min, t_.stop_interval_max);
      // The first goal roughly straight on, so that the robot starts behind the target's motion.
      bool routed = false;
      for (int tries = 0; tries < 50 && !routed; ++tries) {
        const Vec2 ahead = o.position + rng_.uniform(t_.goal_distance_min, 2.0 * t_.goal_distance_min) *
                                            direction(o.heading + rng_.uniform(-0.5, 0.5));
        if (inside_area(ahead, half_w_, half_h_) && free_space_.free(ahead)) routed = set_route(o, ahead, 0.0);
      }
      if (!routed && !new_goal(o, 0.0)) continue;  // a pocket of free space: start elsewhere
      return o;
    }
    throw std::runtime_error("generate_episode: found no free start for the target and the robot");
  }

  Vec2 robot_behind(const Vec2& target, double heading) const { return checks_.robot_behind(target, heading); }
  bool robot_fits(const Vec2& robot, const Vec2& target) { return checks_.robot_fits(robot, target); }

  // The robot starts robot_distance behind the target, opposite the way the target first moves.
  bool place_robot(const std::vector<Operator>& states, Vec2& robot) {
    std::vector<Vec2> path;
    path.reserve(states.size());
    for (const Operator& o : states) path.push_back(o.position);
    return checks_.place_robot(path, states.front().heading, robot);
  }

  // --- One step.

  // Advances the operator by one waypoint period from step k; false at a dead end.
  bool step(Operator& o, int k) {
    const double dt = t_.waypoint_period;
    const double t = time_of(k), t_next = time_of(k + 1);
    if (o.stop_steps_left > 0) return stand_still(o, t, t_next);
    if (!update_intentions(o, t)) return false;
    const auto [wanted_heading, wanted_speed] = wanted_motion(o);

    const double dv = t_.acceleration * dt;
    const double speed_cap = t_.max_speed * (1.0 - 1e-4);  // rounding must not push a segment over the max
    const double speed = std::min(speed_cap, o.speed + std::clamp(wanted_speed - o.speed, -dv, dv));
    const double braking_speed = std::max(0.0, o.speed - t_.braking_deceleration * dt);

    // Arrived at a stop.
    if (o.braking && speed <= 0.0) {
      if (!moving_clear(o.position, o.position, t, t_next)) return false;
      begin_stop(o, t_next);
      return true;
    }

    const std::vector<Candidate> candidates = candidate_headings(o, wanted_heading, speed);
    Candidate chosen{};
    double v = speed;
    bool found = choose_heading(o, candidates, v, t, t_next, chosen);
    if (!found && braking_speed < speed) found = choose_heading(o, candidates, v = braking_speed, t, t_next, chosen);
    if (!found) {
      // Brake straight on: clear of static obstacles by the braking line checked last step.
      v = braking_speed;
      const Vec2 next = round_to(o.position + v * dt * direction(o.heading), t_.decimals);
      if (!static_clear(o.position, next) || !moving_clear(o.position, next, t, t_next)) return false;
      chosen = {o.heading, 0.0};
    }
    o.position = round_to(o.position + v * dt * direction(chosen.heading), t_.decimals);
    o.heading = chosen.heading;
    o.speed = v;
    if (o.speed <= 0.0 && o.braking) begin_stop(o, t_next);
    return true;
  }

  // A step of a stop: the moving obstacles must keep off; the next stop is drawn when this one ends.
  bool stand_still(Operator& o, double t, double t_next) {
    if (!moving_clear(o.position, o.position, t, t_next)) return false;
    --o.stop_steps_left;
    if (o.stop_steps_left == 0) o.next_stop = t_next + rng_.uniform(t_.stop_interval_min, t_.stop_interval_max);
    return true;
  }

  void begin_stop(Operator& o, double t_next) {
    o.speed = 0.0;
    o.braking = false;
    const double stop = rng_.uniform(t_.stop_min, t_.stop_max);
    // This step is the stop's first waypoint period.
    o.stop_steps_left = std::max(0, static_cast<int>(std::lround(stop / t_.waypoint_period)) - 1);
    if (o.stop_steps_left == 0) o.next_stop = t_next + rng_.uniform(t_.stop_interval_min, t_.stop_interval_max);
  }

  // Cruising speed, stops, goal: redrawn when due; a new route when the target strayed from its route.
  // False at a dead end (no goal can be reached).
  bool update_intentions(Operator& o, double t) {
    if (t >= o.next_speed_change) {
      o.cruise_speed = rng_.rising(t_.min_speed, t_.max_speed);
      o.next_speed_change = t + rng_.uniform(t_.speed_change_min, t_.speed_change_max);
    }
    if (!o.braking && t >= o.next_stop) o.braking = true;
    if ((o.route->back() - o.position).norm() < 1.0 || t >= o.goal_deadline) return new_goal(o, t);
    // Strayed (a turn too tight, an obstacle dodged): route again.
    if (generator::advance_on_route(*o.route, o.route_index, o.position) > 0.75)
      return set_route(o, o.route->back(), t) || new_goal(o, t);
    return true;
  }

  // The heading (along the route, with the wandering error) and the speed the operator wants.
  std::pair<double, double> wanted_motion(Operator& o) {
    o.wander = std::clamp(0.8 * o.wander + 0.12 * rng_.normal(), -0.5, 0.5);
    // The heading error wanders less at speed (an operator concentrates when going fast).
    const double heading = route_heading(o, 0.8 + 1.2 * o.speed) + o.wander / std::max(1.0, o.speed);
    double speed = o.braking ? 0.0 : o.cruise_speed;
    if (std::abs(wrap_angle(heading - o.heading)) > 0.9)  // slow down for a sharp turn
      speed = std::min(speed, std::max(t_.min_speed, 0.5 * o.cruise_speed));
    speed = std::min(speed, std::max(t_.min_speed, corner_speed(o)));
    return {heading, speed};
  }

  // Headings within the turn-rate bound at `speed` (any, standing still), nearest the wanted one first, with
  // a small preference for going straight on.
  std::vector<Candidate> candidate_headings(const Operator& o, double wanted_heading, double speed) const {
    std::vector<Candidate> candidates;
    if (o.speed <= 0.0) {
      for (int i = 0; i < 24; ++i) candidates.push_back({o.heading + i * kPi / 12.0, 0.0});
      candidates.push_back({wanted_heading, 0.0});
    } else {
      const double turn_rate = std::min(t_.turn_rate_max, t_.lateral_acceleration / std::max(speed, 1e-9));
      const double max_turn = turn_rate * t_.waypoint_period;
      for (int i = -10; i <= 10; ++i) candidates.push_back({o.heading + max_turn * i / 10.0, 0.0});
    }
    for (Candidate& c : candidates) {
      c.heading = wrap_angle(c.heading);
      c.cost = std::pow(wrap_angle(c.heading - wanted_heading), 2) +
               0.3 * std::pow(wrap_angle(c.heading - o.heading), 2);
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
    return candidates;
  }

  // The first candidate whose segment at speed v is clear and from whose end braking straight on stays
  // clear; one that also keeps away from the moving obstacles for the next two seconds if there is such a
  // candidate. False when none is clear.
  bool choose_heading(const Operator& o, const std::vector<Candidate>& candidates, double v, double t,
                      double t_next, Candidate& chosen) {
    const double dt = t_.waypoint_period;
    bool found = false;
    for (const Candidate& c : candidates) {
      const Vec2 u = direction(c.heading);
      const Vec2 next = round_to(o.position + v * dt * u, t_.decimals);
      if (!static_clear(o.position, next)) continue;
      const double braking_distance = v * v / (2.0 * t_.braking_deceleration) + 0.3;
      if (!static_clear(next, next + braking_distance * u, 0.01)) continue;
      if (!moving_clear(o.position, next, t, t_next)) continue;
      if (moving_clear(next, next + 2.0 * v * u, t_next, t_next + 2.0, 0.2)) {
        chosen = c;
        return true;
      }
      if (!found) chosen = c, found = true;
    }
    return found;
  }

  TargetSettings t_;
  Random rng_;
  generator::TargetChecks checks_;
  double half_w_ = 0.0, half_h_ = 0.0;
  FreeSpace free_space_;
  std::vector<std::vector<Vec2>> moving_paths_;
  int steps_ = 0;
};

}  // namespace

core::Scenario generate_episode(const core::Scenario& world, const TargetSettings& target, std::uint64_t seed,
                                const std::string& name) {
  std::string error;
  if (!target.validate(&error)) throw std::invalid_argument("generate_episode: " + error);
  if (target.motion == TargetMotion::teleop) return generator::generate_teleop_episode(world, target, seed, name);
  EpisodeMaker maker(world, target, seed);
  return maker.make(world, name);
}

}  // namespace occtrack::sim
