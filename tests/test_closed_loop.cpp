// Closed-loop behaviour: planners in the simulator, determinism, and safe outputs on bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/proj_cem.hpp"
#include "occtrack/sim/episode.hpp"

using namespace occtrack;

namespace {

core::Scenario orbit() { return io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml"); }

void expect_same_outcome(const core::EpisodeMetrics& a, const core::EpisodeMetrics& b) {
  EXPECT_EQ(a.occlusion_time_s, b.occlusion_time_s);
  EXPECT_EQ(a.collisions, b.collisions);
  EXPECT_EQ(a.min_clearance_m, b.min_clearance_m);
  EXPECT_EQ(a.acceleration.mean, b.acceleration.mean);
  EXPECT_EQ(a.acceleration.max, b.acceleration.max);
  EXPECT_EQ(a.tracking_distance_mean_m, b.tracking_distance_mean_m);
  EXPECT_EQ(a.cycles, b.cycles);
}

}  // namespace

TEST(ClosedLoop, ProjCemKeepsASlowTargetInSightAroundAnObstacleAndTheFollowerDoesNot) {
  const core::Scenario scenario = orbit();
  sim::EpisodeSettings settings;
  planners::Follower follower;
  planners::ProjCem projcem;
  const auto naive = sim::run_episode(scenario, follower, settings).metrics;
  const auto aware = sim::run_episode(scenario, projcem, settings).metrics;
  EXPECT_GT(naive.occlusion_time_s, 2.0) << "the follower should lose sight behind the obstacle";
  EXPECT_LT(aware.occlusion_time_s, 0.25 * naive.occlusion_time_s);
  EXPECT_EQ(aware.collisions, 0);
  EXPECT_EQ(naive.collisions, 0);
  EXPECT_EQ(aware.planner_failures, 0);
  EXPECT_EQ(aware.cycles, 600);  // 30 s at 20 Hz
}

TEST(ClosedLoop, SameScenarioAndSeedGiveIdenticalMetrics) {
  core::Scenario scenario = orbit();
  scenario.duration = 3.0;
  scenario.sensor.noise = 0.02;  // noise is seeded too
  sim::EpisodeSettings settings;
  settings.seed = 7;
  planners::ProjCem a, b;
  expect_same_outcome(sim::run_episode(scenario, a, settings).metrics, sim::run_episode(scenario, b, settings).metrics);
  // The same planner object again: reset() must forget the previous episode.
  expect_same_outcome(sim::run_episode(scenario, a, settings).metrics, sim::run_episode(scenario, b, settings).metrics);
  planners::Follower f;
  expect_same_outcome(sim::run_episode(scenario, f, settings).metrics, sim::run_episode(scenario, f, settings).metrics);
}

TEST(ClosedLoop, DelayedCommandsChangeTheOutcomeOnlyWhenAsked) {
  core::Scenario scenario = orbit();
  scenario.duration = 4.0;
  sim::EpisodeSettings settings;
  planners::Follower f;
  const auto immediate = sim::run_episode(scenario, f, settings).metrics;
  settings.delay_by_compute = true;
  const auto delayed = sim::run_episode(scenario, f, settings).metrics;
  EXPECT_EQ(immediate.cycles, delayed.cycles);
  // A command delayed by at least one physics step moves the robot differently.
  EXPECT_NE(immediate.tracking_distance_mean_m, delayed.tracking_distance_mean_m);
}

TEST(ClosedLoop, PlannersBrakeInsteadOfPassingOnBadInput) {
  core::Scan scan;
  scan.angle_increment = 2 * M_PI / 360;
  scan.ranges.assign(360, std::numeric_limits<double>::infinity());  // nothing in range: valid, empty
  planners::PlannerInput input;
  input.target_position = {2.0, 0.0};
  input.scan = &scan;
  planners::Follower follower;
  planners::ProjCem projcem;
  for (planners::Planner* p : {static_cast<planners::Planner*>(&follower), static_cast<planners::Planner*>(&projcem)}) {
    SCOPED_TRACE(p->name());
    const auto fine = p->plan(input);
    EXPECT_TRUE(fine.ok) << fine.message;
    EXPECT_TRUE(fine.command_velocity.allFinite());

    auto bad = input;
    bad.target_position.x() = NAN;
    auto out = p->plan(bad);
    EXPECT_FALSE(out.ok);
    EXPECT_EQ(out.command_velocity, core::Vec2::Zero());
    EXPECT_NE(out.message.find("target"), std::string::npos) << out.message;

    bad = input;
    bad.scan = nullptr;
    out = p->plan(bad);
    EXPECT_FALSE(out.ok);
    EXPECT_EQ(out.command_velocity, core::Vec2::Zero());

    core::Scan broken = scan;
    broken.angle_increment = NAN;
    bad = input;
    bad.scan = &broken;
    out = p->plan(bad);
    EXPECT_FALSE(out.ok);
    EXPECT_EQ(out.command_velocity, core::Vec2::Zero());
    EXPECT_NE(out.message.find("angle_increment"), std::string::npos) << out.message;
  }
}

TEST(ClosedLoop, EpisodeSettingsAreChecked) {
  sim::EpisodeSettings s;
  std::string error;
  EXPECT_TRUE(s.validate(&error)) << error;
  s.planning_period = 0.055;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("planning_period"), std::string::npos) << error;
  planners::Follower f;
  EXPECT_THROW(sim::run_episode(orbit(), f, s), std::invalid_argument);
}

TEST(ClosedLoop, PlannerOptionsFollowTheEpisode) {
  sim::EpisodeSettings e;
  e.tau = 0.3;
  e.latency_ms = 40.0;
  e.planning_period = 0.1;
  e.robot_accel_max = 3.0;
  planners::PlannerOptions mine;
  mine.seed = 7;
  mine.shield = true;
  mine.batch = 5;
  const planners::PlannerOptions o = sim::planner_options_for(e, mine);
  EXPECT_EQ(o.response_time, 0.3);  // leads its command by the robot's lag
  EXPECT_DOUBLE_EQ(o.latency, 0.04);
  e.latency_ms = 15.0;  // a command applies at the first 10 ms physics step at or after 15 ms: 20 ms on
  EXPECT_DOUBLE_EQ(sim::planner_options_for(e).latency, 0.02);
  e.latency_ms = 0.5;
  EXPECT_DOUBLE_EQ(sim::planner_options_for(e).latency, 0.01);
  e.latency_ms = 0.0;
  EXPECT_EQ(sim::planner_options_for(e).latency, 0.0);
  EXPECT_EQ(o.planning_period, 0.1);
  EXPECT_EQ(o.accel_max, 3.0);
  EXPECT_EQ(o.seed, 7u);  // the rest is the caller's
  EXPECT_TRUE(o.shield);
  EXPECT_EQ(o.batch, 5);
  e.latency_ms.reset();  // no latency
  EXPECT_EQ(sim::planner_options_for(e).latency, 0.0);
}
