// The dataset file's contract (docs/learning.md, "Dataset file"): tensors, checks, append, statistics.
#include "occtrack/io/dataset_file.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "json_util.hpp"
#include "occtrack/core/bernstein.hpp"
#include "occtrack/io/projection_case.hpp"

namespace occtrack::io {

namespace {

using detail::json;

std::string source_of(const std::string& source) { return source.empty() ? "dataset" : source; }

[[noreturn]] void fail(const std::string& source, const std::string& what) { throw InputError(source + ": " + what); }

void check_size(std::size_t size, std::int64_t expected, const char* name) {
  if (static_cast<std::int64_t>(size) != expected)
    throw std::invalid_argument(std::string("dataset: ") + name + " holds " + std::to_string(size) +
                                " values, expected " + std::to_string(expected));
}

const std::string* find_meta(const TensorFile& file, const std::string& key) {
  const auto it = file.metadata.find(key);
  return it == file.metadata.end() ? nullptr : &it->second;
}

const std::string& require_meta(const TensorFile& file, const std::string& source, const std::string& key) {
  const std::string* value = find_meta(file, key);
  if (!value) fail(source, "metadata '" + key + "' is missing");
  return *value;
}

json parse_meta_object(const std::string& source, const std::string& key, const std::string& text) {
  try {
    json value = json::parse(text);
    if (!value.is_object()) fail(source, "metadata '" + key + "' is not a JSON object");
    return value;
  } catch (const json::exception& e) {
    fail(source, "metadata '" + key + "' is not valid JSON (" + detail::printable(e.what()) + ")");
  }
}

int meta_int(const std::string& source, const json& object, const std::string& key, const std::string& field) {
  if (!object.contains(field) || !object.at(field).is_number_integer())
    fail(source, "metadata '" + key + "': '" + field + "' must be an integer");
  return object.at(field).get<int>();
}

// Dimension `axis` of tensor `name`, which must exist with `rank` dimensions (for sizes the metadata does
// not give).
std::int64_t dimension(const TensorFile& file, const std::string& source, const std::string& name, std::size_t rank,
                       std::size_t axis) {
  const auto it = file.tensors.find(name);
  if (it == file.tensors.end()) fail(source, "tensor '" + name + "' is missing");
  const Tensor& t = it->second;
  if (t.shape.size() != rank)
    fail(source, "tensor '" + name + "' has shape " + t.shape_text() + ", expected " + std::to_string(rank) +
                     " dimension(s)");
  return t.shape[axis];
}

const Tensor& shaped(const TensorFile& file, const std::string& source, const std::string& name,
                     const std::vector<std::int64_t>& shape) {
  const auto it = file.tensors.find(name);
  if (it == file.tensors.end()) fail(source, "tensor '" + name + "' is missing");
  if (it->second.shape != shape)
    fail(source, "tensor '" + name + "' has shape " + it->second.shape_text() + ", expected " + shape_text(shape));
  return it->second;
}

// A float column (F32 or F64) as float32, finite.
std::vector<float> float_column(const TensorFile& file, const std::string& source, const std::string& name,
                                const std::vector<std::int64_t>& shape) {
  const Tensor& t = shaped(file, source, name, shape);
  if (t.dtype != DType::F32 && t.dtype != DType::F64)
    fail(source, "tensor '" + name + "' has dtype " + dtype_name(t.dtype) + ", expected F32 or F64");
  std::vector<float> values = t.as_float();
  const auto bad = std::find_if(values.begin(), values.end(), [](float v) { return !std::isfinite(v); });
  if (bad != values.end()) {
    const std::int64_t per_row = shape[0] == 0 ? 1 : static_cast<std::int64_t>(values.size()) / shape[0];
    fail(source, "tensor '" + name + "' holds a non-finite value in row " + std::to_string((bad - values.begin()) / per_row));
  }
  return values;
}

// The episode column (I32 or I64) as int32, each index in [0, int32 max].
std::vector<std::int32_t> episode_column(const TensorFile& file, const std::string& source, std::int64_t rows) {
  const Tensor& t = shaped(file, source, "episode", {rows});
  if (t.dtype != DType::I32 && t.dtype != DType::I64)
    fail(source, "tensor 'episode' has dtype " + std::string(dtype_name(t.dtype)) + ", expected I32 or I64");
  const std::vector<double> values = t.as_double();  // exact for every int32, and for int64 up to 2^53
  std::vector<std::int32_t> episode(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (values[i] < 0) fail(source, "tensor 'episode' has a negative index in row " + std::to_string(i));
    if (values[i] > std::numeric_limits<std::int32_t>::max())
      fail(source, "tensor 'episode' holds an index beyond int32 in row " + std::to_string(i));
    episode[i] = static_cast<std::int32_t>(values[i]);
  }
  return episode;
}

}  // namespace

TensorFile to_tensor_file(const DatasetFile& d) {
  const std::int64_t S = d.rows, C = d.cloud_points, N = d.nearest_points, n = d.coefficients;
  if (S < 0 || C < 1 || N < 0 || n < 1) throw std::invalid_argument("dataset: negative or zero sizes");
  check_size(d.observation.size(), S * kObservationSize, "observation");
  check_size(d.cloud.size(), S * C * 2, "cloud");
  check_size(d.obstacles.size(), S * N * 4, "obstacles");
  check_size(d.expert_xi.size(), S * 2 * n, "expert_xi");
  check_size(d.expert_cost.size(), S, "expert_cost");
  check_size(d.episode.size(), S, "episode");
  check_size(d.time.size(), S, "time");
  TensorFile file;
  file.source = d.source;
  file.metadata = d.metadata;
  file.metadata["format"] = kDatasetFormat;
  file.metadata["rows"] = std::to_string(S);
  file.put("observation", {S, kObservationSize}, d.observation);
  file.put("cloud", {S, C, 2}, d.cloud);
  file.put("obstacles", {S, N, 4}, d.obstacles);
  file.put("expert_xi", {S, 2 * n}, d.expert_xi);
  file.put("expert_cost", {S}, d.expert_cost);
  file.put("episode", {S}, d.episode);
  file.put("time", {S}, d.time);
  return file;
}

projection::Settings dataset_projection(const DatasetFile& data) {
  const std::string source = source_of(data.source);
  const auto it = data.metadata.find("projection");
  if (it == data.metadata.end()) fail(source, "metadata 'projection' is missing");
  projection::Settings s = parse_projection_settings(it->second, source, "projection", /*strict=*/false);
  std::string error;
  if (!s.validate(&error)) fail(source, "metadata 'projection': " + error);
  return s;
}

DatasetFile validate_dataset_file(const TensorFile& file) {
  DatasetFile d;
  d.source = source_of(file.source);
  const std::string& source = d.source;
  const std::string& format = require_meta(file, source, "format");
  if (format != kDatasetFormat)
    fail(source, "metadata 'format' is '" + detail::printable(format) + "', expected '" + kDatasetFormat + "'");
  d.metadata = file.metadata;
  require_meta(file, source, "projection");
  d.coefficients = dataset_projection(d).coefficients();

  // Sizes: from the metadata where the file records them (checked against the tensors below), otherwise
  // from the tensors themselves.
  std::int64_t S = -1, C = -1, N = -1;
  if (const std::string* text = find_meta(file, "rows")) {
    try {
      std::size_t used = 0;
      S = std::stoll(*text, &used);
      if (used != text->size()) S = -1;
    } catch (const std::exception&) {
      S = -1;
    }
    if (S < 0) fail(source, "metadata 'rows' ('" + *text + "') is not a row count");
  }
  if (const std::string* text = find_meta(file, "perception")) {
    const json perception = parse_meta_object(source, "perception", *text);
    C = meta_int(source, perception, "perception", "cloud_size");
    N = meta_int(source, perception, "perception", "nearest_count");
    if (C < 1 || N < 0)
      fail(source, "metadata 'perception' sizes out of range (cloud_size " + std::to_string(C) + ", nearest_count " +
                       std::to_string(N) + ")");
  }
  if (S < 0) S = dimension(file, source, "observation", 2, 0);
  if (C < 0) C = dimension(file, source, "cloud", 3, 1);
  if (N < 0) N = dimension(file, source, "obstacles", 3, 1);
  if (C == 0) fail(source, "tensor 'cloud' has no points");
  d.rows = S;
  d.cloud_points = static_cast<int>(C);
  d.nearest_points = static_cast<int>(N);

  const std::int64_t n2 = 2 * static_cast<std::int64_t>(d.coefficients);
  d.observation = float_column(file, source, "observation", {S, kObservationSize});
  d.cloud = float_column(file, source, "cloud", {S, C, 2});
  d.obstacles = float_column(file, source, "obstacles", {S, N, 4});
  d.expert_xi = float_column(file, source, "expert_xi", {S, n2});
  d.expert_cost = float_column(file, source, "expert_cost", {S});
  d.episode = episode_column(file, source, S);
  d.time = float_column(file, source, "time", {S});
  return d;
}

DatasetFile read_dataset_file(const std::string& path) {
  TensorFile file = read_safetensors(path);
  if (file.source.empty()) file.source = path;
  return validate_dataset_file(file);
}

void write_dataset_file(const std::string& path, const DatasetFile& data) { write_safetensors(path, to_tensor_file(data)); }

void append_rows(DatasetFile& into, const DatasetFile& from, std::int32_t episode_offset) {
  auto cat = [](auto& a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); };
  cat(into.observation, from.observation);
  cat(into.cloud, from.cloud);
  cat(into.obstacles, from.obstacles);
  cat(into.expert_xi, from.expert_xi);
  cat(into.expert_cost, from.expert_cost);
  cat(into.time, from.time);
  for (std::int32_t e : from.episode) into.episode.push_back(e + episode_offset);
  into.rows += from.rows;
}

void append_dataset(DatasetFile& into, const DatasetFile& more) {
  if (into.rows == 0 && into.metadata.empty()) {
    into = more;
    return;
  }
  if (into.cloud_points != more.cloud_points || into.nearest_points != more.nearest_points ||
      into.coefficients != more.coefficients)
    throw std::invalid_argument("append_dataset: sizes differ (cloud points, nearest points, coefficients)");
  for (const char* key : {"projection", "perception"}) {
    const auto a = into.metadata.find(key);
    const auto b = more.metadata.find(key);
    const std::string left = a == into.metadata.end() ? "" : a->second;
    const std::string right = b == more.metadata.end() ? "" : b->second;
    if (left != right)
      throw std::invalid_argument(std::string("append_dataset: metadata '") + key + "' differs: " + left + " vs " +
                                  right);
  }
  std::int32_t offset = 0;
  for (std::int32_t e : into.episode) offset = std::max(offset, e + 1);
  append_rows(into, more, offset);
  into.metadata["rows"] = std::to_string(into.rows);
}

// ---------------------------------------------------------------------------------------------------------
// Statistics.

DatasetStatistics dataset_statistics(const DatasetFile& d) {
  const std::string source = source_of(d.source);
  const projection::Settings projection = dataset_projection(d);
  const int degree = projection.degree, steps = projection.steps;
  const double horizon = projection.horizon;
  if (degree + 1 != d.coefficients)
    fail(source, "metadata 'projection': degree + 1 differs from the coefficients of expert_xi");
  core::BernsteinBasis basis;
  try {
    basis = core::bernstein_basis(degree, steps, horizon);
  } catch (const std::invalid_argument& e) {
    fail(source, std::string("metadata 'projection': ") + detail::printable(e.what()));
  }
  const int n = d.coefficients;
  const int first_steps = std::max(1, std::min(steps - 1, static_cast<int>(std::lround(0.1 / horizon * (steps - 1)))));

  DatasetStatistics s;
  s.rows = d.rows;
  s.episodes = static_cast<int>(std::set<std::int32_t>(d.episode.begin(), d.episode.end()).size());
  if (d.rows == 0) return s;
  const double S = static_cast<double>(d.rows);
  Eigen::Matrix<double, kObservationSize, 1> sum = decltype(sum)::Zero(), sum2 = decltype(sum)::Zero();
  double speed_sum = 0, speed_sum2 = 0, start_sum = 0, cost_sum = 0, cost_sum2 = 0, distance_sum = 0;
  s.cost_min = INFINITY;
  s.cost_max = -INFINITY;
  Eigen::VectorXd cx(n), cy(n);
  for (std::int64_t r = 0; r < d.rows; ++r) {
    for (int j = 0; j < kObservationSize; ++j) {
      const double v = d.observation[static_cast<std::size_t>(r * kObservationSize + j)];
      sum(j) += v;
      sum2(j) += v * v;
    }
    distance_sum += std::hypot(d.observation[static_cast<std::size_t>(r * kObservationSize + 2)],
                               d.observation[static_cast<std::size_t>(r * kObservationSize + 3)]);
    for (int i = 0; i < n; ++i) {
      cx(i) = d.expert_xi[static_cast<std::size_t>(r * 2 * n + i)];
      cy(i) = d.expert_xi[static_cast<std::size_t>(r * 2 * n + n + i)];
    }
    const Eigen::VectorXd speed = ((basis.Pd * cx).array().square() + (basis.Pd * cy).array().square()).sqrt();
    const double mean_speed = speed.mean();
    speed_sum += mean_speed;
    speed_sum2 += mean_speed * mean_speed;
    s.plan_speed_max = std::max(s.plan_speed_max, speed.maxCoeff());
    const Eigen::Vector2d start((basis.P.row(first_steps) - basis.P.row(0)).dot(cx),
                                (basis.P.row(first_steps) - basis.P.row(0)).dot(cy));
    start_sum += start.norm() / basis.times(first_steps);
    const double c = d.expert_cost[static_cast<std::size_t>(r)];
    cost_sum += c;
    cost_sum2 += c * c;
    s.cost_min = std::min(s.cost_min, c);
    s.cost_max = std::max(s.cost_max, c);
  }
  auto spread = [&](double total, double total2) { return std::sqrt(std::max(0.0, total2 / S - (total / S) * (total / S))); };
  s.observation_mean = sum / S;
  for (int j = 0; j < kObservationSize; ++j) s.observation_std(j) = spread(sum(j), sum2(j));
  s.plan_speed_mean = speed_sum / S;
  s.plan_speed_std = spread(speed_sum, speed_sum2);
  s.start_speed_mean = start_sum / S;
  s.cost_mean = cost_sum / S;
  s.cost_std = spread(cost_sum, cost_sum2);
  s.target_distance_mean = distance_sum / S;
  return s;
}

}  // namespace occtrack::io
