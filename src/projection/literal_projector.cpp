#include "occtrack/projection/literal_projector.hpp"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

#include "occtrack/core/bernstein.hpp"
#include "problem_check.hpp"

namespace occtrack::projection {

template <typename T>
struct LiteralProjector<T>::Impl {
  using Mat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
  using Vec = Eigen::Matrix<T, Eigen::Dynamic, 1>;

  Settings s;
  int n, m, N;
  Mat P, Pd, Pdd, A_obstacle;        // A_obstacle: P stacked N times (N m x n)
  Mat A_eq, A_init;                  // 4 x n, 6 x n
  Eigen::PartialPivLU<Mat> kkt;      // projection KKT, factored once
  Eigen::PartialPivLU<Mat> kkt_init; // initial-guess KKT, factored once
  Vec times;

  explicit Impl(const Settings& settings) : s(settings) {
    std::string error;
    if (!s.validate(&error)) throw std::invalid_argument("projection settings: " + error);
    n = s.coefficients();
    m = s.steps;
    N = s.obstacles;
    const auto basis = core::bernstein_basis(s.degree, m, s.horizon);
    P = basis.P.cast<T>();
    Pd = basis.Pd.cast<T>();
    Pdd = basis.Pdd.cast<T>();
    times = basis.times.cast<T>();
    A_obstacle.resize(N * m, n);
    for (int j = 0; j < N; ++j) A_obstacle.block(j * m, 0, m, n) = P;
    A_eq.resize(4, n);
    A_eq << P.row(0), Pd.row(0), P.row(m - 1), Pd.row(m - 1);
    A_init.resize(6, n);
    A_init << A_eq, P.row(s.via_step_1), P.row(s.via_step_2);

    const auto& rho = s.rho;
    Mat Q = T(rho.projection) * Mat::Identity(n, n) + T(rho.obstacle) * A_obstacle.transpose() * A_obstacle +
            T(rho.velocity) * Pd.transpose() * Pd + T(rho.acceleration) * Pdd.transpose() * Pdd +
            T(rho.tracking) * P.transpose() * P;
    Mat K = Mat::Zero(n + 4, n + 4);
    K << Q, A_eq.transpose(), A_eq, Mat::Zero(4, 4);
    kkt.compute(K);
    Mat K0 = Mat::Zero(n + 6, n + 6);
    K0 << Pdd.transpose() * Pdd, A_init.transpose(), A_init, Mat::Zero(6, 6);
    kkt_init.compute(K0);
  }

  // unit(w) through the angle, as the reference code does: (cos(atan2(y, x)), sin(atan2(y, x))).
  static void direction(T x, T y, T& ux, T& uy) {
    const T angle = std::atan2(y, x);
    ux = std::cos(angle);
    uy = std::sin(angle);
  }

  void solve_sample(const Problem<T>& p, int b, Result<T>& result) const {
    const auto& rho = s.rho;
    const T a = T(s.obstacle_radius);
    Vec c[2], lambda[2], c_bar[2];
    Vec b_eq[2];
    for (int axis = 0; axis < 2; ++axis) {
      b_eq[axis].resize(4);
      b_eq[axis] << T(0), p.robot_velocity(b, axis), p.terminal(b, axis), p.terminal(b, 2 + axis);
      Vec rhs0 = Vec::Zero(n + 6);
      rhs0.tail(6) << b_eq[axis], p.via_points(b, axis), p.via_points(b, 2 + axis);
      c[axis] = kkt_init.solve(rhs0).head(n);
      result.xi_init.row(b).segment(axis * n, n) = c[axis].transpose();
      lambda[axis] = p.lambda0.row(b).segment(axis * n, n).transpose();
      c_bar[axis] = p.xi_bar.row(b).segment(axis * n, n).transpose();
    }
    T residual_sum = 0;
    for (int iteration = 0; iteration < s.iterations; ++iteration) {
      // 1. Evaluate.
      Vec pos[2], vel[2], acc[2];
      for (int axis = 0; axis < 2; ++axis) {
        pos[axis] = P * c[axis];
        vel[axis] = Pd * c[axis];
        acc[axis] = Pdd * c[axis];
      }
      // 2-6. Directions, distances, residuals and targets, stacked like A_obstacle.
      Vec r_o[2], e_o[2], r_v[2], e_v[2], r_a[2], e_a[2], r_r[2], e_r[2];
      for (int axis = 0; axis < 2; ++axis) {
        r_o[axis].resize(N * m);
        e_o[axis].resize(N * m);
        for (Vec* v : {&r_v[axis], &e_v[axis], &r_a[axis], &e_a[axis], &r_r[axis], &e_r[axis]}) v->resize(m);
      }
      for (int j = 0; j < N; ++j) {
        for (int k = 0; k < m; ++k) {
          const T ox = p.obstacles(b, 4 * j) + p.obstacles(b, 4 * j + 2) * times(k);
          const T oy = p.obstacles(b, 4 * j + 1) + p.obstacles(b, 4 * j + 3) * times(k);
          const T wx = pos[0](k) - ox, wy = pos[1](k) - oy;
          T ux, uy;
          direction(wx, wy, ux, uy);
          const T d_o = std::max(T(1), std::sqrt(wx * wx + wy * wy) / a);
          r_o[0](j * m + k) = wx - a * d_o * ux;
          r_o[1](j * m + k) = wy - a * d_o * uy;
          e_o[0](j * m + k) = ox + a * d_o * ux;
          e_o[1](j * m + k) = oy + a * d_o * uy;
        }
      }
      for (int k = 0; k < m; ++k) {
        // 3. Velocity.
        const T speed = std::sqrt(vel[0](k) * vel[0](k) + vel[1](k) * vel[1](k));
        const T d_v = std::min(std::max(speed, T(s.speed_min)), T(s.speed_max));
        T vx_u, vy_u;
        direction(vel[0](k), vel[1](k), vx_u, vy_u);
        e_v[0](k) = d_v * vx_u;
        e_v[1](k) = d_v * vy_u;
        r_v[0](k) = vel[0](k) - e_v[0](k);
        r_v[1](k) = vel[1](k) - e_v[1](k);
        // 4. Acceleration.
        const T accel = std::sqrt(acc[0](k) * acc[0](k) + acc[1](k) * acc[1](k));
        const T d_a = std::min(std::max(accel, T(0)), T(s.accel_max));
        T ax_u, ay_u;
        direction(acc[0](k), acc[1](k), ax_u, ay_u);
        e_a[0](k) = d_a * ax_u;
        e_a[1](k) = d_a * ay_u;
        r_a[0](k) = acc[0](k) - e_a[0](k);
        r_a[1](k) = acc[1](k) - e_a[1](k);
        // 5. Tracking.
        const T xr = p.target(b, 0) + p.target(b, 2) * times(k);
        const T yr = p.target(b, 1) + p.target(b, 3) * times(k);
        const T wx = pos[0](k) - xr, wy = pos[1](k) - yr;
        const T dist = std::sqrt(wx * wx + wy * wy);
        const T d_r = std::min(std::max(dist, p.distance_min(b, k)), p.distance_max(b, k));
        T rx_u, ry_u;
        direction(wx, wy, rx_u, ry_u);
        e_r[0](k) = xr + d_r * rx_u;
        e_r[1](k) = yr + d_r * ry_u;
        r_r[0](k) = wx - d_r * rx_u;
        r_r[1](k) = wy - d_r * ry_u;
      }
      // 6. Residual: Euclidean norm of each family over all its entries.
      auto norm2 = [](const Vec& x, const Vec& y) { return std::sqrt(x.squaredNorm() + y.squaredNorm()); };
      residual_sum += norm2(r_o[0], r_o[1]) + norm2(r_a[0], r_a[1]) + norm2(r_v[0], r_v[1]) + norm2(r_r[0], r_r[1]);
      for (int axis = 0; axis < 2; ++axis) {
        // 7. Multiplier.
        lambda[axis] -= T(rho.obstacle) * A_obstacle.transpose() * r_o[axis] +
                        T(rho.acceleration) * Pdd.transpose() * r_a[axis] +
                        T(rho.velocity) * Pd.transpose() * r_v[axis] + T(rho.tracking) * P.transpose() * r_r[axis];
        // 9. New xi from the KKT system.
        Vec rhs(n + 4);
        rhs.head(n) = lambda[axis] + T(rho.projection) * c_bar[axis] +
                      T(rho.obstacle) * A_obstacle.transpose() * e_o[axis] +
                      T(rho.velocity) * Pd.transpose() * e_v[axis] +
                      T(rho.acceleration) * Pdd.transpose() * e_a[axis] + T(rho.tracking) * P.transpose() * e_r[axis];
        rhs.tail(4) = b_eq[axis];
        c[axis] = kkt.solve(rhs).head(n);
      }
    }
    result.xi.row(b).head(n) = c[0].transpose();
    result.xi.row(b).tail(n) = c[1].transpose();
    result.residual(b) = residual_sum / T(s.iterations);
  }
};

template <typename T>
LiteralProjector<T>::LiteralProjector(const Settings& settings) : impl_(std::make_unique<Impl>(settings)) {}
template <typename T>
LiteralProjector<T>::~LiteralProjector() = default;

template <typename T>
bool LiteralProjector<T>::solve(const Problem<T>& problem, Result<T>& result, std::string* error) {
  if (!detail::check_problem(impl_->s, problem, error)) return false;
  if (!detail::check_result(impl_->s, result, error)) return false;
  for (int b = 0; b < impl_->s.batch; ++b) impl_->solve_sample(problem, b, result);
  result.status = result.xi.allFinite() && result.residual.allFinite() ? SolveStatus::solved : SolveStatus::non_finite;
  return true;
}

template class LiteralProjector<float>;
template class LiteralProjector<double>;

}  // namespace occtrack::projection
