#include "occtrack/projection/kkt.hpp"

#include <Eigen/LU>
#include <stdexcept>
#include <string>

#include "occtrack/core/bernstein.hpp"

namespace occtrack::projection {

template <typename T>
KktFactors<T>::KktFactors(const Settings& settings) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("projection settings: " + error);
  const int n = settings.coefficients(), m = settings.steps;
  const core::BernsteinBasis basis = core::bernstein_basis(settings.degree, m, settings.horizon);
  const auto& rho = settings.rho;

  // Step 9. The obstacle rows of A_f are P stacked N times, so their Gram matrix is N P'P.
  const Eigen::MatrixXd PtP = basis.P.transpose() * basis.P;
  const Eigen::MatrixXd Qm = rho.obstacle * settings.obstacles * PtP + rho.tracking * PtP +
                             rho.velocity * basis.Pd.transpose() * basis.Pd +
                             rho.acceleration * basis.Pdd.transpose() * basis.Pdd;  // Q - rho_p I
  Eigen::MatrixXd A_eq(4, n);
  A_eq << basis.P.row(0), basis.Pd.row(0), basis.P.row(m - 1), basis.Pd.row(m - 1);
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(n + 4, n + 4);
  kkt.topLeftCorner(n, n) = Qm + rho.projection * Eigen::MatrixXd::Identity(n, n);
  kkt.topRightCorner(n, 4) = A_eq.transpose();
  kkt.bottomLeftCorner(4, n) = A_eq;
  const Eigen::MatrixXd inverse = kkt.fullPivLu().inverse();
  M11 = inverse.topLeftCorner(n, n).cast<T>();
  M12 = inverse.topRightCorner(n, 4).cast<T>();
  M11_Qm = (inverse.topLeftCorner(n, n) * Qm).cast<T>();

  // Initial guess: minimise |Pdd c|^2 under the four equalities and the two via points.
  Eigen::MatrixXd A_init(6, n);
  A_init << A_eq, basis.P.row(settings.via_step_1), basis.P.row(settings.via_step_2);
  Eigen::MatrixXd kkt_init = Eigen::MatrixXd::Zero(n + 6, n + 6);
  kkt_init.topLeftCorner(n, n) = basis.Pdd.transpose() * basis.Pdd;
  kkt_init.topRightCorner(n, 6) = A_init.transpose();
  kkt_init.bottomLeftCorner(6, n) = A_init;
  initial_guess = kkt_init.fullPivLu().inverse().topRightCorner(n, 6).cast<T>();
}

template <typename T>
Eigen::Matrix<T, 4, 1> KktFactors<T>::equality_rhs(const Problem<T>& problem, int b, int axis) {
  Eigen::Matrix<T, 4, 1> rhs;
  rhs << T(0), problem.robot_velocity(b, axis), problem.terminal(b, axis), problem.terminal(b, 2 + axis);
  return rhs;
}

template <typename T>
Eigen::Matrix<T, 6, 1> KktFactors<T>::initial_guess_rhs(const Problem<T>& problem, int b, int axis) {
  Eigen::Matrix<T, 6, 1> rhs;
  rhs << equality_rhs(problem, b, axis), problem.via_points(b, axis), problem.via_points(b, 2 + axis);
  return rhs;
}

template struct KktFactors<float>;
template struct KktFactors<double>;

}  // namespace occtrack::projection
