#include "occtrack/policy/model.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "../io/json_util.hpp"
#include "gemm.hpp"
#include "occtrack/io/projection_case.hpp"

namespace occtrack::policy {

namespace {

using io::detail::json;
using io::detail::JsonReader;
using MatrixRd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

[[noreturn]] void fail(const std::string& source, const std::string& what) { throw io::InputError(source + ": " + what); }

std::string shape_string(const std::vector<std::int64_t>& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

template <typename T>
std::string number_text(T value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// One expected dimension of a tensor, and the metadata field it comes from (empty: none in particular).
struct Dim {
  std::int64_t size;
  std::string field;
};

// A linear layer y = W x + b in double while folding; W is [out, in] as in torch.
struct Linear {
  Eigen::MatrixXd weight;
  Eigen::VectorXd bias;
};

// Reads the tensors of docs/learning.md's table with their checks, naming the file and the tensor.
class TensorReader {
 public:
  TensorReader(const io::TensorFile& file, std::string source) : file_(file), source_(std::move(source)) {}

  std::vector<double> values(const std::string& name, const std::vector<Dim>& dims) const {
    if (!file_.has(name)) fail(source_, "tensor '" + name + "' is missing");
    const io::Tensor& t = file_.tensors.at(name);
    std::vector<std::int64_t> expected;
    for (const Dim& d : dims) expected.push_back(d.size);
    if (t.shape != expected) {
      const std::string detail = "tensor '" + name + "' has shape " + t.shape_text() + ", expected " +
                                 shape_string(expected);
      if (t.shape.size() == expected.size())
        for (std::size_t i = 0; i < dims.size(); ++i)
          if (t.shape[i] != expected[i] && !dims[i].field.empty())
            fail(source_, "metadata " + dims[i].field + " is " + std::to_string(expected[i]) + ", the tensors say " +
                              std::to_string(t.shape[i]) + " (" + detail + ")");
      fail(source_, detail);
    }
    if (t.dtype != io::DType::F32 && t.dtype != io::DType::F64)
      fail(source_, "tensor '" + name + "' has dtype " + io::dtype_name(t.dtype) + ", expected F32");
    std::vector<double> v = t.as_double();
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        fail(source_, "tensor '" + name + "' holds a non-finite value (" + number_text(v[i]) + ") at flat index " +
                          std::to_string(i));
    return v;
  }

  Eigen::VectorXd vector(const std::string& name, const Dim& dim) const {
    const std::vector<double> v = values(name, {dim});
    return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  }

  Eigen::VectorXd positive(const std::string& name, const Dim& dim) const {
    Eigen::VectorXd v = vector(name, dim);
    for (Eigen::Index i = 0; i < v.size(); ++i)
      if (!(v(i) > 0.0))
        fail(source_, "tensor '" + name + "' must be positive, holds " + number_text(v(i)) + " at index " +
                          std::to_string(i));
    return v;
  }

  Linear linear(const std::string& prefix, const Dim& out, const Dim& in) const {
    const std::vector<double> w = values(prefix + ".weight", {out, in});
    Linear l;
    l.weight = Eigen::Map<const MatrixRd>(w.data(), out.size, in.size);
    l.bias = vector(prefix + ".bias", out);
    return l;
  }

  // Eval-mode batch norm after `layer`: (y - mean) / sqrt(var + eps) * gamma + beta, folded into the layer.
  void fold_batch_norm(Linear& layer, const std::string& prefix, const Dim& width, double eps) const {
    const Eigen::VectorXd gamma = vector(prefix + ".weight", width);
    const Eigen::VectorXd beta = vector(prefix + ".bias", width);
    const Eigen::VectorXd mean = vector(prefix + ".running_mean", width);
    const Eigen::VectorXd var = vector(prefix + ".running_var", width);
    for (Eigen::Index i = 0; i < var.size(); ++i)
      if (var(i) < 0.0)
        fail(source_, "tensor '" + prefix + ".running_var' holds a negative variance (" + number_text(var(i)) +
                          ") at index " + std::to_string(i));
    const Eigen::VectorXd scale = gamma.array() / (var.array() + eps).sqrt();
    layer.weight = scale.asDiagonal() * layer.weight;
    layer.bias = (scale.array() * (layer.bias - mean).array() + beta.array()).matrix();
  }

 private:
  const io::TensorFile& file_;
  std::string source_;
};

// Inputs x_n = (x - mean) / std in columns [first, first + mean.size()) of a layer: folded into W and b.
void fold_input_normalisation(Linear& layer, Eigen::Index first, const Eigen::VectorXd& mean, const Eigen::VectorXd& std) {
  auto block = layer.weight.middleCols(first, mean.size());
  block = block * std.cwiseInverse().asDiagonal();
  layer.bias -= block * mean;
}

// A folded layer in float, ready for the products.
struct Dense {
  Eigen::MatrixXf weight;  // out x in, column-major (Eigen's blocked kernel packs it once per call)
  Eigen::VectorXf bias;
  detail::Gemm gemm;

  Dense() = default;
  explicit Dense(const Linear& l) : weight(l.weight.cast<float>()), bias(l.bias.cast<float>()), gemm(weight) {}
  Eigen::Index rows() const { return weight.rows(); }
};

float softplus(float x) { return x > 20.0f ? x : std::log1p(std::exp(x)); }  // torch's threshold 20

json parse_metadata_json(const std::string& text, const std::string& source, const std::string& key) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    fail(source, "metadata " + key + " is not valid JSON (" + e.what() + ")");
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------------
// Variant, sizes, metadata JSON.

const char* to_string(Variant variant) {
  switch (variant) {
    case Variant::cvae: return "cvae";
    case Variant::bc: return "bc";
    case Variant::fixed_q: return "fixed-q";
  }
  return "?";
}

Variant parse_variant(const std::string& text) {
  if (text == "cvae") return Variant::cvae;
  if (text == "bc") return Variant::bc;
  if (text == "fixed-q") return Variant::fixed_q;
  throw io::InputError("variant '" + text + "' is not one of cvae, bc, fixed-q");
}

NetworkConfig NetworkConfig::for_projection(const projection::Settings& settings) {
  NetworkConfig c;
  c.coefficients = settings.coefficients();
  c.steps = settings.steps;
  c.nearest_points = settings.obstacles;
  c.outputs = c.expected_outputs();
  return c;
}

bool NetworkConfig::validate(std::string* error) const {
  auto bad = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  const struct {
    const char* name;
    int value;
  } positive[] = {{"observation", observation}, {"cloud_points", cloud_points}, {"latent", latent},
                  {"pointnet_hidden", pointnet_hidden}, {"features", features}, {"hidden", hidden},
                  {"layers", layers}, {"outputs", outputs}, {"coefficients", coefficients}, {"steps", steps}};
  for (const auto& f : positive)
    if (f.value < 1) return bad(std::string(f.name) + " (" + std::to_string(f.value) + ") must be positive");
  if (nearest_points < 0) return bad("nearest_points (" + std::to_string(nearest_points) + ") must not be negative");
  if (observation != 6)
    return bad("observation (" + std::to_string(observation) +
               ") must be 6: robot vx, vy; target x, y; target vx, vy");
  if (pointnet_widths.empty()) return bad("pointnet_widths must hold at least one width");
  for (std::size_t i = 0; i < pointnet_widths.size(); ++i)
    if (pointnet_widths[i] < 1)
      return bad("pointnet_widths[" + std::to_string(i) + "] (" + std::to_string(pointnet_widths[i]) +
                 ") must be positive");
  if (outputs != expected_outputs())
    return bad("outputs (" + std::to_string(outputs) + ") must be 8 + 4n + 2m = " + std::to_string(expected_outputs()) +
               " (n = coefficients, m = steps)");
  if (!(batch_norm_eps > 0.0) || !std::isfinite(batch_norm_eps))
    return bad("batch_norm_eps (" + number_text(batch_norm_eps) + ") must be a positive number");
  return true;
}

std::string NetworkConfig::to_json() const {
  const json j = {{"observation", observation},     {"cloud_points", cloud_points},
                  {"nearest_points", nearest_points}, {"latent", latent},
                  {"pointnet_widths", pointnet_widths}, {"pointnet_hidden", pointnet_hidden},
                  {"features", features},           {"hidden", hidden},
                  {"layers", layers},               {"outputs", outputs},
                  {"coefficients", coefficients},   {"steps", steps},
                  {"batch_norm_eps", batch_norm_eps}};
  return j.dump();
}

NetworkConfig NetworkConfig::parse(const std::string& json_text, const std::string& source) {
  const JsonReader r(source);
  const json doc = parse_metadata_json(json_text, source, "network");
  const std::string p = "network";
  NetworkConfig c;
  c.observation = r.integer(r.member(doc, p, "observation"), p + ".observation");
  c.cloud_points = r.integer(r.member(doc, p, "cloud_points"), p + ".cloud_points");
  c.nearest_points = r.integer(r.member(doc, p, "nearest_points"), p + ".nearest_points");
  c.latent = r.integer(r.member(doc, p, "latent"), p + ".latent");
  const json& widths = r.member(doc, p, "pointnet_widths");
  if (!widths.is_array() || widths.empty()) r.fail(p + ".pointnet_widths", "must be a non-empty list of widths");
  c.pointnet_widths.clear();
  for (std::size_t i = 0; i < widths.size(); ++i)
    c.pointnet_widths.push_back(r.integer(widths[i], p + ".pointnet_widths[" + std::to_string(i) + "]"));
  c.pointnet_hidden = r.integer(r.member(doc, p, "pointnet_hidden"), p + ".pointnet_hidden");
  c.features = r.integer(r.member(doc, p, "features"), p + ".features");
  c.hidden = r.integer(r.member(doc, p, "hidden"), p + ".hidden");
  c.layers = r.integer(r.member(doc, p, "layers"), p + ".layers");
  c.outputs = r.integer(r.member(doc, p, "outputs"), p + ".outputs");
  c.coefficients = r.integer(r.member(doc, p, "coefficients"), p + ".coefficients");
  c.steps = r.integer(r.member(doc, p, "steps"), p + ".steps");
  c.batch_norm_eps = r.number(r.member(doc, p, "batch_norm_eps"), p + ".batch_norm_eps");
  std::string error;
  if (!c.validate(&error)) r.fail(p + "." + error.substr(0, error.find_first_of(" [")), error);
  return c;
}

OutputLayout::OutputLayout(const NetworkConfig& network) {
  const int n2 = 2 * network.coefficients, m = network.steps;
  terminal = 0;
  via = 4;
  lambda0 = 8;
  distance_min = lambda0 + n2;
  distance_max = distance_min + m;
  xi_bar = distance_max + m;
  size = xi_bar + n2;
}

std::string projection_json(const projection::Settings& s) { return io::projection_settings_json(s); }

projection::Settings parse_projection_json(const std::string& json_text, const std::string& source) {
  return io::parse_projection_settings(json_text, source, "projection", /*strict=*/false);
}

std::string band_json(const core::TrackingBand& band) {
  return json{{"min", band.min}, {"reference", band.reference}, {"max", band.max}}.dump();
}

// ---------------------------------------------------------------------------------------------------------------
// The model.

struct Model::Impl {
  std::string source;
  Variant variant = Variant::cvae;
  NetworkConfig network;
  OutputLayout layout{NetworkConfig{}};
  projection::Settings projection;
  bool has_rho = false;
  std::optional<core::TrackingBand> band;
  std::map<std::string, std::string> metadata;

  // Folded networks (float).
  std::vector<Dense> pointnet;  // 1x1 convolutions with batch norm; the first also normalises the cloud
  Dense pointnet_fc0, pointnet_fc1;
  Dense decoder_latent;                  // the latent columns of decoder.fc0 (with its batch norm)
  Eigen::MatrixXf decoder_observation;   // its observation columns (input normalisation folded in)
  Eigen::MatrixXf decoder_features;      // its feature columns
  Eigen::VectorXf decoder_bias;
  std::vector<Dense> decoder_hidden;     // decoder.fc1 .. fc{L-1}
  Dense decoder_out;                     // output scale and offset folded in
  std::vector<Dense> encoder;            // encoder.fc0 .. fc{L-1}; fc0 normalises observation and xi
  Dense encoder_mean, encoder_std;

  // Workspaces.
  int max_batch = 0, max_points = 0;
  Eigen::VectorXf cloud_t;       // 2 x C, column-major
  Eigen::VectorXf ping, pong;    // widest layer x max(points, batch)
  Eigen::VectorXf pooled, pointnet_hidden, decoder_context;

  int widest() const {
    int w = std::max(network.hidden, network.pointnet_hidden);
    for (int x : network.pointnet_widths) w = std::max(w, x);
    return w;
  }

  void reserve(int batch, int points) {
    max_batch = std::max({1, max_batch, batch});
    max_points = std::max({1, max_points, points});
    cloud_t.resize(2 * max_points);
    const Eigen::Index columns = std::max(max_batch, max_points);
    ping.resize(widest() * columns);
    pong.resize(widest() * columns);
    pooled.resize(network.pointnet_widths.back());
    pointnet_hidden.resize(network.pointnet_hidden);
    decoder_context.resize(network.hidden);
  }

  void load(const io::TensorFile& file);
};

void Model::Impl::load(const io::TensorFile& file) {
  source = file.source.empty() ? "model" : file.source;
  metadata = file.metadata;
  auto meta = [&](const std::string& key) -> const std::string& {
    const auto it = file.metadata.find(key);
    if (it == file.metadata.end()) fail(source, "metadata '" + key + "' is missing");
    return it->second;
  };

  // Metadata: format, variant, sizes, the optimizer trained through, the band.
  const std::string& format = meta("format");
  if (format != kModelFormat)
    fail(source, "metadata format is '" + format + "', expected '" + std::string(kModelFormat) + "'");
  const std::string& variant_text = meta("variant");
  if (variant_text != "cvae" && variant_text != "bc" && variant_text != "fixed-q")
    fail(source, "metadata variant is '" + variant_text + "', expected one of cvae, bc, fixed-q");
  variant = parse_variant(variant_text);
  network = NetworkConfig::parse(meta("network"), source);
  layout = OutputLayout(network);
  projection = parse_projection_json(meta("projection"), source);
  has_rho = json::parse(meta("projection")).contains("rho");
  projection.obstacles = network.nearest_points;
  {
    std::string error;
    if (!projection.validate(&error)) fail(source, "metadata projection: " + error);
  }
  if (network.coefficients != projection.coefficients())
    fail(source, "metadata network.coefficients is " + std::to_string(network.coefficients) +
                     ", projection.degree + 1 is " + std::to_string(projection.coefficients()));
  if (network.steps != projection.steps)
    fail(source, "metadata network.steps is " + std::to_string(network.steps) + ", projection.steps is " +
                     std::to_string(projection.steps));
  for (const char* key : {"band", "ranking"}) {
    const auto it = file.metadata.find(key);
    if (it == file.metadata.end() || band) continue;
    const json doc = parse_metadata_json(it->second, source, key);
    const json& b = doc.is_object() && doc.contains("band") ? doc["band"] : doc;
    if (!b.is_object() || !b.contains("min")) continue;
    const JsonReader r(source);
    const std::string p = std::string(key) + (&b == &doc ? "" : ".band");
    core::TrackingBand t;
    t.min = r.number(r.member(b, p, "min"), p + ".min");
    t.reference = r.number(r.member(b, p, "reference"), p + ".reference");
    t.max = r.number(r.member(b, p, "max"), p + ".max");
    band = t;
  }

  // Tensors, in the order of docs/learning.md, folded as they are read.
  const TensorReader t(file, source);
  const NetworkConfig& c = network;
  const double eps = c.batch_norm_eps;
  const int n2 = 2 * c.coefficients;
  const Dim O{c.observation, "network.observation"}, F{c.features, "network.features"},
      H{c.hidden, "network.hidden"}, Hp{c.pointnet_hidden, "network.pointnet_hidden"},
      Z{c.latent, "network.latent"}, Y{c.outputs, "network.outputs"}, N2{n2, "network.coefficients (2n)"},
      two{2, ""};
  const Eigen::VectorXd observation_mean = t.vector("norm.observation.mean", O);
  const Eigen::VectorXd observation_std = t.positive("norm.observation.std", O);
  const Eigen::VectorXd cloud_mean = t.vector("norm.cloud.mean", two);
  const Eigen::VectorXd cloud_std = t.positive("norm.cloud.std", two);
  const Eigen::VectorXd xi_mean = t.vector("norm.xi.mean", N2);
  const Eigen::VectorXd xi_std = t.positive("norm.xi.std", N2);
  const Eigen::VectorXd output_offset = t.vector("norm.output.offset", Y);
  const Eigen::VectorXd output_scale = t.vector("norm.output.scale", Y);

  pointnet.clear();
  Dim in = two;
  for (std::size_t i = 0; i < c.pointnet_widths.size(); ++i) {
    const Dim out{c.pointnet_widths[i], "network.pointnet_widths[" + std::to_string(i) + "]"};
    Linear l = t.linear("pointnet.conv" + std::to_string(i), out, in);
    t.fold_batch_norm(l, "pointnet.bn" + std::to_string(i), out, eps);
    if (i == 0) fold_input_normalisation(l, 0, cloud_mean, cloud_std);
    pointnet.emplace_back(l);
    in = out;
  }
  {
    Linear fc0 = t.linear("pointnet.fc0", Hp, in);
    t.fold_batch_norm(fc0, "pointnet.fc_bn0", Hp, eps);
    pointnet_fc0 = Dense(fc0);
    pointnet_fc1 = Dense(t.linear("pointnet.fc1", F, Hp));
  }

  // Encoder: input [obs_n, features, xi_n].
  encoder.clear();
  const Dim encoder_in{c.observation + c.features + n2,
                       "(network.observation + network.features + 2 network.coefficients)"};
  for (int i = 0; i < c.layers; ++i) {
    Linear l = t.linear("encoder.fc" + std::to_string(i), H, i == 0 ? encoder_in : H);
    t.fold_batch_norm(l, "encoder.bn" + std::to_string(i), H, eps);
    if (i == 0) {
      fold_input_normalisation(l, 0, observation_mean, observation_std);
      fold_input_normalisation(l, c.observation + c.features, xi_mean, xi_std);
    }
    encoder.emplace_back(l);
  }
  encoder_mean = Dense(t.linear("encoder.mean", Z, H));
  encoder_std = Dense(t.linear("encoder.std", Z, H));

  // Decoder: input [z, obs_n, features]; fc0 split by input so that the shared part is computed once a cycle.
  decoder_hidden.clear();
  const Dim decoder_in{c.latent + c.observation + c.features,
                       "(network.latent + network.observation + network.features)"};
  for (int i = 0; i < c.layers; ++i) {
    Linear l = t.linear("decoder.fc" + std::to_string(i), H, i == 0 ? decoder_in : H);
    t.fold_batch_norm(l, "decoder.bn" + std::to_string(i), H, eps);
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
    Linear out = t.linear("decoder.out", Y, H);
    out.weight = output_scale.asDiagonal() * out.weight;
    out.bias = (output_scale.array() * out.bias.array() + output_offset.array()).matrix();
    decoder_out = Dense(out);
  }
}

Model Model::load(const std::string& path) { return Model(io::read_safetensors(path)); }

Model::Model(const io::TensorFile& file) : impl_(std::make_unique<Impl>()) {
  impl_->load(file);
  impl_->reserve(30, impl_->network.cloud_points);
}

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
