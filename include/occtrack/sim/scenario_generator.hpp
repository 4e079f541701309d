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

/// The target's path (a virtual tele-operator) and the robot's start.
struct TargetSettings {
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
  double area_margin = 1.0;        ///< m, the target's centre stays this far inside the area

  double robot_radius = 0.25;      ///< m
  double robot_distance = 2.0;     ///< m, the robot starts this far behind the target's start
  double robot_clearance = 0.5;    ///< m, gap between the robot's disk and every obstacle at t = 0
  core::SensorSpec sensor;

  int decimals = 4;           ///< positions are rounded to this many decimal places
  int max_backtracks = 400;   ///< dead ends (a moving obstacle closing in) before generate_episode gives up

  bool validate(std::string* error = nullptr) const;
  bool operator==(const TargetSettings&) const = default;
};

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
OcclusionProfile leash_follower_occlusion(const core::Scenario& scenario, double distance = 2.0,
                                          double step = 0.05);

/// A benchmark suite of the spec: its worlds and how their episodes are made.
struct SuiteWorld {
  std::string name;            ///< e.g. "forest-a"; episode files are <name>-<k>.yaml, k = 1, 2, ...
  GeneratorSettings settings;
  std::uint64_t seed = 0;      ///< world seed
};
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
};

/// static-1ms, static-2ms, dynamic-1.5ms and their -smoke versions (the same worlds, one 20 s episode per
/// world), with the seeds documented in scenarios/README.md.
std::vector<SuiteSpec> benchmark_suites();
std::optional<SuiteSpec> find_suite(std::string_view name);

}  // namespace occtrack::sim
