// A model file with random weights (docs/learning.md's tensors and metadata), for tests and benchmarks that
// need a model before a trained one exists.
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>

#include "occtrack/policy/model.hpp"

namespace occtrack::policy {

io::TensorFile random_model(const NetworkConfig& network, const projection::Settings& projection, std::string variant,
                            std::uint64_t seed) {
  std::string error;
  if (!network.validate(&error)) throw std::invalid_argument("random_model: network: " + error);
  if (!projection.validate(&error)) throw std::invalid_argument("random_model: projection: " + error);
  if (network.coefficients != projection.coefficients() || network.steps != projection.steps)
    throw std::invalid_argument("random_model: network coefficients and steps must match the projection's");

  std::mt19937_64 rng(seed);
  auto uniform = [&](std::int64_t count, double lo, double hi) {
    std::uniform_real_distribution<double> u(lo, hi);
    std::vector<float> v(static_cast<std::size_t>(count));
    for (float& x : v) x = static_cast<float>(u(rng));
    return v;
  };
  io::TensorFile f;
  f.source = "random model";
  // torch's default initialisation of nn.Linear: U(-1/sqrt(in), 1/sqrt(in)) for weight and bias.
  auto linear = [&](const std::string& name, std::int64_t out, std::int64_t in) {
    const double k = 1.0 / std::sqrt(static_cast<double>(in));
    f.put(name + ".weight", {out, in}, uniform(out * in, -k, k));
    f.put(name + ".bias", {out}, uniform(out, -k, k));
  };
  // Batch-norm statistics near the identity, but not equal to it, so that folding is exercised.
  auto batch_norm = [&](const std::string& name, std::int64_t width) {
    f.put(name + ".weight", {width}, uniform(width, 0.8, 1.2));
    f.put(name + ".bias", {width}, uniform(width, -0.1, 0.1));
    f.put(name + ".running_mean", {width}, uniform(width, -0.1, 0.1));
    f.put(name + ".running_var", {width}, uniform(width, 0.5, 1.5));
  };

  const int O = network.observation, F = network.features, H = network.hidden, Z = network.latent;
  const int n = network.coefficients, n2 = 2 * n, m = network.steps;
  const core::TrackingBand band;

  f.put("norm.observation.mean", {O}, std::vector<float>(O, 0.0f));
  std::vector<float> observation_std(O, 1.0f);
  for (int i = 2; i < std::min(O, 4); ++i) observation_std[i] = 3.0f;  // target position, metres
  f.put("norm.observation.std", {O}, observation_std);
  f.put("norm.cloud.mean", {2}, std::vector<float>{0.0f, 0.0f});
  f.put("norm.cloud.std", {2}, std::vector<float>{3.0f, 3.0f});
  f.put("norm.xi.mean", {n2}, std::vector<float>(n2, 0.0f));
  f.put("norm.xi.std", {n2}, std::vector<float>(n2, 1.0f));

  // Outputs around a straight path to (3, 0): terminal, via points on it, distance bounds at the band.
  const OutputLayout y(network);
  const double reach = 3.0;
  std::vector<float> offset(y.size, 0.0f), scale(y.size, 0.1f);
  offset[y.terminal] = static_cast<float>(reach);
  scale[y.terminal] = scale[y.terminal + 1] = 1.0f;
  scale[y.terminal + 2] = scale[y.terminal + 3] = 0.3f;
  const double s1 = double(projection.via_step_1) / (m - 1), s2 = double(projection.via_step_2) / (m - 1);
  offset[y.via] = static_cast<float>(reach * s1);
  offset[y.via + 2] = static_cast<float>(reach * s2);
  for (int i = 0; i < 4; ++i) scale[y.via + i] = 0.5f;
  for (int k = 0; k < m; ++k) {
    offset[y.distance_min + k] = static_cast<float>(band.min);
    offset[y.distance_max + k] = static_cast<float>(band.max);
  }
  for (int i = 0; i < n; ++i) {
    offset[y.xi_bar + i] = static_cast<float>(reach * i / (n - 1));  // Bernstein coefficients of a line
    scale[y.xi_bar + i] = scale[y.xi_bar + n + i] = 0.5f;
  }
  f.put("norm.output.offset", {y.size}, offset);
  f.put("norm.output.scale", {y.size}, scale);

  std::int64_t in = 2;
  for (std::size_t i = 0; i < network.pointnet_widths.size(); ++i) {
    const std::int64_t out = network.pointnet_widths[i];
    linear("pointnet.conv" + std::to_string(i), out, in);
    batch_norm("pointnet.bn" + std::to_string(i), out);
    in = out;
  }
  linear("pointnet.fc0", network.pointnet_hidden, in);
  batch_norm("pointnet.fc_bn0", network.pointnet_hidden);
  linear("pointnet.fc1", F, network.pointnet_hidden);
  for (int i = 0; i < network.layers; ++i) {
    linear("encoder.fc" + std::to_string(i), H, i == 0 ? O + F + n2 : H);
    batch_norm("encoder.bn" + std::to_string(i), H);
  }
  linear("encoder.mean", Z, H);
  linear("encoder.std", Z, H);
  for (int i = 0; i < network.layers; ++i) {
    linear("decoder.fc" + std::to_string(i), H, i == 0 ? Z + O + F : H);
    batch_norm("decoder.bn" + std::to_string(i), H);
  }
  linear("decoder.out", y.size, H);

  f.metadata["format"] = kModelFormat;
  f.metadata["variant"] = std::move(variant);
  f.metadata["network"] = network.to_json();
  f.metadata["projection"] = projection_json(projection);
  f.metadata["band"] = band_json(band);
  f.metadata["training"] = nlohmann::json{{"random", true}, {"seed", seed}}.dump();
  f.metadata["created_by"] = "occtrack policy::random_model";
  return f;
}

}  // namespace occtrack::policy
