#include "occtrack/occlusion/line_of_sight.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace occtrack::occlusion {

double occlusion_cost(const Eigen::Ref<const Eigen::MatrixX2d>& positions,
                      const Eigen::Ref<const Eigen::MatrixX2d>& targets, const Eigen::VectorXd& times,
                      const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>>& points,
                      const Eigen::VectorXd& weights, int stride, double margin) {
  if (stride < 1)
    throw std::invalid_argument("occlusion_cost: stride (" + std::to_string(stride) + ") must be at least 1");
  double cost = 0.0;
  const double margin2 = margin * margin;
  for (Eigen::Index k = 0; k < positions.rows(); k += stride) {
    const Eigen::Vector2d a = positions.row(k).transpose();
    const Eigen::Vector2d b = targets.row(k).transpose();
    const Eigen::Vector2d ab = b - a;
    const double length2 = ab.squaredNorm();
    const double t = times(k);
    double step_cost = 0.0;
    // Points outside the segment's bounding box grown by the margin cannot come within the margin.
    const double x_lo = std::min(a.x(), b.x()) - margin, x_hi = std::max(a.x(), b.x()) + margin;
    const double y_lo = std::min(a.y(), b.y()) - margin, y_hi = std::max(a.y(), b.y()) + margin;
    for (Eigen::Index j = 0; j < points.rows(); ++j) {
      const double qx = points(j, 0) + points(j, 2) * t, qy = points(j, 1) + points(j, 3) * t;
      if (qx < x_lo || qx > x_hi || qy < y_lo || qy > y_hi) continue;
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
  return cost;
}

}  // namespace occtrack::occlusion
