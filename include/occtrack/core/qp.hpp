// A small dense convex QP solver (AutoChaser's corridor QP, shared/reference/paper_setup.md):
//
//   minimise 1/2 x'Hx + g'x   subject to   A x = b,   C x <= d.
//
// Debian 12 packages no maintained C++ QP solver (no OSQP, qpOASES or eiquadprog; quadprog only for R), and
// the run-time library takes Eigen only, so this is our own: the equalities are eliminated on a null-space
// basis (x = x0 + Z y), and the remaining inequality QP, strictly convex in y, is solved exactly by the dual
// active-set method of Goldfarb and Idnani (Math. Programming 27, 1983): start at the unconstrained minimum
// (dual feasible), add the most violated constraint, take partial steps that drop constraints whose
// multiplier would turn negative, until the primal is feasible. Exact in finitely many steps; meant for tens
// of variables (every step refactors the active set densely).
#pragma once

#include <Eigen/Core>
#include <string>

namespace occtrack::core {

struct QpProblem {
  Eigen::MatrixXd H;  ///< n x n, symmetric; Z'HZ must be positive definite (Z: null space of A)
  Eigen::VectorXd g;  ///< n
  Eigen::MatrixXd A;  ///< m_eq x n, full row rank (m_eq may be 0)
  Eigen::VectorXd b;  ///< m_eq
  Eigen::MatrixXd C;  ///< m_in x n (m_in may be 0)
  Eigen::VectorXd d;  ///< m_in
};

enum class QpStatus {
  solved,          ///< x optimal: KKT conditions hold to rounding
  infeasible,      ///< the inequalities cannot hold together with the equalities
  max_iterations,  ///< the active-set loop stopped early (degenerate problem); x is the last iterate
};

struct QpResult {
  QpStatus status = QpStatus::solved;
  Eigen::VectorXd x;
  /// Multipliers of Hx + g + A'nu + C'lambda = 0, lambda >= 0 and lambda_i (C x - d)_i = 0.
  Eigen::VectorXd nu, lambda;
  int iterations = 0;  ///< constraints added or dropped
};

/// Solves the problem. False, with *error naming what is wrong, for misuse: mismatched sizes, non-finite
/// data, dependent equalities, or a reduced Hessian that is not positive definite. How a valid problem
/// ended (solved, infeasible) is result.status.
bool solve_qp(const QpProblem& problem, QpResult& result, std::string* error = nullptr);

}  // namespace occtrack::core
