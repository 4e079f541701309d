// Recorded target paths: reading the table (io/target_path.hpp) and making a scenario of it
// (sim/recorded_path.hpp), against paths whose waypoints, robot start and overlaps are known by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "occtrack/io/scenario.hpp"
#include "occtrack/io/target_path.hpp"
#include "occtrack/sim/paper_worlds.hpp"
#include "occtrack/sim/recorded_path.hpp"
#include "occtrack/sim/world.hpp"

namespace {

using occtrack::core::ObstacleSpec;
using occtrack::core::Scenario;
using occtrack::core::TargetWaypoint;
using occtrack::core::Vec2;
using occtrack::io::InputError;
using occtrack::io::parse_target_path;
using occtrack::sim::RecordedPathReport;
using occtrack::sim::RecordedPathSettings;
using occtrack::sim::scenario_from_recorded_path;

// The message of the InputError that parsing `text` throws ("" when it throws none).
std::string refusal(const std::string& text, const occtrack::io::TargetPathColumns& columns = {}) {
  try {
    parse_target_path(text, "rec.csv", columns);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(TargetPathFile, ReadsCommaAndSpaceTablesWithOrWithoutAHeader) {
  const auto plain = parse_target_path("# t x y\n0 1 2\n\n0.5\t1.5  2.5\n", "rec.txt");
  ASSERT_EQ(plain.size(), 2u);
  EXPECT_EQ(plain[1].time, 0.5);
  EXPECT_EQ(plain[1].position, Vec2(1.5, 2.5));

  const auto header = parse_target_path("t, x, y\n10, -1, +2\n11, -3e-1, 4\n", "rec.csv");
  ASSERT_EQ(header.size(), 2u);
  EXPECT_EQ(header[0].time, 10.0);  // not shifted: the scenario maker does that
  EXPECT_EQ(header[1].position, Vec2(-0.3, 4.0));

  // Named columns in another order, a string column between them, nanoseconds.
  occtrack::io::TargetPathColumns columns{"%time", "px", "py", 1e-9};
  const auto named =
      parse_target_path("%time,frame,py,px\n2000000000,map,7,8\n2500000000,map,7.5,8.5\n", "rec.csv", columns);
  ASSERT_EQ(named.size(), 2u);
  EXPECT_DOUBLE_EQ(named[1].time, 2.5);
  EXPECT_EQ(named[1].position, Vec2(8.5, 7.5));
}

TEST(TargetPathFile, RefusesBadTablesNamingTheLine) {
  EXPECT_EQ(refusal("0 0 0\n1 1 1\n1 2 2\n"), "rec.csv: line 3: times must strictly increase: 1 s after 1 s");
  EXPECT_NE(refusal("0 0 0\n1 nan 1\n").find("line 2: the x (column 1) must be a finite number, got 'nan'"),
            std::string::npos);
  EXPECT_NE(refusal("0 0 0\n1 1\n").find("line 2: no column 2 (the y): the row has 2 fields"), std::string::npos);
  EXPECT_NE(refusal("0 0 0\n").find("at least two samples, got 1"), std::string::npos);
  EXPECT_NE(refusal("").find("at least two samples, got 0"), std::string::npos);
  EXPECT_NE(refusal("t,a,b\n0,1,2\n1,2,3\n", {"t", "x", "b"}).find("line 1: no column named 'x' (for the x)"),
            std::string::npos);
  EXPECT_NE(refusal("0 0 0\n1 1 1\n", {"0", "1", "2", 0.0}).find("time scale"), std::string::npos);
  EXPECT_NE(refusal("0 0 0\n1e308 1 1\n", {"0", "1", "2", 10.0}).find("line 2: the time times the time scale"),
            std::string::npos);
  EXPECT_THROW(occtrack::io::read_target_path("/nonexistent/rec.csv"), InputError);
}

// A world of one static circle of radius 1 at (5, 0).
Scenario one_circle() {
  Scenario world;
  ObstacleSpec circle;
  circle.center = Vec2(5.0, 0.0);
  circle.radius = 1.0;
  world.obstacles.push_back(circle);
  return world;
}

// (x0, y0) to (x0 + speed * seconds, y0) in samples every `dt`, the clock starting at `t0`.
std::vector<TargetWaypoint> straight(double t0, double x0, double y0, double speed, double seconds, double dt) {
  std::vector<TargetWaypoint> samples;
  for (int i = 0; i * dt <= seconds + 1e-9; ++i) samples.push_back({t0 + i * dt, Vec2(x0 + speed * i * dt, y0)});
  return samples;
}

TEST(RecordedPath, ResamplesFromTimeZeroAndPlacesTheRobotBehindTheTarget) {
  // 100 Hz along y = 3 (clear of the circle), clock starting at 1e6 s.
  const auto samples = straight(1e6, 0.0, 3.0, 1.0, 10.0, 0.01);
  RecordedPathReport report;
  const Scenario s = scenario_from_recorded_path(one_circle(), samples, {}, "rec", &report);
  ASSERT_EQ(s.target.size(), 101u);
  EXPECT_EQ(report.samples_used, 1001);
  for (std::size_t k = 0; k < s.target.size(); ++k) {
    EXPECT_NEAR(s.target[k].time, 0.1 * k, 1e-12);
    EXPECT_NEAR(s.target[k].position.x(), 0.1 * k, 1e-4);  // rounded to 4 decimals
    EXPECT_EQ(s.target[k].position.y(), 3.0);
  }
  EXPECT_NEAR(s.duration, 10.0, 1e-12);
  EXPECT_EQ(s.robot_position, Vec2(-2.0, 3.0));  // 2 m behind, against the way it goes
  EXPECT_TRUE(s.robot_velocity.isZero());
  EXPECT_TRUE(report.robot_sees_target);
  EXPECT_EQ(report.overlap_time, 0.0);
  EXPECT_TRUE(std::isnan(report.first_overlap));
  EXPECT_NEAR(report.top_speed, 1.0, 2e-3);
  EXPECT_EQ(s.obstacles.size(), 1u);
  // It is a valid scenario file.
  const Scenario back = occtrack::io::parse_scenario(occtrack::io::scenario_yaml(s), "rec.yaml");
  EXPECT_EQ(back.target.size(), s.target.size());
}

TEST(RecordedPath, TakesTheStretchAskedForAndKeepsSamplesWithPeriodZero) {
  const auto samples = straight(100.0, 0.0, 3.0, 1.0, 10.0, 0.25);
  RecordedPathSettings settings;
  settings.from = 102.1;  // the first sample used is 102.25's
  settings.to = 104.0;
  settings.period = 0.0;
  const Scenario s = scenario_from_recorded_path(one_circle(), samples, settings, "rec");
  ASSERT_EQ(s.target.size(), 8u);  // 102.25, 102.5, ..., 104
  EXPECT_EQ(s.target.front().time, 0.0);
  EXPECT_EQ(s.target.front().position, Vec2(2.25, 3.0));
  EXPECT_EQ(s.target.back().time, 1.75);
  EXPECT_EQ(s.duration, 1.75);

  // Kept as they are, times that differ by less than the shifted clock resolves are refused, not merged.
  const std::vector<TargetWaypoint> close = {{-1e9, Vec2(0.0, 3.0)}, {1e-7, Vec2(1.0, 3.0)}, {1.5e-7, Vec2(2.0, 3.0)}};
  RecordedPathSettings keep;
  keep.period = 0.0;
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), close, keep, "rec"), std::runtime_error);

  settings.from = 200.0;
  settings.to = 300.0;
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, settings, "rec"), std::runtime_error);
  settings.from = 101.0;
  settings.to = 101.05;  // one sample (101.0)
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, settings, "rec"), std::runtime_error);
}

TEST(RecordedPath, ReportsWhenTheTargetOverlapsAnObstacle) {
  // Along the x axis at 1 m/s through the circle: the disk of radius 0.25 overlaps it while |x - 5| < 1.25,
  // 3.75 < t < 6.25; checked every 0.05 s: t = 3.80 to 6.20, 49 checks.
  const auto samples = straight(0.0, 0.0, 0.0, 1.0, 10.0, 0.1);
  RecordedPathReport report;
  scenario_from_recorded_path(one_circle(), samples, {}, "rec", &report);
  EXPECT_NEAR(report.overlap_time, 49 * 0.05, 1e-9);
  EXPECT_NEAR(report.first_overlap, 3.8, 1e-9);
}

TEST(RecordedPath, PlacesARecordingMadeInAnotherFrame) {
  // Along the recording's x axis at 1 m/s, through the circle when read in the world's frame (the test above).
  // The recording's frame turned a quarter counter-clockwise with its origin at (-3, -5): the path runs up
  // x = -3 from y = -5, clear of the circle, and the robot starts 2 m below it.
  const auto samples = straight(0.0, 0.0, 0.0, 1.0, 10.0, 0.1);
  RecordedPathSettings settings;
  settings.rotation = std::acos(-1.0) / 2.0;
  settings.offset = Vec2(-3.0, -5.0);
  RecordedPathReport report;
  const Scenario s = scenario_from_recorded_path(one_circle(), samples, settings, "rec", &report);
  ASSERT_EQ(s.target.size(), 101u);
  for (std::size_t k = 0; k < s.target.size(); ++k) {
    EXPECT_EQ(s.target[k].position.x(), -3.0);  // cos(pi / 2) x is 6e-17 x, rounded away
    EXPECT_NEAR(s.target[k].position.y(), -5.0 + 0.1 * k, 1e-4);
  }
  EXPECT_EQ(report.overlap_time, 0.0);
  EXPECT_EQ(s.robot_position, Vec2(-3.0, -7.0));

  RecordedPathSettings bad = settings;
  bad.rotation = 7.0;  // beyond 2 pi
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, bad, "rec"), std::invalid_argument);
  bad = settings;
  bad.offset = Vec2(2e6, 0.0);
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, bad, "rec"), std::invalid_argument);
  bad.offset = Vec2(0.0, NAN);
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, bad, "rec"), std::invalid_argument);
  bad.offset = Vec2(0.0, 1e6);  // valid, but turned up +y, the samples at x > 0 land beyond 1e6 m in y
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, bad, "rec"), std::invalid_argument);
}

TEST(RecordedPath, RefusesARobotStartInAnObstacleAndSaysWhenNoneFits) {
  const auto samples = straight(0.0, 0.0, 3.0, 1.0, 10.0, 0.1);
  RecordedPathSettings settings;
  settings.robot_start = Vec2(5.5, 0.0);
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, settings, "rec"), std::runtime_error);
  // A given start need not see the target: reported, not refused. From (6.5, -0.5) to (0, 3) the line passes
  // 0.27 m from the circle's centre.
  settings.robot_start = Vec2(6.5, -0.5);
  RecordedPathReport report;
  const Scenario s = scenario_from_recorded_path(one_circle(), samples, settings, "rec", &report);
  EXPECT_EQ(s.robot_position, Vec2(6.5, -0.5));
  EXPECT_FALSE(report.robot_sees_target);
  EXPECT_NEAR(report.robot_clearance, std::sqrt(1.5 * 1.5 + 0.5 * 0.5) - 1.0 - 0.25, 1e-9);
  // A circle of radius 1.2 where the robot would stand, 2 m behind the target, and wherever 0.6 rad either side
  // puts it: the start turns further round, to the first bearing 0.1 rad at a time that is 0.5 m clear of it.
  Scenario blocked;
  ObstacleSpec circle;
  circle.center = Vec2(-2.0, 3.0);
  circle.radius = 1.2;
  blocked.obstacles.push_back(circle);
  const Scenario beside = scenario_from_recorded_path(blocked, samples, {}, "rec");
  const double bearing = std::atan2(beside.robot_position.y() - 3.0, beside.robot_position.x());
  EXPECT_NEAR((beside.robot_position - Vec2(0.0, 3.0)).norm(), 2.0, 1e-4);
  EXPECT_GE((beside.robot_position - circle.center).norm(), 1.2 + 0.25 + 0.5);
  // Turned by t from straight behind, the robot is 4 sin(t / 2) from the circle's centre, which must be at least
  // 1.2 + 0.25 + 0.5: t >= 1.018 rad, so the first step that fits is 1.1 rad.
  EXPECT_NEAR(std::abs(bearing), M_PI - 1.1, 1e-4);
  // Closed round at 2 m (a ring of radius 2 about the target's start, less than the robot's clearance wide):
  // no start fits.
  Scenario ring;
  for (int k = 0; k < 40; ++k) {
    ObstacleSpec post;
    post.center = Vec2(2.0 * std::cos(0.05 * M_PI * k), 3.0 + 2.0 * std::sin(0.05 * M_PI * k));
    post.radius = 0.2;
    ring.obstacles.push_back(post);
  }
  EXPECT_THROW(scenario_from_recorded_path(ring, samples, {}, "rec"), std::runtime_error);
  // A recording's nanosecond clock read as seconds: 10 s become 1e10 s, more than a million waypoints.
  auto nanoseconds = samples;
  for (TargetWaypoint& w : nanoseconds) w.time *= 1e9;
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), nanoseconds, {}, "rec"), std::runtime_error);
  // Coordinates beyond 1e6 m (a recording in another unit or frame) are refused before any arithmetic.
  auto far = samples;
  far[3].position.x() = 1e300;
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), far, {}, "rec"), std::invalid_argument);
  settings = {};
  settings.period = 0.0005;
  EXPECT_THROW(scenario_from_recorded_path(one_circle(), samples, settings, "rec"), std::invalid_argument);
}

TEST(RecordedPath, KeepsThePaperWorldsMovingWalls) {
  const Scenario world = occtrack::sim::six_wall_world(true);
  const auto samples = straight(0.0, 8.0, -5.0, 0.0, 5.0, 0.1);  // standing east of the walls
  const Scenario s = scenario_from_recorded_path(world, samples, {}, "rec");
  ASSERT_EQ(s.obstacles.size(), world.obstacles.size());
  for (std::size_t k = 0; k < s.obstacles.size(); ++k) EXPECT_TRUE(s.obstacles[k].moving());
  EXPECT_EQ(s.sensor.beams, world.sensor.beams);
}

}  // namespace
