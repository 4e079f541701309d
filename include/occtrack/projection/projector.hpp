// The batched projection optimizer (shared/spec/projection.md).
//
// Settings, setup once, solve many:
//
//   occtrack::projection::Settings settings;             // defaults of the spec's table
//   occtrack::projection::Projector<float> projector(settings);  // factors the KKT matrices
//   auto problem = projector.make_problem();              // sized inputs; fill them
//   auto result = projector.make_result();                // sized outputs
//   std::string error;
//   if (!projector.solve(problem, result, &error)) { /* misuse: wrong sizes or non-finite input */ }
//   if (result.status != SolveStatus::solved) { /* the iteration itself went non-finite */ }
//
// Memory: the constructor allocates every workspace; solve() performs no heap allocation when the problem
// and result have the sizes of make_problem()/make_result() and threads == 1 (tests/test_no_allocation.cpp
// checks this under EIGEN_RUNTIME_NO_MALLOC). With threads > 1 the OpenMP runtime may allocate once, on the
// first parallel solve.
//
// Both float and double are instantiated. Double reproduces the conformance cases to round-off; float is
// the fast path (it uses an approximate reciprocal square root refined by one Newton step).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "occtrack/projection/settings.hpp"

namespace occtrack::projection {

template <typename T>
using RowMatrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Inputs of one batch, one row per sample, in the robot-centric frame (the robot is at the origin at t=0).
/// Column layouts follow the conformance case files.
template <typename T>
struct Problem {
  RowMatrix<T> robot_velocity;  ///< B x 2: (vx, vy).
  RowMatrix<T> obstacles;       ///< B x 4N: point j of sample b at columns 4j..4j+3 = (x, y, vx, vy).
  RowMatrix<T> target;          ///< B x 4: (x, y, vx, vy), predicted linearly over the horizon.
  RowMatrix<T> terminal;        ///< B x 4: terminal state (x, y, vx, vy) of the initial guess and the projection.
  RowMatrix<T> via_points;      ///< B x 4: (x1, y1, x2, y2) at steps s1 and s2, for the initial guess.
  RowMatrix<T> lambda0;         ///< B x 2n: initial multiplier, x coefficients first.
  RowMatrix<T> distance_min;    ///< B x m: lower tracking-distance bound per step.
  RowMatrix<T> distance_max;    ///< B x m: upper tracking-distance bound per step.
  RowMatrix<T> xi_bar;          ///< B x 2n: nominal coefficients the projection stays close to.

  /// Sizes every field for the settings and fills it with zeros.
  void resize(const Settings& settings);
};

enum class SolveStatus {
  solved,      ///< K iterations ran and every output is finite.
  non_finite,  ///< The iteration produced a non-finite value (for example from extreme inputs); do not use xi.
};

const char* to_string(SolveStatus status);

template <typename T>
struct Result {
  RowMatrix<T> xi_init;           ///< B x 2n: xi_0, the initial guess.
  RowMatrix<T> xi;                ///< B x 2n: xi_K, the projected coefficients.
  Eigen::Matrix<T, Eigen::Dynamic, 1> residual;  ///< B: mean over the K iterations of the step-6 residual.
  RowMatrix<T> residual_history;  ///< B x K when Settings::record_residual_history, else empty.
  SolveStatus status = SolveStatus::solved;

  void resize(const Settings& settings);
};

template <typename T>
class Projector {
 public:
  /// Validates the settings and factors the KKT matrices once. Throws std::invalid_argument with the
  /// message of Settings::validate() when the settings are unusable.
  explicit Projector(const Settings& settings);
  ~Projector();
  Projector(Projector&&) noexcept;
  Projector& operator=(Projector&&) noexcept;
  Projector(const Projector&) = delete;
  Projector& operator=(const Projector&) = delete;

  const Settings& settings() const;

  Problem<T> make_problem() const;
  Result<T> make_result() const;

  /// Solves the batch. Returns false, with *error naming the field and the rule, when the problem has the
  /// wrong sizes or a non-finite entry, or the result has the wrong sizes; the result is then untouched.
  /// Otherwise returns true and fills the result; result.status tells how the iteration ended.
  bool solve(const Problem<T>& problem, Result<T>& result, std::string* error = nullptr);

  /// Checks sizes and finiteness only (what solve() checks first).
  bool check(const Problem<T>& problem, std::string* error = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

extern template class Projector<float>;
extern template class Projector<double>;
extern template struct Problem<float>;
extern template struct Problem<double>;
extern template struct Result<float>;
extern template struct Result<double>;

}  // namespace occtrack::projection
