// Worlds of the scenario generator (include/occtrack/sim/scenario_generator.hpp): static obstacles by
// rejection sampling under an exact surface-to-surface gap; moving obstacles as circles whose whole swept
// lane keeps a gap from the static obstacles and from the other lanes. Numbers are rounded before they are
// checked, so that the checks hold for exactly what is written.
#include <algorithm>
#include <numbers>
#include <stdexcept>
#include <string>

#include "../core/no_fma.hpp"
#include "generator_support.hpp"
#include "occtrack/sim/geometry.hpp"
#include "occtrack/sim/scenario_generator.hpp"

OCCTRACK_NO_FMA_CONTRACTION

namespace occtrack::sim {

namespace {

using generator::inside_area;
using generator::Random;
using generator::round_to;
using core::direction;
using Spec = core::ObstacleSpec;
constexpr double kPi = std::numbers::pi;

Spec draw_static_obstacle(const GeneratorSettings& s, Random& rng) {
  const WorldStyle& style = s.style;
  const bool box = style.kind == WorldKind::boxes || (style.kind == WorldKind::mixed && rng.chance(style.box_share));
  Spec o;
  double bound = 0.0;
  if (box) {
    o.shape = Spec::Shape::box;
    o.size = Vec2(round_to(rng.uniform(style.box_side_min, style.box_side_max), s.decimals),
                  round_to(rng.uniform(style.box_side_min, style.box_side_max), s.decimals));
    o.yaw = round_to(rng.uniform(0.0, kPi), s.decimals);
    bound = 0.5 * o.size.norm();
  } else {
    o.shape = Spec::Shape::circle;
    o.radius = round_to(rng.uniform(style.circle_radius_min, style.circle_radius_max), s.decimals);
    bound = o.radius;
  }
  // The bounding circle inside the area less the margin, so that the whole shape is.
  const double half_w = std::max(0.0, 0.5 * s.area_width - s.boundary_margin - bound);
  const double half_h = std::max(0.0, 0.5 * s.area_height - s.boundary_margin - bound);
  o.center = round_to(Vec2(rng.uniform(-half_w, half_w), rng.uniform(-half_h, half_h)), s.decimals);
  return o;
}

std::vector<Vec2> draw_moving_path(const GeneratorSettings& s, double radius, Random& rng) {
  const double length = rng.uniform(s.moving_path_min, s.moving_path_max);
  const double half_w = 0.5 * s.area_width - s.boundary_margin - radius;
  const double half_h = 0.5 * s.area_height - s.boundary_margin - radius;
  const Vec2 start(rng.uniform(-half_w, half_w), rng.uniform(-half_h, half_h));
  const double heading = rng.uniform(-kPi, kPi);
  std::vector<Vec2> path{round_to(start, s.decimals)};
  if (rng.chance(s.moving_two_segment_share)) {
    const double first = length * rng.uniform(0.35, 0.65);
    const double turn = (rng.chance(0.5) ? 1.0 : -1.0) * rng.uniform(kPi / 6.0, 2.0 * kPi / 3.0);
    const Vec2 corner = start + first * direction(heading);
    path.push_back(round_to(corner, s.decimals));
    path.push_back(round_to(corner + (length - first) * direction(heading + turn), s.decimals));
  } else {
    path.push_back(round_to(start + length * direction(heading), s.decimals));
  }
  return path;
}

// Static obstacles, each at least min_gap from every other; their shapes are appended to `placed`.
void place_static_obstacles(const GeneratorSettings& settings, Random& rng, core::Scenario& world,
                            std::vector<Shape>& placed) {
  int attempts = 0;
  while (static_cast<int>(placed.size()) < settings.static_obstacles) {
    if (++attempts > settings.max_attempts)
      throw std::runtime_error("generate_world: placed only " + std::to_string(placed.size()) + " of " +
                               std::to_string(settings.static_obstacles) + " static obstacles with a gap of " +
                               std::to_string(settings.min_gap) + " m; lower the count or the gap");
    const Spec candidate = draw_static_obstacle(settings, rng);
    const Shape shape = shape_of(candidate);
    bool fits = true;
    for (const Shape& other : placed) {
      if ((shape.center - other.center).norm() - bounding_radius(shape) - bounding_radius(other) >= settings.min_gap)
        continue;
      if (shape_gap(shape, other) < settings.min_gap) {
        fits = false;
        break;
      }
    }
    if (!fits) continue;
    placed.push_back(shape);
    world.obstacles.push_back(candidate);
  }
}

// Moving obstacles whose swept lanes keep moving_gap from the static obstacles and from each other.
void place_moving_obstacles(const GeneratorSettings& settings, Random& rng, const std::vector<Shape>& statics,
                            core::Scenario& world) {
  std::vector<std::vector<Vec2>> lanes;
  std::vector<double> lane_radii;
  int attempts = 0;
  while (static_cast<int>(lanes.size()) < settings.moving_obstacles) {
    if (++attempts > settings.max_attempts)
      throw std::runtime_error("generate_world: placed only " + std::to_string(lanes.size()) + " of " +
                               std::to_string(settings.moving_obstacles) + " moving obstacles");
    const double radius = round_to(rng.uniform(settings.moving_radius_min, settings.moving_radius_max),
                                   settings.decimals);
    const std::vector<Vec2> path = draw_moving_path(settings, radius, rng);
    const double half_w = 0.5 * settings.area_width - settings.boundary_margin - radius;
    const double half_h = 0.5 * settings.area_height - settings.boundary_margin - radius;
    bool fits = std::all_of(path.begin(), path.end(), [&](const Vec2& p) { return inside_area(p, half_w, half_h); });
    for (std::size_t k = 0; fits && k < statics.size(); ++k)
      fits = polyline_gap(statics[k], path) - radius >= settings.moving_gap;
    for (std::size_t k = 0; fits && k < lanes.size(); ++k)
      fits = polyline_distance(lanes[k], path) - radius - lane_radii[k] >= settings.moving_gap;
    if (!fits) continue;
    lanes.push_back(path);
    lane_radii.push_back(radius);
    Spec o;
    o.shape = Spec::Shape::circle;
    o.radius = radius;
    o.center = path.front();
    o.path = path;
    o.speed = settings.moving_speed;
    world.obstacles.push_back(o);
  }
}

}  // namespace

core::Scenario generate_world(const GeneratorSettings& settings, std::uint64_t world_seed) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("generate_world: " + error);
  Random rng(world_seed);
  core::Scenario world;
  world.name = "world-" + std::to_string(world_seed);
  std::vector<Shape> statics;
  place_static_obstacles(settings, rng, world, statics);
  place_moving_obstacles(settings, rng, statics, world);
  return world;
}

}  // namespace occtrack::sim
