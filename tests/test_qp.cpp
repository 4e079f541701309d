// The dense QP solver (core/qp.hpp) against exact solutions: the closed-form KKT solution of equality-only
// problems, and brute-force enumeration of active sets on small random problems.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "occtrack/core/qp.hpp"

using namespace occtrack;

namespace {

Eigen::MatrixXd random_matrix(std::mt19937_64& rng, int rows, int cols) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd m(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) m(i, j) = normal(rng);
  return m;
}

/// min 1/2 x'Hx + g'x s.t. E x = e, by the KKT system [H E'; E 0] [x; nu] = [-g; e].
Eigen::VectorXd kkt_solution(const Eigen::MatrixXd& H, const Eigen::VectorXd& g, const Eigen::MatrixXd& E,
                             const Eigen::VectorXd& e, Eigen::VectorXd* nu = nullptr) {
  const int n = static_cast<int>(H.rows()), m = static_cast<int>(E.rows());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n + m, n + m);
  K.topLeftCorner(n, n) = H;
  K.topRightCorner(n, m) = E.transpose();
  K.bottomLeftCorner(m, n) = E;
  Eigen::VectorXd rhs(n + m);
  rhs << -g, e;
  const Eigen::VectorXd z = K.fullPivLu().solve(rhs);
  if (nu) *nu = z.tail(m);
  return z.head(n);
}

void expect_kkt(const core::QpProblem& p, const core::QpResult& r, double tol) {
  const Eigen::VectorXd stationarity = p.H * r.x + p.g + p.A.transpose() * r.nu + p.C.transpose() * r.lambda;
  EXPECT_LT(stationarity.lpNorm<Eigen::Infinity>(), tol);
  if (p.A.rows() > 0) {
    EXPECT_LT((p.A * r.x - p.b).lpNorm<Eigen::Infinity>(), tol);
  }
  for (int i = 0; i < p.C.rows(); ++i) {
    const double slack = p.d(i) - p.C.row(i).dot(r.x);
    EXPECT_GT(slack, -tol) << "inequality " << i;
    EXPECT_GE(r.lambda(i), 0.0) << "inequality " << i;
    EXPECT_LT(std::abs(r.lambda(i) * slack), tol) << "complementarity " << i;
  }
}

}  // namespace

TEST(Qp, EqualityOnlyProblemMatchesTheClosedFormKktSolution) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 6, m = 2;
    const Eigen::MatrixXd M = random_matrix(rng, n, n);
    core::QpProblem p;
    p.H = M * M.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    p.g = random_matrix(rng, n, 1);
    p.A = random_matrix(rng, m, n);
    p.b = random_matrix(rng, m, 1);
    p.C.resize(0, n);
    p.d.resize(0);
    core::QpResult r;
    std::string error;
    ASSERT_TRUE(core::solve_qp(p, r, &error)) << error;
    ASSERT_EQ(r.status, core::QpStatus::solved);
    Eigen::VectorXd nu;
    const Eigen::VectorXd x = kkt_solution(p.H, p.g, p.A, p.b, &nu);
    EXPECT_LT((r.x - x).lpNorm<Eigen::Infinity>(), 1e-9) << "trial " << trial;
    EXPECT_LT((r.nu - nu).lpNorm<Eigen::Infinity>(), 1e-8) << "trial " << trial;
    expect_kkt(p, r, 1e-9);
  }
}

TEST(Qp, HessianSingularButDefiniteOnTheEqualitiesIsSolved) {
  // min 1/2 y^2 - y s.t. x = 2: H = diag(0, 1) is singular, positive definite on x = const.
  core::QpProblem p;
  p.H = Eigen::Vector2d(0.0, 1.0).asDiagonal();
  p.g = Eigen::Vector2d(0.0, -1.0);
  p.A = Eigen::RowVector2d(1.0, 0.0);
  p.b = Eigen::VectorXd::Constant(1, 2.0);
  p.C = Eigen::RowVector2d(0.0, 1.0);  // y <= 0.5
  p.d = Eigen::VectorXd::Constant(1, 0.5);
  core::QpResult r;
  ASSERT_TRUE(core::solve_qp(p, r));
  ASSERT_EQ(r.status, core::QpStatus::solved);
  EXPECT_NEAR(r.x(0), 2.0, 1e-12);
  EXPECT_NEAR(r.x(1), 0.5, 1e-12);
  EXPECT_NEAR(r.lambda(0), 0.5, 1e-12);  // y - 1 + lambda = 0
}

TEST(Qp, RandomProblemsMatchBruteForceEnumerationOfActiveSets) {
  std::mt19937_64 rng(11);
  int with_active = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 4, m_eq = trial % 2, m_in = 6;
    const Eigen::MatrixXd M = random_matrix(rng, n, n);
    core::QpProblem p;
    p.H = M * M.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
    p.g = 3.0 * random_matrix(rng, n, 1);
    p.A = random_matrix(rng, m_eq, n);
    p.b = random_matrix(rng, m_eq, 1);
    p.C = random_matrix(rng, m_in, n);
    p.d = random_matrix(rng, m_in, 1).cwiseAbs();  // x = 0 is feasible for the inequalities
    if (m_eq > 0) p.b.setZero();                    // and for the equality
    core::QpResult r;
    std::string error;
    ASSERT_TRUE(core::solve_qp(p, r, &error)) << error;
    ASSERT_EQ(r.status, core::QpStatus::solved) << "trial " << trial;
    expect_kkt(p, r, 1e-9);

    // Brute force: the subset S of inequalities, taken as equalities, whose KKT point is feasible with
    // multipliers >= 0 is the optimum (unique for a strictly convex problem).
    bool found = false;
    for (int mask = 0; mask < (1 << m_in) && !found; ++mask) {
      std::vector<int> S;
      for (int i = 0; i < m_in; ++i)
        if (mask & (1 << i)) S.push_back(i);
      if (static_cast<int>(S.size()) + m_eq > n) continue;
      Eigen::MatrixXd E(m_eq + S.size(), n);
      Eigen::VectorXd e(m_eq + S.size());
      if (m_eq > 0) E.topRows(m_eq) = p.A, e.head(m_eq) = p.b;
      for (std::size_t k = 0; k < S.size(); ++k) E.row(m_eq + k) = p.C.row(S[k]), e(m_eq + k) = p.d(S[k]);
      Eigen::VectorXd nu;
      const Eigen::VectorXd x = kkt_solution(p.H, p.g, E, e, &nu);
      bool ok = ((p.C * x - p.d).array() <= 1e-10).all();
      for (std::size_t k = 0; k < S.size(); ++k) ok = ok && nu(m_eq + k) >= -1e-10;
      if (!ok) continue;
      found = true;
      EXPECT_LT((r.x - x).lpNorm<Eigen::Infinity>(), 1e-9) << "trial " << trial;
      if (!S.empty()) ++with_active;
    }
    EXPECT_TRUE(found) << "trial " << trial;
  }
  EXPECT_GT(with_active, 100) << "the random problems should mostly have active inequalities";
}

TEST(Qp, RepeatedAndParallelConstraintsAreHandled) {
  // min 1/2 |x - (2, 2)|^2 s.t. x0 <= 1 three times over (scaled), x0 + x1 <= 2.
  core::QpProblem p;
  p.H = Eigen::Matrix2d::Identity();
  p.g = Eigen::Vector2d(-2.0, -2.0);
  p.A.resize(0, 2);
  p.b.resize(0);
  p.C.resize(4, 2);
  p.C << 1, 0, 2, 0, 1, 0, 1, 1;
  p.d = Eigen::Vector4d(1, 2, 1, 2);
  core::QpResult r;
  ASSERT_TRUE(core::solve_qp(p, r));
  ASSERT_EQ(r.status, core::QpStatus::solved);
  // Optimum on x0 + x1 = 2 nearest (2, 2): (1, 1), where x0 <= 1 holds with equality too.
  EXPECT_NEAR(r.x(0), 1.0, 1e-12);
  EXPECT_NEAR(r.x(1), 1.0, 1e-12);
  expect_kkt(p, r, 1e-9);
}

TEST(Qp, InfeasibleInequalitiesAreAStatusNotAnError) {
  core::QpProblem p;
  p.H = Eigen::MatrixXd::Identity(1, 1);
  p.g = Eigen::VectorXd::Zero(1);
  p.A.resize(0, 1);
  p.b.resize(0);
  p.C.resize(2, 1);
  p.C << 1, -1;              // x <= -1 and x >= 1
  p.d = Eigen::Vector2d(-1, -1);
  core::QpResult r;
  ASSERT_TRUE(core::solve_qp(p, r));
  EXPECT_EQ(r.status, core::QpStatus::infeasible);
}

TEST(Qp, MisuseIsAnErrorThatSaysWhat) {
  core::QpProblem p;
  p.H = Eigen::MatrixXd::Identity(2, 2);
  p.g = Eigen::VectorXd::Zero(3);
  core::QpResult r;
  std::string error;
  EXPECT_FALSE(core::solve_qp(p, r, &error));
  EXPECT_NE(error.find("g has 3 entries"), std::string::npos) << error;
  p.g = Eigen::VectorXd::Zero(2);
  p.H(0, 0) = std::nan("");
  EXPECT_FALSE(core::solve_qp(p, r, &error));
  EXPECT_NE(error.find("finite"), std::string::npos) << error;
  p.H = Eigen::Vector2d(1.0, -1.0).asDiagonal();
  EXPECT_FALSE(core::solve_qp(p, r, &error));
  EXPECT_NE(error.find("not positive definite"), std::string::npos) << error;
  p.H.setIdentity();
  p.A = Eigen::MatrixXd::Ones(2, 2);
  p.b = Eigen::VectorXd::Zero(2);
  EXPECT_FALSE(core::solve_qp(p, r, &error));
  EXPECT_NE(error.find("linearly dependent"), std::string::npos) << error;
}
