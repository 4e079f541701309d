// A model file with random weights (docs/learning.md's tensors and metadata), for tests and benchmarks that
// need a model before a trained one exists.
#include <algorithm>
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

  io::ModelFile m;
  m.source = "random model";
  m.variant = io::parse_variant(variant);
  m.network = network;
  m.projection = projection;
  m.band = core::TrackingBand{};
  m.metadata["training"] = nlohmann::json{{"random", true}, {"seed", seed}}.dump();
  m.metadata["created_by"] = "occtrack policy::random_model";

  const int O = network.observation, n = network.coefficients, m_steps = network.steps;
  const core::TrackingBand& band = *m.band;
  // Fixed normalisation: observation std 3 m for the target position, cloud std 3 m, xi standard.
  std::vector<float> observation_std(O, 1.0f);
  for (int i = 2; i < std::min(O, 4); ++i) observation_std[i] = 3.0f;
  // Outputs around a straight path to (3, 0): terminal, via points on it, distance bounds at the band.
  const OutputLayout y(network);
  const double reach = 3.0;
  std::vector<float> offset(y.size, 0.0f), scale(y.size, 0.1f);
  offset[y.terminal] = static_cast<float>(reach);
  scale[y.terminal] = scale[y.terminal + 1] = 1.0f;
  scale[y.terminal + 2] = scale[y.terminal + 3] = 0.3f;
  const double s1 = double(projection.via_step_1) / (m_steps - 1), s2 = double(projection.via_step_2) / (m_steps - 1);
  offset[y.via] = static_cast<float>(reach * s1);
  offset[y.via + 2] = static_cast<float>(reach * s2);
  for (int i = 0; i < 4; ++i) scale[y.via + i] = 0.5f;
  for (int k = 0; k < m_steps; ++k) {
    offset[y.distance_min + k] = static_cast<float>(band.min);
    offset[y.distance_max + k] = static_cast<float>(band.max);
  }
  for (int i = 0; i < n; ++i) {
    offset[y.xi_bar + i] = static_cast<float>(reach * i / (n - 1));  // Bernstein coefficients of a line
    scale[y.xi_bar + i] = scale[y.xi_bar + n + i] = 0.5f;
  }

  std::mt19937_64 rng(seed);
  auto uniform = [&](std::int64_t count, double lo, double hi) {
    std::uniform_real_distribution<double> u(lo, hi);
    std::vector<float> v(static_cast<std::size_t>(count));
    for (float& x : v) x = static_cast<float>(u(rng));
    return v;
  };
  io::TensorFile f;
  double layer_bound = 1.0;  // of the last weight, for its bias
  for (const io::TensorSpec& t : io::model_tensors(network)) {
    const std::int64_t count = t.shape[0] * (t.shape.size() > 1 ? t.shape[1] : 1);
    std::vector<float> values;
    switch (t.role) {
      case io::TensorRole::input_mean: values.assign(count, 0.0f); break;
      case io::TensorRole::input_std:
        values = t.name == "norm.observation.std" ? observation_std
                 : t.name == "norm.cloud.std"     ? std::vector<float>(count, 3.0f)
                                                  : std::vector<float>(count, 1.0f);
        break;
      case io::TensorRole::output_offset: values = offset; break;
      case io::TensorRole::output_scale: values = scale; break;
      // torch's default initialisation of nn.Linear: U(-1/sqrt(in), 1/sqrt(in)) for weight and bias.
      case io::TensorRole::weight:
        layer_bound = 1.0 / std::sqrt(static_cast<double>(t.shape[1]));
        values = uniform(count, -layer_bound, layer_bound);
        break;
      case io::TensorRole::bias: values = uniform(count, -layer_bound, layer_bound); break;
      // Batch-norm statistics near the identity, but not equal to it, so that folding is exercised.
      case io::TensorRole::norm_weight: values = uniform(count, 0.8, 1.2); break;
      case io::TensorRole::norm_bias: values = uniform(count, -0.1, 0.1); break;
      case io::TensorRole::norm_mean: values = uniform(count, -0.1, 0.1); break;
      case io::TensorRole::norm_variance: values = uniform(count, 0.5, 1.5); break;
    }
    f.put(t.name, t.shape, values);
  }
  m.tensors = std::move(f.tensors);
  return io::to_tensor_file(m);
}

}  // namespace occtrack::policy
