#include "occtrack/planners/follower.hpp"

#include <stdexcept>

#include "cycle.hpp"

namespace occtrack::planners {

bool FollowerSettings::validate(std::string* error) const {
  return detail::validate_cycle(projection, nullptr, ranking, response_time, error);
}

struct Follower::Impl {
  detail::Context context;
  detail::Optimizer optimizer;
  PlanRecord record;  // record.frame is the cycle's frame
  Eigen::RowVectorXd line;

  explicit Impl(const FollowerSettings& s)
      : context(occtrack::detail::checked(s, "follower").projection, perception::Settings{}, s.ranking, s.response_time),
        optimizer(s.projection) {
    line.resize(2 * s.projection.coefficients());
    record.xi.resize(line.size());
  }
};

Follower::Follower(const FollowerSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
Follower::~Follower() = default;
void Follower::reset() {
  impl_->context.reset();
  impl_->record.valid = false;
}
const PlanRecord& Follower::last_record() const { return impl_->record; }

void Follower::plan(const PlannerInput& input, PlannerOutput& out) {
  detail::CycleClock clock;
  auto& s = *impl_;
  Frame& frame = s.record.frame;
  std::string error;
  if (detail::hold_unobserved(input, out, s.record, clock)) return;
  if (!s.context.observe(input, frame, clock, &error)) return detail::brake(out, s.record, clock, error);
  s.context.line_to_goal(frame, s.line);
  const Eigen::Vector2d terminal_velocity = frame.target.tail<2>();
  s.context.fill_row(s.optimizer.problem, 0, s.line, frame, &terminal_velocity);
  if (!s.optimizer.projector.solve(s.optimizer.problem, s.optimizer.result, &error) || s.optimizer.result.status != projection::SolveStatus::solved)
    return detail::brake(out, s.record, clock, error.empty() ? "projection produced non-finite values" : error);
  out.resize_candidates(0);
  s.record.xi = s.optimizer.result.xi.row(0).cast<double>();
  // The follower does not rank; its record still carries what the ranking makes of its plan.
  const RankingTerms terms =
      s.context.ranking().evaluate(s.record.xi, frame.target, frame.nearest, frame.occluders_view(), frame.scan,
                                  &frame.forecast, &frame.moving);
  s.context.finish_plan(out, s.record, clock, s.record.xi, terms);
}

}  // namespace occtrack::planners
