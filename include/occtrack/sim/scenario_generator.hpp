// The seeded scenario generator (shared/spec/simulation.md, "Benchmark suites"): cluttered worlds of
// cylinders and boxes, optional obstacles that move back and forth, and target paths that imitate
// tele-operation (smooth random motion through free space with stops, turns and speed changes).
//
// Everything is a pure function of the settings and a seed: one std::mt19937_64 per call, and the uniform and
// normal draws are made from its raw bits here (never std::*_distribution, whose output differs between
// standard libraries). Numbers are rounded to `decimals` places before they are checked, so that what is
// written to a file is exactly what was checked. (The committed suite files are the reference: a compiler
// that rounds floating point differently, e.g. by fusing multiply-adds, may draw different files.)
//
// Seeds. The benchmark suites (benchmark_suites() below, scenarios/README.md) use world and episode seeds
// in [kBenchmarkSeedMin, kBenchmarkSeedMax] = [1000, 1999]. Training data must be generated from seeds outside
// that range, so that no benchmark world or episode is ever seen in training.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "occtrack/core/scenario.hpp"

namespace occtrack::sim {

inline constexpr std::uint64_t kBenchmarkSeedMin = 1000;
inline constexpr std::uint64_t kBenchmarkSeedMax = 1999;
/// Whether a seed is reserved for the benchmark suites (training must not use it).
constexpr bool is_benchmark_seed(std::uint64_t seed) {
  return seed >= kBenchmarkSeedMin && seed <= kBenchmarkSeedMax;
}

enum class WorldKind {
  forest,  ///< cylinders only
  boxes,   ///< rotated boxes only
  mixed,   ///< both, in the share `WorldStyle::box_share`
};
const char* to_string(WorldKind kind);
/// "forest", "boxes" or "mixed"; nullopt otherwise.
std::optional<WorldKind> parse_world_kind(std::string_view text);

/// What the static clutter looks like.
struct WorldStyle {
  WorldKind kind = WorldKind::forest;
  double circle_radius_min = 0.3;  ///< m, cylinders' radius drawn uniformly in [min, max]
  double circle_radius_max = 0.8;
  double box_side_min = 0.5;       ///< m, each side of a box drawn uniformly in [min, max]
  double box_side_max = 2.5;
  double box_share = 0.5;          ///< mixed worlds: probability that an obstacle is a box

  bool operator==(const WorldStyle&) const = default;
};

/// The world: a rectangle centred on the origin, static obstacles, and optionally moving ones.
struct GeneratorSettings {
  WorldStyle style;
  double area_width = 30.0;   ///< m, along x; the area is [-w/2, w/2] x [-h/2, h/2]
  double area_height = 30.0;  ///< m, along y
  int static_obstacles = 70;  ///< placed by rejection sampling; generate_world throws if they do not fit
  /// Smallest gap (m) between the surfaces of any two static obstacles: 1.2 m lets a robot of radius 0.25 pass
  /// with room to spare, and a tracker 1 to 3 m behind the target find a place beside it.
  double min_gap = 1.2;
  double boundary_margin = 0.5;  ///< m, static obstacles stay this far inside the area

  int moving_obstacles = 0;
  double moving_speed = 0.7;        ///< m/s, every moving obstacle
  double moving_radius_min = 0.4;   ///< m, moving obstacles are circles of radius in [min, max]
  double moving_radius_max = 0.6;
  double moving_path_min = 4.0;     ///< m, total length of a moving obstacle's polyline, in [min, max]
  double moving_path_max = 8.0;
  double moving_two_segment_share = 0.5;  ///< probability of a 2-segment path (else straight)
  /// m, gap kept between a moving obstacle's swept disk and every static obstacle and every other moving
  /// obstacle's swept disk, so that moving obstacles never overlap anything but may cross the target's way.
  double moving_gap = 0.3;

  int decimals = 4;           ///< numbers are rounded to this many decimal places
  int max_attempts = 200000;  ///< rejection-sampling draws before giving up

  /// True when every field holds a usable value; otherwise false and *error names the field and its rule.
  bool validate(std::string* error = nullptr) const;
  bool operator==(const GeneratorSettings&) const = default;
};

/// How the virtual operator drives the target.
enum class TargetMotion {
  smooth,  ///< smooth random motion along routes, slowing for turns (v1; src/sim/target_path.cpp)
  teleop,  ///< joystick tele-operation: body-frame commands changing every 20-40 ms (src/sim/teleop_path.cpp)
};
const char* to_string(TargetMotion motion);
/// "smooth" or "teleop"; nullopt otherwise.
std::optional<TargetMotion> parse_target_motion(std::string_view text);

/// The joystick model of TargetMotion::teleop (shared/reference/paper_setup.md, "Target motion: recorded
/// tele-operation"). The operator holds three body-frame commands (forward, sideways, yaw rate) and changes
/// them every command period: forward and yaw rate by mean-reverting noise plus steering towards goals that
/// lie 1 to 2 m from an obstacle's surface (so that the target weaves between and loops around obstacles),
/// sideways by flicking the stick (strafing), now and then a short stop. Speeds are shares of
/// TargetSettings::max_speed, the nominal speed (full forward stick): a diagonal (forward plus sideways) goes
/// faster than nominal, as the recorded target did (1.41 m/s at nominal 1 m/s).
/// teleop_target_settings() below gives the values calibrated against the recordings.
struct TeleopStyle {
  double command_period_min = 0.02;  ///< s between command updates, drawn in [min, max]
  double command_period_max = 0.04;
  double forward_mean = 0.95;        ///< share of nominal the forward command reverts to
  double forward_noise = 0.1;        ///< share of nominal, stationary standard deviation of the forward command
  double forward_time = 2.0;         ///< s, reversion time of the forward command
  double yaw_gain = 2.0;             ///< 1/s, yaw rate per radian of heading error towards the route
  double yaw_noise = 0.5;            ///< rad/s, stationary standard deviation of the yaw-rate noise
  double yaw_noise_time = 0.5;       ///< s, reversion time of the yaw-rate noise
  double yaw_rate_max = 3.0;         ///< rad/s, largest yaw-rate command
  /// rad/s, a steady turn the operator holds on top of steering, one way or the other (the recorded operator
  /// turns 90 % of the time, at a steady rate); its sign flips after waits of mean turn_flip_time seconds
  double turn_bias = 0.0;
  double turn_flip_time = 5.0;
  double strafe_share = 0.1;         ///< share of the time spent strafing (sideways stick held)
  double strafe_min = 0.3;           ///< s, length of a strafe, drawn in [min, max]
  double strafe_max = 1.5;
  double strafe_speed_min = 0.5;     ///< share of nominal, sideways speed while strafing, drawn in [min, max]
  double strafe_speed_max = 1.0;
  double stop_share = 0.01;          ///< share of the time standing still
  double stop_min = 0.3;             ///< s, length of a stop, drawn in [min, max]
  double stop_max = 1.5;
  double goal_gap_min = 1.0;         ///< m, goals lie this far from an obstacle's surface, drawn in [min, max]
  double goal_gap_max = 2.0;
  double loop_share = 0.5;            ///< share of goals that continue round the same obstacle (loops)

  bool operator==(const TeleopStyle&) const = default;
};

/// The target's path (a virtual tele-operator) and the robot's start.
struct TargetSettings {
  /// How the target moves. smooth (the default) is the v1 generator, and its files reproduce bit for bit;
  /// teleop uses `teleop` (and max_speed as the nominal speed, static/moving clearances, area, robot and
  /// sensor settings, max_backtracks) and needs waypoint_period <= 0.1 s, so that statistics sampled every
  /// 0.1 s (sim/path_stats.hpp) see its abrupt changes.
  TargetMotion motion = TargetMotion::smooth;
  TeleopStyle teleop;
  double duration = 150.0;        ///< s, simulated time of the episode
  double waypoint_period = 0.5;   ///< s between waypoints (the path is linear between them)
  double max_speed = 1.0;         ///< m/s, never exceeded on any segment
  double min_speed = 0.25;        ///< m/s; cruising speeds are drawn uniformly in [min_speed, max_speed]
  double acceleration = 1.0;      ///< m/s^2, bound on speed changes between segments, braking aside
  double braking_deceleration = 2.0;  ///< m/s^2, the hardest braking (when the way ahead closes)
  double lateral_acceleration = 2.0;  ///< m/s^2, bounds turning while moving (turn rate <= a_lat / v)
  double turn_rate_max = 1.5;     ///< rad/s, bound on turning at low speed (any turn while stopped)
  double speed_change_min = 3.0;  ///< s between changes of the cruising speed, drawn in [min, max]
  double speed_change_max = 10.0;
  double stop_interval_min = 10.0;  ///< s of motion between stops, drawn in [min, max]
  double stop_interval_max = 30.0;
  double stop_min = 0.5;          ///< s, length of a stop, drawn in [min, max]
  double stop_max = 3.0;
  double goal_distance_min = 6.0;  ///< m; the operator heads for random free goals at least this far away
  /// Share of goals drawn near a moving obstacle's lane (worlds with moving obstacles), so that the target
  /// crosses their way.
  double moving_goal_share = 0.5;

  double target_radius = 0.25;     ///< m
  double static_clearance = 0.6;   ///< m, gap between the target's disk and every static obstacle, always
  double moving_clearance = 0.1;   ///< m, gap between the target's disk and every moving obstacle, always
  double area_width = 30.0;        ///< m, the world's area (GeneratorSettings::area_width of the world)
  double area_height = 30.0;       ///< m
  /// m, the area's centre (teleop only; the smooth generator needs an area centred on the origin, and
  /// validate() says so): the paper's six-wall world lies around (2, 0.5).
  double area_center_x = 0.0;
  double area_center_y = 0.0;
  double area_margin = 1.0;        ///< m, the target's centre stays this far inside the area
  /// Teleop only: the target's and the robot's first positions (the paper's starts, sim/paper_worlds.hpp).
  /// Unset, the target's is drawn in the area and the robot placed robot_distance behind it; a fixed robot
  /// start must keep robot_clearance and see the target's start. generate_episode throws when none fits.
  std::optional<core::Vec2> start;
  std::optional<core::Vec2> robot_start;

  double robot_radius = 0.25;      ///< m
  double robot_distance = 2.0;     ///< m, the robot starts this far behind the target's start
  double robot_clearance = 0.5;    ///< m, gap between the robot's disk and every obstacle at t = 0
  core::SensorSpec sensor;

  int decimals = 4;           ///< positions are rounded to this many decimal places
  int max_backtracks = 400;   ///< dead ends (a moving obstacle closing in) before generate_episode gives up

  bool validate(std::string* error = nullptr) const;
  bool operator==(const TargetSettings&) const = default;
};

/// Tele-operated target settings calibrated against the recordings (scenarios/README.md, "Tele-operated target
/// motion"): motion teleop, waypoint_period 0.1 s, max_speed `nominal_speed`, and a TeleopStyle interpolated
/// between the calm 0.5 m/s recording and the wild 1 m/s one (held beyond them). Other fields keep their
/// defaults; set duration, area and clearances as the world needs.
TargetSettings teleop_target_settings(double nominal_speed);

/// A scenario with the world's obstacles only (no target path; name "world-<seed>", sensor defaults).
/// Throws std::invalid_argument for invalid settings and std::runtime_error when the obstacles do not fit.
core::Scenario generate_world(const GeneratorSettings& settings, std::uint64_t world_seed);

/// One episode in `world` (the result of generate_world, whose area must match the target settings' area;
/// its obstacles are copied): the target's timed path, the robot's start `robot_distance` behind the target's
/// start (opposite the way the target first moves, turned by up to 0.6 rad where that spot is taken) in free
/// space with line of sight, the sensor. Throws
/// std::invalid_argument for invalid settings and std::runtime_error when no path could be made (a world too
/// dense for the clearances).
core::Scenario generate_episode(const core::Scenario& world, const TargetSettings& target, std::uint64_t seed,
                                const std::string& name);

/// How often the simplest follower loses sight of the target: a robot on a 2 m leash (it moves straight
/// towards the target only as far as needed to stay within `distance`, ignoring obstacles), checked every
/// `step` seconds with exact geometry. A measure of how much occlusion a scenario holds, not a planner.
struct OcclusionProfile {
  double occluded_time = 0.0;  ///< s
  int occlusion_events = 0;    ///< separate stretches of lost line of sight
  double duration = 0.0;       ///< s
};
/// Where a robot on a `distance` leash goes when the target is at `target`: it stays put while within the
/// leash, else moves straight towards the target until exactly `distance` away. The one home of the leash, used
/// by leash_follower_occlusion and by sim::median_cycle_ms's replayed scans.
core::Vec2 leash_position(const core::Vec2& robot, const core::Vec2& target, double distance);
OcclusionProfile leash_follower_occlusion(const core::Scenario& scenario, double distance = 2.0,
                                          double step = 0.05);

/// A benchmark suite of the spec: its worlds and how their episodes are made.
struct SuiteWorld {
  std::string name;            ///< e.g. "forest-a"; episode files are <name>-<k>.yaml, k = 1, 2, ...
  GeneratorSettings settings;
  std::uint64_t seed = 0;      ///< world seed
  /// A fixed world (the paper's, sim/paper_worlds.hpp) used instead of generate_world(settings, seed); its
  /// obstacles are the episodes' (settings and seed are then unused).
  std::optional<core::Scenario> fixed;
  /// Episodes of this world; 0: the suite's episodes_per_world (a suite of 10 episodes over 3 worlds).
  int episodes = 0;
};
/// The world's obstacles: `fixed`, or generate_world(settings, seed).
core::Scenario suite_world(const SuiteWorld& world);

struct SuiteSpec {
  std::string name;            ///< e.g. "static-1ms"; the folder name
  std::vector<SuiteWorld> worlds;
  TargetSettings target;
  int episodes_per_world = 5;
  /// Episode k (1-based) of world w (0-based) uses seed episode_seed_base + 20 w + k.
  std::uint64_t episode_seed_base = 0;
  std::uint64_t episode_seed(int world, int episode) const {
    return episode_seed_base + 20 * static_cast<std::uint64_t>(world) + static_cast<std::uint64_t>(episode);
  }
  /// Episodes of world w (0-based): its own count, else episodes_per_world.
  int episodes_of(std::size_t world) const {
    return worlds[world].episodes > 0 ? worlds[world].episodes : episodes_per_world;
  }
};

/// static-1ms, static-2ms, dynamic-1.5ms and their -smoke versions (the same worlds, one 20 s episode per
/// world), with the seeds documented in scenarios/README.md.
std::vector<SuiteSpec> benchmark_suites();
/// The v2 suites of shared/spec/simulation.md ("Suites v2": the paper's worlds and the v1 worlds with
/// tele-operated targets; 10 episodes of 90 s) and their -smoke versions, seeds in scenarios/README.md.
std::vector<SuiteSpec> benchmark_suites_v2();
/// A suite of either list by name.
std::optional<SuiteSpec> find_suite(std::string_view name);
/// The suite's episodes, world by world, named "<world>-<k>" (the scenario files' stems).
std::vector<core::Scenario> suite_scenarios(const SuiteSpec& spec);

}  // namespace occtrack::sim
