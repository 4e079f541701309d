#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include <Eigen/QR>

#include "occtrack/core/bernstein.hpp"

using occtrack::core::bernstein_basis;

namespace {

struct Grid {
  int degree, steps;
  double horizon;
};

class BernsteinGrid : public ::testing::TestWithParam<Grid> {};

TEST_P(BernsteinGrid, PartitionOfUnityAndNonNegative) {
  const auto [D, m, T] = GetParam();
  const auto basis = bernstein_basis(D, m, T);
  ASSERT_EQ(basis.P.rows(), m);
  ASSERT_EQ(basis.P.cols(), D + 1);
  for (int k = 0; k < m; ++k) {
    EXPECT_NEAR(basis.P.row(k).sum(), 1.0, 1e-13) << "step " << k;
    // Derivatives of a constant are zero: rows of Pd and Pdd sum to zero.
    EXPECT_NEAR(basis.Pd.row(k).sum(), 0.0, 1e-11) << "step " << k;
    EXPECT_NEAR(basis.Pdd.row(k).sum(), 0.0, 1e-9) << "step " << k;
    EXPECT_GE(basis.P.row(k).minCoeff(), 0.0);
  }
}

TEST_P(BernsteinGrid, EndpointsInterpolateFirstAndLastCoefficient) {
  const auto [D, m, T] = GetParam();
  const auto basis = bernstein_basis(D, m, T);
  EXPECT_DOUBLE_EQ(basis.times(0), 0.0);
  EXPECT_NEAR(basis.times(m - 1), T, 1e-12);
  EXPECT_DOUBLE_EQ(basis.P(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(basis.P(m - 1, D), 1.0);
  EXPECT_DOUBLE_EQ(basis.P.row(0).tail(D).cwiseAbs().sum(), 0.0);
  EXPECT_DOUBLE_EQ(basis.P.row(m - 1).head(D).cwiseAbs().sum(), 0.0);
  // Endpoint velocity: D/T (c1 - c0) at the start, D/T (c_D - c_{D-1}) at the end.
  EXPECT_NEAR(basis.Pd(0, 0), -D / T, 1e-12);
  EXPECT_NEAR(basis.Pd(0, 1), D / T, 1e-12);
  EXPECT_NEAR(basis.Pd(m - 1, D), D / T, 1e-12);
  EXPECT_NEAR(basis.Pd(m - 1, D - 1), -D / T, 1e-12);
}

TEST_P(BernsteinGrid, DerivativesMatchFiniteDifferences) {
  const auto [D, m, T] = GetParam();
  const auto basis = bernstein_basis(D, m, T);
  const double h = 1e-5;
  for (int k = 0; k < m; k += std::max(1, m / 7)) {
    const double t = basis.times(k);
    for (int i = 0; i <= D; ++i) {
      auto value = [&](double tt) { return occtrack::core::bernstein(D, i, tt / T); };
      const double fd1 = (value(t + h) - value(t - h)) / (2 * h);
      const double fd2 = (value(t + h) - 2 * value(t) + value(t - h)) / (h * h);
      EXPECT_NEAR(basis.Pd(k, i), fd1, 1e-6 * std::max(1.0, std::abs(fd1))) << "k " << k << " i " << i;
      EXPECT_NEAR(basis.Pdd(k, i), fd2, 2e-3 * std::max(1.0, std::abs(fd2))) << "k " << k << " i " << i;
    }
  }
}

TEST_P(BernsteinGrid, ReproducesAQuadraticExactly) {
  // x(t) = 1 + 2t - 0.3t^2 has degree 2 <= D; its Bernstein coefficients come from degree elevation, so
  // evaluate through a least-squares fit and compare value, velocity and acceleration everywhere.
  const auto [D, m, T] = GetParam();
  const auto basis = bernstein_basis(D, m, T);
  Eigen::VectorXd x(m);
  for (int k = 0; k < m; ++k) {
    const double t = basis.times(k);
    x(k) = 1 + 2 * t - 0.3 * t * t;
  }
  const Eigen::VectorXd c = basis.P.colPivHouseholderQr().solve(x);
  for (int k = 0; k < m; ++k) {
    const double t = basis.times(k);
    EXPECT_NEAR((basis.P * c)(k), x(k), 1e-8);
    EXPECT_NEAR((basis.Pd * c)(k), 2 - 0.6 * t, 1e-6);
    EXPECT_NEAR((basis.Pdd * c)(k), -0.6, 1e-5);
  }
}

INSTANTIATE_TEST_SUITE_P(Grids, BernsteinGrid,
                         ::testing::Values(Grid{10, 100, 5.0}, Grid{2, 3, 1.0}, Grid{5, 40, 2.5}, Grid{15, 200, 8.0},
                                           Grid{7, 11, 0.5}));

TEST(Bernstein, RejectsBadArguments) {
  EXPECT_THROW(bernstein_basis(1, 100, 5.0), std::invalid_argument);
  EXPECT_THROW(bernstein_basis(10, 1, 5.0), std::invalid_argument);
  EXPECT_THROW(bernstein_basis(10, 100, 0.0), std::invalid_argument);
  EXPECT_THROW(bernstein_basis(10, 100, NAN), std::invalid_argument);
  try {
    bernstein_basis(10, 100, -1.0);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("horizon"), std::string::npos) << e.what();
  }
}

}  // namespace
