// Random but plausible projection problems, for benchmarks, tests and the shipped example.
//
// A seeded world of a few cylinders around the robot is "scanned" (points on the sides facing the robot),
// the N nearest points become every sample's obstacles, a target stands 1.5 to 3.5 m away and moves at up to
// 1.5 m/s, and each sample gets its own terminal state, via points, bounds and nominal coefficients, as a
// CVAE's samples would.
#pragma once

#include <cstdint>

#include "occtrack/projection/projector.hpp"

namespace occtrack::projection {

struct RandomProblemOptions {
  std::uint64_t seed = 1;
  double moving_share = 0.0;  ///< Share of cylinders that move (at 0.7 m/s), in [0, 1].
};

/// Fills `problem` (resized for the settings) with a random plausible batch.
template <typename T>
void fill_random_problem(const Settings& settings, const RandomProblemOptions& options, Problem<T>& problem);

extern template void fill_random_problem<float>(const Settings&, const RandomProblemOptions&, Problem<float>&);
extern template void fill_random_problem<double>(const Settings&, const RandomProblemOptions&, Problem<double>&);

}  // namespace occtrack::projection
