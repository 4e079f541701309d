#include "occtrack/projection/literal_projector.hpp"

#include <cmath>
#include <stdexcept>

#include "occtrack/core/bernstein.hpp"
#include "occtrack/projection/kkt.hpp"
#include "problem_check.hpp"

namespace occtrack::projection {

template <typename T>
struct LiteralProjector<T>::Impl {
  using Mat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
  using Vec = Eigen::Matrix<T, Eigen::Dynamic, 1>;

  Settings s;
  KktFactors<T> kkt;  // both KKT systems, factored once (validates the settings first)
  int n, m, N;
  Mat P, Pd, Pdd, A_obstacle;  // A_obstacle: P stacked N times (N m x n)
  Vec times;

  explicit Impl(const Settings& settings) : s(settings), kkt(settings) {
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
  }

  // unit(w) through the angle, as the reference code does: (cos(atan2(y, x)), sin(atan2(y, x))).
  static void direction(T x, T y, T& ux, T& uy) {
    const T angle = std::atan2(y, x);
    ux = std::cos(angle);
    uy = std::sin(angle);
  }

  /// Steps 3 to 5 at one step, for w = value - origin: d = clamp(|w|, lo, hi), u = unit(w); the target
  /// e = origin + d u (step 8) and the residual r = w - d u (step 6).
  struct BandStep {
    T ex, ey, rx, ry;
  };
  static BandStep band_step(T wx, T wy, T origin_x, T origin_y, T lo, T hi) {
    const T d = std::min(std::max(std::sqrt(wx * wx + wy * wy), lo), hi);
    T ux, uy;
    direction(wx, wy, ux, uy);
    return {origin_x + d * ux, origin_y + d * uy, wx - d * ux, wy - d * uy};
  }

  static void store(const BandStep& step, Vec (&e)[2], Vec (&r)[2], int k) {
    e[0](k) = step.ex;
    e[1](k) = step.ey;
    r[0](k) = step.rx;
    r[1](k) = step.ry;
  }

  void solve_sample(const Problem<T>& p, int b, Result<T>& result) const {
    const auto& rho = s.rho;
    const T a = T(s.obstacle_radius);
    Vec c[2], lambda[2], c_bar[2];
    Eigen::Matrix<T, 4, 1> b_eq[2];
    for (int axis = 0; axis < 2; ++axis) {
      // Initial guess: the c of its KKT system.
      b_eq[axis] = KktFactors<T>::equality_rhs(p, b, axis);
      c[axis] = kkt.initial_guess * KktFactors<T>::initial_guess_rhs(p, b, axis);
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
      // 2-6 and 8. Directions, distances, residuals and targets, stacked like A_obstacle.
      Vec r_o[2], e_o[2], r_v[2], e_v[2], r_a[2], e_a[2], r_r[2], e_r[2];
      for (int axis = 0; axis < 2; ++axis) {
        r_o[axis].resize(N * m);
        e_o[axis].resize(N * m);
        for (Vec* v : {&r_v[axis], &e_v[axis], &r_a[axis], &e_a[axis], &r_r[axis], &e_r[axis]}) v->resize(m);
      }
      for (int j = 0; j < N; ++j) {
        for (int k = 0; k < m; ++k) {
          // 2. Obstacles.
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
        store(band_step(vel[0](k), vel[1](k), T(0), T(0), T(s.speed_min), T(s.speed_max)), e_v, r_v, k);
        // 4. Acceleration.
        store(band_step(acc[0](k), acc[1](k), T(0), T(0), T(0), T(s.accel_max)), e_a, r_a, k);
        // 5. Tracking.
        const T xr = p.target(b, 0) + p.target(b, 2) * times(k);
        const T yr = p.target(b, 1) + p.target(b, 3) * times(k);
        store(band_step(pos[0](k) - xr, pos[1](k) - yr, xr, yr, p.distance_min(b, k), p.distance_max(b, k)), e_r,
              r_r, k);
      }
      // 6. Residual: Euclidean norm of each family over all its entries.
      auto norm2 = [](const Vec& x, const Vec& y) { return std::sqrt(x.squaredNorm() + y.squaredNorm()); };
      const T residual =
          norm2(r_o[0], r_o[1]) + norm2(r_a[0], r_a[1]) + norm2(r_v[0], r_v[1]) + norm2(r_r[0], r_r[1]);
      residual_sum += residual;
      if (s.record_residual_history) result.residual_history(b, iteration) = residual;
      for (int axis = 0; axis < 2; ++axis) {
        // 7. Multiplier.
        lambda[axis] -= T(rho.obstacle) * A_obstacle.transpose() * r_o[axis] +
                        T(rho.acceleration) * Pdd.transpose() * r_a[axis] +
                        T(rho.velocity) * Pd.transpose() * r_v[axis] + T(rho.tracking) * P.transpose() * r_r[axis];
        // 9. New xi: the c of the KKT system [[Q, A_eq'], [A_eq, 0]] [c; nu] = [rhs; b_eq].
        const Vec rhs = lambda[axis] + T(rho.projection) * c_bar[axis] +
                        T(rho.obstacle) * A_obstacle.transpose() * e_o[axis] +
                        T(rho.velocity) * Pd.transpose() * e_v[axis] +
                        T(rho.acceleration) * Pdd.transpose() * e_a[axis] + T(rho.tracking) * P.transpose() * e_r[axis];
        c[axis] = kkt.M11 * rhs + kkt.M12 * b_eq[axis];
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
