// io/html_replay: the episode replay is one self-contained page whose inlined data holds every frame and
// planning cycle (moving obstacles where sim::World put them), never NaN, stays small for long episodes, and
// recording the cycles changes nothing else of the episode. The page in a browser: tests/cli/html_replay_browser.py.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "occtrack/io/html_replay.hpp"
#include "occtrack/io/results.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/safety.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/world.hpp"

namespace {

using namespace occtrack;
using core::Vec2;
using nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// tests/data/scenarios/example.yaml: 150 s, two static obstacles and a moving circle.
core::Scenario example(double duration) {
  core::Scenario s = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/example.yaml");
  s.duration = duration;
  return s;
}

// A planner with a plan and many candidates, like Proj-CEM's, at the follower's speed of computation: heads
// for the target; the plan is 50 points along that way, the candidates the same fanned out.
class Fan : public planners::Planner {
 public:
  std::string name() const override { return "fan"; }
  void reset() override {}
  void plan(const planners::PlannerInput& in, planners::PlannerOutput& out) override {
    const Vec2 to_target = in.target_position - in.robot_position;
    out.command_velocity = to_target.norm() > 2.0 ? Vec2(to_target.normalized()) : Vec2::Zero();
    out.ok = true;
    out.compute_ms = 0.1;
    out.plan.clear();
    for (int k = 0; k < 50; ++k) out.plan.push_back(in.robot_position + 0.05 * k * out.command_velocity);
    out.candidates.assign(24, {});
    for (int c = 0; c < 24; ++c)
      for (int k = 0; k < 50; ++k)
        out.candidates[c].push_back(in.robot_position + 0.05 * k * Vec2(std::cos(c * 0.26), std::sin(c * 0.26)));
  }
  const planners::PlanRecord& last_record() const override { return record_; }

 private:
  planners::PlanRecord record_;
};

sim::EpisodeResult run(const core::Scenario& scenario, bool record_cycles) {
  Fan planner;
  sim::EpisodeSettings settings;
  settings.record_cycles = record_cycles;
  return sim::run_episode(scenario, planner, settings);
}

// The JSON in <script type="application/json" id="replay-data">.
json page_data(const std::string& page) {
  const std::string open = "<script type=\"application/json\" id=\"replay-data\">";
  const std::size_t begin = page.find(open);
  EXPECT_NE(begin, std::string::npos);
  const std::size_t end = page.find("</script>", begin);
  return json::parse(page.substr(begin + open.size(), end - begin - open.size()));  // strict: no NaN, no Infinity
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

TEST(HtmlReplay, RecordingCyclesChangesNothingElse) {
  const core::Scenario scenario = example(6.0);
  sim::EpisodeResult off = run(scenario, false), on = run(scenario, true);
  EXPECT_TRUE(off.trace.cycles.empty());
  ASSERT_EQ(static_cast<int>(on.trace.cycles.size()), on.metrics.cycles);
  EXPECT_EQ(off.trace.robot, on.trace.robot);
  EXPECT_EQ(off.trace.occluded, on.trace.occluded);
  ASSERT_EQ(off.trace.snapshots.size(), on.trace.snapshots.size());
  for (std::size_t k = 0; k < off.trace.snapshots.size(); ++k) {
    EXPECT_EQ(off.trace.snapshots[k].plan, on.trace.snapshots[k].plan);
    EXPECT_EQ(off.trace.snapshots[k].candidates, on.trace.snapshots[k].candidates);
  }
  off.metrics.compute_ms = on.metrics.compute_ms = {};  // wall-clock times, the one thing that may differ
  EXPECT_EQ(io::episode_json(off.metrics), io::episode_json(on.metrics));

  const core::CycleRecord& c = on.trace.cycles[3];
  EXPECT_DOUBLE_EQ(c.time, 3 * 0.05);
  EXPECT_EQ(c.scan.ranges.size(), 720u);
  EXPECT_EQ(c.plan.size(), 50u);
  EXPECT_EQ(c.candidates.size(), core::CycleRecord::kMaxCandidates);
  EXPECT_STREQ(c.safety, "");  // no safety layer
  const Vec2 to_target = sim::World(scenario).target_position(c.time) - c.robot;
  EXPECT_NEAR(c.command.norm(), to_target.norm() > 2.0 ? 1.0 : 0.0, 1e-12);  // the Fan's command, as sent
}

TEST(HtmlReplay, PageIsSelfContainedAndHoldsEveryFrame) {
  const core::Scenario scenario = example(6.0);
  const sim::EpisodeResult r = run(scenario, true);
  const std::string page = io::episode_html(scenario, r.trace, r.metrics);

  EXPECT_EQ(page.rfind("<!DOCTYPE html>", 0), 0u);
  for (const char* outside : {"http://", "https://", "src=", "<link", "@import", "url(", "//cdn", "fetch("})
    EXPECT_EQ(page.find(outside), std::string::npos) << outside;
  EXPECT_NE(page.find("<canvas"), std::string::npos);
  for (const char* control : {"id=\"play\"", "id=\"speed\"", "id=\"slider\"", "id=\"metrics\"", "id=\"selftest\""})
    EXPECT_NE(page.find(control), std::string::npos) << control;
  EXPECT_EQ(page.find("NaN"), std::string::npos);
  EXPECT_EQ(page.find("Infinity"), std::string::npos);

  const json data = page_data(page);
  EXPECT_EQ(data["metrics"], json::parse(io::episode_json(r.metrics)));  // the results file's object itself
  const json& frames = data["frames"];
  ASSERT_EQ(frames["t"].size(), r.trace.time.size());
  EXPECT_EQ(frames["robot"].size(), 2 * r.trace.robot.size());
  EXPECT_EQ(frames["occluded"].get<std::string>().size(), r.trace.occluded.size());
  EXPECT_EQ(frames["t"][10].get<int>(), static_cast<int>(std::lround(r.trace.time[10] * 1000)));
  EXPECT_EQ(frames["robot"][20].get<int>(), static_cast<int>(std::lround(r.trace.robot[10].x() * 100)));

  ASSERT_EQ(data["cycles"].size(), r.trace.cycles.size());
  const json& cycle = data["cycles"][5];
  EXPECT_EQ(cycle["ranges"].size(), 360u);  // 720 beams, every other one
  EXPECT_NEAR(cycle["angle_step"].get<double>(), 2 * r.trace.cycles[5].scan.angle_increment, 1e-6);
  EXPECT_EQ(cycle["plan"].size(), 2u * 12);
  EXPECT_EQ(cycle["candidates"].size(), 10u);
  EXPECT_EQ(cycle["candidates"][0].size(), 2u * 12);
  EXPECT_EQ(cycle["command"][0].get<int>(), static_cast<int>(std::lround(r.trace.cycles[5].command.x() * 100)));
  EXPECT_FALSE(cycle.contains("safety"));  // written only with the safety layer
  // A beam's return lands where the cycle's robot and the scan say.
  const core::CycleRecord& c = r.trace.cycles[5];
  for (std::size_t b = 0; b < cycle["ranges"].size(); ++b) {
    const double range = c.scan.ranges[2 * b];
    if (std::isfinite(range) && range <= c.scan.range_max)
      EXPECT_EQ(cycle["ranges"][b].get<int>(), static_cast<int>(std::lround(range * 100)));
    else
      EXPECT_EQ(cycle["ranges"][b].get<int>(), -1);  // no return
  }

  // The moving circle (obstacle 2) where sim::World has it at each frame's time.
  ASSERT_EQ(data["moving"], json::array({2}));
  ASSERT_EQ(data["moving_xy"].size(), 2 * r.trace.time.size());
  sim::World world(scenario);
  for (const std::size_t i : {std::size_t{0}, r.trace.time.size() / 2, r.trace.time.size() - 1}) {
    const Vec2 centre = world.shapes_at(r.trace.time[i])[2].center;
    EXPECT_EQ(data["moving_xy"][2 * i].get<int>(), static_cast<int>(std::lround(centre.x() * 100)));
    EXPECT_EQ(data["moving_xy"][2 * i + 1].get<int>(), static_cast<int>(std::lround(centre.y() * 100)));
  }
  EXPECT_NE(data["moving_xy"][0], data["moving_xy"][2 * (r.trace.time.size() - 1)]);  // it did move
}

TEST(HtmlReplay, EachCycleSaysWhatTheSafetyLayerDid) {
  const core::Scenario scenario = example(4.0);
  std::unique_ptr<planners::Planner> shielded = planners::safety::make_shielded(std::make_unique<Fan>(), {});
  sim::EpisodeSettings settings;
  settings.record_cycles = true;
  const sim::EpisodeResult r = sim::run_episode(scenario, *shielded, settings);
  const json data = page_data(io::episode_html(scenario, r.trace, r.metrics));
  ASSERT_EQ(data["cycles"].size(), r.trace.cycles.size());
  int plan = 0;
  for (std::size_t k = 0; k < r.trace.cycles.size(); ++k) {
    const std::string said = data["cycles"][k]["safety"].get<std::string>();
    EXPECT_EQ(said, r.trace.cycles[k].safety);
    bool known = false;
    for (int a = 1; a < planners::kSafetyActions; ++a)
      known = known || said == planners::to_string(static_cast<planners::SafetyAction>(a));
    EXPECT_TRUE(known) << said;
    plan += said == "plan";
  }
  EXPECT_EQ(plan, r.metrics.shield.plan);  // the same counts as the metrics
}

TEST(HtmlReplay, WithoutCyclesTheFramesStillPlay) {
  const core::Scenario scenario = example(2.0);
  const sim::EpisodeResult r = run(scenario, false);
  const json data = page_data(io::episode_html(scenario, r.trace, r.metrics));
  EXPECT_TRUE(data["cycles"].empty());
  EXPECT_EQ(data["frames"]["t"].size(), r.trace.time.size());
}

TEST(HtmlReplay, NonFiniteValuesAreNullAndNamesCannotCloseTheScript) {
  core::Scenario scenario = example(1.0);
  core::Trace trace;
  trace.time = {0.0, 0.05, 0.1};
  trace.robot = {Vec2(0, 0), Vec2(kNaN, 0), Vec2(1, kInf)};
  trace.target = {Vec2(1, 1), Vec2(1, 1), Vec2(1, 1)};
  trace.occluded = {0, 1, 0};
  core::CycleRecord cycle;
  cycle.robot = Vec2(0, 0);
  cycle.scan.angle_increment = 0.5;
  cycle.scan.ranges = {1.0, kInf, kNaN, 12.0, -kInf};  // 12 m: beyond range_max (10 m), no return
  cycle.plan = {Vec2(0, 0), Vec2(kNaN, 1)};
  trace.cycles = {cycle};
  core::EpisodeMetrics metrics;
  metrics.scenario = "</script><script>alert(1)</script>";
  metrics.planner = "a&b";
  metrics.min_clearance_m = kInf;
  metrics.acceleration.mean = kNaN;

  const std::string page = io::episode_html(scenario, trace, metrics);
  EXPECT_EQ(occurrences(page, "</script>"), 3u);  // the error hook, the data, the replay
  EXPECT_EQ(page.find("<script>alert"), std::string::npos);
  EXPECT_NE(page.find("<title>&lt;/script&gt;"), std::string::npos);
  const json data = page_data(page);
  EXPECT_EQ(data["title"], metrics.scenario + " \u2014 a&b");
  EXPECT_EQ(data["frames"]["robot"], json::parse("[0,0,null,0,100,null]"));
  EXPECT_EQ(data["cycles"][0]["ranges"], json::parse("[100,-1,-1,-1,-1]"));
  EXPECT_EQ(data["cycles"][0]["plan"], json::parse("[0,0,null,100]"));
  EXPECT_TRUE(data["metrics"]["acceleration"]["mean"].is_null());
}

TEST(HtmlReplay, RefusesBadOptionsAndTraces) {
  const core::Scenario scenario = example(1.0);
  core::Trace trace;
  trace.time = {0.0};
  trace.robot = {Vec2(0, 0)};
  trace.target = {Vec2(1, 1)};
  trace.occluded = {0};
  io::HtmlReplayOptions options;
  options.max_beams = 0;
  EXPECT_THROW(io::episode_html(scenario, trace, {}, options), std::invalid_argument);
  options = {};
  options.max_path_points = 1;
  std::string error;
  EXPECT_FALSE(options.validate(&error));
  EXPECT_NE(error.find("max_path_points"), std::string::npos);
  trace.occluded.push_back(1);
  EXPECT_THROW(io::episode_html(scenario, trace, {}), std::invalid_argument);
}

// 150 s at 20 Hz with 720-beam scans mostly returning and 24 candidates of 50 points: under 10 MB.
TEST(HtmlReplay, LongEpisodeStaysUnderTenMegabytes) {
  const core::Scenario scenario = example(150.0);
  const sim::EpisodeResult r = run(scenario, true);
  ASSERT_EQ(r.trace.cycles.size(), 3000u);
  const std::string page = io::episode_html(scenario, r.trace, r.metrics);
  EXPECT_LT(page.size(), 10u << 20) << page.size() << " bytes";
}

TEST(HtmlReplay, SuiteIndexLinksEveryPage) {
  core::SuiteResult suite;
  suite.suite = "smoke";
  suite.planner = "follower";
  suite.episodes.resize(2);
  suite.episodes[0].scenario = "forest a";
  suite.episodes[0].occlusion_time_s = 1.25;
  suite.episodes[1].scenario = "<b>";
  suite.episodes[1].success = true;
  suite.summary.min_clearance_m = kNaN;
  const std::string index = io::suite_html_index(suite, {"forest a.follower.html", "x.follower.html"});
  EXPECT_NE(index.find("<a href=\"forest%20a.follower.html\">forest a</a>"), std::string::npos);
  EXPECT_NE(index.find("<a href=\"x.follower.html\">&lt;b&gt;</a>"), std::string::npos);
  EXPECT_NE(index.find("<td>1.25</td>"), std::string::npos);
  EXPECT_NE(index.find("summary (2 episodes)"), std::string::npos);
  EXPECT_EQ(index.find("nan"), std::string::npos);
  EXPECT_EQ(index.find("http"), std::string::npos);
  EXPECT_THROW(io::suite_html_index(suite, {"only-one.html"}), std::invalid_argument);
}

}  // namespace
