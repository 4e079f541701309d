#include "learning/projection_bench.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <vector>

#include "learning/projection.hpp"
#include "occtrack/projection/problem_generator.hpp"

namespace occtrack::learning {

double time_projection_step(bool fast, int batch, int iterations, int obstacles, torch::Device device,
                            int repeats) {
  if (repeats < 1) throw std::invalid_argument("time_projection_step: repeats must be at least 1");
  if (iterations < 1) throw std::invalid_argument("time_projection_step: iterations must be at least 1");
  projection::Settings settings;
  settings.batch = batch;
  settings.obstacles = obstacles;
  settings.iterations = iterations;
  const ProjectionConstants constants(settings, torch::kFloat, device);  // validates the sizes

  projection::Problem<double> problem;
  projection::fill_random_problem(settings, {1, 1.0 / 3.0}, problem);
  const ProjectionInputs data = to_projection_inputs(problem, constants);
  torch::manual_seed(1);
  const torch::Tensor weights = torch::randn({batch, 2 * constants.coefficients}, constants.options());

  const auto project = fast ? project_fast : project_plain;
  const auto synchronize = [&] {
    if (device.is_cuda()) torch::cuda::synchronize(device.index());
  };
  auto step = [&] {
    ProjectionInputs in = data;
    for (torch::Tensor* leaf : {&in.terminal, &in.via_points, &in.lambda0, &in.distance_min, &in.distance_max,
                                &in.xi_bar})
      *leaf = leaf->detach().clone().requires_grad_(true);
    const ProjectionOutputs out = project(constants, in, iterations);
    const torch::Tensor loss = (out.xi * weights).mean() + 0.5 * out.residual.mean();
    loss.backward();
  };

  step();  // warm-up: allocator, kernels, lazy initialisation
  synchronize();
  std::vector<double> milliseconds;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    step();
    synchronize();
    milliseconds.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  std::nth_element(milliseconds.begin(), milliseconds.begin() + milliseconds.size() / 2, milliseconds.end());
  return milliseconds[milliseconds.size() / 2];
}

}  // namespace occtrack::learning
