// The v2 suites (sim::benchmark_suites_v2, shared/spec/simulation.md "Suites v2") and their committed files
// (scenarios/<suite>/): the worlds they promise, seeds apart from v1's, tele-operated targets at the nominal
// speed, and files that hold what the suite says, checked with the simulator's own World.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "occtrack/io/scenario.hpp"
#include "occtrack/sim/paper_worlds.hpp"
#include "occtrack/sim/scenario_generator.hpp"
#include "occtrack/sim/world.hpp"

namespace {

using occtrack::core::ObstacleSpec;
using occtrack::core::Scenario;
using occtrack::core::Vec2;
namespace sim = occtrack::sim;

const std::map<std::string, double> kNominalSpeed = {
    {"sixwall-1ms", 1.0}, {"sixwall-2ms", 2.0},  {"sixwall-dynamic-1.5ms", 1.5},
    {"random-2ms", 2.0},  {"clutter-2ms", 2.0}, {"clutter-dynamic-2ms", 2.0},
};

std::string base_name(const std::string& suite) {
  return suite.ends_with("-smoke") ? suite.substr(0, suite.size() - 6) : suite;
}

std::set<std::uint64_t> episode_seeds(const sim::SuiteSpec& suite) {
  std::set<std::uint64_t> seeds;
  for (std::size_t w = 0; w < suite.worlds.size(); ++w)
    for (int e = 1; e <= suite.episodes_of(w); ++e) seeds.insert(suite.episode_seed(static_cast<int>(w), e));
  return seeds;
}

int episode_count(const sim::SuiteSpec& suite) {
  int n = 0;
  for (std::size_t w = 0; w < suite.worlds.size(); ++w) n += suite.episodes_of(w);
  return n;
}

TEST(SuitesV2, TheSpecsSuitesWithSeedsApartFromV1) {
  std::set<std::uint64_t> v1_seeds;
  for (const sim::SuiteSpec& suite : sim::benchmark_suites()) {
    const std::set<std::uint64_t> s = episode_seeds(suite);
    v1_seeds.insert(s.begin(), s.end());
  }
  std::set<std::string> names;
  std::set<std::uint64_t> v2_seeds;
  for (const sim::SuiteSpec& suite : sim::benchmark_suites_v2()) {
    SCOPED_TRACE(suite.name);
    names.insert(suite.name);
    const bool smoke = suite.name.ends_with("-smoke");
    ASSERT_TRUE(kNominalSpeed.contains(base_name(suite.name)));
    EXPECT_EQ(suite.target.motion, sim::TargetMotion::teleop);
    EXPECT_EQ(suite.target.max_speed, kNominalSpeed.at(base_name(suite.name)));
    EXPECT_EQ(suite.target.duration, smoke ? 20.0 : 90.0);
    std::string error;
    EXPECT_TRUE(suite.target.validate(&error)) << error;
    if (smoke) {
      EXPECT_LE(episode_count(suite), 3);
    } else {
      EXPECT_EQ(episode_count(suite), 10);
    }
    for (const std::uint64_t seed : episode_seeds(suite)) {
      EXPECT_TRUE(sim::is_benchmark_seed(seed)) << seed;
      EXPECT_FALSE(v1_seeds.contains(seed)) << seed;
      EXPECT_TRUE(v2_seeds.insert(seed).second) << "seed " << seed << " used twice";
    }
    ASSERT_TRUE(sim::find_suite(suite.name).has_value());
  }
  EXPECT_EQ(names, (std::set<std::string>{"sixwall-1ms", "sixwall-2ms", "sixwall-dynamic-1.5ms", "random-2ms",
                                          "clutter-2ms", "clutter-dynamic-2ms", "sixwall-1ms-smoke",
                                          "sixwall-2ms-smoke", "sixwall-dynamic-1.5ms-smoke", "random-2ms-smoke",
                                          "clutter-2ms-smoke", "clutter-dynamic-2ms-smoke"}));
}

TEST(SuitesV2, WorldsAreThePapersAndV1s) {
  std::map<std::string, sim::SuiteWorld> v1_worlds;
  for (const sim::SuiteSpec& suite : sim::benchmark_suites())
    for (const sim::SuiteWorld& w : suite.worlds) v1_worlds[w.name] = w;
  const auto same_obstacles = [](const Scenario& a, const Scenario& b) {
    if (a.obstacles.size() != b.obstacles.size()) return false;
    for (std::size_t k = 0; k < a.obstacles.size(); ++k) {
      const ObstacleSpec &p = a.obstacles[k], &q = b.obstacles[k];
      if (p.shape != q.shape || p.center != q.center || p.radius != q.radius || p.size != q.size ||
          p.yaw != q.yaw || p.path != q.path || p.speed != q.speed)
        return false;
    }
    return !a.obstacles.empty();
  };
  const sim::SuiteSpec six = *sim::find_suite("sixwall-1ms");
  ASSERT_EQ(six.worlds.size(), 1u);
  EXPECT_TRUE(same_obstacles(sim::suite_world(six.worlds[0]), sim::six_wall_world(false)));
  const sim::SuiteSpec sliding = *sim::find_suite("sixwall-dynamic-1.5ms");
  EXPECT_TRUE(same_obstacles(sim::suite_world(sliding.worlds[0]), sim::six_wall_world(true)));
  const sim::SuiteSpec random = *sim::find_suite("random-2ms");
  EXPECT_TRUE(same_obstacles(sim::suite_world(random.worlds[0]), sim::random_world()));

  // clutter-2ms: v1's static worlds with their settings and seeds; clutter-dynamic-2ms: v1's dynamic world with
  // its obstacles at 1 m/s.
  const sim::SuiteSpec clutter = *sim::find_suite("clutter-2ms");
  ASSERT_EQ(clutter.worlds.size(), 3u);
  for (const sim::SuiteWorld& w : clutter.worlds) {
    ASSERT_TRUE(v1_worlds.contains(w.name)) << w.name;
    EXPECT_FALSE(w.fixed.has_value());
    EXPECT_EQ(w.settings, v1_worlds[w.name].settings);
    EXPECT_EQ(w.seed, v1_worlds[w.name].seed);
  }
  const sim::SuiteSpec dynamic = *sim::find_suite("clutter-dynamic-2ms");
  ASSERT_EQ(dynamic.worlds.size(), 1u);
  sim::GeneratorSettings expected = v1_worlds.at("dynamic-a").settings;
  expected.moving_speed = 1.0;
  EXPECT_EQ(dynamic.worlds[0].settings, expected);
  EXPECT_EQ(dynamic.worlds[0].seed, v1_worlds.at("dynamic-a").seed);
  int moving = 0;
  for (const ObstacleSpec& o : sim::suite_world(dynamic.worlds[0]).obstacles)
    if (o.moving()) {
      ++moving;
      EXPECT_EQ(o.speed, 1.0);
    }
  EXPECT_EQ(moving, 6);
}

// The committed files (`occtrack scenario generate --suite all --out scenarios`).
TEST(SuitesV2, ShippedFilesHoldWhatTheSuiteSays) {
  const std::filesystem::path root = std::filesystem::path(OCCTRACK_TEST_DATA_DIR) / ".." / ".." / "scenarios";
  for (const sim::SuiteSpec& suite : sim::benchmark_suites_v2()) {
    SCOPED_TRACE(suite.name);
    const bool smoke = suite.name.ends_with("-smoke");
    const std::filesystem::path folder = root / suite.name;
    ASSERT_TRUE(std::filesystem::is_directory(folder)) << folder;
    std::map<std::string, Scenario> worlds;
    for (const sim::SuiteWorld& w : suite.worlds) worlds[w.name] = sim::suite_world(w);
    int files = 0, occluded_episodes = 0;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      if (entry.path().extension() != ".yaml") continue;
      ++files;
      const Scenario s = occtrack::io::read_scenario(entry.path().string());
      SCOPED_TRACE(s.name);
      EXPECT_EQ(s.name, entry.path().stem().string());
      EXPECT_DOUBLE_EQ(s.duration, smoke ? 20.0 : 90.0);
      const std::string world_name = s.name.substr(0, s.name.rfind('-'));
      ASSERT_TRUE(worlds.contains(world_name));
      const Scenario& world = worlds[world_name];
      ASSERT_EQ(s.obstacles.size(), world.obstacles.size());
      for (std::size_t k = 0; k < s.obstacles.size(); ++k) {
        EXPECT_EQ(s.obstacles[k].center, world.obstacles[k].center) << k;
        EXPECT_EQ(s.obstacles[k].path, world.obstacles[k].path) << k;
      }
      // Waypoints every 0.1 s (the teleop generator's period) over the whole episode.
      ASSERT_GE(s.target.size(), 2u);
      EXPECT_NEAR(s.target[1].time - s.target[0].time, 0.1, 1e-9);
      EXPECT_NEAR(s.target.back().time, s.duration, 0.1 + 1e-9);
      sim::World w(s);
      EXPECT_FALSE(w.segment_blocked(s.robot_position, s.target.front().position, 0.0));
      EXPECT_GE(w.clearance(s.robot_position, 0.0), s.robot_radius);
      // The target never touches an obstacle (checked every 0.02 s, moving obstacles where they are then).
      double closest = 1e9;
      for (double t = 0.0; t <= s.duration; t += 0.02) closest = std::min(closest, w.clearance(w.target_position(t), t));
      EXPECT_GT(closest, s.target_radius);
      if (sim::leash_follower_occlusion(s).occlusion_events > 0) ++occluded_episodes;
    }
    EXPECT_EQ(files, episode_count(suite));
    // The smoke bases were chosen so that every smoke episode holds a stretch of lost sight.
    if (smoke) {
      EXPECT_EQ(occluded_episodes, files);
    }
  }
}

}  // namespace
