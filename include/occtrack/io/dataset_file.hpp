// The dataset file (docs/learning.md, "Dataset file"): the one statement of what the demonstration generator
// writes and the trainer reads. A safetensors file whose metadata `format` is "occtrack.dataset.v1", one row
// per labelled planning cycle:
//
//   observation  S x 6      robot vx, vy; target x, y (relative to the robot); target vx, vy
//   cloud        S x C x 2  perception's fixed cloud, robot-centric
//   obstacles    S x N x 4  perception's nearest points: x, y robot-centric, vx, vy
//   expert_xi    S x 2n     the expert's plan, coefficients x then y
//   expert_cost  S          the ranking cost of that plan
//   episode      S          episode index within the file (int)
//   time         S          simulated time of the cycle, seconds
//
// Written as float32 and int32; read from float32 or float64 and int32 or int64 (both have been written).
// Metadata: `format`, `projection` (io::projection_settings_json), `perception` (voxel_size, cloud_size,
// nearest_count, estimate_velocity), `expert`, `driver`, `generator`, `rows`, `created_by`; the reader needs
// `format` and `projection`, and checks `rows` and `perception`'s sizes against the tensors when present.
//
//   io::DatasetFile data = io::read_dataset_file("demo.safetensors");  // checked; throws io::InputError
//   io::append_dataset(merged, data);                                   // episodes renumbered
//   io::write_dataset_file("merged.safetensors", merged);
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "occtrack/io/error.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::io {

/// `__metadata__.format` of a dataset file.
inline constexpr const char* kDatasetFormat = "occtrack.dataset.v1";
/// Columns of `observation`: robot vx, vy; target x, y (relative to the robot); target vx, vy.
inline constexpr int kObservationSize = 6;
/// The tensors, in the table's order (the order in which the reader checks them).
inline constexpr const char* kDatasetColumns[] = {"observation", "cloud",   "obstacles", "expert_xi",
                                                  "expert_cost", "episode", "time"};

/// A dataset file's rows, row-major, float32 as stored.
struct DatasetFile {
  std::string source;        ///< names the file in messages (set by the reader; "dataset" when empty)
  std::int64_t rows = 0;     ///< S
  int cloud_points = 200;    ///< C
  int nearest_points = 60;   ///< N
  int coefficients = 11;     ///< n, per axis
  std::vector<float> observation;     ///< S x 6
  std::vector<float> cloud;           ///< S x C x 2
  std::vector<float> obstacles;       ///< S x N x 4
  std::vector<float> expert_xi;       ///< S x 2n
  std::vector<float> expert_cost;     ///< S
  std::vector<std::int32_t> episode;  ///< S
  std::vector<float> time;            ///< S, seconds
  /// format, projection, perception, expert, driver, generator, rows, created_by (JSON text where
  /// structured). `format` and `rows` are rewritten from the fields when written.
  std::map<std::string, std::string> metadata;
};

/// The file's tensors (float32, episode int32) and metadata (`format`; `rows` from data.rows). Throws
/// std::invalid_argument when a vector's size does not match rows and the sizes.
TensorFile to_tensor_file(const DatasetFile& data);
/// Checks a file in memory (file.source names it, "dataset" when empty) and returns its rows. Throws
/// io::InputError "SOURCE: ..." naming the key or tensor when: `format` is not "occtrack.dataset.v1";
/// `projection` is missing, not JSON or fails projection::Settings::validate (other keys ignored, iterations
/// and rho optional); `perception` or `rows` is present but malformed or contradicts the tensors; a column is
/// missing, has another dtype (floats: F32 or F64; episode: I32 or I64) or shape (S from `rows` or
/// observation, C and N from `perception` or cloud and obstacles, n from projection.degree), holds a
/// non-finite value (naming the row), or an episode index is negative or beyond int32; the cloud has no point.
DatasetFile validate_dataset_file(const TensorFile& file);
/// read_safetensors, then validate_dataset_file.
DatasetFile read_dataset_file(const std::string& path);
void write_dataset_file(const std::string& path, const DatasetFile& data);

/// The `projection` metadata as settings (io::parse_projection_settings, not strict), validated; throws
/// io::InputError naming data.source.
projection::Settings dataset_projection(const DatasetFile& data);

/// Appends `more` to `into` (episode indices of `more` shifted past those of `into`). Both must have the same
/// sizes and the same projection and perception metadata (std::invalid_argument naming the key otherwise);
/// the provenance of `into` is kept. Appending to an empty DatasetFile copies.
void append_dataset(DatasetFile& into, const DatasetFile& more);
/// Appends every row of `from` to `into`, its episode numbers shifted by `episode_offset` (no checks).
void append_rows(DatasetFile& into, const DatasetFile& from, std::int32_t episode_offset);

/// Summary statistics (`occtrack dataset info`).
struct DatasetStatistics {
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
DatasetStatistics dataset_statistics(const DatasetFile& data);

}  // namespace occtrack::io
