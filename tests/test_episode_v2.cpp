// Protocol v2 of the closed-loop episode (shared/spec/simulation.md, "Protocol v2"; docs/protocol_v2.md):
// latency and the replanning rate, the velocity lag, sensing overrides and dropout, target noise,
// line-of-sight target observation, and the occlusion spells of the metrics.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "occtrack/io/results.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/metrics.hpp"
#include "occtrack/sim/world.hpp"

namespace occtrack {
namespace {

using core::Vec2;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A planner that commands a fixed velocity and records what it was given.
class Recorder final : public planners::Planner {
 public:
  explicit Recorder(Vec2 command = Vec2(1.0, 0.0)) : command_(command) {}
  std::string name() const override { return "recorder"; }
  void reset() override {
    ++resets;
    times.clear();
    ages.clear();
    targets.clear();
    range_sums.clear();
    all_dropped.clear();
  }
  using Planner::plan;
  void plan(const planners::PlannerInput& input, planners::PlannerOutput& out) override {
    times.push_back(input.time);
    ages.push_back(input.target_age);
    targets.push_back(input.target_position);
    ++cycles_total;
    bool dropped = true;
    double sum = 0.0;
    for (double r : input.scan->ranges) {
      dropped = dropped && std::isinf(r);
      if (std::isfinite(r)) sum += r;
    }
    range_sums.push_back(sum);
    all_dropped.push_back(dropped);
    out.ok = true;
    out.command_velocity = command_;
    out.compute_ms = 0.0;
  }
  const planners::PlanRecord& last_record() const override { return record_; }

  std::vector<double> times, ages, range_sums;  // since the last reset
  int cycles_total = 0, resets = 0;              // over every reset
  std::vector<Vec2> targets;
  std::vector<bool> all_dropped;

 private:
  Vec2 command_;
  planners::PlanRecord record_;
};

/// An empty world, the robot at rest at the origin, the target 2 m ahead and moving along +x at 0.5 m/s.
core::Scenario open_world(double duration = 2.0) {
  core::Scenario s;
  s.name = "open";
  s.duration = duration;
  s.target = {{0.0, Vec2(2.0, 0.0)}, {duration, Vec2(2.0 + 0.5 * duration, 0.0)}};
  s.sensor.beams = 90;
  return s;
}

/// The robot at the origin, the target 4 m away at (4, 0) and standing still, a wall between them.
core::Scenario hidden_target(double duration = 3.0) {
  core::Scenario s;
  s.name = "hidden";
  s.duration = duration;
  core::ObstacleSpec wall;
  wall.shape = core::ObstacleSpec::Shape::box;
  wall.center = Vec2(2.0, 0.0);
  wall.size = Vec2(0.4, 3.0);
  s.obstacles.push_back(wall);
  s.target = {{0.0, Vec2(4.0, 0.0)}};
  s.sensor.beams = 180;
  return s;
}

sim::EpisodeSettings exact_settings() {
  sim::EpisodeSettings s;
  s.trace_stride = 1;  // every physics step in the trace
  s.snapshots = 0;
  return s;
}

// ------------------------------------------------------------------------------------------------------------
// Latency.

TEST(EpisodeV2, LatencyMakesTheNextCycleWaitAndDelaysTheCommand) {
  const core::Scenario scenario = open_world(2.0);  // 200 steps
  sim::EpisodeSettings settings = exact_settings();
  settings.robot_accel_max = 1000.0;  // the command is reached in one step: its timing shows in the trace

  Recorder none;
  const sim::EpisodeResult v1 = sim::run_episode(scenario, none, settings);
  settings.latency_ms = 120.0;  // 12 steps; next cycle at the first planning tick (every 5 steps) >= t + 12
  Recorder late;
  const sim::EpisodeResult v2 = sim::run_episode(scenario, late, settings);

  // v1: a cycle every 0.05 s, 40 in 2 s. Latency 120 ms: every 0.15 s (0, 0.15, ..., 1.95), 14 cycles.
  EXPECT_EQ(v1.metrics.cycles, 40);
  ASSERT_EQ(v2.metrics.cycles, 14);
  ASSERT_EQ(late.times.size(), 14u);
  for (std::size_t k = 0; k < late.times.size(); ++k) EXPECT_NEAR(late.times[k], 0.15 * double(k), 1e-12);
  EXPECT_EQ(v2.metrics.latency_ms, 120.0);

  // v1: the command applies in the first step, so the robot has moved 0.01 m at step 1. With 120 ms it
  // stands still until step 12 and moves from there: 0.01 m at step 13.
  EXPECT_NEAR(v1.trace.robot[1].x(), 0.01, 1e-12);
  for (int k = 0; k <= 12; ++k) EXPECT_EQ(v2.trace.robot[static_cast<std::size_t>(k)].x(), 0.0) << "step " << k;
  EXPECT_NEAR(v2.trace.robot[13].x(), 0.01, 1e-12);
}

TEST(EpisodeV2, LatencyBelowOnePeriodKeepsTheRateAndRoundsUpToSteps) {
  const core::Scenario scenario = open_world(1.0);
  sim::EpisodeSettings settings = exact_settings();
  settings.robot_accel_max = 1000.0;
  settings.latency_ms = 21.0;  // rounded up to 3 steps
  Recorder planner;
  const sim::EpisodeResult r = sim::run_episode(scenario, planner, settings);
  EXPECT_EQ(r.metrics.cycles, 20);
  EXPECT_EQ(r.trace.robot[3].x(), 0.0);
  EXPECT_NEAR(r.trace.robot[4].x(), 0.01, 1e-12);
}

TEST(EpisodeV2, LatencyZeroIsExactlyNone) {
  core::Scenario scenario = hidden_target(4.0);
  scenario.target = {{0.0, Vec2(-2.0, 0.0)}, {4.0, Vec2(1.0, 2.5)}};
  scenario.robot_position = Vec2(-2.0, -2.0);
  sim::EpisodeSettings settings;
  settings.trace_stride = 1;
  planners::Follower a, b;
  const sim::EpisodeResult none = sim::run_episode(scenario, a, settings);
  settings.latency_ms = 0.0;
  const sim::EpisodeResult zero = sim::run_episode(scenario, b, settings);
  ASSERT_EQ(none.trace.robot.size(), zero.trace.robot.size());
  for (std::size_t k = 0; k < none.trace.robot.size(); ++k) {
    EXPECT_EQ(none.trace.robot[k].x(), zero.trace.robot[k].x()) << k;
    EXPECT_EQ(none.trace.robot[k].y(), zero.trace.robot[k].y()) << k;
  }
  EXPECT_EQ(none.metrics.cycles, zero.metrics.cycles);
  EXPECT_EQ(none.metrics.occlusion_time_s, zero.metrics.occlusion_time_s);
  EXPECT_EQ(none.metrics.acceleration.mean, zero.metrics.acceleration.mean);
  EXPECT_GT(none.trace.robot.back().norm(), 0.0);  // the follower did move: the comparison means something
}

// ------------------------------------------------------------------------------------------------------------
// Velocity lag.

TEST(EpisodeV2, TauLagsTheVelocityAsTheFirstOrderSolution) {
  const core::Scenario scenario = open_world(1.0);
  sim::EpisodeSettings settings = exact_settings();
  settings.robot_accel_max = 100.0;  // 1 m/s per step: never reached by the lag below
  settings.tau = 0.25;
  Recorder planner(Vec2(1.0, 0.0));
  const sim::EpisodeResult r = sim::run_episode(scenario, planner, settings);
  // dv/dt = (1 - v) / tau from rest: v after j steps = 1 - exp(-j dt / tau); x after k steps = sum of dt v_j.
  double x = 0.0;
  for (int k = 1; k <= 100; ++k) {
    x += 0.01 * (1.0 - std::exp(-0.01 * k / 0.25));
    EXPECT_NEAR(r.trace.robot[static_cast<std::size_t>(k)].x(), x, 1e-12) << "step " << k;
  }
  // The largest acceleration is the first step's: (1 - exp(-0.04)) / 0.01.
  EXPECT_NEAR(r.metrics.acceleration.max, (1.0 - std::exp(-0.04)) / 0.01, 1e-9);
}

TEST(EpisodeV2, TauThenTheAccelerationBound) {
  const core::Scenario scenario = open_world(0.5);
  sim::EpisodeSettings settings = exact_settings();
  settings.robot_accel_max = 2.0;  // 0.02 m/s per step, below the lag's first steps (about 0.0392)
  settings.tau = 0.25;
  Recorder planner(Vec2(1.0, 0.0));
  const sim::EpisodeResult r = sim::run_episode(scenario, planner, settings);
  double v = 0.0, x = 0.0;
  const double alpha = 1.0 - std::exp(-0.01 / 0.25);
  for (int k = 1; k <= 50; ++k) {
    v += std::min((1.0 - v) * alpha, 0.02);
    x += 0.01 * v;
    EXPECT_NEAR(r.trace.robot[static_cast<std::size_t>(k)].x(), x, 1e-12) << "step " << k;
  }
}

// ------------------------------------------------------------------------------------------------------------
// Sensing.

TEST(EpisodeV2, EveryBeamDroppedRunsToTheEndWithFiniteCommands) {
  core::Scenario scenario = hidden_target(3.0);
  scenario.target = {{0.0, Vec2(-2.0, 1.0)}, {3.0, Vec2(1.0, 2.5)}};
  sim::EpisodeSettings settings = exact_settings();
  settings.beam_dropout = 1.0;
  Recorder recorder(Vec2::Zero());
  const sim::EpisodeResult seen = sim::run_episode(scenario, recorder, settings);
  ASSERT_EQ(recorder.all_dropped.size(), 60u);
  for (bool dropped : recorder.all_dropped) EXPECT_TRUE(dropped);
  EXPECT_EQ(seen.metrics.cycles, 60);

  planners::Follower follower;
  const sim::EpisodeResult r = sim::run_episode(scenario, follower, settings);
  EXPECT_EQ(r.metrics.cycles, 60);
  EXPECT_NEAR(r.metrics.duration_s, 3.0, 1e-9);
  for (const Vec2& p : r.trace.robot) EXPECT_TRUE(p.allFinite());
  EXPECT_TRUE(std::isfinite(r.metrics.acceleration.max));
}

TEST(EpisodeV2, DropoutUsesItsOwnStreamAndBeamsOverride) {
  core::Scenario scenario = hidden_target(1.0);
  scenario.sensor.noise = 0.05;
  sim::EpisodeSettings settings = exact_settings();
  // The noise draws do not depend on dropout: a beam either returns nothing or exactly the same range.
  core::Scenario dropping = scenario;
  dropping.sensor.dropout = 0.5;
  sim::World a(scenario), b(dropping);
  std::mt19937_64 rng_a(7), rng_b(7);
  int dropped = 0, kept = 0;
  for (int scan = 0; scan < 5; ++scan) {
    const core::Scan sa = a.scan(Vec2::Zero(), 0.1 * scan, rng_a), sb = b.scan(Vec2::Zero(), 0.1 * scan, rng_b);
    for (std::size_t i = 0; i < sa.ranges.size(); ++i) {
      if (std::isinf(sb.ranges[i])) {
        dropped += std::isfinite(sa.ranges[i]);
      } else {
        EXPECT_EQ(sa.ranges[i], sb.ranges[i]);
        ++kept;
      }
    }
  }
  EXPECT_GT(dropped, 0);
  EXPECT_GT(kept, 0);

  // An episode's beam count override reaches the scan.
  settings.beams = 36;
  settings.beam_dropout = 0.0;
  struct Count final : planners::Planner {
    std::size_t beams = 0;
    std::string name() const override { return "count"; }
    void reset() override {}
    using Planner::plan;
    void plan(const planners::PlannerInput& in, planners::PlannerOutput& out) override {
      beams = in.scan->ranges.size();
      out.ok = true;
      out.command_velocity.setZero();
    }
    const planners::PlanRecord& last_record() const override { return record; }
    planners::PlanRecord record;
  } count;
  sim::run_episode(scenario, count, settings);
  EXPECT_EQ(count.beams, 36u);
}

TEST(EpisodeV2, TargetNoiseLeavesTheScansAlone) {
  core::Scenario scenario = open_world(1.0);
  scenario.sensor.noise = 0.05;
  core::ObstacleSpec post;
  post.center = Vec2(1.0, 1.0);
  post.radius = 0.3;
  scenario.obstacles.push_back(post);
  sim::EpisodeSettings settings = exact_settings();
  Recorder exact(Vec2::Zero()), noisy(Vec2::Zero());
  sim::run_episode(scenario, exact, settings);
  settings.target_position_noise = 0.1;
  settings.target_velocity_noise = 0.2;
  sim::run_episode(scenario, noisy, settings);
  ASSERT_EQ(exact.range_sums.size(), noisy.range_sums.size());
  int moved = 0;
  for (std::size_t k = 0; k < exact.range_sums.size(); ++k) {
    EXPECT_GT(exact.range_sums[k], 0.0);  // the post is in the scan
    EXPECT_EQ(exact.range_sums[k], noisy.range_sums[k]);
    moved += (exact.targets[k] - noisy.targets[k]).norm() > 0.0;
    EXPECT_LT((exact.targets[k] - noisy.targets[k]).norm(), 0.1 * 6.0);  // within 6 sigma (2-D)
  }
  EXPECT_EQ(moved, static_cast<int>(exact.targets.size()));
}

// ------------------------------------------------------------------------------------------------------------
// Target observation.

TEST(EpisodeV2, TargetNeverObservedRunsToTheEndAndHoldsStill) {
  const core::Scenario scenario = hidden_target(3.0);
  sim::EpisodeSettings settings = exact_settings();
  settings.target_observation = sim::TargetObservation::line_of_sight;
  Recorder recorder(Vec2::Zero());
  sim::run_episode(scenario, recorder, settings);
  for (double age : recorder.ages) EXPECT_EQ(age, kInf);

  planners::Follower follower;
  const sim::EpisodeResult r = sim::run_episode(scenario, follower, settings);
  EXPECT_EQ(r.metrics.cycles, 60);
  EXPECT_EQ(r.metrics.planner_failures, 0);  // holding still is a plan, not a failure
  for (const Vec2& p : r.trace.robot) EXPECT_EQ(p, Vec2::Zero());
  EXPECT_NEAR(r.metrics.occlusion_time_s, 3.0, 1e-9);
  EXPECT_EQ(r.metrics.occlusion_stretches, 1);
}

TEST(EpisodeV2, HiddenTargetGivesTheLastEstimateAndItsAge) {
  // The target walks from (4, 3), in sight, down behind the wall (hidden once |y| is below about 1.5 * 4/2).
  core::Scenario scenario = hidden_target(3.0);
  scenario.target = {{0.0, Vec2(4.0, 6.0)}, {3.0, Vec2(4.0, 0.0)}};
  sim::EpisodeSettings settings = exact_settings();
  settings.target_observation = sim::TargetObservation::line_of_sight;
  Recorder recorder(Vec2::Zero());
  sim::run_episode(scenario, recorder, settings);
  // Blocked once the line from the origin to (4, y) meets the wall's face at x = 1.8 within |y'| <= 1.5:
  // y <= 1.5 * 4 / 1.8 = 3.33, reached at t = (6 - 3.33) / 2 = 1.333 s; the last fresh cycle is t = 1.30.
  std::size_t hidden = 0;
  for (std::size_t k = 0; k < recorder.times.size(); ++k) {
    const double t = recorder.times[k];
    if (t <= 1.30 + 1e-9) {
      EXPECT_EQ(recorder.ages[k], 0.0) << t;
      EXPECT_NEAR(recorder.targets[k].y(), 6.0 - 2.0 * t, 1e-9);
    } else {
      ++hidden;
      EXPECT_NEAR(recorder.ages[k], t - 1.30, 1e-9) << t;
      EXPECT_NEAR(recorder.targets[k].y(), 6.0 - 2.0 * 1.30, 1e-9);
    }
  }
  EXPECT_EQ(hidden, 33u);  // t = 1.35 ... 2.95

  // Out of range counts as unseen too.
  core::Scenario far = open_world(1.0);
  far.target = {{0.0, Vec2(9.5, 0.0)}, {1.0, Vec2(10.5, 0.0)}};
  Recorder far_recorder(Vec2::Zero());
  sim::run_episode(far, far_recorder, settings);
  EXPECT_EQ(far_recorder.ages.front(), 0.0);
  EXPECT_GT(far_recorder.ages.back(), 0.0);
}

TEST(EpisodeV2, PlannersPredictAHiddenTargetAndHoldWithoutOne) {
  planners::Follower follower;
  core::Scan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 2.0 * std::numbers::pi / 90;
  scan.range_max = 10.0;
  scan.ranges.assign(90, kInf);
  planners::PlannerInput input;
  input.robot_position = Vec2(1.0, 1.0);
  input.target_position = Vec2(3.0, 1.0);
  input.target_velocity = Vec2(1.0, 0.5);
  input.scan = &scan;

  auto target_in_frame = [&](double age) {
    input.target_age = age;
    follower.reset();
    const planners::PlannerOutput out = follower.plan(input);
    EXPECT_TRUE(out.ok) << out.message;
    EXPECT_TRUE(out.command_velocity.allFinite());
    return Vec2(follower.last_record().frame.target.head<2>());
  };
  EXPECT_EQ(target_in_frame(0.0), Vec2(2.0, 0.0));
  const Vec2 one = target_in_frame(1.0);
  EXPECT_NEAR(one.x(), 3.0, 1e-12);
  EXPECT_NEAR(one.y(), 0.5, 1e-12);
  const Vec2 capped = target_in_frame(10.0);  // extrapolated over 2 s at most
  EXPECT_NEAR(capped.x(), 4.0, 1e-12);
  EXPECT_NEAR(capped.y(), 1.0, 1e-12);

  input.target_age = kInf;
  input.target_position = Vec2(NAN, NAN);  // means nothing when never observed; must not leak into the command
  const planners::PlannerOutput hold = follower.plan(input);
  EXPECT_TRUE(hold.ok);
  EXPECT_EQ(hold.command_velocity, Vec2::Zero());
  EXPECT_NE(hold.message.find("not observed"), std::string::npos) << hold.message;

  input.target_position = Vec2(3.0, 1.0);
  input.target_age = NAN;
  const planners::PlannerOutput bad = follower.plan(input);
  EXPECT_FALSE(bad.ok);
  EXPECT_EQ(bad.command_velocity, Vec2::Zero());
}

// ------------------------------------------------------------------------------------------------------------
// Metrics.

TEST(EpisodeV2, OcclusionStretchesAndLongest) {
  // Robot still at the origin; a 1 m box at (5, 0); the target on x = 10 from y = -5 up to 5 (t = 10) and
  // back (t = 20) at 1 m/s. The box hides it while the segment crosses x = 4.5 within |y| <= 0.5, i.e.
  // |y_target| <= 0.5 * 10 / 4.5 = 1.111: two spells of 2.222 s, around t = 5 and t = 15.
  core::Scenario s;
  s.name = "two-spells";
  s.duration = 20.0;
  core::ObstacleSpec box;
  box.shape = core::ObstacleSpec::Shape::box;
  box.center = Vec2(5.0, 0.0);
  box.size = Vec2(1.0, 1.0);
  s.obstacles.push_back(box);
  s.target = {{0.0, Vec2(10.0, -5.0)}, {10.0, Vec2(10.0, 5.0)}, {20.0, Vec2(10.0, -5.0)}};
  s.sensor.beams = 36;
  sim::EpisodeSettings settings;
  settings.snapshots = 0;
  Recorder still(Vec2::Zero());
  const sim::EpisodeResult r = sim::run_episode(s, still, settings);
  const double spell = 2.0 * 0.5 * 10.0 / 4.5;
  EXPECT_EQ(r.metrics.occlusion_stretches, 2);
  EXPECT_NEAR(r.metrics.longest_occlusion_s, spell, 0.011);
  EXPECT_NEAR(r.metrics.occlusion_time_s, 2.0 * spell, 0.022);
  EXPECT_LE(r.metrics.longest_occlusion_s, r.metrics.occlusion_time_s);

  // A suite: stretches add up, the longest is the longest, latency and scale are carried; JSON has the keys.
  core::EpisodeMetrics other = r.metrics;
  other.occlusion_stretches = 3;
  other.longest_occlusion_s = 7.5;
  core::EpisodeMetrics first = r.metrics;
  first.latency_ms = 30.0;
  first.compute_scale = 10.0;
  other.latency_ms = 30.0;
  other.compute_scale = 10.0;
  const core::SuiteResult suite = sim::summarize_suite("suite", "recorder", {first, other});
  EXPECT_EQ(suite.summary.occlusion_stretches, 5);
  EXPECT_EQ(suite.summary.longest_occlusion_s, 7.5);
  EXPECT_EQ(suite.summary.latency_ms, 30.0);
  EXPECT_EQ(suite.summary.compute_scale, 10.0);
  const nlohmann::json j = nlohmann::json::parse(io::suite_json(suite));
  EXPECT_EQ(j["summary"]["occlusion_stretches"], 5);
  EXPECT_EQ(j["summary"]["longest_occlusion_s"], 7.5);
  EXPECT_EQ(j["summary"]["latency_ms"], 30.0);
  EXPECT_EQ(j["summary"]["compute_scale"], 10.0);
  EXPECT_EQ(j["episodes"][1]["occlusion_stretches"], 3);
  const nlohmann::json e = nlohmann::json::parse(io::episode_json(r.metrics));
  EXPECT_EQ(e["occlusion_stretches"], 2);
  EXPECT_EQ(e["latency_ms"], 0.0);
  EXPECT_EQ(e["compute_scale"], 1.0);
}

// ------------------------------------------------------------------------------------------------------------
// Settings, scenario key, median cycle.

TEST(EpisodeV2, ValidateNamesEveryNewField) {
  auto message = [](const std::function<void(sim::EpisodeSettings&)>& change) {
    sim::EpisodeSettings s;
    change(s);
    std::string error;
    EXPECT_FALSE(s.validate(&error));
    return error;
  };
  EXPECT_NE(message([](auto& s) { s.latency_ms = -1.0; }).find("latency_ms"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.latency_ms = NAN; }).find("latency_ms"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.latency_ms = INFINITY; }).find("latency_ms"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.compute_scale = 0.0; }).find("compute_scale"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.tau = -0.1; }).find("tau"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.beams = 0; }).find("beams"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.lidar_noise = NAN; }).find("lidar_noise"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.beam_dropout = 1.5; }).find("beam_dropout"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.beam_dropout = -0.1; }).find("beam_dropout"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.target_position_noise = -1.0; }).find("target_position_noise"), std::string::npos);
  EXPECT_NE(message([](auto& s) { s.target_velocity_noise = NAN; }).find("target_velocity_noise"), std::string::npos);
  EXPECT_NE(message([](auto& s) {
              s.latency_ms = 10.0;
              s.delay_by_compute = true;
            }).find("delay_by_compute"),
            std::string::npos);
  sim::EpisodeSettings ok;
  ok.latency_ms = 0.0;
  ok.tau = 0.0;
  ok.beam_dropout = 1.0;
  EXPECT_TRUE(ok.validate(nullptr));
  Recorder r;
  sim::EpisodeSettings bad;
  bad.beam_dropout = 2.0;
  EXPECT_THROW(sim::run_episode(open_world(), r, bad), std::invalid_argument);
}

TEST(EpisodeV2, ScenarioDropoutKey) {
  core::Scenario s = open_world();
  const std::string v1 = io::scenario_yaml(s);
  EXPECT_EQ(v1.find("dropout"), std::string::npos);  // v1 files are written as before
  s.sensor.dropout = 0.25;
  const std::string text = io::scenario_yaml(s);
  EXPECT_NE(text.find("dropout: 0.25"), std::string::npos);
  EXPECT_EQ(io::parse_scenario(text, "test").sensor.dropout, 0.25);
  std::string bad = text;
  bad.replace(bad.find("dropout: 0.25"), 13, "dropout: 1.5");
  try {
    io::parse_scenario(bad, "bad.yaml");
    FAIL() << "dropout 1.5 accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("sensor.dropout"), std::string::npos) << e.what();
  }
}

TEST(EpisodeV2, MedianCycleRunsThePlannerOnReplayedScans) {
  Recorder recorder(Vec2::Zero());
  std::vector<core::Scenario> scenarios = {open_world(2.0), hidden_target(3.0), open_world(1.0)};
  const double median = sim::median_cycle_ms(recorder, scenarios, sim::EpisodeSettings{}, 10);
  EXPECT_EQ(median, 0.0);                // the recorder reports 0 ms
  EXPECT_EQ(recorder.cycles_total, 10);  // 4 + 3 + 3 over the scenarios
  EXPECT_TRUE(recorder.times.empty());   // reset after
  EXPECT_GE(recorder.resets, 2);
  planners::Follower follower;
  const double follower_ms = sim::median_cycle_ms(follower, scenarios, sim::EpisodeSettings{}, 7);
  EXPECT_GT(follower_ms, 0.0);
  EXPECT_TRUE(std::isfinite(follower_ms));
  EXPECT_THROW(sim::median_cycle_ms(follower, {}, sim::EpisodeSettings{}), std::invalid_argument);
}

}  // namespace
}  // namespace occtrack
