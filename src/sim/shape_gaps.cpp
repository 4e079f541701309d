// Gaps between shapes and paths, as the scenario generator checks them (include/occtrack/sim/geometry.hpp).
#include "occtrack/sim/geometry.hpp"

#include <algorithm>
#include <limits>
#include <numbers>

#include "../core/no_fma.hpp"

// No contraction, as in the generator's files: these gaps decide where obstacles and the target may go.
OCCTRACK_NO_FMA_CONTRACTION

namespace occtrack::sim {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
using Kind = core::ObstacleSpec::Shape;
using core::direction;

}  // namespace

std::array<Vec2, 4> box_corners(const Shape& s) {
  const Vec2 u = direction(s.yaw), v(-u.y(), u.x());
  const Vec2 a = s.half_size.x() * u, b = s.half_size.y() * v;
  return {s.center + a + b, s.center - a + b, s.center - a - b, s.center + a - b};
}

bool boxes_overlap(const Shape& p, const Shape& q) {
  const auto cp = box_corners(p), cq = box_corners(q);
  for (const double yaw : {p.yaw, p.yaw + 0.5 * std::numbers::pi, q.yaw, q.yaw + 0.5 * std::numbers::pi}) {
    const Vec2 axis = direction(yaw);
    double p_lo = kInfinity, p_hi = -kInfinity, q_lo = kInfinity, q_hi = -kInfinity;
    for (const Vec2& c : cp) p_lo = std::min(p_lo, c.dot(axis)), p_hi = std::max(p_hi, c.dot(axis));
    for (const Vec2& c : cq) q_lo = std::min(q_lo, c.dot(axis)), q_hi = std::max(q_hi, c.dot(axis));
    if (p_hi < q_lo || q_hi < p_lo) return false;
  }
  return true;
}

double segment_gap(const Shape& s, const Vec2& a, const Vec2& b) {
  if (s.kind == Kind::circle) return core::point_segment_distance(s.center, a, b) - s.radius;
  if (segment_intersects(s, a, b)) return std::min({signed_distance(s, a), signed_distance(s, b), 0.0});
  double gap = std::min(signed_distance(s, a), signed_distance(s, b));
  for (const Vec2& corner : box_corners(s)) gap = std::min(gap, core::point_segment_distance(corner, a, b));
  return gap;
}

double shape_gap(const Shape& p, const Shape& q) {
  if (p.kind == Kind::circle && q.kind == Kind::circle) return (p.center - q.center).norm() - p.radius - q.radius;
  if (p.kind == Kind::circle) return signed_distance(q, p.center) - p.radius;
  if (q.kind == Kind::circle) return signed_distance(p, q.center) - q.radius;
  if (boxes_overlap(p, q)) return -1.0;
  // Disjoint convex polygons: the nearest pair of points has a corner of one of them.
  double gap = kInfinity;
  for (const Vec2& c : box_corners(p)) gap = std::min(gap, signed_distance(q, c));
  for (const Vec2& c : box_corners(q)) gap = std::min(gap, signed_distance(p, c));
  return gap;
}

double polyline_gap(const Shape& s, const std::vector<Vec2>& path) {
  double gap = kInfinity;
  for (std::size_t j = 1; j < path.size(); ++j) gap = std::min(gap, segment_gap(s, path[j - 1], path[j]));
  return gap;
}

double polyline_distance(const std::vector<Vec2>& p, const std::vector<Vec2>& q) {
  double d = kInfinity;
  for (std::size_t i = 1; i < p.size(); ++i)
    for (std::size_t j = 1; j < q.size(); ++j)
      d = std::min(d, core::segment_segment_distance(p[i - 1], p[i], q[j - 1], q[j]));
  return d;
}

}  // namespace occtrack::sim
