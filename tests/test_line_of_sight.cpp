// The geometric occlusion cost (occlusion/line_of_sight.hpp): hand-computed costs, a stride < 1 refused, and
// the two-round point filter against every point at every step, with core::point_segment_distance.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <stdexcept>
#include <cmath>
#include <random>
#include <vector>

#include "occtrack/core/geometry.hpp"
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

// The two rounds keep every point that can count. Random plans that weave among random moving points, with
// spans cut at every stride and horizon: the cost equals the sum over every step and every point of the
// formula, written plainly (core::point_segment_distance), and the scratch is reused between calls.
TEST(LineOfSight, TwoRoundsCountEveryPointThatCanCount) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-4.0, 4.0), speed(-1.5, 1.5);
  std::vector<int> scratch;
  int counted_calls = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int steps = 1 + trial % 37, stride = 1 + trial % 5, count = trial % 61;
    Lines l;
    l.positions.resize(steps, 2);
    l.targets.resize(steps, 2);
    l.times = Eigen::VectorXd::LinSpaced(steps, 0.0, 5.0);
    l.weights = Eigen::VectorXd::LinSpaced(steps, 1.0, 0.3);
    Eigen::Vector2d robot(uniform(rng), uniform(rng)), target(uniform(rng), uniform(rng));
    const Eigen::Vector2d robot_v(speed(rng), speed(rng)), target_v(speed(rng), speed(rng));
    for (int k = 0; k < steps; ++k) {
      l.positions.row(k) = (robot + robot_v * l.times(k)).transpose();
      l.targets.row(k) = (target + target_v * l.times(k)).transpose();
    }
    Points points(count, 4);
    for (int j = 0; j < count; ++j) points.row(j) << uniform(rng), uniform(rng), speed(rng), speed(rng);
    const double margin = 0.2 + 0.1 * (trial % 7);
    double expected = 0.0;
    for (int k = 0; k < steps; k += stride) {
      const occtrack::core::Vec2 a(l.positions(k, 0), l.positions(k, 1)), b(l.targets(k, 0), l.targets(k, 1));
      double step_cost = 0.0;
      for (int j = 0; j < count; ++j) {
        const double t = l.times(k);
        const occtrack::core::Vec2 q(points(j, 0) + points(j, 2) * t, points(j, 1) + points(j, 3) * t);
        if ((q - b).norm() < margin) continue;
        const double d = occtrack::core::point_segment_distance(q, a, b);
        if (d < margin) step_cost += (margin - d) * (margin - d);
      }
      expected += l.weights(k) * step_cost;
    }
    const double cost = occtrack::occlusion::occlusion_cost(l.positions, l.targets, l.times, points, l.weights,
                                                            stride, margin, &scratch);
    EXPECT_NEAR(cost, expected, 1e-12 * (1.0 + expected)) << "trial " << trial;
    if (expected > 0.0) ++counted_calls;
  }
  EXPECT_GT(counted_calls, 50);  // most trials have points that count, so the filter was put to the test
}

}  // namespace
