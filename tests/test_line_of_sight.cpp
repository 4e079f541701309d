// The geometric occlusion cost (occlusion/line_of_sight.hpp): hand-computed costs, and a stride < 1 refused.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <stdexcept>

#include "occtrack/occlusion/line_of_sight.hpp"

namespace {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;

struct Lines {
  Eigen::MatrixX2d positions, targets;
  Eigen::VectorXd times, weights;
};

// Three steps; the robot at the origin, the target at (4, 0), still.
Lines still_lines() {
  Lines l;
  l.positions = Eigen::MatrixX2d::Zero(3, 2);
  l.targets = Eigen::MatrixX2d::Zero(3, 2);
  l.targets.col(0).setConstant(4.0);
  l.times = Eigen::VectorXd::LinSpaced(3, 0.0, 1.0);
  l.weights = Eigen::VectorXd::Ones(3);
  return l;
}

TEST(LineOfSight, PointNearTheLineCostsTheSquaredShortfall) {
  const Lines l = still_lines();
  Points points(2, 4);
  points << 2.0, 0.3, 0.0, 0.0,   // 0.3 from the line: (0.5 - 0.3)^2 per step
      2.0, 3.0, 0.0, 0.0;         // far away: nothing
  const double cost = occtrack::occlusion::occlusion_cost(l.positions, l.targets, l.times, points, l.weights, 1, 0.5);
  EXPECT_NEAR(cost, 3 * 0.2 * 0.2, 1e-12);
  // Every second step: steps 0 and 2.
  EXPECT_NEAR(occtrack::occlusion::occlusion_cost(l.positions, l.targets, l.times, points, l.weights, 2, 0.5),
              2 * 0.2 * 0.2, 1e-12);
}

TEST(LineOfSight, TargetsOwnReturnsAndMovingPoints) {
  const Lines l = still_lines();
  Points points(2, 4);
  points << 3.8, 0.0, 0.0, 0.0,   // within the margin of the target: its own return, ignored
      2.0, -2.0, 0.0, 2.0;        // moves onto the line at t = 1 (the last step)
  EXPECT_NEAR(occtrack::occlusion::occlusion_cost(l.positions, l.targets, l.times, points, l.weights, 1, 0.5),
              0.25, 1e-12);
}

TEST(LineOfSight, StrideBelowOneIsRefused) {
  const Lines l = still_lines();
  const Points points = Points::Zero(1, 4);
  for (const int stride : {0, -1})
    EXPECT_THROW(occtrack::occlusion::occlusion_cost(l.positions, l.targets, l.times, points, l.weights, stride, 0.5),
                 std::invalid_argument);
}

}  // namespace
