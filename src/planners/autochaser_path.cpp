// AutoChaser's smooth path (shared/reference/paper_setup.md, "AutoChaser", stage 2): per axis, one
// polynomial per segment between waypoints, minimum integrated squared jerk plus a soft pull of each
// segment's end to its waypoint, continuity of position, velocity and acceleration, and box corridors at
// interior points: a small convex QP, solved by core::solve_qp.
#include <algorithm>
#include <cmath>

#include "occtrack/core/qp.hpp"
#include "occtrack/planners/autochaser.hpp"

namespace occtrack::planners::autochaser {

namespace {

/// d^r/dsigma^r of sigma^i at sigma: i! / (i - r)! sigma^(i - r).
double monomial_derivative(int i, int r, double sigma) {
  if (r > i) return 0.0;
  double factor = 1.0;
  for (int k = 0; k < r; ++k) factor *= i - k;
  return factor * std::pow(sigma, i - r);
}

/// The row that maps one segment's coefficients to its r-th derivative in seconds at normalised time sigma.
Eigen::RowVectorXd derivative_row(int degree, int r, double sigma, double duration) {
  Eigen::RowVectorXd row(degree + 1);
  for (int i = 0; i <= degree; ++i) row(i) = monomial_derivative(i, r, sigma) / std::pow(duration, r);
  return row;
}

}  // namespace

Vec2 SmoothPath::derivative(double t, int r) const {
  if (segments <= 0) return Vec2::Zero();
  t = std::clamp(t, 0.0, duration());
  const int s = std::min(segments - 1, static_cast<int>(t / segment_duration));
  const double sigma = (t - s * segment_duration) / segment_duration;
  const Eigen::RowVectorXd row = derivative_row(degree, r, sigma, segment_duration);
  return coefficients.middleCols(s * (degree + 1), degree + 1) * row.transpose();
}

bool smooth_path(const AutoChaserSettings& settings, const Vec2& start, const Vec2& velocity, const Vec2& acceleration,
                 const std::vector<Vec2>& waypoints, double segment_duration, SmoothPath& out, std::string* error) {
  const int D = settings.degree, n = D + 1, K = static_cast<int>(waypoints.size());
  const int P = settings.corridor_points;
  const double T = segment_duration, w = settings.waypoint_weight, h = settings.corridor_half_width;
  if (K == 0 || !(T > 0.0)) {
    if (error) *error = "smooth path: no waypoint or a non-positive segment duration";
    return false;
  }
  core::QpProblem qp;
  // Cost, as 1/2 x'Hx + g'x: jerk integral int_0^T (p''')^2 dtau = T^-5 int_0^1 (d^3p/dsigma^3)^2 dsigma, and
  // w (p(T) - waypoint)^2 with p(T) the sum of the coefficients.
  Eigen::MatrixXd jerk = Eigen::MatrixXd::Zero(n, n);
  for (int i = 3; i <= D; ++i)
    for (int j = 3; j <= D; ++j)
      jerk(i, j) = monomial_derivative(i, 3, 1.0) * monomial_derivative(j, 3, 1.0) / (i + j - 5) / std::pow(T, 5);
  const Eigen::RowVectorXd end = derivative_row(D, 0, 1.0, T);
  qp.H = Eigen::MatrixXd::Zero(n * K, n * K);
  for (int s = 0; s < K; ++s) qp.H.block(s * n, s * n, n, n) = 2.0 * (jerk + w * end.transpose() * end);
  // Equalities: the start state, then continuity of position, velocity and acceleration at each knot.
  qp.A = Eigen::MatrixXd::Zero(3 * K, n * K);
  for (int r = 0; r < 3; ++r) {
    qp.A.block(r, 0, 1, n) = derivative_row(D, r, 0.0, T);
    for (int s = 0; s + 1 < K; ++s) {
      qp.A.block(3 * (s + 1) + r, s * n, 1, n) = derivative_row(D, r, 1.0, T);
      qp.A.block(3 * (s + 1) + r, (s + 1) * n, 1, n) = -derivative_row(D, r, 0.0, T);
    }
  }
  // Corridors: at P interior points per segment, p <= line + h and -p <= -(line - h).
  qp.C = Eigen::MatrixXd::Zero(2 * P * K, n * K);
  for (int s = 0; s < K; ++s)
    for (int c = 0; c < P; ++c) {
      const Eigen::RowVectorXd row = derivative_row(D, 0, (c + 1.0) / (P + 1.0), T);
      qp.C.block(2 * (s * P + c), s * n, 1, n) = row;
      qp.C.block(2 * (s * P + c) + 1, s * n, 1, n) = -row;
    }
  out.degree = D;
  out.segments = K;
  out.segment_duration = T;
  out.coefficients.resize(2, n * K);
  core::QpResult result;
  for (int axis = 0; axis < 2; ++axis) {
    qp.g = Eigen::VectorXd::Zero(n * K);
    for (int s = 0; s < K; ++s) qp.g.segment(s * n, n) = -2.0 * w * waypoints[s](axis) * end.transpose();
    qp.b = Eigen::VectorXd::Zero(3 * K);
    qp.b.head<3>() << start(axis), velocity(axis), acceleration(axis);
    qp.d.resize(2 * P * K);
    for (int s = 0; s < K; ++s) {
      const double from = s == 0 ? start(axis) : waypoints[s - 1](axis), to = waypoints[s](axis);
      for (int c = 0; c < P; ++c) {
        const double line = from + (to - from) * (c + 1.0) / (P + 1.0);
        qp.d(2 * (s * P + c)) = line + h;
        qp.d(2 * (s * P + c) + 1) = -(line - h);
      }
    }
    std::string why;
    if (!core::solve_qp(qp, result, &why)) {
      if (error) *error = "smooth path: " + why;
      return false;
    }
    if (result.status != core::QpStatus::solved) {
      if (error) *error = std::string("smooth path: the corridor QP ended ") +
                          (result.status == core::QpStatus::infeasible ? "infeasible" : "at its iteration limit");
      return false;
    }
    out.coefficients.row(axis) = result.x.transpose();
  }
  return true;
}

}  // namespace occtrack::planners::autochaser
