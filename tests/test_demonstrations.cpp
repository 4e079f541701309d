// Demonstrations: the dataset file's layout and metadata (docs/learning.md), rows that hold exactly what the
// expert saw and planned, determinism whatever the thread count, and refusal of benchmark seeds and bad
// settings.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/error.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/perception/perception.hpp"
#include "occtrack/sim/demonstrations.hpp"
#include "occtrack/sim/scenario_generator.hpp"
#include "test_helpers.hpp"

using namespace occtrack;

namespace {

/// A generation that runs in seconds: two 3 s episodes, an expert with 64 samples and one CEM iteration.
sim::DemonstrationSettings tiny() {
  sim::DemonstrationSettings s;
  s.episodes = 2;
  s.first_seed = 5000;
  s.duration = 3.0;
  s.worlds = {sim::DemonstrationWorld::forest, sim::DemonstrationWorld::dynamic};
  s.expert.samples = 64;
  s.expert.cem_iterations = 1;
  s.expert.projection.iterations = 20;
  s.jobs = 1;
  s.created_by = "test_demonstrations";
  return s;
}

/// Wraps the expert and keeps what it was given, what it returned and the record it kept of the cycle.
class Spy final : public planners::Planner {
 public:
  struct Call {
    planners::PlannerInput input;
    core::Scan scan;
    planners::PlannerOutput output;
    planners::PlanRecord record;
  };
  explicit Spy(const planners::ProjCemSettings& s) : inner_(s) {}
  std::string name() const override { return "spy"; }
  void reset() override {
    inner_.reset();
    calls.clear();
  }
  using planners::Planner::plan;
  void plan(const planners::PlannerInput& input, planners::PlannerOutput& out) override {
    inner_.plan(input, out);
    Call call{input, *input.scan, out, inner_.last_record()};
    call.input.scan = nullptr;
    call.record.frame.scan = nullptr;
    calls.push_back(call);
  }
  const planners::PlanRecord& last_record() const override { return inner_.last_record(); }
  std::vector<Call> calls;

 private:
  planners::ProjCem inner_;
};

core::Scenario orbit(double duration) {
  core::Scenario s = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml");
  s.duration = duration;
  return s;
}

/// Checks every row of `recorder` against the expert calls it was made from: the observation as given, the
/// cloud and obstacles of an independent perception fed the expert's scans, coefficients that reproduce the
/// plan the expert returned, and a cost equal to the expert's own and to an independent ranking of the plan
/// in that frame, scan included (the shadow term the expert ranked by).
void expect_rows_match_calls(const sim::DemonstrationRecorder& recorder, const std::vector<Spy::Call>& calls,
                             const planners::ProjCemSettings& expert, int label_every, bool expert_drives) {
  const core::BernsteinBasis basis =
      core::bernstein_basis(expert.projection.degree, expert.projection.steps, expert.projection.horizon);
  const int n = expert.projection.coefficients();
  perception::Perception reference(expert.perception);
  perception::Observation seen;
  const planners::Ranking ranking(expert.ranking, expert.projection);
  std::size_t row = 0;
  for (std::size_t c = 0; c < calls.size(); ++c) {
    const Spy::Call& call = calls[c];
    ASSERT_TRUE(reference.process(call.scan, call.input.robot_position, seen));
    const bool labelled = !expert_drives || c % static_cast<std::size_t>(label_every) == 0;
    if (!labelled) continue;
    ASSERT_TRUE(call.output.ok) << call.output.message;
    ASSERT_TRUE(call.record.valid);
    ASSERT_LT(row, recorder.rows().size());
    const sim::DemonstrationRow& r = recorder.rows()[row++];
    EXPECT_EQ(r.time, call.input.time);
    EXPECT_EQ(r.observation.segment<2>(0), call.input.robot_velocity);
    EXPECT_EQ(r.observation.segment<2>(2), call.input.target_position - call.input.robot_position);
    EXPECT_EQ(r.observation.segment<2>(4), call.input.target_velocity);
    EXPECT_EQ(r.cloud, seen.cloud) << "cycle " << c;
    EXPECT_EQ(r.obstacles, seen.nearest) << "cycle " << c << ": velocity tracks differ from the expert's";
    double worst = 0.0;
    for (int k = 0; k < basis.steps; ++k) {
      const Eigen::Vector2d planned(basis.P.row(k).dot(r.expert_xi.head(n)), basis.P.row(k).dot(r.expert_xi.tail(n)));
      worst = std::max(worst, (planned - (call.output.plan[static_cast<std::size_t>(k)] - call.input.robot_position))
                                  .cwiseAbs()
                                  .maxCoeff());
    }
    EXPECT_LT(worst, 1e-9) << "cycle " << c;
    // The cost is the expert's own, and what the ranking makes of the plan with the scan.
    EXPECT_EQ(r.expert_cost, call.record.terms.total) << "cycle " << c;
    const int distinct = std::min<int>(seen.voxels, static_cast<int>(seen.cloud.rows()));
    const int near = std::min<int>(distinct, static_cast<int>(seen.nearest.rows()));
    planners::PointRows occluders(distinct, 4);
    occluders.topRows(near) = seen.nearest.topRows(near);
    for (int i = near; i < distinct; ++i) occluders.row(i) << seen.cloud(i, 0), seen.cloud(i, 1), 0, 0;
    Eigen::Vector4d target;
    target << call.input.target_position - call.input.robot_position, call.input.target_velocity;
    const planners::RankingTerms terms = ranking.evaluate(r.expert_xi, target, seen.nearest, occluders, &call.scan);
    EXPECT_NEAR(r.expert_cost, terms.total, 1e-9 * std::max(1.0, std::abs(terms.total))) << "cycle " << c;
    EXPECT_TRUE(std::isfinite(r.expert_cost));
    EXPECT_GE(r.expert_cost, 0.0);
  }
  EXPECT_EQ(row, recorder.rows().size());
}

}  // namespace

TEST(Demonstrations, RowsHoldWhatTheDrivingExpertSawAndPlanned) {
  planners::ProjCemSettings expert = tiny().expert;
  auto spy = std::make_unique<Spy>(expert);
  Spy* log = spy.get();
  sim::DemonstrationRecorder recorder(std::move(spy), nullptr, 2);
  sim::run_episode(orbit(2.0), recorder, {});
  ASSERT_EQ(log->calls.size(), 40u) << "the driving expert runs once per cycle";
  EXPECT_EQ(recorder.report().labelled, 20);
  EXPECT_EQ(recorder.report().rows, 20);
  EXPECT_EQ(recorder.report().skipped(), 0);
  EXPECT_EQ(recorder.name(), "spy");
  expect_rows_match_calls(recorder, log->calls, expert, 2, true);
}

TEST(Demonstrations, AnotherDriverDrivesWhileTheExpertLabelsEveryThirdCycle) {
  planners::ProjCemSettings expert = tiny().expert;
  auto spy = std::make_unique<Spy>(expert);
  Spy* log = spy.get();
  sim::DemonstrationRecorder recorder(std::move(spy), planners::make_planner("follower"), 3);
  const sim::EpisodeResult result = sim::run_episode(orbit(2.0), recorder, {});
  EXPECT_EQ(result.metrics.planner, "follower");
  ASSERT_EQ(log->calls.size(), 14u) << "cycles 0, 3, ..., 39";
  for (std::size_t c = 0; c < log->calls.size(); ++c) EXPECT_DOUBLE_EQ(log->calls[c].input.time, 0.15 * c);
  EXPECT_EQ(recorder.report().cycles, 40);
  EXPECT_EQ(recorder.report().rows, 14);
  expect_rows_match_calls(recorder, log->calls, expert, 3, false);
}

TEST(Demonstrations, GeneratedFileReadsBackWithTheContractsShapesAndMetadata) {
  const sim::DemonstrationSettings settings = tiny();
  sim::DemonstrationReport report;
  const sim::Demonstrations data = sim::generate_demonstrations(settings, &report);
  EXPECT_EQ(report.episodes, 2);
  EXPECT_EQ(report.episodes_failed, 0);
  EXPECT_EQ(report.cycles, 120);  // 2 x 3 s at 20 Hz
  EXPECT_EQ(report.rows + report.skipped(), report.labelled);
  EXPECT_EQ(report.labelled, 120);
  ASSERT_GT(report.rows, 100);

  const std::string path = test::temp_path("demo.safetensors");
  io::write_dataset_file(path, data);
  const io::TensorFile file = io::read_safetensors(path);
  const std::int64_t S = report.rows;
  EXPECT_EQ(file.at("observation", {S, 6}).dtype, io::DType::F32);
  EXPECT_EQ(file.at("cloud", {S, 200, 2}).dtype, io::DType::F32);
  EXPECT_EQ(file.at("obstacles", {S, 60, 4}).dtype, io::DType::F32);
  EXPECT_EQ(file.at("expert_xi", {S, 22}).dtype, io::DType::F32);
  EXPECT_EQ(file.at("expert_cost", {S}).dtype, io::DType::F32);
  EXPECT_EQ(file.at("episode", {S}).dtype, io::DType::I32);
  EXPECT_EQ(file.at("time", {S}).dtype, io::DType::F32);
  EXPECT_EQ(file.tensors.size(), 7u);
  EXPECT_EQ(file.meta("format"), "occtrack.dataset.v1");
  EXPECT_EQ(file.meta("rows"), std::to_string(S));
  EXPECT_EQ(file.meta("driver"), "expert");
  EXPECT_EQ(file.meta("created_by"), "test_demonstrations");
  const auto projection = nlohmann::json::parse(file.meta("projection"));
  EXPECT_EQ(projection.at("degree"), 10);
  EXPECT_EQ(projection.at("steps"), 100);
  EXPECT_EQ(projection.at("iterations"), 20);
  EXPECT_EQ(projection.at("via_steps"), nlohmann::json({49, 74}));
  for (const char* key : {"horizon", "obstacle_radius", "speed_min", "speed_max", "accel_max", "rho"})
    EXPECT_TRUE(projection.contains(key)) << key;
  const auto perception = nlohmann::json::parse(file.meta("perception"));
  EXPECT_EQ(perception.at("cloud_size"), 200);
  EXPECT_EQ(perception.at("nearest_count"), 60);
  EXPECT_EQ(perception.at("estimate_velocity"), true);
  EXPECT_DOUBLE_EQ(perception.at("voxel_size").get<double>(), 0.19);
  const auto expert = nlohmann::json::parse(file.meta("expert"));
  EXPECT_EQ(expert.at("samples"), 64);
  EXPECT_EQ(expert.at("cem_iterations"), 1);
  const auto generator = nlohmann::json::parse(file.meta("generator"));
  EXPECT_EQ(generator.at("world_kinds"), nlohmann::json({"forest", "dynamic"}));
  EXPECT_EQ(generator.at("first_seed"), 5000);
  EXPECT_EQ(generator.at("episodes"), 2);
  EXPECT_EQ(generator.at("duration"), 3.0);
  EXPECT_FALSE(generator.contains("jobs"));
  EXPECT_FALSE(generator.contains("scenarios"));  // named only when given: generated files keep their bytes

  const sim::Demonstrations back = io::read_dataset_file(path);
  EXPECT_EQ(back.rows, S);
  EXPECT_EQ(back.observation, data.observation);
  EXPECT_EQ(back.cloud, data.cloud);
  EXPECT_EQ(back.obstacles, data.obstacles);
  EXPECT_EQ(back.expert_xi, data.expert_xi);
  EXPECT_EQ(back.expert_cost, data.expert_cost);
  EXPECT_EQ(back.episode, data.episode);
  EXPECT_EQ(back.time, data.time);
  // Rows ordered by episode, both episodes present, each starting at t = 0.
  EXPECT_TRUE(std::is_sorted(back.episode.begin(), back.episode.end()));
  EXPECT_EQ(back.episode.front(), 0);
  EXPECT_EQ(back.episode.back(), 1);
  EXPECT_EQ(back.time.front(), 0.0f);
  for (float t : back.time) EXPECT_TRUE(t >= 0.0f && t < 3.0f);
  // The relative target is about 2 m away at the start (the generator's robot_distance).
  EXPECT_NEAR(std::hypot(back.observation[2], back.observation[3]), 2.0, 0.6);

  const io::DatasetStatistics stats = io::dataset_statistics(back);
  EXPECT_EQ(stats.episodes, 2);
  EXPECT_GT(stats.plan_speed_mean, 0.0);
  // Plausible speeds, not garbage: the projection's speed bound (2 m/s) is a penalty, not a hard limit, and
  // this test's small expert (few samples, one CEM iteration) picks among few plans, so allow 50% over it.
  EXPECT_LE(stats.plan_speed_max, 2.0 * 1.5);
  std::filesystem::remove(path);
}

TEST(Demonstrations, GivenScenariosAreDrivenInTurnForAtMostTheDuration) {
  sim::DemonstrationSettings settings = tiny();
  core::Scenario short_one = orbit(1.0), long_one = orbit(10.0);
  short_one.name = "short";
  long_one.name = "long";
  long_one.robot_position = {-4.0, 1.0};
  settings.scenarios = {short_one, long_one};
  settings.episodes = 3;  // the third is the short one again, with its own seed
  settings.duration = 2.0;
  sim::DemonstrationReport report;
  const sim::Demonstrations data = sim::generate_demonstrations(settings, &report);
  EXPECT_EQ(report.episodes, 3);
  EXPECT_EQ(report.cycles, 20 + 40 + 20);  // 1 s, 2 s (of 10) and 1 s at 20 Hz
  std::vector<int> first_row(3, -1);
  for (std::int64_t r = 0; r < data.rows; ++r) {
    const int e = data.episode[static_cast<std::size_t>(r)];
    ASSERT_GE(e, 0);
    ASSERT_LT(e, 3);
    if (first_row[static_cast<std::size_t>(e)] < 0) first_row[static_cast<std::size_t>(e)] = static_cast<int>(r);
  }
  // The first row's target, seen from the robot's start: the scenario's, up to the noise-free estimate.
  const auto target_seen = [&](int e) {
    const std::size_t r = static_cast<std::size_t>(first_row[static_cast<std::size_t>(e)]);
    return Eigen::Vector2d(data.observation[6 * r + 2], data.observation[6 * r + 3]);
  };
  EXPECT_TRUE(target_seen(0).isApprox(Eigen::Vector2d(2.0, 0.0), 1e-6));   // (-2, -1) from (-4, -1)
  EXPECT_TRUE(target_seen(1).isApprox(Eigen::Vector2d(2.0, -2.0), 1e-6));  // from (-4, 1)
  EXPECT_TRUE(target_seen(2).isApprox(Eigen::Vector2d(2.0, 0.0), 1e-6));
  const auto generator = nlohmann::json::parse(data.metadata.at("generator"));
  EXPECT_EQ(generator.at("scenarios"), nlohmann::json({"short", "long"}));
  for (const char* unused : {"world_kinds", "target", "target_speeds"})
    EXPECT_FALSE(generator.contains(unused)) << unused << ": the generated worlds' settings, unused";
  // A scenario without a target path is refused by name.
  settings.scenarios[1].target.clear();
  std::string error;
  EXPECT_FALSE(settings.validate(&error));
  EXPECT_EQ(error, "scenarios: 'long' has no target path or no duration");
}

TEST(Demonstrations, OnlyALearnedDriverMakesADaggerRound) {
  // The `driver` metadata as demonstration_metadata writes it: the expert, a planner's name, or the model file
  // of a learned driver given one.
  const auto with = [](const std::string& driver) { return std::map<std::string, std::string>{{"driver", driver}}; };
  EXPECT_FALSE(sim::learned_driver(with("expert")));
  EXPECT_FALSE(sim::learned_driver(with("projcem")));
  EXPECT_FALSE(sim::learned_driver(with("follower")));
  EXPECT_TRUE(sim::learned_driver(with("cvae")));
  EXPECT_TRUE(sim::learned_driver(with("cvae-fixed-q")));
  EXPECT_TRUE(sim::learned_driver(with("build-data/dagger/cvae-r0.safetensors")));
  EXPECT_FALSE(sim::learned_driver({}));
  sim::DemonstrationSettings s;
  s.driver = "cvae";
  s.model = "round0/cvae.safetensors";
  EXPECT_TRUE(sim::learned_driver(sim::demonstration_metadata(s)));
  s.driver = "expert";
  s.model.clear();
  EXPECT_FALSE(sim::learned_driver(sim::demonstration_metadata(s)));
}

TEST(Demonstrations, SameSeedGivesIdenticalBytesWhateverTheJobs) {
  sim::DemonstrationSettings settings = tiny();
  settings.duration = 1.5;
  settings.label_every = 2;
  const auto one = io::serialize_safetensors(io::to_tensor_file(sim::generate_demonstrations(settings)));
  settings.jobs = 2;
  const auto two = io::serialize_safetensors(io::to_tensor_file(sim::generate_demonstrations(settings)));
  EXPECT_TRUE(one == two) << "jobs 1 and 2 differ";
  settings.first_seed = 6000;
  const auto other = io::serialize_safetensors(io::to_tensor_file(sim::generate_demonstrations(settings)));
  EXPECT_FALSE(one == other) << "another seed should make other worlds";
}

/// Shard k of `shards` of the run `s` (what rank k computes under MPI).
sim::Demonstrations shard_of(sim::DemonstrationSettings s, int k, int shards, sim::DemonstrationReport* report) {
  s.shard = k;
  s.shards = shards;
  return sim::generate_demonstrations(s, report);
}

TEST(Demonstrations, ShardsInterleavedAreTheOneProcessRunToTheByte) {
  sim::DemonstrationSettings settings = tiny();
  settings.episodes = 4;
  settings.duration = 1.5;
  settings.label_every = 2;
  settings.worlds = {sim::DemonstrationWorld::forest, sim::DemonstrationWorld::boxes};
  sim::DemonstrationReport whole_report;
  const sim::Demonstrations whole = sim::generate_demonstrations(settings, &whole_report);
  const auto whole_bytes = io::serialize_safetensors(io::to_tensor_file(whole));
  ASSERT_EQ(whole_report.episodes, 4);
  ASSERT_GT(whole.rows, 0);
  // 2 shards; 3 (4 episodes do not divide); 5 (the last shard has no episode).
  for (const int shards : {2, 3, 5}) {
    SCOPED_TRACE(std::to_string(shards) + " shards");
    std::vector<sim::Demonstrations> parts;
    sim::DemonstrationReport report;
    for (int k = 0; k < shards; ++k) {
      sim::DemonstrationReport part_report;
      parts.push_back(shard_of(settings, k, shards, &part_report));
      const sim::Demonstrations& part = parts.back();
      // Its own episodes, by their index in the whole run, and its own row count.
      EXPECT_EQ(part_report.episodes, k < 4 ? 1 + (3 - k) / shards : 0) << "shard " << k;
      for (const std::int32_t e : part.episode) EXPECT_EQ(e % shards, k) << "shard " << k;
      EXPECT_EQ(part.metadata.at("rows"), std::to_string(part.rows));
      report.add(part_report);
    }
    const sim::Demonstrations merged = sim::interleave_demonstration_shards(parts);
    EXPECT_EQ(merged.rows, whole.rows);
    EXPECT_EQ(merged.cloud_points, whole.cloud_points);
    EXPECT_EQ(merged.nearest_points, whole.nearest_points);
    EXPECT_EQ(merged.coefficients, whole.coefficients);
    EXPECT_TRUE(merged.observation == whole.observation);
    EXPECT_TRUE(merged.cloud == whole.cloud);
    EXPECT_TRUE(merged.obstacles == whole.obstacles);
    EXPECT_TRUE(merged.expert_xi == whole.expert_xi);
    EXPECT_TRUE(merged.expert_cost == whole.expert_cost);
    EXPECT_EQ(merged.episode, whole.episode);
    EXPECT_TRUE(merged.time == whole.time);
    EXPECT_EQ(merged.metadata, whole.metadata);
    EXPECT_TRUE(io::serialize_safetensors(io::to_tensor_file(merged)) == whole_bytes);
    // The shards' reports add up to the run's.
    EXPECT_EQ(report.episodes, whole_report.episodes);
    EXPECT_EQ(report.episodes_failed, whole_report.episodes_failed);
    EXPECT_EQ(report.failures, whole_report.failures);
    EXPECT_EQ(report.cycles, whole_report.cycles);
    EXPECT_EQ(report.labelled, whole_report.labelled);
    EXPECT_EQ(report.rows, whole_report.rows);
    EXPECT_EQ(report.skipped(), whole_report.skipped());
  }
}

TEST(Demonstrations, InterleavingRefusesPartsOfDifferentRunsNamingThePart) {
  sim::DemonstrationSettings settings = tiny();
  settings.episodes = 2;
  settings.duration = 0.5;
  const sim::Demonstrations first = shard_of(settings, 0, 2, nullptr);
  const sim::Demonstrations second = shard_of(settings, 1, 2, nullptr);
  ASSERT_GT(first.rows, 0);
  ASSERT_GT(second.rows, 0);
  const auto expect_refused = [](std::vector<sim::Demonstrations> parts, const std::string& says) {
    try {
      sim::interleave_demonstration_shards(std::move(parts));
      ADD_FAILURE() << "accepted; expected: " << says;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  expect_refused({}, "no part");
  expect_refused({first, first}, "episode 0 is in parts 0 and 1");
  sim::Demonstrations other = second;
  other.metadata["generator"] = "{}";
  expect_refused({first, other}, "part 1: metadata 'generator' differs");
  other = second;
  other.nearest_points = 30;
  expect_refused({first, other}, "part 1: sizes");
  other = second;
  other.time.pop_back();
  expect_refused({first, other}, "part 1: a column");
  // A part out of episode order: the second shard's rows, then the first's.
  other = second;
  io::append_rows(other, first, 0);
  expect_refused({other}, "part 0 is not ordered by episode");
}

TEST(Demonstrations, V2EpisodesInThePaperWorldsWithTeleopTargetsLatencyAndAShieldedDriver) {
  sim::DemonstrationSettings s = tiny();
  s.episodes = 4;
  s.duration = 2.0;
  s.worlds = {sim::DemonstrationWorld::sixwall, sim::DemonstrationWorld::sixwall_sliding,
              sim::DemonstrationWorld::random, sim::DemonstrationWorld::clutter_dynamic};
  s.target_speeds = {2.5};
  s.target = sim::DemonstrationTarget::teleop;
  s.episode.latency_ms = 20.0;
  s.episode.tau = 0.25;
  s.episode.beams = 360;
  s.episode.lidar_noise = 0.01;
  s.episode.target_position_noise = 0.05;
  s.episode.target_velocity_noise = 0.1;
  s.driver = "follower";
  s.driver_options.shield = true;
  s.driver_options.response_time = 0.25;
  s.driver_options.latency = 0.02;
  sim::DemonstrationReport report;
  const sim::Demonstrations data = sim::generate_demonstrations(s, &report);
  EXPECT_EQ(report.episodes, 4);
  EXPECT_EQ(report.episodes_failed, 0) << (report.failures.empty() ? "" : report.failures.front());
  EXPECT_EQ(report.cycles, 4 * 40);  // a 20 ms latency is under the 50 ms period: no cycle is skipped
  EXPECT_EQ(report.labelled, 4 * 40);
  EXPECT_GT(report.rows, 4 * 35);
  const auto generator = nlohmann::json::parse(data.metadata.at("generator"));
  EXPECT_EQ(generator.at("world_kinds"),
            nlohmann::json({"sixwall", "sixwall-sliding", "random", "clutter-dynamic"}));
  EXPECT_EQ(generator.at("target"), "teleop");
  EXPECT_EQ(generator.at("latency_ms"), 20.0);
  EXPECT_EQ(generator.at("tau"), 0.25);
  EXPECT_EQ(generator.at("beams"), 360);
  EXPECT_EQ(generator.at("target_noise"), nlohmann::json({0.05, 0.1}));
  EXPECT_EQ(generator.at("driver_shield"), true);
  EXPECT_EQ(data.metadata.at("driver"), "follower");

  // A tele-operated target is not the smooth one: the same seed and forest world give other rows.
  sim::DemonstrationSettings forest = tiny();
  forest.episodes = 1;
  forest.duration = 1.0;
  forest.worlds = {sim::DemonstrationWorld::forest};
  const sim::Demonstrations smooth_rows = sim::generate_demonstrations(forest);
  forest.target = sim::DemonstrationTarget::teleop;
  const sim::Demonstrations teleop_rows = sim::generate_demonstrations(forest);
  ASSERT_GT(smooth_rows.rows, 0);
  ASSERT_GT(teleop_rows.rows, 0);
  EXPECT_NE(smooth_rows.observation, teleop_rows.observation);
  // With a tele-operated target, `dynamic` keeps dynamic-1.5ms's world (obstacles at 0.7 m/s) and
  // `clutter-dynamic` is clutter-dynamic-2ms's (1 m/s): the same seed, two worlds.
  forest.worlds = {sim::DemonstrationWorld::dynamic};
  const sim::Demonstrations slow_rows = sim::generate_demonstrations(forest);
  forest.worlds = {sim::DemonstrationWorld::clutter_dynamic};
  const sim::Demonstrations fast_rows = sim::generate_demonstrations(forest);
  ASSERT_GT(slow_rows.rows, 0);
  ASSERT_GT(fast_rows.rows, 0);
  EXPECT_NE(slow_rows.obstacles, fast_rows.obstacles);

  for (auto world : {sim::DemonstrationWorld::forest, sim::DemonstrationWorld::clutter_dynamic,
                     sim::DemonstrationWorld::sixwall_sliding, sim::DemonstrationWorld::random})
    EXPECT_EQ(sim::parse_demonstration_world(sim::to_string(world)), world);
  EXPECT_EQ(sim::parse_demonstration_target("teleop"), sim::DemonstrationTarget::teleop);
  EXPECT_FALSE(sim::parse_demonstration_target("wild"));
  EXPECT_FALSE(sim::parse_demonstration_world("sixwall_sliding"));
}

TEST(Demonstrations, BenchmarkSeedsAreRefusedWithTheSeedRange) {
  sim::DemonstrationSettings s = tiny();
  std::string error;
  for (auto [first, episodes] : {std::pair<std::uint64_t, int>{1000, 1}, {1999, 1}, {1500, 3}, {990, 20}}) {
    s.first_seed = first;
    s.episodes = episodes;
    EXPECT_FALSE(s.validate(&error)) << first << " + " << episodes;
    EXPECT_NE(error.find("first_seed"), std::string::npos) << error;
    EXPECT_NE(error.find("1000-1999"), std::string::npos) << error;
  }
  s.first_seed = 990;
  s.episodes = 20;
  try {
    sim::generate_demonstrations(s);
    ADD_FAILURE() << "benchmark seeds accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("1000-1999"), std::string::npos) << e.what();
  }
  for (auto [first, episodes] : {std::pair<std::uint64_t, int>{980, 20}, {2000, 5}, {0, 1000}}) {
    s.first_seed = first;
    s.episodes = episodes;
    EXPECT_TRUE(s.validate(&error)) << error;
  }
}

TEST(Demonstrations, BadSettingsAreNamed) {
  const auto expect_refused = [](const sim::DemonstrationSettings& s, const std::string& field) {
    std::string error;
    EXPECT_FALSE(s.validate(&error)) << field;
    EXPECT_EQ(error.rfind(field, 0), 0u) << "expected the message to start with " << field << ": " << error;
  };
  sim::DemonstrationSettings s = tiny();
  EXPECT_TRUE(s.validate());
  s.episodes = 0;
  expect_refused(s, "episodes");
  s = tiny();
  s.worlds.clear();
  expect_refused(s, "worlds");
  s = tiny();
  s.target_speeds = {1.0, -1.0};
  expect_refused(s, "target_speeds");
  s = tiny();
  s.duration = 0.0;
  expect_refused(s, "duration");
  s = tiny();
  s.label_every = 0;
  expect_refused(s, "label_every");
  s = tiny();
  s.jobs = 0;
  expect_refused(s, "jobs");
  s = tiny();
  s.shards = 2;
  s.shard = 2;
  expect_refused(s, "shard");
  s.shard = 0;
  s.shards = 0;
  expect_refused(s, "shard");
  s = tiny();
  s.expert.samples = 2;
  expect_refused(s, "expert.samples");
  s = tiny();
  s.expert.cem_iterations = 0;
  expect_refused(s, "expert.cem_iterations");
  s = tiny();
  s.expert.perception.nearest_count = 30;
  expect_refused(s, "expert.perception.nearest_count");
  s = tiny();
  s.driver = "projcem";
  s.label_every = 20;  // 1 s between the expert's scans: its velocity tracks would never last
  expect_refused(s, "label_every");
  s = tiny();
  s.episode.latency_ms = 50.0;  // a whole planning period: cycles would be skipped, labels would drift
  expect_refused(s, "episode.latency_ms");
  s = tiny();
  s.driver = "no-such-planner";
  try {
    sim::generate_demonstrations(s);
    ADD_FAILURE() << "unknown driver accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-planner"), std::string::npos) << e.what();
  }
}

TEST(Demonstrations, ReaderRefusesFilesThatBreakTheContractNamingFileAndTensor) {
  sim::Demonstrations d;
  d.rows = 2;
  d.cloud_points = 3;
  d.nearest_points = 2;
  d.coefficients = 11;
  d.observation.assign(12, 0.5f);
  d.cloud.assign(12, 1.0f);
  d.obstacles.assign(16, 0.0f);
  d.expert_xi.assign(44, 0.25f);
  d.expert_cost = {1.0f, 2.0f};
  d.episode = {0, 0};
  d.time = {0.0f, 0.05f};
  sim::DemonstrationSettings s;
  s.expert.perception.cloud_size = 3;
  s.expert.perception.nearest_count = 2;
  d.metadata = sim::demonstration_metadata(s);
  const std::string path = test::temp_path("contract.safetensors");
  io::write_dataset_file(path, d);
  EXPECT_EQ(io::read_dataset_file(path).episode, d.episode);

  const auto expect_refused = [&](const io::TensorFile& file, const std::string& what) {
    io::write_safetensors(path, file);
    try {
      io::read_dataset_file(path);
      ADD_FAILURE() << "accepted a file with " << what;
    } catch (const io::InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
    }
  };
  io::TensorFile file = io::to_tensor_file(d);
  file.metadata["format"] = "occtrack.model.v1";
  expect_refused(file, "format");
  file = io::to_tensor_file(d);
  file.tensors.erase("cloud");
  expect_refused(file, "cloud");
  file = io::to_tensor_file(d);
  file.put("obstacles", {2, 3, 4}, std::vector<float>(24, 0.0f));  // 3 points, the metadata says 2
  expect_refused(file, "obstacles");
  file = io::to_tensor_file(d);
  file.put("episode", {2}, std::vector<float>{0.0f, 0.0f});
  expect_refused(file, "episode");
  file = io::to_tensor_file(d);
  file.put("expert_xi", {2, 20}, std::vector<float>(40, 0.0f));
  expect_refused(file, "expert_xi");
  file = io::to_tensor_file(d);
  file.metadata["rows"] = "3";
  expect_refused(file, "observation");
  file = io::to_tensor_file(d);
  file.metadata["perception"] = "{not json";
  expect_refused(file, "perception");
  file = io::to_tensor_file(d);
  file.put("expert_cost", {2}, std::vector<float>{1.0f, NAN});
  expect_refused(file, "expert_cost");
  std::filesystem::remove(path);

  // Appending renumbers episodes and refuses other sizes.
  sim::Demonstrations merged;
  io::append_dataset(merged, d);
  io::append_dataset(merged, d);
  EXPECT_EQ(merged.rows, 4);
  EXPECT_EQ(merged.episode, (std::vector<std::int32_t>{0, 0, 1, 1}));
  EXPECT_EQ(merged.metadata.at("rows"), "4");
  EXPECT_NO_THROW(io::to_tensor_file(merged));
  sim::Demonstrations other = d;
  other.metadata["projection"] = "{}";
  EXPECT_THROW(io::append_dataset(merged, other), std::invalid_argument);
}
