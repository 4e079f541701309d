// The dataset file format of demonstrations (docs/learning.md, "Dataset file"): tensors, checks, append,
// statistics.
#include "occtrack/sim/demonstrations.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "occtrack/io/error.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/io/safetensors.hpp"

namespace occtrack::sim {

using nlohmann::json;

// Appends every row of `from` to `into`, its episode numbers shifted by `episode_offset`.
void append_rows(Demonstrations& into, const Demonstrations& from, std::int32_t episode_offset) {
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


namespace {

std::int64_t checked_size(const std::vector<float>& v, std::int64_t expected, const char* name) {
  if (static_cast<std::int64_t>(v.size()) != expected)
    throw std::invalid_argument(std::string("demonstrations: ") + name + " holds " + std::to_string(v.size()) +
                                " values, expected " + std::to_string(expected));
  return expected;
}

std::string source_of(const io::TensorFile& file) { return file.source.empty() ? "dataset" : file.source; }

json parse_meta_json(const io::TensorFile& file, const std::string& key) {
  const std::string& text = file.meta(key);
  try {
    json value = json::parse(text);
    if (!value.is_object()) throw io::InputError(source_of(file) + ": metadata '" + key + "' is not a JSON object");
    return value;
  } catch (const json::exception& e) {
    throw io::InputError(source_of(file) + ": metadata '" + key + "' is not valid JSON (" + e.what() + ")");
  }
}

int meta_int(const io::TensorFile& file, const json& object, const std::string& key, const std::string& field) {
  if (!object.contains(field) || !object.at(field).is_number_integer())
    throw io::InputError(source_of(file) + ": metadata '" + key + "': '" + field + "' must be an integer");
  return object.at(field).get<int>();
}

double meta_number(const io::TensorFile& file, const json& object, const std::string& key, const std::string& field) {
  if (!object.contains(field) || !object.at(field).is_number())
    throw io::InputError(source_of(file) + ": metadata '" + key + "': '" + field + "' must be a number");
  return object.at(field).get<double>();
}

std::vector<float> float_tensor(const io::TensorFile& file, const std::string& name,
                                const std::vector<std::int64_t>& shape) {
  const io::Tensor& t = file.at(name, shape);
  if (t.dtype != io::DType::F32)
    throw io::InputError(source_of(file) + ": tensor '" + name + "' has dtype " + io::dtype_name(t.dtype) +
                         ", expected F32");
  std::vector<float> values = t.as_float();
  const auto bad = std::find_if(values.begin(), values.end(), [](float v) { return !std::isfinite(v); });
  if (bad != values.end()) {
    const std::int64_t index = bad - values.begin();
    const std::int64_t per_row = shape.empty() || shape[0] == 0 ? 1 : static_cast<std::int64_t>(values.size()) / shape[0];
    throw io::InputError(source_of(file) + ": tensor '" + name + "' holds a non-finite value in row " +
                         std::to_string(index / per_row));
  }
  return values;
}

}  // namespace

io::TensorFile to_tensor_file(const Demonstrations& d) {
  const std::int64_t S = d.rows, C = d.cloud_points, N = d.nearest_points, n = d.coefficients;
  if (S < 0 || C < 1 || N < 0 || n < 1) throw std::invalid_argument("demonstrations: negative or zero sizes");
  io::TensorFile file;
  file.metadata = d.metadata;
  file.metadata["format"] = kDatasetFormat;
  file.metadata["rows"] = std::to_string(S);
  checked_size(d.observation, S * kObservationSize, "observation");
  checked_size(d.cloud, S * C * 2, "cloud");
  checked_size(d.obstacles, S * N * 4, "obstacles");
  checked_size(d.expert_xi, S * 2 * n, "expert_xi");
  checked_size(d.expert_cost, S, "expert_cost");
  checked_size(d.time, S, "time");
  if (static_cast<std::int64_t>(d.episode.size()) != S)
    throw std::invalid_argument("demonstrations: episode holds " + std::to_string(d.episode.size()) +
                                " values, expected " + std::to_string(S));
  file.put("observation", {S, kObservationSize}, d.observation);
  file.put("cloud", {S, C, 2}, d.cloud);
  file.put("obstacles", {S, N, 4}, d.obstacles);
  file.put("expert_xi", {S, 2 * n}, d.expert_xi);
  file.put("expert_cost", {S}, d.expert_cost);
  file.put("episode", {S}, d.episode);
  file.put("time", {S}, d.time);
  return file;
}

Demonstrations from_tensor_file(const io::TensorFile& file) {
  const std::string source = source_of(file);
  const std::string& format = file.meta("format");
  if (format != kDatasetFormat)
    throw io::InputError(source + ": metadata 'format' is '" + format + "', expected '" + kDatasetFormat + "'");
  Demonstrations d;
  d.metadata = file.metadata;
  const json perception = parse_meta_json(file, "perception");
  const json projection = parse_meta_json(file, "projection");
  d.cloud_points = meta_int(file, perception, "perception", "cloud_size");
  d.nearest_points = meta_int(file, perception, "perception", "nearest_count");
  d.coefficients = meta_int(file, projection, "projection", "degree") + 1;
  if (d.cloud_points < 1 || d.nearest_points < 0 || d.coefficients < 2)
    throw io::InputError(source + ": metadata sizes out of range (cloud_size " + std::to_string(d.cloud_points) +
                         ", nearest_count " + std::to_string(d.nearest_points) + ", degree " +
                         std::to_string(d.coefficients - 1) + ")");
  const std::string& rows_text = file.meta("rows");
  std::int64_t rows = -1;
  try {
    std::size_t used = 0;
    rows = std::stoll(rows_text, &used);
    if (used != rows_text.size()) rows = -1;
  } catch (const std::exception&) {
    rows = -1;
  }
  if (rows < 0) throw io::InputError(source + ": metadata 'rows' ('" + rows_text + "') is not a row count");
  d.rows = rows;
  const std::int64_t S = rows, C = d.cloud_points, N = d.nearest_points, n = d.coefficients;
  d.observation = float_tensor(file, "observation", {S, kObservationSize});
  d.cloud = float_tensor(file, "cloud", {S, C, 2});
  d.obstacles = float_tensor(file, "obstacles", {S, N, 4});
  d.expert_xi = float_tensor(file, "expert_xi", {S, 2 * n});
  d.expert_cost = float_tensor(file, "expert_cost", {S});
  d.time = float_tensor(file, "time", {S});
  const io::Tensor& episode = file.at("episode", {S});
  if (episode.dtype != io::DType::I32)
    throw io::InputError(source + ": tensor 'episode' has dtype " + io::dtype_name(episode.dtype) +
                         ", expected I32");
  d.episode.resize(static_cast<std::size_t>(S));
  for (std::int64_t i = 0; i < S; ++i) {  // little-endian int32, as stored
    const unsigned char* b = episode.bytes.data() + 4 * i;
    d.episode[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(
        static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
        static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24);
  }
  return d;
}

void write_demonstrations(const std::string& path, const Demonstrations& data) {
  io::write_safetensors(path, to_tensor_file(data));
}

Demonstrations read_demonstrations(const std::string& path) {
  io::TensorFile file = io::read_safetensors(path);
  if (file.source.empty()) file.source = path;
  return from_tensor_file(file);
}

void append_demonstrations(Demonstrations& into, const Demonstrations& more) {
  if (into.rows == 0 && into.metadata.empty()) {
    into = more;
    return;
  }
  if (into.cloud_points != more.cloud_points || into.nearest_points != more.nearest_points ||
      into.coefficients != more.coefficients)
    throw std::invalid_argument("append_demonstrations: sizes differ (cloud points, nearest points, coefficients)");
  for (const char* key : {"projection", "perception"}) {
    const auto a = into.metadata.find(key);
    const auto b = more.metadata.find(key);
    const std::string left = a == into.metadata.end() ? "" : a->second;
    const std::string right = b == more.metadata.end() ? "" : b->second;
    if (left != right)
      throw std::invalid_argument(std::string("append_demonstrations: metadata '") + key + "' differs: " + left +
                                  " vs " + right);
  }
  std::int32_t offset = 0;
  for (std::int32_t e : into.episode) offset = std::max(offset, e + 1);
  append_rows(into, more, offset);
  into.metadata["rows"] = std::to_string(into.rows);
}

// ---------------------------------------------------------------------------------------------------------
// Statistics.

DemonstrationStatistics demonstration_statistics(const Demonstrations& d) {
  io::TensorFile meta;
  meta.source = "dataset";
  meta.metadata = d.metadata;
  const json projection = parse_meta_json(meta, "projection");
  const int degree = meta_int(meta, projection, "projection", "degree");
  const int steps = meta_int(meta, projection, "projection", "steps");
  const double horizon = meta_number(meta, projection, "projection", "horizon");
  if (degree + 1 != d.coefficients)
    throw io::InputError("dataset: metadata 'projection': degree + 1 differs from the coefficients of expert_xi");
  core::BernsteinBasis basis;
  try {
    basis = core::bernstein_basis(degree, steps, horizon);
  } catch (const std::invalid_argument& e) {
    throw io::InputError(std::string("dataset: metadata 'projection': ") + e.what());
  }
  const int n = d.coefficients;
  const int first_steps = std::max(1, std::min(steps - 1, static_cast<int>(std::lround(0.1 / horizon * (steps - 1)))));

  DemonstrationStatistics s;
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


}  // namespace occtrack::sim
