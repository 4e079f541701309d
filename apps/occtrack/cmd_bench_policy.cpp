// occtrack bench policy [--model FILE | --random] [--variant cvae|bc|fixed-q] [--batch B] [--iterations K]
//                       [--repeats R] [--scenario FILE] [--seed S] [--shield [--standoff S] [--moving-speed-max V]]
//                       [--predictor] [--tracking-weight W] [--moving-reach S] [--json FILE]
//
// Times the learned policy's whole planning cycle (LearnedPolicy::plan: perception, PointNet, decoder,
// projection, ranking) on one core, on realistic scans: the follower drives a few seconds of a scenario
// (default scenarios/static-1ms/forest-a-1.yaml) and the scans it sees are replayed. Prints the median, p99
// and mean in milliseconds and the median split per stage. --random times a model with random weights, so
// that the cost can be measured before a model is trained. --shield puts the safety layer around the policy
// (docs/safety.md; response time 0.25 s, the v2 tables' lag) and splits out its share of the cycle, and by
// what the layer chose; --standoff sets its moving_standoff (0: the layer before the standoff, to compare side
// by side), --moving-speed-max its moving_speed_max. --predictor ranks against the target predictor (its
// cost: the difference in the cycle against a run without it). The ranking is the one the variant gets by
// name (planners::make_planner): its tracking weight and, behind the layer, its moving reach, unless
// --tracking-weight or --moving-reach say otherwise.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <time.h>
#include <vector>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/core/timing.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/learned.hpp"
#include "occtrack/planners/safety.hpp"
#include "occtrack/policy/model.hpp"
#include "occtrack/sim/world.hpp"

namespace fs = std::filesystem;

namespace occtrack::app {

namespace {

constexpr const char* kDefaultScenario = "scenarios/static-1ms/forest-a-1.yaml";

struct Options {
  std::string model, variant = "cvae", scenario, json_path;
  bool random = false;
  int batch = 30;
  bool keep_last_plan = true;
  bool rank_stop = true;
  bool shield = false;
  bool predictor = false;
  double standoff = planners::safety::Settings{}.moving_standoff;  // s, the layer's default
  double moving_speed_max = planners::safety::Settings{}.moving_speed_max;  // m/s, the layer's default
  int iterations = planners::LearnedPolicySettings{}.projection.iterations;  // the planners' default
  int repeats = 1000;
  double seconds = 5.0;
  std::uint64_t seed = 1;
  planners::PlannerOptions ranking;  // --tracking-weight, --moving-reach (unset: the variant's by name)
};

// The given scenario, else the default one from the working directory or from the source tree (the shipped
// models' folder sits beside scenarios/).
std::string resolve_scenario(const std::string& given) {
  if (!given.empty()) return given;
  if (fs::is_regular_file(kDefaultScenario)) return kDefaultScenario;
  const fs::path source_tree = fs::path(planners::default_model_path(policy::Variant::cvae)).parent_path().parent_path();
  const fs::path beside = source_tree / kDefaultScenario;
  if (fs::is_regular_file(beside)) return beside.string();
  throw std::runtime_error(std::string(kDefaultScenario) + ": not found (pass --scenario FILE)");
}

// CPU time of the calling thread: unlike wall time, it does not count the time slices other processes take on
// a shared machine.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

// Planner inputs along a follower's drive through the scenario, one per planning period.
struct Recording {
  std::vector<core::Scan> scans;
  std::vector<planners::PlannerInput> inputs;
};

Recording record(const core::Scenario& scenario, double seconds) {
  const double period = 0.05;
  const int frames = std::max(1, static_cast<int>(std::min(seconds, scenario.duration) / period));
  sim::World world(scenario);
  std::mt19937_64 rng(1);
  planners::Follower follower;
  follower.reset();
  Recording r;
  r.scans.resize(frames);
  r.inputs.resize(frames);
  Eigen::Vector2d position = scenario.robot_position, velocity = scenario.robot_velocity;
  for (int k = 0; k < frames; ++k) {
    const double t = k * period;
    world.scan(position, t, rng, r.scans[k]);
    r.scans[k].time = t;
    planners::PlannerInput& in = r.inputs[k];
    in.time = t;
    in.robot_position = position;
    in.robot_velocity = velocity;
    in.target_position = world.target_position(t);
    in.target_velocity = world.target_velocity(t);
    in.scan = &r.scans[k];
    velocity = follower.plan(in).command_velocity;
    position += velocity * period;
  }
  return r;
}

int run(const Options& o) {
  planners::LearnedPolicySettings settings;
  settings.variant = policy::parse_variant(o.variant);
  settings.batch = o.batch;
  settings.keep_last_plan = o.keep_last_plan;
  settings.rank_stop = o.rank_stop;
  settings.seed = o.seed;
  settings.projection.iterations = o.iterations;
  planners::PlannerOptions as_named = o.ranking;  // the ranking make_planner gives the variant by name
  as_named.batch = o.batch;
  as_named.shield = o.shield;
  as_named.predictor = o.predictor;
  planners::rank_as_asked(settings.ranking, planners::learned_planner_name(settings.variant), as_named);
  const std::string scenario_path = resolve_scenario(o.scenario);
  const core::Scenario scenario = io::read_scenario(scenario_path);

  std::string model_name;
  std::unique_ptr<planners::LearnedPolicy> planner;
  if (o.random) {
    projection::Settings p = settings.projection;
    p.obstacles = settings.perception.nearest_count;
    policy::NetworkConfig network = policy::NetworkConfig::for_projection(p);
    network.cloud_points = settings.perception.cloud_size;
    policy::Model model(policy::random_model(network, p, o.variant, o.seed));
    planner = std::make_unique<planners::LearnedPolicy>(settings, std::move(model));
    model_name = "random";
  } else {
    settings.model_path = o.model;
    planner = std::make_unique<planners::LearnedPolicy>(settings);
    model_name = planner->model().source();
  }

  // What runs each cycle: the policy, or the safety layer around it (which then owns it).
  planners::LearnedPolicy* policy = planner.get();
  std::unique_ptr<planners::Planner> runner = std::move(planner);
  if (o.shield) {
    planners::safety::Settings shield;
    shield.response_time = 0.25;
    shield.moving_standoff = o.standoff;
    shield.moving_speed_max = o.moving_speed_max;
    runner = planners::safety::make_shielded(std::move(runner), shield);
  }

  const Recording rec = record(scenario, o.seconds);
  const int frames = static_cast<int>(rec.inputs.size());
  // Warm-up: one pass, so that every buffer has its size; then the timed cycles, replaying the drive. One
  // output for all cycles, as a robot's loop keeps it (Tracker, the ROS node, sim::run_episode): its storage
  // is reused, so the cycles allocate nothing (tests/test_allocation_count.cpp).
  planners::PlannerOutput out;
  runner->reset();
  for (const auto& in : rec.inputs) runner->plan(in, out);
  std::vector<double> total, cpu, perception, pointnet, decoder, projection, ranking, safety;
  for (auto* v : {&total, &cpu, &perception, &pointnet, &decoder, &projection, &ranking, &safety})
    v->reserve(o.repeats);
  // The layer's time by what it chose (indexed by planners::SafetyAction): the fallback's search makes the tail.
  std::vector<std::vector<double>> by_action(planners::kSafetyActions);
  int failed = 0;
  for (int r = 0; r < o.repeats; ++r) {
    const int i = r % frames;
    if (i == 0) runner->reset();  // scan times must not go backwards
    const double cpu_start = thread_cpu_ms();
    const auto start = std::chrono::steady_clock::now();
    runner->plan(rec.inputs[i], out);
    total.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    cpu.push_back(thread_cpu_ms() - cpu_start);
    if (!out.ok) ++failed;
    const auto& t = policy->last_timing();
    safety.push_back(o.shield ? out.compute_ms - t.total : 0.0);  // the layer's part of the cycle
    if (o.shield) by_action[static_cast<std::size_t>(out.safety)].push_back(safety.back());
    perception.push_back(t.perception);
    pointnet.push_back(t.pointnet);
    decoder.push_back(t.decoder);
    projection.push_back(t.projection);
    ranking.push_back(t.ranking);
  }
  const core::TimingSummary cycle = core::summarize_timings(total), cycle_cpu = core::summarize_timings(cpu);
  const core::TimingSummary sp = core::summarize_timings(perception), sn = core::summarize_timings(pointnet),
                            sd = core::summarize_timings(decoder), sj = core::summarize_timings(projection),
                            sr = core::summarize_timings(ranking), ss = core::summarize_timings(safety);

  const auto& net = policy->model().network();
  // The rows solved per cycle: the B samples, the last plan and the stop plan (planners/learned.hpp).
  const bool projects = settings.variant != policy::Variant::bc;
  const int rows = o.batch + (o.keep_last_plan ? 1 : 0) + (o.rank_stop && projects ? 1 : 0);
  std::printf("policy %s (%s model), batch %d (%d rows ranked%s%s), %d projection iterations, %d obstacle points, "
              "one core%s; ranking's tracking weight %g, moving reach %g s\n",
              policy->name().c_str(), model_name.c_str(), o.batch, rows, o.keep_last_plan ? ", last plan" : "",
              o.rank_stop && projects ? ", stop plan" : "", o.iterations, settings.projection.obstacles,
              o.predictor ? ", target predictor" : "", settings.ranking.tracking_weight, settings.ranking.moving_reach);
  std::printf("  network: PointNet widths ");
  for (std::size_t i = 0; i < net.pointnet_widths.size(); ++i)
    std::printf("%s%d", i ? "-" : "", net.pointnet_widths[i]);
  std::printf(", features %d, decoder %d x %d\n", net.features, net.layers, net.hidden);
  std::printf("  inputs:  %d scans of %s (follower's drive), replayed\n", frames, scenario.name.c_str());
  std::printf("  cycle:   median %.3f ms, p99 %.3f ms, mean %.3f ms, min %.3f ms (%d cycles, %d without a plan)\n",
              cycle.median, cycle.p99, cycle.mean, cycle.min, o.repeats, failed);
  std::printf("  CPU:     median %.3f ms, p99 %.3f ms (this thread's CPU time: other processes' time slices excluded)\n",
              cycle_cpu.median, cycle_cpu.p99);
  std::printf("  split (medians): perception %.3f, PointNet %.3f, decoder %.3f, projection %.3f, ranking %.3f ms\n",
              sp.median, sn.median, sd.median, sj.median, sr.median);
  if (o.shield) {
    std::printf("  safety layer (standoff %.2f s, moving obstacles up to %g m/s): median %.3f ms, p99 %.3f ms, max %.3f "
                "ms of the cycle\n",
                o.standoff, o.moving_speed_max, ss.median, ss.p99, ss.max);
    std::printf("  by its choice (cycles: median / max ms):");
    for (int a = 0; a < planners::kSafetyActions; ++a) {
      const std::vector<double>& times = by_action[static_cast<std::size_t>(a)];
      if (times.empty()) continue;
      const core::TimingSummary s = core::summarize_timings(times);
      std::printf(" %s %zu: %.3f / %.3f;", planners::to_string(static_cast<planners::SafetyAction>(a)), times.size(),
                  s.median, s.max);
    }
    std::printf("\n");
  }

  if (!o.json_path.empty()) {
    nlohmann::json doc = {
        {"benchmark", "policy"},
        {"planner", policy->name()},
        {"shield", o.shield},
        {"predictor", o.predictor},
        {"tracking_weight", settings.ranking.tracking_weight},
        {"moving_reach_s", settings.ranking.moving_reach},
        {"model", model_name},
        {"batch", o.batch},
        {"rows", rows},
        {"last_plan", o.keep_last_plan},
        {"stop_plan", o.rank_stop && projects},
        {"iterations", o.iterations},
        {"obstacles", settings.projection.obstacles},
        {"scenario", scenario.name},
        {"frames", frames},
        {"repeats", o.repeats},
        {"failed", failed},
        {"median_ms", cycle.median},
        {"p99_ms", cycle.p99},
        {"mean_ms", cycle.mean},
        {"min_ms", cycle.min},
        {"cpu_median_ms", cycle_cpu.median},
        {"cpu_p99_ms", cycle_cpu.p99},
        {"split_median_ms",
         {{"perception", sp.median}, {"pointnet", sn.median}, {"decoder", sd.median}, {"projection", sj.median},
          {"ranking", sr.median}}}};
    if (o.shield) {
      doc["safety_ms"] = {{"median", ss.median}, {"p99", ss.p99}, {"max", ss.max}};
      doc["standoff_s"] = o.standoff;
      doc["moving_speed_max_m_s"] = o.moving_speed_max;
    }
    if (!write_text_file("occtrack bench policy", o.json_path, doc.dump(2) + "\n")) return kExitInputError;
  }
  return kExitOk;
}

}  // namespace

void add_bench_policy_command(CLI::App& bench, int& exit_code) {
  auto [cmd, o] = add_command<Options>(bench, "policy", "Time the learned policy's planning cycle on realistic scans");
  auto* model = cmd->add_option("--model", o->model, "Model file (default: the shipped model of the variant)");
  cmd->add_flag("--random", o->random, "Use random weights of the default sizes instead of a model file")
      ->excludes(model);
  add_choice_option(cmd, "--variant", o->variant, "Model variant", {"cvae", "bc", "fixed-q"});
  add_bounded_option(cmd, "--batch", o->batch, "Latent samples per cycle (B)", 1, 100000);
  cmd->add_flag("--no-last-plan{false}", o->keep_last_plan, "Project the B samples without the last plan");
  cmd->add_flag("--no-stop{false}", o->rank_stop, "Project the B samples without the stop plan");
  add_bounded_option(cmd, "--iterations", o->iterations, "Projection iterations per cycle (K)", 1, 100000);
  add_bounded_option(cmd, "--repeats", o->repeats, "Timed cycles", 1, 10000000);
  cmd->add_option("--scenario", o->scenario, std::string("Scenario whose scans are replayed (default ") +
                                                  kDefaultScenario + ")");
  add_bounded_option(cmd, "--seconds", o->seconds, "Seconds of the follower's drive recorded", 0.05, 3600.0);
  cmd->add_option("--seed", o->seed, "Seed of the latent samples (and of the random weights)")->capture_default_str();
  cmd->add_flag("--shield", o->shield,
                "Put the safety layer around the policy (response time 0.25 s) and time its share of the cycle");
  cmd->add_flag("--predictor", o->predictor,
                "Rank against the target predictor (docs/target_prediction.md) instead of constant velocity");
  add_bounded_option(cmd, "--standoff", o->standoff,
                     "With --shield: the layer's moving_standoff, s (0: a stop clear of the lanes only, as before)", 0.0,
                     kStandoffMax);
  add_bounded_option(cmd, "--moving-speed-max", o->moving_speed_max,
                     "With --shield: the fastest the layer assumes a moving obstacle goes, m/s (its moving_speed_max)",
                     kMovingSpeedMin, kMovingSpeedMax);
  add_ranking_options(cmd, o->ranking);
  cmd->add_option("--json", o->json_path, "Also write the results as JSON to this file");
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
