// End-to-end training through the unrolled projection (shared/spec/policy.md, "Training"; docs/learning.md,
// "Training"):
//
//   loss = 0.5 * MSE(W xi_K, tau_e) + beta_t * KL(N(mu, sigma) || N(0, I)) + 0.5 * mean(residual),
//   beta_t = beta * min(1, step / 1000),
//
// with xi_K the projection's output after K iterations (K = 50 by default) started from the decoder's
// outputs; BC uses the decoder's xi_bar for xi_K and has no residual term. Adam, CPU or CUDA.
//
//   learning::TrainingSettings settings;          // defaults; sizes C, N, n, m come from the data
//   learning::Trainer trainer(settings, learning::load_dataset({"data.safetensors"}));
//   learning::TrainingSummary summary = trainer.run([](const learning::TrainingProgress& p) { ... });
//   learning::export_model("model.safetensors", trainer.model(), trainer.model_metadata(summary, "..."));
//
// Reproducibility: every step reseeds torch's generators from (seed, step), and the batch of a step depends
// only on (seed, step), so a run resumed from a checkpoint repeats the loss trajectory of an uninterrupted
// one (bit for bit on the CPU with a fixed thread count). The batch's random draws (latent noise, dropout) are
// made for the whole batch (PassNoise), so that W data-parallel processes (learning/distributed.hpp, a
// ProcessGroup given to the Trainer) train the model one process trains, to float rounding.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "learning/dataset.hpp"
#include "learning/distributed.hpp"
#include "learning/networks.hpp"
#include "learning/projection.hpp"

namespace occtrack::learning {

struct ModelMetadata;  // export.hpp

struct TrainingSettings {
  io::Variant variant = io::Variant::cvae;
  /// Network sizes (the model file's); cloud_points, nearest_points, coefficients, steps and outputs are
  /// overwritten from the data.
  io::NetworkConfig network;
  double dropout = 0.3;          ///< PointNet's dropout probability (training only; recorded under `training`)
  int64_t steps = 20000;         ///< optimisation steps in all (a resumed run continues up to this)
  int64_t batch = 256;           ///< rows per mini-batch (cut to the training rows when there are fewer)
  double learning_rate = 1e-3;   ///< Adam, at step 0
  /// Cosine decay from learning_rate at step 0 to this at `steps` (negative: constant learning_rate).
  double learning_rate_final = -1;
  /// Stop this run after this many seconds of training (0: no limit); the run then ends as at its last
  /// step (validation, checkpoint) and the summary counts the steps done. For fixed-length GPU leases.
  double max_seconds = 0;
  double beta = 1e-3;            ///< KL weight after the warm-up
  int64_t kl_warmup_steps = 1000;  ///< beta_t = beta * min(1, step / kl_warmup_steps)
  int iterations = 50;           ///< K, unrolled projection iterations in training
  bool plain_projection = false; ///< differentiate through the plain torch loop instead of project_fast
  std::string device = "cpu";    ///< "cpu", "cuda" or "cuda:I"
  std::uint64_t seed = 1;
  core::TrackingBand band;       ///< d_min floor and fixed-q's nominal bounds
  double validation_share = 0.1; ///< share of the episodes held out
  int64_t validation_every = 1000;   ///< steps between validation losses (0: only at the end)
  int64_t validation_rows = 2048;    ///< at most this many validation rows are evaluated
  std::string checkpoint_path;       ///< empty: no checkpoints
  int64_t checkpoint_every = 1000;   ///< steps between checkpoints (and one at the end)
  double progress_seconds = 5.0;     ///< seconds between progress reports
  /// A model file to start from (fine-tuning, for example one more DAgger round on a shipped model): its
  /// weights and input normalisation replace the random weights and the data's normalisation. It must be of
  /// the same variant and sizes (frame included). Empty: random weights.
  std::string initial_model;

  /// False, with *error naming the first broken field, otherwise true.
  bool validate(std::string* error = nullptr) const;
};

/// One batch's loss terms as numbers.
struct LossTerms {
  double total = 0, mse = 0, kl = 0, residual = 0;
  LossTerms& operator+=(const LossTerms& o);
  LossTerms operator/(double d) const;
};

/// The loss terms as tensors (total is the one to differentiate).
struct LossTensors {
  torch::Tensor total, mse, kl, residual;
  LossTerms values() const;
};

/// The learning rate of a step: cosine from `first` at step 0 to `final` at `steps` (final < 0: first).
double learning_rate_at(double first, double final, int64_t step, int64_t steps);
/// beta_t = beta * min(1, step / warmup_steps) (warmup_steps <= 0: beta).
double kl_weight(double beta, int64_t step, int64_t warmup_steps);

/// What the loss needs besides the model and the batch; built once for a device.
struct LossContext {
  LossContext(io::Variant variant, const projection::Settings& projection, const core::TrackingBand& band,
              const io::NetworkConfig& network, int iterations, bool plain_projection, torch::Device device);
  PolicySettings policy;
  io::NetworkConfig network;
  TrajectoryBasis basis;
  std::shared_ptr<ProjectionConstants> constants;  ///< null for BC
  int iterations = 50;
  bool plain_projection = false;
};

/// The loss of one batch (docs/learning.md, "Training"); the model's mode (train/eval) is the caller's.
/// `noise`: the pass's random draws (PassNoise); null: the model draws its own.
LossTensors batch_loss(CvaeImpl& model, const Batch& batch, const LossContext& context, double beta_t,
                       const PassNoise* noise = nullptr);

struct TrainingProgress {
  int64_t step = 0, steps = 0;  ///< steps done, steps in all
  LossTerms loss;               ///< mean over the steps since the last report
  double steps_per_second = 0;  ///< over the steps since the last report
  double elapsed_seconds = 0;   ///< this run's and the resumed runs' training time
  double eta_seconds = 0;
  std::optional<LossTerms> validation;  ///< set when a validation loss was computed since the last report
  std::string checkpoint;               ///< set when a checkpoint was written since the last report
};

struct TrainingSummary {
  int64_t steps = 0;
  double seconds = 0;           ///< training time, resumed runs included
  LossTerms final_loss;         ///< mean over the last (up to 100) steps
  std::optional<LossTerms> validation;  ///< the latest (at the end of a run), when there are validation rows
  int64_t validation_step = -1;         ///< the step `validation` was computed at
  std::vector<LossTerms> history;       ///< every step of this run
};

class Trainer {
 public:
  /// Builds the model (sizes from the data), the normalisation from the training rows and the optimizer.
  /// With settings.initial_model, the weights and normalisation are that file's instead (fine-tuning).
  /// Throws std::invalid_argument on unusable settings (an initial model of another variant or other sizes
  /// among them), io::InputError when the initial model cannot be read, std::runtime_error when CUDA is asked
  /// for and absent.
  /// With a `group` of several processes (learning/distributed.hpp), each process computes its share of every
  /// batch and the gradients are summed: every process must pass the same settings and data (checked), and
  /// only rank 0 validates and writes checkpoints. Throws std::runtime_error when the processes differ.
  Trainer(const TrainingSettings& settings, Dataset data, std::shared_ptr<ProcessGroup> group = nullptr);

  /// One optimisation step at the current step index; returns its loss terms.
  LossTerms step();
  /// The loss on (up to validation_rows of) the validation rows, eval mode, no gradient; nullopt when there
  /// are none. Reseeds torch's generators (the next step() reseeds them again).
  std::optional<LossTerms> validate();
  /// Steps until settings.steps, with progress reports, validation and checkpoints as set.
  /// `after_step`, when set, is called after every step (its validation and checkpoint done) with the step
  /// index and the summary so far (history, and final_loss over its last steps): for snapshots of the model
  /// while it trains.
  TrainingSummary run(const std::function<void(const TrainingProgress&)>& progress = {},
                      const std::function<void(int64_t, const TrainingSummary&)>& after_step = {});

  /// Model, optimizer, step, elapsed time and the settings that must not change on resume.
  void save_checkpoint(const std::string& path) const;
  /// Restores a checkpoint written with the same variant, network, batch, seed, iterations and data rows;
  /// throws std::runtime_error naming the field that differs.
  void load_checkpoint(const std::string& path);

  int64_t current_step() const { return step_; }
  /// Several processes train together.
  bool distributed() const;
  /// This process writes checkpoints and models, and reports (rank 0, or the only process).
  bool writes_files() const;
  double elapsed_seconds() const { return elapsed_seconds_; }
  Cvae& model() { return model_; }
  const TrainingSettings& settings() const { return settings_; }
  const Dataset& data() const { return data_; }
  const DatasetSplit& split() const { return split_; }
  torch::Device device() const { return device_; }
  /// The model file's metadata for this training (export.hpp).
  ModelMetadata model_metadata(const TrainingSummary& summary, const std::string& created_by) const;

 private:
  void reseed(int64_t stream) const;
  /// Copies settings_.initial_model's tensors into the model (after checking its variant and sizes).
  void load_initial_model();
  /// Sums the gradients and the loss terms (each weighted by `weight`, this process's share) over the group.
  LossTerms sum_gradients(const LossTerms& share, double weight);

  TrainingSettings settings_;
  Dataset data_;
  DatasetSplit split_;
  torch::Device device_;
  Cvae model_{nullptr};
  std::unique_ptr<torch::optim::Adam> optimizer_;
  std::unique_ptr<LossContext> context_;
  std::unique_ptr<BatchSampler> sampler_;
  int64_t step_ = 0;
  double elapsed_seconds_ = 0;
  std::shared_ptr<ProcessGroup> group_;
  std::string initial_created_by_, initial_training_;  ///< the initial model's provenance (metadata)
};

/// Sets torch's intra-op threads (threads <= 0: keeps torch's default) and, when torch runs more than one or
/// `shared` (other training processes may share the machine), limits the BLAS library's own thread pool to
/// one thread, unless OPENBLAS_NUM_THREADS says otherwise:
/// OpenBLAS's pthread build otherwise starts its threads under every torch thread, and on 2 cores a training
/// step with 2 torch threads took twice as long (docs/scaling.md, "Measured"). Returns torch's threads.
int set_training_threads(int threads, bool shared = false);

/// "AMD EPYC 7B13 (1 thread)" from /proc/cpuinfo, or the CUDA device's name ("NVIDIA H100 80GB HBM3").
std::string hardware_description(torch::Device device);

}  // namespace occtrack::learning
