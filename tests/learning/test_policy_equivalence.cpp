// The trainer's torch model and the run-time Eigen policy (occtrack/policy/model.hpp) read the same model
// file the same way: same weights and inputs give the same PointNet features, encoder and decoder outputs and
// post-processing, to float round-off (docs/learning.md, "Networks, in eval mode").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <utility>

#include "learning/export.hpp"
#include "learning/networks.hpp"
#include "occtrack/policy/model.hpp"

using namespace occtrack;

namespace {

class PolicyEquivalence : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    setenv("OPENBLAS_NUM_THREADS", "1", 0);
    torch::set_num_threads(1);
  }
};

// Non-trivial normalisation and batch-norm statistics (a freshly built model has mean 0, var 1, identity
// affine), so that every term of the eval-mode formulas is exercised.
void randomize(learning::CvaeImpl& model) {
  torch::NoGradGuard no_grad;
  for (auto& [name, t] : learning::named_model_tensors(model)) {
    auto ends_with = [&](const std::string& s) {
      return name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
    };
    if (ends_with("running_var") || ends_with(".std") || ends_with(".scale"))
      t.uniform_(0.5, 2.0);
    else if (ends_with("running_mean") || ends_with(".mean") || ends_with(".offset"))
      t.uniform_(-0.5, 0.5);
    else if (name.find(".bn") != std::string::npos && ends_with(".weight"))
      t.uniform_(0.7, 1.3);
    else if (name.find(".bn") != std::string::npos && ends_with(".bias"))
      t.uniform_(-0.2, 0.2);
  }
}

policy::Rows rows_of(const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kFloat32).contiguous();
  return Eigen::Map<const policy::Rows>(c.data_ptr<float>(), c.size(0), c.size(1));
}

// Largest |a - b| / (1 + |b|).
double mismatch(const torch::Tensor& a, const torch::Tensor& b) {
  return ((a - b).abs() / (1 + b.abs())).max().item<double>();
}

torch::Tensor tensor_of(const Eigen::Ref<const policy::Rows>& m) {
  return torch::from_blob(const_cast<float*>(m.data()), {m.rows(), m.cols()}, torch::kFloat32).clone();
}

// The small network of these tests (the default's shape, narrower).
io::NetworkConfig small_config() {
  io::NetworkConfig config;
  config.pointnet_widths = {8, 16, 16, 24, 32};
  config.pointnet_hidden = 24;
  config.features = 12;
  config.hidden = 40;
  config.layers = 2;
  config.latent = 3;
  config.outputs = config.expected_outputs();
  return config;
}

// A randomized torch model in eval mode, and the Eigen policy of its exported file.
std::pair<learning::Cvae, policy::Model> model_pair(const io::NetworkConfig& config, uint64_t seed) {
  torch::manual_seed(seed);
  learning::Cvae model(config, /*dropout=*/0.3);
  randomize(*model);
  model->eval();
  learning::ModelMetadata metadata;
  metadata.network = config;
  metadata.projection.obstacles = config.nearest_points;
  metadata.created_by = "test_policy_equivalence";
  policy::Model eigen(io::validate_model_file(io::to_tensor_file(learning::model_file(*model, metadata))));
  return {model, std::move(eigen)};
}

}  // namespace

// A target-frame model: torch's sample() (which turns by itself) and the Eigen model behind
// policy::FrameRotation give the same robot-centric outputs; and the normalisation is of the turned rows.
TEST_F(PolicyEquivalence, TargetFrameModelsTurnAlikeInTorchAndEigen) {
  io::NetworkConfig config = small_config();
  config.target_frame = true;
  auto [model, eigen] = model_pair(config, 12);
  ASSERT_TRUE(eigen.network().target_frame);

  torch::NoGradGuard no_grad;
  const int B = 6, C = config.cloud_points;
  const torch::Tensor cloud = torch::randn({1, C, 2}) * 3.0;
  const torch::Tensor observation = torch::randn({1, 6});
  const torch::Tensor z = torch::randn({B, config.latent});
  const torch::Tensor outputs = model->sample(z, observation.expand({B, 6}), cloud.expand({B, C, 2}));

  Eigen::VectorXf obs = rows_of(observation).row(0).transpose();
  policy::Cloud eigen_cloud = rows_of(cloud[0]);
  policy::FrameRotation turn(eigen.network());
  turn.aim(obs(2), obs(3));
  turn.into_network(obs, eigen_cloud);
  Eigen::VectorXf features(config.features);
  eigen.features(eigen_cloud, features);
  policy::Rows eigen_outputs(B, config.outputs);
  eigen.decode(rows_of(z), obs, features, eigen_outputs);
  turn.out_of_network(eigen_outputs);
  EXPECT_LT(mismatch(tensor_of(eigen_outputs), outputs), 1e-5);
  // In the network's frame the target lies on +x.
  EXPECT_NEAR(obs(3), 0.0f, 1e-6);
  EXPECT_GT(obs(2), 0.0f);
  // And the robot-frame reading of the same weights differs (the turn is not a no-op here).
  io::NetworkConfig robot = config;
  robot.target_frame = false;
  learning::Cvae plain(robot, 0.3);
  {
    auto from = learning::named_model_tensors(*model);
    auto to = learning::named_model_tensors(*plain);
    for (std::size_t i = 0; i < from.size(); ++i) to[i].second.copy_(from[i].second);
  }
  plain->eval();
  const torch::Tensor unturned = plain->sample(z, observation.expand({B, 6}), cloud.expand({B, C, 2}));
  EXPECT_GT(mismatch(unturned, outputs), 1e-3);
}

TEST_F(PolicyEquivalence, TorchAndEigenGiveTheSameOutputs) {
  for (const bool small : {true, false}) {
    SCOPED_TRACE(small ? "small network" : "default network");
    io::NetworkConfig config = small ? small_config() : io::NetworkConfig{};  // or the defaults of docs/learning.md
    auto [model, eigen] = model_pair(config, 11);
    ASSERT_EQ(eigen.network().features, config.features);
    ASSERT_EQ(eigen.network().outputs, config.outputs);

    torch::NoGradGuard no_grad;
    const int B = 7, C = config.cloud_points;
    const torch::Tensor cloud = torch::randn({1, C, 2}) * 3.0;
    const torch::Tensor observation = torch::randn({1, 6});
    const torch::Tensor z = torch::randn({B, config.latent});
    const torch::Tensor expert_xi = torch::randn({B, 2 * config.coefficients}) * 2.0;

    // PointNet.
    const torch::Tensor features = model->features(cloud);
    const policy::Cloud eigen_cloud = rows_of(cloud[0]);
    Eigen::VectorXf eigen_features(config.features);
    eigen.features(eigen_cloud, eigen_features);
    const torch::Tensor eigen_features_t = torch::from_blob(eigen_features.data(), {1, config.features}).clone();
    EXPECT_LT(mismatch(eigen_features_t, features), 1e-5) << "features";

    // Decoder (each side on the torch features, so that the comparison is of the decoder alone).
    const torch::Tensor outputs = model->decode(z, observation.expand({B, 6}), features.expand({B, config.features}));
    const Eigen::VectorXf obs = rows_of(observation).row(0).transpose();
    const Eigen::VectorXf f = rows_of(features).row(0).transpose();
    policy::Rows eigen_outputs(B, config.outputs);
    eigen.decode(rows_of(z), obs, f, eigen_outputs);
    EXPECT_LT(mismatch(tensor_of(eigen_outputs), outputs), 1e-5) << "decoder outputs";

    // Encoder.
    const learning::Posterior q = model->encode(observation.expand({B, 6}), features.expand({B, config.features}), expert_xi);
    policy::Rows mu(B, config.latent), sigma(B, config.latent);
    eigen.encode(obs, f, rows_of(expert_xi), mu, sigma);
    EXPECT_LT(mismatch(tensor_of(mu), q.mean), 1e-5) << "encoder mean";
    EXPECT_LT(mismatch(tensor_of(sigma), q.sigma), 1e-5) << "encoder sigma";

    // Post-processing, on outputs that reach the clamps.
    const torch::Tensor wide = outputs * 4.0;
    policy::Rows eigen_wide = rows_of(wide);
    eigen.postprocess(eigen_wide, 2.0, 1.0);
    const learning::DecodedOutputs d = learning::post_process(learning::split_outputs(wide, config), 2.0, 1.0);
    const torch::Tensor processed =
        torch::cat({d.terminal, d.via_points, d.lambda0, d.distance_min, d.distance_max, d.xi_bar}, 1);
    EXPECT_TRUE(torch::equal(tensor_of(eigen_wide), processed)) << "post-processing";
  }
}
