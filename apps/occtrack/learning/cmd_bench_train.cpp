// occtrack bench train-step [--batch 256] [--iterations 20,50] [--obstacles 60] [--device cpu|cuda]
//                           [--repeats 20] [--threads T] [--variant cvae|fixed-q] [--json]
//
// Times one whole training step (forward through the networks and the K unrolled projection iterations,
// loss, backward, Adam) on synthetic rows of the right shapes, with the hand-written projection backward
// (project_fast) and with autograd through the plain loop (project_plain), side by side, and their ratio.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <utility>

#include "../cli_support.hpp"
#include "../commands.hpp"
#include "allocation.hpp"
#include "occtrack/core/timing.hpp"
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
  core::TimingSummary ms;
  double loss = 0;
};

void synchronize(torch::Device device) {
  if (device.is_cuda()) torch::cuda::synchronize(device.has_index() ? device.index() : -1);
}

StepTiming time_steps(const learning::Dataset& data, const learning::Batch& batch, const BenchTrainOptions& o,
                      io::Variant variant, int iterations, bool plain, torch::Device device) {
  io::NetworkConfig network = io::NetworkConfig::for_projection(data.projection);
  network.cloud_points = o.cloud_points;
  network.nearest_points = o.obstacles;
  torch::manual_seed(1);
  learning::Cvae model(network, learning::TrainingSettings().dropout);
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
  return {core::summarize_timings(std::move(ms)), loss};
}

int run(const BenchTrainOptions& o) {
  keep_large_allocations();
  learning::set_training_threads(o.threads);
  torch::Device device(o.device);
  if (device.is_cuda() && !torch::cuda::is_available()) {
    std::cerr << "occtrack bench train-step: --device " << o.device << ": CUDA is not available\n";
    return kExitInputError;
  }
  const io::Variant variant = io::parse_variant(o.variant);
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
  const StepTiming networks = time_steps(data, batch, o, io::Variant::bc, 1, false, device);
  if (!o.json) {
    std::printf("training step (%s), batch %lld, %d obstacle points, %d cloud points, on %s\n", o.variant.c_str(),
                static_cast<long long>(o.batch), o.obstacles, o.cloud_points, hardware.c_str());
    std::printf("  networks only (bc, no projection): median %.1f ms (min %.1f)\n", networks.ms.median,
                networks.ms.min);
  }
  for (int k : o.iterations) {
    const StepTiming fast = time_steps(data, batch, o, variant, k, false, device);
    StepTiming plain;
    if (!o.skip_plain) plain = time_steps(data, batch, o, variant, k, true, device);
    if (o.json) {
      nlohmann::json r = {{"iterations", k}, {"fast", {{"median_ms", fast.ms.median}, {"min_ms", fast.ms.min}}}};
      if (!o.skip_plain) {
        r["plain"] = {{"median_ms", plain.ms.median}, {"min_ms", plain.ms.min}};
        r["plain_over_fast"] = plain.ms.median / fast.ms.median;
      }
      results.push_back(r);
    } else {
      std::printf("  K = %3d: fast median %.1f ms (min %.1f)", k, fast.ms.median, fast.ms.min);
      if (!o.skip_plain)
        std::printf(", plain median %.1f ms (min %.1f); plain / fast = %.2f", plain.ms.median, plain.ms.min,
                    plain.ms.median / fast.ms.median);
      std::printf("  [%d steps each]\n", o.repeats);
    }
  }
  if (o.json) {
    const nlohmann::json out = {{"benchmark", "train-step"}, {"variant", o.variant},    {"batch", o.batch},
                                {"obstacles", o.obstacles},  {"cloud_points", o.cloud_points},
                                {"device", device.str()},    {"hardware", hardware}, {"threads", torch::get_num_threads()},
                                {"repeats", o.repeats},
                                {"networks_only", {{"median_ms", networks.ms.median}, {"min_ms", networks.ms.min}}},
                                {"results", results}};
    std::cout << out.dump() << "\n";
  }
  return kExitOk;
}

}  // namespace

void add_bench_train_command(CLI::App& bench, int& exit_code) {
  auto [cmd, o] = add_command<BenchTrainOptions>(
      bench, "train-step",
      "Time one training step (forward, loss, backward, Adam) with the fast and the plain projection");
  add_bounded_option(cmd, "--batch", o->batch, "Rows per step", int64_t{1}, int64_t{1} << 20);
  cmd->add_option("--iterations", o->iterations, "Projection iterations K (a list: 20,50)")
      ->delimiter(',')
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  add_bounded_option(cmd, "--obstacles", o->obstacles, "Obstacle points per row (N)", 0, 100000);
  add_bounded_option(cmd, "--cloud-points", o->cloud_points, "Cloud points per row (C)", 1, 100000);
  cmd->add_option("--device", o->device, "cpu, cuda or cuda:I")->capture_default_str();
  add_choice_option(cmd, "--variant", o->variant,
                    "cvae or fixed-q (bc has no projection: its time is the 'networks only' line)",
                    {"cvae", "fixed-q"});
  add_bounded_option(cmd, "--repeats", o->repeats, "Timed steps per configuration", 1, 100000);
  add_bounded_option(cmd, "--warmup", o->warmup, "Untimed steps first", 0, 1000);
  add_bounded_option(cmd, "--threads", o->threads, "CPU threads for torch (0: torch's default)", 0, 1024);
  cmd->add_flag("--skip-plain", o->skip_plain, "Time the fast projection only (the plain one needs far more memory)");
  cmd->add_flag("--json", o->json, "Print one JSON object instead of text");
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
