#include "learning/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>
#include <stdexcept>

#include "occtrack/io/error.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/io/safetensors.hpp"

namespace occtrack::learning {

using torch::indexing::Slice;

// ---------------------------------------------------------------------------------------------------------
// projection metadata

projection::Settings parse_projection_json(const std::string& text) {
  projection::Settings s;
  try {
    s = io::parse_projection_settings(text, "metadata", "projection", /*strict=*/false);
  } catch (const io::InputError& e) {
    throw std::invalid_argument(e.what());
  }
  std::string error;
  if (!s.validate(&error)) throw std::invalid_argument(error);
  return s;
}

std::string projection_json(const projection::Settings& s) { return io::projection_settings_json(s); }

// ---------------------------------------------------------------------------------------------------------
// loading

namespace {

[[noreturn]] void fail(const std::string& source, const std::string& what) { throw io::InputError(source + ": " + what); }

std::string shape_text(const std::vector<int64_t>& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

// The tensor `name` as a CPU tensor of `dtype` with `rank` dimensions; float32/float64 or int32/int64 only.
torch::Tensor to_torch(const io::TensorFile& file, const std::string& name, bool integer, std::size_t rank) {
  const io::Tensor& t = file.at(name);  // throws "SOURCE: tensor 'NAME' is missing"
  const bool is_integer = t.dtype == io::DType::I32 || t.dtype == io::DType::I64;
  if (is_integer != integer)
    fail(file.source, "tensor '" + name + "' has dtype " + io::dtype_name(t.dtype) + ", expected " +
                          (integer ? "I32 or I64" : "F32 or F64"));
  if (t.shape.size() != rank)
    fail(file.source, "tensor '" + name + "' has shape " + t.shape_text() + ", expected " + std::to_string(rank) +
                          " dimension(s)");
  const torch::Dtype source_dtype = t.dtype == io::DType::F32   ? torch::kFloat32
                                    : t.dtype == io::DType::F64 ? torch::kFloat64
                                    : t.dtype == io::DType::I32 ? torch::kInt32
                                                                : torch::kInt64;
  torch::Tensor out = torch::empty(t.shape, source_dtype);
  if (t.bytes.size() != static_cast<std::size_t>(out.numel()) * out.element_size())
    fail(file.source, "tensor '" + name + "' holds " + std::to_string(t.bytes.size()) + " bytes, its shape needs " +
                          std::to_string(out.numel() * out.element_size()));
  if (!t.bytes.empty()) std::memcpy(out.data_ptr(), t.bytes.data(), t.bytes.size());
  out = out.to(integer ? torch::kInt64 : torch::kFloat32);
  if (!integer && !torch::isfinite(out).all().item<bool>()) {
    const int64_t bad = (~torch::isfinite(out.reshape({out.size(0), -1}))).any(1).nonzero()[0].item<int64_t>();
    fail(file.source, "tensor '" + name + "' has a non-finite value in row " + std::to_string(bad));
  }
  return out;
}

void expect_shape(const io::TensorFile& file, const std::string& name, const torch::Tensor& t,
                  const std::vector<int64_t>& shape) {
  if (t.sizes().vec() != shape)
    fail(file.source, "tensor '" + name + "' has shape " + shape_text(t.sizes().vec()) + ", expected " +
                          shape_text(shape));
}

struct LoadedFile {
  DatasetFile info;
  projection::Settings projection;
  torch::Tensor observation, cloud, obstacles, expert_xi, expert_cost, episode, time;
};

LoadedFile load_one(const std::string& path) {
  const io::TensorFile file = io::read_safetensors(path);
  const std::string& format = file.meta("format");
  if (format != kDatasetFormat)
    fail(path, "metadata 'format' is '" + format + "', expected '" + kDatasetFormat + "'");
  LoadedFile f;
  f.info.path = path;
  f.info.metadata = file.metadata;
  try {
    f.projection = parse_projection_json(file.meta("projection"));
  } catch (const std::invalid_argument& e) {
    fail(path, std::string("metadata 'projection': ") + e.what());
  }
  const int64_t n2 = 2 * f.projection.coefficients();

  f.observation = to_torch(file, "observation", false, 2);
  const int64_t S = f.observation.size(0);
  expect_shape(file, "observation", f.observation, {S, 6});
  f.cloud = to_torch(file, "cloud", false, 3);
  expect_shape(file, "cloud", f.cloud, {S, f.cloud.size(1), 2});
  f.obstacles = to_torch(file, "obstacles", false, 3);
  expect_shape(file, "obstacles", f.obstacles, {S, f.obstacles.size(1), 4});
  f.expert_xi = to_torch(file, "expert_xi", false, 2);
  expect_shape(file, "expert_xi", f.expert_xi, {S, n2});
  f.expert_cost = to_torch(file, "expert_cost", false, 1);
  expect_shape(file, "expert_cost", f.expert_cost, {S});
  f.episode = to_torch(file, "episode", true, 1);
  expect_shape(file, "episode", f.episode, {S});
  f.time = to_torch(file, "time", false, 1);
  expect_shape(file, "time", f.time, {S});
  if (S == 0) fail(path, "the dataset has no rows");
  if (f.cloud.size(1) == 0) fail(path, "tensor 'cloud' has no points");
  if (f.episode.min().item<int64_t>() < 0) fail(path, "tensor 'episode' has a negative index");
  f.info.rows = S;
  f.info.episodes = std::get<0>(torch::_unique(f.episode)).numel();
  return f;
}

}  // namespace

Dataset load_dataset(const std::vector<std::string>& paths) {
  if (paths.empty()) throw io::InputError("no dataset file given");
  std::vector<LoadedFile> files;
  for (const auto& path : paths) files.push_back(load_one(path));
  const LoadedFile& first = files.front();
  for (const auto& f : files) {
    if (f.projection.degree != first.projection.degree || f.projection.steps != first.projection.steps ||
        f.projection.horizon != first.projection.horizon || f.projection.via_step_1 != first.projection.via_step_1 ||
        f.projection.via_step_2 != first.projection.via_step_2)
      fail(f.info.path, "metadata 'projection' (degree, steps, horizon, via_steps) differs from " + first.info.path);
    if (f.cloud.size(1) != first.cloud.size(1))
      fail(f.info.path, "tensor 'cloud' has " + std::to_string(f.cloud.size(1)) + " points per row, " +
                            first.info.path + " has " + std::to_string(first.cloud.size(1)));
    if (f.obstacles.size(1) != first.obstacles.size(1))
      fail(f.info.path, "tensor 'obstacles' has " + std::to_string(f.obstacles.size(1)) + " points per row, " +
                            first.info.path + " has " + std::to_string(first.obstacles.size(1)));
  }
  Dataset d;
  d.projection = first.projection;
  std::vector<torch::Tensor> obs, cloud, obstacles, xi, cost, episode, time;
  int64_t episode_offset = 0;
  for (auto& f : files) {
    obs.push_back(f.observation);
    cloud.push_back(f.cloud);
    obstacles.push_back(f.obstacles);
    xi.push_back(f.expert_xi);
    cost.push_back(f.expert_cost);
    time.push_back(f.time);
    episode.push_back(f.episode + episode_offset);
    episode_offset += f.episode.max().item<int64_t>() + 1;
    d.files.push_back(std::move(f.info));
  }
  d.observation = torch::cat(obs);
  d.cloud = torch::cat(cloud);
  d.obstacles = torch::cat(obstacles);
  d.expert_xi = torch::cat(xi);
  d.expert_cost = torch::cat(cost);
  d.episode = torch::cat(episode);
  d.time = torch::cat(time);
  return d;
}

Batch Dataset::gather(const torch::Tensor& indices, torch::Device device) const {
  const torch::Tensor i = indices.to(observation.device());
  return {observation.index_select(0, i).to(device), cloud.index_select(0, i).to(device),
          obstacles.index_select(0, i).to(device), expert_xi.index_select(0, i).to(device)};
}

void Dataset::to(torch::Device device) {
  for (torch::Tensor* t : {&observation, &cloud, &obstacles, &expert_xi, &expert_cost, &episode, &time})
    *t = t->to(device);
}

// ---------------------------------------------------------------------------------------------------------

DatasetSplit split_by_episode(const Dataset& data, double validation_share, std::uint64_t seed) {
  const torch::Tensor episode = data.episode.to(torch::kCPU);
  const torch::Tensor ids = std::get<0>(torch::_unique(episode, /*sorted=*/true));
  std::vector<int64_t> order(ids.data_ptr<int64_t>(), ids.data_ptr<int64_t>() + ids.numel());
  std::mt19937_64 rng(seed ^ 0x5eed5b1177ull);
  std::shuffle(order.begin(), order.end(), rng);
  int64_t held = 0;
  if (validation_share > 0 && order.size() > 1)
    held = std::min<int64_t>(static_cast<int64_t>(order.size()) - 1,
                             static_cast<int64_t>(std::ceil(validation_share * order.size())));
  torch::Tensor is_validation = torch::zeros_like(episode, torch::kBool);
  for (int64_t k = 0; k < held; ++k) is_validation |= episode == order[k];
  DatasetSplit split;
  split.train = (~is_validation).nonzero().reshape({-1});
  split.validation = is_validation.nonzero().reshape({-1});
  split.train_episodes = static_cast<int64_t>(order.size()) - held;
  split.validation_episodes = held;
  return split;
}

NormalizationStats compute_normalization(const Dataset& data, const torch::Tensor& rows, const NetworkConfig& config,
                                         const core::TrackingBand& band, double std_floor) {
  if (rows.numel() == 0) throw std::invalid_argument("normalisation: no training rows");
  torch::NoGradGuard no_grad;
  const torch::Tensor i = rows.to(data.observation.device());
  auto stats = [&](const torch::Tensor& x) {  // x: [R, D] float64
    torch::Tensor mean = x.mean(0);
    torch::Tensor std = x.size(0) > 1 ? x.std(0, /*unbiased=*/false) : torch::zeros_like(mean);
    return std::make_pair(mean, std.clamp_min(std_floor));
  };
  const auto f64 = torch::kFloat64;
  NormalizationStats s;
  std::tie(s.observation_mean, s.observation_std) = stats(data.observation.index_select(0, i).to(f64));
  std::tie(s.cloud_mean, s.cloud_std) = stats(data.cloud.index_select(0, i).to(f64).reshape({-1, 2}));
  const torch::Tensor xi = data.expert_xi.index_select(0, i).to(f64);
  std::tie(s.xi_mean, s.xi_std) = stats(xi);

  // Output offsets and scales: the expert's terminal state and via points, the band, xi.
  const TrajectoryBasis basis(data.projection, f64, xi.device());
  const int64_t n = data.coefficients(), m = data.projection.steps;
  const torch::Tensor cx = xi.index({Slice(), Slice(0, n)}), cy = xi.index({Slice(), Slice(n, 2 * n)});
  auto at = [&](const torch::Tensor& row) { return torch::stack({torch::mv(cx, row), torch::mv(cy, row)}, 1); };
  const torch::Tensor terminal = torch::cat({at(basis.P[m - 1]), at(basis.Pd[m - 1])}, 1);
  const torch::Tensor via = torch::cat({at(basis.P[data.projection.via_step_1]), at(basis.P[data.projection.via_step_2])}, 1);
  const auto [terminal_mean, terminal_std] = stats(terminal);
  const auto [via_mean, via_std] = stats(via);
  const OutputLayout l(config);
  torch::Tensor offset = torch::zeros({l.size}, f64), scale = torch::ones({l.size}, f64);
  offset.index_put_({Slice(l.terminal, l.terminal + 4)}, terminal_mean);
  scale.index_put_({Slice(l.terminal, l.terminal + 4)}, terminal_std);
  offset.index_put_({Slice(l.via, l.via + 4)}, via_mean);
  scale.index_put_({Slice(l.via, l.via + 4)}, via_std);
  const double band_scale = std::max(std_floor, (band.max - band.min) / 4.0);
  offset.index_put_({Slice(l.distance_min, l.distance_max)}, band.min);
  scale.index_put_({Slice(l.distance_min, l.distance_max)}, band_scale);
  offset.index_put_({Slice(l.distance_max, l.xi_bar)}, band.max);
  scale.index_put_({Slice(l.distance_max, l.xi_bar)}, band_scale);
  offset.index_put_({Slice(l.xi_bar, l.size)}, s.xi_mean);
  scale.index_put_({Slice(l.xi_bar, l.size)}, s.xi_std);
  s.output_offset = offset;
  s.output_scale = scale;
  for (torch::Tensor* t : {&s.observation_mean, &s.observation_std, &s.cloud_mean, &s.cloud_std, &s.xi_mean, &s.xi_std,
                           &s.output_offset, &s.output_scale})
    *t = t->to(torch::kCPU, torch::kFloat32);
  return s;
}

// ---------------------------------------------------------------------------------------------------------

BatchSampler::BatchSampler(torch::Tensor rows, int64_t batch, std::uint64_t seed)
    : rows_(rows.to(torch::kCPU, torch::kInt64).contiguous()), seed_(seed) {
  if (rows_.numel() == 0) throw std::invalid_argument("mini-batches: no rows to draw from");
  if (batch <= 0) throw std::invalid_argument("mini-batches: batch must be positive");
  batch_ = std::min<int64_t>(batch, rows_.numel());
  batches_per_epoch_ = rows_.numel() / batch_;
}

torch::Tensor BatchSampler::indices(int64_t step) {
  const int64_t epoch = step / batches_per_epoch_, position = step % batches_per_epoch_;
  if (epoch != epoch_) {
    std::vector<int64_t> order(rows_.numel());
    std::iota(order.begin(), order.end(), 0);
    std::seed_seq seq{static_cast<std::uint32_t>(seed_), static_cast<std::uint32_t>(seed_ >> 32),
                      static_cast<std::uint32_t>(epoch), static_cast<std::uint32_t>(epoch >> 32), 0x6a7cu};
    std::mt19937_64 rng(seq);
    std::shuffle(order.begin(), order.end(), rng);
    permutation_ = rows_.index_select(0, torch::tensor(order, torch::kInt64));
    epoch_ = epoch;
  }
  return permutation_.index({Slice(position * batch_, (position + 1) * batch_)});
}

// ---------------------------------------------------------------------------------------------------------

Dataset synthetic_dataset(const SyntheticDatasetOptions& o, const projection::Settings& projection) {
  if (o.rows <= 0 || o.episodes <= 0 || o.cloud_points <= 0 || o.nearest_points < 0 ||
      o.nearest_points > o.cloud_points)
    throw std::invalid_argument("synthetic_dataset: need rows, episodes, cloud_points > 0 and "
                                "0 <= nearest_points <= cloud_points");
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double pi = 3.14159265358979323846;
  const int n = projection.coefficients(), C = o.cloud_points, N = o.nearest_points;
  const double T = projection.horizon;
  Dataset d;
  d.projection = projection;
  d.observation = torch::empty({o.rows, 6});
  d.cloud = torch::empty({o.rows, C, 2});
  d.obstacles = torch::zeros({o.rows, N, 4});
  d.expert_xi = torch::empty({o.rows, 2 * n});
  d.expert_cost = torch::zeros({o.rows});
  d.episode = torch::empty({o.rows}, torch::kInt64);
  d.time = torch::empty({o.rows});
  auto obs = d.observation.accessor<float, 2>();
  auto cloud = d.cloud.accessor<float, 3>();
  auto obstacles = d.obstacles.accessor<float, 3>();
  auto xi = d.expert_xi.accessor<float, 2>();
  auto episode = d.episode.accessor<int64_t, 1>();
  auto time = d.time.accessor<float, 1>();
  const int64_t per_episode = (o.rows + o.episodes - 1) / o.episodes;
  std::vector<std::pair<double, int>> by_distance(C);
  for (int64_t r = 0; r < o.rows; ++r) {
    episode[r] = r / per_episode;
    time[r] = static_cast<float>(0.1 * static_cast<double>(r % per_episode));
    const double bearing = 2 * pi * u(rng), range = 2.0 + 3.0 * u(rng);
    const double tx = range * std::cos(bearing), ty = range * std::sin(bearing);
    const double tvx = 0.5 * gauss(rng), tvy = 0.5 * gauss(rng);
    const double rvx = 0.5 * gauss(rng), rvy = 0.5 * gauss(rng);
    const float row[6] = {float(rvx), float(rvy), float(tx), float(ty), float(tvx), float(tvy)};
    for (int k = 0; k < 6; ++k) obs[r][k] = row[k];
    // Three round obstacles, their rims sampled.
    double cx[3], cy[3], radius[3];
    for (int b = 0; b < 3; ++b) {
      const double a = 2 * pi * u(rng), dist = 1.5 + 4.0 * u(rng);
      cx[b] = dist * std::cos(a);
      cy[b] = dist * std::sin(a);
      radius[b] = 0.3 + 0.7 * u(rng);
    }
    for (int p = 0; p < C; ++p) {
      const int b = p % 3;
      const double a = 2 * pi * u(rng);
      cloud[r][p][0] = float(cx[b] + radius[b] * std::cos(a));
      cloud[r][p][1] = float(cy[b] + radius[b] * std::sin(a));
      by_distance[p] = {std::hypot(cloud[r][p][0], cloud[r][p][1]), p};
    }
    std::partial_sort(by_distance.begin(), by_distance.begin() + N, by_distance.end());
    for (int j = 0; j < N; ++j) {
      obstacles[r][j][0] = cloud[r][by_distance[j].second][0];
      obstacles[r][j][1] = cloud[r][by_distance[j].second][1];
    }
    // The expert: a straight line to the target's predicted position, pulled back to 2 m.
    const double fx = tx + tvx * T, fy = ty + tvy * T, reach = std::hypot(fx, fy);
    const double keep = reach > 1e-9 ? std::max(0.0, 1.0 - 2.0 / reach) : 0.0;
    for (int i = 0; i < n; ++i) {
      const double s = double(i) / projection.degree;
      xi[r][i] = float(s * fx * keep);
      xi[r][n + i] = float(s * fy * keep);
    }
  }
  DatasetFile file;
  file.path = "synthetic";
  file.rows = o.rows;
  file.episodes = std::min(o.episodes, (o.rows + per_episode - 1) / per_episode);
  d.files.push_back(file);
  return d;
}

}  // namespace occtrack::learning
