// The paper's own worlds (shared/reference/paper_setup.md, "Worlds"), exactly as its tables give them:
// the six-wall world of the Proj-CEM repository (static, or with its walls sliding for the dynamic runs) and
// the seed repository's random world. Like generate_world's output they hold obstacles only (no target path,
// duration 0, sensor defaults); robot_position is the paper's drone start, and the paper's target start is
// given beside it (PaperStart), for episodes that begin as the paper's did.
#pragma once

#include <optional>
#include <string_view>

#include "occtrack/core/scenario.hpp"
#include "occtrack/sim/scenario_generator.hpp"

namespace occtrack::sim {

/// Where the paper's runs began: the drone (robot) and the target.
struct PaperStart {
  core::Vec2 robot = core::Vec2::Zero();
  core::Vec2 target = core::Vec2::Zero();
};

/// The dynamic six-wall runs (the paper: "six obstacles at 0.7 m/s"). The paper's repository gives each wall a
/// planar-move plugin but not the motion, so occtrack chooses one: every wall slides along its own long axis,
/// away from the walls' centroid, kSixWallSlideLength metres at kSixWallSlideSpeed and back, all in phase,
/// starting at t = 0 from its table position (period 2 L / v = 5.7 s). Over a period the gaps between walls
/// open and close between 1.35 m (walls 3 and 4) and 10 m; no two walls come closer than 1.35 m, and no wall
/// comes within 1 m of either start (tests/test_paper_worlds.cpp checks this).
inline constexpr double kSixWallSlideSpeed = 0.7;   ///< m/s
inline constexpr double kSixWallSlideLength = 2.0;  ///< m, each way

/// Six boxes 1.6 m x 0.7 m at the table's centres and yaws, in the table's order; name "six-wall" or, with
/// `sliding`, "six-wall-sliding" (the walls move as described above). robot_position = six_wall_start().robot.
core::Scenario six_wall_world(bool sliding = false);
/// Drone (4, -2), target (3, -1).
PaperStart six_wall_start();

/// The seed's random world, obstacle by obstacle: 16 cylinders, then 20 axis-aligned boxes, in the table's
/// order; name "random". robot_position = random_world_start().robot.
core::Scenario random_world();
/// Drone (-3, 0), target (-0.6, -1).
PaperStart random_world_start();

/// A paper's world by the name the command line uses: "six-wall", "six-wall-sliding" or "random"; nullopt for
/// any other name. (`scenario generate --paper-world`, `scenario import --world`, Python's
/// scenario_from_path.)
std::optional<core::Scenario> paper_world(std::string_view name);

/// The rectangle a generated target roams in (TargetSettings::area_width, area_height, area_center_x/y):
/// the world's obstacles with room round them. Six-wall: the walls, sliding ones at their farthest included,
/// lie in x -3.2..6.9, y -6.1..7.0, so 15 m x 16 m about (2, 0.5). Random world: its obstacles lie in
/// x -15.1..14.2, y -11.5..13.7, so 31 m x 27 m about (-0.5, 1.2).
struct WorldArea {
  double width = 0.0, height = 0.0;
  double center_x = 0.0, center_y = 0.0;
};
WorldArea six_wall_area();
WorldArea random_world_area();

/// Tele-operated target settings for a world: teleop_target_settings(nominal_speed) over `area`, episodes of
/// `duration` seconds (the v2 suites and the shipped worlds).
TargetSettings teleop_target_in(const WorldArea& area, double nominal_speed, double duration);

}  // namespace occtrack::sim
