// Tele-operated target paths (TargetMotion::teleop, include/occtrack/sim/scenario_generator.hpp): a virtual
// person drives the target with a joystick, as in the recordings of shared/reference/paper_setup.md ("Target
// motion: recorded tele-operation").
//   - Commands: body-frame forward and sideways speeds (shares of the nominal speed) and a yaw rate, changed
//     every 20-40 ms. Forward reverts to its mean with noise; sideways is flicked on for a strafe now and then;
//     the yaw rate steers the direction of motion towards the route ahead, plus mean-reverting noise; now and
//     then a short stop. Between command updates the body moves at constant commands.
//   - Intentions: goals 1 to 2 m from an obstacle's surface, often the next one around the same obstacle
//     (loops) or beside a neighbouring one (weaving), reached along shortest routes on the free-space grid
//     (src/sim/free_space.hpp, whose area is centred on the origin: it gets the obstacles shifted by the area's
//     centre).
//   - Safety: each waypoint step (a segment of the written path) must keep static_clearance from static
//     obstacles and moving_clearance from moving ones (checked along it) and stay inside the area. When a step
//     would not, or would head into an obstacle within the next moments, the operator corrects, mildest first:
//     ends the strafe, steers without the noise, veers, slows, creeps along the route, halts; when even halting
//     fails (a moving obstacle closing in) it backs up a few steps and draws again with a new goal. An operator
//     that keeps halting (kStuckHalts) is stuck and backs up the same way, past its halts: without creeping
//     and this, a target at 2 m/s in v1's clutter stood pinned beside an obstacle for most of an episode
//     (halting is always clear, and it won every step where a bend left no clear straight step).
// Determinism as in the rest of the generator (src/sim/generator_support.hpp): raw-bits random numbers, no
// fused multiply-adds, positions rounded before they are checked.
#include "teleop_path.hpp"

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
#include "occtrack/sim/geometry.hpp"
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

// The operator's commands and intentions: everything a step depends on, so that a dead end can back up to
// any earlier step.
struct Driver {
  Vec2 position = Vec2::Zero();  // as written (rounded)
  double yaw = 0.0;              // rad, the body's heading
  double forward = 0.0;          // commands: shares of the nominal speed, and rad/s
  double sideways = 0.0;
  double yaw_rate = 0.0;
  double yaw_noise = 0.0;        // rad/s, the mean-reverting part of the yaw rate
  double turn_sign = 1.0;        // +1 or -1: the way the steady turn (TeleopStyle::turn_bias) goes
  double next_flip = 0.0;        // s, when it flips
  double next_command = 0.0;     // s, times of the next command update, strafe, stop
  double strafe_until = 0.0;
  double next_strafe = 0.0;
  double stop_until = 0.0;
  double next_stop = 0.0;
  std::shared_ptr<const std::vector<Vec2>> route;  // world coordinates, towards the goal (its last point)
  std::size_t route_index = 0;   // route point nearest the target, found moving forward only
  double goal_deadline = 0.0;    // s; a new goal after this
  int goal_obstacle = -1;        // static obstacle the goal lies beside (-1: none)
  double goal_angle = 0.0;       // rad, direction of the goal from that obstacle's centre
  double loop_sense = 1.0;       // +1 or -1: the way round the obstacle
  double veer = 0.0;             // +1 or -1 while a correction holds the yaw rate at its largest (one step)
  int halts = 0;                 // steps halted by a correction since the goal was drawn
};

// How the operator corrects a step that would break a clearance, mildest first; each includes the ones before
// (veer: steering without the noise, the yaw rate at its largest one way or the other for this step).
// creep: a slow push of the stick straight along the route's next half metre (forward and sideways
// together), the way an operator edges round a tight corner rather than standing before it.
enum class Correction { none, end_strafe, steer, veer_toward, veer_away, slow, creep, halt };
constexpr Correction kCorrections[] = {Correction::none,      Correction::end_strafe, Correction::steer,
                                       Correction::veer_toward, Correction::veer_away, Correction::slow,
                                       Correction::creep,     Correction::halt};

class TeleopMaker {
 public:
  // Route cells keep this much more than the required clearance where they can: 0.85 + 0.35 = 1.2 m from an
  // obstacle's surface with the default clearances, inside the recordings' 1 to 2 m.
  static constexpr double kRouteMargin = 0.35;
  static constexpr double kCell = 0.1;
  static constexpr double kLookahead = 0.6;       // s of motion ahead that should stay clear of static obstacles
  static constexpr double kMovingLookahead = 1.0;  // s, the same for moving obstacles (preferred, not required)
  static constexpr double kCreep = 0.25;          // share of nominal, the speed of Correction::creep
  // Halted steps per goal after which the operator counts as stuck: in dense clutter a route can bend round an
  // obstacle so tightly that not even a creep towards it leaves kLookahead of straight motion clear, and
  // halting (always clear) would win every step for the rest of the episode. A stuck operator is a dead end:
  // it backs up to before the halts and draws a new goal. Recorded operators stop 1 % of the time, in short
  // stops (the stop schedule's, which are no corrections).
  static constexpr int kStuckHalts = 10;

  TeleopMaker(const core::Scenario& world, const TargetSettings& t, std::uint64_t seed)
      : t_(t),
        s_(t.teleop),
        rng_(seed),
        checks_(world, t_),
        statics_(checks_.statics()),
        center_(t.area_center_x, t.area_center_y),
        half_w_(checks_.half_w()),
        half_h_(checks_.half_h()),
        free_space_(generator::TargetChecks::static_shapes(world, -center_), half_w_, half_h_,
                    t.target_radius + t.static_clearance, kRouteMargin, kCell) {
    steps_ = static_cast<int>(std::ceil(t.duration / t.waypoint_period - 1e-9));
  }

  core::Scenario make(const core::Scenario& world, const std::string& name) {
    Vec2 robot_start = Vec2::Zero();
    const std::vector<Driver> states = drive(robot_start);
    std::vector<core::TargetWaypoint> path;
    path.reserve(states.size());
    // Times rounded as positions are, so that the file reads 0.3, not 0.30000000000000004.
    for (std::size_t k = 0; k < states.size(); ++k)
      path.push_back({round_to(time_of(static_cast<int>(k)), t_.decimals), states[k].position});
    return generator::episode_scenario(world, t_, name, std::move(path), robot_start);
  }

 private:
  double time_of(int k) const { return k * t_.waypoint_period; }
  Vec2 local(const Vec2& p) const { return checks_.local(p); }
  double nominal() const { return t_.max_speed; }

  // Exponential wait with the given mean (never, for an infinite mean).
  double exponential(double mean) {
    const double u = rng_.uniform();
    return std::isfinite(mean) ? -mean * std::log(1.0 - u) : kInfinity;
  }
  // Mean time between events lasting `mean_length` on average that take up `share` of the time.
  static double mean_gap(double share, double mean_length) {
    return share > 0.0 ? mean_length * (1.0 - share) / share : kInfinity;
  }

  // The driver's states at every waypoint, and the robot's start (generator::drive_path calls the hooks below).
  std::vector<Driver> drive(Vec2& robot_start) {
    return generator::drive_path<Driver>(*this, steps_, t_, robot_start);
  }
  template <class State, class Op>
  friend std::vector<State> generator::drive_path(Op&, int, const TargetSettings&, Vec2&);
  // A stuck operator backs up past its halts as well (their number is the driver's before the failed step).
  int extra_back(const Driver& last) {
    const int back = stuck_ ? last.halts : 0;
    stuck_ = false;
    return back;
  }
  bool resume(Driver& d, double t) {
    d.yaw_noise = 0.0;
    d.goal_obstacle = -1;
    return new_goal(d, t);
  }

  // --- Constraints (src/sim/target_checks.hpp, the same as the smooth generator's).

  bool static_clear(const Vec2& a, const Vec2& b, double extra = 0.0) const { return checks_.static_clear(a, b, extra); }
  bool moving_clear(const Vec2& a, const Vec2& b, double t0, double t1, double extra = 0.0) {
    return checks_.moving_clear(a, b, t0, t1, extra);
  }

  bool goal_usable(const Vec2& g, const Vec2& from) const {
    return inside_area(local(g), half_w_, half_h_) && free_space_.free(local(g)) && (g - from).norm() >= 1.5;
  }

  // --- Intentions.

  // The point `gap` metres from the surface of static obstacle j, in direction `angle` from its centre.
  Vec2 beside(std::size_t j, double angle, double gap) const {
    const Shape& s = statics_[j];
    const Vec2 u = direction(angle);
    double lo = 0.0, hi = bounding_radius(s) + gap + 1.0;
    for (int i = 0; i < 40; ++i) {  // the signed distance grows along a ray out of a convex shape
      const double mid = 0.5 * (lo + hi);
      (signed_distance(s, s.center + mid * u) < gap ? lo : hi) = mid;
    }
    return s.center + hi * u;
  }

  // A goal beside an obstacle: round the same one (a loop) or beside a neighbour (weaving); in a world
  // without static obstacles, anywhere a few metres away. False when none can be reached.
  bool new_goal(Driver& d, double t) {
    std::vector<std::size_t> near;
    for (std::size_t j = 0; j < statics_.size(); ++j) {
      const double r = (statics_[j].center - d.position).norm();
      if (r >= 2.0 && r <= 10.0 && static_cast<int>(j) != d.goal_obstacle) near.push_back(j);
    }
    for (int attempt = 0; attempt < 300; ++attempt) {
      const double gap = rng_.uniform(s_.goal_gap_min, s_.goal_gap_max);
      int obstacle = -1;
      double angle = 0.0, sense = d.loop_sense;
      Vec2 g;
      if (attempt < 200 && d.goal_obstacle >= 0 && rng_.chance(s_.loop_share)) {
        obstacle = d.goal_obstacle;
        angle = d.goal_angle + sense * rng_.uniform(0.8, 1.8);
        g = beside(static_cast<std::size_t>(obstacle), angle, gap);
      } else if (attempt < 200 && !statics_.empty()) {
        obstacle = static_cast<int>(near.empty() ? rng_.index(statics_.size()) : near[rng_.index(near.size())]);
        angle = rng_.uniform(-kPi, kPi);
        sense = rng_.chance(0.5) ? 1.0 : -1.0;
        g = beside(static_cast<std::size_t>(obstacle), angle, gap);
      } else {
        g = d.position + rng_.uniform(3.0, 10.0) * direction(rng_.uniform(-kPi, kPi));
      }
      if (!goal_usable(g, d.position)) continue;
      // Ahead at first (within 90 degrees of the way the target moves): turning back on the spot is rare.
      const Vec2 to = g - d.position;
      if (attempt < 150 && wrap_angle(std::atan2(to.y(), to.x()) - course(d)) * 2.0 > kPi) continue;
      if (attempt < 150 && wrap_angle(std::atan2(to.y(), to.x()) - course(d)) * 2.0 < -kPi) continue;
      std::vector<Vec2> route = free_space_.route(local(d.position), local(g));
      if (route.empty()) continue;
      double length = 0.0;
      for (std::size_t j = 0; j < route.size(); ++j) {
        route[j] += center_;
        if (j > 0) length += (route[j] - route[j - 1]).norm();
      }
      d.route = std::make_shared<const std::vector<Vec2>>(std::move(route));
      d.route_index = 0;
      d.goal_deadline = t + 2.0 * length / nominal() + 10.0;
      d.goal_obstacle = obstacle;
      d.goal_angle = angle;
      d.loop_sense = sense;
      d.halts = 0;
      return true;
    }
    return false;
  }

  // The direction of motion the commands give (body heading plus the strafe's angle).
  static double slip(const Driver& d) {
    return (d.forward > 0.0 || d.sideways != 0.0) ? std::atan2(d.sideways, d.forward) : 0.0;
  }
  static double course(const Driver& d) { return d.yaw + slip(d); }

  // A fresh route to the current goal (after straying from the route).
  bool reroute(Driver& d) {
    std::vector<Vec2> route = free_space_.route(local(d.position), local(d.route->back()));
    if (route.empty()) return false;
    for (Vec2& p : route) p += center_;
    d.route = std::make_shared<const std::vector<Vec2>>(std::move(route));
    d.route_index = 0;
    return true;
  }

  // The direction of motion the operator wants: towards the route point `lookahead` metres further on.
  double wanted_course(const Driver& d) const {
    return generator::route_heading(*d.route, d.route_index, d.position, 1.0 + 0.6 * nominal(), d.yaw);
  }

  // New goal when the goal is reached or overdue, a new route when the target strayed; false at a dead end.
  bool update_intentions(Driver& d, double t) {
    if ((d.route->back() - d.position).norm() < 0.8 || t >= d.goal_deadline) return new_goal(d, t);
    if (generator::advance_on_route(*d.route, d.route_index, d.position) > 0.8) return reroute(d) || new_goal(d, t);
    return true;
  }

  // --- Commands.

  // The command update at time `now`, `period` seconds after the last one.
  void update_commands(Driver& d, double now, double period) {
    // Stops and strafes start and end.
    if (now >= d.next_stop && now >= d.stop_until) {
      d.stop_until = now + rng_.uniform(s_.stop_min, s_.stop_max);
      d.next_stop = d.stop_until + exponential(mean_gap(s_.stop_share, 0.5 * (s_.stop_min + s_.stop_max)));
    }
    if (d.sideways != 0.0 && now >= d.strafe_until) {
      d.sideways = 0.0;
      d.next_strafe = now + exponential(mean_gap(s_.strafe_share, 0.5 * (s_.strafe_min + s_.strafe_max)));
    } else if (d.sideways == 0.0 && now >= d.next_strafe) {
      d.strafe_until = now + rng_.uniform(s_.strafe_min, s_.strafe_max);
      d.sideways = (rng_.chance(0.5) ? 1.0 : -1.0) * rng_.uniform(s_.strafe_speed_min, s_.strafe_speed_max);
    }
    // Mean-reverting forward command and yaw-rate noise (exact discretisation of an Ornstein-Uhlenbeck
    // process over `period`, so that the statistics do not depend on the command rate).
    const double fa = std::exp(-period / s_.forward_time);
    d.forward = std::clamp(s_.forward_mean + fa * (d.forward - s_.forward_mean) +
                               s_.forward_noise * std::sqrt(1.0 - fa * fa) * rng_.normal(),
                           0.0, 1.0);
    if (now >= d.next_flip) {
      d.turn_sign = -d.turn_sign;
      d.next_flip = now + exponential(s_.turn_flip_time);
    }
    const double ya = std::exp(-period / s_.yaw_noise_time);
    d.yaw_noise = ya * d.yaw_noise + s_.yaw_noise * std::sqrt(1.0 - ya * ya) * rng_.normal();
    steer(d);
  }

  // Yaw rate turning the body towards the route.
  void steer(Driver& d) const {
    // The operator points the body along the route; a strafe carries the target off it sideways for a while
    // (the route following catches up), as a joystick operator strafing past a wall does.
    const double error = wrap_angle(wanted_course(d) - d.yaw);
    d.yaw_rate = d.veer != 0.0 ? d.veer * 2.0 * s_.yaw_rate_max  // an evasive turn: twice the usual largest
                               : std::clamp(s_.yaw_gain * error + d.yaw_noise + d.turn_sign * s_.turn_bias,
                                            -s_.yaw_rate_max, s_.yaw_rate_max);
  }

  // Moves the body for `tau` seconds at the current commands, their speeds times `ease`, or at velocity
  // `*creep` (world frame) when given.
  void move(Driver& d, Vec2& p, double now, double tau, double ease, const Vec2* creep = nullptr) const {
    if (now >= d.stop_until) {
      if (creep) {
        p += tau * *creep;
      } else {
        const double mid = d.yaw + 0.5 * d.yaw_rate * tau;
        const Vec2 body(ease * d.forward * nominal(), ease * d.sideways * nominal());
        const Vec2 ahead = direction(mid), left(-ahead.y(), ahead.x());
        p += tau * (body.x() * ahead + body.y() * left);
      }
    }
    d.yaw = wrap_angle(d.yaw + d.yaw_rate * tau);
  }

  // --- One step.

  // The step from time t to t_next with a correction applied at its start; the commands change on their
  // own schedule inside it.
  void simulate(Driver& d, double t, double t_next, Correction c) {
    if (c >= Correction::end_strafe && d.sideways != 0.0) {
      d.sideways = 0.0;
      d.strafe_until = t;
      d.next_strafe = t + exponential(mean_gap(s_.strafe_share, 0.5 * (s_.strafe_min + s_.strafe_max)));
    }
    if (c >= Correction::steer) d.yaw_noise = 0.0;
    if (c == Correction::veer_toward || c == Correction::veer_away) {
      // Towards the route first, then the other way.
      const double toward = wrap_angle(wanted_course(d) - d.yaw) >= 0.0 ? 1.0 : -1.0;
      d.veer = c == Correction::veer_toward ? toward : -toward;
    }
    if (c >= Correction::halt) d.stop_until = std::max(d.stop_until, t_next);
    if (c != Correction::none) steer(d);
    // Slowing holds for this step only: the operator eases off the stick while a wall is close ahead.
    const double ease = c >= Correction::slow ? 0.5 : 1.0;
    // Creeping: towards the route point half a metre on, whatever the body's heading (sideways stick too).
    Vec2 creep_velocity = Vec2::Zero();
    if (c == Correction::creep)
      creep_velocity = kCreep * nominal() *
                       direction(generator::route_heading(*d.route, d.route_index, d.position, 0.5, course(d)));
    const Vec2* creep = c == Correction::creep ? &creep_velocity : nullptr;
    Vec2 p = d.position;
    double now = t;
    while (d.next_command <= t_next) {
      move(d, p, now, d.next_command - now, ease, creep);
      const double period = rng_.uniform(s_.command_period_min, s_.command_period_max);
      now = d.next_command;
      d.next_command += period;
      update_commands(d, now, period);
    }
    move(d, p, now, t_next - now, ease, creep);
    d.veer = 0.0;
    d.position = round_to(p, t_.decimals);
  }

  // Advances the driver by one waypoint period from step k; false at a dead end. Tries the corrections in
  // order: the first whose step is clear and leaves the way ahead clear wins, else the first whose step is
  // clear.
  bool step(Driver& d, int k) {
    const double t = time_of(k), t_next = time_of(k + 1);
    if (!update_intentions(d, t)) return false;
    const Random rng_before = rng_;
    Driver fallback;
    Random fallback_rng = rng_;
    bool have_fallback = false;
    for (const Correction c : kCorrections) {
      rng_ = rng_before;
      Driver next = d;
      simulate(next, t, t_next, c);
      if (!static_clear(d.position, next.position) || !moving_clear(d.position, next.position, t, t_next)) continue;
      const Vec2 velocity = (next.position - d.position) / t_.waypoint_period;
      const bool ahead_clear =
          static_clear(next.position, next.position + kLookahead * velocity) &&
          moving_clear(next.position, next.position + kMovingLookahead * velocity, t_next, t_next + kMovingLookahead,
                       0.2);
      if (ahead_clear) {
        if (c == Correction::halt && ++next.halts >= kStuckHalts) {
          stuck_ = true;
          return false;
        }
        d = std::move(next);
        return true;
      }
      if (!have_fallback) fallback = std::move(next), fallback_rng = rng_, have_fallback = true;
    }
    if (!have_fallback) return false;
    d = std::move(fallback);
    rng_ = fallback_rng;
    return true;
  }

  // --- The start and the robot.

  Driver start() {
    for (int attempt = 0; attempt < 100000; ++attempt) {
      Driver d;
      d.position = t_.start ? *t_.start
                            : round_to(center_ + Vec2(rng_.uniform(-half_w_, half_w_), rng_.uniform(-half_h_, half_h_)),
                                       t_.decimals);
      if (!free_space_.free(local(d.position)) || !static_clear(d.position, d.position, 0.1)) continue;
      if (!moving_clear(d.position, d.position, 0.0, 0.5, 0.3)) continue;
      if (t_.start) d.yaw = rng_.uniform(-kPi, kPi);  // a fixed start: try every first heading, not only +x
      if (!new_goal(d, 0.0)) continue;
      d.yaw = wanted_course(d);
      if (!robot_fits(t_.robot_start ? *t_.robot_start : robot_behind(d.position, d.yaw), d.position)) continue;
      d.forward = s_.forward_mean;
      d.next_command = rng_.uniform(s_.command_period_min, s_.command_period_max);
      d.next_strafe = exponential(mean_gap(s_.strafe_share, 0.5 * (s_.strafe_min + s_.strafe_max)));
      d.next_stop = exponential(mean_gap(s_.stop_share, 0.5 * (s_.stop_min + s_.stop_max)));
      d.turn_sign = rng_.chance(0.5) ? 1.0 : -1.0;
      d.next_flip = exponential(s_.turn_flip_time);
      steer(d);
      return d;
    }
    throw std::runtime_error("generate_episode: found no free start for the target and the robot");
  }

  Vec2 robot_behind(const Vec2& target, double heading) const { return checks_.robot_behind(target, heading); }
  bool robot_fits(const Vec2& robot, const Vec2& target) { return checks_.robot_fits(robot, target); }
  bool place_robot(const std::vector<Driver>& states, Vec2& robot) {
    if (t_.robot_start) {
      robot = *t_.robot_start;
      return robot_fits(robot, states.front().position);
    }
    std::vector<Vec2> path;
    path.reserve(states.size());
    for (const Driver& d : states) path.push_back(d.position);
    return checks_.place_robot(path, states.front().yaw, robot);
  }

  TargetSettings t_;
  TeleopStyle s_;
  Random rng_;
  generator::TargetChecks checks_;
  std::vector<Shape> statics_;
  Vec2 center_;
  double half_w_ = 0.0, half_h_ = 0.0;
  FreeSpace free_space_;
  int steps_ = 0;
  bool stuck_ = false;  // the last failed step was an operator stuck halting (step())
};

// The calm style of the 0.5 m/s recording and the wild one of the 1 m/s recording (fields not named keep
// TeleopStyle's defaults).
constexpr TeleopStyle kCalmStyle{.forward_mean = 0.97, .forward_noise = 0.022, .forward_time = 2.0,
                                 .yaw_gain = 0.55, .yaw_noise = 0.09, .yaw_noise_time = 5.4, .yaw_rate_max = 1.8,
                                 .turn_bias = 0.13, .turn_flip_time = 1.5, .strafe_share = 0.03,
                                 .strafe_min = 0.25, .strafe_max = 1.08, .strafe_speed_min = 0.51,
                                 .strafe_speed_max = 0.76, .goal_gap_min = 1.07, .goal_gap_max = 1.51,
                                 .loop_share = 1.0};
constexpr TeleopStyle kWildStyle{.forward_mean = 1.0, .forward_noise = 0.03, .forward_time = 2.0, .yaw_gain = 2.5,
                                 .yaw_noise = 0.6, .yaw_noise_time = 0.4, .yaw_rate_max = 3.0,
                                 .strafe_share = 0.38, .strafe_min = 0.3, .strafe_max = 1.1,
                                 .strafe_speed_min = 0.7, .strafe_speed_max = 1.0, .loop_share = 0.5};

// Every field of TeleopStyle: a style between two is interpolated field by field.
constexpr double TeleopStyle::*kStyleFields[] = {
    &TeleopStyle::command_period_min, &TeleopStyle::command_period_max, &TeleopStyle::forward_mean,
    &TeleopStyle::forward_noise,      &TeleopStyle::forward_time,       &TeleopStyle::yaw_gain,
    &TeleopStyle::yaw_noise,          &TeleopStyle::yaw_noise_time,     &TeleopStyle::yaw_rate_max,
    &TeleopStyle::turn_bias,          &TeleopStyle::turn_flip_time,     &TeleopStyle::strafe_share,
    &TeleopStyle::strafe_min,         &TeleopStyle::strafe_max,         &TeleopStyle::strafe_speed_min,
    &TeleopStyle::strafe_speed_max,   &TeleopStyle::stop_share,         &TeleopStyle::stop_min,
    &TeleopStyle::stop_max,           &TeleopStyle::goal_gap_min,       &TeleopStyle::goal_gap_max,
    &TeleopStyle::loop_share};
static_assert(sizeof(kStyleFields) / sizeof(kStyleFields[0]) * sizeof(double) == sizeof(TeleopStyle),
              "kStyleFields must name every field of TeleopStyle");

}  // namespace

TargetSettings teleop_target_settings(double nominal_speed) {
  TargetSettings t;
  t.motion = TargetMotion::teleop;
  t.waypoint_period = 0.1;
  t.max_speed = nominal_speed;
  t.min_speed = std::min(t.min_speed, nominal_speed);
  const double x = std::isfinite(nominal_speed) ? std::clamp((nominal_speed - 0.5) / 0.5, 0.0, 1.0) : 0.0;
  for (const auto field : kStyleFields) t.teleop.*field = kCalmStyle.*field + x * (kWildStyle.*field - kCalmStyle.*field);
  return t;
}

namespace generator {

core::Scenario generate_teleop_episode(const core::Scenario& world, const TargetSettings& target, std::uint64_t seed,
                                       const std::string& name) {
  TeleopMaker maker(world, target, seed);
  return maker.make(world, name);
}

}  // namespace generator

}  // namespace occtrack::sim
