// Plane geometry on points and segments, shared by the simulator (its exact checks and the scenario
// generator's placement) and the occlusion cost (line-of-sight segments against obstacle points).
// Shapes (circles, rotated boxes) and ray casting are the simulator's: occtrack/sim/geometry.hpp.
#pragma once

#include <cmath>

#include "occtrack/core/scenario.hpp"

namespace occtrack::core {

/// Unit vector at `angle` radians from +x.
inline Vec2 direction(double angle) { return {std::cos(angle), std::sin(angle)}; }

/// Distance from p to the closed segment a-b (to the point a when a == b).
double point_segment_distance(const Vec2& p, const Vec2& a, const Vec2& b);

/// True when std::sqrt(squared) (a square: not negative, or NaN) is certainly below `limit` without taking the
/// root: squared lies below limit^2 by a relative 1e-9, more than the roundings of the square, the product and
/// the root can bridge (the rounded root is monotone). False for a negative or NaN limit.
inline bool root_clearly_below(double squared, double limit) {
  return limit >= 0.0 && squared < limit * limit * (1.0 - 1e-9);
}

/// std::sqrt(squared) < limit, the same answer for every square (not negative, or NaN) and limit (NaN and
/// infinities included); the root is taken only within a relative 1e-9 of limit^2, or for a negative limit.
inline bool root_below(double squared, double limit) {
  if (limit < 0.0) return std::sqrt(squared) < limit;
  if (root_clearly_below(squared, limit)) return true;
  if (squared > limit * limit * (1.0 + 1e-9)) return false;
  return std::sqrt(squared) < limit;
}

/// Distance between the closed segments a-b and c-d; 0 when they cross.
double segment_segment_distance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

}  // namespace occtrack::core
