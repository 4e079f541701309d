// Settings of the batched projection optimizer (shared/spec/projection.md, "Notation").
#pragma once

#include <string>

namespace occtrack::projection {

/// Penalty weights rho of the augmented Lagrangian; each multiplies one constraint family.
struct PenaltyWeights {
  double obstacle = 1.0;      ///< rho_o: collision with the obstacle points.
  double velocity = 1.0;      ///< rho_v: speed bounds.
  double acceleration = 1.0;  ///< rho_a: acceleration bound.
  double tracking = 1.0;      ///< rho_r: robot-target distance band.
  double projection = 1.0;    ///< rho_p: pull towards the nominal trajectory xi_bar; must be > 0.

  bool operator==(const PenaltyWeights&) const = default;
};

struct Settings {
  // Trajectory parameterisation.
  int degree = 10;        ///< D, Bernstein degree; each axis has D + 1 coefficients. At least 5, so that the
                          ///< six conditions of the initial guess can all be met.
  int steps = 100;        ///< m, time steps on the horizon, both ends included.
  double horizon = 5.0;   ///< T, seconds.
  int via_step_1 = 49;    ///< s1, step of the first via point of the initial guess; 0 < s1 < s2 < m - 1.
  int via_step_2 = 74;    ///< s2, step of the second via point.

  // Problem sizes.
  int batch = 30;         ///< B, samples solved together.
  int obstacles = 60;     ///< N, obstacle points per sample (the nearest LiDAR points). May be 0.
  int iterations = 50;    ///< K, unrolled iterations; 50 when training, more at run time.

  // Constraint set.
  double obstacle_radius = 0.4;  ///< a, metres: each point is a disk of this radius (robot size included).
  double speed_min = 0.1;        ///< v_min, m/s, lower bound on the speed; 0 <= v_min <= v_max.
  double speed_max = 2.0;        ///< v_max, m/s.
  double accel_max = 2.0;        ///< a_max, m/s^2, bound on the acceleration norm.
  PenaltyWeights rho;

  // Execution.
  int threads = 1;                      ///< Samples are split over this many threads (1 = the caller's only).
  bool record_residual_history = false; ///< Keep the residual of every iteration in Result::residual_history.

  /// Number of coefficients of one axis, n = D + 1.
  int coefficients() const { return degree + 1; }

  /// True when every field holds a usable value. Otherwise false, and *error (when given) names the first
  /// broken field and its rule, for example "speed_min (3) must not exceed speed_max (2)".
  bool validate(std::string* error = nullptr) const;
  /// The defaults with another iteration count (the planners' presets).
  static Settings with_iterations(int count) {
    Settings s;
    s.iterations = count;
    return s;
  }

  bool operator==(const Settings&) const = default;
};

}  // namespace occtrack::projection
