#include "learning/networks.hpp"

#include <stdexcept>

#include "occtrack/core/bernstein.hpp"

namespace occtrack::learning {

namespace nn = torch::nn;
using io::NetworkConfig;
using torch::indexing::Slice;

// ---------------------------------------------------------------------------------------------------------

StandardizerImpl::StandardizerImpl(int size) {
  mean = register_buffer("mean", torch::zeros({size}));
  std = register_buffer("std", torch::ones({size}));
}

torch::Tensor StandardizerImpl::forward(const torch::Tensor& x) { return (x - mean) / std; }

OutputScalingImpl::OutputScalingImpl(int size) {
  offset = register_buffer("offset", torch::zeros({size}));
  scale = register_buffer("scale", torch::ones({size}));
}

torch::Tensor OutputScalingImpl::forward(const torch::Tensor& raw) { return raw * scale + offset; }

NormalizationImpl::NormalizationImpl(const NetworkConfig& c) {
  observation = register_module("observation", Standardizer(c.observation));
  cloud = register_module("cloud", Standardizer(2));
  xi = register_module("xi", Standardizer(2 * c.coefficients));
  output = register_module("output", OutputScaling(c.outputs));
}

namespace {

void copy_checked(torch::Tensor& buffer, const torch::Tensor& value, const char* name) {
  if (!value.defined() || value.numel() != buffer.numel())
    throw std::invalid_argument(std::string("normalisation: ") + name + " must have " +
                                std::to_string(buffer.numel()) + " values, got " +
                                (value.defined() ? std::to_string(value.numel()) : std::string("none")));
  torch::NoGradGuard no_grad;
  buffer.copy_(value.reshape(buffer.sizes()).to(buffer.options()));
}

}  // namespace

void NormalizationImpl::set(const NormalizationStats& s) {
  copy_checked(observation->mean, s.observation_mean, "observation mean");
  copy_checked(observation->std, s.observation_std, "observation std");
  copy_checked(cloud->mean, s.cloud_mean, "cloud mean");
  copy_checked(cloud->std, s.cloud_std, "cloud std");
  copy_checked(xi->mean, s.xi_mean, "xi mean");
  copy_checked(xi->std, s.xi_std, "xi std");
  copy_checked(output->offset, s.output_offset, "output offset");
  copy_checked(output->scale, s.output_scale, "output scale");
}

// ---------------------------------------------------------------------------------------------------------

namespace {

nn::BatchNorm1d batch_norm(int features, const NetworkConfig& c) {
  return nn::BatchNorm1d(nn::BatchNorm1dOptions(features).eps(c.batch_norm_eps));
}

}  // namespace

namespace {

/// Training batch norm over the rows of every process, as one autograd node with its own backward: torch's
/// formulas (biased variance to normalise, unbiased in the running estimate) with the statistics, and in the
/// backward the two per-channel sums the input gradient needs, summed over the processes. Then every process
/// gets its rows' share of the one-process gradient. The weight's and bias's gradients are this process's
/// parts (the trainer sums parameter gradients afterwards). A fused eval-mode batch_norm does the output;
/// the backward makes six passes over x, where autograd through the plain formulas made about twice as many.
class GlobalBatchNorm : public torch::autograd::Function<GlobalBatchNorm> {
 public:
  static torch::Tensor forward(torch::autograd::AutogradContext* context, const torch::Tensor& x,
                               const torch::Tensor& weight, const torch::Tensor& bias, const BatchSum* sum,
                               double eps, torch::Tensor running_mean, torch::Tensor running_var, double momentum) {
    const int64_t channels = x.size(1);
    const double rows = static_cast<double>(x.size(0));
    const auto [local_var, local_mean] = torch::var_mean(x, {0}, /*unbiased=*/false);
    // The mean, then the variance by the parallel formula: sum of rows * (var + (mean_p - mean)^2).
    const torch::Tensor first = (*sum)(torch::cat({local_mean * rows, torch::full({1}, rows, x.options())}));
    const double count = first.index({channels}).item<double>();
    const torch::Tensor mean = first.index({Slice(0, channels)}) / count;
    const torch::Tensor var = (*sum)((local_var + (local_mean - mean).square()) * rows) / count;
    const torch::Tensor invstd = torch::rsqrt(var + eps);
    running_mean.mul_(1 - momentum).add_(mean, momentum);
    running_var.mul_(1 - momentum).add_(var * (count / std::max(1.0, count - 1)), momentum);
    context->save_for_backward({x, weight, mean, invstd});
    context->saved_data["count"] = count;
    context->saved_data["sum"] = reinterpret_cast<std::int64_t>(sum);
    return torch::batch_norm(x, weight, bias, mean, var, /*training=*/false, 0.0, eps, /*cudnn_enabled=*/false);
  }

  static torch::autograd::tensor_list backward(torch::autograd::AutogradContext* context,
                                               torch::autograd::tensor_list gradients) {
    const auto saved = context->get_saved_variables();
    const torch::Tensor &x = saved[0], &weight = saved[1], &mean = saved[2], &invstd = saved[3];
    const double count = context->saved_data["count"].toDouble();
    const auto* sum = reinterpret_cast<const BatchSum*>(context->saved_data["sum"].toInt());
    const torch::Tensor dy = gradients[0].contiguous();
    const int64_t channels = x.size(1);
    const torch::Tensor centered = x - mean;
    const torch::Tensor sum_dy = dy.sum(0), sum_dy_centered = (dy * centered).sum(0);
    const torch::Tensor global = (*sum)(torch::cat({sum_dy, sum_dy_centered}));
    // dx = w invstd (dy - S_dy / N - (x - mean) invstd^2 S_dy(x - mean) / N), the sums S over every process.
    const torch::Tensor scale = weight * invstd;
    const torch::Tensor k_centered = -scale * invstd * invstd * global.index({Slice(channels, 2 * channels)}) / count;
    const torch::Tensor k_constant = -scale * global.index({Slice(0, channels)}) / count;
    torch::Tensor dx = torch::addcmul(k_constant, centered, k_centered).addcmul_(dy, scale);
    return {dx,
            sum_dy_centered * invstd,
            sum_dy,
            torch::Tensor(),
            torch::Tensor(),
            torch::Tensor(),
            torch::Tensor(),
            torch::Tensor()};
  }
};

}  // namespace

torch::Tensor normalize_batch(nn::BatchNorm1d& bn, const torch::Tensor& x, const BatchSum* sum) {
  if (sum == nullptr || !*sum || !bn->is_training()) return bn->forward(x);
  const auto& o = bn->options;
  torch::Tensor y = GlobalBatchNorm::apply(x, bn->weight, bn->bias, sum, o.eps(), bn->running_mean, bn->running_var,
                                           o.momentum().value_or(0.1));
  {
    torch::NoGradGuard no_grad;
    bn->num_batches_tracked.add_(1);
  }
  return y;
}

namespace {

// Batch norm over every leading dimension (batch and points): statistics per channel, the last dimension.
torch::Tensor per_point(nn::BatchNorm1d& bn, const torch::Tensor& x, const BatchSum* sum) {
  const auto sizes = x.sizes().vec();
  return normalize_batch(bn, x.reshape({-1, sizes.back()}), sum).reshape(sizes);
}

}  // namespace

PassNoise PassNoise::draw(int64_t rows, const NetworkConfig& config, double dropout, torch::Device device) {
  PassNoise noise;
  noise.eps = torch::randn({rows, config.latent}, torch::kFloat32);
  if (dropout > 0)
    noise.dropout_scale =
        torch::bernoulli(torch::full({rows, config.pointnet_hidden}, 1.0 - dropout, torch::kFloat32)) / (1.0 - dropout);
  noise.eps = noise.eps.to(device);
  if (noise.dropout_scale.defined()) noise.dropout_scale = noise.dropout_scale.to(device);
  return noise;
}

PassNoise PassNoise::rows(int64_t begin, int64_t end) const {
  PassNoise part;
  part.eps = eps.index({Slice(begin, end)});
  if (dropout_scale.defined()) part.dropout_scale = dropout_scale.index({Slice(begin, end)});
  return part;
}

PointNetImpl::PointNetImpl(const NetworkConfig& c, double dropout, std::shared_ptr<BatchSum> sum)
    : sum_(std::move(sum)) {
  int input = 2;
  for (std::size_t i = 0; i < c.pointnet_widths.size(); ++i) {
    const int width = c.pointnet_widths[i];
    conv_.push_back(register_module("conv" + std::to_string(i), nn::Linear(input, width)));
    bn_.push_back(register_module("bn" + std::to_string(i), batch_norm(width, c)));
    input = width;
  }
  fc0_ = register_module("fc0", nn::Linear(input, c.pointnet_hidden));
  fc_bn0_ = register_module("fc_bn0", batch_norm(c.pointnet_hidden, c));
  dropout_ = register_module("dropout", nn::Dropout(dropout));
  fc1_ = register_module("fc1", nn::Linear(c.pointnet_hidden, c.features));
}

torch::Tensor PointNetImpl::pooled(const torch::Tensor& cloud) {
  torch::Tensor x = cloud;
  for (std::size_t i = 0; i < conv_.size(); ++i) x = torch::relu(per_point(bn_[i], conv_[i]->forward(x), sum_.get()));
  return std::get<0>(x.max(/*dim=*/-2));
}

torch::Tensor PointNetImpl::forward(const torch::Tensor& cloud, const torch::Tensor& dropout_scale) {
  const torch::Tensor h = torch::relu(normalize_batch(fc_bn0_, fc0_->forward(pooled(cloud)), sum_.get()));
  return fc1_->forward(dropout_scale.defined() && is_training() ? h * dropout_scale : dropout_->forward(h));
}

MlpTrunk::MlpTrunk(nn::Module& owner, int input, const NetworkConfig& c, std::shared_ptr<BatchSum> sum)
    : sum_(std::move(sum)) {
  for (int i = 0; i < c.layers; ++i) {
    fc_.push_back(owner.register_module("fc" + std::to_string(i), nn::Linear(input, c.hidden)));
    bn_.push_back(owner.register_module("bn" + std::to_string(i), batch_norm(c.hidden, c)));
    input = c.hidden;
  }
}

torch::Tensor MlpTrunk::forward(torch::Tensor x) {
  for (std::size_t i = 0; i < fc_.size(); ++i) x = torch::relu(normalize_batch(bn_[i], fc_[i]->forward(x), sum_.get()));
  return x;
}

EncoderImpl::EncoderImpl(const NetworkConfig& c, std::shared_ptr<BatchSum> sum)
    : trunk_(*this, c.observation + c.features + 2 * c.coefficients, c, std::move(sum)) {
  mean_ = register_module("mean", nn::Linear(c.hidden, c.latent));
  std_ = register_module("std", nn::Linear(c.hidden, c.latent));
}

Posterior EncoderImpl::forward(const torch::Tensor& observation, const torch::Tensor& features,
                               const torch::Tensor& xi) {
  const torch::Tensor x = trunk_.forward(torch::cat({observation, features, xi}, 1));
  return {mean_->forward(x), torch::nn::functional::softplus(std_->forward(x)) + 1e-4};
}

DecoderImpl::DecoderImpl(const NetworkConfig& c, std::shared_ptr<BatchSum> sum)
    : trunk_(*this, c.latent + c.observation + c.features, c, std::move(sum)) {
  out_ = register_module("out", nn::Linear(c.hidden, c.outputs));
  // Start near the output offsets (the training set's means): a small last layer.
  torch::NoGradGuard no_grad;
  out_->weight.mul_(0.1);
  out_->bias.zero_();
}

torch::Tensor DecoderImpl::forward(const torch::Tensor& z, const torch::Tensor& observation,
                                   const torch::Tensor& features) {
  return out_->forward(trunk_.forward(torch::cat({z, observation, features}, 1)));
}

CvaeImpl::CvaeImpl(const NetworkConfig& config, double dropout)
    : config_(config), batch_sum_(std::make_shared<BatchSum>()) {
  std::string error;
  if (!config.validate(&error)) throw std::invalid_argument("network: " + error);
  if (!(dropout >= 0 && dropout < 1))
    throw std::invalid_argument("network: dropout (" + std::to_string(dropout) + ") must be in [0, 1)");
  norm = register_module("norm", Normalization(config));
  pointnet = register_module("pointnet", PointNet(config, dropout, batch_sum_));
  encoder = register_module("encoder", Encoder(config, batch_sum_));
  decoder = register_module("decoder", Decoder(config, batch_sum_));
}

void CvaeImpl::set_batch_sum(BatchSum sum) { *batch_sum_ = std::move(sum); }

torch::Tensor CvaeImpl::features(const torch::Tensor& cloud, const torch::Tensor& dropout_scale) {
  return pointnet->forward(norm->cloud->forward(cloud), dropout_scale);
}

Posterior CvaeImpl::encode(const torch::Tensor& observation, const torch::Tensor& features,
                           const torch::Tensor& expert_xi) {
  return encoder->forward(norm->observation->forward(observation), features, norm->xi->forward(expert_xi));
}

torch::Tensor CvaeImpl::decode(const torch::Tensor& z, const torch::Tensor& observation,
                               const torch::Tensor& features) {
  return norm->output->forward(decoder->forward(z, norm->observation->forward(observation), features));
}

namespace {

// Columns (first of each pair, second of each pair) as index tensors on `device`.
std::pair<torch::Tensor, torch::Tensor> pair_columns(const std::vector<std::pair<int, int>>& pairs, torch::Device device) {
  std::vector<int64_t> xs, ys;
  for (const auto& [x, y] : pairs) {
    xs.push_back(x);
    ys.push_back(y);
  }
  const auto options = torch::TensorOptions().dtype(torch::kInt64);
  return {torch::tensor(xs, options).to(device), torch::tensor(ys, options).to(device)};
}

// Each (x, y) column pair of t [B, D] turned by (c, s) [B, 1]: x' = c x - s y, y' = s x + c y. Out of place.
torch::Tensor turn_pairs(const torch::Tensor& t, const std::vector<std::pair<int, int>>& pairs, const torch::Tensor& c,
                         const torch::Tensor& s) {
  const auto [xs, ys] = pair_columns(pairs, t.device());
  const torch::Tensor x = t.index_select(1, xs), y = t.index_select(1, ys);
  return t.index_copy(1, xs, c * x - s * y).index_copy(1, ys, s * x + c * y);
}

std::vector<std::pair<int, int>> observation_pairs() {
  std::vector<std::pair<int, int>> pairs;
  for (const auto& pair : io::kObservationPairs) pairs.emplace_back(pair[0], pair[1]);
  return pairs;
}

std::vector<std::pair<int, int>> xi_pairs(int64_t n) {
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < n; ++i) pairs.emplace_back(i, static_cast<int>(n) + i);
  return pairs;
}

}  // namespace

FrameTurn::FrameTurn(const torch::Tensor& observation) {
  const torch::Tensor x = observation.index({Slice(), Slice(2, 3)}), y = observation.index({Slice(), Slice(3, 4)});
  const torch::Tensor r = torch::sqrt(x * x + y * y);
  const torch::Tensor on_robot = r <= 0;
  const torch::Tensor safe = torch::where(on_robot, torch::ones_like(r), r);
  cos = torch::where(on_robot, torch::ones_like(r), x / safe);
  sin = torch::where(on_robot, torch::zeros_like(r), y / safe);
}

torch::Tensor FrameTurn::observation_in(const torch::Tensor& observation) const {
  return turn_pairs(observation, observation_pairs(), cos, -sin);
}

torch::Tensor FrameTurn::cloud_in(const torch::Tensor& cloud) const {
  const torch::Tensor x = cloud.select(2, 0), y = cloud.select(2, 1);  // [B, C]
  return torch::stack({cos * x + sin * y, -sin * x + cos * y}, 2);
}

torch::Tensor FrameTurn::xi_in(const torch::Tensor& xi) const { return turn_pairs(xi, xi_pairs(xi.size(1) / 2), cos, -sin); }

torch::Tensor FrameTurn::outputs_out(const torch::Tensor& outputs, const NetworkConfig& config) const {
  return turn_pairs(outputs, io::OutputLayout(config).turning_pairs(), cos, sin);
}

CvaeForward CvaeImpl::forward(const torch::Tensor& observation, const torch::Tensor& cloud,
                              const torch::Tensor& expert_xi, const PassNoise* noise) {
  const torch::Tensor dropout_scale = noise ? noise->dropout_scale : torch::Tensor();
  auto eps = [&](const torch::Tensor& like) { return noise ? noise->eps : torch::randn_like(like); };
  if (!config_.target_frame) {
    const torch::Tensor f = features(cloud, dropout_scale);
    Posterior q = encode(observation, f, expert_xi);
    const torch::Tensor z = q.mean + q.sigma * eps(q.sigma);
    return {decode(z, observation, f), std::move(q)};
  }
  const FrameTurn turn(observation);
  const torch::Tensor o = turn.observation_in(observation);
  const torch::Tensor f = features(turn.cloud_in(cloud), dropout_scale);
  Posterior q = encode(o, f, turn.xi_in(expert_xi));
  const torch::Tensor z = q.mean + q.sigma * eps(q.sigma);
  return {turn.outputs_out(decode(z, o, f), config_), std::move(q)};
}

torch::Tensor CvaeImpl::sample(const torch::Tensor& z, const torch::Tensor& observation, const torch::Tensor& cloud) {
  if (!config_.target_frame) return decode(z, observation, features(cloud));
  const FrameTurn turn(observation);
  const torch::Tensor o = turn.observation_in(observation);
  return turn.outputs_out(decode(z, o, features(turn.cloud_in(cloud))), config_);
}

std::vector<std::pair<std::string, torch::Tensor>> named_model_tensors(CvaeImpl& model) {
  std::vector<std::pair<std::string, torch::Tensor>> out;
  for (const auto& p : model.named_parameters(/*recurse=*/true)) out.emplace_back(p.key(), p.value());
  for (const auto& b : model.named_buffers(/*recurse=*/true)) {
    const std::string& name = b.key();
    const std::string suffix = "num_batches_tracked";
    if (name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) continue;
    out.emplace_back(name, b.value());
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------

DecodedOutputs split_outputs(const torch::Tensor& y, const NetworkConfig& c) {
  const io::OutputLayout l(c);
  if (y.dim() != 2 || y.size(1) != l.size)
    throw std::invalid_argument("decoder outputs must be [B, " + std::to_string(l.size) + "]");
  auto cols = [&](int begin, int end) { return y.index({Slice(), Slice(begin, end)}); };
  return {cols(l.terminal, l.terminal + 4),      cols(l.via, l.via + 4),
          cols(l.lambda0, l.distance_min),       cols(l.distance_min, l.distance_max),
          cols(l.distance_max, l.xi_bar),        cols(l.xi_bar, l.size)};
}

DecodedOutputs post_process(const DecodedOutputs& d, double speed_max, double band_min) {
  DecodedOutputs out = d;
  out.terminal = torch::cat({d.terminal.index({Slice(), Slice(0, 2)}),
                             d.terminal.index({Slice(), Slice(2, 4)}).clamp(-speed_max, speed_max)},
                            1);
  out.distance_min = d.distance_min.clamp_min(band_min);
  return out;
}

TrajectoryBasis::TrajectoryBasis(const projection::Settings& s, torch::Dtype dtype, torch::Device device) {
  const core::BernsteinBasis b = core::bernstein_basis(s.degree, s.steps, s.horizon);
  auto to_tensor = [&](const Eigen::MatrixXd& m) {
    torch::Tensor t = torch::empty({m.rows(), m.cols()}, torch::kFloat64);
    auto a = t.accessor<double, 2>();
    for (Eigen::Index i = 0; i < m.rows(); ++i)
      for (Eigen::Index j = 0; j < m.cols(); ++j) a[i][j] = m(i, j);
    return t.to(device, dtype);
  };
  P = to_tensor(b.P);
  Pd = to_tensor(b.Pd);
}

torch::Tensor TrajectoryBasis::positions(const torch::Tensor& xi) const {
  const int64_t n = P.size(1);
  const torch::Tensor pt = P.t();
  return torch::cat({torch::matmul(xi.index({Slice(), Slice(0, n)}), pt),
                     torch::matmul(xi.index({Slice(), Slice(n, 2 * n)}), pt)},
                    1);
}

ProjectionInputs policy_outputs(const torch::Tensor& outputs, const torch::Tensor& observation,
                                const torch::Tensor& obstacles, const PolicySettings& settings,
                                const TrajectoryBasis& basis, const NetworkConfig& config) {
  const DecodedOutputs d =
      post_process(split_outputs(outputs, config), settings.projection.speed_max, settings.band.min);
  ProjectionInputs in;
  in.robot_velocity = observation.index({Slice(), Slice(0, 2)});
  in.target = observation.index({Slice(), Slice(2, 6)});
  in.obstacles = obstacles;
  in.via_points = d.via_points;
  in.lambda0 = d.lambda0;
  in.xi_bar = d.xi_bar;
  if (settings.variant != io::Variant::fixed_q) {
    in.terminal = d.terminal;
    in.distance_min = d.distance_min;
    in.distance_max = d.distance_max;
    return in;
  }
  // Nominal q, as planners::detail::Context::fill_row: the terminal state of xi_bar, its speed capped.
  const int64_t n = config.coefficients, m = config.steps;
  const torch::Tensor cx = d.xi_bar.index({Slice(), Slice(0, n)}), cy = d.xi_bar.index({Slice(), Slice(n, 2 * n)});
  const torch::Tensor p_end = basis.P[m - 1], pd_end = basis.Pd[m - 1];
  const torch::Tensor position = torch::stack({torch::mv(cx, p_end), torch::mv(cy, p_end)}, 1);
  torch::Tensor velocity = torch::stack({torch::mv(cx, pd_end), torch::mv(cy, pd_end)}, 1);
  const torch::Tensor speed = velocity.norm(2, /*dim=*/{1}, /*keepdim=*/true);
  const double speed_max = settings.projection.speed_max;
  velocity = torch::where(speed > speed_max, velocity * (speed_max / speed.clamp_min(1e-12)), velocity);
  in.terminal = torch::cat({position, velocity}, 1);
  const auto batch = outputs.size(0);
  in.distance_min = torch::full({batch, m}, settings.band.min, outputs.options());
  in.distance_max = torch::full({batch, m}, settings.band.max, outputs.options());
  return in;
}

}  // namespace occtrack::learning
