// The scenario generator's settings (include/occtrack/sim/scenario_generator.hpp): world kinds and the
// checks of GeneratorSettings and TargetSettings. The generator itself: world_drawing.cpp (obstacles),
// target_path.cpp (the target's path and the robot's start, on free_space.cpp's routes), suites.cpp (the
// benchmark suites), generator_support.hpp (random numbers, rounding; why no fused multiply-adds).
#include "occtrack/sim/scenario_generator.hpp"

#include <algorithm>
#include <utility>

#include "../core/name_table.hpp"
#include "../core/settings_checker.hpp"

namespace occtrack::sim {

namespace {

using Checker = occtrack::detail::SettingsChecker;

// Each world kind's name, for both directions.
constexpr std::pair<WorldKind, const char*> kWorldKindNames[] = {
    {WorldKind::forest, "forest"}, {WorldKind::boxes, "boxes"}, {WorldKind::mixed, "mixed"}};
constexpr std::pair<TargetMotion, const char*> kTargetMotionNames[] = {{TargetMotion::smooth, "smooth"},
                                                                       {TargetMotion::teleop, "teleop"}};

// A range [lo, hi] of positive numbers: each positive, lo <= hi.
void positive_range(Checker& c, double lo, double hi, const char* lo_field, const char* hi_field) {
  c.positive(lo, lo_field);
  c.positive(hi, hi_field);
  c.range(lo, hi, lo_field, hi_field);
}

// An interval [lo, hi] above zero: lo positive, lo <= hi (hi may be infinite, for "never").
void positive_interval(Checker& c, double lo, double hi, const char* lo_field, const char* hi_field) {
  c.positive(lo, lo_field);
  c.range(lo, hi, lo_field, hi_field);
}

// The world's area: width along x, height along y, both positive.
void area(Checker& c, double width, double height) {
  c.positive(width, "area_width");
  c.positive(height, "area_height");
}

}  // namespace

const char* to_string(WorldKind kind) { return occtrack::detail::name_of(kWorldKindNames, kind); }

std::optional<WorldKind> parse_world_kind(std::string_view text) { return occtrack::detail::value_of(kWorldKindNames, text); }

const char* to_string(TargetMotion motion) { return occtrack::detail::name_of(kTargetMotionNames, motion); }

std::optional<TargetMotion> parse_target_motion(std::string_view text) {
  return occtrack::detail::value_of(kTargetMotionNames, text);
}

bool GeneratorSettings::validate(std::string* error) const {
  Checker c;
  positive_range(c, style.circle_radius_min, style.circle_radius_max, "style.circle_radius_min",
                 "style.circle_radius_max");
  positive_range(c, style.box_side_min, style.box_side_max, "style.box_side_min", "style.box_side_max");
  c.share(style.box_share, "style.box_share");
  area(c, area_width, area_height);
  c.require(static_obstacles >= 0, "static_obstacles (", static_obstacles, ") must not be negative");
  c.non_negative(min_gap, "min_gap");
  c.non_negative(boundary_margin, "boundary_margin");
  c.require(moving_obstacles >= 0, "moving_obstacles (", moving_obstacles, ") must not be negative");
  c.positive(moving_speed, "moving_speed");
  positive_range(c, moving_radius_min, moving_radius_max, "moving_radius_min", "moving_radius_max");
  positive_range(c, moving_path_min, moving_path_max, "moving_path_min", "moving_path_max");
  c.share(moving_two_segment_share, "moving_two_segment_share");
  c.non_negative(moving_gap, "moving_gap");
  c.require(decimals >= 1 && decimals <= 12, "decimals (", decimals, ") must be between 1 and 12");
  c.require(max_attempts >= 1, "max_attempts (", max_attempts, ") must be positive");
  return c.done(error);
}

bool TargetSettings::validate(std::string* error) const {
  Checker c;
  c.positive(duration, "duration");
  c.positive(waypoint_period, "waypoint_period");
  c.positive(max_speed, "max_speed");
  positive_interval(c, min_speed, max_speed, "min_speed", "max_speed");
  c.positive(acceleration, "acceleration");
  c.positive(braking_deceleration, "braking_deceleration");
  c.range(acceleration, braking_deceleration, "acceleration", "braking_deceleration");
  c.positive(lateral_acceleration, "lateral_acceleration");
  c.positive(turn_rate_max, "turn_rate_max");
  positive_interval(c, speed_change_min, speed_change_max, "speed_change_min", "speed_change_max");
  positive_interval(c, stop_interval_min, stop_interval_max, "stop_interval_min", "stop_interval_max");
  positive_interval(c, stop_min, stop_max, "stop_min", "stop_max");
  c.non_negative(goal_distance_min, "goal_distance_min");
  c.share(moving_goal_share, "moving_goal_share");
  c.positive(target_radius, "target_radius");
  c.non_negative(static_clearance, "static_clearance");
  c.non_negative(moving_clearance, "moving_clearance");
  area(c, area_width, area_height);
  c.non_negative(area_margin, "area_margin");
  c.require(area_margin < 0.5 * std::min(area_width, area_height), "area_margin (", area_margin,
            ") must be less than half the area's smaller side");
  c.positive(robot_radius, "robot_radius");
  c.positive(robot_distance, "robot_distance");
  c.non_negative(robot_clearance, "robot_clearance");
  c.require(sensor.beams >= 1, "sensor.beams (", sensor.beams, ") must be at least 1");
  c.positive(sensor.range, "sensor.range");
  c.non_negative(sensor.noise, "sensor.noise");
  c.require(decimals >= 1 && decimals <= 12, "decimals (", decimals, ") must be between 1 and 12");
  c.require(max_backtracks >= 0, "max_backtracks (", max_backtracks, ") must not be negative");
  c.finite(area_center_x, "area_center_x");
  c.finite(area_center_y, "area_center_y");
  if (start) {
    c.finite(start->x(), "start.x");
    c.finite(start->y(), "start.y");
    c.require(motion == TargetMotion::teleop, "start must be unset with motion smooth (it draws its own)");
  }
  if (robot_start) {
    c.finite(robot_start->x(), "robot_start.x");
    c.finite(robot_start->y(), "robot_start.y");
    c.require(motion == TargetMotion::teleop, "robot_start must be unset with motion smooth (it places its own)");
  }
  if (motion == TargetMotion::smooth) {
    c.require(area_center_x == 0.0 && area_center_y == 0.0, "area_center_x, area_center_y (", area_center_x, ", ",
              area_center_y, ") must be 0 with motion smooth (its area is centred on the origin)");
  } else {
    c.require(waypoint_period <= 0.1, "waypoint_period (", waypoint_period,
              ") must be at most 0.1 s with motion teleop");
    const TeleopStyle& s = teleop;
    positive_range(c, s.command_period_min, s.command_period_max, "teleop.command_period_min",
                   "teleop.command_period_max");
    c.share(s.forward_mean, "teleop.forward_mean");
    c.non_negative(s.forward_noise, "teleop.forward_noise");
    c.positive(s.forward_time, "teleop.forward_time");
    c.non_negative(s.yaw_gain, "teleop.yaw_gain");
    c.non_negative(s.yaw_noise, "teleop.yaw_noise");
    c.positive(s.yaw_noise_time, "teleop.yaw_noise_time");
    c.positive(s.yaw_rate_max, "teleop.yaw_rate_max");
    c.non_negative(s.turn_bias, "teleop.turn_bias");
    c.positive(s.turn_flip_time, "teleop.turn_flip_time");
    c.share(s.strafe_share, "teleop.strafe_share");
    c.require(s.strafe_share < 1.0, "teleop.strafe_share (", s.strafe_share, ") must be less than 1");
    positive_range(c, s.strafe_min, s.strafe_max, "teleop.strafe_min", "teleop.strafe_max");
    positive_range(c, s.strafe_speed_min, s.strafe_speed_max, "teleop.strafe_speed_min", "teleop.strafe_speed_max");
    c.share(s.stop_share, "teleop.stop_share");
    c.require(s.stop_share < 1.0, "teleop.stop_share (", s.stop_share, ") must be less than 1");
    positive_range(c, s.stop_min, s.stop_max, "teleop.stop_min", "teleop.stop_max");
    positive_range(c, s.goal_gap_min, s.goal_gap_max, "teleop.goal_gap_min", "teleop.goal_gap_max");
    c.share(s.loop_share, "teleop.loop_share");
  }
  return c.done(error);
}

}  // namespace occtrack::sim
