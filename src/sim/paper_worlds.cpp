// The paper's worlds (include/occtrack/sim/paper_worlds.hpp), transcribed from shared/reference/paper_setup.md.
#include "occtrack/sim/paper_worlds.hpp"

#include <cmath>

#include "../core/no_fma.hpp"

// As the generator's files (generator_support.hpp): the sliding walls' path ends are the same on every
// instruction set.
OCCTRACK_NO_FMA_CONTRACTION

namespace occtrack::sim {

namespace {

using core::ObstacleSpec;
using core::Vec2;

// paper_setup.md, "Six-wall world": centre x, y and yaw (rad) of walls 1 to 6.
struct WallPose {
  double x, y, yaw;
};
constexpr WallPose kSixWalls[] = {
    {1.00, 0.00, 1.0}, {5.20, 0.65, -1.0}, {-1.32, 2.20, 1.0}, {2.50, 4.37, -1.0}, {2.88, -3.50, 1.0}, {-1.47, -3.20, 1.0},
};
constexpr double kWallLength = 1.6;
constexpr double kWallThickness = 0.7;

// paper_setup.md, "Random world, obstacle by obstacle".
struct CylinderPose {
  double x, y, radius;
};
constexpr CylinderPose kRandomCylinders[] = {
    {-0.097, 0.931, 0.5},    {0.141, -4.064, 0.665},  {-6.509, -3.000, 0.665}, {9.243, -4.851, 0.665},
    {5.037, -5.852, 0.665},  {-2.904, 11.198, 0.665}, {6.000, 13.000, 0.665},  {7.283, 8.069, 0.665},
    {-9.300, 11.445, 0.665}, {-13.878, 0.842, 0.665}, {-14.350, 5.738, 0.665}, {-13.254, 9.250, 0.665},
    {-3.527, -9.601, 0.665}, {1.647, -9.972, 0.665},  {-2.711, -5.181, 0.665}, {-11.669, -5.726, 0.665},
};
struct BoxPose {
  double x, y, size_x, size_y;
};
constexpr BoxPose kRandomBoxes[] = {
    {-3.986, -1.603, 1.0, 1.0},     {-5.834, 1.692, 1.541, 1.0},    {-5.186, 5.886, 1.541, 1.0},
    {2.026, 7.175, 1.541, 1.0},     {4.232, 3.635, 1.541, 1.0},     {6.000, -1.000, 1.541, 1.0},
    {-9.475, -1.499, 1.541, 1.0},   {-10.000, 3.000, 1.541, 1.0},   {-9.689, 6.680, 1.541, 1.0},
    {10.560, 5.000, 1.541, 1.0},    {7.566, -10.647, 1.541, 1.622}, {1.443, -7.228, 1.541, 1.622},
    {2.733, -1.566, 1.541, 1.622},  {-1.390, 3.934, 1.541, 1.622},  {10.149, 1.091, 1.541, 1.622},
    {13.435, -2.919, 1.541, 1.622}, {11.770, -9.262, 1.541, 1.622}, {-9.000, -10.000, 1.541, 1.622},
    {2.093, 10.923, 1.541, 1.622},  {-6.630, -6.247, 1.541, 1.0},
};

// Path ends are written with 4 decimals, as the generator's numbers are.
double round4(double v) { return std::round(v * 1e4) / 1e4; }

}  // namespace

core::Scenario six_wall_world(bool sliding) {
  core::Scenario world;
  world.name = sliding ? "six-wall-sliding" : "six-wall";
  world.robot_position = six_wall_start().robot;
  Vec2 centroid = Vec2::Zero();
  for (const WallPose& w : kSixWalls) centroid += Vec2(w.x, w.y);
  centroid /= static_cast<double>(std::size(kSixWalls));
  for (const WallPose& w : kSixWalls) {
    ObstacleSpec o;
    o.shape = ObstacleSpec::Shape::box;
    o.center = Vec2(w.x, w.y);
    o.size = Vec2(kWallLength, kWallThickness);
    o.yaw = w.yaw;
    if (sliding) {
      // Along the wall's long axis, away from the centroid (paper_worlds.hpp says why this motion).
      Vec2 axis(std::cos(w.yaw), std::sin(w.yaw));
      if (axis.dot(o.center - centroid) < 0.0) axis = -axis;
      const Vec2 end = o.center + kSixWallSlideLength * axis;
      o.path = {o.center, Vec2(round4(end.x()), round4(end.y()))};
      o.speed = kSixWallSlideSpeed;
    }
    world.obstacles.push_back(o);
  }
  return world;
}

PaperStart six_wall_start() { return {Vec2(4.0, -2.0), Vec2(3.0, -1.0)}; }

core::Scenario random_world() {
  core::Scenario world;
  world.name = "random";
  world.robot_position = random_world_start().robot;
  for (const CylinderPose& c : kRandomCylinders) {
    ObstacleSpec o;
    o.shape = ObstacleSpec::Shape::circle;
    o.center = Vec2(c.x, c.y);
    o.radius = c.radius;
    world.obstacles.push_back(o);
  }
  for (const BoxPose& b : kRandomBoxes) {
    ObstacleSpec o;
    o.shape = ObstacleSpec::Shape::box;
    o.center = Vec2(b.x, b.y);
    o.size = Vec2(b.size_x, b.size_y);
    world.obstacles.push_back(o);
  }
  return world;
}

PaperStart random_world_start() { return {Vec2(-3.0, 0.0), Vec2(-0.6, -1.0)}; }

std::optional<core::Scenario> paper_world(std::string_view name) {
  if (name == "six-wall" || name == "six-wall-sliding") return six_wall_world(name == "six-wall-sliding");
  if (name == "random") return random_world();
  return std::nullopt;
}

WorldArea six_wall_area() { return {15.0, 16.0, 2.0, 0.5}; }
WorldArea random_world_area() { return {31.0, 27.0, -0.5, 1.2}; }

TargetSettings teleop_target_in(const WorldArea& area, double nominal_speed, double duration) {
  TargetSettings t = teleop_target_settings(nominal_speed);
  t.duration = duration;
  t.area_width = area.width;
  t.area_height = area.height;
  t.area_center_x = area.center_x;
  t.area_center_y = area.center_y;
  return t;
}

}  // namespace occtrack::sim
