// occtrack scenario predict FILE|DIR [--target-noise P,V] [--period S] [--seed N] [--json]
//
// How well the target predictor (core/target_predictor.hpp) foresees a scenario's target path, against the
// constant-velocity prediction from the same estimate: the target's path is replayed, one noisy estimate per
// planning period is fed to the predictor (Gaussian noise P m on position and V m/s on velocity, as the
// simulator draws them), and at every estimate after the first second the prediction error is measured
// at 0.5, 1, 2 and 3 s ahead. Prints the mean error of each, per file and for all files together.
#include <array>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "commands.hpp"
#include "occtrack/core/target_predictor.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/sim/world.hpp"
#include "suite_runner.hpp"

namespace occtrack::app {

namespace {

constexpr std::array<double, 4> kHorizons = {0.5, 1.0, 2.0, 3.0};

struct PredictOptions {
  std::string path;
  std::vector<double> target_noise = {0.05, 0.1};
  double period = 0.05;
  std::uint64_t seed = 1;
  bool json = false;
  core::TargetPredictorSettings predictor;
};

/// Sums of prediction errors (m) per horizon, constant velocity and predictor.
struct Errors {
  std::array<double, kHorizons.size()> cv{}, predicted{};
  std::array<long, kHorizons.size()> count{};
  void add(const Errors& o) {
    for (std::size_t h = 0; h < kHorizons.size(); ++h) {
      cv[h] += o.cv[h];
      predicted[h] += o.predicted[h];
      count[h] += o.count[h];
    }
  }
  double mean_cv(std::size_t h) const { return count[h] ? cv[h] / count[h] : 0.0; }
  double mean_predicted(std::size_t h) const { return count[h] ? predicted[h] / count[h] : 0.0; }
};

Errors replay(const core::Scenario& scenario, const PredictOptions& o, std::uint64_t seed) {
  sim::World world(scenario);
  core::TargetPredictor predictor(o.predictor);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  Errors errors;
  const int steps = static_cast<int>(scenario.duration / o.period);
  for (int i = 0; i <= steps; ++i) {
    const double t = i * o.period;
    Eigen::Vector2d p = world.target_position(t), v = world.target_velocity(t);
    const double px = gaussian(rng), py = gaussian(rng), vx = gaussian(rng), vy = gaussian(rng);
    p += o.target_noise[0] * Eigen::Vector2d(px, py);
    v += o.target_noise[1] * Eigen::Vector2d(vx, vy);
    predictor.observe(t, p, v);
    if (t < 1.0) continue;
    for (std::size_t h = 0; h < kHorizons.size(); ++h) {
      const double ahead = kHorizons[h];
      if (t + ahead > scenario.duration) continue;
      const Eigen::Vector2d truth = world.target_position(t + ahead);
      Eigen::Vector2d predicted, velocity;
      predictor.state_at(ahead, predicted, velocity);
      errors.cv[h] += (p + v * ahead - truth).norm();
      errors.predicted[h] += (predicted - truth).norm();
      ++errors.count[h];
    }
  }
  return errors;
}

nlohmann::json errors_json(const std::string& name, const Errors& e) {
  nlohmann::json rows = nlohmann::json::array();
  for (std::size_t h = 0; h < kHorizons.size(); ++h)
    rows.push_back({{"horizon_s", kHorizons[h]},
                    {"constant_velocity_m", e.mean_cv(h)},
                    {"predictor_m", e.mean_predicted(h)},
                    {"predictions", e.count[h]}});
  return {{"file", name}, {"errors", rows}};
}

void print_row(const std::string& name, const Errors& e) {
  std::printf("%-32s", name.c_str());
  for (std::size_t h = 0; h < kHorizons.size(); ++h) {
    const double cv = e.mean_cv(h), p = e.mean_predicted(h);
    std::printf("   %5.2f %5.2f %+4.0f%%", cv, p, cv > 0 ? 100.0 * (p - cv) / cv : 0.0);
  }
  std::printf("\n");
}

int run_predict(const PredictOptions& o) {
  if (o.target_noise.size() != 2 || !(o.target_noise[0] >= 0.0) || !(o.target_noise[1] >= 0.0) ||
      !std::isfinite(o.target_noise[0]) || !std::isfinite(o.target_noise[1]))
    throw std::invalid_argument("--target-noise takes two finite numbers >= 0: position (m), velocity (m/s)");
  if (!(o.period > 0.0) || !std::isfinite(o.period))
    throw std::invalid_argument("--period must be a positive number of seconds");
  namespace fs = std::filesystem;
  const std::vector<fs::path> files = app::file_or_scenario_files(o.path);
  if (!o.json) {
    std::printf("mean error (m) of constant velocity, of the predictor, and the change, at each horizon\n");
    std::printf("%-32s", "file");
    for (const double h : kHorizons) std::printf("   %-18s", (std::to_string(h).substr(0, 3) + " s").c_str());
    std::printf("\n");
  }
  Errors all;
  nlohmann::json rows = nlohmann::json::array();
  std::uint64_t seed = o.seed;
  for (const fs::path& file : files) {
    const core::Scenario scenario = io::read_scenario(file.string());
    const Errors e = replay(scenario, o, seed++);
    all.add(e);
    if (o.json) rows.push_back(errors_json(file.filename().string(), e));
    else print_row(file.filename().string(), e);
  }
  if (o.json) {
    nlohmann::json out = {{"period_s", o.period}, {"target_noise", o.target_noise}, {"files", rows}};
    if (files.size() > 1) out["all"] = errors_json("all", all);
    std::cout << out.dump(2) << "\n";
  } else if (files.size() > 1) {
    print_row("all (" + std::to_string(files.size()) + " files)", all);
  }
  return kExitOk;
}

}  // namespace

void add_scenario_predict_command(CLI::App& scenario, int& exit_code) {
  auto [cmd, o] = add_command<PredictOptions>(
      scenario, "predict",
      "How well the target predictor foresees a scenario's target path (or every *.yaml in a folder), against "
      "constant velocity: noisy estimates once per period, mean error 0.5, 1, 2 and 3 s ahead "
      "(docs/target_prediction.md)");
  cmd->add_option("path", o->path, "Scenario file, or a folder of them")->required();
  cmd->add_option("--target-noise", o->target_noise, "Estimate noise: position m, velocity m/s (default 0.05,0.1)")
      ->delimiter(',')
      ->expected(2);
  cmd->add_option("--period", o->period, "Seconds between estimates (default 0.05, the planning period)");
  cmd->add_option("--seed", o->seed, "Seed of the noise (default 1; file i uses seed + i)");
  cmd->add_option("--window", o->predictor.window, "Predictor: seconds of estimates fitted (default 1)");
  cmd->add_option("--turn-decay", o->predictor.turn_decay, "Predictor: time constant (s) of the turn rate's decay");
  cmd->add_option("--max-turn-rate", o->predictor.max_turn_rate, "Predictor: largest turn rate (rad/s; 0: none)");
  cmd->add_option("--mode-sigma", o->predictor.mode_sigma, "Predictor: error scale (m) in the models' weights");
  cmd->add_flag("--json", o->json, "Print JSON instead of a table");
  set_command_body(cmd, exit_code, [o] { return run_predict(*o); });
}

}  // namespace occtrack::app
