#include "occtrack/sim/demonstrations.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "../core/name_table.hpp"
#include "occtrack/io/error.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/planners/learned.hpp"
#include "occtrack/sim/paper_worlds.hpp"
#include "occtrack/sim/scenario_generator.hpp"

namespace occtrack::sim {

using nlohmann::json;

// ---------------------------------------------------------------------------------------------------------
// World kinds and settings.

// One table for both directions.
constexpr std::pair<DemonstrationWorld, const char*> kDemonstrationWorldNames[] = {
    {DemonstrationWorld::forest, "forest"},
    {DemonstrationWorld::boxes, "boxes"},
    {DemonstrationWorld::mixed, "mixed"},
    {DemonstrationWorld::dynamic, "dynamic"},
    {DemonstrationWorld::clutter_dynamic, "clutter-dynamic"},
    {DemonstrationWorld::sixwall, "sixwall"},
    {DemonstrationWorld::sixwall_sliding, "sixwall-sliding"},
    {DemonstrationWorld::random, "random"}};

constexpr std::pair<DemonstrationTarget, const char*> kDemonstrationTargetNames[] = {
    {DemonstrationTarget::smooth, "smooth"}, {DemonstrationTarget::teleop, "teleop"}};

const char* to_string(DemonstrationWorld world) { return occtrack::detail::name_of(kDemonstrationWorldNames, world); }

std::optional<DemonstrationWorld> parse_demonstration_world(std::string_view text) {
  return occtrack::detail::value_of(kDemonstrationWorldNames, text);
}

const char* to_string(DemonstrationTarget target) { return occtrack::detail::name_of(kDemonstrationTargetNames, target); }

std::optional<DemonstrationTarget> parse_demonstration_target(std::string_view text) {
  return occtrack::detail::value_of(kDemonstrationTargetNames, text);
}

namespace {

/// Where a kind's world and target come from: the benchmark suite whose world it is (in a suite of several
/// worlds, the generated one of `kind`), and the suites whose target settings it takes with a smooth (v1)
/// and a tele-operated (v2) target.
struct WorldSource {
  const char* world_suite;
  std::optional<WorldKind> kind;
  const char* smooth_suite;  ///< nullptr: the kind has no smooth-target version (the paper's worlds)
  const char* teleop_suite;
};

WorldSource world_source(DemonstrationWorld world) {
  switch (world) {
    case DemonstrationWorld::forest: return {"static-1ms", WorldKind::forest, "static-1ms", "clutter-2ms"};
    case DemonstrationWorld::boxes: return {"static-1ms", WorldKind::boxes, "static-1ms", "clutter-2ms"};
    case DemonstrationWorld::mixed: return {"static-1ms", WorldKind::mixed, "static-1ms", "clutter-2ms"};
    case DemonstrationWorld::dynamic:
      return {"dynamic-1.5ms", std::nullopt, "dynamic-1.5ms", "clutter-dynamic-2ms"};
    case DemonstrationWorld::clutter_dynamic:
      return {"clutter-dynamic-2ms", std::nullopt, nullptr, "clutter-dynamic-2ms"};
    case DemonstrationWorld::sixwall: return {"sixwall-1ms", std::nullopt, nullptr, "sixwall-1ms"};
    case DemonstrationWorld::sixwall_sliding:
      return {"sixwall-dynamic-1.5ms", std::nullopt, nullptr, "sixwall-dynamic-1.5ms"};
    case DemonstrationWorld::random: return {"random-2ms", std::nullopt, nullptr, "random-2ms"};
  }
  throw std::logic_error("demonstrations: unknown world kind");
}

bool teleop_target(const DemonstrationSettings& s, DemonstrationWorld world) {
  return s.target == DemonstrationTarget::teleop || world_source(world).smooth_suite == nullptr;
}

SuiteSpec benchmark_suite(const char* name) {
  std::optional<SuiteSpec> suite = find_suite(name);
  if (!suite || suite->worlds.empty()) throw std::logic_error("demonstrations: benchmark suites are missing");
  return *suite;
}

/// The benchmark world an episode of this kind is drawn like.
SuiteWorld source_world(const WorldSource& source) {
  for (const SuiteWorld& w : benchmark_suite(source.world_suite).worlds)
    if (!source.kind || (!w.fixed && w.settings.style.kind == *source.kind)) return w;
  throw std::logic_error("demonstrations: no benchmark world of this kind");
}

/// Episode `seed`'s scenario: the kind's world (generated from the seed, or the paper's fixed layout) and a
/// target path drawn from the seed like the source suite's, at top speed `speed`. Throws std::runtime_error
/// when the generator cannot place the obstacles or the path.
core::Scenario demonstration_scenario(const DemonstrationSettings& s, DemonstrationWorld world, double speed,
                                      std::uint64_t seed, const std::string& name) {
  const bool teleop = teleop_target(s, world);
  const WorldSource where = world_source(world);
  const SuiteWorld source = source_world(where);
  const core::Scenario layout = source.fixed ? *source.fixed : generate_world(source.settings, seed);
  TargetSettings t = benchmark_suite(teleop ? where.teleop_suite : where.smooth_suite).target;
  if (teleop) {
    // The suite's area, re-calibrated for this speed (its style depends on the nominal speed).
    t = teleop_target_in(WorldArea{t.area_width, t.area_height, t.area_center_x, t.area_center_y}, speed,
                         s.duration);
  } else {
    t.max_speed = speed;
    t.min_speed = std::min(t.min_speed, speed);
    t.duration = s.duration;
  }
  return generate_episode(layout, t, seed, name);
}

}  // namespace

bool DemonstrationSettings::validate(std::string* error) const {
  std::ostringstream why;
  std::string inner;
  if (episodes < 1 || episodes > 10000000) {
    why << "episodes (" << episodes << ") must be between 1 and 10000000";
  } else if (first_seed > std::numeric_limits<std::uint64_t>::max() - static_cast<std::uint64_t>(episodes)) {
    why << "first_seed (" << first_seed << ") + episodes overflows a 64-bit seed";
  } else if (const std::uint64_t last = first_seed + static_cast<std::uint64_t>(episodes) - 1;
             first_seed <= kBenchmarkSeedMax && last >= kBenchmarkSeedMin) {
    // The episodes use the consecutive seeds first_seed .. last; the interval meets the benchmark's.
    why << "first_seed (" << first_seed << "): the episodes would use seeds " << first_seed << "-" << last
        << ", which meet the benchmark's seeds " << kBenchmarkSeedMin << "-" << kBenchmarkSeedMax
        << " (sim::is_benchmark_seed); training data must come from other worlds, e.g. first_seed 5000";
  } else if (auto bad = std::find_if(scenarios.begin(), scenarios.end(),
                                     [](const core::Scenario& sc) {
                                       return sc.target.empty() || !(sc.duration > 0.0);
                                     });
             bad != scenarios.end()) {
    why << "scenarios: '" << bad->name << "' has no target path or no duration";
  } else if (worlds.empty()) {
    why << "worlds must not be empty (forest, boxes, mixed, dynamic, clutter-dynamic, sixwall, sixwall-sliding, "
           "random)";
  } else if (target_speeds.empty()) {
    why << "target_speeds must not be empty";
  } else if (auto bad = std::find_if(target_speeds.begin(), target_speeds.end(),
                                     [](double v) { return !(v > 0.0 && v <= 20.0); });
             bad != target_speeds.end()) {
    why << "target_speeds (" << *bad << ") must be in (0, 20] m/s";
  } else if (!(duration > 0.0 && duration <= 36000.0)) {
    why << "duration (" << duration << ") must be in (0, 36000] seconds";
  } else if (label_every < 1) {
    why << "label_every (" << label_every << ") must be at least 1";
  } else if (episode.latency_ms && !(*episode.latency_ms < episode.planning_period * 1000.0)) {
    // Demonstrations label every planning cycle they are asked to: a latency of a period or more would skip
    // cycles, and the recorder's label_every would no longer count planning periods.
    why << "episode.latency_ms (" << *episode.latency_ms << ") must be below one planning period ("
        << episode.planning_period * 1000.0 << " ms) in demonstrations";
  } else if (driver.empty()) {
    why << "driver must be \"expert\" or a planner name";
  } else if (jobs < 1 || jobs > 4096) {
    why << "jobs (" << jobs << ") must be between 1 and 4096";
  } else if (shards < 1 || shard < 0 || shard >= shards) {
    why << "shard (" << shard << ") must be between 0 and shards - 1 (shards: " << shards << ", at least 1)";
  } else if (!expert.validate(&inner)) {
    why << "expert." << inner;
  } else if (!episode.validate(&inner)) {
    why << "episode." << inner;
  } else if (!(duration >= episode.planning_period)) {
    why << "duration (" << duration << ") must be at least one planning period (" << episode.planning_period
        << " s)";
  } else if (driver != "expert" && expert.perception.estimate_velocity &&
             label_every * episode.planning_period > expert.perception.max_scan_gap) {
    // A labelling expert that does not drive sees one scan in label_every; further apart than the gap, its
    // velocity tracks start over at every label and every obstacle reads as static.
    why << "label_every (" << label_every << ") x planning period (" << episode.planning_period
        << " s) must not exceed expert.perception.max_scan_gap (" << expert.perception.max_scan_gap
        << " s) when the expert does not drive: its velocity estimates would always be zero";
  }
  if (why.str().empty()) return true;
  if (error) *error = why.str();
  return false;
}

// ---------------------------------------------------------------------------------------------------------
// The recorder.

namespace {

json perception_json(const perception::Settings& p) {
  return json{{"voxel_size", p.voxel_size},
              {"cloud_size", p.cloud_size},
              {"nearest_count", p.nearest_count},
              {"estimate_velocity", p.estimate_velocity}};
}

std::string driver_text(const DemonstrationSettings& s) {
  if (s.driver == "expert" || s.model.empty()) return s.driver;
  return s.model;  // docs/learning.md: a learned driver is named by its model file
}

}  // namespace

bool learned_driver(const std::map<std::string, std::string>& metadata) {
  const auto it = metadata.find("driver");
  if (it == metadata.end() || it->second == "expert") return false;
  for (const policy::Variant v : {policy::Variant::cvae, policy::Variant::bc, policy::Variant::fixed_q})
    if (it->second == planners::learned_planner_name(v)) return true;
  const std::vector<std::string> planners = planners::planner_names();
  // Any other planner's name drove without learning; what is left is a model file (driver_text).
  return std::find(planners.begin(), planners.end(), it->second) == planners.end();
}

std::map<std::string, std::string> demonstration_metadata(const DemonstrationSettings& s) {
  json kinds = json::array();
  for (DemonstrationWorld w : s.worlds) kinds.push_back(to_string(w));
  const json expert{{"samples", s.expert.samples},
                    {"cem_iterations", s.expert.cem_iterations},
                    {"projection_iterations", s.expert.projection.iterations},
                    {"elite_fraction", s.expert.elite_fraction},
                    {"initial_std", s.expert.initial_std},
                    {"min_std", s.expert.min_std},
                    {"settle_distance", s.expert.settle_distance},
                    {"ranking",
                     {{"occlusion_weight", s.expert.ranking.occlusion_weight},
                      {"tracking_weight", s.expert.ranking.tracking_weight},
                      {"smoothness_weight", s.expert.ranking.smoothness_weight},
                      {"violation_weight", s.expert.ranking.violation_weight},
                      {"band", {s.expert.ranking.band.min, s.expert.ranking.band.reference, s.expert.ranking.band.max}}}}};
  // `jobs` is left out on purpose: it does not change the rows, and the file should not change with it.
  json generator{{"world_kinds", kinds},
                       {"target", to_string(s.target)},
                       {"first_seed", s.first_seed},
                       {"episodes", s.episodes},
                       {"duration", s.duration},
                       {"target_speeds", s.target_speeds},
                       {"label_every", s.label_every},
                       {"driver", s.driver},
                       {"model", s.model},
                       {"seeds", s.scenarios.empty()
                                     ? "episode i: world, target path, sensor noise and planners from first_seed + i; "
                                       "world kind worlds[i % W], target speed target_speeds[(i / W) % S]"
                                     : "episode i: scenarios[i % N]; sensor noise and planners from first_seed + i"},
                       {"physics_step", s.episode.physics_step},
                       {"planning_period", s.episode.planning_period},
                       {"robot_accel_max", s.episode.robot_accel_max},
                       {"latency_ms", s.episode.latency_ms ? json(*s.episode.latency_ms) : json(nullptr)},
                       {"tau", s.episode.tau},
                       {"beams", s.episode.beams ? json(*s.episode.beams) : json(nullptr)},
                       {"lidar_noise", s.episode.lidar_noise ? json(*s.episode.lidar_noise) : json(nullptr)},
                       {"target_noise", {s.episode.target_position_noise, s.episode.target_velocity_noise}},
                       {"driver_shield", s.driver != "expert" && s.driver_options.shield},
                       {"response_time", s.driver_options.response_time}};
  // Named only when given, so that a file of generated episodes keeps the bytes it had before the option; the
  // generated worlds' kinds, target model and speeds are then unused and left out, so that the provenance
  // says only what made the rows.
  if (!s.scenarios.empty()) {
    json names = json::array();
    for (const core::Scenario& sc : s.scenarios) names.push_back(sc.name);
    generator["scenarios"] = names;
    for (const char* unused : {"world_kinds", "target", "target_speeds"}) generator.erase(unused);
  }
  return {{"format", io::kDatasetFormat},
          {"projection", io::projection_settings_json(s.expert.projection)},
          {"perception", perception_json(s.expert.perception).dump()},
          {"expert", expert.dump()},
          {"driver", driver_text(s)},
          {"generator", generator.dump()},
          {"created_by", s.created_by}};
}

// ---------------------------------------------------------------------------------------------------------
// Generation.

namespace {

void append_rows(Demonstrations& d, const std::vector<DemonstrationRow>& rows, std::int32_t episode) {
  for (const DemonstrationRow& r : rows) {
    for (int j = 0; j < kObservationSize; ++j) d.observation.push_back(static_cast<float>(r.observation(j)));
    for (Eigen::Index i = 0; i < r.cloud.size(); ++i) d.cloud.push_back(static_cast<float>(r.cloud.data()[i]));
    for (Eigen::Index i = 0; i < r.obstacles.size(); ++i)
      d.obstacles.push_back(static_cast<float>(r.obstacles.data()[i]));
    for (Eigen::Index i = 0; i < r.expert_xi.size(); ++i) d.expert_xi.push_back(static_cast<float>(r.expert_xi(i)));
    d.expert_cost.push_back(static_cast<float>(r.expert_cost));
    d.episode.push_back(episode);
    d.time.push_back(static_cast<float>(r.time));
    ++d.rows;
  }
}

/// Appends rows [begin, end) of `from` to `into`.
void append_row_range(Demonstrations& into, const Demonstrations& from, std::int64_t begin, std::int64_t end) {
  auto copy = [&](auto& to, const auto& column, std::int64_t width) {
    to.insert(to.end(), column.begin() + begin * width, column.begin() + end * width);
  };
  copy(into.observation, from.observation, kObservationSize);
  copy(into.cloud, from.cloud, std::int64_t{2} * from.cloud_points);
  copy(into.obstacles, from.obstacles, std::int64_t{4} * from.nearest_points);
  copy(into.expert_xi, from.expert_xi, std::int64_t{2} * from.coefficients);
  copy(into.expert_cost, from.expert_cost, 1);
  copy(into.episode, from.episode, 1);
  copy(into.time, from.time, 1);
  into.rows += end - begin;
}

/// The one home of the file's row order: appends every row of `parts` to `into` ordered by episode, the rows
/// of an episode together and in their order. Each part must be ordered by episode, and no two parts may hold
/// the same episode (std::invalid_argument otherwise). Used with a part per episode (one process) and with a
/// part per shard; each part is freed as soon as its last row is copied.
void append_ordered_by_episode(Demonstrations& into, std::vector<Demonstrations>& parts) {
  struct Run {  // consecutive rows of one episode in one part
    std::int32_t episode;
    std::size_t part;
    std::int64_t begin, end;
  };
  std::vector<Run> runs;
  std::int64_t rows = 0;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const Demonstrations& p = parts[k];
    for (std::int64_t r = 0; r < p.rows;) {
      const auto at = [&](std::int64_t row) { return p.episode[static_cast<std::size_t>(row)]; };
      std::int64_t end = r + 1;
      while (end < p.rows && at(end) == at(r)) ++end;
      if (end < p.rows && at(end) < at(r))
        throw std::invalid_argument("demonstrations: part " + std::to_string(k) + " is not ordered by episode (row " +
                                    std::to_string(end) + ")");
      runs.push_back({at(r), k, r, end});
      r = end;
    }
    rows += p.rows;
  }
  std::stable_sort(runs.begin(), runs.end(), [](const Run& a, const Run& b) { return a.episode < b.episode; });
  for (std::size_t j = 1; j < runs.size(); ++j)
    if (runs[j].episode == runs[j - 1].episode)
      throw std::invalid_argument("demonstrations: episode " + std::to_string(runs[j].episode) + " is in parts " +
                                  std::to_string(runs[j - 1].part) + " and " + std::to_string(runs[j].part));
  const auto reserve = [&](auto& column, std::int64_t width) {
    column.reserve(column.size() + static_cast<std::size_t>(rows * width));
  };
  reserve(into.observation, kObservationSize);
  reserve(into.cloud, std::int64_t{2} * into.cloud_points);
  reserve(into.obstacles, std::int64_t{4} * into.nearest_points);
  reserve(into.expert_xi, std::int64_t{2} * into.coefficients);
  reserve(into.expert_cost, 1);
  reserve(into.episode, 1);
  reserve(into.time, 1);
  for (const Run& run : runs) {
    append_row_range(into, parts[run.part], run.begin, run.end);
    if (run.end == parts[run.part].rows) parts[run.part] = Demonstrations{};
  }
}

/// True when every column of `d` holds `rows` rows of its sizes.
bool columns_agree(const Demonstrations& d) {
  const auto holds = [&](const auto& column, std::int64_t width) {
    return static_cast<std::int64_t>(column.size()) == d.rows * width;
  };
  return d.rows >= 0 && holds(d.observation, kObservationSize) && holds(d.cloud, std::int64_t{2} * d.cloud_points) &&
         holds(d.obstacles, std::int64_t{4} * d.nearest_points) &&
         holds(d.expert_xi, std::int64_t{2} * d.coefficients) && holds(d.expert_cost, 1) && holds(d.episode, 1) &&
         holds(d.time, 1);
}

}  // namespace

void DemonstrationReport::add(const DemonstrationReport& other) {
  episodes += other.episodes;
  episodes_failed += other.episodes_failed;
  if (!other.failures.empty()) {
    failures.insert(failures.end(), other.failures.begin(), other.failures.end());
    std::sort(failures.begin(), failures.end());
  }
  cycles += other.cycles;
  labelled += other.labelled;
  rows += other.rows;
  skipped_failed += other.skipped_failed;
  skipped_nonfinite += other.skipped_nonfinite;
  expert_ms += other.expert_ms;
  seconds = std::max(seconds, other.seconds);
}

Demonstrations generate_demonstrations(const DemonstrationSettings& settings, DemonstrationReport* report_out,
                                       const std::function<void(const DemonstrationProgress&)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("demonstrations: " + error);
  const bool expert_drives = settings.driver == "expert";
  auto make_driver = [&](std::uint64_t seed) -> std::unique_ptr<planners::Planner> {
    if (expert_drives) return nullptr;
    planners::PlannerOptions options = settings.driver_options;
    options.seed = seed;
    options.threads = 1;
    options.model = settings.model;
    return planners::make_planner(settings.driver, options);
  };
  make_driver(settings.first_seed);  // refuse an unknown driver (or a bad model) before any episode runs

  // This shard's episodes: shard, shard + shards, ... (every episode in one process). `k` counts them; `i`,
  // an episode's index in the whole run, seeds it and labels its rows.
  const int total =
      settings.shard < settings.episodes ? 1 + (settings.episodes - 1 - settings.shard) / settings.shards : 0;
  const auto episode_index = [&](int k) { return settings.shard + k * settings.shards; };
  const int W = static_cast<int>(settings.worlds.size());
  const int S = static_cast<int>(settings.target_speeds.size());
  // Each finished episode's rows, already in float32 (half the memory of DemonstrationRow).
  std::vector<Demonstrations> episodes(static_cast<std::size_t>(total));
  std::vector<double> fraction(static_cast<std::size_t>(total), 0.0);
  std::vector<std::int64_t> live_rows(static_cast<std::size_t>(total), 0);
  DemonstrationReport report;
  std::mutex lock;
  std::atomic<int> next{0};
  std::atomic<bool> stop{false};
  std::string fatal;
  int done = 0;

  auto notify = [&]() {  // with `lock` held
    if (!progress) return;
    DemonstrationProgress p;
    p.episodes_done = done;
    p.episodes_total = total;
    double sum = 0.0;
    for (double f : fraction) sum += f;
    // 100% only once every episode is done (an episode reports 1.0 before its rows are collected).
    p.fraction = done < total ? std::min(sum / total, 0.99) : 1.0;
    for (std::int64_t r : live_rows) p.rows += r;
    p.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress(p);
  };

  auto worker = [&]() {
    for (int k = next++; k < total && !stop; k = next++) {
      const int i = episode_index(k);
      const std::uint64_t seed = demonstration_seed(settings, i);
      const DemonstrationWorld kind = settings.worlds[static_cast<std::size_t>(i % W)];
      const double speed = settings.target_speeds[static_cast<std::size_t>((i / W) % S)];
      const std::size_t N = settings.scenarios.size();
      const core::Scenario* given = N == 0 ? nullptr : &settings.scenarios[static_cast<std::size_t>(i) % N];
      const std::string name =
          std::string("demo-") + (given ? given->name : std::string(to_string(kind))) + "-" + std::to_string(seed);
      try {
        core::Scenario scenario;
        try {
          if (given) {
            scenario = *given;
            scenario.name = name;
            scenario.duration = std::min(scenario.duration, settings.duration);
          } else {
            scenario = demonstration_scenario(settings, kind, speed, seed, name);
          }
        } catch (const std::runtime_error& e) {  // the generator could not place obstacles or a path: skip
          const std::lock_guard<std::mutex> guard(lock);
          ++report.episodes_failed;
          report.failures.push_back(name + " (seed " + std::to_string(seed) + "): " + e.what());
          fraction[static_cast<std::size_t>(k)] = 1.0;
          ++done;
          notify();
          continue;
        }
        planners::ProjCemSettings expert_settings = settings.expert;
        expert_settings.seed = seed;
        if (expert_drives) expert_settings.response_time = planners::command_lead(settings.driver_options);
        DemonstrationRecorder recorder(std::make_unique<planners::ProjCem>(expert_settings), make_driver(seed),
                                       settings.label_every);
        EpisodeSettings episode = settings.episode;
        episode.seed = seed;
        episode.snapshots = 0;
        episode.trace_stride = std::numeric_limits<int>::max();
        run_episode(scenario, recorder, episode, [&](double f) {
          const std::lock_guard<std::mutex> guard(lock);
          fraction[static_cast<std::size_t>(k)] = std::min(1.0, f);
          live_rows[static_cast<std::size_t>(k)] = static_cast<std::int64_t>(recorder.rows().size());
          notify();
        });
        Demonstrations block;
        append_rows(block, recorder.take_rows(), i);
        const std::lock_guard<std::mutex> guard(lock);
        live_rows[static_cast<std::size_t>(k)] = block.rows;
        episodes[static_cast<std::size_t>(k)] = std::move(block);
        report.add(recorder.report());
        ++report.episodes;
        fraction[static_cast<std::size_t>(k)] = 1.0;
        ++done;
        notify();
      } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> guard(lock);
        if (fatal.empty()) fatal = name + " (seed " + std::to_string(seed) + "): " + e.what();
        stop = true;
      }
    }
  };
  const int jobs = std::min(settings.jobs, total);
  if (jobs <= 1) {
    worker();
  } else {
    std::vector<std::thread> threads;
    for (int j = 0; j < jobs; ++j) threads.emplace_back(worker);
    for (std::thread& t : threads) t.join();
  }
  if (!fatal.empty()) throw std::runtime_error("demonstrations: " + fatal);

  Demonstrations data;
  data.cloud_points = settings.expert.perception.cloud_size;
  data.nearest_points = settings.expert.perception.nearest_count;
  data.coefficients = settings.expert.projection.coefficients();
  data.metadata = demonstration_metadata(settings);
  append_ordered_by_episode(data, episodes);  // whatever order the threads finished in
  data.metadata["rows"] = std::to_string(data.rows);
  std::sort(report.failures.begin(), report.failures.end());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (report_out) *report_out = report;
  return data;
}

Demonstrations interleave_demonstration_shards(std::vector<Demonstrations> parts) {
  const char* const who = "interleave_demonstration_shards: ";
  if (parts.empty()) throw std::invalid_argument(std::string(who) + "no part");
  const Demonstrations& first = parts.front();
  Demonstrations data;
  data.cloud_points = first.cloud_points;
  data.nearest_points = first.nearest_points;
  data.coefficients = first.coefficients;
  data.metadata = first.metadata;
  data.metadata.erase("rows");
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const Demonstrations& p = parts[k];
    const std::string part = "part " + std::to_string(k);
    if (p.cloud_points != data.cloud_points || p.nearest_points != data.nearest_points ||
        p.coefficients != data.coefficients)
      throw std::invalid_argument(who + part +
                                  ": sizes (cloud points, nearest points, coefficients) differ from part 0's");
    if (!columns_agree(p)) throw std::invalid_argument(who + part + ": a column does not hold `rows` rows");
    std::map<std::string, std::string> metadata = p.metadata;
    metadata.erase("rows");
    if (metadata != data.metadata) {
      std::string key;  // the first that differs
      for (const auto& [name, value] : metadata)
        if (auto it = data.metadata.find(name); it == data.metadata.end() || it->second != value) {
          key = name;
          break;
        }
      for (const auto& [name, value] : data.metadata)
        if (key.empty() && metadata.count(name) == 0) key = name;
      throw std::invalid_argument(who + part + ": metadata '" + key + "' differs from part 0's");
    }
  }
  append_ordered_by_episode(data, parts);
  data.metadata["rows"] = std::to_string(data.rows);
  return data;
}

}  // namespace occtrack::sim
