// The middleware-free tracking API (planners/tracker.hpp): a normal cycle commands a finite velocity towards
// the target; bad inputs (NaN scan, stale or future stamps, non-finite odometry) stop the robot with a reason,
// never NaN and never an exception; bad settings are refused naming the setting.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "occtrack/planners/tracker.hpp"

namespace occtrack {
namespace {

using core::Vec2;
using planners::RobotState;
using planners::TargetEstimate;
using planners::Tracker;
using planners::TrackerOutput;
using planners::TrackerSettings;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNow = 1.7e9;  // a ROS-like epoch: internal times must not lose precision

/// 360 beams over the full circle, nothing within range except a post 4 m away at -90 degrees.
core::Scan open_scan(double time = kNow) {
  core::Scan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 2.0 * std::numbers::pi / 360;
  scan.range_max = 10.0;
  scan.ranges.assign(360, kInf);
  for (int i = 265; i <= 275; ++i) scan.ranges[static_cast<std::size_t>(i)] = 4.0;
  scan.time = time;
  return scan;
}

RobotState robot_at_origin() { return {Vec2::Zero(), Vec2::Zero(), kNow}; }
/// 4 m ahead along +x, walking away at 1 m/s.
TargetEstimate target_ahead(double stamp = kNow) { return {Vec2(4.0, 0.0), Vec2(1.0, 0.0), stamp}; }

void expect_stop(const TrackerOutput& out, const std::string& words) {
  EXPECT_TRUE(out.stopped);
  EXPECT_EQ(out.command, Vec2::Zero());
  EXPECT_NE(out.reason.find(words), std::string::npos) << out.reason;
  EXPECT_TRUE(out.planner.plan.empty());
}

TEST(Tracker, NormalStepCommandsTowardsTheTarget) {
  Tracker tracker(TrackerSettings{});  // the defaults: cvae, shipped model, safety layer on
  EXPECT_TRUE(tracker.settings().options.shield);
  const core::Scan scan = open_scan();
  TrackerOutput out;
  for (int k = 0; k < 3; ++k) out = tracker.step(kNow + 0.05 * k, robot_at_origin(), target_ahead(kNow + 0.05 * k), &scan);
  EXPECT_FALSE(out.stopped) << out.reason;
  EXPECT_TRUE(out.reason.empty());
  ASSERT_TRUE(out.command.allFinite());
  // After the target, along +x: the plan heads for it (its end within 30 degrees of +x, at least 2 m on) and
  // the first command does not move away from it. From rest the command is bounded by the acceleration over
  // one period (0.1 m/s), and its direction is the plan's first bend (the DAgger cvae starts about 45 degrees
  // off +x and swings back), so the plan says more than the command.
  EXPECT_GT(out.command.x(), 0.0) << out.command.transpose();
  ASSERT_FALSE(out.planner.plan.empty());
  const Vec2 end = out.planner.plan.back();
  EXPECT_GT(end.x(), 2.0) << end.transpose();
  EXPECT_LT(std::abs(end.y()), std::tan(std::numbers::pi / 6) * end.x()) << end.transpose();
  EXPECT_NE(out.planner.safety, planners::SafetyAction::off);
}

TEST(Tracker, NanScanStops) {
  Tracker tracker(TrackerSettings{});
  core::Scan scan = open_scan();
  scan.ranges.assign(scan.ranges.size(), kNaN);
  expect_stop(tracker.step(kNow, robot_at_origin(), target_ahead(), &scan), "scan: only 0 of 360 beams usable");
  expect_stop(tracker.step(kNow, robot_at_origin(), target_ahead(), nullptr), "scan: none received");
  scan = open_scan();
  scan.angle_increment = kNaN;
  expect_stop(tracker.step(kNow, robot_at_origin(), target_ahead(), &scan), "angle_increment");
  scan = open_scan();
  scan.ranges.clear();
  expect_stop(tracker.step(kNow, robot_at_origin(), target_ahead(), &scan), "scan: no beams");
}

TEST(Tracker, DroppedBeamsAreFilledButWideGapsStop) {
  Tracker tracker(TrackerSettings{});
  core::Scan scan = open_scan();
  for (int i = 0; i < 360; i += 10) scan.ranges[static_cast<std::size_t>(i)] = kNaN;  // scattered dropouts
  const TrackerOutput& out = tracker.step(kNow, robot_at_origin(), target_ahead(), &scan);
  EXPECT_FALSE(out.stopped) << out.reason;
  EXPECT_TRUE(out.command.allFinite());
  // 20 beams in a row (21 degrees between the beams around them) are more than max_invalid_gap allows.
  for (int i = 100; i < 120; ++i) scan.ranges[static_cast<std::size_t>(i)] = kNaN;
  expect_stop(tracker.step(kNow + 0.05, robot_at_origin(), target_ahead(kNow + 0.05), &scan), "max_invalid_gap");
}

TEST(Tracker, StaleOrFutureTargetStops) {
  Tracker tracker(TrackerSettings{});
  const core::Scan scan = open_scan(kNow + 1.0);
  const RobotState robot{Vec2::Zero(), Vec2::Zero(), kNow + 1.0};
  expect_stop(tracker.step(kNow + 1.0, robot, target_ahead(kNow), &scan), "target: stale");
  expect_stop(tracker.step(kNow + 1.0, robot, target_ahead(kNow + 2.0), &scan), "target: stamp is 1 s ahead");
  TargetEstimate bad = target_ahead(kNow + 1.0);
  bad.velocity.y() = kNaN;
  expect_stop(tracker.step(kNow + 1.0, robot, bad, &scan), "target: velocity");
  // A target estimate younger than the timeout is tracked (extrapolated by its age).
  const TrackerOutput& out = tracker.step(kNow + 1.0, robot, target_ahead(kNow + 0.7), &scan);
  EXPECT_FALSE(out.stopped) << out.reason;
}

TEST(Tracker, BadRobotStateOrStaleScanStops) {
  Tracker tracker(TrackerSettings{});
  const core::Scan scan = open_scan();
  RobotState robot = robot_at_origin();
  robot.position.x() = kInf;
  expect_stop(tracker.step(kNow, robot, target_ahead(), &scan), "robot: position");
  expect_stop(tracker.step(kNow + 2.0, {Vec2::Zero(), Vec2::Zero(), kNow + 2.0}, target_ahead(kNow + 2.0), &scan),
              "scan: stale");
  expect_stop(tracker.step(kNaN, robot_at_origin(), target_ahead(), &scan), "time");
}

TEST(Tracker, BadSettingsAreRefusedNamingTheSetting) {
  auto message = [](const TrackerSettings& s) {
    try {
      Tracker tracker(s);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  TrackerSettings s;
  s.target_timeout = 0.0;
  EXPECT_NE(message(s).find("target_timeout"), std::string::npos) << message(s);
  s = {};
  s.planner = "teleport";
  EXPECT_NE(message(s).find("planner \"teleport\""), std::string::npos) << message(s);
  s = {};
  s.min_valid_share = 1.5;
  EXPECT_NE(message(s).find("min_valid_share"), std::string::npos) << message(s);
  s = {};
  s.options.planning_period = kNaN;
  EXPECT_NE(message(s).find("options.planning_period"), std::string::npos) << message(s);
  s = {};
  s.options.model = "/nonexistent/model.safetensors";
  EXPECT_NE(message(s).find("tracker: planner:"), std::string::npos) << message(s);
}

}  // namespace
}  // namespace occtrack
