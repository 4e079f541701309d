// Motion statistics of target paths (include/occtrack/sim/path_stats.hpp): paths whose statistics are known in
// closed form, irregular waypoint times, stops, U-turns, nearest-rank percentiles, joined samples.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "occtrack/core/timing.hpp"
#include "occtrack/sim/path_stats.hpp"

namespace {

using occtrack::core::TargetWaypoint;
using occtrack::core::Vec2;
namespace sim = occtrack::sim;

sim::PathStats stats_of(const std::vector<TargetWaypoint>& path) { return sim::summarize_path(sim::sample_path(path)); }

TEST(PathStats, NearestRankPercentiles) {
  const std::vector<double> v = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  EXPECT_EQ(occtrack::core::nearest_rank(v, 0.5), 5.0);
  EXPECT_EQ(occtrack::core::nearest_rank(v, 0.9), 9.0);
  EXPECT_EQ(occtrack::core::nearest_rank(v, 0.99), 10.0);
  EXPECT_EQ(occtrack::core::nearest_rank(v, 0.0), 1.0);
  EXPECT_EQ(occtrack::core::nearest_rank(v, 1.0), 10.0);
}

TEST(PathStats, StraightLineWithIrregularWaypointTimes) {
  // 1.5 m/s along a diagonal, waypoints at uneven times (as a 44 Hz recording with jitter).
  std::vector<TargetWaypoint> path;
  const Vec2 u = Vec2(3.0, 4.0) / 5.0;
  double t = 0.0;
  for (int k = 0; t < 10.0; ++k) {
    path.push_back({t, 1.5 * t * u});
    t += (k % 3 == 0) ? 0.017 : 0.029;
  }
  const sim::PathStats s = stats_of(path);
  EXPECT_NEAR(s.duration, path.back().time, 1e-12);
  EXPECT_NEAR(s.speed_mean, 1.5, 1e-9);
  EXPECT_NEAR(s.speed_max, 1.5, 1e-9);
  EXPECT_NEAR(s.acceleration_p99, 0.0, 1e-6);
  EXPECT_NEAR(s.heading_rate_p99, 0.0, 1e-6);
  const int samples = static_cast<int>(std::floor(path.back().time / 0.1 + 1e-9));
  EXPECT_EQ(s.speed_samples, samples);
  EXPECT_NEAR(s.length, 1.5 * samples * 0.1, 1e-9);
}

TEST(PathStats, CircleGivesItsTurnRateAndChordSpeed) {
  // A circle of radius 2 m at 0.5 rad/s, waypoints every 0.05 s (on the samples' times): every sampled point
  // lies on the circle, so the chords turn by exactly 0.05 rad per 0.1 s.
  const double r = 2.0, w = 0.5, h = 0.1;
  std::vector<TargetWaypoint> path;
  for (int k = 0; k <= 1200; ++k) {
    const double t = 0.05 * k;
    path.push_back({t, r * Vec2(std::cos(w * t), std::sin(w * t))});
  }
  const sim::PathStats s = stats_of(path);
  const double chord_speed = 2.0 * r * std::sin(0.5 * w * h) / h;
  const double chord_acceleration = 2.0 * chord_speed * std::sin(0.5 * w * h) / h;
  EXPECT_NEAR(s.speed_mean, chord_speed, 1e-9);
  EXPECT_NEAR(s.speed_p90, chord_speed, 1e-9);
  EXPECT_NEAR(s.acceleration_p50, chord_acceleration, 1e-9);
  EXPECT_NEAR(s.heading_rate_p50, w, 1e-9);
  EXPECT_NEAR(s.heading_rate_p99, w, 1e-9);
  EXPECT_NEAR(s.length, 600 * chord_speed * h, 1e-6);
}

TEST(PathStats, StopsLeaveHeadingRatesOutAndUTurnsCountPi) {
  // 1 m/s east for 1 s, stand 1 s, 1 m/s west for 1 s.
  const std::vector<TargetWaypoint> path = {
      {0.0, {0.0, 0.0}}, {1.0, {1.0, 0.0}}, {2.0, {1.0, 0.0}}, {3.0, {0.0, 0.0}}};
  const sim::PathSamples s = sim::sample_path(path);
  ASSERT_EQ(s.speed.size(), 30u);
  ASSERT_EQ(s.acceleration.size(), 29u);
  EXPECT_EQ(s.heading_rate.size(), 18u);  // 9 pairs east, 9 west, none across the stop
  for (const double rate : s.heading_rate) EXPECT_NEAR(rate, 0.0, 1e-9);
  const sim::PathStats stats = sim::summarize_path(s);
  EXPECT_NEAR(stats.speed_mean, 20.0 / 30.0, 1e-9);
  EXPECT_NEAR(stats.acceleration_p99, 10.0, 1e-9);  // 1 m/s to 0 within one sample

  // Reversing without stopping: the direction turns by pi within one sample.
  const std::vector<TargetWaypoint> u_turn = {{0.0, {0.0, 0.0}}, {1.0, {1.0, 0.0}}, {2.0, {0.0, 0.0}}};
  const sim::PathStats r = stats_of(u_turn);
  EXPECT_NEAR(r.heading_rate_p99, std::numbers::pi / 0.1, 1e-9);
  EXPECT_NEAR(r.acceleration_p99, 20.0, 1e-9);
}

TEST(PathStats, EmptyPathsAndJoinedSamples) {
  const sim::PathStats none = stats_of({{0.0, {1.0, 2.0}}});
  EXPECT_EQ(none.speed_samples, 0);
  EXPECT_EQ(none.speed_max, 0.0);
  EXPECT_EQ(none.duration, 0.0);

  sim::PathSamples slow = sim::sample_path({{0.0, {0.0, 0.0}}, {10.0, {5.0, 0.0}}});
  const sim::PathSamples fast = sim::sample_path({{0.0, {0.0, 0.0}}, {10.0, {0.0, 15.0}}});
  slow.append(fast);
  const sim::PathStats both = sim::summarize_path(slow);
  EXPECT_NEAR(both.duration, 20.0, 1e-12);
  EXPECT_NEAR(both.length, 20.0, 1e-9);
  EXPECT_NEAR(both.speed_mean, 1.0, 1e-9);
  EXPECT_NEAR(both.speed_max, 1.5, 1e-9);
  EXPECT_NEAR(both.heading_rate_p99, 0.0, 1e-9);  // no pair straddles the two paths
  EXPECT_EQ(both.heading_samples, 2 * 99);
}

}  // namespace
