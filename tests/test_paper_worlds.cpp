// The paper's worlds (sim/paper_worlds.hpp) against shared/reference/paper_setup.md: counts, coordinates,
// the spacing the reference states, no overlaps, and the sliding walls' motion, measured with the simulator's
// own World and the generator's gap functions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <filesystem>
#include <limits>
#include <string>

#include "occtrack/io/scenario.hpp"
#include "occtrack/sim/geometry.hpp"
#include "occtrack/sim/paper_worlds.hpp"
#include "occtrack/sim/scenario_generator.hpp"
#include "occtrack/sim/world.hpp"

namespace {

using occtrack::core::ObstacleSpec;
using occtrack::core::Scenario;
using occtrack::core::Vec2;
namespace sim = occtrack::sim;

// World needs a duration and a target; the worlds carry obstacles only.
Scenario runnable(Scenario world, double duration) {
  world.duration = duration;
  world.target = {{0.0, Vec2(100.0, 100.0)}};
  return world;
}

double smallest_gap(const std::vector<sim::Shape>& shapes) {
  double gap = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < shapes.size(); ++i)
    for (std::size_t j = i + 1; j < shapes.size(); ++j) gap = std::min(gap, sim::shape_gap(shapes[i], shapes[j]));
  return gap;
}

TEST(PaperWorlds, SixWallIsTheTable) {
  const Scenario world = sim::six_wall_world();
  EXPECT_EQ(world.name, "six-wall");
  ASSERT_EQ(world.obstacles.size(), 6u);
  for (const ObstacleSpec& o : world.obstacles) {
    EXPECT_EQ(o.shape, ObstacleSpec::Shape::box);
    EXPECT_EQ(o.size, Vec2(1.6, 0.7));
    EXPECT_FALSE(o.moving());
  }
  EXPECT_EQ(world.obstacles[0].center, Vec2(1.0, 0.0));
  EXPECT_EQ(world.obstacles[0].yaw, 1.0);
  EXPECT_EQ(world.obstacles[3].center, Vec2(2.5, 4.37));
  EXPECT_EQ(world.obstacles[3].yaw, -1.0);
  EXPECT_EQ(world.obstacles[5].center, Vec2(-1.47, -3.2));
  EXPECT_EQ(world.robot_position, Vec2(4.0, -2.0));
  EXPECT_EQ(sim::six_wall_start().target, Vec2(3.0, -1.0));
  // "Gaps between walls are 2.4 to 3.0 m": the nearest neighbour of every wall is that far.
  sim::World w(runnable(world, 1.0));
  EXPECT_GT(w.clearance(sim::six_wall_start().robot, 0.0), 0.5);
  EXPECT_GT(w.clearance(sim::six_wall_start().target, 0.0), 0.5);
  EXPECT_FALSE(w.segment_blocked(sim::six_wall_start().robot, sim::six_wall_start().target, 0.0));
  std::vector<sim::Shape> shapes;
  for (const ObstacleSpec& o : world.obstacles) shapes.push_back(sim::shape_of(o));
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < shapes.size(); ++j)
      if (j != i) nearest = std::min(nearest, sim::shape_gap(shapes[i], shapes[j]));
    EXPECT_GE(nearest, 2.4) << "wall " << i + 1;
    EXPECT_LE(nearest, 3.05) << "wall " << i + 1;
  }
}

TEST(PaperWorlds, SlidingWallsMoveAtTheirSpeedAndStayApart) {
  const Scenario world = sim::six_wall_world(true);
  EXPECT_EQ(world.name, "six-wall-sliding");
  ASSERT_EQ(world.obstacles.size(), 6u);
  const Scenario fixed = sim::six_wall_world(false);
  for (std::size_t k = 0; k < 6; ++k) {
    const ObstacleSpec& o = world.obstacles[k];
    ASSERT_TRUE(o.moving()) << k;
    EXPECT_EQ(o.speed, 0.7);
    EXPECT_EQ(o.center, fixed.obstacles[k].center);  // at t = 0 the table's walls
    ASSERT_EQ(o.path.size(), 2u);
    const Vec2 travel = o.path[1] - o.path[0];
    EXPECT_NEAR(travel.norm(), 2.0, 1e-4) << k;
    // Along the wall's own long axis.
    EXPECT_NEAR(std::abs(travel.normalized().dot(Vec2(std::cos(o.yaw), std::sin(o.yaw)))), 1.0, 1e-4) << k;
  }
  // Wall 1 slides down and to the left: away from the six walls' centroid (1.465, 0.087).
  EXPECT_NEAR(world.obstacles[0].path[1].x(), 1.0 - 2.0 * std::cos(1.0), 1e-4);
  EXPECT_NEAR(world.obstacles[0].path[1].y(), -2.0 * std::sin(1.0), 1e-4);

  // Over two periods (2 x 2 x 2 m / 0.7 m/s), sampled finely: every wall moves at 0.7 m/s (away from the
  // turning points), the walls never come closer than 1.3 m, some gap closes below 1.5 m and some opens
  // beyond 8 m, and no wall comes within 1 m of the paper's starts.
  sim::World w(runnable(world, 20.0));
  const double period = 2.0 * 2.0 / 0.7;
  const double dt = 0.01;
  double closest = std::numeric_limits<double>::infinity(), widest = 0.0;
  double start_clearance = std::numeric_limits<double>::infinity();
  std::vector<sim::Shape> before = w.shapes_at(0.0);
  int speed_checks = 0;
  for (double t = dt; t <= 2.0 * period; t += dt) {
    const std::vector<sim::Shape> now = w.shapes_at(t);
    const double phase = std::fmod(t, period / 2.0);
    for (std::size_t k = 0; k < now.size(); ++k) {
      if (phase > dt && phase < period / 2.0 - dt) {
        EXPECT_NEAR((now[k].center - before[k].center).norm() / dt, 0.7, 1e-6) << "wall " << k + 1 << " t " << t;
        ++speed_checks;
      }
      start_clearance = std::min({start_clearance, sim::signed_distance(now[k], sim::six_wall_start().robot),
                                  sim::signed_distance(now[k], sim::six_wall_start().target)});
    }
    closest = std::min(closest, smallest_gap(now));
    for (std::size_t i = 0; i < now.size(); ++i)
      for (std::size_t j = i + 1; j < now.size(); ++j) widest = std::max(widest, sim::shape_gap(now[i], now[j]));
    before = now;
  }
  EXPECT_GT(speed_checks, 1000);
  EXPECT_GT(closest, 1.3);
  EXPECT_LT(closest, 1.5);
  EXPECT_GT(widest, 8.0);
  EXPECT_GT(start_clearance, 1.0);
}

TEST(PaperWorlds, RandomWorldIsTheTable) {
  const Scenario world = sim::random_world();
  EXPECT_EQ(world.name, "random");
  ASSERT_EQ(world.obstacles.size(), 36u);
  int cylinders = 0, big_cylinders = 0, boxes = 0, narrow_boxes = 0, wide_boxes = 0, square_boxes = 0;
  for (const ObstacleSpec& o : world.obstacles) {
    EXPECT_FALSE(o.moving());
    if (o.shape == ObstacleSpec::Shape::circle) {
      ++cylinders;
      big_cylinders += o.radius == 0.665 ? 1 : 0;
    } else {
      ++boxes;
      EXPECT_EQ(o.yaw, 0.0);
      narrow_boxes += o.size == Vec2(1.541, 1.0) ? 1 : 0;
      wide_boxes += o.size == Vec2(1.541, 1.622) ? 1 : 0;
      square_boxes += o.size == Vec2(1.0, 1.0) ? 1 : 0;
    }
  }
  // "15 cylinders of radius 0.665 m, one of 0.5 m, ten boxes 1.54 x 1.0 m, nine 1.54 x 1.62 m, one 1 x 1 m".
  EXPECT_EQ(cylinders, 16);
  EXPECT_EQ(big_cylinders, 15);
  EXPECT_EQ(boxes, 20);
  EXPECT_EQ(narrow_boxes, 10);
  EXPECT_EQ(wide_boxes, 9);
  EXPECT_EQ(square_boxes, 1);
  EXPECT_EQ(world.obstacles[0].center, Vec2(-0.097, 0.931));
  EXPECT_EQ(world.obstacles[0].radius, 0.5);
  EXPECT_EQ(world.obstacles[15].center, Vec2(-11.669, -5.726));
  EXPECT_EQ(world.obstacles[16].center, Vec2(-3.986, -1.603));
  EXPECT_EQ(world.obstacles[35].center, Vec2(-6.63, -6.247));
  EXPECT_EQ(world.robot_position, Vec2(-3.0, 0.0));
  EXPECT_EQ(sim::random_world_start().target, Vec2(-0.6, -1.0));

  // "Nearest-neighbour centre spacing 2.75 to 5.0 m (median 3.8 m)", and nothing overlaps.
  std::vector<double> nearest;
  Vec2 low(1e9, 1e9), high(-1e9, -1e9);
  for (const ObstacleSpec& o : world.obstacles) {
    double d = std::numeric_limits<double>::infinity();
    for (const ObstacleSpec& p : world.obstacles)
      if (&p != &o) d = std::min(d, (p.center - o.center).norm());
    nearest.push_back(d);
    low = low.cwiseMin(o.center);
    high = high.cwiseMax(o.center);
  }
  std::sort(nearest.begin(), nearest.end());
  EXPECT_NEAR(nearest.front(), 2.75, 0.01);
  EXPECT_NEAR(nearest.back(), 5.0, 0.05);
  EXPECT_NEAR((nearest[17] + nearest[18]) / 2.0, 3.8, 0.1);
  EXPECT_NEAR(low.x(), -14.35, 1e-9);
  EXPECT_NEAR(high.x(), 13.435, 1e-9);
  EXPECT_NEAR(low.y(), -10.647, 1e-9);
  EXPECT_NEAR(high.y(), 13.0, 1e-9);
  std::vector<sim::Shape> shapes;
  for (const ObstacleSpec& o : world.obstacles) shapes.push_back(sim::shape_of(o));
  EXPECT_GT(smallest_gap(shapes), 1.0);
  // Both starts are in free space with a clear line of sight.
  sim::World w(runnable(world, 1.0));
  EXPECT_GT(w.clearance(sim::random_world_start().robot, 0.0), 0.5);
  EXPECT_GT(w.clearance(sim::random_world_start().target, 0.0), 0.5);
  EXPECT_FALSE(w.segment_blocked(sim::random_world_start().robot, sim::random_world_start().target, 0.0));
}

// A tele-operated episode can begin where the paper's did: the target at its start, the robot at its own.
TEST(PaperWorlds, TeleopEpisodesStartAtThePapersStarts) {
  sim::TargetSettings target = sim::teleop_target_in(sim::six_wall_area(), 1.0, 10.0);
  target.start = sim::six_wall_start().target;
  target.robot_start = sim::six_wall_start().robot;
  for (const bool sliding : {false, true}) {
    const Scenario s = sim::generate_episode(sim::six_wall_world(sliding), target, 7, "start");
    EXPECT_EQ(s.target.front().position, Vec2(3.0, -1.0));
    EXPECT_EQ(s.robot_position, Vec2(4.0, -2.0));
    EXPECT_GT((s.target[20].position - s.target.front().position).norm(), 0.5);  // it drives off
  }

  std::string error;
  sim::TargetSettings bad = target;
  bad.start = Vec2(std::numeric_limits<double>::quiet_NaN(), 0.0);
  EXPECT_FALSE(bad.validate(&error));
  EXPECT_NE(error.find("start.x"), std::string::npos) << error;
  sim::TargetSettings smooth;
  smooth.robot_start = Vec2(4.0, -2.0);
  EXPECT_FALSE(smooth.validate(&error));
  EXPECT_NE(error.find("robot_start"), std::string::npos) << error;
}

// The shipped worlds (scenarios/worlds/, scenarios/README.md "Suites v2"): the paper's worlds and starts.
TEST(PaperWorlds, ShippedWorldFiles) {
  const std::filesystem::path root =
      std::filesystem::path(OCCTRACK_TEST_DATA_DIR) / ".." / ".." / "scenarios" / "worlds";
  struct Expected {
    std::string file;
    Scenario world;
    sim::PaperStart start;
  };
  const Expected expected[] = {{"six-wall.yaml", sim::six_wall_world(false), sim::six_wall_start()},
                               {"six-wall-sliding.yaml", sim::six_wall_world(true), sim::six_wall_start()},
                               {"random.yaml", sim::random_world(), sim::random_world_start()}};
  for (const Expected& e : expected) {
    SCOPED_TRACE(e.file);
    const Scenario s = occtrack::io::read_scenario((root / e.file).string());
    ASSERT_EQ(s.obstacles.size(), e.world.obstacles.size());
    for (std::size_t k = 0; k < s.obstacles.size(); ++k) {
      EXPECT_EQ(s.obstacles[k].center, e.world.obstacles[k].center) << k;
      EXPECT_EQ(s.obstacles[k].size, e.world.obstacles[k].size) << k;
      EXPECT_EQ(s.obstacles[k].radius, e.world.obstacles[k].radius) << k;
      EXPECT_EQ(s.obstacles[k].path, e.world.obstacles[k].path) << k;
      EXPECT_NEAR(s.obstacles[k].yaw, e.world.obstacles[k].yaw, 1e-12) << k;
    }
    EXPECT_EQ(s.robot_position, e.start.robot);
    EXPECT_EQ(s.target.front().position, e.start.target);
    EXPECT_GE(s.duration, 30.0);
    sim::World w(s);
    double closest = std::numeric_limits<double>::infinity();
    for (double t = 0.0; t <= s.duration; t += 0.02) closest = std::min(closest, w.clearance(w.target_position(t), t));
    EXPECT_GT(closest, s.target_radius);
  }
}

}  // namespace
