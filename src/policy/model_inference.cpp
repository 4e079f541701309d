// Inference of the folded networks (docs/learning.md, "Networks, in eval mode"): float32 matrix products on
// the whole cloud and the whole batch, in the workspaces reserved beforehand.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "model_impl.hpp"

namespace occtrack::policy {

namespace {

using Dense = detail::Dense;

float softplus(float x) { return x > 20.0f ? x : std::log1p(std::exp(x)); }  // torch's threshold 20

int widest_layer(const NetworkConfig& network) {
  int w = std::max(network.hidden, network.pointnet_hidden);
  for (int x : network.pointnet_widths) w = std::max(w, x);
  return w;
}

}  // namespace

void Model::Impl::reserve(int batch, int points) {
  max_batch = std::max({1, max_batch, batch});
  max_points = std::max({1, max_points, points});
  cloud_t.resize(2 * max_points);
  const Eigen::Index columns = std::max(max_batch, max_points);
  ping.resize(widest_layer(network) * columns);
  pong.resize(widest_layer(network) * columns);
  pooled.resize(network.pointnet_widths.back());
  pointnet_hidden.resize(network.pointnet_hidden);
  decoder_context.resize(network.hidden);
}

void Model::reserve(int max_batch, int max_points) { impl_->reserve(max_batch, max_points); }

void Model::features(const Eigen::Ref<const Cloud>& cloud, Eigen::Ref<Eigen::VectorXf> out) {
  Impl& s = *impl_;
  const Eigen::Index C = cloud.rows();
  if (C < 1) throw std::invalid_argument("policy::Model::features: the cloud has no point");
  if (out.size() != s.network.features)
    throw std::invalid_argument("policy::Model::features: out has size " + std::to_string(out.size()) +
                                ", expected " + std::to_string(s.network.features));
  if (C > s.max_points) s.reserve(s.max_batch, static_cast<int>(C));

  Eigen::Map<Eigen::MatrixXf> input(s.cloud_t.data(), 2, C);
  input = cloud.transpose();
  // Per-point layers on the whole cloud: x_{l+1} = relu(W_l x_l + b_l), one product per layer.
  const float* x = input.data();
  Eigen::Index width = 2;
  const std::size_t L = s.pointnet.size();
  for (std::size_t l = 0; l < L; ++l) {
    Dense& layer = s.pointnet[l];
    float* y = (l % 2 == 0 ? s.ping : s.pong).data();
    Eigen::Map<Eigen::MatrixXf> Y(y, layer.rows(), C);
    Y.colwise() = layer.bias;
    layer.gemm.accumulate(layer.weight, x, width, C, y, layer.rows());
    if (l + 1 < L) Y = Y.cwiseMax(0.0f);
    x = y;
    width = layer.rows();
  }
  // Max pool over points; relu commutes with max, so it is applied once after pooling.
  Eigen::Map<const Eigen::MatrixXf> last(x, width, C);
  s.pooled = last.rowwise().maxCoeff().cwiseMax(0.0f);
  s.pointnet_hidden = s.pointnet_fc0.bias;
  s.pointnet_hidden.noalias() += s.pointnet_fc0.weight * s.pooled;
  s.pointnet_hidden = s.pointnet_hidden.cwiseMax(0.0f);
  out = s.pointnet_fc1.bias;
  out.noalias() += s.pointnet_fc1.weight * s.pointnet_hidden;
}

void Model::decode(const Eigen::Ref<const Rows>& z, const Eigen::Ref<const Eigen::VectorXf>& observation,
                   const Eigen::Ref<const Eigen::VectorXf>& features, Eigen::Ref<Rows> out) {
  Impl& s = *impl_;
  const NetworkConfig& c = s.network;
  const Eigen::Index B = z.rows();
  if (z.cols() != c.latent || observation.size() != c.observation || features.size() != c.features ||
      out.rows() != B || out.cols() != c.outputs)
    throw std::invalid_argument("policy::Model::decode: expected z B x " + std::to_string(c.latent) +
                                ", observation " + std::to_string(c.observation) + ", features " +
                                std::to_string(c.features) + ", out B x " + std::to_string(c.outputs) + "; got z " +
                                std::to_string(z.rows()) + " x " + std::to_string(z.cols()) + ", observation " +
                                std::to_string(observation.size()) + ", features " + std::to_string(features.size()) +
                                ", out " + std::to_string(out.rows()) + " x " + std::to_string(out.cols()));
  if (B == 0) return;
  if (B > s.max_batch) s.reserve(static_cast<int>(B), s.max_points);

  // The part of the first layer that all samples share: W_obs obs_n + W_features features + b.
  s.decoder_context = s.decoder_bias;
  s.decoder_context.noalias() += s.decoder_observation * observation;
  s.decoder_context.noalias() += s.decoder_features * features;
  // h_1 = relu(W_z z + context), samples as columns (z's rows, read in place).
  float* h = s.ping.data();
  Eigen::Map<Eigen::MatrixXf> H1(h, c.hidden, B);
  H1.colwise() = s.decoder_context;
  s.decoder_latent.gemm.accumulate(s.decoder_latent.weight, z.data(), z.outerStride(), B, h, c.hidden);
  H1 = H1.cwiseMax(0.0f);
  for (std::size_t l = 0; l < s.decoder_hidden.size(); ++l) {
    Dense& layer = s.decoder_hidden[l];
    float* next = (h == s.ping.data() ? s.pong : s.ping).data();
    Eigen::Map<Eigen::MatrixXf> Hn(next, c.hidden, B);
    Hn.colwise() = layer.bias;
    layer.gemm.accumulate(layer.weight, h, c.hidden, B, next, c.hidden);
    Hn = Hn.cwiseMax(0.0f);
    h = next;
  }
  // y = W_out h + b_out (scale and offset folded in), written straight into out: its B x Y rows are the
  // columns of a Y x B column-major matrix.
  using Stride = Eigen::OuterStride<>;
  Eigen::Map<Eigen::MatrixXf, 0, Stride> Yt(out.data(), c.outputs, B, Stride(out.outerStride()));
  Yt.colwise() = s.decoder_out.bias;
  s.decoder_out.gemm.accumulate(s.decoder_out.weight, h, c.hidden, B, out.data(), out.outerStride());
}

void Model::encode(const Eigen::Ref<const Eigen::VectorXf>& observation, const Eigen::Ref<const Eigen::VectorXf>& features,
                   const Eigen::Ref<const Rows>& expert_xi, Eigen::Ref<Rows> mu, Eigen::Ref<Rows> sigma) const {
  const Impl& s = *impl_;
  const NetworkConfig& c = s.network;
  const Eigen::Index B = expert_xi.rows(), n2 = 2 * c.coefficients;
  if (observation.size() != c.observation || features.size() != c.features || expert_xi.cols() != n2 ||
      mu.rows() != B || mu.cols() != c.latent || sigma.rows() != B || sigma.cols() != c.latent)
    throw std::invalid_argument("policy::Model::encode: expected observation " + std::to_string(c.observation) +
                                ", features " + std::to_string(c.features) + ", expert_xi B x " +
                                std::to_string(n2) + ", mu and sigma B x " + std::to_string(c.latent));
  Eigen::MatrixXf x(c.observation + c.features + n2, B);
  x.topRows(c.observation).colwise() = observation;
  x.middleRows(c.observation, c.features).colwise() = features;
  x.bottomRows(n2) = expert_xi.transpose();
  for (const Dense& layer : s.encoder) {
    Eigen::MatrixXf y = layer.weight * x;
    y.colwise() += layer.bias;
    x = y.cwiseMax(0.0f);
  }
  Eigen::MatrixXf m = s.encoder_mean.weight * x, d = s.encoder_std.weight * x;
  m.colwise() += s.encoder_mean.bias;
  d.colwise() += s.encoder_std.bias;
  mu = m.transpose();
  sigma = d.transpose().unaryExpr([](float v) { return softplus(v) + 1e-4f; });
}

void Model::postprocess(Eigen::Ref<Rows> outputs, double speed_max, double distance_floor) const {
  const OutputLayout& y = impl_->layout;
  const float v = static_cast<float>(speed_max), floor = static_cast<float>(distance_floor);
  for (Eigen::Index b = 0; b < outputs.rows(); ++b) {
    for (int i = 2; i < 4; ++i) outputs(b, y.terminal + i) = std::clamp(outputs(b, y.terminal + i), -v, v);
    auto d_min = outputs.row(b).segment(y.distance_min, impl_->network.steps);
    d_min = d_min.cwiseMax(floor);
  }
}

}  // namespace occtrack::policy
