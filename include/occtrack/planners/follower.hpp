// The naive follower: the floor every planner must beat. It heads for the point behind the target at the
// reference distance, in a straight line, and ignores occlusion. Obstacles only enter through the
// projection's collision constraints.
#pragma once

#include <memory>
#include <string>

#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::planners {

struct FollowerSettings {
  projection::Settings projection = [] {
    projection::Settings s;
    s.batch = 1;
    return s;
  }();
  RankingSettings ranking;  ///< its tracking band sets the goal; the whole ranking scores the plan (PlanRecord)
  /// s by which commands lead the plan (0: v1): the robot's velocity time constant, Protocol v2's tau, plus
  /// the command latency when make_planner builds it (command_lead).
  double response_time = 0.0;

  /// True when the projection (batch 1 is what the follower projects) and ranking settings are valid;
  /// otherwise false, and *error names the field and the rule ("projection.steps ...").
  bool validate(std::string* error = nullptr) const;
  bool operator==(const FollowerSettings&) const = default;
};

class Follower final : public Planner {
 public:
  /// Throws std::invalid_argument "follower: <validate's message>" for unusable settings.
  explicit Follower(const FollowerSettings& settings = {});
  ~Follower() override;
  std::string name() const override { return "follower"; }
  void reset() override;
  using Planner::plan;
  void plan(const PlannerInput& input, PlannerOutput& out) override;
  const PlanRecord& last_record() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::planners
