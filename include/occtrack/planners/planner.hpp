// The Planner interface: what every planner sees and returns (shared/spec/simulation.md).
//
// A planner sees what a robot would see: its own state (odometry), the target's current position and
// velocity (from a tracker), and the LiDAR scan. Never the world. Frames: world positions in, a world-frame
// velocity command out; internally planners work in the robot-centric frame (a translation, no rotation).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "occtrack/core/scan.hpp"
#include "occtrack/core/scenario.hpp"

namespace occtrack::planners {

using core::Vec2;

struct PlannerInput {
  double time = 0.0;
  Vec2 robot_position = Vec2::Zero();  ///< world frame, from odometry
  Vec2 robot_velocity = Vec2::Zero();
  Vec2 target_position = Vec2::Zero();  ///< world frame, current estimate
  Vec2 target_velocity = Vec2::Zero();
  const core::Scan* scan = nullptr;     ///< the latest scan; must not be null
};

struct PlannerOutput {
  Vec2 command_velocity = Vec2::Zero();  ///< world frame; always finite
  std::vector<Vec2> plan;                ///< the chosen trajectory, world frame, one point per step
  std::vector<std::vector<Vec2>> candidates;  ///< other projected samples, for figures (may be empty)
  double compute_ms = 0.0;               ///< wall time of plan(), filled by the planner
  bool ok = true;       ///< false: no usable plan; the command brakes (zero velocity) and `message` says why
  std::string message;
};

class Planner {
 public:
  virtual ~Planner() = default;
  virtual std::string name() const = 0;
  /// Forget everything from previous calls (warm starts, velocity estimates); called at episode start.
  virtual void reset() = 0;
  /// One planning cycle. Never throws for bad sensor data and never returns a non-finite command.
  virtual PlannerOutput plan(const PlannerInput& input) = 0;
};

/// Options shared by the planners that the command line exposes.
struct PlannerOptions {
  std::uint64_t seed = 1;
  int threads = 1;          ///< Proj-CEM: projection threads
  int samples = 0;          ///< Proj-CEM: samples per CEM iteration (0: the planner's default)
  bool offline_expert = false;  ///< Proj-CEM: the offline expert budget (thousands of samples)
  std::string model;        ///< learned planners: model file (empty: the shipped model of the variant)
  int batch = 30;           ///< learned planners: samples drawn per cycle (30; 5 for constrained hardware)
  bool keep_last_plan = true;  ///< learned planners: also rank the last plan, shifted (LearnedPolicySettings)
  bool rank_stop = true;       ///< learned planners: also rank a plan that stops (LearnedPolicySettings)
};

/// Names the command line accepts, e.g. "projcem", "follower".
std::vector<std::string> planner_names();
/// Builds a planner by name; throws std::invalid_argument listing the known names otherwise.
std::unique_ptr<Planner> make_planner(const std::string& name, const PlannerOptions& options = {});

}  // namespace occtrack::planners
