// The Planner interface: what every planner sees and returns (shared/spec/simulation.md).
//
// A planner sees what a robot would see: its own state (odometry), the target's current position and
// velocity (from a tracker), and the LiDAR scan. Never the world. Frames: world positions in, a world-frame
// velocity command out; internally planners work in the robot-centric frame (a translation, no rotation).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "occtrack/core/scan.hpp"
#include "occtrack/core/scenario.hpp"
#include "occtrack/planners/ranking.hpp"

namespace occtrack::perception {
struct Settings;
struct Observation;
}  // namespace occtrack::perception

namespace occtrack::planners {

using core::Vec2;

/// Perception of a cycle's scan already run by a wrapper around the planner (the safety layer,
/// planners/safety.hpp), so that the scan is perceived once a cycle rather than once by each. A planner whose
/// perception settings equal `settings` but for a smaller or equal nearest_count uses `observation` (its own
/// nearest_count first rows) instead of perceiving, adds `ms` to its cycle's time (its perception took that
/// long) and sets `used`; any other planner ignores it. Valid during the cycle only.
struct SharedPerception {
  const perception::Settings* settings = nullptr;
  const perception::Observation* observation = nullptr;
  double ms = 0.0;    ///< what perceiving took
  bool used = false;  ///< set by the planner that used it
  /// Per row of observation->nearest, when not null: whether the wrapper's evidence shows that point's object
  /// moved (the safety layer's MotionEvidence, planners/safety.hpp). Frame::moving copies it.
  const RowMask* moving = nullptr;
};

struct PlannerInput {
  double time = 0.0;
  Vec2 robot_position = Vec2::Zero();  ///< world frame, from odometry
  Vec2 robot_velocity = Vec2::Zero();
  Vec2 target_position = Vec2::Zero();  ///< world frame, current estimate
  Vec2 target_velocity = Vec2::Zero();
  /// Seconds since the target estimate above was measured (Protocol v2, target_observation line_of_sight):
  /// 0 for a current estimate; while the target is hidden, the last estimate and its age; +infinity when the
  /// target has never been observed (the position and velocity then mean nothing and a planner holds still).
  double target_age = 0.0;
  const core::Scan* scan = nullptr;     ///< the latest scan; must not be null
  SharedPerception* perceived = nullptr;  ///< the scan already perceived, when a wrapper did (else null)
};

/// What the safety layer did with a cycle's command (planners/safety.hpp; the metrics count each).
enum class SafetyAction {
  off,          ///< no safety layer (the default; --shield turns it on), or a planner used directly
  plan,         ///< the planner's own command was certified
  alternative,  ///< not its own command, but a lower-ranked candidate, or the command slowed or slid along the
                ///< nearest obstacle, was certified (docs/safety.md, "Fallback")
  stop,         ///< no candidate was certified; braking to a stop was
  evasive,      ///< neither; a certified evasive command (away from approaching obstacles) was sent
  best_effort,  ///< nothing certified: the manoeuvre in known-free space (with the margin, else at the bare
                ///< radius) farthest from moving obstacles' paths
  brake,        ///< nothing could be certified, nor stays in known-free space: full brake (command zero)
};
/// How many SafetyAction values there are (brake is the last).
constexpr int kSafetyActions = static_cast<int>(SafetyAction::brake) + 1;
/// The action's name as the result files spell it ("plan", "best_effort", ...; "off").
constexpr const char* to_string(SafetyAction action) {
  switch (action) {
    case SafetyAction::off: return "off";
    case SafetyAction::plan: return "plan";
    case SafetyAction::alternative: return "alternative";
    case SafetyAction::stop: return "stop";
    case SafetyAction::evasive: return "evasive";
    case SafetyAction::best_effort: return "best_effort";
    case SafetyAction::brake: return "brake";
  }
  return "unknown";
}

struct PlannerOutput {
  Vec2 command_velocity = Vec2::Zero();  ///< world frame; always finite
  std::vector<Vec2> plan;                ///< the chosen trajectory, world frame, one point per step
  std::vector<std::vector<Vec2>> candidates;  ///< other projected samples, for figures (may be empty)
  double compute_ms = 0.0;               ///< wall time of plan(), filled by the planner
  bool ok = true;       ///< false: no usable plan; the command brakes (zero velocity) and `message` says why
  std::string message;
  /// The commands of the planner's ranked candidates, best first (the chosen one included), for the safety
  /// layer to fall back on; planners that do not rank leave it empty.
  std::vector<Vec2> ranked_commands;
  SafetyAction safety = SafetyAction::off;
  /// Set by the safety layer: moving obstacles look faster than it assumes (safety::SpeedWatch), so its
  /// guarantees against obstacles that turn or reverse may not hold; raise its moving_speed_max if they are.
  bool beyond_envelope = false;
  /// Storage of candidates dropped by resize_candidates, taken back when the count grows again (not output).
  std::vector<std::vector<Vec2>> spare_candidates;

  /// Makes `candidates` hold n trajectories (their contents are the caller's to fill), keeping the storage of
  /// those it drops. vector::resize and clear would free them, and the next cycle that shows more would
  /// allocate again: with this, an output reused cycle after cycle allocates nothing once it has held n.
  void resize_candidates(std::size_t n) {
    for (; candidates.size() > n; candidates.pop_back()) spare_candidates.push_back(std::move(candidates.back()));
    for (; candidates.size() < n; spare_candidates.pop_back()) {
      if (spare_candidates.empty()) {  // more than ever before: new trajectories, and room to keep them all
        candidates.resize(n);
        spare_candidates.reserve(candidates.capacity());
        break;
      }
      candidates.push_back(std::move(spare_candidates.back()));
    }
  }
};

/// One cycle's robot-centric view, as perception and the frame change make it: the robot is at the origin,
/// axes parallel to the world's.
struct Frame {
  Eigen::Vector2d robot_velocity = Eigen::Vector2d::Zero();
  Eigen::Vector4d target = Eigen::Vector4d::Zero();  ///< x, y, vx, vy
  /// The predicted target at every step, when the planner's ranking predicts it (RankingSettings::predict_target).
  TargetForecast forecast;
  PointRows nearest;    ///< the optimizer's obstacles, N x 4 (padded as perception pads)
  /// Per row of `nearest`: shown moved by the safety layer (SharedPerception::moving); empty when no layer
  /// judged this cycle's points (RankingSettings::moving_reach then goes by speed alone).
  RowMask moving;
  /// Every distinct point that can block the view (x, y, vx, vy): the first `occluder_count` rows. The
  /// storage keeps the cloud's size so that a cycle allocates nothing; use occluders_view().
  PointRows occluders;
  int occluder_count = 0;
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> cloud;  ///< perception's fixed cloud (PointNet input)
  const core::Scan* scan = nullptr;  ///< the cycle's scan (valid during the cycle only), for the shadow term
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< the robot's world position
  double time = 0.0;

  Eigen::Ref<const PointRows> occluders_view() const { return occluders.topRows(occluder_count); }
};

/// What a planner decided in its last cycle, in its own terms: the frame it planned in, the coefficients of
/// the plan it chose and that plan's ranking terms (with the scan: exactly the cost it ranked by). Training
/// data is made from this record (sim::DemonstrationRecorder), so that a row holds the expert's own view.
struct PlanRecord {
  bool valid = false;       ///< false when the last cycle braked (no plan) or no cycle ran yet
  Frame frame;
  Eigen::RowVectorXd xi;    ///< coefficients, x then y, robot-centric (frame.origin)
  RankingTerms terms;       ///< the ranking of xi in `frame`; terms.total is the planner's cost
};

class Planner {
 public:
  virtual ~Planner() = default;
  virtual std::string name() const = 0;
  /// Forget everything from previous calls (warm starts, velocity estimates); called at episode start.
  virtual void reset() = 0;
  /// Prior knowledge of the world, for the baselines that plan on a prior map (AutoChaser: the scenario's
  /// static obstacles and, when asked, the target's true future path). This is the one documented exception
  /// to "planners see only the scan" (shared/spec/simulation.md); sim::run_episode calls it before reset().
  /// Every other planner ignores it.
  virtual void use_prior(const core::Scenario& /*scenario*/) {}
  /// One planning cycle into `out`, whose storage is reused: given the same `out` every cycle, the planners
  /// of this library allocate nothing after the first cycles (tests/test_allocation_count.cpp). Never throws
  /// for bad sensor data and never leaves a non-finite command.
  virtual void plan(const PlannerInput& input, PlannerOutput& out) = 0;
  /// The same, into a fresh output (allocates).
  PlannerOutput plan(const PlannerInput& input) {
    PlannerOutput out;
    plan(input, out);
    return out;
  }
  /// The last cycle's record (valid = false before the first cycle and after a cycle that braked).
  virtual const PlanRecord& last_record() const = 0;
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
  /// Learned planners that project (cvae, cvae-fixed-q): projection iterations per cycle (0: the planner's
  /// default of 50, LearnedPolicySettings::projection). The shipped models were trained through K = 20.
  int iterations = 0;
  /// The ranking's weight on the tracking distance (RankingSettings::tracking_weight) for the planners that
  /// rank plans (Proj-CEM, the follower, the learned planners). 0: the planner's default, which is the
  /// ranking's 1 except for the learned planners (learned_tracking_weight).
  double tracking_weight = 0.0;
  /// s, the ranking's RankingSettings::moving_reach for the planners that rank plans (0: off, the paper's
  /// ranking). Unset: the planner's default (moving_reach_for).
  std::optional<double> moving_reach;
  /// s, the robot's velocity time constant (Protocol v2's tau; 0: v1). Commands lead the plan by it and by
  /// the latency (command_lead); the safety layer models the robot's lag with it.
  double response_time = 0.0;
  int waypoints = 0;  ///< AutoChaser: true future target points given as prior (0: constant-velocity prediction)
  /// The safety layer (planners/safety.hpp) around the planner. Off by default until issue 11's measurements
  /// are in (docs/safety.md); off reproduces the planners of before it exactly.
  bool shield = false;
  /// The target predictor in the ranking (RankingSettings::predict_target); off: constant velocity, as before.
  bool predictor = false;
  double latency = 0.0;          ///< s from the scan until a command applies (Protocol v2); see command_lead
  double planning_period = 0.05; ///< s between cycles, for the safety layer
  double accel_max = 2.0;        ///< m/s^2, the robot's acceleration bound, for the safety layer
  double passive_turn = 180.0;   ///< degrees, the safety layer's safety::Settings::moving_turn_max
  double standoff = 0.5;         ///< s, the safety layer's safety::Settings::moving_standoff
  double moving_speed_max = 1.0; ///< m/s, the safety layer's safety::Settings::moving_speed_max
};

/// s by which a planner's command leads its plan: a command takes effect `latency` after the scan it was
/// planned from, and the robot's velocity follows it with the time constant `response_time`, so the plan's
/// velocity that far ahead is the one to send. make_planner gives it to every planner as its settings'
/// response_time; the safety layer keeps the two apart (the robot holds its last command through the latency).
double command_lead(const PlannerOptions& options);

/// Names the command line accepts, e.g. "projcem", "follower".
std::vector<std::string> planner_names();
/// The ranking's tracking weight the planner `name` gets from make_planner: options.tracking_weight unless it
/// is 0, else the planner's default (learned_tracking_weight for the learned planners, the ranking's 1 for
/// the others; AutoChaser ranks nothing and ignores it). A negative or non-finite weight is returned as it is,
/// and make_planner then refuses it ("ranking.tracking_weight ...").
double tracking_weight_for(const std::string& name, const PlannerOptions& options);
/// The ranking's moving reach (s) the planner `name` gets from make_planner: options.moving_reach when set,
/// else the planner's default: learned_moving_reach for a learned planner behind the safety layer (the layer
/// tells the ranking which points moved; SharedPerception::moving), 0 (off) otherwise. Without the layer the
/// term would go by speed alone, which drifts on static walls (docs/learning.md, "Room for the layer"). A
/// negative or non-finite value is returned as it is, for make_planner to refuse by name.
double moving_reach_for(const std::string& name, const PlannerOptions& options);
/// The ranking settings make_planner gives the planner `name` from `options` (predict_target, tracking_weight_for,
/// moving_reach_for), for every planner that ranks plans; the rest of `ranking` is left as it is.
void rank_as_asked(RankingSettings& ranking, const std::string& name, const PlannerOptions& options);
/// What the planner `name` ranks and assumes with `options`, each planner's own default resolved, for a
/// settings line: "tracking weight W", then ", moving reach S s" when it is on, then (with the safety layer)
/// ", standoff X s, moving obstacles up to V m/s". The command line's settings line and the ROS node print it.
std::string describe_ranking_and_layer(const std::string& name, const PlannerOptions& options);
/// Builds a planner by name; throws std::invalid_argument listing the known names otherwise.
std::unique_ptr<Planner> make_planner(const std::string& name, const PlannerOptions& options = {});

}  // namespace occtrack::planners
