// The export of a trained model as a model file (io/model_file.hpp, the contract): every tensor of the
// model in float32 on the CPU under its docs/learning.md name, the metadata the run-time policy checks
// (variant, network, projection, band) and the training's provenance (`training`, `created_by`).
//
//   learning::export_model("model.safetensors", trainer.model(), trainer.model_metadata(summary, created_by));
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "learning/networks.hpp"
#include "learning/trainer.hpp"
#include "occtrack/core/tracking.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::learning {

/// Where a model came from (the `training` metadata JSON).
struct TrainingRecord {
  struct File {
    std::string path;
    int64_t rows = 0;
    int64_t episodes = 0;
    std::string driver;  ///< the dataset's `driver` metadata: "expert", a planner, or the model file that drove
    bool learned_driver = false;  ///< a learned policy drove (a DAgger round; sim::learned_driver)
  };
  std::vector<File> datasets;
  int64_t train_rows = 0, validation_rows = 0;
  std::uint64_t seed = 0;
  int64_t steps = 0, batch = 0, kl_warmup_steps = 0;
  double learning_rate = 0, learning_rate_final = 0, beta = 0, dropout = 0;  ///< learning rate: cosine, first to final
  int iterations = 0;           ///< K in training
  bool plain_projection = false;
  std::string device, hardware;
  double seconds = 0;
  LossTerms final_loss;
  std::optional<LossTerms> validation;
  /// The model this training started from (TrainingSettings::initial_model), when it did not start from
  /// random weights: its path, `created_by` and `training` JSON, kept whole so that the lineage is recorded.
  struct Initial {
    std::string path, created_by, training;
  };
  std::optional<Initial> initial_model;
};

struct ModelMetadata {
  io::Variant variant = io::Variant::cvae;
  io::NetworkConfig network;
  projection::Settings projection;  ///< iterations = the training iteration count
  core::TrackingBand band;
  TrainingRecord training;
  std::string created_by;           ///< occtrack version and command line
};

/// The `training` metadata as JSON text.
std::string training_json(const TrainingRecord& record);

/// The file's contents: variant, network, projection, band, metadata `training` and `created_by`, and every
/// tensor of named_model_tensors() as float32 (io::to_tensor_file adds the format).
io::ModelFile model_file(CvaeImpl& model, const ModelMetadata& metadata);
/// Writes model_file() with io::write_model_file (io::InputError when it cannot be written).
void export_model(const std::string& path, CvaeImpl& model, const ModelMetadata& metadata);

}  // namespace occtrack::learning
