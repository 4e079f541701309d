#include "occtrack/projection/problem_generator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace occtrack::projection {

namespace {

struct Point {
  double x, y, vx, vy;
};

}  // namespace

template <typename T>
void fill_random_problem(const Settings& s, const RandomProblemOptions& options, Problem<T>& problem) {
  std::mt19937_64 rng(options.seed);
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  auto normal = [&](double sigma) { return std::normal_distribution<double>(0.0, sigma)(rng); };
  const double pi = std::numbers::pi;
  problem.resize(s);
  const int n = s.coefficients(), m = s.steps, D = s.degree;

  // The world: cylinders 1.2 to 7 m away, scanned on the side that faces the robot.
  std::vector<Point> scan;
  const int cylinders = 4 + static_cast<int>(uniform(0, 5));
  for (int c = 0; c < cylinders; ++c) {
    const double radius = uniform(0.3, 0.8);
    const double distance = uniform(1.2 + radius, 7.0);
    const double bearing = uniform(-pi, pi);
    const double cx = distance * std::cos(bearing), cy = distance * std::sin(bearing);
    const bool moving = uniform(0, 1) < options.moving_share;
    const double heading = uniform(-pi, pi);
    const double vx = moving ? 0.7 * std::cos(heading) : 0.0, vy = moving ? 0.7 * std::sin(heading) : 0.0;
    const int points = 12 + static_cast<int>(uniform(0, 20));
    for (int i = 0; i < points; ++i) {
      const double angle = bearing + pi + uniform(-0.45 * pi, 0.45 * pi);
      scan.push_back({cx + radius * std::cos(angle), cy + radius * std::sin(angle), vx, vy});
    }
  }
  std::sort(scan.begin(), scan.end(),
            [](const Point& a, const Point& b) { return a.x * a.x + a.y * a.y < b.x * b.x + b.y * b.y; });
  while (static_cast<int>(scan.size()) < s.obstacles) scan.push_back(scan.front());  // pad like perception

  // The robot and the target.
  const double robot_speed = uniform(0.0, 1.5), robot_heading = uniform(-pi, pi);
  const double target_distance = uniform(1.5, 3.5), target_bearing = uniform(-pi, pi);
  const double target_speed = uniform(0.0, 1.5), target_heading = uniform(-pi, pi);
  const double xr = target_distance * std::cos(target_bearing), yr = target_distance * std::sin(target_bearing);
  const double vxr = target_speed * std::cos(target_heading), vyr = target_speed * std::sin(target_heading);
  // Where the robot should be at the end: 2 m behind the target's predicted position.
  const double xe = xr + vxr * s.horizon, ye = yr + vyr * s.horizon;
  const double back = std::hypot(xe, ye) > 1e-6 ? 2.0 / std::hypot(xe, ye) : 0.0;
  const double xf = xe * (1.0 - back), yf = ye * (1.0 - back);

  for (int b = 0; b < s.batch; ++b) {
    problem.robot_velocity(b, 0) = T(robot_speed * std::cos(robot_heading));
    problem.robot_velocity(b, 1) = T(robot_speed * std::sin(robot_heading));
    for (int j = 0; j < s.obstacles; ++j) {
      problem.obstacles(b, 4 * j + 0) = T(scan[j].x);
      problem.obstacles(b, 4 * j + 1) = T(scan[j].y);
      problem.obstacles(b, 4 * j + 2) = T(scan[j].vx);
      problem.obstacles(b, 4 * j + 3) = T(scan[j].vy);
    }
    problem.target.row(b) << T(xr), T(yr), T(vxr), T(vyr);
    // Terminal and via points away from the obstacle disks (they are constraints, and a planner would not
    // ask for a position inside an obstacle); redrawn a few times, then kept as they are.
    auto clear = [&](double x, double y) {
      for (const Point& p : scan)
        if (std::hypot(x - p.x, y - p.y) < s.obstacle_radius + 0.3) return false;
      return true;
    };
    const double f1 = double(s.via_step_1) / (m - 1), f2 = double(s.via_step_2) / (m - 1);
    double txf = 0, tyf = 0, x1 = 0, y1 = 0, x2 = 0, y2 = 0;
    for (int attempt = 0; attempt < 50; ++attempt) {
      txf = xf + normal(1.0);
      tyf = yf + normal(1.0);
      x1 = f1 * txf + normal(0.5);
      y1 = f1 * tyf + normal(0.5);
      x2 = f2 * txf + normal(0.5);
      y2 = f2 * tyf + normal(0.5);
      if (clear(txf, tyf) && clear(x1, y1) && clear(x2, y2)) break;
    }
    problem.terminal.row(b) << T(txf), T(tyf), T(std::clamp(vxr + normal(0.3), -s.speed_max, s.speed_max)),
        T(std::clamp(vyr + normal(0.3), -s.speed_max, s.speed_max));
    problem.via_points.row(b) << T(x1), T(y1), T(x2), T(y2);
    for (int i = 0; i < 2 * n; ++i) problem.lambda0(b, i) = T(normal(0.1));
    const double d_min = 1.0 + uniform(0.0, 0.5), d_max = d_min + uniform(1.0, 2.5);
    problem.distance_min.row(b).setConstant(T(d_min));
    problem.distance_max.row(b).setConstant(T(d_max));
    for (int i = 0; i < n; ++i) {
      const double f = double(i) / D;
      problem.xi_bar(b, i) = T(f * txf + (i == 0 ? 0.0 : normal(0.3)));
      problem.xi_bar(b, n + i) = T(f * tyf + (i == 0 ? 0.0 : normal(0.3)));
    }
  }
}

template void fill_random_problem<float>(const Settings&, const RandomProblemOptions&, Problem<float>&);
template void fill_random_problem<double>(const Settings&, const RandomProblemOptions&, Problem<double>&);

}  // namespace occtrack::projection
