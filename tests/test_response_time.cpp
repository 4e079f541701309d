// A robot whose velocity lags its command (Protocol v2's tau) is commanded the plan's velocity tau ahead
// (planners' response_time, docs/protocol_v2.md): the command is checked against the chosen plan's own
// coefficients, and closed loop the lagging robot keeps the clearance the plan promised.
#include <gtest/gtest.h>

#include <random>

#include "occtrack/core/bernstein.hpp"
#include "occtrack/core/robot_response.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/world.hpp"

namespace occtrack {
namespace {

/// The mean velocity over [t0, t0 + 0.1] of the plan with coefficients xi (x then y; degree 10, horizon 5 s).
Eigen::Vector2d mean_velocity(const Eigen::RowVectorXd& xi, double t0) {
  const int n = 11;
  auto position = [&](double t) {
    Eigen::Vector2d p = Eigen::Vector2d::Zero();
    for (int i = 0; i < n; ++i) {
      const double b = core::bernstein(10, i, t / 5.0);
      p += b * Eigen::Vector2d(xi(i), xi(n + i));
    }
    return p;
  };
  return (position(t0 + 0.1) - position(t0)) / 0.1;
}

planners::PlannerOutput plan_once(planners::Planner& planner, const core::Scenario& scenario) {
  sim::World world(scenario);
  std::mt19937_64 rng(1);
  const core::Scan scan = world.scan(scenario.robot_position, 0.0, rng);
  planners::PlannerInput input;
  input.robot_position = scenario.robot_position;
  input.target_position = world.target_position(0.0);
  input.target_velocity = world.target_velocity(0.0);
  input.scan = &scan;
  return planner.plan(input);
}

TEST(ResponseTime, TheCommandIsThePlansVelocityTauAhead) {
  const core::Scenario scenario = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml");
  for (double tau : {0.0, 0.25, 0.6}) {
    SCOPED_TRACE(tau);
    planners::FollowerSettings s;
    s.response_time = tau;
    planners::Follower follower(s);
    const planners::PlannerOutput out = plan_once(follower, scenario);
    ASSERT_TRUE(out.ok) << out.message;
    const Eigen::Vector2d expected = mean_velocity(follower.last_record().xi, tau);
    ASSERT_LT(expected.norm(), s.projection.speed_max);  // not capped: the lead alone sets the command
    EXPECT_NEAR((out.command_velocity - expected).norm(), 0.0, 1e-9);
  }
  // The robot starts at rest and accelerates: leading the plan asks for more than its first 0.1 s.
  planners::FollowerSettings lead;
  lead.response_time = 0.25;
  planners::Follower now, ahead(lead);
  EXPECT_GT(plan_once(ahead, scenario).command_velocity.norm(), plan_once(now, scenario).command_velocity.norm());
}

// A command applies `latency` after its scan: make_planner's planners lead their plan by the lag and the
// latency together (command_lead), and the safety layer keeps the lag alone as the robot's.
TEST(ResponseTime, PlannersLeadByTheLatencyToo) {
  const core::Scenario scenario = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml");
  planners::PlannerOptions late, lag_only, lumped;
  late.response_time = 0.25;
  late.latency = 0.15;
  lag_only.response_time = 0.25;
  lumped.response_time = 0.4;
  EXPECT_DOUBLE_EQ(planners::command_lead(late), 0.4);
  EXPECT_DOUBLE_EQ(planners::command_lead(lag_only), 0.25);
  for (const std::string name : {"follower", "projcem", "cvae"}) {
    SCOPED_TRACE(name);
    const auto command = [&](const planners::PlannerOptions& options) {
      const auto planner = planners::make_planner(name, options);
      const planners::PlannerOutput out = plan_once(*planner, scenario);
      EXPECT_TRUE(out.ok) << out.message;
      return Eigen::Vector2d(out.command_velocity);
    };
    const Eigen::Vector2d with_latency = command(late);
    EXPECT_EQ(with_latency, command(lumped));
    // The robot starts at rest and accelerates: 0.15 s further along asks for more.
    EXPECT_GT(with_latency.norm(), command(lag_only).norm() + 1e-3);
  }
}

TEST(ResponseTime, ZeroIsTheV1CommandExactly) {
  const core::Scenario scenario = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml");
  planners::Follower v1, zero(planners::FollowerSettings{});
  EXPECT_EQ(plan_once(v1, scenario).command_velocity, plan_once(zero, scenario).command_velocity);
}

// velocity_change skips the square root well inside the limit: its answer must be the plain formula's (the
// root compared with the limit) bit for bit, also for changes a hair either side of the limit and for the
// values a simulator can meet (zero, no lag, a zero limit).
TEST(ResponseTime, TheVelocityChangeIsThePlainFormulasBitForBit) {
  const auto plain = [](const Eigen::Vector2d& v, const Eigen::Vector2d& u, double lag, double limit) {
    Eigen::Vector2d change = (u - v) * lag;
    const double size = change.norm();
    if (size > limit) change *= limit / size;
    return change;
  };
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int near_limit = 0, cases = 0;
  for (int i = 0; i < 200000; ++i, ++cases) {
    const double lag = i % 7 == 0 ? 1.0 : 0.5 * (unit(rng) + 1.0);
    const double limit = i % 11 == 0 ? 0.0 : 0.05 * (unit(rng) + 1.0);
    const Eigen::Vector2d v(unit(rng), unit(rng));
    Eigen::Vector2d u(unit(rng), unit(rng));
    if (i % 3 == 0 && limit > 0.0) {
      // A change whose size is the limit to within a few parts in 1e12.
      const Eigen::Vector2d direction = Eigen::Vector2d(unit(rng), unit(rng)).normalized();
      u = v + direction * (limit * (1.0 + 4e-12 * unit(rng)) / lag);
      ++near_limit;
    }
    if (i % 13 == 0) u = v;  // no change at all
    const Eigen::Vector2d fast = core::velocity_change(v, u, lag, limit), reference = plain(v, u, lag, limit);
    ASSERT_EQ(fast.x(), reference.x()) << i;
    ASSERT_EQ(fast.y(), reference.y()) << i;
  }
  EXPECT_GT(near_limit, cases / 4);
}

}  // namespace
}  // namespace occtrack
