// Geometric occlusion of predicted lines of sight by obstacle points: the cost term that makes a planner
// keep the target in view.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace occtrack::occlusion {

/// Occlusion cost of one trajectory. For every `stride`-th step k, the line of sight runs from the robot's
/// planned position (positions row k) to the target's predicted position (targets row k); every obstacle point
/// (x, y, vx, vy, predicted linearly to t_k) closer than `margin` to it adds (margin - distance)^2, weighted by
/// `weights(k)` (for instance more weight on the near future). Points within `margin` of the target itself are
/// ignored: a scan often sees the target, and it cannot occlude itself. The distance is
/// core::point_segment_distance's, computed inline with the segment's terms hoisted out of the loop over points.
/// Throws std::invalid_argument when stride < 1 (the steps would never advance).
///
/// The points are tested in two rounds: once per span of kSpanSteps checked steps against the box of the
/// span's lines of sight, then only those that pass, at each step. The sum is the same, term for term and in
/// the same order, as testing every point at every step. `scratch` holds the candidates of a span; give one
/// whose capacity covers the points, and the call allocates nothing (null: a local one).
inline constexpr int kSpanSteps = 4;
double occlusion_cost(const Eigen::Ref<const Eigen::MatrixX2d>& positions,
                      const Eigen::Ref<const Eigen::MatrixX2d>& targets, const Eigen::VectorXd& times,
                      const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>>& points,
                      const Eigen::VectorXd& weights, int stride, double margin, std::vector<int>* scratch = nullptr);

}  // namespace occtrack::occlusion
