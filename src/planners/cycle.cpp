#include "cycle.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace occtrack::planners::detail {

namespace {
/// True when perceiving with `a` and with `b` gives the same observation but for the nearest points' count.
bool same_but_nearest(perception::Settings a, const perception::Settings& b) {
  a.nearest_count = b.nearest_count;
  return a == b;
}
}  // namespace

bool validate_cycle(const projection::Settings& projection, const perception::Settings* perception,
                    const RankingSettings& ranking, double response_time, std::string* error) {
  std::string why;
  auto fail = [&](const char* group) {
    if (error) *error = group + why;
    return false;
  };
  if (!projection.validate(&why)) return fail("projection.");
  if (perception && !perception->validate(&why)) return fail("perception.");
  if (!ranking.validate(&why)) return fail("ranking.");
  if (!(std::isfinite(response_time) && response_time >= 0.0 && response_time < projection.horizon)) {
    if (error)
      *error = "response_time (" + std::to_string(response_time) +
               " s, the command's lead: the robot's lag plus the latency) must lie in [0, projection.horizon = " +
               std::to_string(projection.horizon) + " s)";
    return false;
  }
  if (perception && perception->nearest_count != projection.obstacles) {
    why = "nearest_count (" + std::to_string(perception->nearest_count) + ") must equal projection.obstacles (" +
          std::to_string(projection.obstacles) + ")";
    return fail("perception.");
  }
  return true;
}

void finish(PlannerOutput& out, const CycleClock& clock) { out.compute_ms = clock.elapsed_ms(); }

void brake(PlannerOutput& out, PlanRecord& record, const CycleClock& clock, std::string_view message) {
  out.ok = false;
  out.message.assign(message);
  out.command_velocity.setZero();
  out.plan.clear();
  out.resize_candidates(0);
  record.valid = false;
  finish(out, clock);
}

bool hold_unobserved(const PlannerInput& input, PlannerOutput& out, PlanRecord& record, const CycleClock& clock) {
  if (!std::isinf(input.target_age)) return false;
  brake(out, record, clock, "target not observed yet: holding still");
  out.ok = true;  // standing still is the plan here, not a failure
  return true;
}

Context::Context(const projection::Settings& projection, const perception::Settings& perception,
                 const RankingSettings& ranking, double response_time)
    : projection_(projection),
      ranking_settings_(ranking),
      perception_(perception),
      ranking_(ranking, projection),
      predictor_(ranking.predictor) {
  const int n = projection.coefficients(), m = projection.steps;
  for (Eigen::VectorXd* v : {&cx_, &cy_, &fit_x_, &fit_y_}) v->resize(n);
  for (Eigen::VectorXd* v : {&x_, &y_}) v->resize(m);
  shifted_.resize(m, 2);
  shift_basis_.resize(m, n);
  const double dt = std::min(0.1, projection.horizon);
  command_row_.resize(n);
  // v1 (response_time 0): the window [0, dt], evaluated exactly as before.
  const double lead = std::clamp(response_time, 0.0, projection.horizon - dt);
  for (int i = 0; i < n; ++i)
    command_row_(i) = (core::bernstein(projection.degree, i, (lead + dt) / projection.horizon) -
                       core::bernstein(projection.degree, i, lead / projection.horizon)) / dt;
  least_squares_ = basis().P.completeOrthogonalDecomposition().pseudoInverse();
}

bool Context::observe(const PlannerInput& input, Frame& frame, CycleClock& clock, std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (input.scan == nullptr) return fail("planner input: no scan");
  if (!input.robot_position.allFinite() || !input.robot_velocity.allFinite())
    return fail("planner input: robot state is not finite");
  if (!input.target_position.allFinite() || !input.target_velocity.allFinite())
    return fail("planner input: target state is not finite");
  if (!(input.target_age >= 0.0)) return fail("planner input: target age is negative or not a number");
  // The observation: the one perceived for this cycle already, when made with this planner's settings but
  // for more nearest points (its first rows are then those this planner's perception would give: one sorted
  // list, perception.hpp); else this planner's own.
  const perception::Settings& own = perception_.settings();
  const perception::Observation* seen = &observation_;
  if (SharedPerception* shared = input.perceived;
      shared != nullptr && shared->settings != nullptr && shared->observation != nullptr &&
      shared->settings->nearest_count >= own.nearest_count &&
      shared->observation->nearest.rows() >= own.nearest_count && same_but_nearest(*shared->settings, own)) {
    seen = shared->observation;
    shared->used = true;
    clock.credit(shared->ms);
  } else if (!perception_.process(*input.scan, input.robot_position, observation_, error)) {
    return false;
  }

  frame.time = input.time;
  frame.origin = input.robot_position;
  frame.robot_velocity = input.robot_velocity;
  frame.target << input.target_position - input.robot_position, input.target_velocity;
  const double carried = std::min(input.target_age, kMaxTargetPrediction);
  if (ranking_settings_.predict_target) {
    // The estimate's time is input.time - age; a repeated (hidden) estimate is ignored by the predictor.
    predictor_.observe(input.time - input.target_age, input.target_position, input.target_velocity);
    Eigen::Vector2d position, velocity;
    predictor_.state_at(carried, position, velocity);
    // Segment by segment: GCC 12 misreads the comma initializer's AVX loads here (-Warray-bounds).
    frame.target.head<2>() = position - input.robot_position;
    frame.target.tail<2>() = velocity;
    predictor_.predict(carried, basis().times, frame.forecast.positions, forecast_sigma_);
    frame.forecast.positions.rowwise() -= input.robot_position.transpose();
    const double d2 = ranking_settings_.forecast_distance * ranking_settings_.forecast_distance;
    frame.forecast.weights = (1.0 + forecast_sigma_.array().square() / d2).inverse().matrix();
    frame.forecast.valid = true;
  } else if (input.target_age > 0.0) {
    // A hidden target's last estimate, carried forward at constant velocity (the v1 case, age 0, is untouched).
    frame.target.head<2>() += input.target_velocity * carried;
  }
  frame.nearest = seen->nearest.topRows(own.nearest_count);
  if (seen != &observation_ && input.perceived->moving != nullptr &&
      input.perceived->moving->size() >= own.nearest_count)
    frame.moving = input.perceived->moving->head(own.nearest_count);
  else
    frame.moving.resize(0);
  frame.cloud = seen->cloud;
  frame.scan = input.scan;
  // Occluders: the nearest points (with velocity estimates), then the rest of the distinct cloud points.
  // The storage keeps the cloud's size (no reallocation from one cycle to the next).
  const int distinct = std::min<int>(seen->voxels, static_cast<int>(seen->cloud.rows()));
  const int near = std::min<int>(distinct, own.nearest_count);
  if (frame.occluders.rows() < seen->cloud.rows()) frame.occluders.resize(seen->cloud.rows(), 4);
  frame.occluder_count = distinct;
  frame.occluders.topRows(near) = seen->nearest.topRows(near);
  for (int i = near; i < distinct; ++i) frame.occluders.row(i) << seen->cloud(i, 0), seen->cloud(i, 1), 0, 0;
  return true;
}

Eigen::Vector2d Context::goal(const Frame& frame) const {
  const Eigen::Vector2d future = frame.target.head<2>() + frame.target.tail<2>() * projection_.horizon;
  const double distance = future.norm();
  if (distance < 1e-9) return Eigen::Vector2d::Zero();
  return future * std::max(0.0, 1.0 - ranking_settings_.band.reference / distance);
}

void Context::line_to_goal(const Frame& frame, Eigen::RowVectorXd& out) const { line_through(goal(frame), out); }

void Context::line_through(const Eigen::Vector2d& end, Eigen::RowVectorXd& xi) const {
  const int n = projection_.coefficients();
  xi.resize(2 * n);
  for (int i = 0; i < n; ++i) {
    const double s = double(i) / projection_.degree;  // Bernstein coefficients of a linear function
    xi(i) = s * end.x();
    xi(n + i) = s * end.y();
  }
}

void Context::fill_row(projection::Problem<float>& problem, int b, const Eigen::RowVectorXd& xi_bar, const Frame& frame,
                       const Eigen::Vector2d* terminal_velocity) const {
  const int n = projection_.coefficients(), m = projection_.steps;
  const auto& P = basis().P;
  const auto& Pd = basis().Pd;
  Eigen::VectorXd &cx = cx_, &cy = cy_;
  cx = xi_bar.head(n).transpose();
  cy = xi_bar.tail(n).transpose();
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

Eigen::Vector2d Context::command(const Eigen::Ref<const Eigen::RowVectorXd>& xi) const {
  const int n = projection_.coefficients();
  Eigen::Vector2d v(command_row_.dot(xi.head(n)), command_row_.dot(xi.tail(n)));
  if (!v.allFinite()) return Eigen::Vector2d::Zero();
  const double speed = v.norm();
  if (speed > projection_.speed_max) v *= projection_.speed_max / speed;
  return v;
}

void Context::world_positions(const Eigen::Ref<const Eigen::RowVectorXd>& xi, const Frame& frame,
                              std::vector<Vec2>& out) const {
  const int n = projection_.coefficients();
  x_.noalias() = basis().P * xi.head(n).transpose();
  y_.noalias() = basis().P * xi.tail(n).transpose();
  out.resize(static_cast<std::size_t>(x_.size()));
  for (Eigen::Index k = 0; k < x_.size(); ++k) out[k] = frame.origin + Vec2(x_(k), y_(k));
}

void Context::finish_plan(PlannerOutput& out, PlanRecord& record, const CycleClock& clock,
                          const Eigen::Ref<const Eigen::RowVectorXd>& xi, const RankingTerms& terms) const {
  out.ok = true;
  out.message.clear();
  out.command_velocity = command(xi);
  world_positions(xi, record.frame, out.plan);
  if (record.xi.data() != xi.data()) record.xi = xi;
  record.terms = terms;
  record.valid = true;
  finish(out, clock);
}

void Context::shift(const Eigen::RowVectorXd& xi, double dt, const Eigen::Vector2d& offset,
                    Eigen::RowVectorXd& out) const {
  const int n = projection_.coefficients(), m = projection_.steps;
  const double T = projection_.horizon;
  // The basis at the shifted times depends on dt alone, which is the same every cycle at a fixed rate: it is
  // kept for the last dt.
  if (!(dt == shift_basis_dt_)) {
    for (int k = 0; k < m; ++k) {
      const double s = std::min(1.0, (basis().times(k) + dt) / T);
      for (int i = 0; i < n; ++i) shift_basis_(k, i) = core::bernstein(projection_.degree, i, s);
    }
    shift_basis_dt_ = dt;
  }
  Eigen::MatrixX2d& positions = shifted_;
  for (int k = 0; k < m; ++k) {
    double x = 0, y = 0;
    for (int i = 0; i < n; ++i) {
      const double b = shift_basis_(k, i);
      x += b * xi(i);
      y += b * xi(n + i);
    }
    positions.row(k) << x + offset.x(), y + offset.y();
  }
  fit_x_.noalias() = least_squares_ * positions.col(0);
  fit_y_.noalias() = least_squares_ * positions.col(1);
  out.resize(2 * n);
  out.head(n) = fit_x_.transpose();
  out.tail(n) = fit_y_.transpose();
}

}  // namespace occtrack::planners::detail
