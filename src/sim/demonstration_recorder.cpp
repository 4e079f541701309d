// The demonstration recorder: the planner placed into sim::run_episode while labelling.
#include "occtrack/sim/demonstrations.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <cmath>

namespace occtrack::sim {

namespace {

Eigen::RowVectorXd fit_with(const Eigen::MatrixXd& P, const Eigen::MatrixXd& least_squares,
                            const std::vector<core::Vec2>& positions, const core::Vec2& origin, double* residual) {
  const Eigen::Index m = P.rows(), n = P.cols();
  Eigen::MatrixX2d relative(m, 2);
  for (Eigen::Index k = 0; k < m; ++k) relative.row(k) = (positions[static_cast<std::size_t>(k)] - origin).transpose();
  const Eigen::MatrixX2d coefficients = least_squares * relative;  // n x 2
  Eigen::RowVectorXd xi(2 * n);
  xi.head(n) = coefficients.col(0).transpose();
  xi.tail(n) = coefficients.col(1).transpose();
  if (residual) {
    const double worst = (P * coefficients - relative).cwiseAbs().maxCoeff();
    *residual = std::isfinite(worst) ? worst : INFINITY;
  }
  return xi;
}

}  // namespace

Eigen::RowVectorXd fit_coefficients(const core::BernsteinBasis& basis, const std::vector<core::Vec2>& positions,
                                    const core::Vec2& origin, double* residual) {
  if (static_cast<int>(positions.size()) != basis.steps)
    throw std::invalid_argument("fit_coefficients: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(basis.steps) + " steps");
  const Eigen::MatrixXd least_squares = basis.P.completeOrthogonalDecomposition().pseudoInverse();
  return fit_with(basis.P, least_squares, positions, origin, residual);
}

DemonstrationRecorder::DemonstrationRecorder(std::unique_ptr<planners::Planner> expert,
                                             std::unique_ptr<planners::Planner> driver,
                                             const planners::ProjCemSettings& expert_settings, int label_every)
    : expert_(std::move(expert)),
      driver_(std::move(driver)),
      settings_(expert_settings),
      label_every_(label_every),
      perception_(expert_settings.perception),
      ranking_(expert_settings.ranking, expert_settings.projection) {
  if (!expert_) throw std::invalid_argument("DemonstrationRecorder: no expert");
  if (label_every < 1) throw std::invalid_argument("DemonstrationRecorder: label_every must be at least 1");
  least_squares_ = ranking_.basis().P.completeOrthogonalDecomposition().pseudoInverse();
}

DemonstrationRecorder::~DemonstrationRecorder() = default;

std::string DemonstrationRecorder::name() const { return driver_ ? driver_->name() : expert_->name(); }

void DemonstrationRecorder::reset() {
  expert_->reset();
  if (driver_) driver_->reset();
  perception_.reset();
  cycle_ = 0;
}

planners::PlannerOutput DemonstrationRecorder::plan(const planners::PlannerInput& input) {
  const bool label = cycle_ % label_every_ == 0;
  ++cycle_;
  ++report_.cycles;
  if (!driver_ || label) {
    // The recorder's perception sees exactly the scans the expert's sees, after the same checks as the
    // planners' (planners/context.cpp, observe), so that their velocity tracks stay identical.
    bool observed = false;
    if (input.scan != nullptr && input.robot_position.allFinite() && input.robot_velocity.allFinite() &&
        input.target_position.allFinite() && input.target_velocity.allFinite())
      observed = perception_.process(*input.scan, input.robot_position, observation_);
    const auto start = std::chrono::steady_clock::now();
    planners::PlannerOutput expert_output = expert_->plan(input);
    report_.expert_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (label) {
      ++report_.labelled;
      if (observed)
        record(input, expert_output);
      else
        ++report_.skipped_failed;
    }
    if (!driver_) return expert_output;
  }
  return driver_->plan(input);
}

bool DemonstrationRecorder::record(const planners::PlannerInput& input, const planners::PlannerOutput& out) {
  if (!out.ok) {
    ++report_.skipped_failed;
    return false;
  }
  const core::BernsteinBasis& basis = ranking_.basis();
  bool finite = static_cast<int>(out.plan.size()) == basis.steps;
  for (std::size_t k = 0; finite && k < out.plan.size(); ++k) finite = out.plan[k].allFinite();
  if (!finite) {
    ++report_.skipped_nonfinite;
    return false;
  }
  DemonstrationRow row;
  row.expert_xi = fit_with(basis.P, least_squares_, out.plan, input.robot_position, &row.fit_residual);
  if (!row.expert_xi.allFinite()) {
    ++report_.skipped_nonfinite;
    return false;
  }
  if (!(row.fit_residual <= kPlanFitTolerance)) {
    ++report_.skipped_fit;
    return false;
  }
  // The frame the expert ranked in (planners/context.cpp, observe): the target predicted linearly, the nearest
  // points as obstacles, every distinct cloud point as a possible occluder.
  Eigen::Vector4d target;
  target << input.target_position - input.robot_position, input.target_velocity;
  const int distinct = std::min<int>(observation_.voxels, static_cast<int>(observation_.cloud.rows()));
  const int near = std::min<int>(distinct, static_cast<int>(observation_.nearest.rows()));
  planners::PointRows occluders(distinct, 4);
  occluders.topRows(near) = observation_.nearest.topRows(near);
  for (int i = near; i < distinct; ++i) occluders.row(i) << observation_.cloud(i, 0), observation_.cloud(i, 1), 0, 0;
  row.expert_cost = ranking_.evaluate(row.expert_xi, target, observation_.nearest, occluders).total;
  if (!std::isfinite(row.expert_cost)) {
    ++report_.skipped_nonfinite;
    return false;
  }
  row.observation << input.robot_velocity, input.target_position - input.robot_position, input.target_velocity;
  row.cloud = observation_.cloud;
  row.obstacles = observation_.nearest;
  row.time = input.time;
  if (!row.observation.allFinite()) {
    ++report_.skipped_nonfinite;
    return false;
  }
  report_.worst_fit_residual = std::max(report_.worst_fit_residual, row.fit_residual);
  ++report_.rows;
  rows_.push_back(std::move(row));
  return true;
}

// ---------------------------------------------------------------------------------------------------------
// Metadata.


}  // namespace occtrack::sim
