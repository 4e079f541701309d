// Tele-operated target motion (TargetMotion::teleop, include/occtrack/sim/scenario_generator.hpp): settings
// checks, determinism, clearances in the paper's worlds and v1 clutter at the suites' speeds, and the
// calibration against the recorded tele-operation of shared/reference/paper_setup.md, measured through
// sim/path_stats on the produced scenarios (not the generator's internals).
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "occtrack/io/scenario.hpp"
#include "occtrack/sim/paper_worlds.hpp"
#include "occtrack/sim/path_stats.hpp"
#include "occtrack/sim/scenario_generator.hpp"
#include "occtrack/sim/world.hpp"

namespace {

using occtrack::core::Scenario;
using occtrack::core::Vec2;
namespace sim = occtrack::sim;

// The six-wall world's area as the v2 suites use it: 15 m x 16 m around (2, 0.5).
sim::TargetSettings six_wall_target(double nominal, double duration) {
  sim::TargetSettings t = sim::teleop_target_settings(nominal);
  t.duration = duration;
  t.area_width = 15.0;
  t.area_height = 16.0;
  t.area_center_x = 2.0;
  t.area_center_y = 0.5;
  return t;
}

// Only the static, or only the moving, obstacles of a scenario.
Scenario only(const Scenario& s, bool moving) {
  Scenario out = s;
  out.obstacles.clear();
  for (const auto& o : s.obstacles)
    if (o.moving() == moving) out.obstacles.push_back(o);
  return out;
}

// Clearance breaches, checked independently of the generator: static obstacles every 0.01 s, moving ones
// every 0.05 s, the area at every waypoint.
int clearance_violations(const Scenario& s, const sim::TargetSettings& t) {
  sim::World statics(only(s, false)), moving(only(s, true));
  const bool any_moving = !moving.scenario().obstacles.empty();
  int violations = 0;
  const double end = s.target.back().time;
  for (int i = 0; i * 0.01 <= end; ++i) {
    const double time = i * 0.01;
    const Vec2 p = statics.target_position(time);
    if (statics.clearance(p, time) - s.target_radius < t.static_clearance - 1e-9) ++violations;
    if (any_moving && i % 5 == 0 && moving.clearance(p, time) - s.target_radius < t.moving_clearance - 1e-9)
      ++violations;
  }
  for (const auto& w : s.target) {
    const Vec2 local = w.position - Vec2(t.area_center_x, t.area_center_y);
    if (std::abs(local.x()) > 0.5 * t.area_width - t.area_margin + 1e-9 ||
        std::abs(local.y()) > 0.5 * t.area_height - t.area_margin + 1e-9)
      ++violations;
  }
  return violations;
}

TEST(Teleop, DefaultsKeepTheSmoothGenerator) {
  const sim::TargetSettings t;
  EXPECT_EQ(t.motion, sim::TargetMotion::smooth);
  EXPECT_EQ(t.area_center_x, 0.0);
  EXPECT_EQ(t.area_center_y, 0.0);
  EXPECT_STREQ(sim::to_string(sim::TargetMotion::teleop), "teleop");
  EXPECT_EQ(sim::parse_target_motion("smooth"), sim::TargetMotion::smooth);
  EXPECT_FALSE(sim::parse_target_motion("joystick").has_value());
}

TEST(Teleop, SettingsCheckThemselves) {
  std::string error;
  EXPECT_TRUE(sim::teleop_target_settings(1.0).validate(&error)) << error;
  sim::TargetSettings t = sim::teleop_target_settings(1.0);
  t.waypoint_period = 0.5;
  EXPECT_FALSE(t.validate(&error));
  EXPECT_NE(error.find("waypoint_period"), std::string::npos) << error;
  t = sim::teleop_target_settings(1.0);
  t.teleop.strafe_share = 1.5;
  EXPECT_FALSE(t.validate(&error));
  EXPECT_NE(error.find("teleop.strafe_share"), std::string::npos) << error;
  t = sim::teleop_target_settings(1.0);
  t.teleop.command_period_min = 0.05;  // above the max
  EXPECT_FALSE(t.validate(&error));
  EXPECT_NE(error.find("teleop.command_period_min"), std::string::npos) << error;
  t = sim::teleop_target_settings(1.0);
  t.area_center_x = std::nan("");
  EXPECT_FALSE(t.validate(&error));
  EXPECT_NE(error.find("area_center_x"), std::string::npos) << error;
  sim::TargetSettings smooth;
  smooth.area_center_y = 1.0;  // the smooth generator's area is centred on the origin
  EXPECT_FALSE(smooth.validate(&error));
  EXPECT_NE(error.find("area_center"), std::string::npos) << error;
  EXPECT_THROW(sim::generate_episode(sim::six_wall_world(), t, 1, "bad"), std::invalid_argument);
}

TEST(Teleop, SameSeedSameFileAndWaypointsEveryTenthOfASecond) {
  const sim::TargetSettings t = six_wall_target(1.0, 30.0);
  const Scenario a = sim::generate_episode(sim::six_wall_world(), t, 7, "a");
  const Scenario b = sim::generate_episode(sim::six_wall_world(), t, 7, "a");
  const Scenario c = sim::generate_episode(sim::six_wall_world(), t, 8, "a");
  EXPECT_EQ(occtrack::io::scenario_yaml(a), occtrack::io::scenario_yaml(b));
  EXPECT_NE(occtrack::io::scenario_yaml(a), occtrack::io::scenario_yaml(c));
  ASSERT_EQ(a.target.size(), 301u);
  for (std::size_t k = 0; k < a.target.size(); ++k) EXPECT_NEAR(a.target[k].time, 0.1 * k, 1e-9);
}

TEST(Teleop, KeepsClearanceInThePapersWorldsAndClutterAtTheSuitesSpeeds) {
  for (const double speed : {0.5, 1.0, 1.5, 2.0})
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      const sim::TargetSettings t = six_wall_target(speed, 60.0);
      const Scenario s = sim::generate_episode(sim::six_wall_world(), t, seed, "six-wall");
      EXPECT_EQ(clearance_violations(s, t), 0) << "six-wall, " << speed << " m/s, seed " << seed;
    }
  {
    const sim::TargetSettings t = six_wall_target(1.5, 60.0);
    const Scenario s = sim::generate_episode(sim::six_wall_world(true), t, 3, "six-wall-sliding");
    EXPECT_EQ(clearance_violations(s, t), 0) << "six-wall sliding";
  }
  {
    sim::TargetSettings t = sim::teleop_target_settings(2.0);
    t.duration = 60.0;
    t.area_width = 31.0, t.area_height = 27.0, t.area_center_x = -0.5, t.area_center_y = 1.2;
    const Scenario s = sim::generate_episode(sim::random_world(), t, 4, "random");
    EXPECT_EQ(clearance_violations(s, t), 0) << "random world";
  }
  for (const int moving : {0, 4}) {
    sim::GeneratorSettings g;
    g.moving_obstacles = moving;
    const Scenario world = sim::generate_world(g, 11 + moving);
    sim::TargetSettings t = sim::teleop_target_settings(2.0);
    t.duration = 60.0;
    const Scenario s = sim::generate_episode(world, t, 5, "clutter");
    EXPECT_EQ(clearance_violations(s, t), 0) << "clutter with " << moving << " moving obstacles";
  }
}

// One statistic of the recorded table and the generated paths' value.
void expect_within_20_percent(double generated, double recorded, const char* what, double nominal) {
  EXPECT_LE(std::abs(generated / recorded - 1.0), 0.2)
      << what << " at nominal " << nominal << " m/s: generated " << generated << ", recorded " << recorded;
}

// shared/reference/paper_setup.md, "Target motion: recorded tele-operation".
struct Recorded {
  double nominal, duration;
  double speed_mean, speed_p90, speed_max, acc_p50, acc_p90, acc_p99, rate_p50, rate_p90, rate_p99;
};

TEST(Teleop, MatchesTheRecordedTeleoperationWithinTwentyPercent) {
  for (const Recorded& r : {Recorded{0.5, 152.0, 0.45, 0.50, 0.71, 0.12, 0.19, 1.8, 0.25, 0.39, 2.8},
                            Recorded{1.0, 90.0, 1.03, 1.35, 1.41, 0.60, 4.6, 8.4, 0.64, 3.6, 7.7}}) {
    sim::PathSamples samples;
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const sim::TargetSettings t = six_wall_target(r.nominal, r.duration);
      const Scenario s = sim::generate_episode(sim::six_wall_world(), t, seed, "calibration");
      // Through the file format, as `occtrack scenario stats` reads it.
      samples.append(sim::sample_path(occtrack::io::parse_scenario(occtrack::io::scenario_yaml(s), "gen").target));
    }
    const sim::PathStats g = sim::summarize_path(samples);
    expect_within_20_percent(g.speed_mean, r.speed_mean, "speed mean", r.nominal);
    expect_within_20_percent(g.speed_p90, r.speed_p90, "speed p90", r.nominal);
    expect_within_20_percent(g.speed_max, r.speed_max, "speed max", r.nominal);
    expect_within_20_percent(g.acceleration_p50, r.acc_p50, "acceleration p50", r.nominal);
    expect_within_20_percent(g.acceleration_p90, r.acc_p90, "acceleration p90", r.nominal);
    expect_within_20_percent(g.acceleration_p99, r.acc_p99, "acceleration p99", r.nominal);
    expect_within_20_percent(g.heading_rate_p50, r.rate_p50, "heading-rate p50", r.nominal);
    expect_within_20_percent(g.heading_rate_p90, r.rate_p90, "heading-rate p90", r.nominal);
    expect_within_20_percent(g.heading_rate_p99, r.rate_p99, "heading-rate p99", r.nominal);
    // Almost never standing still (the recordings: 1 % of the time).
    int still = 0;
    for (const double v : samples.speed) still += v < sim::kMovingSpeed ? 1 : 0;
    EXPECT_LT(still, 0.03 * static_cast<double>(samples.speed.size())) << "nominal " << r.nominal;
  }
}

// The v1 clutter worlds at the clutter suites' 2 m/s: the operator keeps moving as the recorded one does
// (mean speed near nominal, standing still about 1 % of the time) and keeps its clearances. A router whose
// bends leave no clear straight step once pinned the target beside an obstacle for most of an episode (mixed-a
// at 0.03 m/s), halting every step; a stuck operator now backs up and draws a new goal.
TEST(Teleop, KeepsMovingInTheClutterWorldsAtTwoMetresPerSecond) {
  for (const char* name : {"clutter-2ms", "clutter-dynamic-2ms"}) {
    const std::optional<sim::SuiteSpec> suite = sim::find_suite(name);
    ASSERT_TRUE(suite.has_value()) << name;
    const double nominal = suite->target.max_speed;
    ASSERT_EQ(nominal, 2.0);
    for (std::size_t w = 0; w < suite->worlds.size(); ++w) {
      const Scenario world = sim::suite_world(suite->worlds[w]);
      // The suite's first two episodes of each world (their seeds), each on its own: one stuck episode among
      // several moving ones must not hide in an average.
      for (int k = 1; k <= 2; ++k) {
        const std::string what = std::string(name) + " " + suite->worlds[w].name + "-" + std::to_string(k);
        const Scenario s = sim::generate_episode(world, suite->target, suite->episode_seed(static_cast<int>(w), k), what);
        const sim::PathSamples samples = sim::sample_path(s.target);
        ASSERT_FALSE(samples.speed.empty()) << what;
        double sum = 0.0;
        int still = 0;
        for (const double v : samples.speed) {
          sum += v;
          still += v < sim::kMovingSpeed ? 1 : 0;
        }
        const double n = static_cast<double>(samples.speed.size());
        EXPECT_GE(sum / n, 0.7 * nominal) << what << ": mean speed";
        EXPECT_LE(still, 0.03 * n) << what << ": samples standing still";
        EXPECT_EQ(clearance_violations(s, suite->target), 0) << what;
      }
    }
  }
}

}  // namespace
