// Bernstein polynomial basis sampled on a uniform time grid.
//
// A trajectory axis is x(t) = sum_i c_i B_{i,D}(t / T) with B_{i,D}(s) = C(D,i) (1-s)^(D-i) s^i. Sampled at
// t_k = k T / (m - 1), k = 0..m-1 (both ends included), the basis becomes three m x (D+1) matrices:
// positions P, and the exact first and second time derivatives Pd and Pdd (carrying 1/T and 1/T^2).
// See shared/spec/projection.md, "Basis".
#pragma once

#include <Eigen/Core>

namespace occtrack::core {

struct BernsteinBasis {
  int degree = 0;        ///< D; each axis has D + 1 coefficients.
  int steps = 0;         ///< m, samples on the horizon, both ends included.
  double horizon = 0.0;  ///< T in seconds.
  Eigen::VectorXd times; ///< t_k, size m.
  Eigen::MatrixXd P;     ///< m x (D+1), positions.
  Eigen::MatrixXd Pd;    ///< m x (D+1), first time derivative.
  Eigen::MatrixXd Pdd;   ///< m x (D+1), second time derivative.

  int coefficients() const { return degree + 1; }
};

/// Builds the sampled basis. Requires degree >= 2 (so that acceleration is not identically zero),
/// steps >= 2 and a positive, finite horizon; throws std::invalid_argument naming the argument otherwise.
BernsteinBasis bernstein_basis(int degree, int steps, double horizon);

/// Value of the i-th Bernstein polynomial of the given degree at s in [0, 1]; zero outside 0 <= i <= degree.
double bernstein(int degree, int i, double s);

}  // namespace occtrack::core
