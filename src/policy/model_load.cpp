// Loading a checked model file and folding it for inference (docs/learning.md, "Networks, in eval mode"):
// every batch norm (running statistics) into the layer before it, the input normalisation into the first layer
// of each network, and the output scale and offset into the decoder's last layer. Folding is in double; the
// folded layers are stored in float.
#include <Eigen/Core>
#include <sstream>
#include <stdexcept>

#include "model_impl.hpp"

namespace occtrack::policy {

namespace {

using detail::Linear;
using Dense = detail::Dense;
using MatrixRd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

[[noreturn]] void fail(const std::string& source, const std::string& what) { throw io::InputError(source + ": " + what); }

template <typename T>
std::string number_text(T value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// The tensors of a checked file (shapes, finiteness and signs are io::validate_model_file's), as Eigen. A
// size that is not the table's (a ModelFile changed after its check) is refused rather than read past.
class TensorReader {
 public:
  explicit TensorReader(const io::ModelFile& file) : file_(file) {}

  std::vector<double> values(const std::string& name, Eigen::Index size) const {
    std::vector<double> v = file_.values(name);
    if (static_cast<Eigen::Index>(v.size()) != size)
      throw std::invalid_argument(file_.source + ": tensor '" + name + "' holds " + std::to_string(v.size()) +
                                  " values, the network needs " + std::to_string(size) +
                                  " (io::validate_model_file checks a file before it is folded)");
    return v;
  }

  Eigen::VectorXd vector(const std::string& name, Eigen::Index size) const {
    const std::vector<double> v = values(name, size);
    return Eigen::Map<const Eigen::VectorXd>(v.data(), size);
  }

  Linear linear(const std::string& prefix, Eigen::Index out, Eigen::Index in) const {
    const std::vector<double> w = values(prefix + ".weight", out * in);
    Linear l;
    l.weight = Eigen::Map<const MatrixRd>(w.data(), out, in);
    l.bias = vector(prefix + ".bias", out);
    return l;
  }

  // Eval-mode batch norm after `layer`: (y - mean) / sqrt(var + eps) * gamma + beta, folded into the layer.
  void fold_batch_norm(Linear& layer, const std::string& prefix, double eps) const {
    const Eigen::Index width = layer.weight.rows();
    const Eigen::VectorXd gamma = vector(prefix + ".weight", width);
    const Eigen::VectorXd beta = vector(prefix + ".bias", width);
    const Eigen::VectorXd mean = vector(prefix + ".running_mean", width);
    const Eigen::VectorXd var = vector(prefix + ".running_var", width);
    const Eigen::VectorXd scale = gamma.array() / (var.array() + eps).sqrt();
    layer.weight = scale.asDiagonal() * layer.weight;
    layer.bias = (scale.array() * (layer.bias - mean).array() + beta.array()).matrix();
  }

 private:
  const io::ModelFile& file_;
};

// Inputs x_n = (x - mean) / std in columns [first, first + mean.size()) of a layer: folded into W and b.
void fold_input_normalisation(Linear& layer, Eigen::Index first, const Eigen::VectorXd& mean, const Eigen::VectorXd& std) {
  auto block = layer.weight.middleCols(first, mean.size());
  block = block * std.cwiseInverse().asDiagonal();
  layer.bias -= block * mean;
}

}  // namespace

void Model::Impl::fold(const io::ModelFile& file) {
  source = file.source;
  variant = file.variant;
  network = file.network;
  layout = OutputLayout(network);
  projection = file.projection;
  has_rho = file.projection_has_rho;
  band = file.band;
  metadata = file.metadata;

  // Tensors, in the order of docs/learning.md, folded as they are read.
  const TensorReader t(file);
  const NetworkConfig& c = network;
  const double eps = c.batch_norm_eps;
  const int n2 = 2 * c.coefficients;
  const Eigen::VectorXd observation_mean = t.vector("norm.observation.mean", c.observation);
  const Eigen::VectorXd observation_std = t.vector("norm.observation.std", c.observation);
  const Eigen::VectorXd cloud_mean = t.vector("norm.cloud.mean", 2);
  const Eigen::VectorXd cloud_std = t.vector("norm.cloud.std", 2);
  const Eigen::VectorXd xi_mean = t.vector("norm.xi.mean", n2);
  const Eigen::VectorXd xi_std = t.vector("norm.xi.std", n2);
  const Eigen::VectorXd output_offset = t.vector("norm.output.offset", c.outputs);
  const Eigen::VectorXd output_scale = t.vector("norm.output.scale", c.outputs);

  pointnet.clear();
  int in = 2;
  for (std::size_t i = 0; i < c.pointnet_widths.size(); ++i) {
    const int out = c.pointnet_widths[i];
    Linear l = t.linear("pointnet.conv" + std::to_string(i), out, in);
    t.fold_batch_norm(l, "pointnet.bn" + std::to_string(i), eps);
    if (i == 0) fold_input_normalisation(l, 0, cloud_mean, cloud_std);
    pointnet.emplace_back(l);
    in = out;
  }
  {
    Linear fc0 = t.linear("pointnet.fc0", c.pointnet_hidden, in);
    t.fold_batch_norm(fc0, "pointnet.fc_bn0", eps);
    pointnet_fc0 = Dense(fc0);
    pointnet_fc1 = Dense(t.linear("pointnet.fc1", c.features, c.pointnet_hidden));
  }

  // Encoder: input [obs_n, features, xi_n].
  encoder.clear();
  for (int i = 0; i < c.layers; ++i) {
    Linear l = t.linear("encoder.fc" + std::to_string(i), c.hidden, i == 0 ? c.observation + c.features + n2 : c.hidden);
    t.fold_batch_norm(l, "encoder.bn" + std::to_string(i), eps);
    if (i == 0) {
      fold_input_normalisation(l, 0, observation_mean, observation_std);
      fold_input_normalisation(l, c.observation + c.features, xi_mean, xi_std);
    }
    encoder.emplace_back(l);
  }
  encoder_mean = Dense(t.linear("encoder.mean", c.latent, c.hidden));
  encoder_std = Dense(t.linear("encoder.std", c.latent, c.hidden));

  // Decoder: input [z, obs_n, features]; fc0 split by input so that the shared part is computed once a cycle.
  decoder_hidden.clear();
  for (int i = 0; i < c.layers; ++i) {
    Linear l = t.linear("decoder.fc" + std::to_string(i), c.hidden, i == 0 ? c.latent + c.observation + c.features : c.hidden);
    t.fold_batch_norm(l, "decoder.bn" + std::to_string(i), eps);
    if (i == 0) {
      fold_input_normalisation(l, c.latent, observation_mean, observation_std);
      decoder_latent = Dense(Linear{l.weight.leftCols(c.latent), l.bias});
      decoder_observation = l.weight.middleCols(c.latent, c.observation).cast<float>();
      decoder_features = l.weight.rightCols(c.features).cast<float>();
      decoder_bias = l.bias.cast<float>();
    } else {
      decoder_hidden.emplace_back(l);
    }
  }
  {
    Linear out = t.linear("decoder.out", c.outputs, c.hidden);
    out.weight = output_scale.asDiagonal() * out.weight;
    out.bias = (output_scale.array() * out.bias.array() + output_offset.array()).matrix();
    decoder_out = Dense(out);
  }
}

Model Model::load(const std::string& path) { return Model(io::read_model_file(path)); }

Model::Model(const io::ModelFile& file) : impl_(std::make_unique<Impl>()) {
  impl_->fold(file);
  impl_->reserve(30, impl_->network.cloud_points);
}

Model::Model(const io::TensorFile& file) : Model(io::validate_model_file(file)) {}

Model::~Model() = default;
Model::Model(Model&&) noexcept = default;
Model& Model::operator=(Model&&) noexcept = default;

const std::string& Model::source() const { return impl_->source; }
Variant Model::variant() const { return impl_->variant; }
const NetworkConfig& Model::network() const { return impl_->network; }
const OutputLayout& Model::layout() const { return impl_->layout; }
const projection::Settings& Model::projection() const { return impl_->projection; }
const std::optional<core::TrackingBand>& Model::band() const { return impl_->band; }
const std::map<std::string, std::string>& Model::metadata() const { return impl_->metadata; }

void Model::check_projection(const projection::Settings& s) const {
  const projection::Settings& m = impl_->projection;
  auto differ = [&](const std::string& field, const auto& model_value, const auto& planner_value) {
    if (model_value == planner_value) return;
    fail(impl_->source, field + " is " + number_text(model_value) + " in the model, the planner uses " +
                            number_text(planner_value));
  };
  differ("projection.degree", m.degree, s.degree);
  differ("projection.steps", m.steps, s.steps);
  differ("projection.horizon", m.horizon, s.horizon);
  differ("projection.via_steps[0]", m.via_step_1, s.via_step_1);
  differ("projection.via_steps[1]", m.via_step_2, s.via_step_2);
  differ("projection.obstacle_radius", m.obstacle_radius, s.obstacle_radius);
  differ("projection.speed_min", m.speed_min, s.speed_min);
  differ("projection.speed_max", m.speed_max, s.speed_max);
  differ("projection.accel_max", m.accel_max, s.accel_max);
  differ("network.nearest_points", m.obstacles, s.obstacles);
  if (impl_->has_rho) {
    differ("projection.rho.obstacle", m.rho.obstacle, s.rho.obstacle);
    differ("projection.rho.velocity", m.rho.velocity, s.rho.velocity);
    differ("projection.rho.acceleration", m.rho.acceleration, s.rho.acceleration);
    differ("projection.rho.tracking", m.rho.tracking, s.rho.tracking);
    differ("projection.rho.projection", m.rho.projection, s.rho.projection);
  }
}

void Model::require_variant(Variant expected, const std::string& planner) const {
  if (impl_->variant == expected) return;
  fail(impl_->source, std::string("variant is '") + to_string(impl_->variant) + "' but planner " + planner + " needs '" +
                          to_string(expected) + "'");
}

}  // namespace occtrack::policy
