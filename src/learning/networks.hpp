// The policy's networks in LibTorch (docs/learning.md, "Networks"): PointNet, the CVAE's encoder and decoder,
// the normalisation buffers, the post-processing of the decoder's outputs, and the map from those outputs to
// the projection's inputs for each variant.
//
// Module and buffer names are the model file's tensor names: CvaeImpl::named_parameters() and
// named_buffers() (less batch norm's num_batches_tracked) give exactly "pointnet.conv0.weight", ...,
// "norm.output.scale" of docs/learning.md, so that the export is a plain walk over them.
//
//   io::NetworkConfig config;                       // defaults of docs/learning.md
//   learning::Cvae model(config, /*dropout=*/0.3);
//   model->set_normalization(stats);                // from learning::compute_normalization
//   learning::CvaeForward f = model->forward(observation, cloud, expert_xi);  // training: z ~ q(z | ...)
//   model->eval();                                                              // inference: z ~ N(0, I)
//   torch::Tensor y = model->decode(z, observation, model->features(cloud));
#pragma once

#include <torch/torch.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "learning/projection.hpp"
#include "occtrack/core/tracking.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::learning {

// The sizes, the output layout and the variants are the model file's (io/model_file.hpp): io::NetworkConfig,
// io::OutputLayout, io::Variant. What only training uses (PointNet's dropout) is passed beside them.

// ---------------------------------------------------------------------------------------------------------
// Normalisation buffers ("norm.*"): statistics of the training set, stored in the model file.

/// (x - mean) / std, per feature (the last dimension).
class StandardizerImpl : public torch::nn::Module {
 public:
  explicit StandardizerImpl(int size);
  torch::Tensor forward(const torch::Tensor& x);
  torch::Tensor mean, std;
};
TORCH_MODULE(Standardizer);

/// raw * scale + offset, per output.
class OutputScalingImpl : public torch::nn::Module {
 public:
  explicit OutputScalingImpl(int size);
  torch::Tensor forward(const torch::Tensor& raw);
  torch::Tensor offset, scale;
};
TORCH_MODULE(OutputScaling);

/// Statistics that set the normalisation; shapes O, 2, 2n, Y (float32 on any device).
struct NormalizationStats {
  torch::Tensor observation_mean, observation_std;
  torch::Tensor cloud_mean, cloud_std;
  torch::Tensor xi_mean, xi_std;
  torch::Tensor output_offset, output_scale;
};

class NormalizationImpl : public torch::nn::Module {
 public:
  explicit NormalizationImpl(const io::NetworkConfig& config);
  /// Copies the statistics into the buffers (checks their sizes; std::invalid_argument otherwise).
  void set(const NormalizationStats& stats);
  Standardizer observation{nullptr}, cloud{nullptr}, xi{nullptr};
  OutputScaling output{nullptr};
};
TORCH_MODULE(Normalization);

// ---------------------------------------------------------------------------------------------------------
// The networks (docs/learning.md, "Networks, in eval mode"). Inputs are already normalised.

/// Returns the sum of a tensor over the processes of a data-parallel training (learning/distributed.hpp).
/// With one set, training-mode batch norm takes its statistics over the global batch and its input gradient
/// from sums over the global batch, as one process would. Empty: one process.
using BatchSum = std::function<torch::Tensor(const torch::Tensor&)>;

/// Batch norm of x [M, channels]: bn itself, or in training mode with `sum` set, the same formulas over the
/// rows of every process (running statistics updated alike on every process; the weight's and bias's
/// gradients are this process's parts, to be summed with the other parameters').
torch::Tensor normalize_batch(torch::nn::BatchNorm1d& bn, const torch::Tensor& x, const BatchSum* sum);

/// The random draws of one training pass (the latent noise and PointNet's dropout), drawn for the whole
/// global batch from torch's CPU generator and then cut to a process's rows, so that a data-parallel run
/// draws for every row what one process draws.
struct PassNoise {
  torch::Tensor eps;            ///< [B, Z], N(0, I)
  torch::Tensor dropout_scale;  ///< [B, H_p], 0 or 1 / (1 - p); undefined when p = 0
  /// Draws eps, then the dropout mask, on the CPU, and moves them to `device`.
  static PassNoise draw(int64_t rows, const io::NetworkConfig& config, double dropout, torch::Device device);
  /// Rows [begin, end).
  PassNoise rows(int64_t begin, int64_t end) const;
};

/// Per-point shared layers (1x1 convolutions as Linear over the last dimension) with batch norm over batch
/// and points, max pool over points, then fc0, batch norm, ReLU, dropout (training only) and fc1 to F features.
class PointNetImpl : public torch::nn::Module {
 public:
  PointNetImpl(const io::NetworkConfig& config, double dropout, std::shared_ptr<BatchSum> sum = nullptr);
  /// cloud: [B, C, 2], normalised. Returns [B, F]. In training mode, dropout multiplies by `dropout_scale`
  /// when it is given (PassNoise) and draws its own mask otherwise.
  torch::Tensor forward(const torch::Tensor& cloud, const torch::Tensor& dropout_scale = {});
  /// The per-point part alone, max-pooled: [B, E] (for tests against the Eigen policy).
  torch::Tensor pooled(const torch::Tensor& cloud);

 private:
  std::vector<torch::nn::Linear> conv_;
  std::vector<torch::nn::BatchNorm1d> bn_;
  torch::nn::Linear fc0_{nullptr}, fc1_{nullptr};
  torch::nn::BatchNorm1d fc_bn0_{nullptr};
  torch::nn::Dropout dropout_{nullptr};
  std::shared_ptr<BatchSum> sum_;
};
TORCH_MODULE(PointNet);

/// L times relu(bn(fc x)); the building block of the encoder and the decoder (names fc{i}, bn{i}).
class MlpTrunk {
 public:
  MlpTrunk() = default;
  MlpTrunk(torch::nn::Module& owner, int input, const io::NetworkConfig& config,
           std::shared_ptr<BatchSum> sum = nullptr);
  torch::Tensor forward(torch::Tensor x);

 private:
  std::vector<torch::nn::Linear> fc_;
  std::vector<torch::nn::BatchNorm1d> bn_;
  std::shared_ptr<BatchSum> sum_;
};

struct Posterior {
  torch::Tensor mean;   ///< mu, [B, Z]
  torch::Tensor sigma;  ///< softplus(std x) + 1e-4, [B, Z]
};

/// q(z | observation, features, expert trajectory): input [obs_n, features, xi_n] (O + F + 2n).
class EncoderImpl : public torch::nn::Module {
 public:
  explicit EncoderImpl(const io::NetworkConfig& config, std::shared_ptr<BatchSum> sum = nullptr);
  Posterior forward(const torch::Tensor& observation, const torch::Tensor& features, const torch::Tensor& xi);

 private:
  MlpTrunk trunk_;
  torch::nn::Linear mean_{nullptr}, std_{nullptr};
};
TORCH_MODULE(Encoder);

/// p(outputs | z, observation, features): input [z, obs_n, features] (Z + O + F); returns raw [B, Y].
class DecoderImpl : public torch::nn::Module {
 public:
  explicit DecoderImpl(const io::NetworkConfig& config, std::shared_ptr<BatchSum> sum = nullptr);
  torch::Tensor forward(const torch::Tensor& z, const torch::Tensor& observation, const torch::Tensor& features);

 private:
  MlpTrunk trunk_;
  torch::nn::Linear out_{nullptr};
};
TORCH_MODULE(Decoder);

/// The network frame of a target-frame model (io::NetworkConfig::target_frame; docs/learning.md, "Target
/// frame"), per row: turned about the robot by the bearing of the target (observation columns 2 and 3), so
/// that the target lies on +x; the identity for a target on the robot. policy::FrameRotation is the Eigen twin.
struct FrameTurn {
  torch::Tensor cos, sin;  ///< [B, 1]
  explicit FrameTurn(const torch::Tensor& observation);
  /// Observation [B, 6], cloud [B, C, 2] and expert coefficients [B, 2n] (x block, then y) into the frame.
  torch::Tensor observation_in(const torch::Tensor& observation) const;
  torch::Tensor cloud_in(const torch::Tensor& cloud) const;
  torch::Tensor xi_in(const torch::Tensor& xi) const;
  /// Decoder outputs [B, Y] out of the frame (io::OutputLayout::turning_pairs turn; d_min, d_max do not).
  torch::Tensor outputs_out(const torch::Tensor& outputs, const io::NetworkConfig& config) const;
};

struct CvaeForward {
  torch::Tensor outputs;  ///< decoder outputs y (scaled, before post-processing), [B, Y]
  Posterior posterior;    ///< q(z | ...), for the KL term
};

/// The whole model: normalisation buffers, PointNet, encoder and decoder. Raw (unnormalised) inputs.
class CvaeImpl : public torch::nn::Module {
 public:
  /// Throws std::invalid_argument "network: FIELD ..." when config.validate() fails, or when dropout is not
  /// in [0, 1).
  CvaeImpl(const io::NetworkConfig& config, double dropout);

  void set_normalization(const NormalizationStats& stats) { norm->set(stats); }

  /// Data-parallel training: batch norm's statistics summed by `sum` (see BatchSum; empty: this process's).
  void set_batch_sum(BatchSum sum);

  /// PointNet features of raw clouds [B, C, 2] -> [B, F] (dropout_scale: see PointNetImpl::forward).
  torch::Tensor features(const torch::Tensor& cloud, const torch::Tensor& dropout_scale = {});
  /// q(z | observation, features, expert_xi) from raw observation [B, O] and expert_xi [B, 2n].
  Posterior encode(const torch::Tensor& observation, const torch::Tensor& features, const torch::Tensor& expert_xi);
  /// Decoder outputs y = raw * scale + offset, [B, Y], from z [B, Z] and raw observation [B, O].
  torch::Tensor decode(const torch::Tensor& z, const torch::Tensor& observation, const torch::Tensor& features);
  /// features(), encode() and decode() work in the network's frame: for a target-frame model (config().target_frame)
  /// the caller turns their inputs and outputs (FrameTurn). forward() and sample() take and return robot-centric
  /// tensors and turn by themselves.
  /// Training pass: z = mu + sigma * eps with eps and the dropout mask from `noise`, or drawn from torch's
  /// global generator when it is null.
  CvaeForward forward(const torch::Tensor& observation, const torch::Tensor& cloud, const torch::Tensor& expert_xi,
                      const PassNoise* noise = nullptr);

  /// Inference: decoder outputs [B, Y] (robot-centric, before post-processing) of latent samples z [B, Z] for
  /// robot-centric observation [B, O] and cloud [B, C, 2].
  torch::Tensor sample(const torch::Tensor& z, const torch::Tensor& observation, const torch::Tensor& cloud);
  const io::NetworkConfig& config() const { return config_; }

  Normalization norm{nullptr};
  PointNet pointnet{nullptr};
  Encoder encoder{nullptr};
  Decoder decoder{nullptr};

 private:
  io::NetworkConfig config_;
  std::shared_ptr<BatchSum> batch_sum_;  ///< shared with the submodules; empty function: one process
};
TORCH_MODULE(Cvae);

/// The model's tensors by file name (docs/learning.md), parameters and buffers, without batch norm's
/// num_batches_tracked. The tensors are the module's own (not copies).
std::vector<std::pair<std::string, torch::Tensor>> named_model_tensors(CvaeImpl& model);

// ---------------------------------------------------------------------------------------------------------
// Post-processing and the projection's inputs (docs/learning.md, "Post-processing and the cycle").

/// The decoder outputs split by the layout; each [B, ...].
struct DecodedOutputs {
  torch::Tensor terminal;      ///< [B, 4] x, y, vx, vy
  torch::Tensor via_points;    ///< [B, 4] x1, y1, x2, y2
  torch::Tensor lambda0;       ///< [B, 2n]
  torch::Tensor distance_min;  ///< [B, m]
  torch::Tensor distance_max;  ///< [B, m]
  torch::Tensor xi_bar;        ///< [B, 2n]
};

DecodedOutputs split_outputs(const torch::Tensor& outputs, const io::NetworkConfig& config);
/// Step 1: terminal velocities clamped to [-speed_max, speed_max] per axis; d_min floored at band_min.
DecodedOutputs post_process(const DecodedOutputs& decoded, double speed_max, double band_min);

/// The sampled Bernstein basis as tensors (core::bernstein_basis), for W xi and the nominal q.
struct TrajectoryBasis {
  torch::Tensor P, Pd;  ///< [m, n]
  TrajectoryBasis() = default;
  TrajectoryBasis(const projection::Settings& settings, torch::Dtype dtype, torch::Device device);
  /// W xi: positions (x at the m steps, then y), [B, 2m], from coefficients [B, 2n].
  torch::Tensor positions(const torch::Tensor& xi) const;
};

/// What the policy needs beyond the decoder outputs to build the projection's inputs.
struct PolicySettings {
  io::Variant variant = io::Variant::cvae;
  projection::Settings projection;
  core::TrackingBand band;
};

/// Maps decoder outputs y [B, Y] (post-processing included here) and the cycle's observation [B, O] and
/// obstacles [B, N, 4] to the projection's inputs:
/// - robot_velocity = observation[0:2], target = observation[2:6], obstacles as given;
/// - cvae: terminal, via points, lambda0, d_min, d_max and xi_bar from the decoder;
/// - fixed-q: q nominal as planners/context.cpp fill_row: terminal position and velocity read off xi_bar
///   (velocity capped at speed_max in norm), d_min = band.min, d_max = band.max; via points and lambda0
///   from the decoder;
/// - bc: as cvae (the caller skips the projection; the plan is xi_bar).
ProjectionInputs policy_outputs(const torch::Tensor& outputs, const torch::Tensor& observation,
                                const torch::Tensor& obstacles, const PolicySettings& settings,
                                const TrajectoryBasis& basis, const io::NetworkConfig& config);

}  // namespace occtrack::learning
