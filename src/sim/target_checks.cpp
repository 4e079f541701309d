// The rules every generated target path keeps, and the robot's start (src/sim/target_checks.hpp).
#include "target_checks.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "../core/no_fma.hpp"
#include "generator_support.hpp"
#include "occtrack/core/geometry.hpp"

OCCTRACK_NO_FMA_CONTRACTION

namespace occtrack::sim::generator {

namespace {

// The world with a placeholder target, so that World accepts it (only its obstacles are asked about).
core::Scenario with_dummy_target(const core::Scenario& world) {
  core::Scenario s = world;
  s.duration = 1.0;
  s.target = {{0.0, Vec2::Zero()}};
  return s;
}

}  // namespace

TargetChecks::TargetChecks(const core::Scenario& world, const TargetSettings& t)
    : t_(t),
      world_(with_dummy_target(world)),
      statics_(static_shapes(world)),
      center_(t.area_center_x, t.area_center_y),
      half_w_(0.5 * t.area_width - t.area_margin),
      half_h_(0.5 * t.area_height - t.area_margin) {
  for (std::size_t k = 0; k < world.obstacles.size(); ++k)
    if (world.obstacles[k].moving()) moving_index_.push_back(k);
}

std::vector<Shape> TargetChecks::static_shapes(const core::Scenario& world, const Vec2& shift) {
  std::vector<Shape> shapes;
  for (const core::ObstacleSpec& o : world.obstacles)
    if (!o.moving()) {
      Shape shape = shape_of(o);
      shape.center += shift;
      shapes.push_back(shape);
    }
  return shapes;
}

bool TargetChecks::static_clear(const Vec2& a, const Vec2& b, double extra) const {
  if (!inside_area(local(a), half_w_ - extra, half_h_ - extra) || !inside_area(local(b), half_w_ - extra, half_h_ - extra))
    return false;
  const double need = t_.target_radius + t_.static_clearance + extra + 1e-6;
  const double reach = (b - a).norm();
  for (const Shape& s : statics_) {
    if ((s.center - a).norm() - bounding_radius(s) - reach > need) continue;
    if (segment_gap(s, a, b) < need) return false;
  }
  return true;
}

bool TargetChecks::moving_clear(const Vec2& a, const Vec2& b, double t0, double t1, double extra) {
  if (moving_index_.empty()) return true;
  const int samples = std::max(1, static_cast<int>(std::ceil((t1 - t0) / 0.025 - 1e-9)));
  for (int i = 0; i <= samples; ++i) {
    const double alpha = static_cast<double>(i) / samples;
    const Vec2 p = a + alpha * (b - a);
    const std::vector<Shape>& shapes = world_.shapes_at(t0 + alpha * (t1 - t0));
    for (const std::size_t k : moving_index_) {
      const Shape& m = shapes[k];
      // Circles (generate_world's moving obstacles) by their centre distance; any other shape (the paper's
      // sliding six-wall world moves boxes) by shape_gap.
      double gap;
      if (m.kind == core::ObstacleSpec::Shape::circle) {
        gap = (p - m.center).norm() - m.radius - t_.target_radius;
      } else {
        Shape disk;
        disk.center = p;
        disk.radius = t_.target_radius;
        gap = shape_gap(m, disk);
      }
      if (gap < t_.moving_clearance + extra) return false;
    }
  }
  return true;
}

Vec2 TargetChecks::robot_behind(const Vec2& target, double heading) const {
  return round_to(target - t_.robot_distance * core::direction(heading), t_.decimals);
}

bool TargetChecks::robot_fits(const Vec2& robot, const Vec2& target) {
  const double half_w = 0.5 * t_.area_width - t_.robot_radius, half_h = 0.5 * t_.area_height - t_.robot_radius;
  return inside_area(local(robot), half_w, half_h) &&
         world_.clearance(robot, 0.0) >= t_.robot_radius + t_.robot_clearance &&
         !world_.segment_blocked(robot, target, 0.0);
}

bool TargetChecks::place_robot(const std::vector<Vec2>& path, double heading, Vec2& robot, double widest_turn) {
  const Vec2 start = path.front();
  for (const Vec2& p : path)
    if ((p - start).norm() >= 0.5) {
      heading = std::atan2(p.y() - start.y(), p.x() - start.x());
      break;
    }
  // Turns 0, 0.1, -0.1, 0.2, -0.2, ... (k / 10.0 is the double of the literal 0.k, as the list this replaced).
  for (int k = 0; k / 10.0 <= widest_turn + 1e-9; ++k)
    for (const double turn : {k / 10.0, -k / 10.0}) {
      robot = robot_behind(start, heading + turn);
      if (robot_fits(robot, start)) return true;
      if (k == 0) break;
    }
  return false;
}

core::Scenario episode_scenario(const core::Scenario& world, const TargetSettings& t, const std::string& name,
                                std::vector<core::TargetWaypoint> target, const Vec2& robot) {
  core::Scenario s;
  s.name = name;
  s.duration = t.duration;
  s.obstacles = world.obstacles;
  s.robot_radius = t.robot_radius;
  s.target_radius = t.target_radius;
  s.sensor = t.sensor;
  s.target = std::move(target);
  s.robot_position = robot;
  s.robot_velocity = Vec2::Zero();
  return s;
}

double advance_on_route(const std::vector<Vec2>& route, std::size_t& index, const Vec2& p) {
  double best = (route[index] - p).norm();
  const std::size_t end = std::min(route.size(), index + 40);
  for (std::size_t j = index + 1; j < end; ++j)
    if (const double r = (route[j] - p).norm(); r < best) best = r, index = j;
  return best;
}

double route_heading(const std::vector<Vec2>& route, std::size_t index, const Vec2& p, double lookahead,
                     double fallback) {
  std::size_t j = index;
  for (double along = 0.0; j + 1 < route.size() && along < lookahead; ++j) along += (route[j + 1] - route[j]).norm();
  const Vec2 to = route[j] - p;
  return to.squaredNorm() > 1e-12 ? std::atan2(to.y(), to.x()) : fallback;
}

}  // namespace occtrack::sim::generator
