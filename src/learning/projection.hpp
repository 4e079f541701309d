// The projection optimizer (shared/spec/projection.md) in batched torch ops, differentiable end to end, for
// training the CVAE policy (docs/learning.md, "Training"). The run-time twin is projection::Projector (Eigen).
//
//   occtrack::learning::ProjectionConstants constants(settings, torch::kFloat, torch::kCUDA);  // once
//   ProjectionInputs in{...};                                  // [B, ...] tensors of that dtype and device
//   ProjectionOutputs out = project_fast(constants, in, 50);   // or project_plain: same values, same gradients
//   loss(out.xi, out.residual).backward();                     // gradients reach terminal, via_points, lambda0,
//                                                              // distance_min, distance_max and xi_bar
//
// Two implementations of the same arithmetic:
//  - project_plain follows the spec one step per line and lets autograd record every op. It is the reference.
//  - project_fast runs the K iterations inside one torch::autograd::Function whose backward is written by
//    hand (reverse mode over the unrolled loop); it keeps only what the backward needs, and visits only the
//    (point, step) pairs inside an obstacle disk. Same values to round-off, same gradients.
//
// Cost (float, B = 256, N = 60, default settings, one CPU thread, forward + backward; see projection_bench):
// project_fast about 70 ms at K = 20 and 150 to 180 ms at K = 50, some 20 times less than project_plain,
// and it holds about 1.4 MB per iteration for the backward (70 MB at K = 50) where project_plain's graph
// holds about 130 MB per iteration (6.7 GB at K = 50). project_fast synchronises with the device twice per
// iteration (nonzero() sizes the obstacle contacts), so on a GPU it is bound by kernel launches up to a few
// thousand samples: larger batches cost almost nothing extra there. Its saved tensors go through
// save_for_backward, so they are freed when backward() returns (unless retain_graph).
//
// Steps 7 to 9 are evaluated in the rearranged form that src/projection/projector.cpp explains, with the
// blocks [M11 M12] of the inverse KKT matrix from projection::KktFactors (occtrack/projection/kkt.hpp): with
// h = -(rho_o P' sum_j r_o,j + rho_r P' r_r + rho_v Pd' r_v + rho_a Pdd' r_a), lambda += h and
// xi_{k+1} = M11 (lambda_{k+1} + h) + M11 (Q - rho_p I) xi_k + M11 rho_p xi_bar + M12 b_eq.
//
// unit(0) = (1, 0): as in the Eigen code, every offset w gets `nudge` added to its x entry and its norm is
// taken as sqrt(max(|w|^2, nudge^2)), so values and gradients stay finite. The gradient of unit(w) is
// (I - u u') / |w|, unbounded as w -> 0; where |w| < direction_gradient_floor the direction is held
// constant in the backward pass (its value is still the exact w / |w|). Robot trajectories pinned to v0 = 0
// at t = 0 touch this case every iteration; without the floor their gradient overflows in float.
//
// Shapes use B samples, N obstacle points, n = degree + 1 coefficients per axis, m steps. Coefficient
// vectors are [x coefficients, y coefficients] (2n), as in the case files and the model's outputs.
#pragma once

#include <torch/torch.h>

#include "occtrack/projection/projector.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::learning {

/// Everything that depends on the settings only, built once in double and cast to the working dtype. No
/// learnable values. Settings::obstacles fixes N (the KKT matrix holds rho_o N P'P); Settings::batch and
/// Settings::iterations are not used (the inputs give B, the call gives K).
struct ProjectionConstants {
  /// Throws std::invalid_argument when the settings are unusable (Settings::validate's message) or the dtype
  /// is neither float nor double.
  ProjectionConstants(const projection::Settings& settings, torch::Dtype dtype, torch::Device device);

  projection::Settings settings;
  int coefficients = 0;  ///< n
  int steps = 0;         ///< m
  int obstacles = 0;     ///< N

  torch::Tensor times;     ///< [m]: t_k
  torch::Tensor P;         ///< [m, n]: positions
  torch::Tensor Pd;        ///< [m, n]: first time derivative
  torch::Tensor Pdd;       ///< [m, n]: second time derivative
  torch::Tensor basis;     ///< [3m, n]: [P; Pd; Pdd], the whole of step 1 in one product

  /// [n, 6]: the initial guess of one axis, xi_0 = initial_guess (0, v0, x_f, vx_f, x_1, x_2)' (the top-right
  /// block of the inverse of the initial guess's KKT matrix; spec "Initial guess").
  torch::Tensor initial_guess;
  /// [n, n] and [n, 4]: the top rows [M11 M12] of the inverse of step 9's KKT matrix [[Q, A_eq'], [A_eq, 0]].
  torch::Tensor kkt_inverse_11, kkt_inverse_12;
  /// [n, n]: M11 (Q - rho_p I), the part of step 9 that multiplies xi_k.
  torch::Tensor kkt_inverse_11_q;

  double nudge = 0.0;  ///< added to the x entry of every offset: 1e-18 in float, 1e-150 in double
  double tiny = 0.0;   ///< nudge^2: the floor of every squared norm
  /// Below this norm the direction unit(w) is held constant in the backward pass: 1e-6 in float, 1e-12 in
  /// double (metres, or m/s, m/s^2). Values are unaffected. Set it before a call to change it.
  double direction_gradient_floor = 0.0;

  torch::TensorOptions options() const { return basis.options(); }
};

/// One batch. Every tensor has the constants' dtype and device. Gradients flow to terminal, via_points,
/// lambda0, distance_min, distance_max and xi_bar when they require them; robot_velocity, obstacles and
/// target are treated as data.
struct ProjectionInputs {
  torch::Tensor robot_velocity;  ///< [B, 2]: (vx, vy)
  torch::Tensor obstacles;       ///< [B, N, 4]: (x, y, vx, vy) per point, predicted linearly
  torch::Tensor target;          ///< [B, 4]: (x, y, vx, vy), predicted linearly
  torch::Tensor terminal;        ///< [B, 4]: (x_f, y_f, vx_f, vy_f)
  torch::Tensor via_points;      ///< [B, 4]: (x_1, y_1, x_2, y_2) at the via steps s1, s2
  torch::Tensor lambda0;         ///< [B, 2n]
  torch::Tensor distance_min;    ///< [B, m]
  torch::Tensor distance_max;    ///< [B, m]
  torch::Tensor xi_bar;          ///< [B, 2n]
};

struct ProjectionOutputs {
  torch::Tensor xi;        ///< [B, 2n]: xi_K
  torch::Tensor xi_init;   ///< [B, 2n]: xi_0
  torch::Tensor residual;  ///< [B]: mean over the K iterations of the step-6 residual
};

/// Throws std::invalid_argument naming the field when an input has the wrong shape, dtype or device, or is
/// undefined. Both project functions call it first.
void check_inputs(const ProjectionConstants& constants, const ProjectionInputs& inputs);

/// The reference: the spec step by step in batched torch ops, differentiated by autograd. iterations >= 1.
ProjectionOutputs project_plain(const ProjectionConstants& constants, const ProjectionInputs& inputs,
                                int iterations);

/// The same values and gradients, with the loop's backward written by hand (faster, far less memory).
/// iterations >= 1. Not twice differentiable (the backward is not itself recorded).
ProjectionOutputs project_fast(const ProjectionConstants& constants, const ProjectionInputs& inputs,
                               int iterations);

/// The inputs of an Eigen problem (projection::Problem, e.g. from a case file) as tensors of the constants'
/// dtype and device, leaves without requires_grad. Its obstacles must number constants.obstacles.
ProjectionInputs to_projection_inputs(const projection::Problem<double>& problem,
                                      const ProjectionConstants& constants);

}  // namespace occtrack::learning
