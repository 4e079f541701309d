// The learned policy at run time: model files (checks and refusals), the folded Eigen inference against a naive
// per-sample reference, and the planner built on it (finite commands, batch sizes, determinism).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "occtrack/io/safetensors.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/learned.hpp"
#include "occtrack/policy/model.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/world.hpp"
#include "test_helpers.hpp"

using namespace occtrack;
using nlohmann::json;

namespace {

projection::Settings default_projection() {
  projection::Settings s;
  s.iterations = 50;
  return s;
}

// The default sizes of docs/learning.md.
policy::NetworkConfig default_network() { return policy::NetworkConfig::for_projection(default_projection()); }

// A small network with sizes that differ from each other, so that a transposed index cannot pass.
projection::Settings small_projection() {
  projection::Settings s;
  s.degree = 5;
  s.steps = 12;
  s.via_step_1 = 5;
  s.via_step_2 = 8;
  s.obstacles = 7;
  return s;
}

policy::NetworkConfig small_network() {
  policy::NetworkConfig c = policy::NetworkConfig::for_projection(small_projection());
  c.cloud_points = 13;
  c.latent = 3;
  c.pointnet_widths = {8, 16, 24};
  c.pointnet_hidden = 12;
  c.features = 5;
  c.hidden = 10;
  c.layers = 2;
  return c;
}

// Random normalisation statistics and output scales (random_model keeps them simple), so that folding them
// into the layers is exercised.
void randomise_normalisation(io::TensorFile& file, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), positive(0.3, 2.5);
  for (const char* name : {"norm.observation", "norm.cloud", "norm.xi"}) {
    const std::int64_t size = file.at(std::string(name) + ".mean").numel();
    std::vector<float> mean(size), std(size);
    for (auto& x : mean) x = static_cast<float>(u(rng));
    for (auto& x : std) x = static_cast<float>(positive(rng));
    file.put(std::string(name) + ".mean", {size}, mean);
    file.put(std::string(name) + ".std", {size}, std);
  }
  const std::int64_t Y = file.at("norm.output.scale").numel();
  std::vector<float> offset(Y), scale(Y);
  for (auto& x : offset) x = static_cast<float>(u(rng));
  for (auto& x : scale) x = static_cast<float>(positive(rng));
  file.put("norm.output.offset", {Y}, offset);
  file.put("norm.output.scale", {Y}, scale);
}

// docs/learning.md's networks written the plain way: one point and one sample at a time, batch norm applied
// as stored, in double.
class NaiveNetworks {
 public:
  NaiveNetworks(const io::TensorFile& file, const policy::NetworkConfig& network) : file_(file), c_(network) {}

  Eigen::VectorXd features(const Eigen::MatrixX2d& cloud) const {
    const auto mean = get("norm.cloud.mean"), std = get("norm.cloud.std");
    Eigen::VectorXd pooled = Eigen::VectorXd::Constant(c_.pointnet_widths.back(), -INFINITY);
    for (Eigen::Index p = 0; p < cloud.rows(); ++p) {
      Eigen::VectorXd x(2);
      for (int i = 0; i < 2; ++i) x(i) = (cloud(p, i) - mean(i)) / std(i);
      for (std::size_t l = 0; l < c_.pointnet_widths.size(); ++l)
        x = relu(batch_norm("pointnet.bn" + std::to_string(l), linear("pointnet.conv" + std::to_string(l), x)));
      pooled = pooled.cwiseMax(x);
    }
    const Eigen::VectorXd h = relu(batch_norm("pointnet.fc_bn0", linear("pointnet.fc0", pooled)));
    return linear("pointnet.fc1", h);
  }

  Eigen::VectorXd decode(const Eigen::VectorXd& z, const Eigen::VectorXd& observation,
                         const Eigen::VectorXd& features) const {
    Eigen::VectorXd x(z.size() + observation.size() + features.size());
    x << z, normalise("norm.observation", observation), features;
    for (int l = 0; l < c_.layers; ++l)
      x = relu(batch_norm("decoder.bn" + std::to_string(l), linear("decoder.fc" + std::to_string(l), x)));
    const Eigen::VectorXd raw = linear("decoder.out", x);
    return raw.cwiseProduct(get("norm.output.scale")) + get("norm.output.offset");
  }

  void encode(const Eigen::VectorXd& observation, const Eigen::VectorXd& features, const Eigen::VectorXd& xi,
              Eigen::VectorXd& mu, Eigen::VectorXd& sigma) const {
    Eigen::VectorXd x(observation.size() + features.size() + xi.size());
    x << normalise("norm.observation", observation), features, normalise("norm.xi", xi);
    for (int l = 0; l < c_.layers; ++l)
      x = relu(batch_norm("encoder.bn" + std::to_string(l), linear("encoder.fc" + std::to_string(l), x)));
    mu = linear("encoder.mean", x);
    sigma = linear("encoder.std", x).unaryExpr([](double v) { return std::log1p(std::exp(v)) + 1e-4; });
  }

 private:
  Eigen::VectorXd get(const std::string& name) const {
    const std::vector<double> v = file_.at(name).as_double();
    return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  }
  Eigen::VectorXd linear(const std::string& prefix, const Eigen::VectorXd& x) const {
    const io::Tensor& w = file_.at(prefix + ".weight");
    const std::vector<double> values = w.as_double();
    const Eigen::VectorXd b = get(prefix + ".bias");
    Eigen::VectorXd y(w.shape[0]);
    for (std::int64_t o = 0; o < w.shape[0]; ++o) {
      double sum = b(o);
      for (std::int64_t i = 0; i < w.shape[1]; ++i) sum += values[o * w.shape[1] + i] * x(i);
      y(o) = sum;
    }
    return y;
  }
  Eigen::VectorXd batch_norm(const std::string& prefix, const Eigen::VectorXd& x) const {
    const Eigen::VectorXd g = get(prefix + ".weight"), b = get(prefix + ".bias"), m = get(prefix + ".running_mean"),
                          v = get(prefix + ".running_var");
    Eigen::VectorXd y(x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) y(i) = (x(i) - m(i)) / std::sqrt(v(i) + c_.batch_norm_eps) * g(i) + b(i);
    return y;
  }
  Eigen::VectorXd normalise(const std::string& prefix, const Eigen::VectorXd& x) const {
    return (x - get(prefix + ".mean")).cwiseQuotient(get(prefix + ".std"));
  }
  static Eigen::VectorXd relu(const Eigen::VectorXd& x) { return x.cwiseMax(0.0); }

  const io::TensorFile& file_;
  policy::NetworkConfig c_;
};

policy::Cloud random_cloud(int points, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-8.0f, 8.0f);
  policy::Cloud cloud(points, 2);
  for (int i = 0; i < points; ++i) cloud.row(i) << u(rng), u(rng);
  return cloud;
}

policy::Rows random_rows(int rows, int cols, std::uint64_t seed, float spread = 1.0f) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> normal(0.0f, spread);
  policy::Rows z(rows, cols);
  for (int b = 0; b < rows; ++b)
    for (int j = 0; j < cols; ++j) z(b, j) = normal(rng);
  return z;
}

// Folded float inference against the naive double reference, on one file.
void expect_matches_naive(const io::TensorFile& file, int points, int batch) {
  policy::Model model(file);
  const policy::NetworkConfig& c = model.network();
  const NaiveNetworks naive(file, c);
  const policy::Cloud cloud = random_cloud(points, 11);
  Eigen::VectorXf features(c.features);
  model.features(cloud, features);
  const Eigen::VectorXd expected_features = naive.features(cloud.cast<double>());
  EXPECT_LT(test::worst_error(features, expected_features), 2e-4) << "features\n" << features.transpose();

  Eigen::VectorXf observation(c.observation);
  observation << 0.4f, -0.3f, 2.5f, 1.0f, -0.6f, 0.2f;
  const policy::Rows z = random_rows(batch, c.latent, 12);
  policy::Rows out(batch, c.outputs);
  model.decode(z, observation, features, out);
  Eigen::MatrixXd expected(batch, c.outputs);
  for (int b = 0; b < batch; ++b)
    expected.row(b) = naive.decode(z.row(b).transpose().cast<double>(), observation.cast<double>(),
                                   features.cast<double>()).transpose();
  EXPECT_LT(test::worst_error(out, expected), 2e-4);

  const int n2 = 2 * c.coefficients;
  const policy::Rows xi = random_rows(batch, n2, 13, 2.0f);
  policy::Rows mu(batch, c.latent), sigma(batch, c.latent);
  model.encode(observation, features, xi, mu, sigma);
  Eigen::MatrixXd expected_mu(batch, c.latent), expected_sigma(batch, c.latent);
  for (int b = 0; b < batch; ++b) {
    Eigen::VectorXd m, s;
    naive.encode(observation.cast<double>(), features.cast<double>(), xi.row(b).transpose().cast<double>(), m, s);
    expected_mu.row(b) = m.transpose();
    expected_sigma.row(b) = s.transpose();
  }
  EXPECT_LT(test::worst_error(mu, expected_mu), 2e-4);
  EXPECT_LT(test::worst_error(sigma, expected_sigma), 2e-4);
}

// The message of the io::InputError that `f` throws ("" when it throws none).
template <typename F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const io::InputError& e) {
    return e.what();
  }
  return "";
}

io::TensorFile default_file(const std::string& variant = "cvae") {
  io::TensorFile f = policy::random_model(default_network(), default_projection(), variant, 5);
  f.source = "model.safetensors";
  return f;
}

void set_network_field(io::TensorFile& f, const std::string& key, const json& value) {
  json network = json::parse(f.metadata.at("network"));
  network[key] = value;
  f.metadata["network"] = network.dump();
}

std::vector<float> zeros(std::int64_t n) { return std::vector<float>(static_cast<std::size_t>(n), 0.0f); }

// --- planner helpers

planners::LearnedPolicySettings policy_settings(policy::Variant variant, int batch) {
  planners::LearnedPolicySettings s;
  s.variant = variant;
  s.batch = batch;
  return s;
}

planners::LearnedPolicy random_policy(policy::Variant variant, int batch, std::uint64_t seed = 1) {
  auto s = policy_settings(variant, batch);
  s.seed = seed;
  return planners::LearnedPolicy(s, policy::Model(policy::random_model(default_network(), default_projection(),
                                                                        policy::to_string(variant), 5)));
}

// Scans of a generated forest along a short straight drive, with the target ahead.
struct Drive {
  std::vector<core::Scan> scans;
  std::vector<planners::PlannerInput> inputs;
};

Drive forest_drive(int frames) {
  const core::Scenario scenario =
      io::read_scenario(OCCTRACK_TEST_DATA_DIR "/../../scenarios/static-1ms/forest-a-1.yaml");
  sim::World world(scenario);
  std::mt19937_64 rng(1);
  Drive d;
  d.scans.resize(frames);
  d.inputs.resize(frames);
  for (int k = 0; k < frames; ++k) {
    const double t = 0.05 * k;
    const Eigen::Vector2d target = world.target_position(t);
    const Eigen::Vector2d robot = scenario.robot_position + (target - scenario.robot_position) * 0.02 * k;
    world.scan(robot, t, rng, d.scans[k]);
    d.scans[k].time = t;
    auto& in = d.inputs[k];
    in.time = t;
    in.robot_position = robot;
    in.robot_velocity = {0.5, 0.1};
    in.target_position = target;
    in.target_velocity = world.target_velocity(t);
    in.scan = &d.scans[k];
  }
  return d;
}

void expect_usable(const planners::PlannerOutput& out, const std::string& what) {
  EXPECT_TRUE(out.command_velocity.allFinite()) << what;
  if (out.ok) {
    EXPECT_FALSE(out.plan.empty()) << what;
    for (const auto& p : out.plan) ASSERT_TRUE(p.allFinite()) << what;
  } else {
    EXPECT_EQ(out.command_velocity, Eigen::Vector2d::Zero()) << what;
    EXPECT_FALSE(out.message.empty()) << what;
  }
}

}  // namespace

// ------------------------------------------------------------------------------------------------------------
// Model files.

TEST(PolicyModel, RandomModelRoundTripsThroughSafetensorsBytes) {
  const io::TensorFile file = default_file();
  const io::TensorFile back = io::parse_safetensors(io::serialize_safetensors(file), "model.safetensors");
  EXPECT_EQ(back.metadata, file.metadata);
  ASSERT_EQ(back.tensors.size(), file.tensors.size());
  for (const auto& [name, t] : file.tensors) {
    EXPECT_EQ(back.at(name).shape, t.shape) << name;
    EXPECT_EQ(back.at(name).bytes, t.bytes) << name;
  }
  policy::Model a(file), b(back);
  EXPECT_EQ(b.network(), default_network());
  EXPECT_EQ(b.variant(), policy::Variant::cvae);
  EXPECT_EQ(b.projection().horizon, default_projection().horizon);
  ASSERT_TRUE(b.band().has_value());
  EXPECT_EQ(b.band()->min, 1.0);
  const policy::Cloud cloud = random_cloud(200, 3);
  Eigen::VectorXf fa(64), fb(64);
  a.features(cloud, fa);
  b.features(cloud, fb);
  EXPECT_EQ(fa, fb);
  Eigen::VectorXf observation = Eigen::VectorXf::LinSpaced(6, -1.0f, 1.0f);
  const policy::Rows z = random_rows(30, 2, 4);
  policy::Rows ya(30, 252), yb(30, 252);
  a.decode(z, observation, fa, ya);
  b.decode(z, observation, fb, yb);
  EXPECT_EQ(ya, yb);
  EXPECT_TRUE(ya.allFinite());

  // Same seed, same weights; another seed, other weights.
  EXPECT_EQ(policy::random_model(default_network(), default_projection(), "cvae", 5).tensors.at("decoder.out.weight").bytes,
            file.tensors.at("decoder.out.weight").bytes);
  EXPECT_NE(policy::random_model(default_network(), default_projection(), "cvae", 6).tensors.at("decoder.out.weight").bytes,
            file.tensors.at("decoder.out.weight").bytes);
}

TEST(PolicyModel, NetworkConfigJsonRoundTripsAndValidates) {
  const policy::NetworkConfig c = small_network();
  EXPECT_EQ(policy::NetworkConfig::parse(c.to_json(), "x"), c);
  std::string error;
  EXPECT_TRUE(default_network().validate(&error)) << error;
  EXPECT_EQ(default_network().outputs, 252);
  policy::NetworkConfig bad = default_network();
  bad.outputs = 250;
  EXPECT_FALSE(bad.validate(&error));
  EXPECT_NE(error.find("outputs (250)"), std::string::npos) << error;
  EXPECT_NE(error.find("252"), std::string::npos) << error;
  const policy::OutputLayout y(default_network());
  EXPECT_EQ(y.lambda0, 8);
  EXPECT_EQ(y.distance_min, 30);
  EXPECT_EQ(y.distance_max, 130);
  EXPECT_EQ(y.xi_bar, 230);
  EXPECT_EQ(y.size, 252);
  // The projection metadata reads back as written (obstacles = the network's nearest points).
  const projection::Settings p = small_projection();
  EXPECT_EQ(io::validate_model_file(policy::random_model(small_network(), p, "cvae", 1)).projection, p);
}

TEST(PolicyModel, FoldedInferenceMatchesANaivePerSampleLoop) {
  io::TensorFile file = policy::random_model(small_network(), small_projection(), "cvae", 21);
  randomise_normalisation(file, 22);
  expect_matches_naive(file, 13, 4);
  expect_matches_naive(file, 1, 1);
  expect_matches_naive(file, 40, 33);  // more points and samples than reserved: the workspaces grow
}

TEST(PolicyModel, FoldedInferenceMatchesTheNaiveLoopAtTheDefaultSizes) {
  io::TensorFile file = default_file();
  randomise_normalisation(file, 23);
  expect_matches_naive(file, 200, 30);
  expect_matches_naive(file, 37, 5);
}

// A target-frame model sees the same inputs whichever way the scene is turned about the robot, so its outputs
// turn with the scene: positions, velocities and coefficient pairs turn, the distance bounds do not.
TEST(PolicyModel, ATargetFrameModelTurnsWithTheScene) {
  policy::NetworkConfig config = small_network();
  config.target_frame = true;
  io::TensorFile file = policy::random_model(config, small_projection(), "cvae", 31);
  randomise_normalisation(file, 32);
  policy::Model model{file};
  policy::FrameRotation turn(model.network());
  ASSERT_TRUE(turn.turns());
  std::mt19937_64 rng(33);
  std::normal_distribution<float> normal(0.0f, 2.0f);
  const int B = 5, C = 17;
  Eigen::VectorXf observation(6);
  for (int i = 0; i < 6; ++i) observation(i) = normal(rng);
  policy::Cloud cloud(C, 2);
  for (int i = 0; i < C; ++i) cloud.row(i) << normal(rng), normal(rng);
  policy::Rows z(B, config.latent);
  for (int b = 0; b < B; ++b)
    for (int j = 0; j < config.latent; ++j) z(b, j) = normal(rng);
  auto outputs = [&](Eigen::VectorXf o, policy::Cloud c) {
    turn.aim(o(2), o(3));
    turn.into_network(o, c);
    Eigen::VectorXf features(config.features);
    model.features(c, features);
    policy::Rows y(B, config.outputs);
    model.decode(z, o, features, y);
    turn.out_of_network(y);
    return y;
  };
  const policy::Rows straight = outputs(observation, cloud);
  const float angle = 2.3f, c = std::cos(angle), s = std::sin(angle);
  auto turned = [&](float x, float y) { return Eigen::Vector2f(c * x - s * y, s * x + c * y); };
  Eigen::VectorXf turned_observation(6);
  for (int k = 0; k < 3; ++k) turned_observation.segment<2>(2 * k) = turned(observation(2 * k), observation(2 * k + 1));
  policy::Cloud turned_cloud(C, 2);
  for (int i = 0; i < C; ++i) turned_cloud.row(i) = turned(cloud(i, 0), cloud(i, 1)).transpose();
  const policy::Rows after = outputs(turned_observation, turned_cloud);

  policy::Rows expected = straight;
  const auto pairs = model.layout().turning_pairs();
  ASSERT_EQ(pairs.size(), std::size_t(4 + 2 * config.coefficients));
  for (int b = 0; b < B; ++b)
    for (const auto& [ix, iy] : pairs) {
      const Eigen::Vector2f v = turned(straight(b, ix), straight(b, iy));
      expected(b, ix) = v.x();
      expected(b, iy) = v.y();
    }
  const double scale = 1.0 + straight.cwiseAbs().maxCoeff();
  EXPECT_LT((after - expected).cwiseAbs().maxCoeff() / scale, 1e-4);
  // Not by accident: the outputs do change with the turn.
  EXPECT_GT((after - straight).cwiseAbs().maxCoeff() / scale, 1e-2);

  // A robot-frame model's turn is the identity.
  policy::FrameRotation none(small_network());
  none.aim(1.0, 2.0);
  EXPECT_FALSE(none.turns());
  Eigen::VectorXf o = observation;
  policy::Cloud cl = cloud;
  none.into_network(o, cl);
  EXPECT_EQ(o, observation);
  EXPECT_EQ(cl, cloud);
}

TEST(PolicyModel, HandCheckedOneUnitNetwork) {
  // Every width 1, identity-like weights: the result can be followed by hand.
  projection::Settings p = small_projection();
  policy::NetworkConfig c = policy::NetworkConfig::for_projection(p);
  c.cloud_points = 3;
  c.latent = 1;
  c.pointnet_widths = {1};
  c.pointnet_hidden = 1;
  c.features = 1;
  c.hidden = 1;
  c.layers = 1;
  io::TensorFile f = policy::random_model(c, p, "cvae", 1);
  const double eps = c.batch_norm_eps;
  auto one = [](float v) { return std::vector<float>{v}; };
  auto identity_bn = [&](const std::string& name, float var) {
    f.put(name + ".weight", {1}, one(1.0f));
    f.put(name + ".bias", {1}, one(0.0f));
    f.put(name + ".running_mean", {1}, one(0.0f));
    f.put(name + ".running_var", {1}, one(var));
  };
  f.put("norm.cloud.mean", {2}, std::vector<float>{1.0f, 0.0f});
  f.put("norm.cloud.std", {2}, std::vector<float>{2.0f, 1.0f});
  // conv0: x_n + 0 y_n, batch norm with variance 4 - eps: divides by 2.
  f.put("pointnet.conv0.weight", {1, 2}, std::vector<float>{1.0f, 0.0f});
  f.put("pointnet.conv0.bias", {1}, one(0.0f));
  identity_bn("pointnet.bn0", static_cast<float>(4.0 - eps));
  f.put("pointnet.fc0.weight", {1, 1}, one(3.0f));
  f.put("pointnet.fc0.bias", {1}, one(1.0f));
  identity_bn("pointnet.fc_bn0", static_cast<float>(1.0 - eps));
  f.put("pointnet.fc1.weight", {1, 1}, one(0.5f));
  f.put("pointnet.fc1.bias", {1}, one(-1.0f));
  policy::Model model(f);
  policy::Cloud cloud(3, 2);
  cloud << 5.0f, 7.0f,  //  x_n = 2    -> 1
      9.0f, -3.0f,      //  x_n = 4    -> 2 (the max)
      -3.0f, 0.0f;      //  x_n = -2   -> relu 0
  Eigen::VectorXf features(1);
  model.features(cloud, features);
  // pooled 2; fc0: 3 * 2 + 1 = 7; relu 7; fc1: 0.5 * 7 - 1 = 2.5
  EXPECT_NEAR(features(0), 2.5f, 1e-5f);

  // Post-processing: terminal velocities clamped per axis, d_min floored.
  const policy::OutputLayout y = model.layout();
  policy::Rows out = policy::Rows::Zero(1, y.size);
  out(0, y.terminal + 2) = 5.0f;
  out(0, y.terminal + 3) = -7.0f;
  out(0, y.terminal + 0) = 9.0f;  // positions are not clamped
  out(0, y.distance_min) = 0.2f;
  out(0, y.distance_min + 1) = 1.7f;
  out(0, y.distance_max) = 0.1f;  // nor is d_max
  model.postprocess(out, 2.0, 1.0);
  EXPECT_EQ(out(0, y.terminal + 2), 2.0f);
  EXPECT_EQ(out(0, y.terminal + 3), -2.0f);
  EXPECT_EQ(out(0, y.terminal + 0), 9.0f);
  EXPECT_EQ(out(0, y.distance_min), 1.0f);
  EXPECT_EQ(out(0, y.distance_min + 1), 1.7f);
  EXPECT_EQ(out(0, y.distance_min + 2), 1.0f);
  EXPECT_EQ(out(0, y.distance_max), 0.1f);
}

TEST(PolicyModel, DuplicatePointsDoNotChangeTheFeatures) {
  policy::Model model(default_file());
  policy::Cloud distinct = random_cloud(50, 8);
  policy::Cloud padded(200, 2);
  padded.topRows(50) = distinct;
  for (int i = 50; i < 200; ++i) padded.row(i) = distinct.row(0);  // perception's padding
  Eigen::VectorXf a(64), b(64);
  model.features(distinct, a);
  model.features(padded, b);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-5f * std::max(1.0f, a.cwiseAbs().maxCoeff()));
}

TEST(PolicyModel, RefusesAWrongFormatTag) {
  io::TensorFile f = default_file();
  f.metadata["format"] = "occtrack.dataset.v1";
  const std::string m = refusal([&] { policy::Model model(f); });
  EXPECT_NE(m.find("model.safetensors"), std::string::npos) << m;
  EXPECT_NE(m.find("format is 'occtrack.dataset.v1', expected 'occtrack.model.v1'"), std::string::npos) << m;
  f.metadata.erase("format");
  EXPECT_NE(refusal([&] { policy::Model model(f); }).find("metadata 'format' is missing"), std::string::npos);
}

TEST(PolicyModel, RefusesAnUnknownVariant) {
  io::TensorFile f = default_file();
  f.metadata["variant"] = "gan";
  const std::string m = refusal([&] { policy::Model model(f); });
  EXPECT_NE(m.find("variant is 'gan', expected one of cvae, bc, fixed-q"), std::string::npos) << m;
}

TEST(PolicyModel, RefusesAMissingTensor) {
  io::TensorFile f = default_file();
  f.tensors.erase("pointnet.bn2.running_var");
  const std::string m = refusal([&] { policy::Model model(f); });
  EXPECT_NE(m.find("model.safetensors: tensor 'pointnet.bn2.running_var' is missing"), std::string::npos) << m;
}

TEST(PolicyModel, RefusesAWrongShapeNamingTheTensorAndTheMetadataField) {
  io::TensorFile f = default_file();
  f.put("decoder.out.weight", {252, 128}, zeros(252 * 128));
  const std::string m = refusal([&] { policy::Model model(f); });
  EXPECT_NE(m.find("tensor 'decoder.out.weight' has shape [252, 128], expected [252, 256]"), std::string::npos) << m;
  EXPECT_NE(m.find("metadata network.hidden is 256, the tensors say 128"), std::string::npos) << m;

  io::TensorFile g = default_file();
  g.put("norm.cloud.std", {3}, std::vector<float>{1, 1, 1});
  const std::string m2 = refusal([&] { policy::Model model(g); });
  EXPECT_NE(m2.find("tensor 'norm.cloud.std' has shape [3], expected [2]"), std::string::npos) << m2;

  io::TensorFile h = default_file();
  h.put("pointnet.conv1.weight", {64}, zeros(64));  // wrong rank
  const std::string m3 = refusal([&] { policy::Model model(h); });
  EXPECT_NE(m3.find("tensor 'pointnet.conv1.weight' has shape [64], expected [64, 64]"), std::string::npos) << m3;
}

TEST(PolicyModel, RefusesMetadataThatDisagreesWithTheTensors) {
  io::TensorFile f = default_file();
  set_network_field(f, "features", 32);
  const std::string m = refusal([&] { policy::Model model(f); });
  EXPECT_NE(m.find("model.safetensors: metadata network.features is 32, the tensors say 64"), std::string::npos) << m;

  io::TensorFile g = default_file();
  set_network_field(g, "pointnet_widths", json::array({64, 64, 64, 128, 512}));
  const std::string m2 = refusal([&] { policy::Model model(g); });
  EXPECT_NE(m2.find("metadata network.pointnet_widths[4] is 512, the tensors say 256"), std::string::npos) << m2;

  io::TensorFile h = default_file();
  set_network_field(h, "outputs", 250);
  const std::string m3 = refusal([&] { policy::Model model(h); });
  EXPECT_NE(m3.find("network.outputs"), std::string::npos) << m3;

  io::TensorFile k = default_file();
  json network = json::parse(k.metadata.at("network"));
  network.erase("hidden");
  k.metadata["network"] = network.dump();
  const std::string m4 = refusal([&] { policy::Model model(k); });
  EXPECT_NE(m4.find("network.hidden: missing required key"), std::string::npos) << m4;

  io::TensorFile q = default_file();
  q.metadata["network"] = "{not json";
  EXPECT_NE(refusal([&] { policy::Model model(q); }).find("metadata network is not valid JSON"), std::string::npos);
}

TEST(PolicyModel, RefusesNonFiniteWeightsAndNonPositiveStatistics) {
  io::TensorFile f = default_file();
  std::vector<float> w = f.at("decoder.fc1.weight").as_float();
  w[17] = std::numeric_limits<float>::quiet_NaN();
  f.put("decoder.fc1.weight", {256, 256}, w);
  const std::string m = refusal([&] { policy::Model model(f); });
  EXPECT_NE(m.find("tensor 'decoder.fc1.weight' holds a non-finite value"), std::string::npos) << m;

  io::TensorFile g = default_file();
  g.put("norm.observation.std", {6}, std::vector<float>{1, 1, 0, 1, 1, 1});
  const std::string m2 = refusal([&] { policy::Model model(g); });
  EXPECT_NE(m2.find("tensor 'norm.observation.std' must be positive"), std::string::npos) << m2;

  io::TensorFile h = default_file();
  std::vector<float> var = h.at("decoder.bn0.running_var").as_float();
  var[3] = -1.0f;
  h.put("decoder.bn0.running_var", {256}, var);
  EXPECT_NE(refusal([&] { policy::Model model(h); }).find("'decoder.bn0.running_var' holds a negative variance"),
            std::string::npos);
}

TEST(PolicyModel, RefusesProjectionSettingsThatDisagree) {
  const io::TensorFile f = default_file();
  const policy::Model model(f);
  EXPECT_NO_THROW(model.check_projection(default_projection()));
  projection::Settings more_iterations = default_projection();
  more_iterations.iterations = 200;
  more_iterations.batch = 5;
  EXPECT_NO_THROW(model.check_projection(more_iterations));  // may differ from training's

  struct Case {
    const char* field;
    void (*change)(projection::Settings&);
  };
  const Case cases[] = {
      {"projection.degree is 10 in the model, the planner uses 9", [](projection::Settings& s) { s.degree = 9; }},
      {"projection.steps is 100", [](projection::Settings& s) { s.steps = 80; }},
      {"projection.horizon is 5 in the model, the planner uses 4", [](projection::Settings& s) { s.horizon = 4; }},
      {"projection.obstacle_radius", [](projection::Settings& s) { s.obstacle_radius = 0.5; }},
      {"projection.speed_max", [](projection::Settings& s) { s.speed_max = 3; }},
      {"projection.speed_min", [](projection::Settings& s) { s.speed_min = 0; }},
      {"projection.accel_max", [](projection::Settings& s) { s.accel_max = 1; }},
      {"projection.via_steps[0]", [](projection::Settings& s) { s.via_step_1 = 40; }},
      {"projection.via_steps[1]", [](projection::Settings& s) { s.via_step_2 = 80; }},
      {"network.nearest_points is 60 in the model, the planner uses 40", [](projection::Settings& s) { s.obstacles = 40; }},
      {"projection.rho.tracking", [](projection::Settings& s) { s.rho.tracking = 2; }},
  };
  for (const Case& c : cases) {
    projection::Settings s = default_projection();
    c.change(s);
    const std::string m = refusal([&] { model.check_projection(s); });
    EXPECT_NE(m.find(std::string("model.safetensors: ") + c.field), std::string::npos) << c.field << ": " << m;
  }

  // The planner refuses such a model when it is built.
  auto settings = policy_settings(policy::Variant::cvae, 30);
  settings.projection.horizon = 4;
  const std::string m = refusal([&] { planners::LearnedPolicy p(settings, policy::Model(f)); });
  EXPECT_NE(m.find("projection.horizon is 5 in the model, the planner uses 4"), std::string::npos) << m;

  // So does a projection block that the metadata lacks a field of.
  io::TensorFile g = default_file();
  json p = json::parse(g.metadata.at("projection"));
  p.erase("horizon");
  g.metadata["projection"] = p.dump();
  EXPECT_NE(refusal([&] { policy::Model model2(g); }).find("projection.horizon: missing required key"),
            std::string::npos);
}

TEST(PolicyModel, RefusesAModelOfAnotherVariantOrBand) {
  const std::string m = refusal([&] {
    planners::LearnedPolicy p(policy_settings(policy::Variant::cvae, 30), policy::Model(default_file("bc")));
  });
  EXPECT_NE(m.find("model.safetensors: variant is 'bc' but planner cvae needs 'cvae'"), std::string::npos) << m;
  const std::string m2 = refusal([&] {
    planners::LearnedPolicy p(policy_settings(policy::Variant::fixed_q, 30), policy::Model(default_file("cvae")));
  });
  EXPECT_NE(m2.find("variant is 'cvae' but planner cvae-fixed-q needs 'fixed-q'"), std::string::npos) << m2;

  io::TensorFile f = default_file();
  f.metadata["band"] = R"({"min": 1.5, "reference": 2.0, "max": 3.0})";
  const std::string m3 =
      refusal([&] { planners::LearnedPolicy p(policy_settings(policy::Variant::cvae, 30), policy::Model(f)); });
  EXPECT_NE(m3.find("band.min is 1.5"), std::string::npos) << m3;
}

TEST(PolicyModel, LoadsFromAFileAndExplainsAMissingOne) {
  const std::string path = test::temp_path("policy.safetensors");
  io::write_safetensors(path, policy::random_model(default_network(), default_projection(), "bc", 2));
  const policy::Model model = policy::Model::load(path);
  EXPECT_EQ(model.variant(), policy::Variant::bc);
  EXPECT_EQ(model.source(), path);

  planners::PlannerOptions options;
  options.model = path;
  options.batch = 5;
  auto planner = planners::make_planner("bc", options);
  EXPECT_EQ(planner->name(), "bc");
  const std::string wrong = refusal([&] { planners::make_planner("cvae", options); });
  EXPECT_NE(wrong.find("variant is 'bc' but planner cvae needs 'cvae'"), std::string::npos) << wrong;
  std::filesystem::remove(path);

  const std::string missing = refusal([&] { planners::make_planner("cvae", options); });
  EXPECT_NE(missing.find("no model file at " + path), std::string::npos) << missing;
  EXPECT_NE(missing.find("Train one"), std::string::npos) << missing;
  EXPECT_NE(missing.find("--model"), std::string::npos) << missing;

  const auto names = planners::planner_names();
  for (const char* name : {"cvae", "bc", "cvae-fixed-q", "projcem", "follower"})
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  EXPECT_TRUE(planners::default_model_path(policy::Variant::fixed_q).ends_with("models/fixed-q.safetensors"))
      << planners::default_model_path(policy::Variant::fixed_q);
}

namespace {

/// Writes a random cvae model (seed) to path and returns options that build it by name at B = 5.
planners::PlannerOptions random_cvae_options(const std::string& path, std::uint64_t seed) {
  io::write_safetensors(path, policy::random_model(default_network(), default_projection(), "cvae", seed));
  planners::PlannerOptions options;
  options.model = path;
  options.batch = 5;
  return options;
}

}  // namespace

TEST(PolicyModel, TheFactoryRunsTheProjectionForTheIterationsAsked) {
  // PlannerOptions::iterations (the command line's --iterations) reaches the projection: a cvae built by name
  // with K = 20 plans exactly as one built with LearnedPolicySettings' projection at 20, and unlike the
  // default of 50.
  const std::string path = test::temp_path("iterations.safetensors");
  planners::PlannerOptions options = random_cvae_options(path, 3);
  auto by_default = planners::make_planner("cvae", options);
  options.iterations = 20;
  auto by_name = planners::make_planner("cvae", options);
  auto settings = policy_settings(policy::Variant::cvae, 5);
  settings.projection.iterations = 20;
  settings.ranking.tracking_weight = planners::learned_tracking_weight(policy::Variant::cvae);  // as by name
  planners::LearnedPolicy direct(settings, policy::Model::load(path));
  std::filesystem::remove(path);

  const Drive drive = forest_drive(3);
  bool differs_from_default = false;
  for (const auto& in : drive.inputs) {
    const planners::PlannerOutput a = by_name->plan(in);
    const planners::PlannerOutput b = direct.plan(in);
    const planners::PlannerOutput c = by_default->plan(in);
    ASSERT_TRUE(a.ok && b.ok && c.ok) << a.message << b.message << c.message;
    ASSERT_EQ(a.plan.size(), b.plan.size());
    for (std::size_t k = 0; k < a.plan.size(); ++k) EXPECT_EQ(a.plan[k], b.plan[k]) << "step " << k;
    for (std::size_t k = 0; k < std::min(a.plan.size(), c.plan.size()); ++k)
      differs_from_default = differs_from_default || (a.plan[k] - c.plan[k]).norm() > 1e-9;
  }
  EXPECT_TRUE(differs_from_default) << "K = 20 and K = 50 gave the same plans";
}

TEST(PolicyModel, TheFactoryRanksWithTheVariantsTrackingWeight) {
  // make_planner gives cvae and bc the tracking weight chosen in closed loop (5), fixed-q and the other
  // planners the ranking's 1, and PlannerOptions::tracking_weight (--tracking-weight) replaces either.
  planners::PlannerOptions options;
  EXPECT_EQ(planners::tracking_weight_for("cvae", options), 5.0);
  EXPECT_EQ(planners::tracking_weight_for("bc", options), 5.0);
  EXPECT_EQ(planners::tracking_weight_for("cvae-fixed-q", options), 1.0);
  EXPECT_EQ(planners::tracking_weight_for("projcem", options), planners::RankingSettings{}.tracking_weight);
  EXPECT_EQ(planners::tracking_weight_for("follower", options), planners::RankingSettings{}.tracking_weight);
  options.tracking_weight = 2.5;
  for (const char* name : {"cvae", "bc", "cvae-fixed-q", "projcem", "follower"})
    EXPECT_EQ(planners::tracking_weight_for(name, options), 2.5) << name;

  // The weight reaches the ranking: a cvae built by name plans and costs exactly as one built from settings
  // weighted 5, and its costs are not those of the ranking's default weight.
  const std::string path = test::temp_path("tracking-weight.safetensors");
  auto by_name = planners::make_planner("cvae", random_cvae_options(path, 4));
  auto settings = policy_settings(policy::Variant::cvae, 5);
  settings.ranking.tracking_weight = planners::learned_tracking_weight(policy::Variant::cvae);
  planners::LearnedPolicy weighted(settings, policy::Model::load(path));
  settings.ranking.tracking_weight = planners::RankingSettings{}.tracking_weight;
  planners::LearnedPolicy unweighted(settings, policy::Model::load(path));
  std::filesystem::remove(path);

  bool cost_differs = false;
  for (const auto& in : forest_drive(3).inputs) {
    const planners::PlannerOutput a = by_name->plan(in);
    const planners::PlannerOutput b = weighted.plan(in);
    const planners::PlannerOutput c = unweighted.plan(in);
    ASSERT_TRUE(a.ok && b.ok && c.ok) << a.message << b.message << c.message;
    ASSERT_EQ(a.plan.size(), b.plan.size());
    for (std::size_t k = 0; k < a.plan.size(); ++k) EXPECT_EQ(a.plan[k], b.plan[k]) << "step " << k;
    EXPECT_EQ(by_name->last_record().terms.total, weighted.last_record().terms.total);
    cost_differs = cost_differs || by_name->last_record().terms.total != unweighted.last_record().terms.total;
  }
  EXPECT_TRUE(cost_differs) << "weights 5 and 1 ranked every cycle at the same cost";
}

TEST(PolicyModel, TheFactoryGivesTheCvaeItsMovingReachBehindTheLayerOnly) {
  // Unset, the moving reach is the planner's default: 1 s for the cvae at B >= 30 behind the safety layer
  // (which says which points moved), 0 for every other planner, batch, or without the layer; a set value,
  // 0 included, replaces the default everywhere.
  planners::PlannerOptions options;
  options.shield = true;
  EXPECT_EQ(planners::moving_reach_for("cvae", options), 1.0);
  for (const char* name : {"bc", "cvae-fixed-q", "projcem", "follower", "autochaser"})
    EXPECT_EQ(planners::moving_reach_for(name, options), 0.0) << name;
  options.batch = 5;
  EXPECT_EQ(planners::moving_reach_for("cvae", options), 0.0);
  options.batch = 30;
  options.shield = false;
  EXPECT_EQ(planners::moving_reach_for("cvae", options), 0.0);
  for (const bool shield : {false, true}) {
    options.shield = shield;
    options.moving_reach = 0.0;
    EXPECT_EQ(planners::moving_reach_for("cvae", options), 0.0);
    options.moving_reach = 0.5;
    for (const char* name : {"cvae", "bc", "projcem"}) EXPECT_EQ(planners::moving_reach_for(name, options), 0.5);
  }

  // A negative reach is passed on and refused by the ranking, by name.
  const std::string path = test::temp_path("moving-reach.safetensors");
  planners::PlannerOptions bad = random_cvae_options(path, 4);
  bad.moving_reach = -1.0;
  try {
    planners::make_planner("cvae", bad);
    ADD_FAILURE() << "a negative moving reach was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("moving_reach"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

// ------------------------------------------------------------------------------------------------------------
// The planner.

TEST(LearnedPolicy, GivesFiniteCommandsOnRealScansForEveryVariantAndBatch) {
  const Drive drive = forest_drive(6);
  for (const policy::Variant variant : {policy::Variant::cvae, policy::Variant::fixed_q, policy::Variant::bc})
    for (const int batch : {5, 30}) {
      planners::LearnedPolicy planner = random_policy(variant, batch);
      const std::string what = planner.name() + " B=" + std::to_string(batch);
      for (const auto& in : drive.inputs) {
        const planners::PlannerOutput out = planner.plan(in);
        expect_usable(out, what);
        EXPECT_TRUE(out.ok) << what << ": " << out.message;
        EXPECT_EQ(out.plan.size(), 100u) << what;
        EXPECT_EQ(out.candidates.size(), static_cast<std::size_t>(batch)) << what;
        EXPECT_LE(out.command_velocity.norm(), 2.0 + 1e-9) << what;
        EXPECT_GT(out.compute_ms, 0.0);
      }
      const auto& t = planner.last_timing();
      EXPECT_GT(t.pointnet, 0.0);
      EXPECT_GE(t.total, t.pointnet + t.decoder + t.projection);
    }
}

TEST(LearnedPolicy, BrakesOnAnEmptyScanOrANonFiniteTarget) {
  core::Scan empty;
  empty.angle_increment = 2 * M_PI / 360;
  empty.ranges.assign(360, std::numeric_limits<double>::infinity());
  planners::PlannerInput input;
  input.target_position = {2.0, 0.5};
  input.scan = &empty;
  for (const policy::Variant variant : {policy::Variant::cvae, policy::Variant::fixed_q, policy::Variant::bc}) {
    planners::LearnedPolicy planner = random_policy(variant, 5);
    const auto out = planner.plan(input);
    expect_usable(out, planner.name() + " empty scan");
    EXPECT_TRUE(out.ok) << out.message;  // nothing in range is a valid scan

    planners::PlannerInput bad = input;
    bad.time = 0.05;
    bad.target_position.x() = std::numeric_limits<double>::quiet_NaN();
    const auto nan = planner.plan(bad);
    EXPECT_FALSE(nan.ok);
    EXPECT_EQ(nan.command_velocity, Eigen::Vector2d::Zero());
    EXPECT_NE(nan.message.find("target"), std::string::npos) << nan.message;

    planners::PlannerInput no_scan = input;
    no_scan.scan = nullptr;
    const auto none = planner.plan(no_scan);
    EXPECT_FALSE(none.ok);
    EXPECT_TRUE(none.command_velocity.allFinite());
  }
}

TEST(LearnedPolicy, BrakesWhenEveryDecodedSampleIsNonFinite) {
  // Output scales that overflow float once folded (the file holds them as F64): every sample is non-finite,
  // and the planner must not pass that on.
  io::TensorFile f = default_file();
  f.put("norm.output.scale", {252}, std::vector<double>(252, 1e300));
  const Drive drive = forest_drive(3);
  for (const policy::Variant variant : {policy::Variant::cvae, policy::Variant::bc}) {
    f.metadata["variant"] = policy::to_string(variant);
    auto settings = policy_settings(variant, 5);
    settings.rank_stop = false;
    planners::LearnedPolicy planner(settings, policy::Model(f));
    const auto out = planner.plan(drive.inputs[0]);
    EXPECT_FALSE(out.ok);
    EXPECT_EQ(out.command_velocity, Eigen::Vector2d::Zero());
    EXPECT_NE(out.message.find("no finite candidate"), std::string::npos) << out.message;

    // With the stop plan ranked (the default), that plan is chosen instead (later, it or its own
    // continuation, the last plan): a finite command within the acceleration bound of the robot's velocity.
    // bc projects nothing and has no stop plan.
    if (variant == policy::Variant::bc) continue;
    settings.rank_stop = true;
    planners::LearnedPolicy stopping(settings, policy::Model(f));
    const double accel_max = settings.projection.accel_max;
    for (std::size_t k = 0; k < drive.inputs.size(); ++k) {
      const auto& in = drive.inputs[k];
      const auto o = stopping.plan(in);
      expect_usable(o, stopping.name() + " stop plan");
      EXPECT_TRUE(o.ok) << o.message;
      const auto& choice = stopping.last_choice();
      EXPECT_TRUE(k == 0 ? choice.stop : choice.stop || choice.last_plan) << "cycle " << k;
      EXPECT_LE((o.command_velocity - in.robot_velocity).norm(), accel_max * 0.1 + 1e-6) << "cycle " << k;
    }
  }
}

TEST(LearnedPolicy, SameSeedSameCommandsAndResetStartsOver) {
  const Drive drive = forest_drive(5);
  // Samples only: with random weights the stop plan would win every cycle, whatever the seed.
  auto samples_only = [](std::uint64_t seed) {
    auto s = policy_settings(policy::Variant::cvae, 30);
    s.seed = seed;
    s.rank_stop = false;
    s.keep_last_plan = false;
    return planners::LearnedPolicy(
        s, policy::Model(policy::random_model(default_network(), default_projection(), "cvae", 5)));
  };
  planners::LearnedPolicy a = samples_only(7), b = samples_only(7), c = samples_only(8);
  std::vector<Eigen::Vector2d> first;
  bool differs = false;
  for (const auto& in : drive.inputs) {
    const auto oa = a.plan(in), ob = b.plan(in), oc = c.plan(in);
    EXPECT_EQ(oa.command_velocity, ob.command_velocity);
    EXPECT_EQ(oa.plan, ob.plan);
    differs = differs || oa.command_velocity != oc.command_velocity;
    first.push_back(oa.command_velocity);
  }
  EXPECT_TRUE(differs) << "another seed should draw other latent samples";
  a.reset();
  for (std::size_t k = 0; k < drive.inputs.size(); ++k) EXPECT_EQ(a.plan(drive.inputs[k]).command_velocity, first[k]);
}

TEST(LearnedPolicy, RunsAClosedLoopEpisode) {
  core::Scenario scenario = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml");
  scenario.duration = 2.0;
  planners::LearnedPolicy planner = random_policy(policy::Variant::cvae, 5);
  const auto m = sim::run_episode(scenario, planner, sim::EpisodeSettings{}).metrics;
  EXPECT_EQ(m.cycles, 40);
  EXPECT_EQ(m.planner_failures, 0);
  EXPECT_EQ(m.planner, "cvae");
}

TEST(LearnedPolicy, KeepingTheLastPlanNeverRanksWorseAndIsUsed) {
  // Same seed and the same recorded inputs: both planners draw the same B samples every cycle, so the one
  // that also ranks the last plan (shifted to now) must end each cycle at a cost no higher than the other's.
  const Drive drive = forest_drive(6);
  for (const policy::Variant variant : {policy::Variant::cvae, policy::Variant::bc}) {
    auto settings = policy_settings(variant, 5);
    settings.rank_stop = false;  // the same rows but the last plan
    settings.keep_last_plan = false;
    const io::TensorFile weights =
        policy::random_model(default_network(), default_projection(), policy::to_string(variant), 5);
    planners::LearnedPolicy paper(settings, policy::Model(weights));
    settings.keep_last_plan = true;
    planners::LearnedPolicy kept(settings, policy::Model(weights));
    int used = 0;
    for (std::size_t k = 0; k < drive.inputs.size(); ++k) {
      const auto a = paper.plan(drive.inputs[k]), b = kept.plan(drive.inputs[k]);
      ASSERT_TRUE(a.ok && b.ok) << a.message << b.message;
      expect_usable(b, kept.name() + " keeping the last plan");
      EXPECT_FALSE(paper.last_choice().last_plan);
      // Float projection: a batch of B + 1 rows may round a row differently from a batch of B.
      EXPECT_LE(kept.last_choice().cost, paper.last_choice().cost * (1 + 1e-5) + 1e-6) << "cycle " << k;
      if (k == 0) {
        EXPECT_FALSE(kept.last_choice().last_plan) << "no last plan at the first cycle";
      }
      used += kept.last_choice().last_plan;
    }
    // Random weights draw poor samples: last cycle's plan, projected again from where it is now, wins some
    // cycles. (bc's last plan is not projected; with random weights it need not ever win.)
    if (variant == policy::Variant::cvae) {
      EXPECT_GT(used, 0) << kept.name();
    }
    kept.reset();
    kept.plan(drive.inputs[0]);
    EXPECT_FALSE(kept.last_choice().last_plan) << "reset() forgets the last plan";
  }
}
