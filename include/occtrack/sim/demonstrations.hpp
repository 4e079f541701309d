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
//   sim::write_demonstrations("demo.safetensors", data);
//   sim::Demonstrations back = sim::read_demonstrations("demo.safetensors");      // throws io::InputError
//
// One row per labelled planning cycle. What a row holds, all robot-centric (the robot at the origin, axes
// parallel to the world's) and exactly as the expert saw it:
//   observation  robot velocity, target position minus robot position, target velocity (the PlannerInput's);
//   cloud        the C x 2 fixed cloud and
//   obstacles    the N x 4 nearest points (x, y, vx, vy) of a perception::Perception configured like the
//                expert's and fed the same scans in the same order as the expert's own, so that its velocity
//                tracks are the expert's;
//   expert_xi    the coefficients (x then y) of the expert's plan, recovered from PlannerOutput::plan (world
//                positions) minus the robot position by least squares with the Bernstein basis P. The plan is
//                P xi evaluated in double, so the fit is exact up to round-off; a row whose worst fit residual
//                exceeds kPlanFitTolerance is skipped and counted;
//   expert_cost  planners::Ranking of that plan in the same frame (the expert's own ranking settings; the
//                planner does not return its cost, and the ranking is a function of the frame alone);
//   episode      the episode index within the file; time: the simulated time of the cycle.
// Cycles where the expert fails (ok = false), returns a plan of the wrong length or non-finite numbers, or
// whose cost is not finite, are skipped and counted in DemonstrationReport.
//
// Determinism: every episode is a pure function of the settings and its index (world, target path, sensor
// noise and both planners are seeded from first_seed + index), and rows are ordered by episode, so the same
// settings give the same bytes whatever `jobs` is.
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
#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/proj_cem.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/sim/episode.hpp"

namespace occtrack::io {
struct TensorFile;
}

namespace occtrack::sim {

/// `__metadata__.format` of a dataset file.
inline constexpr const char* kDatasetFormat = "occtrack.dataset.v1";
/// Columns of `observation`: robot vx, vy; target x, y (relative to the robot); target vx, vy.
inline constexpr int kObservationSize = 6;
/// Metres: worst |P xi - (plan - robot)| accepted when recovering the expert's coefficients.
inline constexpr double kPlanFitTolerance = 1e-6;

/// The worlds demonstrations are drawn in: the benchmark suites' world settings (benchmark_suites()) with
/// other seeds. `dynamic` is the dynamic-1.5ms suite's mixed world with 6 moving obstacles.
enum class DemonstrationWorld { forest, boxes, mixed, dynamic };
const char* to_string(DemonstrationWorld world);
/// "forest", "boxes", "mixed" or "dynamic"; nullopt otherwise.
std::optional<DemonstrationWorld> parse_demonstration_world(std::string_view text);

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
  double duration = 40.0;  ///< simulated seconds per episode
  /// Label one planning cycle in this many (the first cycle of an episode is always labelled).
  int label_every = 1;
  /// Who drives: "expert" (the expert's own plan is the command; it runs once per cycle), or any name
  /// planners::make_planner knows ("projcem": online Proj-CEM; a learned planner with `model` for DAgger),
  /// in which case the expert runs only on labelled cycles, next to the driver.
  std::string driver = "expert";
  std::string model;  ///< driver's model file (learned planners; empty: the shipped model)
  /// The labelling expert. Its seed is replaced by each episode's seed; its projection runs on one thread
  /// (episodes run in parallel instead).
  planners::ProjCemSettings expert = planners::ProjCemSettings::offline_expert(1);
  /// Physics, planning period and band of every episode; its `seed` (sensor noise) is replaced by the
  /// episode's seed. Snapshots and trace are not needed here and are thinned out.
  EpisodeSettings episode;
  /// Episodes run at the same time, each on its own thread with its own planners. Does not change the result.
  int jobs = 1;
  /// Provenance written to the `created_by` metadata (occtrack version and command line).
  std::string created_by = "occtrack";

  /// True when every field holds a usable value; otherwise false and *error names the field and its rule.
  bool validate(std::string* error = nullptr) const;
};

/// Seed of episode `index` (0-based).
inline std::uint64_t demonstration_seed(const DemonstrationSettings& settings, int index) {
  return settings.first_seed + static_cast<std::uint64_t>(index);
}

/// The rows of a dataset file, row-major, float32 as stored (docs/learning.md, "Dataset file").
struct Demonstrations {
  std::int64_t rows = 0;     ///< S
  int cloud_points = 200;    ///< C
  int nearest_points = 60;   ///< N
  int coefficients = 11;     ///< n, per axis
  std::vector<float> observation;   ///< S x 6
  std::vector<float> cloud;         ///< S x C x 2
  std::vector<float> obstacles;     ///< S x N x 4
  std::vector<float> expert_xi;     ///< S x 2n
  std::vector<float> expert_cost;   ///< S
  std::vector<std::int32_t> episode;  ///< S
  std::vector<float> time;          ///< S, seconds
  /// format, projection, perception, expert, driver, generator, rows, created_by (JSON text where
  /// structured). `rows` is rewritten from `rows` when written.
  std::map<std::string, std::string> metadata;
};

/// What happened while generating (counts over all episodes).
struct DemonstrationReport {
  int episodes = 0;            ///< episodes run to their end
  int episodes_failed = 0;     ///< worlds or target paths the generator could not make (skipped)
  std::vector<std::string> failures;  ///< one message per failed episode, naming its seed
  std::int64_t cycles = 0;     ///< planning cycles simulated
  std::int64_t labelled = 0;   ///< cycles the expert was asked to label
  std::int64_t rows = 0;       ///< rows kept
  std::int64_t skipped_failed = 0;     ///< expert returned ok = false (or perception refused the input)
  std::int64_t skipped_nonfinite = 0;  ///< plan of the wrong length, non-finite plan or non-finite cost
  std::int64_t skipped_fit = 0;        ///< fit residual above kPlanFitTolerance
  double worst_fit_residual = 0.0;     ///< metres, over the rows kept
  double expert_ms = 0.0;      ///< summed wall time of the expert's plan() calls
  double seconds = 0.0;        ///< wall time of generate_demonstrations
  std::int64_t skipped() const { return skipped_failed + skipped_nonfinite + skipped_fit; }
};

/// Progress, reported after each simulated second of any episode and after each episode (from the worker
/// threads, one call at a time).
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

/// One row as the recorder sees it (double precision, before it is stored as float32).
struct DemonstrationRow {
  Eigen::Matrix<double, kObservationSize, 1> observation;
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> cloud;
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> obstacles;
  Eigen::RowVectorXd expert_xi;
  double expert_cost = 0.0;
  double time = 0.0;
  double fit_residual = 0.0;  ///< metres, worst |P xi - (plan - robot)|
};

/// The planner placed into sim::run_episode while labelling: it passes every cycle to the driver and, on
/// labelled cycles, asks the expert for its plan and records a row. With no driver the expert drives (and
/// is called once per cycle).
class DemonstrationRecorder final : public planners::Planner {
 public:
  /// `expert` is normally a planners::ProjCem built from `expert_settings`; its perception, projection and
  /// ranking settings say how rows are observed, fitted and costed. `driver` may be null.
  DemonstrationRecorder(std::unique_ptr<planners::Planner> expert, std::unique_ptr<planners::Planner> driver,
                        const planners::ProjCemSettings& expert_settings, int label_every);
  ~DemonstrationRecorder() override;

  std::string name() const override;
  /// Resets both planners and the recorder's perception; keeps the rows recorded so far.
  void reset() override;
  planners::PlannerOutput plan(const planners::PlannerInput& input) override;

  const std::vector<DemonstrationRow>& rows() const { return rows_; }
  /// Moves the rows out (the recorder keeps none).
  std::vector<DemonstrationRow> take_rows() { return std::exchange(rows_, {}); }
  /// Counts of this recorder (episodes, failures and seconds are left to the caller).
  const DemonstrationReport& report() const { return report_; }

 private:
  bool record(const planners::PlannerInput& input, const planners::PlannerOutput& expert_output);

  std::unique_ptr<planners::Planner> expert_, driver_;
  planners::ProjCemSettings settings_;
  int label_every_;
  perception::Perception perception_;
  perception::Observation observation_;
  planners::Ranking ranking_;
  Eigen::MatrixXd least_squares_;  // n x m, pseudo-inverse of P
  std::int64_t cycle_ = 0;
  std::vector<DemonstrationRow> rows_;
  DemonstrationReport report_;
};

/// Coefficients (x then y) of the trajectory through `positions - origin` by least squares with basis.P; the
/// worst absolute residual goes to *residual. positions must hold basis.steps points.
Eigen::RowVectorXd fit_coefficients(const core::BernsteinBasis& basis, const std::vector<core::Vec2>& positions,
                                    const core::Vec2& origin, double* residual = nullptr);

/// The metadata of a dataset made with these settings (rows left to the writer).
std::map<std::string, std::string> demonstration_metadata(const DemonstrationSettings& settings);

/// The file's tensors and metadata (`rows` set from data.rows). Throws std::invalid_argument when a vector's
/// size does not match rows and the sizes.
io::TensorFile to_tensor_file(const Demonstrations& data);
/// Validates a file's format tag, metadata and every tensor's dtype and shape against each other and the
/// metadata's sizes; throws io::InputError naming the file and the tensor or key.
Demonstrations from_tensor_file(const io::TensorFile& file);
void write_demonstrations(const std::string& path, const Demonstrations& data);
Demonstrations read_demonstrations(const std::string& path);

/// Appends `more` to `into` (episode indices of `more` shifted past those of `into`). Both must have the same
/// sizes and the same projection and perception metadata (std::invalid_argument naming the key otherwise);
/// the provenance of `into` is kept. Appending to an empty Demonstrations copies.
void append_demonstrations(Demonstrations& into, const Demonstrations& more);
/// Appends every row of `from` to `into`, its episode numbers shifted by `episode_offset` (no checks).
void append_rows(Demonstrations& into, const Demonstrations& from, std::int32_t episode_offset);

/// Summary statistics for `occtrack dataset info`.
struct DemonstrationStatistics {
  std::int64_t rows = 0;
  int episodes = 0;  ///< distinct episode indices
  Eigen::Matrix<double, kObservationSize, 1> observation_mean = Eigen::Matrix<double, kObservationSize, 1>::Zero();
  Eigen::Matrix<double, kObservationSize, 1> observation_std = Eigen::Matrix<double, kObservationSize, 1>::Zero();
  double plan_speed_mean = 0.0;   ///< m/s, mean over rows of the plan's mean speed over the horizon
  double plan_speed_std = 0.0;
  double plan_speed_max = 0.0;    ///< m/s, fastest speed at any step of any plan
  double start_speed_mean = 0.0;  ///< m/s, mean over rows of the plan's mean speed over its first 0.1 s
  double cost_mean = 0.0, cost_std = 0.0, cost_min = 0.0, cost_max = 0.0;
  double target_distance_mean = 0.0;  ///< m
};
/// Needs the projection metadata (degree, steps, horizon) for the basis; throws io::InputError otherwise.
DemonstrationStatistics demonstration_statistics(const Demonstrations& data);

}  // namespace occtrack::sim
