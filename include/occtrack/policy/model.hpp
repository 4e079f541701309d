// The learned policy's networks at run time, in Eigen (docs/learning.md, "Networks"): a model file, checked
// against the contract by io::validate_model_file (io/model_file.hpp), is folded for inference; PointNet
// encodes the cloud, the decoder maps latent samples to trajectories and constraint parameters.
//
// Settings, setup once, solve many:
//
//   policy::Model model = policy::Model::load("models/cvae.safetensors");  // throws io::InputError
//   model.check_projection(projection_settings);       // the optimizer the planner runs must be the trained one
//   model.reserve(30, 200);                            // workspaces for 30 samples and 200 cloud points
//   Eigen::VectorXf features(model.network().features);
//   model.features(cloud, features);                   // C x 2, robot-centric, metres
//   policy::Rows outputs(30, model.network().outputs);
//   model.decode(z, observation, features, outputs);   // B x Z latent samples -> B x Y, de-normalised
//   model.postprocess(outputs, speed_max, band_min);   // clamps and floors of docs/learning.md
//
// Loading folds every batch norm (eval mode: running statistics) into the linear layer before it, the input
// normalisation into the first layer of each network, and the output scale and offset into the decoder's last
// layer; inference is float32 matrix products on the whole cloud and the whole batch (one core).
//
// Memory: features() and decode() allocate nothing while the cloud has at most the reserved points and the
// batch at most the reserved samples (larger calls grow the workspaces once). encode() allocates; it exists
// to compare with the trainer, not for the planning cycle. A Model is not safe to use from two threads at once
// (the workspaces are shared); give each thread its own.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "occtrack/core/tracking.hpp"
#include "occtrack/io/error.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::policy {

/// The model file's names (io/model_file.hpp), where the run-time code has always found them.
using io::NetworkConfig;
using io::OutputLayout;
using io::parse_variant;
using io::to_string;
using io::Variant;

/// Float rows, one per sample (row-major, as the projection's problems).
using Rows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// A point cloud, one (x, y) point per row.
using Cloud = Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>;

class Model {
 public:
  /// io::read_model_file, then the constructor: throws io::InputError naming the file and what differs from
  /// the contract (a missing file included).
  static Model load(const std::string& path);

  /// Folds a checked model file for inference (batch norms into the layers before them, the input
  /// normalisation into the first layers, the output scale and offset into the decoder's last layer).
  /// Reserves workspaces for 30 samples and network().cloud_points points.
  explicit Model(const io::ModelFile& file);
  /// io::validate_model_file(file), then the above: throws io::InputError as validate_model_file does.
  explicit Model(const io::TensorFile& file);
  ~Model();
  Model(Model&&) noexcept;
  Model& operator=(Model&&) noexcept;
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

  const std::string& source() const;
  Variant variant() const;
  const NetworkConfig& network() const;
  const OutputLayout& layout() const;
  /// The projection settings recorded in the file (training's iteration count; batch and threads default,
  /// obstacles = network().nearest_points).
  const projection::Settings& projection() const;
  /// The tracking band recorded in the file (metadata `band`, or `ranking` holding {"band": {...}}), if any.
  const std::optional<core::TrackingBand>& band() const;
  const std::map<std::string, std::string>& metadata() const;

  /// Throws io::InputError naming the first field where `settings` (the optimizer the planner will run)
  /// differs from the file's: degree, steps, horizon, via steps, obstacle radius, speed and acceleration
  /// bounds, obstacles (N), and rho when the file records it, e.g. "model.safetensors: projection.horizon is 4
  /// in the model, the planner uses 5". Iterations, batch and threads may differ.
  void check_projection(const projection::Settings& settings) const;
  /// Throws io::InputError "SOURCE: variant is 'bc' but planner cvae needs 'cvae'" unless variant() == expected.
  void require_variant(Variant expected, const std::string& planner) const;

  /// Sizes the workspaces for up to max_batch decoder samples and max_points cloud points (at least 1 each).
  void reserve(int max_batch, int max_points);

  /// PointNet: cloud (C x 2, robot-centric, not normalised; C >= 1, any C since it max-pools) -> features
  /// (size F). Duplicate points do not change the result.
  void features(const Eigen::Ref<const Cloud>& cloud, Eigen::Ref<Eigen::VectorXf> out);
  /// Decoder: latent samples z (B x Z), the observation (size O, not normalised) and the cloud features
  /// (size F) shared by all samples -> out (B x Y), de-normalised (raw * scale + offset), before
  /// post-processing. out must have B rows and Y columns.
  void decode(const Eigen::Ref<const Rows>& z, const Eigen::Ref<const Eigen::VectorXf>& observation,
              const Eigen::Ref<const Eigen::VectorXf>& features, Eigen::Ref<Rows> out);
  /// Encoder q(z | observation, features, expert_xi): expert_xi (B x 2n, coefficients x then y, not
  /// normalised) -> mu and sigma (B x Z each, sigma = softplus + 1e-4). Allocates; for tests and tools.
  void encode(const Eigen::Ref<const Eigen::VectorXf>& observation, const Eigen::Ref<const Eigen::VectorXf>& features,
              const Eigen::Ref<const Rows>& expert_xi, Eigen::Ref<Rows> mu, Eigen::Ref<Rows> sigma) const;
  /// Post-processing (docs/learning.md): terminal velocities clamped to [-speed_max, speed_max] per axis;
  /// d_min = max(d_min, distance_floor) at every step (the band's min, 1.0 m).
  void postprocess(Eigen::Ref<Rows> outputs, double speed_max, double distance_floor) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The turn between a model's network frame and the robot-centric frame (io::NetworkConfig::target_frame;
/// docs/learning.md, "Target frame"). For a target-frame model, aim() turns by the target's bearing, so that
/// the target lies on +x in the network's frame; for a robot-frame model, and for a target on the robot, it is
/// the identity. Build once per model (it lists the turning outputs); aim() and the turns allocate nothing.
///
///   policy::FrameRotation turn(model.network());
///   turn.aim(target_x, target_y);                  // robot-centric target position
///   turn.into_network(observation, cloud);         // in place
///   model.features(cloud, features); model.decode(z, observation, features, outputs);
///   turn.out_of_network(outputs);                  // in place, before postprocess()
class FrameRotation {
 public:
  explicit FrameRotation(const NetworkConfig& network);
  bool turns() const { return target_frame_; }
  void aim(double target_x, double target_y);
  /// observation (size 6: three (x, y) pairs) and cloud (C x 2) into the network's frame.
  void into_network(Eigen::Ref<Eigen::VectorXf> observation, Eigen::Ref<Cloud> cloud) const;
  /// Every row of the decoder outputs (B x Y) from the network's frame back to the robot-centric one.
  void out_of_network(Eigen::Ref<Rows> outputs) const;

 private:
  bool target_frame_ = false;
  float cos_ = 1.0f, sin_ = 0.0f;
  std::vector<std::pair<int, int>> pairs_;  // the outputs' turning (x, y) columns
};

/// A model file with random weights of the right shapes and plausible normalisation (outputs near a straight
/// path towards +x, distance bounds near the default band), for tests and benchmarks before a trained model
/// exists, written through io::to_tensor_file. Deterministic in the seed. `variant` is "cvae", "bc" or
/// "fixed-q" (io::InputError otherwise).
io::TensorFile random_model(const NetworkConfig& network, const projection::Settings& projection, std::string variant,
                            std::uint64_t seed);

}  // namespace occtrack::policy
