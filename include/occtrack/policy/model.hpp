// The learned policy's networks at run time, in Eigen (docs/learning.md, "Model file" and "Networks"): a
// model file is read, checked against the contract and folded for inference; PointNet encodes the cloud,
// the decoder maps latent samples to trajectories and constraint parameters.
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
#include "occtrack/io/safetensors.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::policy {

inline constexpr const char* kModelFormat = "occtrack.model.v1";

/// Float rows, one per sample (row-major, as the projection's problems).
using Rows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// A point cloud, one (x, y) point per row.
using Cloud = Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>;

/// What the networks were trained for: `cvae` (the paper's policy), `bc` (no projection; the decoder's
/// xi_bar is the plan) and `fixed-q` (nominal d_min, d_max and terminal state instead of predictions).
enum class Variant { cvae, bc, fixed_q };

/// "cvae", "bc", "fixed-q" (the metadata's spelling).
const char* to_string(Variant variant);
/// The variant of a metadata spelling; throws io::InputError listing the three otherwise.
Variant parse_variant(const std::string& text);

/// Sizes of the networks (docs/learning.md, "Sizes"); the metadata key `network` holds them as JSON.
struct NetworkConfig {
  int observation = 6;     ///< O: robot vx, vy; target x, y (relative); target vx, vy
  int cloud_points = 200;  ///< C: perception's cloud_size
  int nearest_points = 60; ///< N: the optimizer's obstacles (perception's nearest_count)
  int latent = 2;          ///< Z
  std::vector<int> pointnet_widths = {64, 64, 64, 128, 256};  ///< per-point 1x1 convolutions; the last is E
  int pointnet_hidden = 256;  ///< H_p
  int features = 64;          ///< F
  int hidden = 256;           ///< H: encoder and decoder width
  int layers = 3;             ///< L: hidden layers of the encoder and of the decoder
  int outputs = 252;          ///< Y = 4 + 4 + 2n + m + m + 2n
  int coefficients = 11;      ///< n = degree + 1
  int steps = 100;            ///< m
  double batch_norm_eps = 1e-5;

  /// The default sizes, with n, m, N and Y taken from the projection settings.
  static NetworkConfig for_projection(const projection::Settings& settings);
  /// 8 + 4n + 2m: the decoder outputs the sizes imply.
  int expected_outputs() const { return 8 + 4 * coefficients + 2 * steps; }
  /// True when every size is usable (positive, Y consistent with n and m, observation 6, eps > 0).
  /// Otherwise false, and *error names the field and the rule, e.g. "outputs (250) must be 8 + 4n + 2m = 252".
  bool validate(std::string* error = nullptr) const;
  /// The metadata JSON: {"observation": 6, "cloud_points": 200, ..., "batch_norm_eps": 1e-05}.
  std::string to_json() const;
  /// Parses the metadata JSON; throws io::InputError "SOURCE: network.KEY: rule" (unknown keys are ignored).
  static NetworkConfig parse(const std::string& json_text, const std::string& source);

  bool operator==(const NetworkConfig&) const = default;
};

/// Column offsets of the decoder outputs (docs/learning.md: terminal, via, lambda0, d_min, d_max, xi_bar).
struct OutputLayout {
  int terminal = 0;      ///< 4: x, y, vx, vy
  int via = 4;           ///< 4: x1, y1, x2, y2
  int lambda0 = 8;       ///< 2n
  int distance_min = 0;  ///< m
  int distance_max = 0;  ///< m
  int xi_bar = 0;        ///< 2n
  int size = 0;          ///< Y

  explicit OutputLayout(const NetworkConfig& network);
};

/// The metadata JSON of projection settings (the projection-case "config" layout: degree, steps, horizon,
/// iterations, obstacle_radius, speed_min, speed_max, accel_max, via_steps [s1, s2], rho {...}).
std::string projection_json(const projection::Settings& settings);
/// Parses it; iterations and rho are optional (defaults kept), unknown keys are ignored. Throws io::InputError
/// "SOURCE: projection.KEY: rule".
projection::Settings parse_projection_json(const std::string& json_text, const std::string& source);
/// The metadata JSON of a tracking band: {"min": 1.0, "reference": 2.0, "max": 3.0}.
std::string band_json(const core::TrackingBand& band);

class Model {
 public:
  /// Reads a model file and checks it (see the constructor); throws io::InputError naming the file and what
  /// differs (a missing file included).
  static Model load(const std::string& path);

  /// Checks a model file already in memory (file.source names it in messages, "model" when empty) and folds
  /// it for inference. Throws io::InputError when: metadata `format` is not "occtrack.model.v1"; `variant` is
  /// not cvae, bc or fixed-q; `network` or `projection` is missing, not JSON, lacks a field or breaks
  /// NetworkConfig::validate(); network and projection disagree (n, m); a tensor of docs/learning.md is
  /// missing, has another shape ("tensor 'decoder.out.weight' has shape [252, 128], expected [252, 256]",
  /// prefixed by the metadata field it contradicts when there is one: "metadata network.features is 32, the
  /// tensors say 64"), or holds a non-finite value; a normalisation std or batch-norm variance is not positive.
  /// Reserves workspaces for 30 samples and network().cloud_points points.
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

/// A model file with random weights of the right shapes and plausible normalisation (outputs near a straight
/// path towards +x, distance bounds near the default band), for tests and benchmarks before a trained model
/// exists. Deterministic in the seed. `variant` is written as given ("cvae", "bc", "fixed-q").
io::TensorFile random_model(const NetworkConfig& network, const projection::Settings& projection, std::string variant,
                            std::uint64_t seed);

}  // namespace occtrack::policy
