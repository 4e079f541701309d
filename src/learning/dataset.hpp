// Training data: one or more dataset files (io/dataset_file.hpp, the contract, which reads and checks them)
// as CPU float32 tensors, with the normalisation statistics, a held-out validation split by episode, and
// seeded mini-batches.
//
//   learning::Dataset data = learning::load_dataset({"a.safetensors", "b.safetensors"});  // io::InputError
//   learning::DatasetSplit split = learning::split_by_episode(data, 0.1, seed);
//   learning::BatchSampler sampler(split.train, 256, seed);
//   learning::Batch batch = data.gather(sampler.indices(step), device);
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "learning/networks.hpp"
#include "occtrack/core/tracking.hpp"
#include "occtrack/io/dataset_file.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::learning {

/// One mini-batch, on the training device.
struct Batch {
  torch::Tensor observation;  ///< [B, 6]
  torch::Tensor cloud;        ///< [B, C, 2]
  torch::Tensor obstacles;    ///< [B, N, 4]
  torch::Tensor expert_xi;    ///< [B, 2n]
  int64_t size() const { return observation.size(0); }
};

/// One file of a Dataset.
struct DatasetSource {
  std::string path;
  int64_t rows = 0;
  int64_t episodes = 0;
  std::map<std::string, std::string> metadata;
};

/// Every file's rows, concatenated in file order. Float tensors are float32 on the CPU; `episode` is int64
/// and globally unique (file k's episodes are offset by the episodes of files 0..k-1).
struct Dataset {
  std::vector<DatasetSource> files;
  projection::Settings projection;  ///< from the first file's `projection` metadata (all files must agree)
  torch::Tensor observation;        ///< [S, 6]
  torch::Tensor cloud;              ///< [S, C, 2]
  torch::Tensor obstacles;          ///< [S, N, 4]
  torch::Tensor expert_xi;          ///< [S, 2n]
  torch::Tensor expert_cost;        ///< [S]
  torch::Tensor episode;            ///< [S] int64
  torch::Tensor time;               ///< [S]

  int64_t rows() const { return observation.defined() ? observation.size(0) : 0; }
  int64_t cloud_points() const { return cloud.size(1); }
  int64_t nearest_points() const { return obstacles.size(1); }
  int coefficients() const { return projection.coefficients(); }

  /// The rows `indices` (int64, any device) of observation, cloud, obstacles and expert_xi, on `device`.
  Batch gather(const torch::Tensor& indices, torch::Device device) const;
  /// Moves the tensors (to a GPU, say, so that batches are gathered there).
  void to(torch::Device device);
};

/// Reads and checks every file with io::read_dataset_file, then concatenates them: at least one row, and all
/// files with the same cloud and obstacle points and projection geometry (degree, steps, horizon, via steps).
/// Throws io::InputError naming the file and the tensor or metadata key.
Dataset load_dataset(const std::vector<std::string>& paths);
/// The same from checked files already in memory (each file's `source` names it).
Dataset make_dataset(const std::vector<io::DatasetFile>& files);

/// Row indices (int64, CPU) of the training and the validation rows. Whole episodes go to validation,
/// chosen at random (seeded) until at least `validation_share` of the episodes are held out; none when the
/// share is 0 or there is a single episode.
struct DatasetSplit {
  torch::Tensor train, validation;
  int64_t train_episodes = 0, validation_episodes = 0;
};
DatasetSplit split_by_episode(const Dataset& data, double validation_share, std::uint64_t seed);

/// Normalisation statistics of the rows `rows` (docs/learning.md, "norm.*"):
/// - observation, cloud (per coordinate, over all points) and xi: mean and standard deviation, the latter
///   floored at `std_floor`;
/// - output offset and scale: terminal state and via points from the expert trajectories' statistics
///   (W expert_xi at the last step and at the via steps), lambda0 offset 0 and scale 1, d_min offset
///   band.min and d_max offset band.max with scale (band.max - band.min) / 4, xi_bar as xi.
NormalizationStats compute_normalization(const Dataset& data, const torch::Tensor& rows, const io::NetworkConfig& config,
                                         const core::TrackingBand& band, double std_floor = 1e-3);

/// Mini-batches of `batch` rows drawn without replacement from `rows`, reshuffled every epoch. The batch of
/// step s depends only on (rows, batch, seed, s), so a resumed run sees the same batches. A batch larger
/// than the rows is cut to the rows; the last incomplete batch of an epoch is dropped.
class BatchSampler {
 public:
  BatchSampler(torch::Tensor rows, int64_t batch, std::uint64_t seed);
  /// Indices (int64, CPU) of step `step`'s batch.
  torch::Tensor indices(int64_t step);
  int64_t batch() const { return batch_; }
  int64_t batches_per_epoch() const { return batches_per_epoch_; }

 private:
  torch::Tensor rows_;
  int64_t batch_ = 0, batches_per_epoch_ = 0;
  std::uint64_t seed_ = 0;
  int64_t epoch_ = -1;
  torch::Tensor permutation_;
};

/// Random but plausible rows, for benchmarks and tests (no file involved): the target 2 to 5 m away, a few
/// round obstacles as the cloud (C points), the N nearest of them as static obstacle points, and as expert a
/// straight line towards the target's predicted position pulled back to 2 m. Episodes of equal length.
/// Deterministic in the seed.
struct SyntheticDatasetOptions {
  int64_t rows = 256;
  int64_t episodes = 4;
  int cloud_points = 200;
  int nearest_points = 60;
  std::uint64_t seed = 1;
};
Dataset synthetic_dataset(const SyntheticDatasetOptions& options, const projection::Settings& projection);

}  // namespace occtrack::learning
