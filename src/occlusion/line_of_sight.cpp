#include "occtrack/occlusion/line_of_sight.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace occtrack::occlusion {

double occlusion_cost(const Eigen::Ref<const Eigen::MatrixX2d>& positions,
                      const Eigen::Ref<const Eigen::MatrixX2d>& targets, const Eigen::VectorXd& times,
                      const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>>& points,
                      const Eigen::VectorXd& weights, int stride, double margin, std::vector<int>* scratch) {
  if (stride < 1)
    throw std::invalid_argument("occlusion_cost: stride (" + std::to_string(stride) + ") must be at least 1");
  std::vector<int> local;
  std::vector<int>& candidates = scratch ? *scratch : local;
  double cost = 0.0;
  const double margin2 = margin * margin;
  const Eigen::Index rows = positions.rows();
  for (Eigen::Index first = 0; first < rows; first += static_cast<Eigen::Index>(stride) * kSpanSteps) {
    // Round 1, for a span of up to kSpanSteps checked steps: the box of its lines of sight, grown by the
    // margin (and by a hair, so that no rounding of q = p + v t can put a point of round 2 outside it), and
    // the points whose path over the span's times meets that box. A point that passes a step's box below
    // is among them, so round 2 visits the same points in the same order as testing every point.
    Eigen::Index last = first;
    double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
    for (int i = 0; i < kSpanSteps && first + i * stride < rows; ++i) {
      last = first + i * stride;
      x_lo = std::min({x_lo, positions(last, 0), targets(last, 0)});
      x_hi = std::max({x_hi, positions(last, 0), targets(last, 0)});
      y_lo = std::min({y_lo, positions(last, 1), targets(last, 1)});
      y_hi = std::max({y_hi, positions(last, 1), targets(last, 1)});
    }
    const double extent = std::max({std::abs(x_lo), std::abs(x_hi), std::abs(y_lo), std::abs(y_hi)});
    const double grow = margin + 1e-9 * (1.0 + extent);
    x_lo -= grow;
    x_hi += grow;
    y_lo -= grow;
    y_hi += grow;
    const double t_first = times(first), t_last = times(last);
    candidates.clear();
    for (Eigen::Index j = 0; j < points.rows(); ++j) {
      const double x0 = points(j, 0) + points(j, 2) * t_first, x1 = points(j, 0) + points(j, 2) * t_last;
      const double y0 = points(j, 1) + points(j, 3) * t_first, y1 = points(j, 1) + points(j, 3) * t_last;
      if (std::max(x0, x1) < x_lo || std::min(x0, x1) > x_hi || std::max(y0, y1) < y_lo || std::min(y0, y1) > y_hi)
        continue;
      candidates.push_back(static_cast<int>(j));
    }
    // Round 2, step by step, as core::point_segment_distance with the segment's terms hoisted.
    for (Eigen::Index k = first; k <= last; k += stride) {
      const Eigen::Vector2d a = positions.row(k).transpose();
      const Eigen::Vector2d b = targets.row(k).transpose();
      const Eigen::Vector2d ab = b - a;
      const double length2 = ab.squaredNorm();
      const double t = times(k);
      double step_cost = 0.0;
      // Points outside the segment's bounding box grown by the margin cannot come within the margin.
      const double bx_lo = std::min(a.x(), b.x()) - margin, bx_hi = std::max(a.x(), b.x()) + margin;
      const double by_lo = std::min(a.y(), b.y()) - margin, by_hi = std::max(a.y(), b.y()) + margin;
      for (const int j : candidates) {
        const double qx = points(j, 0) + points(j, 2) * t, qy = points(j, 1) + points(j, 3) * t;
        if (qx < bx_lo || qx > bx_hi || qy < by_lo || qy > by_hi) continue;
        const Eigen::Vector2d q(qx, qy);
        if ((q - b).squaredNorm() < margin2) continue;  // the target's own returns
        const double s = length2 > 0.0 ? std::clamp((q - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
        const double d2 = (q - (a + s * ab)).squaredNorm();
        if (d2 < margin2) {
          const double gap = margin - std::sqrt(d2);
          step_cost += gap * gap;
        }
      }
      cost += weights(k) * step_cost;
    }
  }
  return cost;
}

}  // namespace occtrack::occlusion
