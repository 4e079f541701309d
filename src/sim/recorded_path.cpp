// A scenario from a recorded target path (include/occtrack/sim/recorded_path.hpp). The robot's start comes
// from the generator's own rule (target_checks.hpp), so that imported and generated episodes begin alike.
#include "occtrack/sim/recorded_path.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "../core/settings_checker.hpp"
#include "generator_support.hpp"
#include "occtrack/sim/world.hpp"
#include "target_checks.hpp"

namespace occtrack::sim {

namespace {

using core::TargetWaypoint;
using core::Vec2;

constexpr double kOverlapStep = 0.05;  // s between the checks of the target's disk against the obstacles
// Waypoints a made scenario may hold: 28 hours at 0.1 s, about 30 MB of YAML. A recording's clock read in the
// wrong unit (nanoseconds as seconds) asks for far more.
constexpr double kMaxWaypoints = 1e6;
// m: no coordinate of a sample may lie farther out (the interpolation and the geometry stay finite).
constexpr double kMaxCoordinate = 1e6;

Vec2 position_at(const std::vector<TargetWaypoint>& samples, double t, std::size_t& k) {
  while (k + 2 < samples.size() && samples[k + 1].time <= t) ++k;
  const TargetWaypoint &a = samples[k], &b = samples[k + 1];
  const double alpha = std::clamp((t - a.time) / (b.time - a.time), 0.0, 1.0);
  return a.position + alpha * (b.position - a.position);
}

Vec2 rounded(const Vec2& p, int decimals) { return decimals > 0 ? generator::round_to(p, decimals) : p; }

}  // namespace

bool RecordedPathSettings::validate(std::string* error) const {
  detail::SettingsChecker c;
  c.require(!std::isnan(from) && !std::isnan(to), "from and to must be numbers");
  c.require(from < to, "from (", from, ") must be less than to (", to, ")");
  c.require(period == 0.0 || (period >= 0.001 && period <= 60.0), "period (", period,
            ") must be 0 (keep every sample) or between 0.001 and 60 s");
  c.require(std::abs(rotation) <= 2.0 * std::numbers::pi, "rotation (", rotation, " rad) must be within [-2 pi, 2 pi]");
  c.require(offset.allFinite() && offset.cwiseAbs().maxCoeff() <= kMaxCoordinate, "offset (", offset.x(), ", ",
            offset.y(), ") must be finite and within 1e6 m of the origin along each axis");
  if (robot_start) {
    c.finite(robot_start->x(), "robot_start.x");
    c.finite(robot_start->y(), "robot_start.y");
  }
  c.positive(robot_distance, "robot_distance");
  c.non_negative(robot_clearance, "robot_clearance");
  c.require(decimals >= 0 && decimals <= 12, "decimals (", decimals, ") must be between 0 and 12");
  return c.done(error);
}

core::Scenario scenario_from_recorded_path(const core::Scenario& world, const std::vector<TargetWaypoint>& samples,
                                           const RecordedPathSettings& settings, const std::string& name,
                                           RecordedPathReport* report) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("recorded path: " + error);
  // Into the world's frame, checked there: a far sample (or a far frame) would make coordinates the scenario
  // file and the geometry do not hold.
  const bool moved = settings.rotation != 0.0 || !settings.offset.isZero();
  const double c = std::cos(settings.rotation), sn = std::sin(settings.rotation);
  std::vector<TargetWaypoint> placed = samples;
  for (std::size_t k = 0; k < placed.size(); ++k) {
    TargetWaypoint& w = placed[k];
    if (!std::isfinite(w.time) || !w.position.allFinite())
      throw std::invalid_argument("recorded path: sample " + std::to_string(k) + " is not finite");
    if (moved) w.position = Vec2(c * w.position.x() - sn * w.position.y(), sn * w.position.x() + c * w.position.y()) +
                            settings.offset;
    if (!(w.position.cwiseAbs().maxCoeff() <= kMaxCoordinate))
      throw std::invalid_argument("recorded path: sample " + std::to_string(k) + " lies more than " +
                                  std::to_string(static_cast<long long>(kMaxCoordinate)) + " m from the origin " +
                                  "along an axis" + (moved ? " once placed by the frame" : "") +
                                  ": is the position in metres, in the world's frame?");
    if (k > 0 && !(w.time > placed[k - 1].time))
      throw std::invalid_argument("recorded path: times must strictly increase (sample " + std::to_string(k) + ")");
  }

  // The stretch: the samples within [from, to].
  const auto first = std::lower_bound(placed.cbegin(), placed.cend(), settings.from,
                                      [](const TargetWaypoint& w, double t) { return w.time < t; });
  const auto last = std::upper_bound(placed.cbegin(), placed.cend(), settings.to,
                                     [](double t, const TargetWaypoint& w) { return t < w.time; });
  const std::vector<TargetWaypoint> stretch(first, std::max(first, last));
  if (stretch.size() < 2)
    throw std::runtime_error("recorded path: the stretch from " + std::to_string(settings.from) + " to " +
                             std::to_string(settings.to) + " s holds " + std::to_string(stretch.size()) +
                             " samples of the recording; at least two are needed");
  const double t0 = stretch.front().time, span = stretch.back().time - t0;
  if (!std::isfinite(span)) throw std::runtime_error("recorded path: the stretch's span of time is not finite");

  std::vector<TargetWaypoint> path;
  if (settings.period == 0.0) {
    for (const TargetWaypoint& w : stretch) {
      // Shifted, two times far from the first can round to one (a clock at -1e9 s, samples 1e-7 s apart).
      if (!path.empty() && !(w.time - t0 > path.back().time))
        throw std::runtime_error("recorded path: two samples' times, " + std::to_string(w.time) +
                                 " s and the one before, are too close to tell apart from the stretch's start; "
                                 "resample (a period) instead");
      path.push_back({w.time - t0, rounded(w.position, settings.decimals)});
    }
  } else {
    if (!(span / settings.period <= kMaxWaypoints))
      throw std::runtime_error("recorded path: the stretch lasts " + std::to_string(span) + " s, more than " +
                               std::to_string(static_cast<long long>(kMaxWaypoints)) + " waypoints at " +
                               std::to_string(settings.period) +
                               " s: is the time in seconds (the time scale)? Choose a stretch (from, to) or a "
                               "longer period");
    // A wall clock's times (1.7e9 s, spaced to 2.4e-7 s) make a 10 s stretch 9.9999998 s long: the grid may end
    // up to a thousandth of a period after the last sample, where the path holds it.
    const long long steps = static_cast<long long>(std::floor(span / settings.period + 1e-3));
    if (steps < 1)
      throw std::runtime_error("recorded path: the stretch lasts " + std::to_string(span) +
                               " s, shorter than one period (" + std::to_string(settings.period) + " s)");
    std::size_t k = 0;
    for (long long i = 0; i <= steps; ++i) {
      const double t = generator::round_to(static_cast<double>(i) * settings.period, 6);
      path.push_back({t, rounded(position_at(stretch, t0 + t, k), settings.decimals)});
    }
  }

  // The robot's start, by the generator's rule unless given.
  TargetSettings t;
  t.robot_radius = world.robot_radius;
  t.target_radius = world.target_radius;
  t.robot_distance = settings.robot_distance;
  t.robot_clearance = settings.robot_clearance;
  t.decimals = settings.decimals > 0 ? settings.decimals : 12;
  Vec2 low = path.front().position, high = low;
  for (const TargetWaypoint& w : path) low = low.cwiseMin(w.position), high = high.cwiseMax(w.position);
  const double room = settings.robot_distance + world.robot_radius + 1.0;  // the area only bounds the robot here
  t.area_width = high.x() - low.x() + 2.0 * room;
  t.area_height = high.y() - low.y() + 2.0 * room;
  t.area_center_x = 0.5 * (low.x() + high.x());
  t.area_center_y = 0.5 * (low.y() + high.y());
  Vec2 robot = Vec2::Zero();
  if (settings.robot_start) {
    robot = *settings.robot_start;
  } else {
    std::vector<Vec2> positions;
    positions.reserve(path.size());
    for (const TargetWaypoint& w : path) positions.push_back(w.position);
    // The generator's rule, turned further round where it finds no room (up to 3.1 rad, straight ahead): a
    // recording may start beside a wall where the generator would not start.
    generator::TargetChecks checks(world, t);
    if (!checks.place_robot(positions, 0.0, robot, 3.1)) {
      char why[200];
      std::snprintf(why, sizeof why,
                    "recorded path: no robot start %g m from the target's first position (%g, %g) is %g m clear of "
                    "every obstacle and in sight of the target; give the robot's start",
                    settings.robot_distance, positions.front().x(), positions.front().y(), settings.robot_clearance);
      throw std::runtime_error(why);
    }
  }

  t.duration = path.back().time;
  t.sensor = world.sensor;
  core::Scenario s = generator::episode_scenario(world, t, name, std::move(path), robot);
  World w(s);
  const double robot_clearance = w.clearance(robot, 0.0) - s.robot_radius;
  if (!(robot_clearance >= 0.0))
    throw std::runtime_error("recorded path: the robot's start (" + std::to_string(robot.x()) + ", " +
                             std::to_string(robot.y()) + ") overlaps an obstacle by " +
                             std::to_string(-robot_clearance) + " m");
  if (report) {
    *report = RecordedPathReport{};
    report->samples_used = static_cast<int>(stretch.size());
    for (std::size_t k = 1; k < s.target.size(); ++k)
      report->top_speed = std::max(report->top_speed, (s.target[k].position - s.target[k - 1].position).norm() /
                                                          (s.target[k].time - s.target[k - 1].time));
    // Every 0.05 s; coarser on a path longer than kMaxWaypoints of them (only with every sample kept).
    const double step = std::max(kOverlapStep, s.duration / kMaxWaypoints);
    const long long checks = static_cast<long long>(std::floor(s.duration / step + 1e-9));
    for (long long i = 0; i <= checks; ++i) {
      const double time = static_cast<double>(i) * step;
      if (w.clearance(w.target_position(time), time) >= s.target_radius) continue;
      report->overlap_time += step;
      if (std::isnan(report->first_overlap)) report->first_overlap = time;
    }
    report->robot_sees_target = !w.segment_blocked(robot, w.target_position(0.0), 0.0);
    report->robot_clearance = robot_clearance;
  }
  return s;
}

}  // namespace occtrack::sim
