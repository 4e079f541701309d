// The planning cycle that every planner shares (private to src/planners): settings checks, the frame
// change from a PlannerInput to the robot-centric Frame, the nominal constraint parameters q, the conversions
// between coefficients, commands and the world frame, braking, and the cycle's timing.
//
//   detail::CycleClock clock;                                   // at the top of plan()
//   if (detail::hold_unobserved(input, out, record, clock)) return;  // target never seen: stand still
//   if (!context.observe(input, record.frame, &error)) return detail::brake(out, record, clock, name() + ": " + error);
//   ...
//   context.finish_plan(out, record, clock, xi, terms);         // command, world plan, record, timing
//
// Every function here allocates nothing once `out` and the record have been through a cycle.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "../core/settings_checker.hpp"
#include "occtrack/core/bernstein.hpp"
#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::planners::detail {

/// True when the projection, perception (when given) and ranking settings are usable and fit together
/// (perception's nearest points are the optimizer's obstacles). Otherwise false, and *error names the field
/// with its group, e.g. "ranking.occlusion_stride (0) must be at least 1". Every planner's settings call it
/// from their validate().
bool validate_cycle(const projection::Settings& projection, const perception::Settings* perception,
                    const RankingSettings& ranking, double response_time, std::string* error);

/// The optimizer of a planner that projects: factored once, with its problem and result buffers.
struct Optimizer {
  explicit Optimizer(const projection::Settings& settings)
      : projector(settings), problem(projector.make_problem()), result(projector.make_result()) {}
  projection::Projector<float> projector;
  projection::Problem<float> problem;
  projection::Result<float> result;
};

/// Wall time of one cycle, from construction.
class CycleClock {
 public:
  using Clock = std::chrono::steady_clock;
  CycleClock() : start_(Clock::now()) {}
  double elapsed_ms() const { return ms_since(start_); }
  /// When the cycle started: construction, less any time credited.
  Clock::time_point start() const { return start_; }
  /// Counts `ms` more to the cycle, work done for it before construction (a shared perception).
  void credit(double ms) {
    if (ms > 0.0) start_ -= std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(ms));
  }
  static double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
  }

 private:
  Clock::time_point start_;
};

/// The end of every cycle: out.compute_ms from the clock.
void finish(PlannerOutput& out, const CycleClock& clock);
/// A cycle without a usable plan: zero command, empty plan and candidates (storage kept), ok = false with
/// `message` (copied into out.message, whose storage is kept), the record invalidated, and finish().
void brake(PlannerOutput& out, PlanRecord& record, const CycleClock& clock, std::string_view message);

/// Protocol v2: a target never observed (input.target_age +infinity) leaves nothing to track. Then the cycle
/// commands zero velocity (the robot brakes to a stop under its acceleration bound), ok = true with a message
/// saying why, and returns true; the planner returns at once. False otherwise (nothing is touched).
bool hold_unobserved(const PlannerInput& input, PlannerOutput& out, PlanRecord& record, const CycleClock& clock);

/// The longest extrapolation of a hidden target's last estimate (s): beyond it, a constant-velocity guess is
/// worth less than the last place it was seen heading from (docs/protocol_v2.md).
constexpr double kMaxTargetPrediction = 2.0;

/// The most lower-ranked candidates a planner offers the safety layer (PlannerOutput::ranked_commands).
constexpr int kRankedCommands = 32;

/// Fills `ranked` with the commands of the candidates whose cost is finite, cheapest first, at most
/// kRankedCommands: `command_of(b)` gives candidate b's command. `order` is workspace (resized to the costs).
template <typename CommandOf>
void rank_commands(const std::vector<double>& costs, std::vector<int>& order, CommandOf&& command_of,
                   std::vector<Vec2>& ranked) {
  order.resize(costs.size());
  std::size_t finite = 0;
  for (std::size_t b = 0; b < costs.size(); ++b)
    if (std::isfinite(costs[b])) order[finite++] = static_cast<int>(b);
  const std::size_t kept = std::min<std::size_t>(finite, kRankedCommands);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(kept),
                    order.begin() + static_cast<std::ptrdiff_t>(finite),
                    [&](int a, int b) { return costs[static_cast<std::size_t>(a)] < costs[static_cast<std::size_t>(b)]; });
  ranked.reserve(kRankedCommands + 1);  // once: room for the most, and one more in front (Proj-CEM's best)
  ranked.resize(kept);
  for (std::size_t i = 0; i < kept; ++i) ranked[i] = command_of(order[i]);
}

class Context {
 public:
  /// `response_time`: how far ahead along the plan commands are taken (the robot's velocity time constant,
  /// Protocol v2's tau, plus the command latency: command_lead).
  Context(const projection::Settings& projection, const perception::Settings& perception,
          const RankingSettings& ranking, double response_time = 0.0);

  /// Forgets perception's tracks (velocity estimates) and the target's history; called when an episode starts.
  void reset() {
    perception_.reset();
    predictor_.reset();
  }

  /// Perception and frame change. False, with *error, on unusable input (null scan, non-finite state, a
  /// negative or NaN target age). Perception is input.perceived's when it fits this planner's settings
  /// (PlannerInput): then its time is credited to `clock`. A target estimate of age a > 0 (hidden target,
  /// Protocol v2) is predicted over min(a, kMaxTargetPrediction), at constant velocity or, with RankingSettings::predict_target, by the
  /// target predictor, which then also fills frame.forecast; the planners plan on that prediction.
  bool observe(const PlannerInput& input, Frame& frame, CycleClock& clock, std::string* error);

  /// The end of a cycle that chose `xi` (robot-centric in record.frame) with ranking `terms`: out's command
  /// and world plan (candidates are left as they are), out.ok, the record, and finish(). xi may alias
  /// record.xi.
  void finish_plan(PlannerOutput& out, PlanRecord& record, const CycleClock& clock,
                   const Eigen::Ref<const Eigen::RowVectorXd>& xi, const RankingTerms& terms) const;

  /// Where the naive follower heads: the target's predicted position at the horizon's end, pulled back
  /// towards the robot to the reference distance.
  Eigen::Vector2d goal(const Frame& frame) const;
  /// Coefficients (x then y) of a straight line from the origin to `end` at constant velocity, into `xi`
  /// (resized to 2n).
  void line_through(const Eigen::Vector2d& end, Eigen::RowVectorXd& xi) const;

  /// Fills problem row b with the nominal q for nominal coefficients xi_bar: terminal state and via points
  /// read off xi_bar (terminal speed clamped to speed_max, or `terminal_velocity` when given), lambda0 = 0,
  /// the tracking band as distance bounds.
  void fill_row(projection::Problem<float>& problem, int b, const Eigen::RowVectorXd& xi_bar, const Frame& frame,
                const Eigen::Vector2d* terminal_velocity = nullptr) const;

  /// The command of a plan: its mean velocity over the first 0.1 s, capped at speed_max; zero if not finite.
  /// With a response time tau > 0, the mean over [tau, tau + 0.1 s] instead: a robot whose velocity follows its
  /// command with lag tau tracks v(t) when commanded about v(t + tau) (v + tau dv/dt), so the plan's
  /// accelerations, braking included, are realised rather than damped (docs/protocol_v2.md).
  Eigen::Vector2d command(const Eigen::Ref<const Eigen::RowVectorXd>& xi) const;
  /// World-frame positions of a plan, one per step, into `out` (resized to the steps).
  void world_positions(const Eigen::Ref<const Eigen::RowVectorXd>& xi, const Frame& frame, std::vector<Vec2>& out) const;
  /// Least-squares coefficients of a previous plan shifted by dt seconds and by `offset` metres (its frame's
  /// origin minus the new one), so that it can seed the next cycle; into `out` (2n).
  void shift(const Eigen::RowVectorXd& xi, double dt, const Eigen::Vector2d& offset, Eigen::RowVectorXd& out) const;
  /// Straight line to the goal, into `out` (2n): line_through(goal(frame), out).
  void line_to_goal(const Frame& frame, Eigen::RowVectorXd& out) const;

  const projection::Settings& projection() const { return projection_; }
  const Ranking& ranking() const { return ranking_; }
  const core::BernsteinBasis& basis() const { return ranking_.basis(); }

 private:
  projection::Settings projection_;
  RankingSettings ranking_settings_;
  perception::Perception perception_;
  perception::Observation observation_;
  Ranking ranking_;
  core::TargetPredictor predictor_;
  Eigen::VectorXd forecast_sigma_;
  Eigen::RowVectorXd command_row_;      // (B(0.1) - B(0)) / 0.1
  Eigen::MatrixXd least_squares_;       // n x m: pseudo-inverse of P
  // Workspaces (fill_row, shift, world_positions), sized at construction.
  mutable Eigen::VectorXd cx_, cy_, x_, y_;
  mutable Eigen::MatrixX2d shifted_;
  mutable Eigen::MatrixXd shift_basis_;  // m x n: the basis at the steps' times plus shift_basis_dt_
  mutable double shift_basis_dt_ = std::numeric_limits<double>::quiet_NaN();
  mutable Eigen::VectorXd fit_x_, fit_y_;
};

}  // namespace occtrack::planners::detail
