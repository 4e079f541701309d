// Timing of one training step's projection (forward and backward), for `occtrack bench train-step`.
#pragma once

#include <torch/torch.h>

namespace occtrack::learning {

/// Median wall-clock milliseconds, over `repeats` timed runs after one warm-up, of project_fast (fast = true)
/// or project_plain on a random plausible batch (projection::fill_random_problem, seed 1, a third of the
/// obstacles moving), float32, the default projection settings with the given batch and obstacle count,
/// followed by backward() of a loss on xi and the residual, with gradients reaching every learnable input.
/// CUDA work is synchronised before the clock stops. Throws std::invalid_argument on unusable sizes.
double time_projection_step(bool fast, int batch, int iterations, int obstacles, torch::Device device,
                            int repeats);

}  // namespace occtrack::learning
