// The model file's contract (docs/learning.md, "Model file"): variant, sizes, metadata, the tensor table,
// and the checks every reader relies on.
#include "occtrack/io/model_file.hpp"

#include <cmath>
#include <sstream>

#include "json_util.hpp"
#include "occtrack/io/projection_case.hpp"

namespace occtrack::io {

namespace {

using detail::json;
using detail::JsonReader;

[[noreturn]] void fail(const std::string& source, const std::string& what) { throw InputError(source + ": " + what); }

template <typename T>
std::string number_text(T value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

json parse_metadata_json(const std::string& text, const std::string& source, const std::string& key) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    fail(source, "metadata " + key + " is not valid JSON (" + detail::printable(e.what()) + ")");
  }
}

// Checks one tensor against its entry of the table: present, shaped, F32 or F64, finite, and the rule of its
// role. The first broken rule is reported, naming the metadata field a wrong dimension contradicts.
void check_tensor(const TensorFile& file, const std::string& source, const TensorSpec& spec) {
  const auto it = file.tensors.find(spec.name);
  if (it == file.tensors.end()) fail(source, "tensor '" + spec.name + "' is missing");
  const Tensor& t = it->second;
  if (t.shape != spec.shape) {
    const std::string detail =
        "tensor '" + spec.name + "' has shape " + t.shape_text() + ", expected " + shape_text(spec.shape);
    if (t.shape.size() == spec.shape.size())
      for (std::size_t i = 0; i < spec.shape.size(); ++i)
        if (t.shape[i] != spec.shape[i] && !spec.fields[i].empty())
          fail(source, "metadata " + spec.fields[i] + " is " + std::to_string(spec.shape[i]) + ", the tensors say " +
                           std::to_string(t.shape[i]) + " (" + detail + ")");
    fail(source, detail);
  }
  if (t.dtype != DType::F32 && t.dtype != DType::F64)
    fail(source, "tensor '" + spec.name + "' has dtype " + dtype_name(t.dtype) + ", expected F32");
  const std::vector<double> v = t.as_double();
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      fail(source, "tensor '" + spec.name + "' holds a non-finite value (" + number_text(v[i]) + ") at flat index " +
                       std::to_string(i));
  if (spec.role == TensorRole::input_std)
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!(v[i] > 0.0))
        fail(source, "tensor '" + spec.name + "' must be positive, holds " + number_text(v[i]) + " at index " +
                         std::to_string(i));
  if (spec.role == TensorRole::norm_variance)
    for (std::size_t i = 0; i < v.size(); ++i)
      if (v[i] < 0.0)
        fail(source, "tensor '" + spec.name + "' holds a negative variance (" + number_text(v[i]) + ") at index " +
                         std::to_string(i));
}

// Metadata `band`, or `ranking` holding {"band": {...}}; the first that holds a band object.
std::optional<core::TrackingBand> read_band(const std::map<std::string, std::string>& metadata,
                                            const std::string& source) {
  for (const char* key : {"band", "ranking"}) {
    const auto it = metadata.find(key);
    if (it == metadata.end()) continue;
    const json doc = parse_metadata_json(it->second, source, key);
    const json& b = doc.is_object() && doc.contains("band") ? doc["band"] : doc;
    if (!b.is_object() || !b.contains("min")) continue;
    const JsonReader r(source);
    const std::string p = std::string(key) + (&b == &doc ? "" : ".band");
    core::TrackingBand band;
    band.min = r.number(r.member(b, p, "min"), p + ".min");
    band.reference = r.number(r.member(b, p, "reference"), p + ".reference");
    band.max = r.number(r.member(b, p, "max"), p + ".max");
    return band;
  }
  return std::nullopt;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------------
// Variant, sizes, layout.

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
  throw InputError("variant '" + detail::printable(text) + "' is not one of cvae, bc, fixed-q");
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
  // Upper bounds, so that a malformed file cannot ask for gigabytes of workspace before its tensors are
  // checked (the cloud sizes the PointNet workspaces; found by fuzz/fuzz_model_file.cpp). Points share the
  // projection's bound (10^5); layers and widths are far above any network occtrack trains.
  const struct {
    const char* name;
    int value, max;
  } bounded[] = {{"cloud_points", cloud_points, kMaxNetworkPoints}, {"nearest_points", nearest_points, kMaxNetworkPoints},
                 {"latent", latent, kMaxNetworkWidth},          {"pointnet_hidden", pointnet_hidden, kMaxNetworkWidth},
                 {"features", features, kMaxNetworkWidth},      {"hidden", hidden, kMaxNetworkWidth},
                 {"layers", layers, kMaxNetworkLayers},         {"coefficients", coefficients, kMaxNetworkWidth},
                 {"steps", steps, kMaxNetworkWidth}};
  for (const auto& f : bounded)
    if (f.value > f.max)
      return bad(std::string(f.name) + " (" + std::to_string(f.value) + ") must be at most " + std::to_string(f.max));
  if (pointnet_widths.size() > static_cast<std::size_t>(kMaxNetworkLayers))
    return bad("pointnet_widths holds " + std::to_string(pointnet_widths.size()) + " widths, at most " +
               std::to_string(kMaxNetworkLayers) + " are allowed");
  for (std::size_t i = 0; i < pointnet_widths.size(); ++i)
    if (pointnet_widths[i] > kMaxNetworkWidth)
      return bad("pointnet_widths[" + std::to_string(i) + "] (" + std::to_string(pointnet_widths[i]) +
                 ") must be at most " + std::to_string(kMaxNetworkWidth));
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
                  {"batch_norm_eps", batch_norm_eps},
                  {"frame", target_frame ? "target" : "robot"}};
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
  if (doc.contains("frame")) {  // files before issue 12 have none: robot frame
    const json& frame = doc["frame"];
    if (!frame.is_string() || (frame != "robot" && frame != "target"))
      r.fail(p + ".frame", "must be \"robot\" or \"target\"");
    c.target_frame = frame == "target";
  }
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

std::vector<std::pair<int, int>> OutputLayout::turning_pairs() const {
  const int n = (distance_min - lambda0) / 2;
  std::vector<std::pair<int, int>> pairs = {{terminal, terminal + 1}, {terminal + 2, terminal + 3}, {via, via + 1},
                                            {via + 2, via + 3}};
  for (int block : {lambda0, xi_bar})
    for (int i = 0; i < n; ++i) pairs.emplace_back(block + i, block + n + i);
  return pairs;
}

std::string band_json(const core::TrackingBand& band) {
  return json{{"min", band.min}, {"reference", band.reference}, {"max", band.max}}.dump();
}

// ---------------------------------------------------------------------------------------------------------------
// The tensor table.

std::vector<TensorSpec> model_tensors(const NetworkConfig& c) {
  // One dimension and the metadata field it comes from.
  struct Dim {
    std::int64_t size;
    std::string field;
  };
  std::vector<TensorSpec> specs;
  auto add = [&](const std::string& name, std::initializer_list<Dim> dims, TensorRole role) {
    TensorSpec s{name, {}, {}, role};
    for (const Dim& d : dims) {
      s.shape.push_back(d.size);
      s.fields.push_back(d.field);
    }
    specs.push_back(std::move(s));
  };
  auto linear = [&](const std::string& prefix, const Dim& out, const Dim& in) {
    add(prefix + ".weight", {out, in}, TensorRole::weight);
    add(prefix + ".bias", {out}, TensorRole::bias);
  };
  auto batch_norm = [&](const std::string& prefix, const Dim& width) {
    add(prefix + ".weight", {width}, TensorRole::norm_weight);
    add(prefix + ".bias", {width}, TensorRole::norm_bias);
    add(prefix + ".running_mean", {width}, TensorRole::norm_mean);
    add(prefix + ".running_var", {width}, TensorRole::norm_variance);
  };
  const int n2 = 2 * c.coefficients;
  const Dim O{c.observation, "network.observation"}, F{c.features, "network.features"},
      H{c.hidden, "network.hidden"}, Hp{c.pointnet_hidden, "network.pointnet_hidden"}, Z{c.latent, "network.latent"},
      Y{c.outputs, "network.outputs"}, N2{n2, "network.coefficients (2n)"}, two{2, ""};

  add("norm.observation.mean", {O}, TensorRole::input_mean);
  add("norm.observation.std", {O}, TensorRole::input_std);
  add("norm.cloud.mean", {two}, TensorRole::input_mean);
  add("norm.cloud.std", {two}, TensorRole::input_std);
  add("norm.xi.mean", {N2}, TensorRole::input_mean);
  add("norm.xi.std", {N2}, TensorRole::input_std);
  add("norm.output.offset", {Y}, TensorRole::output_offset);
  add("norm.output.scale", {Y}, TensorRole::output_scale);

  Dim in = two;
  for (std::size_t i = 0; i < c.pointnet_widths.size(); ++i) {
    const Dim out{c.pointnet_widths[i], "network.pointnet_widths[" + std::to_string(i) + "]"};
    linear("pointnet.conv" + std::to_string(i), out, in);
    batch_norm("pointnet.bn" + std::to_string(i), out);
    in = out;
  }
  linear("pointnet.fc0", Hp, in);
  batch_norm("pointnet.fc_bn0", Hp);
  linear("pointnet.fc1", F, Hp);

  const Dim encoder_in{c.observation + c.features + n2,
                       "(network.observation + network.features + 2 network.coefficients)"};
  for (int i = 0; i < c.layers; ++i) {
    linear("encoder.fc" + std::to_string(i), H, i == 0 ? encoder_in : H);
    batch_norm("encoder.bn" + std::to_string(i), H);
  }
  linear("encoder.mean", Z, H);
  linear("encoder.std", Z, H);

  const Dim decoder_in{c.latent + c.observation + c.features,
                       "(network.latent + network.observation + network.features)"};
  for (int i = 0; i < c.layers; ++i) {
    linear("decoder.fc" + std::to_string(i), H, i == 0 ? decoder_in : H);
    batch_norm("decoder.bn" + std::to_string(i), H);
  }
  linear("decoder.out", Y, H);
  return specs;
}

// ---------------------------------------------------------------------------------------------------------------
// Reading and writing.

std::vector<double> ModelFile::values(const std::string& name) const {
  const auto it = tensors.find(name);
  if (it == tensors.end()) fail(source, "tensor '" + name + "' is missing");
  return it->second.as_double();
}

ModelFile validate_model_file(const TensorFile& file) {
  ModelFile m;
  m.source = file.source.empty() ? "model" : file.source;
  m.metadata = file.metadata;
  const std::string& source = m.source;
  auto meta = [&](const std::string& key) -> const std::string& {
    const auto it = file.metadata.find(key);
    if (it == file.metadata.end()) fail(source, "metadata '" + key + "' is missing");
    return it->second;
  };

  // Metadata: format, variant, sizes, the optimizer trained through, the band.
  const std::string& format = meta("format");
  if (format != kModelFormat)
    fail(source, "metadata format is '" + detail::printable(format) + "', expected '" + std::string(kModelFormat) + "'");
  const std::string& variant = meta("variant");
  if (variant != "cvae" && variant != "bc" && variant != "fixed-q")
    fail(source, "metadata variant is '" + detail::printable(variant) + "', expected one of cvae, bc, fixed-q");
  m.variant = parse_variant(variant);
  m.network = NetworkConfig::parse(meta("network"), source);
  m.projection = parse_projection_settings(meta("projection"), source, "projection", /*strict=*/false);
  m.projection_has_rho = json::parse(meta("projection")).contains("rho");
  m.projection.obstacles = m.network.nearest_points;
  {
    std::string error;
    if (!m.projection.validate(&error)) fail(source, "metadata projection: " + error);
  }
  if (m.network.coefficients != m.projection.coefficients())
    fail(source, "metadata network.coefficients is " + std::to_string(m.network.coefficients) +
                     ", projection.degree + 1 is " + std::to_string(m.projection.coefficients()));
  if (m.network.steps != m.projection.steps)
    fail(source, "metadata network.steps is " + std::to_string(m.network.steps) + ", projection.steps is " +
                     std::to_string(m.projection.steps));
  m.band = read_band(file.metadata, source);

  // Tensors, in the table's order, so that the first broken one is the one reported.
  for (const TensorSpec& spec : model_tensors(m.network)) check_tensor(file, source, spec);
  m.tensors = file.tensors;
  return m;
}

ModelFile read_model_file(const std::string& path) {
  TensorFile file = read_safetensors(path);
  if (file.source.empty()) file.source = path;
  return validate_model_file(file);
}

TensorFile to_tensor_file(const ModelFile& m) {
  TensorFile file;
  file.source = m.source;
  file.metadata = m.metadata;
  file.metadata["format"] = kModelFormat;
  file.metadata["variant"] = to_string(m.variant);
  file.metadata["network"] = m.network.to_json();
  json projection = json::parse(projection_settings_json(m.projection));
  projection["training_iterations"] = m.projection.iterations;
  // A file that did not record rho is written without it: check_projection compares rho only when the file
  // records one, so writing the default here would change what the file asks of the run's settings.
  if (!m.projection_has_rho) projection.erase("rho");
  file.metadata["projection"] = projection.dump();
  if (m.band) file.metadata["band"] = band_json(*m.band);
  file.tensors = m.tensors;
  return file;
}

void write_model_file(const std::string& path, const ModelFile& model) {
  write_safetensors(path, to_tensor_file(model));
}

}  // namespace occtrack::io
