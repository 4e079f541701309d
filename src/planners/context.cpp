#include "context.hpp"

#include <Eigen/QR>
#include <cmath>

namespace occtrack::planners::detail {

Context::Context(const projection::Settings& projection, const perception::Settings& perception,
                 const RankingSettings& ranking)
    : projection_(projection), ranking_settings_(ranking), perception_(perception), ranking_(ranking, projection) {
  const int n = projection.coefficients();
  const double dt = std::min(0.1, projection.horizon);
  command_row_.resize(n);
  for (int i = 0; i < n; ++i)
    command_row_(i) = (core::bernstein(projection.degree, i, dt / projection.horizon) -
                       core::bernstein(projection.degree, i, 0.0)) / dt;
  least_squares_ = basis().P.completeOrthogonalDecomposition().pseudoInverse();
}

bool Context::observe(const PlannerInput& input, Frame& frame, std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (input.scan == nullptr) return fail("planner input: no scan");
  if (!input.robot_position.allFinite() || !input.robot_velocity.allFinite())
    return fail("planner input: robot state is not finite");
  if (!input.target_position.allFinite() || !input.target_velocity.allFinite())
    return fail("planner input: target state is not finite");
  if (!perception_.process(*input.scan, input.robot_position, observation_, error)) return false;

  frame.time = input.time;
  frame.origin = input.robot_position;
  frame.robot_velocity = input.robot_velocity;
  frame.target << input.target_position - input.robot_position, input.target_velocity;
  frame.nearest = observation_.nearest;
  frame.cloud = observation_.cloud;
  frame.scan = input.scan;
  // Occluders: the nearest points (with velocity estimates), then the rest of the distinct cloud points.
  const int distinct = std::min<int>(observation_.voxels, static_cast<int>(observation_.cloud.rows()));
  const int near = std::min<int>(distinct, static_cast<int>(observation_.nearest.rows()));
  frame.occluders.resize(distinct, 4);
  frame.occluders.topRows(near) = observation_.nearest.topRows(near);
  for (int i = near; i < distinct; ++i) frame.occluders.row(i) << observation_.cloud(i, 0), observation_.cloud(i, 1), 0, 0;
  return true;
}

Eigen::Vector2d Context::goal(const Frame& frame) const {
  const Eigen::Vector2d future = frame.target.head<2>() + frame.target.tail<2>() * projection_.horizon;
  const double distance = future.norm();
  if (distance < 1e-9) return Eigen::Vector2d::Zero();
  return future * std::max(0.0, 1.0 - ranking_settings_.band.reference / distance);
}

Eigen::RowVectorXd Context::straight_line(const Eigen::Vector2d& end) const {
  const int n = projection_.coefficients();
  Eigen::RowVectorXd xi(2 * n);
  for (int i = 0; i < n; ++i) {
    const double s = double(i) / projection_.degree;  // Bernstein coefficients of a linear function
    xi(i) = s * end.x();
    xi(n + i) = s * end.y();
  }
  return xi;
}

void Context::fill_row(projection::Problem<float>& problem, int b, const Eigen::RowVectorXd& xi_bar, const Frame& frame,
                       const Eigen::Vector2d* terminal_velocity) const {
  const int n = projection_.coefficients(), m = projection_.steps;
  const auto& P = basis().P;
  const auto& Pd = basis().Pd;
  const Eigen::VectorXd cx = xi_bar.head(n).transpose(), cy = xi_bar.tail(n).transpose();
  Eigen::Vector2d end_velocity = terminal_velocity ? *terminal_velocity
                                                   : Eigen::Vector2d(Pd.row(m - 1).dot(cx), Pd.row(m - 1).dot(cy));
  const double speed = end_velocity.norm();
  if (speed > projection_.speed_max) end_velocity *= projection_.speed_max / speed;
  problem.robot_velocity.row(b) = frame.robot_velocity.transpose().cast<float>();
  problem.target.row(b) = frame.target.transpose().cast<float>();
  problem.terminal.row(b) << float(P.row(m - 1).dot(cx)), float(P.row(m - 1).dot(cy)), float(end_velocity.x()),
      float(end_velocity.y());
  const int s1 = projection_.via_step_1, s2 = projection_.via_step_2;
  problem.via_points.row(b) << float(P.row(s1).dot(cx)), float(P.row(s1).dot(cy)), float(P.row(s2).dot(cx)),
      float(P.row(s2).dot(cy));
  problem.lambda0.row(b).setZero();
  problem.distance_min.row(b).setConstant(float(ranking_settings_.band.min));
  problem.distance_max.row(b).setConstant(float(ranking_settings_.band.max));
  problem.xi_bar.row(b) = xi_bar.cast<float>();
  const int N = projection_.obstacles;
  for (int j = 0; j < N; ++j)
    for (int f = 0; f < 4; ++f) problem.obstacles(b, 4 * j + f) = float(frame.nearest(j, f));
}

Eigen::Vector2d Context::command(const Eigen::RowVectorXd& xi) const {
  const int n = projection_.coefficients();
  Eigen::Vector2d v(command_row_.dot(xi.head(n)), command_row_.dot(xi.tail(n)));
  if (!v.allFinite()) return Eigen::Vector2d::Zero();
  const double speed = v.norm();
  if (speed > projection_.speed_max) v *= projection_.speed_max / speed;
  return v;
}

std::vector<Vec2> Context::world_positions(const Eigen::RowVectorXd& xi, const Frame& frame) const {
  const int n = projection_.coefficients();
  const Eigen::VectorXd x = basis().P * xi.head(n).transpose(), y = basis().P * xi.tail(n).transpose();
  std::vector<Vec2> out(x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k) out[k] = frame.origin + Vec2(x(k), y(k));
  return out;
}

Eigen::RowVectorXd Context::shift(const Eigen::RowVectorXd& xi, double dt, const Eigen::Vector2d& offset) const {
  const int n = projection_.coefficients(), m = projection_.steps;
  const double T = projection_.horizon;
  Eigen::MatrixX2d positions(m, 2);
  for (int k = 0; k < m; ++k) {
    const double s = std::min(1.0, (basis().times(k) + dt) / T);
    double x = 0, y = 0;
    for (int i = 0; i < n; ++i) {
      const double b = core::bernstein(projection_.degree, i, s);
      x += b * xi(i);
      y += b * xi(n + i);
    }
    positions.row(k) << x + offset.x(), y + offset.y();
  }
  Eigen::RowVectorXd out(2 * n);
  out.head(n) = (least_squares_ * positions.col(0)).transpose();
  out.tail(n) = (least_squares_ * positions.col(1)).transpose();
  return out;
}

}  // namespace occtrack::planners::detail
