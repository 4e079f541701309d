// occtrack bench train-step [--batch 256] [--iterations 20,50] [--obstacles 60] [--device cpu|cuda]
//                           [--repeats 20] [--threads T] [--variant cvae|fixed-q] [--json]
//
// Times one whole training step (forward through the networks and the K unrolled projection iterations,
// loss, backward, Adam) on synthetic rows of the right shapes, with the hand-written projection backward
// (project_fast) and with autograd through the plain loop (project_plain), side by side, and their ratio.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "../commands.hpp"
#include "allocation.hpp"
#include "learning/dataset.hpp"
#include "learning/trainer.hpp"

namespace occtrack::app {

namespace {

struct BenchTrainOptions {
  int64_t batch = 256;
  std::vector<int> iterations = {20, 50};
  int obstacles = 60;
  int cloud_points = 200;
  std::string device = "cpu";
  std::string variant = "cvae";
  int repeats = 20;
  int warmup = 2;
  int threads = 0;
  bool skip_plain = false;
  bool json = false;
};

struct StepTiming {
  double median_ms = 0, min_ms = 0, mean_ms = 0;
  double loss = 0;
};

void synchronize(torch::Device device) {
  if (device.is_cuda()) torch::cuda::synchronize(device.has_index() ? device.index() : -1);
}

StepTiming time_steps(const learning::Dataset& data, const learning::Batch& batch, const BenchTrainOptions& o,
                      learning::Variant variant, int iterations, bool plain, torch::Device device) {
  learning::NetworkConfig network;
  network.cloud_points = o.cloud_points;
  network.nearest_points = o.obstacles;
  network.coefficients = data.coefficients();
  network.steps = data.projection.steps;
  torch::manual_seed(1);
  learning::Cvae model(network);
  model->set_normalization(learning::compute_normalization(
      data, torch::arange(data.rows(), torch::kInt64), network, core::TrackingBand{}));
  model->to(device);
  model->train();
  torch::optim::Adam optimizer(model->parameters(), torch::optim::AdamOptions(1e-3));
  const learning::LossContext context(variant, data.projection, core::TrackingBand{},
                                      network, iterations, plain, device);
  std::vector<double> ms;
  double loss = 0;
  for (int r = 0; r < o.warmup + o.repeats; ++r) {
    synchronize(device);
    const auto start = std::chrono::steady_clock::now();
    optimizer.zero_grad();
    const learning::LossTensors l = learning::batch_loss(*model, batch, context, 1e-3);
    l.total.backward();
    optimizer.step();
    synchronize(device);
    const double elapsed = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (r >= o.warmup) ms.push_back(elapsed);
    loss = l.total.item<double>();
  }
  std::sort(ms.begin(), ms.end());
  StepTiming t;
  t.median_ms = ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
  t.min_ms = ms.front();
  for (double x : ms) t.mean_ms += x / ms.size();
  t.loss = loss;
  return t;
}

int run(const BenchTrainOptions& o) {
  keep_large_allocations();
  if (o.threads > 0) torch::set_num_threads(o.threads);
  torch::Device device(o.device);
  if (device.is_cuda() && !torch::cuda::is_available()) {
    std::cerr << "occtrack bench train-step: --device " << o.device << ": CUDA is not available\n";
    return kExitInputError;
  }
  const learning::Variant variant = learning::parse_variant(o.variant);
  projection::Settings settings;
  learning::SyntheticDatasetOptions synthetic;
  synthetic.rows = o.batch;
  synthetic.episodes = 1;
  synthetic.cloud_points = o.cloud_points;
  synthetic.nearest_points = o.obstacles;
  const learning::Dataset data = learning::synthetic_dataset(synthetic, settings);
  const learning::Batch batch = data.gather(torch::arange(data.rows(), torch::kInt64), device);
  const std::string hardware = learning::hardware_description(device);

  nlohmann::json results = nlohmann::json::array();
  // The same step without the projection (BC): what the networks alone cost.
  const StepTiming networks = time_steps(data, batch, o, learning::Variant::bc, 1, false, device);
  if (!o.json) {
    std::printf("training step (%s), batch %lld, %d obstacle points, %d cloud points, on %s\n", o.variant.c_str(),
                static_cast<long long>(o.batch), o.obstacles, o.cloud_points, hardware.c_str());
    std::printf("  networks only (bc, no projection): median %.1f ms (min %.1f)\n", networks.median_ms,
                networks.min_ms);
  }
  for (int k : o.iterations) {
    const StepTiming fast = time_steps(data, batch, o, variant, k, false, device);
    StepTiming plain;
    if (!o.skip_plain) plain = time_steps(data, batch, o, variant, k, true, device);
    if (o.json) {
      nlohmann::json r = {{"iterations", k}, {"fast", {{"median_ms", fast.median_ms}, {"min_ms", fast.min_ms}}}};
      if (!o.skip_plain) {
        r["plain"] = {{"median_ms", plain.median_ms}, {"min_ms", plain.min_ms}};
        r["plain_over_fast"] = plain.median_ms / fast.median_ms;
      }
      results.push_back(r);
    } else {
      std::printf("  K = %3d: fast median %.1f ms (min %.1f)", k, fast.median_ms, fast.min_ms);
      if (!o.skip_plain)
        std::printf(", plain median %.1f ms (min %.1f); plain / fast = %.2f", plain.median_ms, plain.min_ms,
                    plain.median_ms / fast.median_ms);
      std::printf("  [%d steps each]\n", o.repeats);
    }
  }
  if (o.json) {
    const nlohmann::json out = {{"benchmark", "train-step"}, {"variant", o.variant},    {"batch", o.batch},
                                {"obstacles", o.obstacles},  {"cloud_points", o.cloud_points},
                                {"device", device.str()},    {"hardware", hardware}, {"threads", torch::get_num_threads()},
                                {"repeats", o.repeats},
                                {"networks_only", {{"median_ms", networks.median_ms}, {"min_ms", networks.min_ms}}},
                                {"results", results}};
    std::cout << out.dump() << "\n";
  }
  return kExitOk;
}

}  // namespace

void add_bench_train_command(CLI::App& bench, int& exit_code) {
  auto o = std::make_shared<BenchTrainOptions>();
  CLI::App* cmd = bench.add_subcommand(
      "train-step", "Time one training step (forward, loss, backward, Adam) with the fast and the plain projection");
  cmd->add_option("--batch", o->batch, "Rows per step")->check(CLI::Range(int64_t{1}, int64_t{1} << 20))->capture_default_str();
  cmd->add_option("--iterations", o->iterations, "Projection iterations K (a list: 20,50)")
      ->delimiter(',')
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--obstacles", o->obstacles, "Obstacle points per row (N)")->check(CLI::Range(0, 100000))->capture_default_str();
  cmd->add_option("--cloud-points", o->cloud_points, "Cloud points per row (C)")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--device", o->device, "cpu, cuda or cuda:I")->capture_default_str();
  cmd->add_option("--variant", o->variant, "cvae or fixed-q (bc has no projection: its time is the 'networks only' line)")
      ->check(CLI::IsMember({"cvae", "fixed-q"}))
      ->capture_default_str();
  cmd->add_option("--repeats", o->repeats, "Timed steps per configuration")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--warmup", o->warmup, "Untimed steps first")->check(CLI::Range(0, 1000))->capture_default_str();
  cmd->add_option("--threads", o->threads, "CPU threads for torch (0: torch's default)")->check(CLI::Range(0, 1024))->capture_default_str();
  cmd->add_flag("--skip-plain", o->skip_plain, "Time the fast projection only (the plain one needs far more memory)");
  cmd->add_flag("--json", o->json, "Print one JSON object instead of text");
  cmd->callback([o, &exit_code]() {
    try {
      exit_code = run(*o);
    } catch (const std::exception& e) {
      std::cerr << "occtrack bench train-step: " << e.what() << "\n";
      exit_code = kExitInputError;
    }
  });
}

}  // namespace occtrack::app
