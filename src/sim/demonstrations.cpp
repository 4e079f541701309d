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

#include "occtrack/io/error.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/sim/scenario_generator.hpp"

namespace occtrack::sim {

using nlohmann::json;

// ---------------------------------------------------------------------------------------------------------
// World kinds and settings.

const char* to_string(DemonstrationWorld world) {
  switch (world) {
    case DemonstrationWorld::forest: return "forest";
    case DemonstrationWorld::boxes: return "boxes";
    case DemonstrationWorld::mixed: return "mixed";
    case DemonstrationWorld::dynamic: return "dynamic";
  }
  return "?";
}

std::optional<DemonstrationWorld> parse_demonstration_world(std::string_view text) {
  if (text == "forest") return DemonstrationWorld::forest;
  if (text == "boxes") return DemonstrationWorld::boxes;
  if (text == "mixed") return DemonstrationWorld::mixed;
  if (text == "dynamic") return DemonstrationWorld::dynamic;
  return std::nullopt;
}

namespace {

// Appends every row of `from` to `into`, its episode numbers shifted by `episode_offset`.
void append_rows(Demonstrations& into, const Demonstrations& from, std::int32_t episode_offset) {
  auto cat = [](auto& a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); };
  cat(into.observation, from.observation);
  cat(into.cloud, from.cloud);
  cat(into.obstacles, from.obstacles);
  cat(into.expert_xi, from.expert_xi);
  cat(into.expert_cost, from.expert_cost);
  cat(into.time, from.time);
  for (std::int32_t e : from.episode) into.episode.push_back(e + episode_offset);
  into.rows += from.rows;
}

/// The benchmark's world settings of a kind (their seeds are not used): the static suites' forest, boxes and
/// mixed worlds, and the dynamic suite's world with moving obstacles.
GeneratorSettings world_settings(DemonstrationWorld world) {
  const bool dynamic = world == DemonstrationWorld::dynamic;
  const std::optional<SuiteSpec> suite = find_suite(dynamic ? "dynamic-1.5ms" : "static-1ms");
  if (!suite || suite->worlds.empty()) throw std::logic_error("demonstrations: benchmark suites are missing");
  if (dynamic) return suite->worlds.front().settings;
  const WorldKind kind = world == DemonstrationWorld::forest  ? WorldKind::forest
                         : world == DemonstrationWorld::boxes ? WorldKind::boxes
                                                              : WorldKind::mixed;
  for (const SuiteWorld& w : suite->worlds)
    if (w.settings.style.kind == kind) return w.settings;
  throw std::logic_error("demonstrations: no benchmark world of this kind");
}

/// The benchmark suite's target settings for the world, at another top speed and duration.
TargetSettings target_settings(DemonstrationWorld world, double max_speed, double duration) {
  const std::optional<SuiteSpec> suite =
      find_suite(world == DemonstrationWorld::dynamic ? "dynamic-1.5ms" : "static-1ms");
  if (!suite) throw std::logic_error("demonstrations: benchmark suites are missing");
  TargetSettings t = suite->target;
  t.max_speed = max_speed;
  t.min_speed = std::min(t.min_speed, max_speed);
  t.duration = duration;
  return t;
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
  } else if (worlds.empty()) {
    why << "worlds must not be empty (forest, boxes, mixed, dynamic)";
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
  } else if (driver.empty()) {
    why << "driver must be \"expert\" or a planner name";
  } else if (jobs < 1 || jobs > 4096) {
    why << "jobs (" << jobs << ") must be between 1 and 4096";
  } else if (expert.samples < 4) {
    why << "expert.samples (" << expert.samples << ") must be at least 4";
  } else if (expert.cem_iterations < 1) {
    why << "expert.cem_iterations (" << expert.cem_iterations << ") must be at least 1";
  } else if (!(expert.elite_fraction > 0.0 && expert.elite_fraction <= 1.0)) {
    why << "expert.elite_fraction (" << expert.elite_fraction << ") must be in (0, 1]";
  } else if (!expert.projection.validate(&inner)) {
    why << "expert.projection." << inner;
  } else if (!expert.perception.validate(&inner)) {
    why << "expert.perception." << inner;
  } else if (expert.perception.nearest_count != expert.projection.obstacles) {
    why << "expert.perception.nearest_count (" << expert.perception.nearest_count
        << ") must equal expert.projection.obstacles (" << expert.projection.obstacles << ")";
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

Eigen::RowVectorXd fit_with(const Eigen::MatrixXd& P, const Eigen::MatrixXd& least_squares,
                            const std::vector<core::Vec2>& positions, const core::Vec2& origin, double* residual) {
  const Eigen::Index m = P.rows(), n = P.cols();
  Eigen::MatrixX2d relative(m, 2);
  for (Eigen::Index k = 0; k < m; ++k) relative.row(k) = (positions[static_cast<std::size_t>(k)] - origin).transpose();
  const Eigen::MatrixX2d coefficients = least_squares * relative;  // n x 2
  Eigen::RowVectorXd xi(2 * n);
  xi.head(n) = coefficients.col(0).transpose();
  xi.tail(n) = coefficients.col(1).transpose();
  if (residual) {
    const double worst = (P * coefficients - relative).cwiseAbs().maxCoeff();
    *residual = std::isfinite(worst) ? worst : INFINITY;
  }
  return xi;
}

}  // namespace

Eigen::RowVectorXd fit_coefficients(const core::BernsteinBasis& basis, const std::vector<core::Vec2>& positions,
                                    const core::Vec2& origin, double* residual) {
  if (static_cast<int>(positions.size()) != basis.steps)
    throw std::invalid_argument("fit_coefficients: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(basis.steps) + " steps");
  const Eigen::MatrixXd least_squares = basis.P.completeOrthogonalDecomposition().pseudoInverse();
  return fit_with(basis.P, least_squares, positions, origin, residual);
}

DemonstrationRecorder::DemonstrationRecorder(std::unique_ptr<planners::Planner> expert,
                                             std::unique_ptr<planners::Planner> driver,
                                             const planners::ProjCemSettings& expert_settings, int label_every)
    : expert_(std::move(expert)),
      driver_(std::move(driver)),
      settings_(expert_settings),
      label_every_(label_every),
      perception_(expert_settings.perception),
      ranking_(expert_settings.ranking, expert_settings.projection) {
  if (!expert_) throw std::invalid_argument("DemonstrationRecorder: no expert");
  if (label_every < 1) throw std::invalid_argument("DemonstrationRecorder: label_every must be at least 1");
  least_squares_ = ranking_.basis().P.completeOrthogonalDecomposition().pseudoInverse();
}

DemonstrationRecorder::~DemonstrationRecorder() = default;

std::string DemonstrationRecorder::name() const { return driver_ ? driver_->name() : expert_->name(); }

void DemonstrationRecorder::reset() {
  expert_->reset();
  if (driver_) driver_->reset();
  perception_.reset();
  cycle_ = 0;
}

planners::PlannerOutput DemonstrationRecorder::plan(const planners::PlannerInput& input) {
  const bool label = cycle_ % label_every_ == 0;
  ++cycle_;
  ++report_.cycles;
  if (!driver_ || label) {
    // The recorder's perception sees exactly the scans the expert's sees, after the same checks as the
    // planners' (planners/context.cpp, observe), so that their velocity tracks stay identical.
    bool observed = false;
    if (input.scan != nullptr && input.robot_position.allFinite() && input.robot_velocity.allFinite() &&
        input.target_position.allFinite() && input.target_velocity.allFinite())
      observed = perception_.process(*input.scan, input.robot_position, observation_);
    const auto start = std::chrono::steady_clock::now();
    planners::PlannerOutput expert_output = expert_->plan(input);
    report_.expert_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (label) {
      ++report_.labelled;
      if (observed)
        record(input, expert_output);
      else
        ++report_.skipped_failed;
    }
    if (!driver_) return expert_output;
  }
  return driver_->plan(input);
}

bool DemonstrationRecorder::record(const planners::PlannerInput& input, const planners::PlannerOutput& out) {
  if (!out.ok) {
    ++report_.skipped_failed;
    return false;
  }
  const core::BernsteinBasis& basis = ranking_.basis();
  bool finite = static_cast<int>(out.plan.size()) == basis.steps;
  for (std::size_t k = 0; finite && k < out.plan.size(); ++k) finite = out.plan[k].allFinite();
  if (!finite) {
    ++report_.skipped_nonfinite;
    return false;
  }
  DemonstrationRow row;
  row.expert_xi = fit_with(basis.P, least_squares_, out.plan, input.robot_position, &row.fit_residual);
  if (!row.expert_xi.allFinite()) {
    ++report_.skipped_nonfinite;
    return false;
  }
  if (!(row.fit_residual <= kPlanFitTolerance)) {
    ++report_.skipped_fit;
    return false;
  }
  // The frame the expert ranked in (planners/context.cpp, observe): the target predicted linearly, the nearest
  // points as obstacles, every distinct cloud point as a possible occluder.
  Eigen::Vector4d target;
  target << input.target_position - input.robot_position, input.target_velocity;
  const int distinct = std::min<int>(observation_.voxels, static_cast<int>(observation_.cloud.rows()));
  const int near = std::min<int>(distinct, static_cast<int>(observation_.nearest.rows()));
  planners::PointRows occluders(distinct, 4);
  occluders.topRows(near) = observation_.nearest.topRows(near);
  for (int i = near; i < distinct; ++i) occluders.row(i) << observation_.cloud(i, 0), observation_.cloud(i, 1), 0, 0;
  row.expert_cost = ranking_.evaluate(row.expert_xi, target, observation_.nearest, occluders).total;
  if (!std::isfinite(row.expert_cost)) {
    ++report_.skipped_nonfinite;
    return false;
  }
  row.observation << input.robot_velocity, input.target_position - input.robot_position, input.target_velocity;
  row.cloud = observation_.cloud;
  row.obstacles = observation_.nearest;
  row.time = input.time;
  if (!row.observation.allFinite()) {
    ++report_.skipped_nonfinite;
    return false;
  }
  report_.worst_fit_residual = std::max(report_.worst_fit_residual, row.fit_residual);
  ++report_.rows;
  rows_.push_back(std::move(row));
  return true;
}

// ---------------------------------------------------------------------------------------------------------
// Metadata.

namespace {

json projection_json(const projection::Settings& p) { return json::parse(io::projection_settings_json(p)); }

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

std::map<std::string, std::string> demonstration_metadata(const DemonstrationSettings& s) {
  json kinds = json::array();
  for (DemonstrationWorld w : s.worlds) kinds.push_back(to_string(w));
  const json expert{{"samples", s.expert.samples},
                    {"cem_iterations", s.expert.cem_iterations},
                    {"projection_iterations", s.expert.projection.iterations},
                    {"elite_fraction", s.expert.elite_fraction},
                    {"initial_std", s.expert.initial_std},
                    {"min_std", s.expert.min_std},
                    {"ranking",
                     {{"occlusion_weight", s.expert.ranking.occlusion_weight},
                      {"tracking_weight", s.expert.ranking.tracking_weight},
                      {"smoothness_weight", s.expert.ranking.smoothness_weight},
                      {"violation_weight", s.expert.ranking.violation_weight},
                      {"band", {s.expert.ranking.band.min, s.expert.ranking.band.reference, s.expert.ranking.band.max}}}}};
  // `jobs` is left out on purpose: it does not change the rows, and the file should not change with it.
  const json generator{{"world_kinds", kinds},
                       {"first_seed", s.first_seed},
                       {"episodes", s.episodes},
                       {"duration", s.duration},
                       {"target_speeds", s.target_speeds},
                       {"label_every", s.label_every},
                       {"driver", s.driver},
                       {"model", s.model},
                       {"seeds", "episode i: world, target path, sensor noise and planners from first_seed + i; "
                                 "world kind worlds[i % W], target speed target_speeds[(i / W) % S]"},
                       {"physics_step", s.episode.physics_step},
                       {"planning_period", s.episode.planning_period},
                       {"robot_accel_max", s.episode.robot_accel_max}};
  return {{"format", kDatasetFormat},
          {"projection", projection_json(s.expert.projection).dump()},
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

void add_counts(DemonstrationReport& total, const DemonstrationReport& part) {
  total.cycles += part.cycles;
  total.labelled += part.labelled;
  total.rows += part.rows;
  total.skipped_failed += part.skipped_failed;
  total.skipped_nonfinite += part.skipped_nonfinite;
  total.skipped_fit += part.skipped_fit;
  total.worst_fit_residual = std::max(total.worst_fit_residual, part.worst_fit_residual);
  total.expert_ms += part.expert_ms;
}

}  // namespace

Demonstrations generate_demonstrations(const DemonstrationSettings& settings, DemonstrationReport* report_out,
                                       const std::function<void(const DemonstrationProgress&)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("demonstrations: " + error);
  const bool expert_drives = settings.driver == "expert";
  auto make_driver = [&](std::uint64_t seed) -> std::unique_ptr<planners::Planner> {
    if (expert_drives) return nullptr;
    planners::PlannerOptions options;
    options.seed = seed;
    options.threads = 1;
    options.model = settings.model;
    return planners::make_planner(settings.driver, options);
  };
  make_driver(settings.first_seed);  // refuse an unknown driver (or a bad model) before any episode runs

  const int total = settings.episodes;
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
    for (int i = next++; i < total && !stop; i = next++) {
      const std::uint64_t seed = demonstration_seed(settings, i);
      const DemonstrationWorld kind = settings.worlds[static_cast<std::size_t>(i % W)];
      const double speed = settings.target_speeds[static_cast<std::size_t>((i / W) % S)];
      const std::string name = std::string("demo-") + to_string(kind) + "-" + std::to_string(seed);
      try {
        core::Scenario scenario;
        try {
          const core::Scenario world = generate_world(world_settings(kind), seed);
          scenario = generate_episode(world, target_settings(kind, speed, settings.duration), seed, name);
        } catch (const std::runtime_error& e) {  // the generator could not place obstacles or a path: skip
          const std::lock_guard<std::mutex> guard(lock);
          ++report.episodes_failed;
          report.failures.push_back(name + " (seed " + std::to_string(seed) + "): " + e.what());
          fraction[static_cast<std::size_t>(i)] = 1.0;
          ++done;
          notify();
          continue;
        }
        planners::ProjCemSettings expert_settings = settings.expert;
        expert_settings.seed = seed;
        DemonstrationRecorder recorder(std::make_unique<planners::ProjCem>(expert_settings), make_driver(seed),
                                       expert_settings, settings.label_every);
        EpisodeSettings episode = settings.episode;
        episode.seed = seed;
        episode.snapshots = 0;
        episode.trace_stride = std::numeric_limits<int>::max();
        run_episode(scenario, recorder, episode, [&](double f) {
          const std::lock_guard<std::mutex> guard(lock);
          fraction[static_cast<std::size_t>(i)] = std::min(1.0, f);
          live_rows[static_cast<std::size_t>(i)] = static_cast<std::int64_t>(recorder.rows().size());
          notify();
        });
        Demonstrations block;
        append_rows(block, recorder.take_rows(), i);
        const std::lock_guard<std::mutex> guard(lock);
        live_rows[static_cast<std::size_t>(i)] = block.rows;
        episodes[static_cast<std::size_t>(i)] = std::move(block);
        add_counts(report, recorder.report());
        ++report.episodes;
        fraction[static_cast<std::size_t>(i)] = 1.0;
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
  std::int64_t rows = 0;
  for (const Demonstrations& e : episodes) rows += e.rows;
  data.observation.reserve(static_cast<std::size_t>(rows * kObservationSize));
  data.cloud.reserve(static_cast<std::size_t>(rows * data.cloud_points * 2));
  data.obstacles.reserve(static_cast<std::size_t>(rows * data.nearest_points * 4));
  data.expert_xi.reserve(static_cast<std::size_t>(rows * data.coefficients * 2));
  data.expert_cost.reserve(static_cast<std::size_t>(rows));
  data.episode.reserve(static_cast<std::size_t>(rows));
  data.time.reserve(static_cast<std::size_t>(rows));
  for (Demonstrations& e : episodes) {  // ordered by episode, whatever order the threads finished in
    append_rows(data, e, 0);
    e = Demonstrations{};  // free each episode's buffers as soon as they are copied
  }
  data.metadata["rows"] = std::to_string(data.rows);
  std::sort(report.failures.begin(), report.failures.end());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (report_out) *report_out = report;
  return data;
}

// ---------------------------------------------------------------------------------------------------------
// Files.

namespace {

std::int64_t checked_size(const std::vector<float>& v, std::int64_t expected, const char* name) {
  if (static_cast<std::int64_t>(v.size()) != expected)
    throw std::invalid_argument(std::string("demonstrations: ") + name + " holds " + std::to_string(v.size()) +
                                " values, expected " + std::to_string(expected));
  return expected;
}

std::string source_of(const io::TensorFile& file) { return file.source.empty() ? "dataset" : file.source; }

json parse_meta_json(const io::TensorFile& file, const std::string& key) {
  const std::string& text = file.meta(key);
  try {
    json value = json::parse(text);
    if (!value.is_object()) throw io::InputError(source_of(file) + ": metadata '" + key + "' is not a JSON object");
    return value;
  } catch (const json::exception& e) {
    throw io::InputError(source_of(file) + ": metadata '" + key + "' is not valid JSON (" + e.what() + ")");
  }
}

int meta_int(const io::TensorFile& file, const json& object, const std::string& key, const std::string& field) {
  if (!object.contains(field) || !object.at(field).is_number_integer())
    throw io::InputError(source_of(file) + ": metadata '" + key + "': '" + field + "' must be an integer");
  return object.at(field).get<int>();
}

double meta_number(const io::TensorFile& file, const json& object, const std::string& key, const std::string& field) {
  if (!object.contains(field) || !object.at(field).is_number())
    throw io::InputError(source_of(file) + ": metadata '" + key + "': '" + field + "' must be a number");
  return object.at(field).get<double>();
}

std::vector<float> float_tensor(const io::TensorFile& file, const std::string& name,
                                const std::vector<std::int64_t>& shape) {
  const io::Tensor& t = file.at(name, shape);
  if (t.dtype != io::DType::F32)
    throw io::InputError(source_of(file) + ": tensor '" + name + "' has dtype " + io::dtype_name(t.dtype) +
                         ", expected F32");
  std::vector<float> values = t.as_float();
  const auto bad = std::find_if(values.begin(), values.end(), [](float v) { return !std::isfinite(v); });
  if (bad != values.end()) {
    const std::int64_t index = bad - values.begin();
    const std::int64_t per_row = shape.empty() || shape[0] == 0 ? 1 : static_cast<std::int64_t>(values.size()) / shape[0];
    throw io::InputError(source_of(file) + ": tensor '" + name + "' holds a non-finite value in row " +
                         std::to_string(index / per_row));
  }
  return values;
}

}  // namespace

io::TensorFile to_tensor_file(const Demonstrations& d) {
  const std::int64_t S = d.rows, C = d.cloud_points, N = d.nearest_points, n = d.coefficients;
  if (S < 0 || C < 1 || N < 0 || n < 1) throw std::invalid_argument("demonstrations: negative or zero sizes");
  io::TensorFile file;
  file.metadata = d.metadata;
  file.metadata["format"] = kDatasetFormat;
  file.metadata["rows"] = std::to_string(S);
  checked_size(d.observation, S * kObservationSize, "observation");
  checked_size(d.cloud, S * C * 2, "cloud");
  checked_size(d.obstacles, S * N * 4, "obstacles");
  checked_size(d.expert_xi, S * 2 * n, "expert_xi");
  checked_size(d.expert_cost, S, "expert_cost");
  checked_size(d.time, S, "time");
  if (static_cast<std::int64_t>(d.episode.size()) != S)
    throw std::invalid_argument("demonstrations: episode holds " + std::to_string(d.episode.size()) +
                                " values, expected " + std::to_string(S));
  file.put("observation", {S, kObservationSize}, d.observation);
  file.put("cloud", {S, C, 2}, d.cloud);
  file.put("obstacles", {S, N, 4}, d.obstacles);
  file.put("expert_xi", {S, 2 * n}, d.expert_xi);
  file.put("expert_cost", {S}, d.expert_cost);
  file.put("episode", {S}, d.episode);
  file.put("time", {S}, d.time);
  return file;
}

Demonstrations from_tensor_file(const io::TensorFile& file) {
  const std::string source = source_of(file);
  const std::string& format = file.meta("format");
  if (format != kDatasetFormat)
    throw io::InputError(source + ": metadata 'format' is '" + format + "', expected '" + kDatasetFormat + "'");
  Demonstrations d;
  d.metadata = file.metadata;
  const json perception = parse_meta_json(file, "perception");
  const json projection = parse_meta_json(file, "projection");
  d.cloud_points = meta_int(file, perception, "perception", "cloud_size");
  d.nearest_points = meta_int(file, perception, "perception", "nearest_count");
  d.coefficients = meta_int(file, projection, "projection", "degree") + 1;
  if (d.cloud_points < 1 || d.nearest_points < 0 || d.coefficients < 2)
    throw io::InputError(source + ": metadata sizes out of range (cloud_size " + std::to_string(d.cloud_points) +
                         ", nearest_count " + std::to_string(d.nearest_points) + ", degree " +
                         std::to_string(d.coefficients - 1) + ")");
  const std::string& rows_text = file.meta("rows");
  std::int64_t rows = -1;
  try {
    std::size_t used = 0;
    rows = std::stoll(rows_text, &used);
    if (used != rows_text.size()) rows = -1;
  } catch (const std::exception&) {
    rows = -1;
  }
  if (rows < 0) throw io::InputError(source + ": metadata 'rows' ('" + rows_text + "') is not a row count");
  d.rows = rows;
  const std::int64_t S = rows, C = d.cloud_points, N = d.nearest_points, n = d.coefficients;
  d.observation = float_tensor(file, "observation", {S, kObservationSize});
  d.cloud = float_tensor(file, "cloud", {S, C, 2});
  d.obstacles = float_tensor(file, "obstacles", {S, N, 4});
  d.expert_xi = float_tensor(file, "expert_xi", {S, 2 * n});
  d.expert_cost = float_tensor(file, "expert_cost", {S});
  d.time = float_tensor(file, "time", {S});
  const io::Tensor& episode = file.at("episode", {S});
  if (episode.dtype != io::DType::I32)
    throw io::InputError(source + ": tensor 'episode' has dtype " + io::dtype_name(episode.dtype) +
                         ", expected I32");
  d.episode.resize(static_cast<std::size_t>(S));
  for (std::int64_t i = 0; i < S; ++i) {  // little-endian int32, as stored
    const unsigned char* b = episode.bytes.data() + 4 * i;
    d.episode[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(
        static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
        static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24);
  }
  return d;
}

void write_demonstrations(const std::string& path, const Demonstrations& data) {
  io::write_safetensors(path, to_tensor_file(data));
}

Demonstrations read_demonstrations(const std::string& path) {
  io::TensorFile file = io::read_safetensors(path);
  if (file.source.empty()) file.source = path;
  return from_tensor_file(file);
}

void append_demonstrations(Demonstrations& into, const Demonstrations& more) {
  if (into.rows == 0 && into.metadata.empty()) {
    into = more;
    return;
  }
  if (into.cloud_points != more.cloud_points || into.nearest_points != more.nearest_points ||
      into.coefficients != more.coefficients)
    throw std::invalid_argument("append_demonstrations: sizes differ (cloud points, nearest points, coefficients)");
  for (const char* key : {"projection", "perception"}) {
    const auto a = into.metadata.find(key);
    const auto b = more.metadata.find(key);
    const std::string left = a == into.metadata.end() ? "" : a->second;
    const std::string right = b == more.metadata.end() ? "" : b->second;
    if (left != right)
      throw std::invalid_argument(std::string("append_demonstrations: metadata '") + key + "' differs: " + left +
                                  " vs " + right);
  }
  std::int32_t offset = 0;
  for (std::int32_t e : into.episode) offset = std::max(offset, e + 1);
  append_rows(into, more, offset);
  into.metadata["rows"] = std::to_string(into.rows);
}

// ---------------------------------------------------------------------------------------------------------
// Statistics.

DemonstrationStatistics demonstration_statistics(const Demonstrations& d) {
  io::TensorFile meta;
  meta.source = "dataset";
  meta.metadata = d.metadata;
  const json projection = parse_meta_json(meta, "projection");
  const int degree = meta_int(meta, projection, "projection", "degree");
  const int steps = meta_int(meta, projection, "projection", "steps");
  const double horizon = meta_number(meta, projection, "projection", "horizon");
  if (degree + 1 != d.coefficients)
    throw io::InputError("dataset: metadata 'projection': degree + 1 differs from the coefficients of expert_xi");
  core::BernsteinBasis basis;
  try {
    basis = core::bernstein_basis(degree, steps, horizon);
  } catch (const std::invalid_argument& e) {
    throw io::InputError(std::string("dataset: metadata 'projection': ") + e.what());
  }
  const int n = d.coefficients;
  const int first_steps = std::max(1, std::min(steps - 1, static_cast<int>(std::lround(0.1 / horizon * (steps - 1)))));

  DemonstrationStatistics s;
  s.rows = d.rows;
  s.episodes = static_cast<int>(std::set<std::int32_t>(d.episode.begin(), d.episode.end()).size());
  if (d.rows == 0) return s;
  const double S = static_cast<double>(d.rows);
  Eigen::Matrix<double, kObservationSize, 1> sum = decltype(sum)::Zero(), sum2 = decltype(sum)::Zero();
  double speed_sum = 0, speed_sum2 = 0, start_sum = 0, cost_sum = 0, cost_sum2 = 0, distance_sum = 0;
  s.cost_min = INFINITY;
  s.cost_max = -INFINITY;
  Eigen::VectorXd cx(n), cy(n);
  for (std::int64_t r = 0; r < d.rows; ++r) {
    for (int j = 0; j < kObservationSize; ++j) {
      const double v = d.observation[static_cast<std::size_t>(r * kObservationSize + j)];
      sum(j) += v;
      sum2(j) += v * v;
    }
    distance_sum += std::hypot(d.observation[static_cast<std::size_t>(r * kObservationSize + 2)],
                               d.observation[static_cast<std::size_t>(r * kObservationSize + 3)]);
    for (int i = 0; i < n; ++i) {
      cx(i) = d.expert_xi[static_cast<std::size_t>(r * 2 * n + i)];
      cy(i) = d.expert_xi[static_cast<std::size_t>(r * 2 * n + n + i)];
    }
    const Eigen::VectorXd speed = ((basis.Pd * cx).array().square() + (basis.Pd * cy).array().square()).sqrt();
    const double mean_speed = speed.mean();
    speed_sum += mean_speed;
    speed_sum2 += mean_speed * mean_speed;
    s.plan_speed_max = std::max(s.plan_speed_max, speed.maxCoeff());
    const Eigen::Vector2d start((basis.P.row(first_steps) - basis.P.row(0)).dot(cx),
                                (basis.P.row(first_steps) - basis.P.row(0)).dot(cy));
    start_sum += start.norm() / basis.times(first_steps);
    const double c = d.expert_cost[static_cast<std::size_t>(r)];
    cost_sum += c;
    cost_sum2 += c * c;
    s.cost_min = std::min(s.cost_min, c);
    s.cost_max = std::max(s.cost_max, c);
  }
  auto spread = [&](double total, double total2) { return std::sqrt(std::max(0.0, total2 / S - (total / S) * (total / S))); };
  s.observation_mean = sum / S;
  for (int j = 0; j < kObservationSize; ++j) s.observation_std(j) = spread(sum(j), sum2(j));
  s.plan_speed_mean = speed_sum / S;
  s.plan_speed_std = spread(speed_sum, speed_sum2);
  s.start_speed_mean = start_sum / S;
  s.cost_mean = cost_sum / S;
  s.cost_std = spread(cost_sum, cost_sum2);
  s.target_distance_mean = distance_sum / S;
  return s;
}

}  // namespace occtrack::sim
