// Demonstrations for training (shared/spec/policy.md, "The expert"; docs/learning.md, "Dataset file"):
// closed-loop episodes on generated worlds whose seeds are disjoint from the benchmark's, in which the
// offline Proj-CEM expert labels planning cycles. Either the expert drives, or another planner drives
// (online Proj-CEM, or a learned policy for DAgger) while the expert labels what it sees.
//
// Settings, generate, write; read back, one file at a time:
//
//   sim::DemonstrationSettings settings;            // 8 episodes from seed 5000, the offline expert drives
//   settings.jobs = 16;
//   sim::DemonstrationReport report;
//   sim::Demonstrations data = sim::generate_demonstrations(settings, &report);   // throws invalid_argument
//   io::write_dataset_file("demo.safetensors", data);
//   sim::Demonstrations back = io::read_dataset_file("demo.safetensors");        // throws io::InputError
//
// One row per labelled planning cycle, taken from the expert's own record of that cycle
// (planners::Planner::last_record(): nothing is perceived, fitted or ranked a second time). What a row holds,
// all robot-centric (the robot at the origin, axes parallel to the world's) and exactly as the expert saw it:
//   observation  robot velocity, target position minus robot position, target velocity (the frame's);
//   cloud        the C x 2 fixed cloud of the expert's perception;
//   obstacles    the N x 4 nearest points (x, y, vx, vy) the expert's optimizer avoided;
//   expert_xi    the coefficients (x then y) of the plan the expert chose;
//   expert_cost  the ranking cost the expert chose it by (with the scan's shadow term, as it ranked);
//   episode      the episode index within the file; time: the simulated time of the cycle.
// Cycles where the expert fails (ok = false, or no valid record) or whose numbers are not finite are skipped
// and counted in DemonstrationReport.
//
// Determinism: every episode is a pure function of the settings and its index (world, target path, sensor
// noise and both planners are seeded from first_seed + index), and rows are ordered by episode, so the same
// settings give the same bytes whatever `jobs` is, and whatever the number of processes that share the run
// (`shard` of `shards`, then interleave_demonstration_shards).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "occtrack/core/bernstein.hpp"
#include "occtrack/io/dataset_file.hpp"
#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/proj_cem.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/sim/episode.hpp"

namespace occtrack::sim {

/// Columns of `observation` (the dataset file's, io/dataset_file.hpp).
using io::kObservationSize;

/// The worlds demonstrations are drawn in. The generated kinds take the benchmark suites' world settings
/// (benchmark_suites(), benchmark_suites_v2()) with other seeds: forest, boxes and mixed are the static suites'
/// worlds, `dynamic` the dynamic-1.5ms suite's mixed world with 6 moving obstacles, `clutter-dynamic` the
/// clutter-dynamic-2ms suite's (the same, its obstacles at 1 m/s). The paper's worlds are fixed layouts
/// (sim/paper_worlds.hpp), as in the v2 suites: `sixwall`, `sixwall-sliding` (its walls move) and `random`;
/// there, only the target's path and the noise change with the seed.
enum class DemonstrationWorld { forest, boxes, mixed, dynamic, clutter_dynamic, sixwall, sixwall_sliding, random };
const char* to_string(DemonstrationWorld world);
/// "forest", "boxes", "mixed", "dynamic", "clutter-dynamic", "sixwall", "sixwall-sliding" or "random";
/// nullopt otherwise.
std::optional<DemonstrationWorld> parse_demonstration_world(std::string_view text);

/// How the demonstrations' target moves: `smooth`, the v1 suites' generator (TargetMotion::smooth), or
/// `teleop`, the v2 suites' virtual tele-operator calibrated for each top speed (sim::teleop_target_in, over
/// the area of the v2 suite that holds the world). The paper's worlds always use `teleop`, as their suites do.
enum class DemonstrationTarget { smooth, teleop };
const char* to_string(DemonstrationTarget target);
/// "smooth" or "teleop"; nullopt otherwise.
std::optional<DemonstrationTarget> parse_demonstration_target(std::string_view text);

struct DemonstrationSettings {
  /// Closed-loop episodes, each in a world of its own. Episode i uses world kind worlds[i % W] and target top
  /// speed target_speeds[(i / W) % S], so that every combination appears once every W * S episodes.
  int episodes = 8;
  /// Episode i draws its world, its target path, its sensor noise and its planners' samples from seed
  /// first_seed + i. No such seed may be a benchmark seed (sim::is_benchmark_seed, 1000-1999).
  std::uint64_t first_seed = 5000;
  std::vector<DemonstrationWorld> worlds = {DemonstrationWorld::forest, DemonstrationWorld::boxes,
                                            DemonstrationWorld::mixed, DemonstrationWorld::dynamic};
  std::vector<double> target_speeds = {1.0, 1.5, 2.0};  ///< m/s, the target's top speed
  DemonstrationTarget target = DemonstrationTarget::smooth;
  /// Scenarios to drive instead of generated ones (your own recorded target paths, `scenario import`): when
  /// not empty, episode i runs scenarios[i % N] for min(its duration, `duration`), and `worlds`,
  /// `target_speeds` and `target` are not used; the seed first_seed + i still draws the sensor noise and the
  /// planners' samples. Their names are recorded in the metadata.
  std::vector<core::Scenario> scenarios;
  double duration = 40.0;  ///< simulated seconds per episode (at most, with `scenarios`)
  /// Label one planning cycle in this many (the first cycle of an episode is always labelled).
  int label_every = 1;
  /// Who drives: "expert" (the expert's own plan is the command; it runs once per cycle), or any name
  /// planners::make_planner knows ("projcem": online Proj-CEM; a learned planner with `model` for DAgger),
  /// in which case the expert runs only on labelled cycles, next to the driver.
  std::string driver = "expert";
  std::string model;  ///< driver's model file (learned planners; empty: the shipped model)
  /// The driver's other options (shield, response time, latency, ...): its seed, threads and model are
  /// replaced by the episode's seed, 1 and `model`.
  planners::PlannerOptions driver_options;
  /// The labelling expert. Its seed is replaced by each episode's seed; its projection runs on one thread
  /// (episodes run in parallel instead).
  planners::ProjCemSettings expert = planners::ProjCemSettings::offline_expert(1);
  /// Physics, planning period, band and Protocol v2 (latency, robot lag, sensor and target noise) of every
  /// episode; its `seed` (sensor noise) is replaced by the episode's seed. `beams` and `lidar_noise` override
  /// the sensor of every episode's scenario. Snapshots and trace are not needed here and are thinned out.
  EpisodeSettings episode;
  /// Episodes run at the same time, each on its own thread with its own planners. Does not change the result.
  int jobs = 1;
  /// This process's share of the run (several processes, e.g. MPI ranks): only the episodes i with
  /// i % shards == shard. The result holds those episodes' rows, each with its index in the whole run;
  /// interleave_demonstration_shards() makes the whole run's rows from every shard's. Like `jobs`, not written
  /// to the metadata: the shards of a run and the run in one process share their metadata but `rows`.
  int shard = 0;
  int shards = 1;
  /// Provenance written to the `created_by` metadata (occtrack version and command line).
  std::string created_by = "occtrack";

  /// True when every field holds a usable value; otherwise false and *error names the field and its rule.
  bool validate(std::string* error = nullptr) const;
};

/// Seed of episode `index` (0-based).
inline std::uint64_t demonstration_seed(const DemonstrationSettings& settings, int index) {
  return settings.first_seed + static_cast<std::uint64_t>(index);
}

/// The rows of a dataset file (io/dataset_file.hpp, which writes, reads, appends and summarises them).
using Demonstrations = io::DatasetFile;

/// What happened while generating (counts over all episodes).
struct DemonstrationReport {
  int episodes = 0;            ///< episodes run to their end
  int episodes_failed = 0;     ///< worlds or target paths the generator could not make (skipped)
  std::vector<std::string> failures;  ///< one message per failed episode, naming its seed
  std::int64_t cycles = 0;     ///< planning cycles simulated
  std::int64_t labelled = 0;   ///< cycles the expert was asked to label
  std::int64_t rows = 0;       ///< rows kept
  std::int64_t skipped_failed = 0;     ///< expert returned ok = false (or perception refused the input)
  std::int64_t skipped_nonfinite = 0;  ///< non-finite observation, plan or cost
  double expert_ms = 0.0;      ///< summed wall time of the expert's plan() calls
  double seconds = 0.0;        ///< wall time of generate_demonstrations
  std::int64_t skipped() const { return skipped_failed + skipped_nonfinite; }
  /// Adds the counts of `other` (a part of the same run: an episode, a shard); failures stay sorted, and
  /// `seconds` becomes the longer of the two, as the parts ran side by side.
  void add(const DemonstrationReport& other);
};

/// Progress, reported after each simulated second of any episode and after each episode (from the worker
/// threads, one call at a time). A shard counts only its own episodes.
struct DemonstrationProgress {
  int episodes_done = 0;
  int episodes_total = 0;
  double fraction = 0.0;     ///< of all simulated time
  std::int64_t rows = 0;     ///< rows so far, episodes in flight included
  double elapsed_s = 0.0;
};

/// Runs the episodes and returns their rows ordered by episode. Throws std::invalid_argument for invalid
/// settings (the message of validate()) or a driver the factory refuses; std::runtime_error when an episode
/// fails for another reason than the scenario generator (the message names its seed).
Demonstrations generate_demonstrations(const DemonstrationSettings& settings, DemonstrationReport* report = nullptr,
                                       const std::function<void(const DemonstrationProgress&)>& progress = {});

/// The whole run from its shards' results (parts[k]: generate_demonstrations with shard k of parts.size()):
/// exactly what one process returns for the same settings, rows ordered by episode, the sizes and metadata of
/// the parts with `rows` rewritten. Throws std::invalid_argument when there is no part, when the parts' sizes
/// or metadata (`rows` aside) differ, or when a part is not ordered by episode or holds an episode of another.
Demonstrations interleave_demonstration_shards(std::vector<Demonstrations> parts);

/// One row as the recorder sees it (double precision, before it is stored as float32).
struct DemonstrationRow {
  Eigen::Matrix<double, kObservationSize, 1> observation;
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> cloud;
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> obstacles;
  Eigen::RowVectorXd expert_xi;
  double expert_cost = 0.0;
  double time = 0.0;
};

/// The planner placed into sim::run_episode while labelling: it passes every cycle to the driver and, on
/// labelled cycles, asks the expert for its plan and records a row from the expert's PlanRecord. With no
/// driver the expert drives (and is called once per cycle).
class DemonstrationRecorder final : public planners::Planner {
 public:
  /// `expert` is normally a planners::ProjCem; `driver` may be null (the expert drives).
  DemonstrationRecorder(std::unique_ptr<planners::Planner> expert, std::unique_ptr<planners::Planner> driver,
                        int label_every);
  ~DemonstrationRecorder() override;

  std::string name() const override;
  /// Resets both planners; keeps the rows recorded so far.
  void reset() override;
  using planners::Planner::plan;
  void plan(const planners::PlannerInput& input, planners::PlannerOutput& out) override;
  /// The driving planner's record (the expert's when it drives).
  const planners::PlanRecord& last_record() const override;

  const std::vector<DemonstrationRow>& rows() const { return rows_; }
  /// Moves the rows out (the recorder keeps none).
  std::vector<DemonstrationRow> take_rows() { return std::exchange(rows_, {}); }
  /// Counts of this recorder (episodes, failures and seconds are left to the caller).
  const DemonstrationReport& report() const { return report_; }

 private:
  bool record(bool expert_ok);

  std::unique_ptr<planners::Planner> expert_, driver_;
  int label_every_;
  planners::PlannerOutput expert_output_;  // the expert's output while another planner drives
  std::int64_t cycle_ = 0;
  std::vector<DemonstrationRow> rows_;
  DemonstrationReport report_;
};

/// The metadata of a dataset made with these settings (rows left to the writer).
std::map<std::string, std::string> demonstration_metadata(const DemonstrationSettings& settings);

/// Whether a dataset's rows were driven by a learned policy while the expert labelled (a DAgger round), read
/// from the `driver` its metadata holds: "expert" or a non-learned planner's name (projcem, follower, ...) is
/// not; a learned planner's name (cvae, bc, cvae-fixed-q) or a model file is. False without the key.
bool learned_driver(const std::map<std::string, std::string>& metadata);

}  // namespace occtrack::sim
