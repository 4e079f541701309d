// The planning cycle's memory contracts, counted (allocation_counter.hpp: every operator new and malloc,
// freed or not) on the scans of short closed-loop episodes of the shipped smoke scenarios:
//   - Perception::process allocates nothing after its first scan (perception.hpp, "Memory");
//   - Model::features and Model::decode allocate nothing within the reserved sizes (model.hpp, "Memory");
//   - World::scan into a sized Scan allocates nothing (world.hpp);
//   - Planner::plan(input, out) of LearnedPolicy (cvae, cvae-fixed-q, bc), ProjCem and the follower, given
//     the same `out` every cycle, allocates nothing after the first cycle, holds (brakes) in between
//     included, all but the first (planner.hpp; PlannerOutput::resize_candidates);
//   - Tracker::step, the robots' API, allocates nothing after its first cycle (tracker.hpp), stop cycles
//     included from the first.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <filesystem>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "allocation_counter.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/learned.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/tracker.hpp"
#include "occtrack/policy/model.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/world.hpp"

using namespace occtrack;
using test::AllocationCount;

namespace {

const char* const kScenarios[] = {OCCTRACK_SCENARIO_DIR "/static-1ms-smoke/forest-a-1.yaml",
                                  OCCTRACK_SCENARIO_DIR "/dynamic-1.5ms-smoke/dynamic-a-1.yaml"};
constexpr double kEpisodeSeconds = 3.0;  // 60 planning cycles at 20 Hz

core::Scenario short_scenario(const std::string& path) {
  core::Scenario scenario = io::read_scenario(path);
  scenario.duration = kEpisodeSeconds;
  return scenario;
}

// What a planner saw in a closed-loop episode (the follower driving): the inputs, each with its own scan.
struct Recording {
  std::vector<core::Scan> scans;
  std::vector<planners::PlannerInput> inputs;  // .scan points into scans
};

class Recorder final : public planners::Planner {
 public:
  explicit Recorder(Recording& recording) : recording_(recording) {}
  std::string name() const override { return "recorder"; }
  void reset() override { follower_.reset(); }
  using Planner::plan;
  void plan(const planners::PlannerInput& input, planners::PlannerOutput& out) override {
    recording_.scans.push_back(*input.scan);
    recording_.inputs.push_back(input);
    follower_.plan(input, out);
  }
  const planners::PlanRecord& last_record() const override { return follower_.last_record(); }

 private:
  Recording& recording_;
  planners::Follower follower_;
};

Recording record(const std::string& scenario_path) {
  Recording r;
  Recorder recorder(r);
  sim::run_episode(short_scenario(scenario_path), recorder, sim::EpisodeSettings{});
  for (std::size_t k = 0; k < r.inputs.size(); ++k) r.inputs[k].scan = &r.scans[k];
  return r;
}

// "cycle 3: 2, cycle 7: 1" for the cycles whose count is not zero (empty when all are).
std::string nonzero(const std::vector<long>& counts, std::size_t first_cycle = 0) {
  std::ostringstream out;
  for (std::size_t k = 0; k < counts.size(); ++k)
    if (counts[k] != 0) out << (out.tellp() > 0 ? ", " : "") << "cycle " << first_cycle + k << ": " << counts[k];
  return out.str();
}

}  // namespace

namespace {
// Keeps an allocation observable, so that the compiler may not elide it (C++14 allows eliding new-expressions).
void keep(const void* p) { asm volatile("" : : "g"(p) : "memory"); }
}  // namespace

// The witness itself: what it must see, and that it sees nothing before its region or outside it.
TEST(AllocationCount, CountsEachAllocationInItsRegion) {
  std::vector<int> before(10);
  keep(before.data());
  {
    AllocationCount count;
    EXPECT_EQ(count.allocations(), 0) << "an allocation made before the region";
    std::vector<int> deliberate(10);
    keep(deliberate.data());
    EXPECT_EQ(count.allocations(), 1);
  }
  {
    AllocationCount count;
    // Eigen allocates with malloc, not operator new: the count must see that too.
    Eigen::MatrixXd m(50, 50);
    keep(m.data());
    const long eigen = count.allocations();
    auto p = std::make_unique<int>(3);
    keep(p.get());
    EXPECT_EQ(eigen, 1);
    EXPECT_EQ(count.allocations(), 2);
  }
  {
    AllocationCount count;
    before.assign(10, 1);  // reuses its storage
    EXPECT_EQ(count.allocations(), 0);
  }
}

TEST(AllocationCount, AnAllocationFreedInsideTheRegionStillCounts) {
  AllocationCount count;
  {
    std::string temporary(100, 'x');  // a heap-size comparison before and after would see no change
    keep(temporary.data());
  }
  EXPECT_EQ(count.allocations(), 1);
}

TEST(AllocationCount, WorldScanIntoASizedScanDoesNotAllocate) {
  for (const char* path : kScenarios) {
    const core::Scenario scenario = short_scenario(path);
    sim::World world(scenario);
    std::mt19937_64 rng(3);
    core::Scan scan;
    world.scan(scenario.robot_position, 0.0, rng, scan);
    std::vector<long> counts;
    for (int k = 1; k <= 40; ++k) {
      const core::Vec2 position = scenario.robot_position + core::Vec2(0.05 * k, -0.03 * k);
      AllocationCount count;
      world.scan(position, 0.05 * k, rng, scan);
      counts.push_back(count.allocations());
    }
    EXPECT_EQ(nonzero(counts, 1), "") << path;
  }
}

TEST(AllocationCount, PerceptionProcessDoesNotAllocateAfterTheFirstScan) {
  for (const char* path : kScenarios) {
    const Recording recording = record(path);
    ASSERT_GE(recording.inputs.size(), 50u);
    for (const bool velocity : {false, true}) {
      perception::Settings settings;
      settings.estimate_velocity = velocity;
      perception::Perception perception(settings);
      perception::Observation out;
      ASSERT_TRUE(perception.process(recording.scans[0], recording.inputs[0].robot_position, out));
      std::vector<long> counts;
      int failures = 0, clusters = 0;
      for (std::size_t k = 1; k < recording.inputs.size(); ++k) {
        AllocationCount count;
        const bool ok = perception.process(recording.scans[k], recording.inputs[k].robot_position, out);
        counts.push_back(count.allocations());
        failures += !ok;
        clusters = std::max(clusters, out.clusters);
      }
      EXPECT_EQ(failures, 0);
      EXPECT_EQ(nonzero(counts, 1), "") << path << ", estimate_velocity " << velocity;
      if (velocity) {
        EXPECT_GT(clusters, 0) << "the tracking path ran";
      }
      // The other half of the contract, and the count's witness: a scan with more beams than any before
      // grows the buffers.
      core::Scan finer = recording.scans.back();
      finer.ranges.resize(2 * finer.ranges.size(), finer.range_max / 2);
      finer.angle_increment /= 2;
      finer.time += 0.05;
      AllocationCount count;
      EXPECT_TRUE(perception.process(finer, recording.inputs.back().robot_position, out));
      EXPECT_GT(count.allocations(), 0) << path << ", twice the beams";
    }
  }
}

namespace {

// The shipped models are part of the repository: a missing one is an error (Model::load throws), not a skip.
std::unique_ptr<policy::Model> shipped_model(const char* variant) {
  return std::make_unique<policy::Model>(
      policy::Model::load(std::string(OCCTRACK_MODEL_DIR) + "/" + variant + ".safetensors"));
}

// The clouds and observations of a recording, as the learned planner hands them to the networks.
struct NetworkInputs {
  std::vector<policy::Cloud> clouds;  // the distinct points only (1..C rows)
  std::vector<Eigen::VectorXf> observations;
};

NetworkInputs network_inputs(const Recording& recording, int cloud_size) {
  perception::Settings settings = perception::Settings::tracking();
  settings.cloud_size = cloud_size;
  perception::Perception perception(settings);
  NetworkInputs in;
  for (const planners::PlannerInput& input : recording.inputs) {
    perception::Observation o;
    if (!perception.process(*input.scan, input.robot_position, o)) continue;
    const Eigen::Index distinct = std::clamp<Eigen::Index>(o.voxels, 1, o.cloud.rows());
    in.clouds.push_back(o.cloud.topRows(distinct).cast<float>());
    Eigen::VectorXf observation(6);
    const core::Vec2 target = input.target_position - input.robot_position;
    observation << float(input.robot_velocity.x()), float(input.robot_velocity.y()), float(target.x()),
        float(target.y()), float(input.target_velocity.x()), float(input.target_velocity.y());
    in.observations.push_back(observation);
  }
  return in;
}

}  // namespace

TEST(AllocationCount, ModelFeaturesAndDecodeDoNotAllocateWithinTheReservedSizes) {
  std::unique_ptr<policy::Model> model = shipped_model("cvae");
  const policy::NetworkConfig& net = model->network();
  const int batch = 30;
  model->reserve(batch, net.cloud_points);
  for (const char* path : kScenarios) {
    const NetworkInputs in = network_inputs(record(path), net.cloud_points);
    ASSERT_GE(in.clouds.size(), 50u);
    std::mt19937_64 rng(5);
    std::normal_distribution<float> normal;
    policy::Rows z(batch, net.latent), outputs(batch, net.outputs);
    Eigen::VectorXf features(net.features);
    // Warm-up: one call of each.
    model->features(in.clouds[0], features);
    model->decode(z.setZero(), in.observations[0], features, outputs);

    std::vector<long> feature_counts, decode_counts;
    for (std::size_t k = 0; k < in.clouds.size(); ++k) {
      for (Eigen::Index i = 0; i < z.size(); ++i) z.data()[i] = normal(rng);
      const int samples = k % 3 == 0 ? 5 : batch;  // fewer samples than reserved too
      {
        AllocationCount count;
        model->features(in.clouds[k], features);
        feature_counts.push_back(count.allocations());
      }
      {
        AllocationCount count;
        model->decode(z.topRows(samples), in.observations[k], features, outputs.topRows(samples));
        decode_counts.push_back(count.allocations());
      }
      ASSERT_TRUE(outputs.topRows(samples).allFinite()) << "cycle " << k;
    }
    EXPECT_EQ(nonzero(feature_counts), "") << path << ": features";
    EXPECT_EQ(nonzero(decode_counts), "") << path << ": decode";
  }
}

// The contract's other half (model.hpp): past the reserve the workspaces grow, once. This also shows that the
// count sees the networks' allocations.
TEST(AllocationCount, ModelWorkspacesGrowOncePastTheReserve) {
  std::unique_ptr<policy::Model> model = shipped_model("cvae");
  const policy::NetworkConfig& net = model->network();
  const int batch = 45, points = net.cloud_points + 50;  // the constructor reserved 30 and cloud_points
  const policy::Cloud cloud = policy::Cloud::Random(points, 2) * 4.0f;
  Eigen::VectorXf features(net.features), observation = Eigen::VectorXf::Zero(net.observation);
  const policy::Rows z = policy::Rows::Random(batch, net.latent);
  policy::Rows outputs(batch, net.outputs);
  std::vector<long> counts;
  for (int k = 0; k < 3; ++k) {
    AllocationCount count;
    model->features(cloud, features);
    model->decode(z, observation, features, outputs);
    counts.push_back(count.allocations());
  }
  EXPECT_GT(counts[0], 0) << points << " points and " << batch << " samples exceed the reserve";
  EXPECT_EQ(counts[1], 0);
  EXPECT_EQ(counts[2], 0);
}

namespace {

constexpr std::size_t kPlannerWarmUp = 1;  // the first cycle sizes the output (plan, candidates)
// Cycles whose target was never observed (target_age infinite): the planner holds still, with no candidates
// (detail::brake). The first hold may size the output's message; the second hold, and the cycles after it,
// must not allocate.
constexpr std::size_t kHoldCycle = 20;
constexpr std::size_t kHoldCycles = 2;

// Replays each scenario's recording through the planner (reset first), into one reused output, with holds
// from kHoldCycle: the allocations of each cycle after warm-up but the first hold, "" when there are none,
// else "SCENARIO cycle K: COUNT, ...".
std::string planner_allocations(planners::Planner& planner) {
  std::string found;
  for (const char* path : kScenarios) {
    const Recording recording = record(path);
    planner.reset();
    planners::PlannerOutput out;
    std::vector<long> counts;
    int failures = 0;
    for (std::size_t k = 0; k < recording.inputs.size(); ++k) {
      planners::PlannerInput input = recording.inputs[k];
      const bool hold = k >= kHoldCycle && k < kHoldCycle + kHoldCycles;
      if (hold) input.target_age = INFINITY;
      AllocationCount count;
      planner.plan(input, out);
      const long allocations = count.allocations();
      // The planner braked (the safety layer around it may still send an evasive command: a hold is not
      // always safe among moving obstacles), so it shows no candidates.
      if (hold) {
        EXPECT_TRUE(out.candidates.empty()) << planner.name() << ", " << path << ": no hold";
      }
      // The first hold's own count is not judged.
      if (k >= kPlannerWarmUp) counts.push_back(k == kHoldCycle ? 0 : allocations);
      failures += !out.ok;
    }
    EXPECT_EQ(failures, 0) << planner.name() << ", " << path;
    EXPECT_GT(counts.size(), 40u);
    // The count's witness: the same cycle into a fresh output allocates (the output's vectors at least).
    AllocationCount fresh;
    const planners::PlannerOutput once = planner.plan(recording.inputs.back());
    EXPECT_GT(fresh.allocations(), 0) << planner.name() << ", fresh output";
    const std::string here = nonzero(counts, kPlannerWarmUp);
    if (!here.empty()) found += (found.empty() ? "" : "; ") + std::filesystem::path(path).stem().string() + " " + here;
  }
  return found;
}

}  // namespace

TEST(AllocationCount, DroppedCandidatesKeepTheirStorage) {
  planners::PlannerOutput out;
  out.resize_candidates(5);
  std::vector<const planners::Vec2*> made;
  for (auto& c : out.candidates) {
    c.assign(100, planners::Vec2::Ones());
    made.push_back(c.data());
  }
  {
    AllocationCount count;
    out.resize_candidates(0);
    EXPECT_TRUE(out.candidates.empty());
    out.resize_candidates(3);
    ASSERT_EQ(out.candidates.size(), 3u);
    for (auto& c : out.candidates) {
      EXPECT_NE(std::find(made.begin(), made.end(), c.data()), made.end()) << "a trajectory's storage was not kept";
      c.assign(100, planners::Vec2::Zero());  // within its capacity
    }
    out.resize_candidates(5);
    EXPECT_EQ(count.allocations(), 0);
  }
  // More than ever before makes new trajectories (the count's witness).
  AllocationCount count;
  out.resize_candidates(8);
  EXPECT_EQ(out.candidates.size(), 8u);
  EXPECT_GT(count.allocations(), 0);
}

TEST(AllocationCount, LearnedPlanDoesNotAllocateAfterTheFirstCycle) {
  for (const char* variant : {"cvae", "cvae-fixed-q", "bc"}) {
    planners::PlannerOptions options;
    options.model = std::string(OCCTRACK_MODEL_DIR) + "/" +
                    (std::string(variant) == "cvae-fixed-q" ? "fixed-q" : variant) + ".safetensors";
    ASSERT_TRUE(std::filesystem::exists(options.model)) << "no shipped model " << options.model;
    std::unique_ptr<planners::Planner> planner = planners::make_planner(variant, options);
    EXPECT_EQ(planner_allocations(*planner), "") << variant;
  }
  // A target-frame model turns its inputs and outputs in place (policy::FrameRotation).
  planners::LearnedPolicySettings settings;
  policy::NetworkConfig network = policy::NetworkConfig::for_projection(settings.projection);
  network.target_frame = true;
  planners::LearnedPolicy turned(settings, policy::Model(policy::random_model(network, settings.projection, "cvae", 3)));
  EXPECT_EQ(planner_allocations(turned), "") << "cvae, target frame";
}

TEST(AllocationCount, ShieldedPlannersDoNotAllocateAfterTheFirstCycle) {
  // The safety layer around a planner (its perception, free space and certification) keeps to the same rule.
  for (const char* name : {"follower", "cvae"}) {
    planners::PlannerOptions options;
    options.shield = true;
    options.response_time = 0.25;
    std::unique_ptr<planners::Planner> planner = planners::make_planner(name, options);
    EXPECT_EQ(planner_allocations(*planner), "") << name;
  }
}

TEST(AllocationCount, PredictingPlannersDoNotAllocateAfterTheFirstCycle) {
  // The target predictor's history, its forecast and the weighted ranking keep to the same rule.
  for (const char* name : {"follower", "cvae"}) {
    planners::PlannerOptions options;
    options.predictor = true;
    std::unique_ptr<planners::Planner> planner = planners::make_planner(name, options);
    EXPECT_EQ(planner_allocations(*planner), "") << name;
  }
}

TEST(AllocationCount, ProjCemPlanDoesNotAllocateAfterTheFirstCycle) {
  planners::PlannerOptions options;
  options.samples = 48;  // the default's code path (one thread), at a third of the time
  std::unique_ptr<planners::Planner> planner = planners::make_planner("projcem", options);
  EXPECT_EQ(planner_allocations(*planner), "");
}

TEST(AllocationCount, FollowerPlanDoesNotAllocateAfterTheFirstCycle) {
  std::unique_ptr<planners::Planner> planner = planners::make_planner("follower");
  EXPECT_EQ(planner_allocations(*planner), "");
}

TEST(AllocationCount, TrackerStepDoesNotAllocateAfterTheFirstCycle) {
  // The middleware-free API (tracker.hpp: "its storage is reused from call to call"), the safety layer on.
  planners::TrackerSettings settings;
  planners::Tracker tracker(settings);
  for (const char* path : kScenarios) {
    const Recording recording = record(path);
    tracker.reset();
    std::vector<long> counts;
    int stopped = 0;
    for (std::size_t k = 0; k < recording.inputs.size(); ++k) {
      const planners::PlannerInput& in = recording.inputs[k];
      const double now = 100.0 + in.time;
      planners::RobotState robot{in.robot_position, in.robot_velocity, now};
      planners::TargetEstimate target{in.target_position, in.target_velocity, now - in.target_age};
      core::Scan scan = *in.scan;
      scan.time = now;
      AllocationCount count;
      const planners::TrackerOutput& out = tracker.step(now, robot, target, &scan);
      if (k >= kPlannerWarmUp) counts.push_back(count.allocations());
      stopped += out.stopped;
    }
    EXPECT_EQ(stopped, 0) << path;
    EXPECT_EQ(nonzero(counts, kPlannerWarmUp), "") << path;
  }
}

TEST(AllocationCount, TrackerStopsDoNotAllocate) {
  // A robot that has lost its target, or whose sensor fails, runs stop cycles for as long as that lasts: each
  // formats its reason into the output's kept string (tracker.cpp, docs/ros.md "Memory"), from the first one.
  planners::TrackerSettings settings;
  planners::Tracker tracker(settings);
  const Recording recording = record(kScenarios[1]);
  enum Fault { none, stale_target, nan_robot, scan_mostly_nan, scan_gap, future_scan, nan_now, count };
  const char* const expected[] = {"", "target: stale", "robot: position (nan", "scan: only ", "scan: 11 unusable beams",
                                  "scan: stamp is ", "time: now must be"};
  std::vector<long> counts;
  int stopped = 0;
  for (std::size_t k = 0; k < recording.inputs.size(); ++k) {
    const planners::PlannerInput& in = recording.inputs[k];
    // The first cycle tracks (it sizes the plan's storage); then a fault every other cycle, each kind in turn.
    const Fault fault = (k == 0 || k % 2 == 1) ? none : static_cast<Fault>(1 + (k / 2) % (count - 1));
    double now = 100.0 + in.time;
    planners::RobotState robot{in.robot_position, in.robot_velocity, now};
    planners::TargetEstimate target{in.target_position, in.target_velocity, now - in.target_age};
    core::Scan scan = *in.scan;
    scan.time = now;
    switch (fault) {
      case stale_target: target.stamp = now - 2.0 * settings.target_timeout; break;
      case nan_robot: robot.position.x() = NAN; break;
      case scan_mostly_nan: std::fill(scan.ranges.begin(), scan.ranges.end() - 10, NAN); break;
      case scan_gap: std::fill(scan.ranges.begin() + 100, scan.ranges.begin() + 111, NAN); break;  // 11 beams, 0.19 rad
      case future_scan: scan.time = now + 1.0; break;
      case nan_now: now = NAN; break;
      default: break;
    }
    AllocationCount count_here;
    const planners::TrackerOutput& out = tracker.step(now, robot, target, &scan);
    const long allocations = count_here.allocations();
    if (k == 0) continue;
    counts.push_back(allocations);
    EXPECT_EQ(out.stopped, fault != none) << "cycle " << k << ": " << out.reason;
    EXPECT_EQ(out.reason.rfind(expected[fault], 0), 0u) << "cycle " << k << ": " << out.reason;
    if (fault != none) {
      EXPECT_TRUE(out.command.isZero()) << "cycle " << k;
    }
    stopped += out.stopped;
  }
  EXPECT_GE(stopped, 25);
  EXPECT_EQ(nonzero(counts, 1), "");
}
