// The demonstration recorder: the planner placed into sim::run_episode while labelling. A row is the
// expert's own record of a labelled cycle (planners::PlanRecord): the frame it planned in, the coefficients it
// chose and the cost it ranked them by. Nothing is observed, fitted or ranked a second time.
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "occtrack/sim/demonstrations.hpp"

namespace occtrack::sim {

DemonstrationRecorder::DemonstrationRecorder(std::unique_ptr<planners::Planner> expert,
                                             std::unique_ptr<planners::Planner> driver, int label_every)
    : expert_(std::move(expert)), driver_(std::move(driver)), label_every_(label_every) {
  if (!expert_) throw std::invalid_argument("DemonstrationRecorder: no expert");
  if (label_every < 1) throw std::invalid_argument("DemonstrationRecorder: label_every must be at least 1");
}

DemonstrationRecorder::~DemonstrationRecorder() = default;

std::string DemonstrationRecorder::name() const { return driver_ ? driver_->name() : expert_->name(); }

void DemonstrationRecorder::reset() {
  expert_->reset();
  if (driver_) driver_->reset();
  cycle_ = 0;
}

const planners::PlanRecord& DemonstrationRecorder::last_record() const {
  return driver_ ? driver_->last_record() : expert_->last_record();
}

void DemonstrationRecorder::plan(const planners::PlannerInput& input, planners::PlannerOutput& out) {
  const bool label = cycle_ % label_every_ == 0;
  ++cycle_;
  ++report_.cycles;
  if (!driver_ || label) {
    // When the expert drives, its output is the command; otherwise it only labels.
    planners::PlannerOutput& expert_out = driver_ ? expert_output_ : out;
    const auto start = std::chrono::steady_clock::now();
    expert_->plan(input, expert_out);
    report_.expert_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (label) {
      ++report_.labelled;
      record(expert_out.ok);
    }
    if (!driver_) return;
  }
  driver_->plan(input, out);
}

bool DemonstrationRecorder::record(bool expert_ok) {
  const planners::PlanRecord& expert = expert_->last_record();
  if (!expert_ok || !expert.valid) {
    ++report_.skipped_failed;
    return false;
  }
  const planners::Frame& frame = expert.frame;
  DemonstrationRow row;
  row.observation << frame.robot_velocity, frame.target;
  row.cloud = frame.cloud;
  row.obstacles = frame.nearest;
  row.expert_xi = expert.xi;
  row.expert_cost = expert.terms.total;
  row.time = frame.time;
  if (!row.observation.allFinite() || !row.expert_xi.allFinite() || !std::isfinite(row.expert_cost) ||
      !row.cloud.allFinite() || !row.obstacles.allFinite()) {
    ++report_.skipped_nonfinite;
    return false;
  }
  ++report_.rows;
  rows_.push_back(std::move(row));
  return true;
}

}  // namespace occtrack::sim
