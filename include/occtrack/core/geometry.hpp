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

/// Distance between the closed segments a-b and c-d; 0 when they cross.
double segment_segment_distance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

}  // namespace occtrack::core
