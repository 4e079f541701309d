// The model file (docs/learning.md, "Model file"): the one statement of what the trainer writes and the
// run-time policy reads. A safetensors file whose metadata `format` is "occtrack.model.v1", with the variant,
// the network sizes, the projection settings it was trained through and the tracking band, and the tensors
// of docs/learning.md's table (float32; float64 is read too).
//
//   io::ModelFile model = io::read_model_file("models/cvae.safetensors");  // checked; throws io::InputError
//   model.network.features;                         // 64
//   std::vector<double> w = model.values("decoder.out.weight");   // [Y, H], row-major
//   io::write_model_file("copy.safetensors", model);
//
// No LibTorch and no inference here: policy::Model folds a checked ModelFile for Eigen inference, and
// learning's export fills one from the torch modules.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "occtrack/core/tracking.hpp"
#include "occtrack/io/error.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::io {

/// `__metadata__.format` of a model file.
inline constexpr const char* kModelFormat = "occtrack.model.v1";

/// What the networks were trained for: `cvae` (the paper's policy), `bc` (no projection; the decoder's
/// xi_bar is the plan) and `fixed-q` (nominal d_min, d_max and terminal state instead of predictions).
enum class Variant { cvae, bc, fixed_q };

/// "cvae", "bc", "fixed-q" (the metadata's spelling).
const char* to_string(Variant variant);
/// The variant of a metadata spelling; throws io::InputError listing the three otherwise.
Variant parse_variant(const std::string& text);

/// Sizes of the networks (docs/learning.md, "Sizes"); the metadata key `network` holds them as JSON.
/// Upper bounds of NetworkConfig's sizes (validate() refuses larger ones).
inline constexpr int kMaxNetworkPoints = 100000;  ///< cloud_points, nearest_points (the projection's point bound)
inline constexpr int kMaxNetworkWidth = 16384;    ///< latent, widths, features, hidden, n, m
inline constexpr int kMaxNetworkLayers = 64;      ///< layers, PointNet widths

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
  /// The frame the networks see (docs/learning.md, "Target frame"). false: robot-centric, axes parallel to the
  /// world's (every model before issue 12; metadata "frame": "robot" or no "frame"). true: also rotated about
  /// the robot so that the target lies on +x ("frame": "target"); the policy rotates the observation and the
  /// cloud into it and the decoder's outputs back (io::OutputLayout::turning_pairs).
  bool target_frame = false;

  /// The default sizes, with n, m, N and Y taken from the projection settings.
  static NetworkConfig for_projection(const projection::Settings& settings);
  /// 8 + 4n + 2m: the decoder outputs the sizes imply.
  int expected_outputs() const { return 8 + 4 * coefficients + 2 * steps; }
  /// True when every size is usable (positive, Y consistent with n and m, observation 6, eps > 0).
  /// Otherwise false, and *error names the field and the rule, e.g. "outputs (250) must be 8 + 4n + 2m = 252".
  bool validate(std::string* error = nullptr) const;
  /// The metadata JSON: {"batch_norm_eps": 1e-05, "cloud_points": 200, ..., "steps": 100}.
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
  /// The (x, y) column pairs of the outputs that turn with the frame: terminal position and velocity, both via
  /// points, and every coefficient pair of lambda0 and xi_bar (x block, then y block). d_min and d_max do not.
  std::vector<std::pair<int, int>> turning_pairs() const;
};

/// The (x, y) pairs of the observation (robot velocity, target position, target velocity): every entry turns.
inline constexpr int kObservationPairs[3][2] = {{0, 1}, {2, 3}, {4, 5}};

/// The metadata JSON of a tracking band: {"max": 3.0, "min": 1.0, "reference": 2.0}.
std::string band_json(const core::TrackingBand& band);

/// What a tensor of the file is, which says how it is checked (and how a random model fills it).
enum class TensorRole {
  input_mean,      ///< norm.{observation,cloud,xi}.mean
  input_std,       ///< norm.{observation,cloud,xi}.std: must be positive
  output_offset,   ///< norm.output.offset
  output_scale,    ///< norm.output.scale
  weight,          ///< a linear layer's or 1x1 convolution's weight [out, in]
  bias,            ///< its bias [out]
  norm_weight,     ///< batch norm gamma
  norm_bias,       ///< batch norm beta
  norm_mean,       ///< batch norm running_mean
  norm_variance,   ///< batch norm running_var: must not be negative
};

/// One tensor the file must hold: its name, its shape, and per dimension the metadata field that sets it
/// ("network.features", ...; empty when none in particular), for messages that name the contradiction.
struct TensorSpec {
  std::string name;
  std::vector<std::int64_t> shape;
  std::vector<std::string> fields;
  TensorRole role = TensorRole::weight;
};

/// Every tensor of docs/learning.md's table for these sizes, in the table's order: the normalisation
/// (norm.observation, norm.cloud, norm.xi, norm.output), PointNet (conv{i} and bn{i}, fc0, fc_bn0, fc1), the
/// encoder (fc{i}, bn{i}, mean, std), the decoder (fc{i}, bn{i}, out). A layer's weight comes before its bias,
/// and a batch norm's weight, bias, running_mean, running_var after the layer it follows.
std::vector<TensorSpec> model_tensors(const NetworkConfig& network);

/// A model file's contents, checked against the contract.
struct ModelFile {
  std::string source;  ///< names the file in messages ("model" when read from a nameless TensorFile)
  Variant variant = Variant::cvae;
  NetworkConfig network;
  /// The optimizer trained through (metadata `projection`): iterations are the training's; obstacles =
  /// network.nearest_points; batch and threads keep their defaults.
  projection::Settings projection;
  /// Whether the file's `projection` records rho (policy::Model::check_projection compares it only then).
  /// to_tensor_file writes rho only when this is true, so a file keeps its answer through a round trip.
  bool projection_has_rho = true;
  /// Metadata `band`, or `ranking` holding {"band": {...}}, when the file records one.
  std::optional<core::TrackingBand> band;
  /// Every metadata key as read. Written: these keys, then the contract's (format, variant, network,
  /// projection, band) from the fields above; provenance such as `training` and `created_by` lives here.
  std::map<std::string, std::string> metadata;
  /// The tensors by name (read: F32 or F64, each of model_tensors(network) with its shape, finite).
  std::map<std::string, Tensor> tensors;

  /// The values of a tensor, row-major, as double; throws io::InputError "SOURCE: tensor 'NAME' is missing".
  std::vector<double> values(const std::string& name) const;
};

/// Checks a model file in memory (file.source names it, "model" when empty). Throws io::InputError
/// "SOURCE: ..." when: metadata `format` is not "occtrack.model.v1"; `variant` is not cvae, bc or fixed-q;
/// `network` or `projection` is missing, not JSON, lacks a field or breaks NetworkConfig::validate() or
/// projection::Settings::validate(); network and projection disagree (n, m); a tensor of model_tensors() is
/// missing, has another shape ("tensor 'decoder.out.weight' has shape [252, 128], expected [252, 256]",
/// prefixed by the metadata field it contradicts when there is one: "metadata network.features is 32, the
/// tensors say 64"), has another dtype than F32 or F64, or holds a non-finite value; a normalisation std is
/// not positive or a batch-norm variance negative. Tensors beyond the table are kept and not checked.
ModelFile validate_model_file(const TensorFile& file);
/// read_safetensors, then validate_model_file; throws io::InputError naming the file (a missing one included).
ModelFile read_model_file(const std::string& path);

/// The file's contents: model.metadata, then format, variant, network, projection (with
/// "training_iterations" = projection.iterations, docs/learning.md) and band when set; the tensors as held.
TensorFile to_tensor_file(const ModelFile& model);
/// Writes to_tensor_file(model) (io::InputError when it cannot be written). Does not check the contents.
void write_model_file(const std::string& path, const ModelFile& model);

}  // namespace occtrack::io
