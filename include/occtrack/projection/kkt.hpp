// The two KKT systems of the projection whose matrices depend on the settings only
// (shared/spec/projection.md, "Initial guess" and step 9), assembled and factored once, in double, for every
// implementation: Projector and LiteralProjector, and the torch twin in src/learning/projection.cpp, which
// converts these blocks to tensors. One factoring means the three start from the same numbers.
//
// Both systems are solved through the blocks of their inverses (full-pivot LU, once, at setup):
//
//   step 9:         [[Q, A_eq'], [A_eq, 0]]^-1 = [[M11, M12], [., .]], so xi = M11 rhs + M12 b_eq, with
//                   Q = rho_p I + rho_o N P'P + rho_v Pd'Pd + rho_a Pdd'Pdd + rho_r P'P and
//                   A_eq = [P[0]; Pd[0]; P[m-1]; Pd[m-1]];
//   initial guess:  [[Pdd'Pdd, A_init'], [A_init, 0]]^-1 = [[., initial_guess], [., .]], so
//                   xi_0 = initial_guess (b_eq, x_1, x_2), with A_init = [A_eq; P[s1]; P[s2]].
//
// Per axis: the same matrices serve x and y, every sample and every iteration.
#pragma once

#include <Eigen/Core>

#include "occtrack/projection/projector.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::projection {

template <typename T>
struct KktFactors {
  using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

  /// Factors both systems in double and keeps the blocks in T. Throws std::invalid_argument with the message
  /// of Settings::validate() when the settings are unusable.
  explicit KktFactors(const Settings& settings);

  Matrix M11;            ///< n x n: top-left block of the inverse of step 9's KKT matrix.
  Matrix M12;            ///< n x 4: its top-right block, which multiplies b_eq.
  Matrix M11_Qm;         ///< n x n: M11 (Q - rho_p I), for the rearranged step 9 of the fast paths.
  Matrix initial_guess;  ///< n x 6: maps (b_eq, x_1, x_2) of one axis to xi_0.

  /// b_eq = (0, v0, x_f, vx_f) of one axis of sample b (step 9's equality constraints; the robot starts at
  /// the origin).
  static Eigen::Matrix<T, 4, 1> equality_rhs(const Problem<T>& problem, int b, int axis);
  /// (b_eq, x_1, x_2) of one axis of sample b, the right-hand side of the initial guess.
  static Eigen::Matrix<T, 6, 1> initial_guess_rhs(const Problem<T>& problem, int b, int axis);
};

extern template struct KktFactors<float>;
extern template struct KktFactors<double>;

}  // namespace occtrack::projection
