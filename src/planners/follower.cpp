#include "occtrack/planners/follower.hpp"

#include <chrono>

#include "context.hpp"

namespace occtrack::planners {

struct Follower::Impl {
  detail::Context context;
  projection::Projector<float> projector;
  projection::Problem<float> problem;
  projection::Result<float> result;
  detail::Frame frame;

  explicit Impl(const FollowerSettings& s)
      : context(s.projection, perception::Settings{}, s.ranking),
        projector(s.projection),
        problem(projector.make_problem()),
        result(projector.make_result()) {}
};

Follower::Follower(const FollowerSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
Follower::~Follower() = default;
void Follower::reset() { impl_->context.reset(); }

PlannerOutput Follower::plan(const PlannerInput& input) {
  const auto start = std::chrono::steady_clock::now();
  PlannerOutput out;
  auto& s = *impl_;
  std::string error;
  if (!s.context.observe(input, s.frame, &error)) {
    out.ok = false;
    out.message = error;
  } else {
    const Eigen::RowVectorXd line = s.context.straight_line(s.context.goal(s.frame));
    const Eigen::Vector2d terminal_velocity = s.frame.target.tail<2>();
    s.context.fill_row(s.problem, 0, line, s.frame, &terminal_velocity);
    if (!s.projector.solve(s.problem, s.result, &error) ||
        s.result.status != projection::SolveStatus::solved) {
      out.ok = false;
      out.message = error.empty() ? "projection produced non-finite values" : error;
    } else {
      const Eigen::RowVectorXd xi = s.result.xi.row(0).cast<double>();
      out.command_velocity = s.context.command(xi);
      out.plan = s.context.world_positions(xi, s.frame);
    }
  }
  out.compute_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace occtrack::planners
