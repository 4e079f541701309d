#include "occtrack/core/qp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <vector>

namespace occtrack::core {

namespace {

bool fail(std::string* error, const std::string& message) {
  if (error) *error = "qp: " + message;
  return false;
}

std::string size_text(Eigen::Index r, Eigen::Index c) { return std::to_string(r) + " x " + std::to_string(c); }

}  // namespace

bool solve_qp(const QpProblem& p, QpResult& result, std::string* error) {
  const Eigen::Index n = p.H.rows(), m_eq = p.A.rows(), m_in = p.C.rows();
  // Misuse first: sizes and finiteness.
  if (n == 0 || p.H.cols() != n) return fail(error, "H must be square and non-empty, got " + size_text(n, p.H.cols()));
  if (p.g.size() != n) return fail(error, "g has " + std::to_string(p.g.size()) + " entries, H has " + std::to_string(n) + " rows");
  if (m_eq > 0 && p.A.cols() != n) return fail(error, "A has " + std::to_string(p.A.cols()) + " columns, expected " + std::to_string(n));
  if (p.b.size() != m_eq) return fail(error, "b has " + std::to_string(p.b.size()) + " entries, A has " + std::to_string(m_eq) + " rows");
  if (m_in > 0 && p.C.cols() != n) return fail(error, "C has " + std::to_string(p.C.cols()) + " columns, expected " + std::to_string(n));
  if (p.d.size() != m_in) return fail(error, "d has " + std::to_string(p.d.size()) + " entries, C has " + std::to_string(m_in) + " rows");
  if (!p.H.allFinite() || !p.g.allFinite() || !p.A.allFinite() || !p.b.allFinite() || !p.C.allFinite() || !p.d.allFinite())
    return fail(error, "H, g, A, b, C and d must be finite");
  if (m_eq > n) return fail(error, "more equalities (" + std::to_string(m_eq) + ") than variables (" + std::to_string(n) + ")");

  // Equalities: x = x0 + Z y with A x0 = b and A Z = 0, from A' P = Q R (column-pivoted QR of A').
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd Z = Eigen::MatrixXd::Identity(n, n);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  Eigen::MatrixXd Q;
  if (m_eq > 0) {
    qr.compute(p.A.transpose());
    if (qr.rank() < m_eq) return fail(error, "the equality constraints A are linearly dependent (rank " + std::to_string(qr.rank()) + " of " + std::to_string(m_eq) + ")");
    Q = qr.householderQ();
    const auto R1 = qr.matrixR().topLeftCorner(m_eq, m_eq).triangularView<Eigen::Upper>();
    x0 = Q.leftCols(m_eq) * R1.transpose().solve(qr.colsPermutation().transpose() * p.b);
    Z = Q.rightCols(n - m_eq);
  }
  const Eigen::Index k = Z.cols();

  result.iterations = 0;
  result.status = QpStatus::solved;
  result.lambda = Eigen::VectorXd::Zero(m_in);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(k);

  // Inequalities in Goldfarb-Idnani's form n_i'y >= b_i, rows scaled to unit length so that one tolerance
  // fits them all; scale_i maps the multipliers back.
  const Eigen::MatrixXd CZ = p.C * Z;
  const Eigen::VectorXd slack0 = p.d - p.C * x0;  // C Z y <= slack0
  Eigen::MatrixXd N(k, m_in);
  Eigen::VectorXd bn(m_in), scale(m_in);
  std::vector<char> usable(m_in, 1);
  const double tol = 1e-11;
  bool infeasible = false;
  for (Eigen::Index i = 0; i < m_in; ++i) {
    const double norm = CZ.row(i).norm();
    scale(i) = norm;
    if (norm <= 1e-14 * (1.0 + p.C.row(i).norm())) {  // constant on the equality set: holds or never does
      usable[i] = 0;
      if (slack0(i) < -tol * (1.0 + std::abs(p.d(i)))) infeasible = true;
      N.col(i).setZero();
      bn(i) = 0.0;
      continue;
    }
    N.col(i) = -CZ.row(i).transpose() / norm;
    bn(i) = -slack0(i) / norm;
  }

  if (k > 0 && !infeasible) {
    const Eigen::MatrixXd G = Z.transpose() * p.H * Z;
    const Eigen::VectorXd a = Z.transpose() * (p.H * x0 + p.g);
    Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (G + G.transpose()));
    const Eigen::VectorXd diag = llt.matrixLLT().diagonal();
    if (llt.info() != Eigen::Success || !(diag.minCoeff() > 1e-7 * diag.maxCoeff()))
      return fail(error, "the Hessian is not positive definite on the equalities' null space");

    // Step 0: the unconstrained minimum, no active constraint.
    y = -llt.solve(a);
    std::vector<Eigen::Index> active;
    std::vector<double> u;  // multipliers of the active constraints, >= 0
    const int max_iterations = static_cast<int>(10 * (m_in + k) + 100);
    Eigen::MatrixXd Nact, GN;
    Eigen::VectorXd r, z, Ginv_np;
    bool done = false;
    while (!done && !infeasible) {
      // Step 1: the most violated constraint; none: optimal.
      Eigen::Index p_idx = -1;
      double worst = -tol;
      std::vector<char> is_active(m_in, 0);
      for (const auto j : active) is_active[j] = 1;
      for (Eigen::Index i = 0; i < m_in; ++i) {
        if (!usable[i] || is_active[i]) continue;
        const double violation = (N.col(i).dot(y) - bn(i)) / (1.0 + std::abs(bn(i)));
        if (violation < worst) worst = violation, p_idx = i;
      }
      if (p_idx < 0) break;
      const Eigen::VectorXd np = N.col(p_idx);
      double u_p = 0.0;
      // Step 2: move towards satisfying p, dropping constraints whose multipliers reach zero first.
      for (;;) {
        if (++result.iterations > max_iterations) {
          result.status = QpStatus::max_iterations;
          done = true;
          break;
        }
        const Eigen::Index q = static_cast<Eigen::Index>(active.size());
        Ginv_np = llt.solve(np);
        if (q > 0) {
          Nact.resize(k, q);
          for (Eigen::Index j = 0; j < q; ++j) Nact.col(j) = N.col(active[j]);
          GN = llt.solve(Nact);
          const Eigen::MatrixXd M = Nact.transpose() * GN;
          r = M.ldlt().solve(Nact.transpose() * Ginv_np);  // dual step direction
          z = Ginv_np - GN * r;                             // primal step direction
        } else {
          r.resize(0);
          z = Ginv_np;
        }
        double t1 = std::numeric_limits<double>::infinity();  // partial step: a multiplier hits zero
        Eigen::Index drop = -1;
        for (Eigen::Index j = 0; j < q; ++j)
          if (r(j) > 1e-14 && u[j] / r(j) < t1) t1 = u[j] / r(j), drop = j;
        const double zn = z.dot(np);
        double t2 = std::numeric_limits<double>::infinity();  // full step: p becomes active
        if (zn > 1e-12 * np.dot(Ginv_np)) t2 = -(np.dot(y) - bn(p_idx)) / zn;
        if (!std::isfinite(t1) && !std::isfinite(t2)) {
          infeasible = true;
          break;
        }
        const double t = std::min(t1, t2);
        if (std::isfinite(t2)) y += t * z;  // with z = 0 the step is in the dual space only
        for (Eigen::Index j = 0; j < q; ++j) u[j] -= t * r(j);
        u_p += t;
        if (t2 <= t1) {
          active.push_back(p_idx);
          u.push_back(u_p);
          break;
        }
        active.erase(active.begin() + drop);
        u.erase(u.begin() + drop);
      }
    }
    for (std::size_t j = 0; j < active.size(); ++j) result.lambda(active[j]) = std::max(0.0, u[j]) / scale(active[j]);
  } else if (!infeasible) {
    for (Eigen::Index i = 0; i < m_in; ++i)
      if (usable[i] && N.col(i).dot(y) - bn(i) < -tol * (1.0 + std::abs(bn(i)))) infeasible = true;
  }

  result.x = x0 + Z * y;
  if (infeasible) result.status = QpStatus::infeasible;
  // Equality multipliers from stationarity: A'nu = -(Hx + g + C'lambda), on the same factorisation.
  result.nu = Eigen::VectorXd::Zero(m_eq);
  if (m_eq > 0) {
    const Eigen::VectorXd w = -(p.H * result.x + p.g + p.C.transpose() * result.lambda);
    const auto R1 = qr.matrixR().topLeftCorner(m_eq, m_eq).triangularView<Eigen::Upper>();
    result.nu = qr.colsPermutation() * R1.solve(Q.leftCols(m_eq).transpose() * w);
  }
  return true;
}

}  // namespace occtrack::core
