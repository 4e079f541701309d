// What the projection-based planners share (private to src/planners): the robot-centric view of one
// cycle, the nominal constraint parameters q, and the conversions between coefficients, commands and the
// world frame.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "occtrack/core/bernstein.hpp"
#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::planners::detail {

/// One cycle's robot-centric view: the robot is at the origin.
struct Frame {
  Eigen::Vector2d robot_velocity = Eigen::Vector2d::Zero();
  Eigen::Vector4d target = Eigen::Vector4d::Zero();  ///< x, y, vx, vy
  PointRows nearest;    ///< the optimizer's obstacles, N x 4 (padded as perception pads)
  PointRows occluders;  ///< every distinct point that can block the view, x 4
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> cloud;  ///< perception's fixed cloud (PointNet input)
  const core::Scan* scan = nullptr;  ///< the cycle's scan (valid during the cycle only), for the shadow term
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< the robot's world position
  double time = 0.0;
};

class Context {
 public:
  Context(const projection::Settings& projection, const perception::Settings& perception,
          const RankingSettings& ranking);

  /// Forgets perception's tracks (velocity estimates); called when an episode starts.
  void reset() { perception_.reset(); }

  /// Perception and frame change. False, with *error, on unusable input (null scan, non-finite state).
  bool observe(const PlannerInput& input, Frame& frame, std::string* error);

  /// Where the naive follower heads: the target's predicted position at the horizon's end, pulled back
  /// towards the robot to the reference distance.
  Eigen::Vector2d goal(const Frame& frame) const;
  /// Coefficients (x then y) of a straight line from the origin to `end` at constant velocity.
  Eigen::RowVectorXd straight_line(const Eigen::Vector2d& end) const;

  /// Fills problem row b with the nominal q for nominal coefficients xi_bar: terminal state and via points
  /// read off xi_bar (terminal speed clamped to speed_max, or `terminal_velocity` when given), lambda0 = 0,
  /// the tracking band as distance bounds.
  void fill_row(projection::Problem<float>& problem, int b, const Eigen::RowVectorXd& xi_bar, const Frame& frame,
                const Eigen::Vector2d* terminal_velocity = nullptr) const;

  /// The command of a plan: its mean velocity over the first 0.1 s, capped at speed_max; zero if not finite.
  Eigen::Vector2d command(const Eigen::RowVectorXd& xi) const;
  /// World-frame positions of a plan, one per step.
  std::vector<Vec2> world_positions(const Eigen::RowVectorXd& xi, const Frame& frame) const;
  /// Least-squares coefficients of a previous plan shifted by dt seconds and by `offset` metres (its frame's
  /// origin minus the new one), so that it can seed the next cycle.
  Eigen::RowVectorXd shift(const Eigen::RowVectorXd& xi, double dt, const Eigen::Vector2d& offset) const;

  const projection::Settings& projection() const { return projection_; }
  const Ranking& ranking() const { return ranking_; }
  const core::BernsteinBasis& basis() const { return ranking_.basis(); }

 private:
  projection::Settings projection_;
  RankingSettings ranking_settings_;
  perception::Perception perception_;
  perception::Observation observation_;
  Ranking ranking_;
  Eigen::RowVectorXd command_row_;      // (B(0.1) - B(0)) / 0.1
  Eigen::MatrixXd least_squares_;       // n x m: pseudo-inverse of P
};

}  // namespace occtrack::planners::detail
