// The simulated world: obstacle shapes over time, the target's replayed path, LiDAR scans and the exact
// queries the metrics need (shared/spec/simulation.md), on the shapes of occtrack/sim/geometry.hpp. Only the
// simulator knows the world; planners see scans.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "occtrack/core/scan.hpp"
#include "occtrack/core/scenario.hpp"
#include "occtrack/sim/geometry.hpp"

namespace occtrack::sim {

using core::Vec2;

class World {
 public:
  /// The scenario must be valid (io::read_scenario validates); throws std::invalid_argument otherwise.
  explicit World(const core::Scenario& scenario);

  const core::Scenario& scenario() const { return scenario_; }

  /// Every obstacle's shape at time t (moving ones along their paths, back and forth).
  const std::vector<Shape>& shapes_at(double t);

  /// Target position and velocity at time t (linear between waypoints, held after the last; velocity is the
  /// slope of the current segment, zero after the last waypoint).
  Vec2 target_position(double t) const;
  Vec2 target_velocity(double t) const;

  /// LiDAR scan from `position` at time t: scenario().sensor.beams beams evenly over 360 degrees starting at
  /// angle 0, first hit against every shape, +infinity where nothing is hit within range; Gaussian range
  /// noise of the sensor's standard deviation from `rng` when noise > 0; then, when sensor.dropout > 0, each
  /// beam returns nothing (+infinity) with that probability, drawn from the world's own dropout stream
  /// (seed_dropout), so that the noise draws are the same with and without dropout.
  core::Scan scan(const Vec2& position, double t, std::mt19937_64& rng);
  /// The same into `out`, reusing its storage (no allocation once `out.ranges` has the beam count).
  void scan(const Vec2& position, double t, std::mt19937_64& rng, core::Scan& out);

  /// Restarts the beam-dropout random stream (one uniform draw per beam and scan, only when dropout > 0).
  void seed_dropout(std::uint64_t seed) { dropout_rng_.seed(seed); }

  /// Whether the segment between two points touches any obstacle at time t (line of sight is blocked).
  bool segment_blocked(const Vec2& a, const Vec2& b, double t);

  /// Smallest signed distance from point p to any obstacle at time t (negative: inside one);
  /// +infinity without obstacles.
  double clearance(const Vec2& p, double t);

 private:
  core::Scenario scenario_;
  std::vector<Shape> shapes_;  // cache for shapes_at
  double shapes_time_ = -1.0;
  std::vector<double> path_lengths_;  // per obstacle, total polyline length (0 if static)
  std::vector<std::vector<double>> path_arc_;  // per obstacle, arc length at each path point (empty if static)
  std::vector<std::size_t> moving_;            // indices of the obstacles that move
  std::vector<double> bounding_radius_;        // per obstacle, radius of a circle about its centre holding it
  std::vector<Vec2> box_axis_;                 // per obstacle, (cos yaw, sin yaw) (boxes; (1, 0) for circles)
  std::vector<Vec2> beam_directions_;          // unit direction of every LiDAR beam
  bool shapes_valid_ = false;                  // whether shapes_ holds shapes_time_
  std::mt19937_64 dropout_rng_{0x64726f706f7574ULL};  // beam dropout ("dropout"), apart from the noise stream
};

}  // namespace occtrack::sim
