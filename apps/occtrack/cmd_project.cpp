// occtrack project CASE.json [--precision double|float] [--out RESULT.json] [--tolerance X]
//
// Solves a projection case file (shared/spec/projection.md) and writes {"xi_init", "xi", "residual"}. When
// the case holds expected outputs, prints the worst error against them and fails when it is over tolerance.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "cli_support.hpp"
#include "commands.hpp"
#include "occtrack/core/bernstein.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::app {

namespace {

struct Options {
  std::string case_path;
  std::string precision = "double";
  std::string out_path;
  double tolerance = -1.0;  // < 0: the default of the precision
};

// Worst |got - expected| / max(1, |expected|): relative for large entries, absolute for small ones.
template <typename M, typename E>
double worst_error(const M& got, const E& expected) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < expected.rows(); ++i)
    for (Eigen::Index j = 0; j < expected.cols(); ++j) {
      const double e = expected(i, j), g = static_cast<double>(got(i, j));
      const double err = std::isfinite(g) ? std::abs(g - e) / std::max(1.0, std::abs(e)) : INFINITY;
      worst = std::max(worst, err);
    }
  return worst;
}

// What a robotics user wants to know about each projected trajectory: is it clear of the obstacles, within
// the speed and acceleration bounds, and at a sensible distance from the target?
template <typename T>
void print_summary(std::ostream& out, const io::ProjectionCase& c, const projection::Result<T>& result,
                   double solve_ms) {
  const auto& s = c.settings;
  const auto basis = core::bernstein_basis(s.degree, s.steps, s.horizon);
  const int n = s.coefficients();
  char line[256];
  out << "case " << (c.name.empty() ? std::string("(unnamed)") : c.name) << ": " << s.batch << " samples, "
      << s.obstacles << " obstacle points, " << s.iterations << " iterations, solved in ";
  std::snprintf(line, sizeof line, "%.3f ms (%s)\n", solve_ms, projection::to_string(result.status));
  out << line;
  out << " sample  mean_residual  clearance_m (nominal -> projected)  speed_max  accel_max  target_dist_m\n";
  const int shown = std::min(s.batch, 12);
  // Clearance of a trajectory: distance to the nearest obstacle disk over the horizon (negative = inside).
  auto clearance = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& y, int b) {
    double c_min = INFINITY;
    for (int k = 0; k < s.steps; ++k)
      for (int j = 0; j < s.obstacles; ++j) {
        const double t = basis.times(k);
        const double ox = c.problem.obstacles(b, 4 * j) + c.problem.obstacles(b, 4 * j + 2) * t;
        const double oy = c.problem.obstacles(b, 4 * j + 1) + c.problem.obstacles(b, 4 * j + 3) * t;
        c_min = std::min(c_min, std::hypot(x(k) - ox, y(k) - oy) - s.obstacle_radius);
      }
    return c_min;
  };
  for (int b = 0; b < shown; ++b) {
    const Eigen::VectorXd cx = result.xi.row(b).head(n).transpose().template cast<double>();
    const Eigen::VectorXd cy = result.xi.row(b).tail(n).transpose().template cast<double>();
    const Eigen::VectorXd x = basis.P * cx, y = basis.P * cy;
    const Eigen::VectorXd vx = basis.Pd * cx, vy = basis.Pd * cy;
    const Eigen::VectorXd ax = basis.Pdd * cx, ay = basis.Pdd * cy;
    const Eigen::VectorXd nx = basis.P * c.problem.xi_bar.row(b).head(n).transpose();
    const Eigen::VectorXd ny = basis.P * c.problem.xi_bar.row(b).tail(n).transpose();
    double dist_min = INFINITY, dist_max = 0.0;
    for (int k = 0; k < s.steps; ++k) {
      const double t = basis.times(k);
      const double d = std::hypot(x(k) - c.problem.target(b, 0) - c.problem.target(b, 2) * t,
                                  y(k) - c.problem.target(b, 1) - c.problem.target(b, 3) * t);
      dist_min = std::min(dist_min, d);
      dist_max = std::max(dist_max, d);
    }
    const double speed = (vx.array().square() + vy.array().square()).sqrt().maxCoeff();
    const double accel = (ax.array().square() + ay.array().square()).sqrt().maxCoeff();
    std::snprintf(line, sizeof line, " %6d  %13.4f  %14.3f -> %-17.3f  %9.3f  %9.3f  %5.2f..%-5.2f\n", b,
                  static_cast<double>(result.residual(b)), clearance(nx, ny, b), clearance(x, y, b), speed, accel,
                  dist_min, dist_max);
    out << line;
  }
  if (shown < s.batch) out << " (" << s.batch - shown << " more samples not shown)\n";
  out << " clearance_m: distance to the nearest obstacle disk of the nominal trajectory xi_bar and of the\n"
      << " projected one (negative = inside); bounds: speed "
      << s.speed_min << ".." << s.speed_max << " m/s, acceleration " << s.accel_max << " m/s^2\n";
}

template <typename T>
int run(const Options& o) {
  const io::ProjectionCase c = io::read_projection_case(o.case_path);
  projection::Projector<T> projector(c.settings);
  projection::Problem<T> problem = projector.make_problem();
  problem.robot_velocity = c.problem.robot_velocity.cast<T>();
  problem.obstacles = c.problem.obstacles.cast<T>();
  problem.target = c.problem.target.cast<T>();
  problem.terminal = c.problem.terminal.cast<T>();
  problem.via_points = c.problem.via_points.cast<T>();
  problem.lambda0 = c.problem.lambda0.cast<T>();
  problem.distance_min = c.problem.distance_min.cast<T>();
  problem.distance_max = c.problem.distance_max.cast<T>();
  problem.xi_bar = c.problem.xi_bar.cast<T>();
  projection::Result<T> result = projector.make_result();
  std::string error;
  const auto start = std::chrono::steady_clock::now();
  if (!projector.solve(problem, result, &error)) {
    // Values that fit in double but not in float (or became non-finite in the cast) end here.
    std::cerr << "occtrack project: " << o.case_path << ": " << error << "\n";
    return kExitInputError;
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  const std::string json = io::projection_result_json(result, 1);
  std::ostream& report = o.out_path.empty() ? std::cerr : std::cout;
  if (o.out_path.empty()) {
    std::cout << json << "\n";
  } else {
    std::ofstream file(o.out_path);
    if (!(file << json << "\n")) {
      std::cerr << "occtrack project: " << o.out_path << ": cannot write the result file\n";
      return kExitInputError;
    }
  }
  print_summary(report, c, result, ms);
  if (!o.out_path.empty()) report << "result written to " << o.out_path << "\n";
  if (result.status != projection::SolveStatus::solved) {
    std::cerr << "occtrack project: the solve produced non-finite values\n";
    return kExitSolveFailed;
  }
  if (!c.expected) return kExitOk;

  const bool is_double = sizeof(T) == 8;
  const double tolerance = o.tolerance >= 0 ? o.tolerance : (is_double ? 1e-9 : 5e-2);
  const double e_init = worst_error(result.xi_init, c.expected->xi_init);
  const double e_xi = worst_error(result.xi, c.expected->xi);
  const double e_res = worst_error(result.residual, c.expected->residual);
  const double worst = std::max({e_init, e_xi, e_res});
  char line[256];
  std::snprintf(line, sizeof line,
                "worst error against expected (|got - expected| / max(1, |expected|)): xi_init %.3e, xi %.3e, "
                "residual %.3e; tolerance %.1e: %s\n",
                e_init, e_xi, e_res, tolerance, worst <= tolerance ? "PASS" : "FAIL");
  report << line;
  return worst <= tolerance ? kExitOk : kExitMismatch;
}

}  // namespace

void add_project_command(CLI::App& app, int& exit_code) {
  auto [cmd, options] =
      add_command<Options>(app, "project", "Solve a projection case file and compare it with its expected outputs");
  cmd->add_option("case", options->case_path, "Case file (occtrack.projection-case.v1 JSON)")->required();
  add_choice_option(cmd, "--precision", options->precision, "Arithmetic of the solve", {"double", "float"});
  cmd->add_option("--out", options->out_path, "Write the result JSON here instead of standard output");
  cmd->add_option("--tolerance", options->tolerance,
                  "Largest accepted error against expected (default 1e-9 for double, 5e-2 for float)")
      ->check(CLI::NonNegativeNumber);
  set_command_body(cmd, exit_code, [options] {
    return options->precision == "float" ? run<float>(*options) : run<double>(*options);
  });
}

}  // namespace occtrack::app
