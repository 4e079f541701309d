// The naive follower: the floor every planner must beat. It heads for the point behind the target at the
// reference distance, in a straight line, and ignores occlusion. Obstacles only enter through the
// projection's collision constraints.
#pragma once

#include <memory>

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
  RankingSettings ranking;  ///< only its tracking band is used
};

class Follower final : public Planner {
 public:
  explicit Follower(const FollowerSettings& settings = {});
  ~Follower() override;
  std::string name() const override { return "follower"; }
  void reset() override;
  PlannerOutput plan(const PlannerInput& input) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::planners
