#include "learning/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

#include "occtrack/io/error.hpp"

namespace occtrack::learning {

using torch::indexing::Slice;

// ---------------------------------------------------------------------------------------------------------
// loading

namespace {

[[noreturn]] void fail(const std::string& source, const std::string& what) { throw io::InputError(source + ": " + what); }

// A checked column as a CPU tensor of its own shape (copied: the file's vectors are not kept).
template <typename T>
torch::Tensor column(const std::vector<T>& values, std::vector<int64_t> shape, torch::Dtype dtype) {
  return torch::from_blob(const_cast<T*>(values.data()), shape, dtype).clone();
}

}  // namespace

Dataset load_dataset(const std::vector<std::string>& paths) {
  if (paths.empty()) throw io::InputError("no dataset file given");
  std::vector<io::DatasetFile> files;
  for (const auto& path : paths) files.push_back(io::read_dataset_file(path));
  return make_dataset(files);
}

Dataset make_dataset(const std::vector<io::DatasetFile>& files) {
  if (files.empty()) throw io::InputError("no dataset file given");
  std::vector<projection::Settings> projections;
  for (const io::DatasetFile& f : files) {
    projections.push_back(io::dataset_projection(f));
    if (f.rows == 0) fail(f.source, "the dataset has no rows");
  }
  const io::DatasetFile& first = files.front();
  const projection::Settings& p0 = projections.front();
  for (std::size_t k = 0; k < files.size(); ++k) {
    const io::DatasetFile& f = files[k];
    const projection::Settings& p = projections[k];
    if (p.degree != p0.degree || p.steps != p0.steps || p.horizon != p0.horizon || p.via_step_1 != p0.via_step_1 ||
        p.via_step_2 != p0.via_step_2)
      fail(f.source, "metadata 'projection' (degree, steps, horizon, via_steps) differs from " + first.source);
    if (f.cloud_points != first.cloud_points)
      fail(f.source, "tensor 'cloud' has " + std::to_string(f.cloud_points) + " points per row, " + first.source +
                         " has " + std::to_string(first.cloud_points));
    if (f.nearest_points != first.nearest_points)
      fail(f.source, "tensor 'obstacles' has " + std::to_string(f.nearest_points) + " points per row, " +
                         first.source + " has " + std::to_string(first.nearest_points));
  }
  Dataset d;
  d.projection = p0;
  std::vector<torch::Tensor> obs, cloud, obstacles, xi, cost, episode, time;
  int64_t episode_offset = 0;
  for (const io::DatasetFile& f : files) {
    const int64_t S = f.rows, C = f.cloud_points, N = f.nearest_points, n2 = 2 * f.coefficients;
    obs.push_back(column(f.observation, {S, io::kObservationSize}, torch::kFloat32));
    cloud.push_back(column(f.cloud, {S, C, 2}, torch::kFloat32));
    obstacles.push_back(column(f.obstacles, {S, N, 4}, torch::kFloat32));
    xi.push_back(column(f.expert_xi, {S, n2}, torch::kFloat32));
    cost.push_back(column(f.expert_cost, {S}, torch::kFloat32));
    time.push_back(column(f.time, {S}, torch::kFloat32));
    const torch::Tensor e = column(f.episode, {S}, torch::kInt32).to(torch::kInt64);
    episode.push_back(e + episode_offset);
    episode_offset += e.max().item<int64_t>() + 1;
    d.files.push_back({f.source, S, std::get<0>(torch::_unique(e)).numel(), f.metadata});
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

NormalizationStats compute_normalization(const Dataset& data, const torch::Tensor& rows, const io::NetworkConfig& config,
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
  // The statistics of what the networks see: for a target-frame model, the rows turned into its frame.
  torch::Tensor observation = data.observation.index_select(0, i).to(f64);
  torch::Tensor cloud = data.cloud.index_select(0, i).to(f64);
  torch::Tensor xi = data.expert_xi.index_select(0, i).to(f64);
  if (config.target_frame) {
    const FrameTurn turn(observation);
    cloud = turn.cloud_in(cloud);
    xi = turn.xi_in(xi);
    observation = turn.observation_in(observation);
  }
  NormalizationStats s;
  std::tie(s.observation_mean, s.observation_std) = stats(observation);
  std::tie(s.cloud_mean, s.cloud_std) = stats(cloud.reshape({-1, 2}));
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
  const io::OutputLayout l(config);
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
  DatasetSource file;
  file.path = "synthetic";
  file.rows = o.rows;
  file.episodes = std::min(o.episodes, (o.rows + per_episode - 1) / per_episode);
  d.files.push_back(file);
  return d;
}

}  // namespace occtrack::learning
