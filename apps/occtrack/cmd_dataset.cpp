// occtrack dataset generate --out FILE [--episodes 8] [--seed 5000] [--duration 40]
//                           [--worlds forest,boxes,mixed,dynamic] [--speeds 1,1.5,2] [--label-every 1]
//                           [--scenarios FILE|DIR,...]
//                           [--driver expert|projcem|NAME] [--model FILE] [--jobs J]
//                           [--expert-samples 120] [--expert-iterations 8] [--expert-settle 0]
//                           [--target smooth|teleop] [--no-shield] [Protocol v2: --latency MS --tau S
//                           --beams N --lidar-noise SIGMA --target-noise POS,VEL ...]
// occtrack dataset info FILE
// occtrack dataset merge --out FILE IN IN...
//
// Demonstrations for training (docs/learning.md, "Dataset file"): closed-loop episodes on generated worlds
// whose seeds are outside the benchmark's 1000-1999, labelled by the offline Proj-CEM expert, written as one
// safetensors file; or, with --scenarios, on scenario files (your own recorded target paths, made with
// `scenario import`; a benchmark suite's folder is refused). `info` prints a file's metadata, tensor shapes
// and statistics; `merge` concatenates
// files made with the same projection and perception settings (episode indices renumbered).
//
// `mpirun -n R occtrack dataset generate ...` shares the episodes among R ranks (docs/scaling.md,
// "Demonstrations under MPI"): rank k runs episodes k, k + R, ... on its threads, and rank 0 writes the one
// file, byte for byte the file one process writes.
#include <chrono>
#include <cstdio>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "launcher.hpp"
#include "mpi_world.hpp"
#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/sim/demonstrations.hpp"
#include "occtrack/sim/scenario_generator.hpp"
#include "suite_runner.hpp"

namespace occtrack::app {

namespace {

struct GenerateOptions {
  std::string out;
  int episodes = 0;  ///< 0: 8, or one per scenario with --scenarios
  std::uint64_t seed = 5000;
  std::optional<double> duration;  ///< default: 40 s, or each scenario's own length with --scenarios
  std::vector<std::string> scenarios;  ///< scenario files or folders of them (instead of generated worlds)
  std::vector<std::string> worlds = {"forest", "boxes", "mixed", "dynamic"};
  std::vector<double> speeds = {1.0, 1.5, 2.0};
  int label_every = 1;
  std::string driver = "expert";
  std::string model;
  std::optional<int> jobs;  ///< default: MpiWorld::default_threads()
  // The offline expert's preset (planners::ProjCemSettings::offline_expert), overridable.
  int expert_samples = planners::ProjCemSettings::offline_expert(1).samples;
  int expert_iterations = planners::ProjCemSettings::offline_expert(1).cem_iterations;
  double expert_settle = planners::ProjCemSettings::offline_expert(1).settle_distance;
  std::string target = "smooth";
  /// Protocol v2 settings of every episode, and the driver's shield (on, as on the command line's planners).
  EpisodeCliOptions episode;
};

struct MergeOptions {
  std::string out;
  std::vector<std::string> inputs;
};

std::string join(const std::vector<std::string>& items, const char* separator = ",") {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : separator) + item;
  return out;
}

std::string number_text(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

/// The settings as a command line, for the file's provenance. --out and --jobs are left out: they do not
/// change the rows, and the same settings should give the same bytes.
std::string speeds_text(const GenerateOptions& o) {
  std::vector<std::string> speeds;
  for (double v : o.speeds) speeds.push_back(number_text(v));
  return join(speeds);
}

/// s per episode: --duration, else 40 s for generated episodes and each scenario's own length for files (the
/// settings' largest, 36000 s).
double duration_of(const GenerateOptions& o) { return o.duration.value_or(o.scenarios.empty() ? 40.0 : 36000.0); }

/// The scenarios of --scenarios, read; a file in a benchmark suite's folder is refused, so that no benchmark
/// episode is trained on (scenarios/README.md, "Seeds: benchmark against training").
std::vector<core::Scenario> read_training_scenarios(const std::vector<std::string>& paths) {
  std::vector<core::Scenario> scenarios;
  for (const std::string& path : paths)
    for (const std::filesystem::path& file : file_or_scenario_files(path)) {
      const std::string folder = std::filesystem::absolute(file).parent_path().filename().string();
      if (sim::find_suite(folder))
        throw std::invalid_argument("--scenarios: " + file.string() + " is in the folder of benchmark suite " +
                                    folder + ": training on the benchmark's episodes would make its results "
                                    "meaningless; import or generate other episodes");
      scenarios.push_back(io::read_scenario(file.string()));
    }
  return scenarios;
}

std::string canonical_command(const GenerateOptions& o) {
  std::string text = "occtrack dataset generate --episodes " + std::to_string(o.episodes) + " --seed " +
                     std::to_string(o.seed);
  if (o.scenarios.empty() || o.duration) text += " --duration " + number_text(duration_of(o));
  if (o.scenarios.empty())
    text += " --worlds " + join(o.worlds) + " --speeds " + speeds_text(o);
  else
    text += " --scenarios " + join(o.scenarios);
  text += " --label-every " + std::to_string(o.label_every) + " --driver " + o.driver;
  if (!o.model.empty()) text += " --model " + o.model;
  if (o.driver != "expert") {
    const planners::PlannerOptions& driver = o.episode.planner_options;
    text += " --tracking-weight " + number_text(planners::tracking_weight_for(o.driver, driver));
    // The reach in effect; none when off, so that files made before it had a default keep their bytes.
    const double reach = planners::moving_reach_for(o.driver, driver);
    if (reach > 0.0) text += " --moving-reach " + number_text(reach);
  }
  text += " --expert-samples " + std::to_string(o.expert_samples) + " --expert-iterations " +
          std::to_string(o.expert_iterations) + " --expert-settle " + number_text(o.expert_settle);
  const EpisodeCliOptions& e = o.episode;
  if (o.scenarios.empty()) text += " --target " + o.target;  // the scenarios' own paths otherwise
  text += e.planner_options.shield ? "" : " --no-shield";
  if (e.latency != "none") text += " --latency " + e.latency;
  if (e.tau != 0.0) text += " --tau " + number_text(e.tau);
  if (!e.beams.empty()) text += " --beams " + e.beams;
  if (!e.lidar_noise.empty()) text += " --lidar-noise " + e.lidar_noise;
  if (!e.beam_dropout.empty()) text += " --beam-dropout " + e.beam_dropout;
  if (!e.target_noise.empty()) text += " --target-noise " + e.target_noise;
  if (!e.response_time.empty()) text += " --response-time " + e.response_time;
  if (e.target_observation != "always") text += " --target-observation " + e.target_observation;
  return text;
}

/// Which command-line option sets the settings field a validate() message starts with.
std::string option_of(const std::string& message) {
  static const std::pair<const char*, const char*> fields[] = {
      {"episodes", "--episodes"},     {"first_seed", "--seed"},          {"worlds", "--worlds"},
      {"target_speeds", "--speeds"},  {"duration", "--duration"},        {"label_every", "--label-every"},
      {"driver", "--driver"},         {"jobs", "--jobs"},                {"expert.samples", "--expert-samples"},
      {"expert.cem_iterations", "--expert-iterations"}, {"expert.settle_distance", "--expert-settle"},
      {"episode.latency_ms", "--latency"}};
  for (const auto& [field, option] : fields)
    if (message.rfind(field, 0) == 0) return std::string(option) + ": ";
  return "";
}

std::string duration_text(double seconds) {
  char text[32];
  if (seconds < 120)
    std::snprintf(text, sizeof text, "%.0f s", seconds);
  else if (seconds < 7200)
    std::snprintf(text, sizeof text, "%.1f min", seconds / 60);
  else
    std::snprintf(text, sizeof text, "%.1f h", seconds / 3600);
  return text;
}

/// A shard's report travels to rank 0 in its dataset's metadata, under this key (taken out before the
/// shards are interleaved, so it never reaches the file).
constexpr const char* kShardReportKey = "occtrack.shard_report";

std::string report_json(const sim::DemonstrationReport& r) {
  return nlohmann::json{{"episodes", r.episodes},
                        {"episodes_failed", r.episodes_failed},
                        {"failures", r.failures},
                        {"cycles", r.cycles},
                        {"labelled", r.labelled},
                        {"rows", r.rows},
                        {"skipped_failed", r.skipped_failed},
                        {"skipped_nonfinite", r.skipped_nonfinite},
                        {"expert_ms", r.expert_ms},
                        {"seconds", r.seconds}}
      .dump();
}

sim::DemonstrationReport report_from_json(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  sim::DemonstrationReport r;
  r.episodes = j.at("episodes").get<int>();
  r.episodes_failed = j.at("episodes_failed").get<int>();
  r.failures = j.at("failures").get<std::vector<std::string>>();
  r.cycles = j.at("cycles").get<std::int64_t>();
  r.labelled = j.at("labelled").get<std::int64_t>();
  r.rows = j.at("rows").get<std::int64_t>();
  r.skipped_failed = j.at("skipped_failed").get<std::int64_t>();
  r.skipped_nonfinite = j.at("skipped_nonfinite").get<std::int64_t>();
  r.expert_ms = j.at("expert_ms").get<double>();
  r.seconds = j.at("seconds").get<double>();
  return r;
}

void print_summary(const std::string& out, const sim::DemonstrationReport& report) {
  for (const std::string& failure : report.failures) std::fprintf(stderr, "skipped episode %s\n", failure.c_str());
  const double rate = report.seconds > 0 ? static_cast<double>(report.rows) / report.seconds : 0.0;
  std::printf("wrote %s: %lld rows from %d episodes (%d skipped by the scenario generator) in %.1f s, %.2f rows/s\n",
              out.c_str(), static_cast<long long>(report.rows), report.episodes, report.episodes_failed,
              report.seconds, rate);
  std::printf("  cycles %lld, labelled %lld, skipped %lld (expert failed %lld, non-finite %lld); "
              "expert %.1f ms per labelled cycle\n",
              static_cast<long long>(report.cycles), static_cast<long long>(report.labelled),
              static_cast<long long>(report.skipped()), static_cast<long long>(report.skipped_failed),
              static_cast<long long>(report.skipped_nonfinite),
              report.labelled > 0 ? report.expert_ms / static_cast<double>(report.labelled) : 0.0);
}

using ProgressCallback = std::function<void(const sim::DemonstrationProgress&)>;

/// `generate` with several ranks: rank k runs shard k of the episodes and hands it to rank 0 as a dataset file
/// in memory (safetensors, its report in the metadata); rank 0 interleaves the shards, writes the file and
/// prints the summary, or names the ranks that failed. Every rank returns rank 0's exit code.
int generate_shared(const MpiWorld& world, const std::string& out, sim::DemonstrationSettings s,
                    const ProgressCallback& progress) {
  const char* const who = "occtrack dataset generate: ";
  const auto start = std::chrono::steady_clock::now();
  s.shard = world.rank();
  s.shards = world.size();
  MpiWorld::Result mine;
  try {
    sim::DemonstrationReport report;
    io::TensorFile file = io::to_tensor_file(sim::generate_demonstrations(s, &report, progress));
    file.metadata[kShardReportKey] = report_json(report);
    mine.bytes = io::serialize_safetensors(file);
  } catch (const std::exception& e) {
    mine.ok = false;
    mine.error = e.what();
  }
  std::vector<MpiWorld::Result> results = world.gather_to_root(std::move(mine));
  if (!world.root()) return world.broadcast_from_root(kExitOk);

  int code = kExitOk;
  const std::string of = " of " + std::to_string(world.size());
  for (std::size_t rank = 0; rank < results.size(); ++rank)
    if (!results[rank].ok) {
      std::cerr << who << "rank " << rank << of << ": " << results[rank].error << "\n";
      code = kExitInputError;
    }
  if (code == kExitOk) {
    try {
      std::vector<sim::Demonstrations> parts;
      sim::DemonstrationReport report;
      for (std::size_t rank = 0; rank < results.size(); ++rank) {
        io::TensorFile file = io::parse_safetensors(results[rank].bytes, "rank " + std::to_string(rank) + of);
        results[rank].bytes = {};
        report.add(report_from_json(file.metadata.at(kShardReportKey)));
        file.metadata.erase(kShardReportKey);
        parts.push_back(io::validate_dataset_file(file));
      }
      io::write_dataset_file(out, sim::interleave_demonstration_shards(std::move(parts)));
      report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      print_summary(out, report);
    } catch (const std::exception& e) {
      std::cerr << who << e.what() << "\n";
      code = kExitInputError;
    }
  }
  return world.broadcast_from_root(code);
}

int generate(GenerateOptions o) {
  const char* const who = "occtrack dataset generate: ";
  // Under MPI, every rank checks the options alike, before any communication; rank 0 alone says what is
  // wrong, and every rank exits with the same code.
  const std::optional<LauncherRanks> launcher = launcher_ranks();
  const bool speaks = !launcher || launcher->rank == 0;
  const auto refuse = [&](const std::string& why) {
    if (speaks) std::cerr << who << why << "\n";
    return kExitInputError;
  };
  std::optional<MpiWorld> world;
  try {
    world.emplace();
  } catch (const std::runtime_error& e) {
    return refuse(e.what());
  }
  sim::DemonstrationSettings s;
  try {
    s.scenarios = read_training_scenarios(o.scenarios);
  } catch (const std::exception& e) {
    return refuse(e.what());
  }
  if (o.episodes == 0) o.episodes = s.scenarios.empty() ? 8 : static_cast<int>(s.scenarios.size());
  s.episodes = o.episodes;
  s.first_seed = o.seed;
  s.worlds.clear();
  for (const std::string& name : o.worlds) {
    const auto world_kind = sim::parse_demonstration_world(name);
    if (!world_kind)
      return refuse("--worlds: unknown world kind '" + name +
                    "' (forest, boxes, mixed, dynamic, clutter-dynamic, sixwall, sixwall-sliding, random)");
    s.worlds.push_back(*world_kind);
  }
  s.target_speeds = o.speeds;
  const auto target = sim::parse_demonstration_target(o.target);
  if (!target) return refuse("--target: must be smooth or teleop, got '" + o.target + "'");
  s.target = *target;
  if (o.episode.latency_auto())
    return refuse("--latency: give a number of ms; auto is measured per planner in `bench` and `run` only");
  try {
    s.episode = o.episode.settings();
    s.driver_options = o.episode.planner_settings(&s.episode);
  } catch (const std::invalid_argument& e) {
    return refuse(e.what());
  }
  s.duration = duration_of(o);
  s.label_every = o.label_every;
  s.driver = o.driver;
  s.model = o.model;
  s.jobs = o.jobs.value_or(world->default_threads());
  s.expert = planners::ProjCemSettings::offline_expert(1);
  s.expert.samples = o.expert_samples;
  s.expert.cem_iterations = o.expert_iterations;
  s.expert.settle_distance = o.expert_settle;
  s.created_by = created_by(canonical_command(o));
  std::string error;
  if (!s.validate(&error)) return refuse(option_of(error) + error);
  if (!o.model.empty() && o.driver == "expert")
    return refuse("--model: only a learned --driver uses a model (the driver is the expert)");

  const int ranks = world->size();
  // Threads per rank: no more than rank 0's episodes, the most any rank runs.
  const int jobs = std::min(s.jobs, (o.episodes + ranks - 1) / ranks);
  if (!world->root()) return generate_shared(*world, o.out, s, {});  // rank 0 alone reports
  const std::string parallel = ranks > 1 ? std::to_string(ranks) + " ranks, " + std::to_string(jobs) + " jobs each"
                                         : std::to_string(jobs) + " jobs";
  char source[512];
  if (s.scenarios.empty())
    std::snprintf(source, sizeof source, "of %.0f s (seeds %llu-%llu; worlds %s; %s target, top speeds %s m/s)",
                  s.duration, static_cast<unsigned long long>(o.seed),
                  static_cast<unsigned long long>(sim::demonstration_seed(s, o.episodes - 1)),
                  join(o.worlds).c_str(), o.target.c_str(), speeds_text(o).c_str());
  else
    std::snprintf(source, sizeof source, "on %zu scenario files (each its own length%s; seeds %llu-%llu)",
                  s.scenarios.size(), o.duration ? (", at most " + number_text(*o.duration) + " s").c_str() : "",
                  static_cast<unsigned long long>(o.seed),
                  static_cast<unsigned long long>(sim::demonstration_seed(s, o.episodes - 1)));
  std::fprintf(stderr,
               "dataset: %d episodes %s, driver "
               "%s%s, expert %d samples x %d CEM iterations, labelling 1 cycle in %d, latency %s, tau %g s, %s\n",
               o.episodes, source, o.driver.c_str(),
               o.driver != "expert" && s.driver_options.shield ? " (shield on)" : "", o.expert_samples,
               o.expert_iterations, o.label_every, o.episode.latency.c_str(), o.episode.tau, parallel.c_str());
  // Under MPI, rank 0's progress is that of its own episodes.
  Progress progress(ranks > 1 ? "dataset (rank 0 of " + std::to_string(ranks) + ")" : "dataset");
  const ProgressCallback show = [&](const sim::DemonstrationProgress& p) {
    std::string detail = "episodes " + std::to_string(p.episodes_done) + "/" + std::to_string(p.episodes_total) +
                         ", " + std::to_string(p.rows) + " rows, " + duration_text(p.elapsed_s);
    if (p.fraction > 0.01 && p.fraction < 1.0)
      detail += ", ETA " + duration_text(p.elapsed_s * (1.0 - p.fraction) / p.fraction);
    progress.update(p.fraction, detail);
  };
  if (ranks > 1) return generate_shared(*world, o.out, s, show);

  sim::DemonstrationReport report;
  const sim::Demonstrations data = sim::generate_demonstrations(s, &report, show);
  io::write_dataset_file(o.out, data);
  print_summary(o.out, report);
  return kExitOk;
}

// `dataset generate`: its options, and generate() above as its body.
void add_generate_command(CLI::App& dataset, int& exit_code) {
  auto [gen, o] = add_command<GenerateOptions>(
      dataset, "generate",
      "Run closed-loop episodes on generated worlds (seeds outside the benchmark's 1000-1999) and write the "
      "expert's labelled planning cycles as a safetensors dataset");
  gen->add_option("--out", o->out, "Dataset file to write (safetensors)")->required();
  gen->add_option("--episodes", o->episodes,
                  "Episodes, each in a world of its own (default 8; with --scenarios, one per scenario)");
  gen->add_option("--seed", o->seed, "First seed; episode i uses seed + i (none may fall in 1000-1999)")
      ->capture_default_str();
  gen->add_option("--duration", o->duration,
                  "Simulated seconds per episode (default 40; with --scenarios, at most, default each one's length)");
  gen->add_option("--scenarios", o->scenarios,
                  "Scenario files or folders of them to drive instead of generated worlds (your own recorded "
                  "target paths, `scenario import`); episode i runs the (i mod N)-th; a benchmark suite's folder "
                  "is refused")
      ->delimiter(',');
  gen->add_option("--worlds", o->worlds,
                  "World kinds, used in turn: forest, boxes, mixed, dynamic, clutter-dynamic, sixwall, "
                  "sixwall-sliding, random")
      ->delimiter(',')
      ->capture_default_str();
  gen->add_option("--speeds", o->speeds, "Target top speeds (m/s), used in turn after every world kind")
      ->delimiter(',')
      ->capture_default_str();
  add_choice_option(gen, "--target", o->target,
                    "How the target moves: smooth (the v1 suites' generator) or teleop (the v2 suites' "
                    "tele-operator; the paper's worlds always use it)",
                    {"smooth", "teleop"});
  gen->add_flag("--shield,!--no-shield", o->episode.planner_options.shield,
                "On by default: a driver other than the expert goes through the safety layer (docs/safety.md)");
  add_protocol_options(gen, o->episode);
  gen->add_option("--label-every", o->label_every, "Label one planning cycle in this many")->capture_default_str();
  std::string names = join(planners::planner_names(), ", ");
  gen->add_option("--driver", o->driver,
                  "Who drives: expert (the labeller itself), or a planner (" + names +
                      ") while the expert labels (DAgger with a learned planner and --model)")
      ->capture_default_str();
  gen->add_option("--model", o->model, "Model file of a learned --driver");
  add_ranking_options(gen, o->episode.planner_options);  // the driver's (dagger.sh: tracking weight 1)
  gen->add_option("--jobs", o->jobs,
                  "Episodes run at the same time (default: every hardware thread; under MPI, per rank, the "
                  "machine's hardware threads shared among its ranks, at most the CPUs the rank is bound to)");
  gen->add_option("--expert-samples", o->expert_samples, "Expert's samples per CEM iteration")->capture_default_str();
  gen->add_option("--expert-iterations", o->expert_iterations, "Expert's CEM iterations")->capture_default_str();
  gen->add_option("--expert-settle", o->expert_settle,
                  "Expert: stop iterating once a refit moves the plan's mean by less than this (m; 0: never)")
      ->capture_default_str();
  set_command_body(gen, exit_code, [o] { return generate(*o); });
}

int info(const std::string& path) {
  const io::TensorFile file = io::read_safetensors(path);
  const io::DatasetFile data = io::validate_dataset_file(file);  // validates format and shapes
  std::printf("%s: %lld rows\n", path.c_str(), static_cast<long long>(data.rows));
  std::printf("metadata:\n");
  for (const auto& [key, value] : file.metadata) std::printf("  %-11s %s\n", key.c_str(), value.c_str());
  std::printf("tensors:\n");
  for (const auto& [name, tensor] : file.tensors)
    std::printf("  %-12s %s %s\n", name.c_str(), io::dtype_name(tensor.dtype), tensor.shape_text().c_str());
  const io::DatasetStatistics st = io::dataset_statistics(data);
  std::printf("statistics (%d episodes):\n", st.episodes);
  static const char* const columns[io::kObservationSize] = {"robot vx", "robot vy", "target x", "target y",
                                                            "target vx", "target vy"};
  for (int j = 0; j < io::kObservationSize; ++j)
    std::printf("  observation %-9s mean %7.3f  std %6.3f\n", columns[j], st.observation_mean(j),
                st.observation_std(j));
  std::printf("  target distance        mean %7.3f m\n", st.target_distance_mean);
  std::printf("  expert plan speed      mean %7.3f  std %6.3f  max %6.3f m/s (over the horizon); first 0.1 s "
              "mean %.3f m/s\n",
              st.plan_speed_mean, st.plan_speed_std, st.plan_speed_max, st.start_speed_mean);
  std::printf("  expert cost            mean %7.3f  std %6.3f  min %.3f  max %.3f\n", st.cost_mean, st.cost_std,
              st.cost_min, st.cost_max);
  return kExitOk;
}

int merge(const std::string& out, const std::vector<std::string>& inputs) {
  io::DatasetFile merged;
  nlohmann::json sources = nlohmann::json::array();
  for (const std::string& path : inputs) {
    const io::DatasetFile part = io::read_dataset_file(path);
    try {
      io::append_dataset(merged, part);
    } catch (const std::invalid_argument& e) {
      std::cerr << "occtrack dataset merge: " << path << ": " << e.what() << "\n";
      return kExitInputError;
    }
    const auto generator = part.metadata.find("generator");
    const auto driver = part.metadata.find("driver");
    sources.push_back({{"file", path},
                       {"rows", part.rows},
                       {"generator", generator == part.metadata.end() ? "" : generator->second},
                       {"driver", driver == part.metadata.end() ? "" : driver->second}});
  }
  merged.metadata["merged_from"] = sources.dump();
  io::write_dataset_file(out, merged);
  std::printf("wrote %s: %lld rows from %zu files\n", out.c_str(), static_cast<long long>(merged.rows),
              inputs.size());
  return kExitOk;
}

}  // namespace

void add_dataset_command(CLI::App& app, int& exit_code) {
  CLI::App* dataset = add_command_group(app, "dataset", "Make and inspect demonstration files for training");
  add_generate_command(*dataset, exit_code);

  auto [inf, info_path] =
      add_command<std::string>(*dataset, "info", "Print a dataset's rows, metadata, tensor shapes and statistics");
  inf->add_option("file", *info_path, "Dataset file (occtrack.dataset.v1)")->required();
  set_command_body(inf, exit_code, [info_path] { return info(*info_path); });

  auto [mrg, m] = add_command<MergeOptions>(
      *dataset, "merge",
      "Concatenate datasets made with the same projection and perception settings (episodes renumbered)");
  mrg->add_option("--out", m->out, "Dataset file to write")->required();
  mrg->add_option("files", m->inputs, "Dataset files, in order")->required();
  set_command_body(mrg, exit_code, [m] { return merge(m->out, m->inputs); });
}

}  // namespace occtrack::app
