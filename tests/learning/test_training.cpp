// The trainer (src/learning): a short training on a tiny dataset file lowers the loss; a run resumed from a
// checkpoint repeats the uninterrupted run's losses; the export holds every tensor of docs/learning.md with
// its shape and the metadata; bad dataset files are refused naming what is wrong; fixed-q's nominal q is
// planners::detail::Context::fill_row's.
#include <gtest/gtest.h>

#include <cmath>
#include <dirent.h>
#include <unistd.h>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "learning/dataset.hpp"
#include "learning/export.hpp"
#include "learning/networks.hpp"
#include "learning/trainer.hpp"
#include "occtrack/io/error.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/io/safetensors.hpp"
#include "planners/cycle.hpp"

namespace fs = std::filesystem;
using namespace occtrack;

namespace {

class Training : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    setenv("OPENBLAS_NUM_THREADS", "1", 0);
    torch::set_num_threads(1);
  }
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("occtrack_training_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  // POSIX calls rather than fs::remove_all: LibTorch 2.x wheels export their own std::filesystem symbols,
  // and their remove_all crashes on a non-empty folder when it interposes libstdc++'s.
  void TearDown() override {
    if (DIR* d = ::opendir(dir_.c_str())) {
      while (const dirent* e = ::readdir(d))
        if (std::string(e->d_name) != "." && std::string(e->d_name) != "..") ::unlink((dir_ / e->d_name).c_str());
      ::closedir(d);
    }
    ::rmdir(dir_.c_str());
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

std::vector<float> floats(const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kFloat32).contiguous();
  return std::vector<float>(c.data_ptr<float>(), c.data_ptr<float>() + c.numel());
}

// A dataset file of `rows` synthetic rows (straight-line experts), in the layout of docs/learning.md.
io::TensorFile dataset_file(int64_t rows, int cloud_points = 32, int nearest_points = 8, std::uint64_t seed = 3) {
  learning::SyntheticDatasetOptions o;
  o.rows = rows;
  o.episodes = 4;
  o.cloud_points = cloud_points;
  o.nearest_points = nearest_points;
  o.seed = seed;
  const projection::Settings settings;
  const learning::Dataset d = learning::synthetic_dataset(o, settings);
  io::TensorFile f;
  f.metadata["format"] = "occtrack.dataset.v1";
  f.metadata["projection"] = io::projection_settings_json(settings);
  f.metadata["rows"] = std::to_string(rows);
  f.metadata["created_by"] = "test_training";
  f.put("observation", {rows, 6}, floats(d.observation));
  f.put("cloud", {rows, cloud_points, 2}, floats(d.cloud));
  f.put("obstacles", {rows, nearest_points, 4}, floats(d.obstacles));
  f.put("expert_xi", {rows, 2 * settings.coefficients()}, floats(d.expert_xi));
  f.put("expert_cost", {rows}, floats(d.expert_cost));
  const torch::Tensor episode = d.episode.to(torch::kInt32).contiguous();
  f.put("episode", {rows}, std::vector<std::int32_t>(episode.data_ptr<int32_t>(), episode.data_ptr<int32_t>() + rows));
  f.put("time", {rows}, floats(d.time));
  return f;
}

// Small networks, so that a step takes milliseconds on one thread.
learning::TrainingSettings small_settings() {
  learning::TrainingSettings s;
  s.network.pointnet_widths = {16, 16, 16, 32, 32};
  s.network.pointnet_hidden = 32;
  s.network.features = 16;
  s.network.hidden = 32;
  s.network.layers = 2;
  s.dropout = 0.1;
  s.batch = 16;
  s.iterations = 5;
  s.learning_rate = 3e-3;
  s.steps = 60;
  s.validation_share = 0.25;
  s.validation_rows = 16;
  s.validation_every = 0;
  s.progress_seconds = 1e9;
  s.seed = 7;
  return s;
}

double mean_total(const std::vector<learning::LossTerms>& history, std::size_t begin, std::size_t end) {
  double sum = 0;
  for (std::size_t i = begin; i < end; ++i) sum += history[i].total;
  return sum / static_cast<double>(end - begin);
}

}  // namespace

TEST_F(Training, ShortRunLowersTheLoss) {
  const std::string data = path("data.safetensors");
  io::write_safetensors(data, dataset_file(64));
  for (const auto& [variant, target_frame] :
       {std::pair{io::Variant::cvae, false}, std::pair{io::Variant::bc, false}, std::pair{io::Variant::cvae, true}}) {
    SCOPED_TRACE(std::string(io::to_string(variant)) + (target_frame ? ", target frame" : ""));
    learning::TrainingSettings s = small_settings();
    s.variant = variant;
    s.network.target_frame = target_frame;
    learning::Trainer trainer(s, learning::load_dataset({data}));
    // The normalisation is of what the networks see: in the target frame the target lies on +x.
    const auto& norm = trainer.model()->norm->observation;
    if (target_frame) {
      EXPECT_NEAR(norm->mean[3].item<double>(), 0.0, 1e-5);
      EXPECT_NEAR(norm->std[3].item<double>(), 1e-3, 1e-6);  // the floor
      EXPECT_GT(norm->mean[2].item<double>(), 0.5);          // the target's distance
    } else {
      EXPECT_GT(norm->std[3].item<double>(), 0.1);
    }
    EXPECT_EQ(trainer.split().validation_episodes, 1);
    EXPECT_EQ(trainer.split().train.numel() + trainer.split().validation.numel(), 64);
    int reports = 0;
    const learning::TrainingSummary summary = trainer.run([&](const learning::TrainingProgress& p) {
      ++reports;
      EXPECT_EQ(p.steps, 60);
    });
    ASSERT_EQ(summary.history.size(), 60u);
    EXPECT_EQ(reports, 1);  // only the last step's report with progress_seconds this large
    for (const auto& h : summary.history) ASSERT_TRUE(std::isfinite(h.total));
    const double first = mean_total(summary.history, 0, 5), last = mean_total(summary.history, 55, 60);
    EXPECT_LT(last, 0.7 * first) << "first steps " << first << ", last steps " << last;
    ASSERT_TRUE(summary.validation.has_value());
    EXPECT_TRUE(std::isfinite(summary.validation->total));
    // Eval mode (batch norm on running statistics, no dropout) on rows of the same distribution: the model
    // learnt there too.
    EXPECT_LT(summary.validation->total, first);
    if (variant == io::Variant::bc) EXPECT_EQ(summary.history.back().residual, 0.0);
    else EXPECT_GT(summary.history.back().residual, 0.0);
  }
}

TEST_F(Training, CudaRunLowersTheLoss) {
  if (!torch::cuda::is_available()) GTEST_SKIP() << "no CUDA device";
  const std::string data = path("data.safetensors");
  io::write_safetensors(data, dataset_file(64));
  learning::TrainingSettings s = small_settings();
  s.device = "cuda";
  learning::Trainer trainer(s, learning::load_dataset({data}));
  const learning::TrainingSummary summary = trainer.run();
  ASSERT_EQ(summary.history.size(), 60u);
  const double first = mean_total(summary.history, 0, 5), last = mean_total(summary.history, 55, 60);
  EXPECT_LT(last, 0.7 * first) << "first steps " << first << ", last steps " << last;
  // Checkpoints and the export work from the GPU too (weights come back as float32 on the CPU).
  trainer.save_checkpoint(path("cuda.ckpt"));
  learning::Trainer resumed(s, learning::load_dataset({data}));
  resumed.load_checkpoint(path("cuda.ckpt"));
  EXPECT_EQ(resumed.current_step(), 60);
  const std::string out = path("model.safetensors");
  learning::export_model(out, *trainer.model(), trainer.model_metadata(summary, "test_training"));
  const auto training = nlohmann::json::parse(io::read_safetensors(out).meta("training"));
  EXPECT_EQ(training.at("device"), "cuda");
  // The hardware names the GPU that trained, not the host's CPU (whatever either is).
  const std::string hardware = training.at("hardware").get<std::string>();
  EXPECT_FALSE(hardware.empty());
  EXPECT_NE(hardware, learning::hardware_description(torch::Device(torch::kCPU)));
}

TEST_F(Training, ResumedRunRepeatsTheLosses) {
  const std::string data = path("data.safetensors");
  io::write_safetensors(data, dataset_file(48));
  learning::TrainingSettings s = small_settings();
  s.steps = 12;
  learning::Trainer whole(s, learning::load_dataset({data}));
  const auto uninterrupted = whole.run().history;

  learning::TrainingSettings first_half = s;
  first_half.steps = 6;
  first_half.checkpoint_path = path("run.ckpt");
  first_half.checkpoint_every = 4;
  learning::Trainer a(first_half, learning::load_dataset({data}));
  const auto before = a.run().history;
  ASSERT_TRUE(fs::exists(first_half.checkpoint_path));

  learning::Trainer b(s, learning::load_dataset({data}));
  b.load_checkpoint(first_half.checkpoint_path);
  EXPECT_EQ(b.current_step(), 6);
  const auto after = b.run().history;
  ASSERT_EQ(before.size() + after.size(), uninterrupted.size());
  for (std::size_t i = 0; i < uninterrupted.size(); ++i) {
    const auto& got = i < before.size() ? before[i] : after[i - before.size()];
    EXPECT_DOUBLE_EQ(got.total, uninterrupted[i].total) << "step " << i;
    EXPECT_DOUBLE_EQ(got.residual, uninterrupted[i].residual) << "step " << i;
  }

  // A checkpoint of another configuration is refused, naming the field.
  learning::TrainingSettings other = s;
  other.batch = 8;
  learning::Trainer c(other, learning::load_dataset({data}));
  try {
    c.load_checkpoint(first_half.checkpoint_path);
    FAIL() << "a checkpoint with another batch was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("batch"), std::string::npos) << e.what();
  }
}

TEST_F(Training, ExportWritesEveryTensorOfTheContract) {
  const std::string data = path("data.safetensors"), dagger = path("dagger.safetensors");
  io::write_safetensors(data, dataset_file(32));
  io::TensorFile driven = dataset_file(16, 32, 8, 4);  // a DAgger round: a learned policy drove
  driven.metadata["driver"] = "round0/cvae.safetensors";
  io::write_safetensors(dagger, driven);
  learning::TrainingSettings s = small_settings();
  s.steps = 2;
  s.variant = io::Variant::fixed_q;
  learning::Trainer trainer(s, learning::load_dataset({data, dagger}));
  const learning::TrainingSummary summary = trainer.run();
  const std::string out = path("model.safetensors");
  learning::export_model(out, *trainer.model(), trainer.model_metadata(summary, "test_training"));
  const io::TensorFile file = io::read_safetensors(out);

  // The tensor list of docs/learning.md, built here from the sizes, independently of the module tree.
  const io::NetworkConfig& c = trainer.settings().network;
  const int64_t O = 6, n2 = 22, Y = 252, Z = c.latent, F = c.features, H = c.hidden, Hp = c.pointnet_hidden;
  std::map<std::string, std::vector<int64_t>> expected = {
      {"norm.observation.mean", {O}}, {"norm.observation.std", {O}}, {"norm.cloud.mean", {2}},
      {"norm.cloud.std", {2}},        {"norm.xi.mean", {n2}},        {"norm.xi.std", {n2}},
      {"norm.output.offset", {Y}},    {"norm.output.scale", {Y}}};
  auto linear = [&](const std::string& name, int64_t out_size, int64_t in_size) {
    expected[name + ".weight"] = {out_size, in_size};
    expected[name + ".bias"] = {out_size};
  };
  auto batch_norm = [&](const std::string& name, int64_t width) {
    for (const char* field : {".weight", ".bias", ".running_mean", ".running_var"}) expected[name + field] = {width};
  };
  int64_t in = 2;
  for (int i = 0; i < 5; ++i) {
    linear("pointnet.conv" + std::to_string(i), c.pointnet_widths[i], in);
    batch_norm("pointnet.bn" + std::to_string(i), c.pointnet_widths[i]);
    in = c.pointnet_widths[i];
  }
  linear("pointnet.fc0", Hp, in);
  batch_norm("pointnet.fc_bn0", Hp);
  linear("pointnet.fc1", F, Hp);
  for (int i = 0; i < c.layers; ++i) {
    linear("encoder.fc" + std::to_string(i), H, i == 0 ? O + F + n2 : H);
    batch_norm("encoder.bn" + std::to_string(i), H);
    linear("decoder.fc" + std::to_string(i), H, i == 0 ? Z + O + F : H);
    batch_norm("decoder.bn" + std::to_string(i), H);
  }
  linear("encoder.mean", Z, H);
  linear("encoder.std", Z, H);
  linear("decoder.out", Y, H);

  EXPECT_EQ(file.tensors.size(), expected.size());
  for (const auto& [name, shape] : expected) {
    ASSERT_TRUE(file.has(name)) << name;
    EXPECT_EQ(file.at(name).shape, shape) << name;
    EXPECT_EQ(file.at(name).dtype, io::DType::F32) << name;
  }
  for (const auto& [name, tensor] : file.tensors) EXPECT_TRUE(expected.count(name)) << "unexpected tensor " << name;

  EXPECT_EQ(file.meta("format"), "occtrack.model.v1");
  EXPECT_EQ(file.meta("variant"), "fixed-q");
  EXPECT_EQ(io::NetworkConfig::parse(file.meta("network"), out), c);
  const auto network = nlohmann::json::parse(file.meta("network"));
  EXPECT_EQ(network.at("outputs"), 252);
  EXPECT_EQ(network.at("cloud_points"), 32);
  EXPECT_EQ(network.at("nearest_points"), 8);
  const projection::Settings projection =
      io::parse_projection_settings(file.meta("projection"), out, "projection", /*strict=*/false);
  EXPECT_EQ(projection.iterations, s.iterations);
  EXPECT_EQ(nlohmann::json::parse(file.meta("projection")).at("training_iterations"), s.iterations);
  // The run-time reader accepts it: the contract is the same on both sides.
  const io::ModelFile checked = io::validate_model_file(file);
  EXPECT_EQ(checked.variant, io::Variant::fixed_q);
  EXPECT_EQ(checked.network, c);
  const auto band = nlohmann::json::parse(file.meta("band"));
  EXPECT_EQ(band.at("min"), 1.0);
  EXPECT_EQ(band.at("max"), 3.0);
  const auto training = nlohmann::json::parse(file.meta("training"));
  for (const char* key : {"datasets", "rows", "seed", "steps", "batch", "learning_rate", "beta", "device", "seconds",
                          "hardware", "final_losses", "iterations"})
    EXPECT_TRUE(training.contains(key)) << key;
  EXPECT_EQ(training.at("datasets").at(0).at("path"), data);
  EXPECT_EQ(training.at("datasets").at(0).at("rows"), 32);
  EXPECT_EQ(training.at("datasets").at(0).at("driver"), "");
  EXPECT_EQ(training.at("datasets").at(1).at("rows"), 16);
  EXPECT_EQ(training.at("datasets").at(1).at("driver"), "round0/cvae.safetensors");
  EXPECT_GT(training.at("datasets").at(1).at("episodes"), 0);
  EXPECT_EQ(training.at("rows"), 48);
  EXPECT_EQ(training.at("dagger_rounds"), 1);
  EXPECT_EQ(training.at("steps"), 2);
  EXPECT_EQ(training.at("device"), "cpu");
  EXPECT_FALSE(training.at("hardware").get<std::string>().empty());
  EXPECT_TRUE(training.at("final_losses").contains("train"));
  EXPECT_EQ(file.meta("created_by"), "test_training");
}

TEST_F(Training, BadDatasetsAreRefusedNamingTheProblem) {
  auto refused = [&](const io::TensorFile& f, const std::string& name, const std::vector<std::string>& words) {
    const std::string p = path(name);
    io::write_safetensors(p, f);
    try {
      learning::load_dataset({p});
      ADD_FAILURE() << name << " was accepted";
    } catch (const io::InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(name), std::string::npos) << message;
      for (const auto& w : words) EXPECT_NE(message.find(w), std::string::npos) << "'" << w << "' in: " << message;
    }
  };
  const io::TensorFile good = dataset_file(16);
  {
    io::TensorFile f = good;
    f.tensors.erase("expert_xi");
    refused(f, "missing.safetensors", {"expert_xi", "missing"});
  }
  {
    io::TensorFile f = good;
    f.metadata["format"] = "occtrack.model.v1";
    refused(f, "format.safetensors", {"format", "occtrack.dataset.v1"});
  }
  {
    io::TensorFile f = good;
    f.metadata.erase("projection");
    refused(f, "noprojection.safetensors", {"projection"});
  }
  {
    io::TensorFile f = good;
    f.put("expert_xi", {16, 20}, std::vector<float>(16 * 20, 0.f));
    refused(f, "shape.safetensors", {"expert_xi", "[16, 20]", "[16, 22]"});
  }
  {
    io::TensorFile f = good;
    f.put("episode", {16}, std::vector<float>(16, 0.f));
    refused(f, "dtype.safetensors", {"episode", "dtype"});
  }
  {
    io::TensorFile f = good;
    std::vector<float> observation = f.at("observation").as_float();
    observation[6 * 5 + 2] = std::nanf("");
    f.put("observation", {16, 6}, observation);
    refused(f, "nan.safetensors", {"observation", "non-finite", "row 5"});
  }
  {  // Two files whose sizes disagree.
    const std::string a = path("a.safetensors"), b = path("b.safetensors");
    io::write_safetensors(a, dataset_file(16, 32, 8));
    io::write_safetensors(b, dataset_file(16, 24, 8));
    try {
      learning::load_dataset({a, b});
      ADD_FAILURE() << "files of different cloud sizes were accepted";
    } catch (const io::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cloud"), std::string::npos) << e.what();
    }
  }
  // Two good files: rows and episodes add up, episodes stay distinct.
  const std::string a = path("a.safetensors"), b = path("b.safetensors");
  io::write_safetensors(a, dataset_file(16));
  io::write_safetensors(b, dataset_file(24));
  const learning::Dataset d = learning::load_dataset({a, b});
  EXPECT_EQ(d.rows(), 40);
  EXPECT_EQ(std::get<0>(torch::_unique(d.episode)).numel(), 8);
}

TEST_F(Training, FixedQIsContextFillRow) {
  // The nominal q of fixed-q (learning::policy_outputs) against planners::detail::Context::fill_row.
  projection::Settings ps;
  ps.batch = 3;
  ps.obstacles = 4;
  perception::Settings perception;
  perception.nearest_count = 4;
  planners::RankingSettings ranking;
  planners::detail::Context context(ps, perception, ranking);

  io::NetworkConfig network;
  network.nearest_points = 4;
  torch::manual_seed(5);
  torch::Tensor outputs = torch::randn({3, network.outputs});
  const io::OutputLayout layout(network);
  // xi_bar: one slow and two fast paths (the speed cap must act on those).
  outputs.index_put_({torch::indexing::Slice(), torch::indexing::Slice(layout.xi_bar, layout.size)},
                     torch::randn({3, 22}) * torch::tensor({0.5, 4.0, 8.0}).unsqueeze(1));
  const torch::Tensor observation = torch::randn({3, 6}), obstacles = torch::randn({3, 4, 4});
  learning::PolicySettings policy;
  policy.variant = io::Variant::fixed_q;
  policy.projection = ps;
  policy.band = ranking.band;
  const learning::TrajectoryBasis basis(ps, torch::kFloat32, torch::kCPU);
  const learning::ProjectionInputs in = learning::policy_outputs(outputs, observation, obstacles, policy, basis, network);

  projection::Problem<float> problem;
  problem.resize(ps);
  for (int b = 0; b < 3; ++b) {
    planners::Frame frame;
    frame.robot_velocity = Eigen::Vector2d(observation[b][0].item<double>(), observation[b][1].item<double>());
    for (int k = 0; k < 4; ++k) frame.target(k) = observation[b][2 + k].item<double>();
    frame.nearest.resize(4, 4);
    for (int j = 0; j < 4; ++j)
      for (int f = 0; f < 4; ++f) frame.nearest(j, f) = obstacles[b][j][f].item<double>();
    Eigen::RowVectorXd xi_bar(22);
    for (int i = 0; i < 22; ++i) xi_bar(i) = in.xi_bar[b][i].item<double>();
    context.fill_row(problem, b, xi_bar, frame);
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(in.terminal[b][k].item<float>(), problem.terminal(b, k), 1e-4) << "row " << b << " terminal " << k;
      EXPECT_NEAR(in.target[b][k].item<float>(), problem.target(b, k), 1e-6);
    }
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(in.robot_velocity[b][k].item<float>(), problem.robot_velocity(b, k), 1e-6);
    for (int k = 0; k < ps.steps; ++k) {
      EXPECT_EQ(in.distance_min[b][k].item<float>(), problem.distance_min(b, k));
      EXPECT_EQ(in.distance_max[b][k].item<float>(), problem.distance_max(b, k));
    }
    // Via points and lambda0 still come from the decoder (docs/learning.md), not from fill_row.
    EXPECT_TRUE(torch::equal(in.via_points[b], outputs[b].slice(0, layout.via, layout.via + 4)));
    EXPECT_TRUE(torch::equal(in.lambda0[b], outputs[b].slice(0, layout.lambda0, layout.distance_min)));
  }
  const double speed = in.terminal.index({torch::indexing::Slice(), torch::indexing::Slice(2, 4)}).norm(2, 1).max().item<double>();
  EXPECT_LE(speed, ps.speed_max + 1e-5);

  // cvae: q from the decoder, post-processed (velocity clamp per axis, d_min floored at band.min).
  policy.variant = io::Variant::cvae;
  const learning::ProjectionInputs cvae = learning::policy_outputs(outputs * 5, observation, obstacles, policy, basis, network);
  EXPECT_GE(cvae.distance_min.min().item<float>(), 1.0f);
  EXPECT_LE(cvae.terminal.index({torch::indexing::Slice(), torch::indexing::Slice(2, 4)}).abs().max().item<float>(), 2.0f);
}

TEST(LearningRate, CosineFromFirstToFinal) {
  EXPECT_DOUBLE_EQ(learning::learning_rate_at(1e-3, 1e-4, 0, 100), 1e-3);
  EXPECT_NEAR(learning::learning_rate_at(1e-3, 1e-4, 50, 100), 5.5e-4, 1e-15);
  EXPECT_NEAR(learning::learning_rate_at(1e-3, 1e-4, 100, 100), 1e-4, 1e-15);
  EXPECT_NEAR(learning::learning_rate_at(1e-3, 1e-4, 150, 100), 1e-4, 1e-15);  // past the end: final
  EXPECT_DOUBLE_EQ(learning::learning_rate_at(1e-3, -1, 70, 100), 1e-3);      // negative final: constant
  for (int64_t step = 1; step <= 100; ++step)
    EXPECT_LE(learning::learning_rate_at(1e-3, 1e-4, step, 100), learning::learning_rate_at(1e-3, 1e-4, step - 1, 100));
}

TEST_F(Training, TimeLimitEndsTheRunAsAtItsLastStep) {
  const std::string data = path("data.safetensors");
  io::write_safetensors(data, dataset_file(64));
  learning::TrainingSettings s = small_settings();
  s.steps = 1000000;       // far more than the limit allows
  s.max_seconds = 1e-9;    // out of time after the first step
  s.learning_rate_final = 1e-4;
  s.checkpoint_path = path("limited.checkpoint");
  learning::Trainer trainer(s, learning::load_dataset({data}));
  const learning::TrainingSummary summary = trainer.run();
  EXPECT_EQ(summary.steps, 1);
  EXPECT_EQ(trainer.current_step(), 1);
  ASSERT_TRUE(summary.validation.has_value());  // validated as at a last step
  EXPECT_TRUE(std::isfinite(summary.validation->total));
  EXPECT_TRUE(std::ifstream(s.checkpoint_path).good());  // and checkpointed
  const auto metadata = trainer.model_metadata(summary, "test");
  EXPECT_EQ(metadata.training.steps, 1);
  EXPECT_DOUBLE_EQ(metadata.training.learning_rate_final, 1e-4);

  s.max_seconds = -1;
  std::string error;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("max_seconds"), std::string::npos) << error;
  s.max_seconds = 0;
  s.learning_rate_final = 1.0;  // above the first rate
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("learning_rate_final"), std::string::npos) << error;
}

// Fine-tuning (--init): a training started from a model file begins with that model's weights and
// normalisation (an export after 0 steps is the file, tensor for tensor), goes on from its loss rather than
// from a random model's, records the lineage in the metadata, and refuses a model of another variant or size.
TEST_F(Training, InitialModelIsWhereTheTrainingStarts) {
  const std::string data = path("data.safetensors"), dagger = path("dagger.safetensors");
  io::write_safetensors(data, dataset_file(64));
  io::TensorFile driven = dataset_file(32, 32, 8, 5);  // other rows: the next DAgger round
  driven.metadata["driver"] = "parent.safetensors";
  io::write_safetensors(dagger, driven);
  const std::string parent = path("parent.safetensors");
  learning::TrainingSettings s = small_settings();
  s.steps = 120;
  learning::Trainer first(s, learning::load_dataset({data}));
  const learning::TrainingSummary first_summary = first.run();
  learning::export_model(parent, *first.model(), first.model_metadata(first_summary, "parent command"));

  learning::TrainingSettings f = small_settings();
  f.initial_model = parent;
  f.steps = 0;
  f.seed = 11;  // another seed: the weights must come from the file, not from the seed
  learning::Trainer unchanged(f, learning::load_dataset({dagger}));
  const learning::TrainingSummary none = unchanged.run();
  const std::string copy = path("copy.safetensors");
  learning::export_model(copy, *unchanged.model(), unchanged.model_metadata(none, "copy command"));
  const io::ModelFile a = io::read_model_file(parent), b = io::read_model_file(copy);
  ASSERT_EQ(a.tensors.size(), b.tensors.size());
  for (const auto& [name, tensor] : a.tensors) EXPECT_EQ(a.values(name), b.values(name)) << name;

  const auto training = nlohmann::json::parse(b.metadata.at("training"));
  ASSERT_TRUE(training.contains("initial_model"));
  EXPECT_EQ(training.at("initial_model").at("path"), parent);
  EXPECT_EQ(training.at("initial_model").at("created_by"), "parent command");
  EXPECT_EQ(training.at("initial_model").at("training").at("rows"), 64);
  EXPECT_EQ(training.at("initial_model").at("training").at("steps"), 120);
  EXPECT_EQ(training.at("rows"), 32);
  EXPECT_EQ(training.at("rows_with_initial"), 96);
  EXPECT_EQ(training.at("dagger_rounds"), 1);
  EXPECT_EQ(training.at("dagger_rounds_with_initial"), 1);
  EXPECT_FALSE(nlohmann::json::parse(a.metadata.at("training")).contains("initial_model"));

  // Fine-tuning on the new rows starts where the parent left off, below a random model's start.
  f.steps = 20;
  learning::Trainer tuned(f, learning::load_dataset({dagger}));
  learning::TrainingSettings r = f;
  r.initial_model.clear();
  learning::Trainer fresh(r, learning::load_dataset({dagger}));
  const double tuned_start = mean_total(tuned.run().history, 0, 5);
  const double fresh_start = mean_total(fresh.run().history, 0, 5);
  EXPECT_LT(tuned_start, 0.7 * fresh_start) << "fine-tuned " << tuned_start << ", from random weights " << fresh_start;

  auto refused = [&](const learning::TrainingSettings& settings, const std::string& word) {
    try {
      learning::Trainer t(settings, learning::load_dataset({dagger}));
      ADD_FAILURE() << "accepted; expected an error naming " << word;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(parent), std::string::npos) << e.what();
    }
  };
  learning::TrainingSettings wider = f;
  wider.network.hidden = 48;
  refused(wider, "network");
  learning::TrainingSettings other_frame = f;
  other_frame.network.target_frame = !f.network.target_frame;
  refused(other_frame, "network");
  learning::TrainingSettings bc = f;
  bc.variant = io::Variant::bc;
  refused(bc, "variant");
  learning::TrainingSettings missing = f;
  missing.initial_model = path("no-such-model.safetensors");
  EXPECT_THROW(learning::Trainer(missing, learning::load_dataset({dagger})), io::InputError);
}

namespace {

// Batch norm over the processes' rows (normalize_batch with a BatchSum, as data-parallel training uses it):
// with one process (the sum of one is the identity) it must be torch's own batch norm, in its output, its
// gradients and its running statistics. Two batch norms start equal; one runs torch's, the other ours.
TEST(DistributedBatchNorm, OneProcessIsTorchsBatchNorm) {
  torch::manual_seed(3);
  auto options = torch::nn::BatchNorm1dOptions(5).eps(1e-5);
  torch::nn::BatchNorm1d ours(options), torchs(options);
  {
    torch::NoGradGuard no_grad;
    torchs->weight.copy_(torch::rand({5}) + 0.5);
    torchs->bias.copy_(torch::randn({5}));
    ours->weight.copy_(torchs->weight);
    ours->bias.copy_(torchs->bias);
  }
  const torch::Tensor x = torch::randn({12, 5}) * 3 + 1;
  const torch::Tensor weights = torch::randn({12, 5});  // a loss that is not symmetric in the rows
  const learning::BatchSum identity = [](const torch::Tensor& t) { return t; };
  torch::Tensor x_ours = x.clone().requires_grad_(true), x_torchs = x.clone().requires_grad_(true);
  const torch::Tensor y_ours = learning::normalize_batch(ours, x_ours, &identity);
  const torch::Tensor y_torchs = torchs->forward(x_torchs);
  EXPECT_TRUE(torch::allclose(y_ours, y_torchs, 1e-5, 1e-5));
  (y_ours * weights).sum().backward();
  (y_torchs * weights).sum().backward();
  EXPECT_TRUE(torch::allclose(x_ours.grad(), x_torchs.grad(), 1e-4, 1e-5));
  EXPECT_TRUE(torch::allclose(ours->weight.grad(), torchs->weight.grad(), 1e-4, 1e-5));
  EXPECT_TRUE(torch::allclose(ours->bias.grad(), torchs->bias.grad(), 1e-4, 1e-5));
  EXPECT_TRUE(torch::allclose(ours->running_mean, torchs->running_mean, 1e-5, 1e-6));
  EXPECT_TRUE(torch::allclose(ours->running_var, torchs->running_var, 1e-5, 1e-6));
  EXPECT_EQ(ours->num_batches_tracked.item<int64_t>(), torchs->num_batches_tracked.item<int64_t>());
  // In eval mode, both use the running statistics alone.
  ours->eval();
  torchs->eval();
  EXPECT_TRUE(torch::allclose(learning::normalize_batch(ours, x, &identity), torchs->forward(x), 1e-5, 1e-5));
}

// A training's random draws are made for the whole batch: a process's rows of them are the rows of the
// whole draw, whatever the other processes take.
TEST(DistributedBatchNorm, PassNoiseRowsAreTheWholeDrawsRows) {
  io::NetworkConfig config;
  torch::manual_seed(11);
  const learning::PassNoise whole = learning::PassNoise::draw(10, config, 0.3, torch::kCPU);
  ASSERT_TRUE(whole.dropout_scale.defined());
  const learning::PassNoise part = whole.rows(3, 7);
  EXPECT_TRUE(torch::equal(part.eps, whole.eps.index({torch::indexing::Slice(3, 7)})));
  EXPECT_TRUE(torch::equal(part.dropout_scale, whole.dropout_scale.index({torch::indexing::Slice(3, 7)})));
  // Dropout keeps a share 1 - p of the units, scaled by 1 / (1 - p).
  const torch::Tensor kept = whole.dropout_scale > 0;
  EXPECT_NEAR(kept.to(torch::kFloat64).mean().item<double>(), 0.7, 0.1);
  EXPECT_TRUE(torch::allclose(whole.dropout_scale.index({kept}), torch::full({1}, 1.0f / 0.7f)));
  torch::manual_seed(11);
  const learning::PassNoise again = learning::PassNoise::draw(10, config, 0.3, torch::kCPU);
  EXPECT_TRUE(torch::equal(again.eps, whole.eps));
  EXPECT_FALSE(learning::PassNoise::draw(10, config, 0.0, torch::kCPU).dropout_scale.defined());
}

}  // namespace
