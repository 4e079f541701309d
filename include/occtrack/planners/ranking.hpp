// The ranking cost that picks the plan among projected samples (shared/spec/policy.md, planning cycle
// step 6): occlusion of the predicted line of sight, deviation from the reference tracking distance,
// smoothness, and whatever constraint violation the projection left.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "occtrack/core/bernstein.hpp"
#include "occtrack/core/scan.hpp"
#include "occtrack/core/target_predictor.hpp"
#include "occtrack/core/tracking.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::planners {

struct RankingSettings {
  double occlusion_weight = 20.0;   ///< per squared metre of line-of-sight intrusion, summed over steps
  double tracking_weight = 1.0;     ///< mean squared deviation from band.reference
  double smoothness_weight = 0.02;  ///< mean squared acceleration
  double violation_weight = 200.0;  ///< mean obstacle penetration, speed and acceleration excess
  double occlusion_margin = 0.35;   ///< metres: a point this close to the line of sight blocks it
  int occlusion_stride = 4;         ///< check the line of sight every this many steps
  double late_occlusion_weight = 0.3;  ///< occlusion weight at the horizon's end, relative to its start
  /// Per metre (mean over the checked steps) of plan behind a surface the LiDAR sees. The optimizer's
  /// obstacles are disks around the visible points, so a plan that has crossed a wall of points is pushed
  /// further through it, not back: from the scan, such a plan is in the shadow of a return, where the
  /// obstacle's inside is. 0 switches the term off.
  double shadow_weight = 200.0;
  double shadow_horizon = 2.5;     ///< seconds of the plan checked against the scan (nearer is what matters)
  double shadow_depth_cap = 1.0;   ///< metres: depth behind a return beyond which the penalty stops growing
  /// Per metre of the deepest intrusion, in the plan's first near_horizon seconds, closer than near_clearance
  /// to an obstacle point. The violation term above is a mean over the whole horizon, so a plan that
  /// grazes a wall for a few steps right ahead costs little there; this is where the robot will be next.
  double near_weight = 2000.0;
  double near_horizon = 1.5;      ///< seconds
  double near_clearance = 0.4;    ///< metres from an obstacle point to the robot centre: the optimizer's disk radius
  /// Seconds of a moving obstacle point's speed added to near_clearance for that point (0: off, the settings'
  /// default; make_planner gives the cvae at B >= 30 behind the safety layer 1, planners::moving_reach_for).
  /// The safety layer refuses a command whose stop comes within a moving point's passive-safety reach (any
  /// heading, at its speed), so a plan that keeps only the near term's distance from a sliding wall can be
  /// refused cycle after cycle, and the robot falls back on evasive manoeuvres; this keeps plans farther
  /// from such points. Going by speed alone it traded sight between suites rather than saving it
  /// (docs/learning.md, "Room for the layer"); on the layer's verdicts it helps the cvae at B = 30 ("The
  /// moving reach by default"). Only points faster than
  /// moving_reach_speed_min count, each at most at moving_reach_speed_max (the layer's moving_speed_max).
  /// Behind the safety layer, only the points its motion evidence shows moved count (evaluate()'s `moving`):
  /// perception's velocity estimates drift on static walls, which this term would take for motion.
  double moving_reach = 0.0;
  double moving_reach_speed_min = 0.3;  ///< m/s
  double moving_reach_speed_max = 1.0;  ///< m/s
  core::TrackingBand band;
  /// The target predictor (core/target_predictor.hpp, issue 11): off ranks against the constant-velocity
  /// target (the paper's planners, before issue 11). On, the occlusion and tracking terms use the predicted
  /// target at every step, weighted 1 / (1 + (sigma_k / forecast_distance)^2) for the prediction's spread
  /// sigma_k, so that the near future, where the prediction is good, counts most (these weights replace
  /// late_occlusion_weight's taper); a hidden target's estimate is carried forward along the prediction.
  bool predict_target = false;
  core::TargetPredictorSettings predictor;
  double forecast_distance = 1.0;  ///< m, the spread at which a step counts half

  /// True when every weight is finite and >= 0, every distance and horizon finite and >= 0 (the margin and
  /// the shadow cap positive), the stride at least 1, late_occlusion_weight in [0, 1] and the band ordered
  /// (0 < min <= reference <= max). Otherwise false, and *error names the field and the rule.
  bool validate(std::string* error = nullptr) const;
  bool operator==(const RankingSettings&) const = default;
};

/// The terms of one plan's cost, unweighted, and their weighted sum `total` (infinite when not finite).
struct RankingTerms {
  double occlusion = 0, tracking = 0, smoothness = 0, violation = 0, shadow = 0, near = 0, total = 0;
};

using PointRows = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// One flag per row of a PointRows.
using RowMask = Eigen::Array<bool, Eigen::Dynamic, 1>;

/// The predicted target at every step of the plan (robot-centric), and each step's weight (see
/// RankingSettings::predict_target). `valid` false: rank against the linear target instead.
struct TargetForecast {
  Eigen::MatrixX2d positions;
  Eigen::VectorXd weights;
  bool valid = false;
};

/// Not safe to share between threads: evaluate() works in buffers sized at construction, so that it
/// allocates nothing.
class Ranking {
 public:
  /// Throws std::invalid_argument with "ranking: <validate's message>" for unusable settings.
  Ranking(const RankingSettings& settings, const projection::Settings& projection);

  /// Costs of trajectories given as coefficient rows (x coefficients, then y), robot-centric. target:
  /// (x, y, vx, vy) robot-centric, predicted linearly. collision_points: the optimizer's obstacles (N x 4).
  /// occlusion_points: every point that can block the view (x, y, vx, vy). scan: the cycle's scan, taken
  /// at the robot-centric origin, for the shadow term (null: no shadow term). forecast: when given and valid
  /// (one row per step), the occlusion and tracking terms use its positions and weights instead of `target`.
  /// moving: when given with one flag per collision point, only flagged points can count as moving for
  /// RankingSettings::moving_reach (the safety layer's verdict, SharedPerception::moving); else speed decides.
  RankingTerms evaluate(const Eigen::Ref<const Eigen::RowVectorXd>& xi, const Eigen::Vector4d& target,
                        const Eigen::Ref<const PointRows>& collision_points,
                        const Eigen::Ref<const PointRows>& occlusion_points, const core::Scan* scan = nullptr,
                        const TargetForecast* forecast = nullptr, const RowMask* moving = nullptr) const;

  const core::BernsteinBasis& basis() const { return basis_; }

 private:
  RankingSettings settings_;
  projection::Settings projection_;
  core::BernsteinBasis basis_;
  Eigen::VectorXd occlusion_weights_;
  // Workspaces of evaluate(), m rows each.
  mutable Eigen::MatrixX2d positions_, targets_;
  mutable Eigen::VectorXd cx_, cy_, px_, py_, vx_, vy_, ax_, ay_;
  /// The collision points column by column (x, y, vx, vy; projection.obstacles rows reserved), so that the
  /// nearest-point search runs in SIMD lanes.
  mutable Eigen::Matrix<double, Eigen::Dynamic, 4> collision_columns_;
  mutable Eigen::VectorXd reach_;   // per moving collision point: near_clearance plus its moving_reach
  mutable Eigen::VectorXi reaching_;  // the moving collision points' rows
  /// occlusion::occlusion_cost's candidates (grows to the largest cloud seen, then allocates no more).
  mutable std::vector<int> occluder_candidates_;
};

}  // namespace occtrack::planners
