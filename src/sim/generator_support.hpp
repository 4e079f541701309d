// What every part of the scenario generator draws and rounds with (private to src/sim/): seeded random
// numbers from raw bits, rounding to the files' decimals, angles.
//
// Determinism. A seed must draw the same scenario with every standard library and on every instruction set:
//   - the uniform and normal draws are made here from std::mt19937_64's raw bits, never by
//     std::*_distribution (whose output differs between standard libraries);
//   - the generator's files are compiled without fused multiply-add contraction (OCCTRACK_NO_FMA_CONTRACTION
//     of src/core/no_fma.hpp, after their includes), and the functions declared here are defined out of line
//     in such a file: a decision on a threshold (a grid cell free or not, a candidate clear or not) flips on
//     the last bit, and the path then goes elsewhere. The gaps the generator checks (src/sim/shape_gaps.cpp)
//     and core's segment distances (src/core/geometry.cpp) are compiled the same way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>

#include "occtrack/core/scenario.hpp"

namespace occtrack::sim::generator {

using core::Vec2;

/// Randomness from raw bits, so that a seed gives the same scenario with every standard library.
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1), 53 random bits.
  double uniform();
  double uniform(double lo, double hi);
  bool chance(double p);
  /// Uniform in {0, ..., n - 1}.
  std::size_t index(std::size_t n);
  /// In [lo, hi] with density rising linearly towards hi (mean lo + 2 (hi - lo) / 3).
  double rising(double lo, double hi);
  /// Standard normal (Box-Muller, one value per call).
  double normal();

 private:
  std::mt19937_64 engine_;
};

/// Rounds to `decimals` places: round(x * 10^d) / 10^d is the double nearest the short decimal, so files
/// print it in few digits; never "-0".
double round_to(double x, int decimals);
Vec2 round_to(const Vec2& v, int decimals);

/// The angle in [-pi, pi) that equals a modulo 2 pi.
double wrap_angle(double a);

/// Whether p lies in [-half_w, half_w] x [-half_h, half_h].
bool inside_area(const Vec2& p, double half_w, double half_h);

}  // namespace occtrack::sim::generator
