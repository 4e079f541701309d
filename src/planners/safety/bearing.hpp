// A cheap bearing for the safety layer's lookups by bearing (FreeSpace's sectors, MotionEvidence's beams):
// atan2 within a known error, and the sector or beam it names where that is sure to be the one the exact
// std::atan2 names. Elsewhere the callers take std::atan2, so every answer is the one std::atan2 gives.
#pragma once

#include <algorithm>
#include <cmath>

namespace occtrack::planners::safety::detail {

/// The most rough_bearing can differ from std::atan2, radians. The polynomial's own error is under 2e-8
/// (Abramowitz and Stegun 4.4.49); the rest is room for rounding. tests/test_safety.cpp measures it.
constexpr double kRoughBearingError = 1e-6;
/// The margin the callers keep from a sector edge, a midpoint between beams or atan2's jump: twice the error,
/// room for the roundings of their own arithmetic on the bearing.
constexpr double kRoughBearingSlack = 2.0 * kRoughBearingError;

/// std::atan2(y, x) within kRoughBearingError, for finite (x, y) other than the origin; NaN otherwise (the
/// callers then take std::atan2). Signs follow atan2's, -0 included, so that only bearings near +-pi, where
/// atan2 jumps, can land on the other side.
inline double rough_bearing(double y, double x) {
  if (!(std::isfinite(x) && std::isfinite(y)) || (x == 0.0 && y == 0.0)) return NAN;
  const double ax = std::abs(x), ay = std::abs(y);
  const double big = std::max(ax, ay), small = std::min(ax, ay);
  const double t = small / big, t2 = t * t;  // t in [0, 1]
  double a = t * (1.0 + t2 * (-0.3333314528 + t2 * (0.1999355085 + t2 * (-0.1420889944 + t2 * (0.1065626393 +
             t2 * (-0.0752896400 + t2 * (0.0429096138 + t2 * (-0.0161657367 + t2 * 0.0028662257))))))));
  if (ay > ax) a = M_PI_2 - a;
  if (std::signbit(x)) a = M_PI - a;
  return std::signbit(y) ? -a : a;
}

/// floor(u) where u lies within `slack` of `rough`, when that floor is sure: `rough` at least `slack` from
/// every integer. False otherwise (and for NaN or beyond 1e15).
inline bool sure_floor(double rough, double slack, long* floor_of) {
  if (!(std::abs(rough) < 1e15)) return false;
  const double f = std::floor(rough);
  if (!(rough - f >= slack && f + 1.0 - rough >= slack)) return false;
  *floor_of = static_cast<long>(f);
  return true;
}

/// std::lround((std::atan2(y, x) - angle_min) / increment), the beam nearest the bearing of (x, y), the same
/// answer: on the rough bearing where it is sure (away from atan2's jump at +-pi and from the midpoints
/// between beams), else on the exact one.
inline long nearest_beam(double y, double x, double angle_min, double increment) {
  const double rough = rough_bearing(y, x), error = kRoughBearingSlack;
  long beam = 0;
  if (std::abs(rough) <= M_PI - error && sure_floor((rough - angle_min) / increment + 0.5, error / increment, &beam))
    return beam;
  return std::lround((std::atan2(y, x) - angle_min) / increment);
}

}  // namespace occtrack::planners::safety::detail
