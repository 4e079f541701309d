// The simulated world (shared/spec/simulation.md, "Simulation semantics"): obstacle and target motion, the
// LiDAR, and the exact queries of the metrics, on the shapes of sim/geometry.
//
// The scan is the hot path of the benchmark (720 beams, about 50 shapes, 20 times per simulated second, hours
// of simulated time). Rather than testing every beam against every shape, each shape visits only the beams
// inside the angular span of its bounding circle as seen from the sensor; a beam keeps the nearest hit. The
// result is the same as the per-beam loop (min is exact and order-free), at a few per cent of the cost.
#include "occtrack/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace occtrack::sim {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

[[noreturn]] void invalid(const std::string& field, const std::string& rule) {
  throw std::invalid_argument("sim::World: scenario." + field + ": " + rule);
}

bool finite(const Vec2& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); }

void check_scenario(const core::Scenario& s) {
  if (!(std::isfinite(s.duration) && s.duration > 0.0)) invalid("duration", "must be a positive number");
  for (std::size_t k = 0; k < s.obstacles.size(); ++k) {
    const core::ObstacleSpec& o = s.obstacles[k];
    const std::string name = "obstacles[" + std::to_string(k) + "]";
    if (!finite(o.center)) invalid(name + ".center", "must be finite");
    if (o.shape == core::ObstacleSpec::Shape::circle) {
      if (!(std::isfinite(o.radius) && o.radius > 0.0)) invalid(name + ".radius", "must be positive");
    } else {
      if (!(finite(o.size) && o.size.x() > 0.0 && o.size.y() > 0.0)) invalid(name + ".size", "must be positive");
      if (!std::isfinite(o.yaw)) invalid(name + ".yaw", "must be finite");
    }
    if (!(std::isfinite(o.speed) && o.speed >= 0.0)) invalid(name + ".speed", "must be finite and >= 0");
    if (o.path.size() == 1) invalid(name + ".path", "needs at least 2 points");
    for (const Vec2& point : o.path)
      if (!finite(point)) invalid(name + ".path", "must be finite");
  }
  if (!finite(s.robot_position) || !finite(s.robot_velocity)) invalid("robot", "must be finite");
  if (!(std::isfinite(s.robot_radius) && s.robot_radius > 0.0)) invalid("robot_radius", "must be positive");
  if (!(std::isfinite(s.target_radius) && s.target_radius > 0.0)) invalid("target_radius", "must be positive");
  if (s.target.empty()) invalid("target", "needs at least one waypoint");
  for (std::size_t k = 0; k < s.target.size(); ++k) {
    if (!std::isfinite(s.target[k].time) || !finite(s.target[k].position))
      invalid("target[" + std::to_string(k) + "]", "must be finite");
    if (k > 0 && !(s.target[k].time > s.target[k - 1].time))
      invalid("target[" + std::to_string(k) + "].time", "must be strictly increasing");
  }
  if (s.sensor.beams < 1) invalid("sensor.beams", "must be at least 1");
  if (!(std::isfinite(s.sensor.range) && s.sensor.range > 0.0)) invalid("sensor.range", "must be positive");
  if (!(std::isfinite(s.sensor.noise) && s.sensor.noise >= 0.0)) invalid("sensor.noise", "must be >= 0");
  if (!(s.sensor.dropout >= 0.0 && s.sensor.dropout <= 1.0)) invalid("sensor.dropout", "must be in [0, 1]");
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// World.

World::World(const core::Scenario& scenario) : scenario_(scenario) {
  check_scenario(scenario_);
  const std::size_t count = scenario_.obstacles.size();
  shapes_.resize(count);
  path_lengths_.assign(count, 0.0);
  path_arc_.resize(count);
  bounding_radius_.resize(count);
  box_axis_.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const core::ObstacleSpec& spec = scenario_.obstacles[k];
    shapes_[k] = shape_of(spec);
    box_axis_[k] = box_axis(shapes_[k]);
    bounding_radius_[k] = bounding_radius(shapes_[k]);
    if (!spec.moving()) continue;
    std::vector<double>& arc = path_arc_[k];
    arc.assign(1, 0.0);
    for (std::size_t j = 1; j < spec.path.size(); ++j)
      arc.push_back(arc.back() + (spec.path[j] - spec.path[j - 1]).norm());
    path_lengths_[k] = arc.back();
    if (path_lengths_[k] > 0.0) moving_.push_back(k);  // a path of zero length leaves the obstacle where it is
  }

  beam_directions_.resize(static_cast<std::size_t>(scenario_.sensor.beams));
  const double increment = 2.0 * std::numbers::pi / scenario_.sensor.beams;
  for (std::size_t i = 0; i < beam_directions_.size(); ++i) {
    beam_directions_[i] = core::direction(static_cast<double>(i) * increment);
  }
}

const std::vector<Shape>& World::shapes_at(double t) {
  if (shapes_valid_ && t == shapes_time_) return shapes_;
  for (const std::size_t k : moving_) {
    const core::ObstacleSpec& spec = scenario_.obstacles[k];
    const std::vector<double>& arc = path_arc_[k];
    const double length = path_lengths_[k];
    // Arc length along the path: a triangle wave of period 2L (out along the path, then back).
    double phase = std::fmod(spec.speed * t, 2.0 * length);
    if (phase < 0.0) phase += 2.0 * length;
    const bool outward = phase < length;
    const double s = outward ? phase : 2.0 * length - phase;
    // Segment j-1 -> j holding s, of positive length: the first point beyond s, or at the end the first
    // point that reaches the full length (so that zero-length segments are never chosen).
    auto beyond = std::upper_bound(arc.begin(), arc.end(), s);
    if (beyond == arc.end()) beyond = std::lower_bound(arc.begin(), arc.end(), length);
    const std::size_t j = static_cast<std::size_t>(beyond - arc.begin());
    const double segment_length = arc[j] - arc[j - 1];
    const Vec2 direction = (spec.path[j] - spec.path[j - 1]) / segment_length;
    const Vec2 position = spec.path[j - 1] + (s - arc[j - 1]) * direction;
    shapes_[k].center = spec.center + (position - spec.path.front());
    shapes_[k].velocity = (outward ? spec.speed : -spec.speed) * direction;
  }
  shapes_time_ = t;
  shapes_valid_ = true;
  return shapes_;
}

Vec2 World::target_position(double t) const {
  const std::vector<core::TargetWaypoint>& path = scenario_.target;
  if (!(t > path.front().time)) return path.front().position;  // also for a NaN time
  if (!(t < path.back().time)) return path.back().position;
  const auto next = std::upper_bound(path.begin(), path.end(), t,
                                     [](double time, const core::TargetWaypoint& w) { return time < w.time; });
  const core::TargetWaypoint& a = *(next - 1);
  const core::TargetWaypoint& b = *next;
  const double alpha = (t - a.time) / (b.time - a.time);
  return a.position + alpha * (b.position - a.position);
}

Vec2 World::target_velocity(double t) const {
  const std::vector<core::TargetWaypoint>& path = scenario_.target;
  if (!(t >= path.front().time && t < path.back().time)) return Vec2::Zero();
  const auto next = std::upper_bound(path.begin(), path.end(), t,
                                     [](double time, const core::TargetWaypoint& w) { return time < w.time; });
  const core::TargetWaypoint& a = *(next - 1);
  const core::TargetWaypoint& b = *next;
  return (b.position - a.position) / (b.time - a.time);
}

core::Scan World::scan(const Vec2& position, double t, std::mt19937_64& rng) {
  core::Scan out;
  scan(position, t, rng, out);
  return out;
}

void World::scan(const Vec2& position, double t, std::mt19937_64& rng, core::Scan& out) {
  const int beams = scenario_.sensor.beams;
  const double range = scenario_.sensor.range;
  const double increment = 2.0 * std::numbers::pi / beams;
  out.angle_min = 0.0;
  out.angle_increment = increment;
  out.range_max = range;
  out.time = t;
  out.ranges.assign(static_cast<std::size_t>(beams), kInfinity);

  const std::vector<Shape>& shapes = shapes_at(t);
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const Shape& shape = shapes[k];
    const Vec2 offset = shape.center - position;
    const double distance = offset.norm();
    // A hair larger than the shape, so that rounding in the span below never drops a grazing beam.
    const double bound = bounding_radius_[k] * (1.0 + 1e-12) + 1e-12;
    const double nearest_possible = distance - bound;
    if (nearest_possible > range) continue;

    // Beams j in [first, last] (modulo beams) can meet the bounding circle; all of them when the sensor is
    // inside it. floor/ceil widen the span by up to a beam on each side; the exact test below decides.
    long first = 0, last = beams - 1;
    if (distance > bound) {
      const double half_width = std::asin(bound / distance);
      const double bearing = std::atan2(offset.y(), offset.x());
      const double lo = std::floor((bearing - half_width) / increment);
      const double hi = std::ceil((bearing + half_width) / increment);
      if (hi - lo + 1.0 < beams) {
        first = static_cast<long>(lo);
        last = static_cast<long>(hi);
      }
    }
    for (long j = first; j <= last; ++j) {
      long i = j % beams;
      if (i < 0) i += beams;
      double& hit = out.ranges[static_cast<std::size_t>(i)];
      if (nearest_possible >= hit) continue;  // this beam already hit something nearer
      const Vec2& direction = beam_directions_[static_cast<std::size_t>(i)];
      hit = std::min(hit, ray_distance(shape, box_axis_[k], position, direction, range));
    }
  }

  // Range noise on returns only, beam by beam in order (so a seed fixes the scan); never below zero.
  const double noise = scenario_.sensor.noise;
  if (noise > 0.0) {
    std::normal_distribution<double> gaussian(0.0, noise);
    for (double& r : out.ranges)
      if (std::isfinite(r)) r = std::max(0.0, r + gaussian(rng));
  }

  // Dropout (Protocol v2): a dropped beam returns nothing. One draw per beam whatever it hit, so that the
  // stream's position depends only on the number of scans.
  const double dropout = scenario_.sensor.dropout;
  if (dropout > 0.0) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (double& r : out.ranges)
      if (uniform(dropout_rng_) < dropout) r = kInfinity;
  }
}

bool World::segment_blocked(const Vec2& a, const Vec2& b, double t) {
  const std::vector<Shape>& shapes = shapes_at(t);
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const Shape& shape = shapes[k];
    // Boxes: the bounding circle first (a box the segment passes far from costs one distance).
    if (shape.kind == core::ObstacleSpec::Shape::box &&
        core::point_segment_distance(shape.center, a, b) > bounding_radius_[k])
      continue;
    if (segment_intersects(shape, box_axis_[k], a, b)) return true;
  }
  return false;
}

double World::clearance(const Vec2& p, double t) {
  const std::vector<Shape>& shapes = shapes_at(t);
  double best = kInfinity;
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const Shape& shape = shapes[k];
    const double centre_distance = (p - shape.center).norm();
    if (centre_distance - bounding_radius_[k] >= best) continue;  // cannot be nearer than the best so far
    best = std::min(best, signed_distance(shape, box_axis_[k], p));
  }
  return best;
}

}  // namespace occtrack::sim
