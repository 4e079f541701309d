#include "occtrack/core/bernstein.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace occtrack::core {

namespace {

double binomial(int n, int k) {
  double result = 1.0;
  for (int i = 1; i <= k; ++i) result = result * (n - k + i) / i;
  return result;
}

}  // namespace

double bernstein(int degree, int i, double s) {
  if (i < 0 || i > degree) return 0.0;
  return binomial(degree, i) * std::pow(1.0 - s, degree - i) * std::pow(s, i);
}

BernsteinBasis bernstein_basis(int degree, int steps, double horizon) {
  if (degree < 2)
    throw std::invalid_argument("bernstein_basis: degree must be at least 2, got " + std::to_string(degree));
  if (steps < 2)
    throw std::invalid_argument("bernstein_basis: steps must be at least 2, got " + std::to_string(steps));
  if (!std::isfinite(horizon) || horizon <= 0.0)
    throw std::invalid_argument("bernstein_basis: horizon must be positive and finite, got " +
                                std::to_string(horizon));

  BernsteinBasis basis;
  basis.degree = degree;
  basis.steps = steps;
  basis.horizon = horizon;
  const int n = degree + 1;
  basis.times.resize(steps);
  basis.P.resize(steps, n);
  basis.Pd.resize(steps, n);
  basis.Pdd.resize(steps, n);

  // d/ds B_{i,D} = D (B_{i-1,D-1} - B_{i,D-1});  d2/ds2 B_{i,D} = D (D-1) (B_{i-2,D-2} - 2 B_{i-1,D-2} + B_{i,D-2}).
  const double D = degree;
  const double first = D / horizon;
  const double second = D * (D - 1.0) / (horizon * horizon);
  for (int k = 0; k < steps; ++k) {
    const double t = k * horizon / (steps - 1);
    const double s = t / horizon;
    basis.times(k) = t;
    for (int i = 0; i < n; ++i) {
      basis.P(k, i) = bernstein(degree, i, s);
      basis.Pd(k, i) = first * (bernstein(degree - 1, i - 1, s) - bernstein(degree - 1, i, s));
      basis.Pdd(k, i) = second * (bernstein(degree - 2, i - 2, s) - 2.0 * bernstein(degree - 2, i - 1, s) +
                                  bernstein(degree - 2, i, s));
    }
  }
  return basis;
}

}  // namespace occtrack::core
