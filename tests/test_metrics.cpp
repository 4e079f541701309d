// Episode and suite metrics (sim/metrics.hpp) on hand-made sequences, and the results JSON they feed
// (io/results.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "occtrack/io/results.hpp"
#include "occtrack/sim/metrics.hpp"

namespace {

using occtrack::core::EpisodeMetrics;
using occtrack::core::TrackingBand;
namespace sim = occtrack::sim;
namespace io = occtrack::io;

TEST(Metrics, EpisodeAccumulatesStepsCyclesAndAccelerations) {
  // 4 steps of 0.5 s (5 states); band [1, 3]; sensor range 4 m.
  sim::EpisodeMetricsAccumulator acc("scene", "planner", 0.5, 4.0, TrackingBand{}, 2);
  acc.add_state(1.0, false, 2.0, false);   // in band
  acc.add_state(-0.1, true, 5.0, false);   // collision begins, occluded, out of range
  acc.add_state(-0.2, true, 0.5, false);   // still in the same collision
  acc.add_state(0.3, false, 3.0, false);   // in band (the boundary counts)
  acc.add_state(-0.3, true, 9.0, true);    // last state: a new collision, but no time
  acc.add_cycle(2.0, false);
  acc.add_cycle(4.0, true);
  for (const double a : {1.0, 0.0, 3.0, 2.0}) acc.add_acceleration(a);

  const EpisodeMetrics m = acc.finish();
  EXPECT_EQ(m.scenario, "scene");
  EXPECT_EQ(m.planner, "planner");
  EXPECT_DOUBLE_EQ(m.duration_s, 2.0);
  EXPECT_DOUBLE_EQ(m.occlusion_time_s, 1.0);
  EXPECT_FALSE(m.success);
  EXPECT_EQ(m.collisions, 2);
  EXPECT_DOUBLE_EQ(m.collision_time_s, 1.0);
  EXPECT_DOUBLE_EQ(m.min_clearance_m, -0.3);
  EXPECT_DOUBLE_EQ(m.target_out_of_range_s, 0.5);
  EXPECT_DOUBLE_EQ(m.tracking_distance_mean_m, (2.0 + 5.0 + 0.5 + 3.0) / 4);
  EXPECT_DOUBLE_EQ(m.tracking_in_band_share, 0.5);
  EXPECT_DOUBLE_EQ(m.acceleration.mean, 1.5);
  EXPECT_DOUBLE_EQ(m.acceleration.min, 0.0);
  EXPECT_DOUBLE_EQ(m.acceleration.max, 3.0);
  EXPECT_EQ(m.cycles, 2);
  EXPECT_EQ(m.planner_failures, 1);
  EXPECT_DOUBLE_EQ(m.compute_ms.mean, 3.0);
  EXPECT_DOUBLE_EQ(m.compute_ms.median, 3.0);
  EXPECT_DOUBLE_EQ(m.compute_ms.max, 4.0);
}

TEST(Metrics, EpisodeWithoutStepsOrObstacles) {
  sim::EpisodeMetricsAccumulator acc("s", "p", 0.01, 10.0, TrackingBand{});
  acc.add_state(INFINITY, false, 2.0, true);
  const EpisodeMetrics m = acc.finish();
  EXPECT_EQ(m.duration_s, 0.0);
  EXPECT_TRUE(m.success);
  EXPECT_EQ(m.acceleration.min, 0.0);  // none measured
  EXPECT_EQ(m.min_clearance_m, INFINITY);
  EXPECT_EQ(m.cycles, 0);
  // The JSON writes an infinite clearance as 0 (JSON has no infinity).
  EXPECT_EQ(nlohmann::json::parse(io::episode_json(m))["min_clearance_m"], 0.0);
}

TEST(Metrics, SuiteSummaryWeightsAndCombines) {
  EpisodeMetrics a, b;
  a.duration_s = 10.0;
  a.occlusion_time_s = 0.0;
  a.success = true;
  a.collisions = 1;
  a.min_clearance_m = 0.2;
  a.acceleration = {1.0, 0.5, 2.0};
  a.compute_ms.mean = 2.0;
  a.compute_ms.median = 1.0;
  a.compute_ms.p99 = 5.0;
  a.compute_ms.max = 6.0;
  a.tracking_distance_mean_m = 2.0;
  a.tracking_in_band_share = 1.0;
  a.cycles = 100;
  b = a;
  b.duration_s = 30.0;
  b.occlusion_time_s = 1.5;
  b.success = false;
  b.min_clearance_m = -0.1;
  b.acceleration = {3.0, 0.1, 1.5};
  b.compute_ms.mean = 4.0;
  b.compute_ms.median = 3.0;
  b.compute_ms.p99 = 4.0;
  b.compute_ms.max = 9.0;
  b.tracking_distance_mean_m = 4.0;
  b.tracking_in_band_share = 0.5;
  b.cycles = 300;

  const auto r = sim::summarize_suite("suite", "planner", {a, b});
  EXPECT_EQ(r.episodes.size(), 2u);
  EXPECT_DOUBLE_EQ(r.success_rate, 0.5);
  EXPECT_FALSE(r.summary.success);
  EXPECT_DOUBLE_EQ(r.summary.duration_s, 40.0);
  EXPECT_DOUBLE_EQ(r.summary.occlusion_time_s, 1.5);
  EXPECT_EQ(r.summary.collisions, 2);
  EXPECT_DOUBLE_EQ(r.summary.min_clearance_m, -0.1);
  EXPECT_DOUBLE_EQ(r.summary.acceleration.mean, (1.0 * 10 + 3.0 * 30) / 40);  // weighted by duration
  EXPECT_DOUBLE_EQ(r.summary.acceleration.min, 0.1);
  EXPECT_DOUBLE_EQ(r.summary.acceleration.max, 2.0);
  EXPECT_DOUBLE_EQ(r.summary.compute_ms.mean, (2.0 * 100 + 4.0 * 300) / 400);  // weighted by cycles
  EXPECT_DOUBLE_EQ(r.summary.compute_ms.median, 2.0);  // the median of the medians
  EXPECT_DOUBLE_EQ(r.summary.compute_ms.p99, 5.0);
  EXPECT_DOUBLE_EQ(r.summary.compute_ms.max, 9.0);
  EXPECT_DOUBLE_EQ(r.summary.tracking_distance_mean_m, (2.0 * 10 + 4.0 * 30) / 40);
  EXPECT_EQ(r.summary.cycles, 400);

  const auto j = nlohmann::json::parse(io::suite_json(r));
  EXPECT_EQ(j["suite"], "suite");
  EXPECT_EQ(j["episodes"].size(), 2u);
  EXPECT_EQ(j["summary"]["success"], 0.5);  // the summary's success is the rate
  EXPECT_EQ(j["episodes"][1]["success"], false);
  EXPECT_NE(io::suite_table({r}).find("| suite "), std::string::npos);
}

TEST(Metrics, EmptySuite) {
  const auto r = sim::summarize_suite("suite", "planner", {});
  EXPECT_EQ(r.success_rate, 0.0);
  EXPECT_EQ(r.summary.duration_s, 0.0);
  EXPECT_EQ(r.summary.scenario, "suite");
}

// A suite over three sensor draws whose totals are 1, 2 and 6 s: mean 3, sample sd sqrt(((1-3)^2 + (2-3)^2 +
// (6-3)^2) / 2) = sqrt(7), least at the first draw's seed, largest at the third's; collisions in one draw.
TEST(Metrics, DrawsSpreadOverSensorSeeds) {
  auto draw = [](double hidden, int collisions, double clearance, double longest) {
    EpisodeMetrics a, b;
    a.duration_s = b.duration_s = 10.0;
    a.occlusion_time_s = hidden / 2;
    b.occlusion_time_s = hidden / 2;
    a.success = b.success = hidden == 0.0;
    a.collisions = collisions;
    a.min_clearance_m = clearance;
    b.min_clearance_m = 0.5;
    a.longest_occlusion_s = longest;
    b.beyond_envelope_cycles = 2;
    return sim::summarize_suite("suite", "planner", {a, b});
  };
  const std::vector<std::uint64_t> seeds = {7, 3, 11};
  const auto r =
      sim::summarize_draws(seeds, {draw(1.0, 0, 0.3, 0.5), draw(2.0, 2, -0.05, 1.0), draw(6.0, 0, 0.2, 4.0)});
  EXPECT_EQ(r.suite, "suite");
  EXPECT_EQ(r.draws.size(), 3u);
  EXPECT_DOUBLE_EQ(r.occlusion_time_s.mean, 3.0);
  EXPECT_DOUBLE_EQ(r.occlusion_time_s.sd, std::sqrt(7.0));
  EXPECT_DOUBLE_EQ(r.occlusion_time_s.min, 1.0);
  EXPECT_DOUBLE_EQ(r.occlusion_time_s.max, 6.0);
  EXPECT_EQ(r.occlusion_time_s.min_at, 0u);
  EXPECT_EQ(r.occlusion_time_s.max_at, 2u);
  EXPECT_DOUBLE_EQ(r.longest_occlusion_s.mean, 5.5 / 3);
  EXPECT_DOUBLE_EQ(r.collisions.mean, 2.0 / 3);
  EXPECT_EQ(r.collisions.max_at, 1u);
  EXPECT_EQ(r.draws_with_collision, 1);
  EXPECT_DOUBLE_EQ(r.min_clearance_m, -0.05);
  EXPECT_EQ(r.beyond_envelope_cycles, 6);
  EXPECT_DOUBLE_EQ(r.success_rate.sd, 0.0);  // no draw has a successful episode

  const auto j = nlohmann::json::parse(io::draws_json(r));
  EXPECT_EQ(j["sensor_seeds"], nlohmann::json({7, 3, 11}));
  ASSERT_EQ(j["draws"].size(), 3u);
  EXPECT_EQ(j["draws"][1]["sensor_seed"], 3);
  EXPECT_EQ(j["draws"][1]["summary"]["collisions"], 2);
  EXPECT_EQ(j["over_draws"]["occlusion_time_s"]["min_seed"], 7);  // seeds, not indices
  EXPECT_EQ(j["over_draws"]["occlusion_time_s"]["max_seed"], 11);
  EXPECT_EQ(j["over_draws"]["draws_with_collision"], 1);
  const std::string table = io::draws_table(r);
  EXPECT_NE(table.find("over 3 sensor draws"), std::string::npos);
  EXPECT_NE(table.find("3.0 / 2.6 / 1.0 (7) / 6.0 (11)"), std::string::npos) << table;
  EXPECT_NE(table.find("1 of 3 draws; least clearance -0.050 m"), std::string::npos) << table;

  // One draw: no spread.
  const auto one = sim::summarize_draws({5}, {draw(2.0, 0, 0.3, 1.0)});
  EXPECT_DOUBLE_EQ(one.occlusion_time_s.sd, 0.0);
  EXPECT_DOUBLE_EQ(one.occlusion_time_s.mean, 2.0);

  EXPECT_THROW(sim::summarize_draws({}, {}), std::invalid_argument);
  EXPECT_THROW(sim::summarize_draws({1, 2}, {draw(1.0, 0, 0.3, 0.5)}), std::invalid_argument);
  EXPECT_THROW(sim::summarize_draws({4, 4}, {draw(1.0, 0, 0.3, 0.5), draw(1.0, 0, 0.3, 0.5)}), std::invalid_argument);
  auto other = draw(1.0, 0, 0.3, 0.5);
  other.planner = "another";
  EXPECT_THROW(sim::summarize_draws({1, 2}, {draw(1.0, 0, 0.3, 0.5), other}), std::invalid_argument);
}

}  // namespace
