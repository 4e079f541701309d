// Shared helpers of the test suite.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "occtrack/core/scenario.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::test {

/// An axis-aligned static box obstacle (yaw 0) of full extent `size` centred at `center`.
inline core::ObstacleSpec box(const core::Vec2& center, const core::Vec2& size) {
  core::ObstacleSpec o;
  o.shape = core::ObstacleSpec::Shape::box;
  o.center = center;
  o.size = size;
  return o;
}

/// A path in the system's temporary folder for file NAME, unique to this process (tests run in parallel).
inline std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("occtrack_test_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

#ifdef OCCTRACK_CONFORMANCE_DIRS
/// The conformance case files (*.json) of the folders in OCCTRACK_CONFORMANCE_DIRS ('|'-separated; missing
/// folders are skipped), sorted.
inline std::vector<std::string> conformance_case_files() {
  std::vector<std::string> files;
  std::stringstream dirs(OCCTRACK_CONFORMANCE_DIRS);
  std::string dir;
  while (std::getline(dirs, dir, '|')) {
    if (!std::filesystem::is_directory(dir)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      if (entry.path().extension() == ".json") files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}
#endif

/// Worst |a - b| / max(1, |b|): relative for entries above 1, absolute below. Non-finite counts as infinite.
template <typename A, typename B>
double worst_error(const A& got, const B& expected) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < expected.rows(); ++i)
    for (Eigen::Index j = 0; j < expected.cols(); ++j) {
      const double g = static_cast<double>(got(i, j)), e = static_cast<double>(expected(i, j));
      worst = std::max(worst, std::isfinite(g) ? std::abs(g - e) / std::max(1.0, std::abs(e)) : INFINITY);
    }
  return worst;
}

template <typename To, typename From>
projection::Problem<To> cast_problem(const projection::Problem<From>& p) {
  projection::Problem<To> q;
  q.robot_velocity = p.robot_velocity.template cast<To>();
  q.obstacles = p.obstacles.template cast<To>();
  q.target = p.target.template cast<To>();
  q.terminal = p.terminal.template cast<To>();
  q.via_points = p.via_points.template cast<To>();
  q.lambda0 = p.lambda0.template cast<To>();
  q.distance_min = p.distance_min.template cast<To>();
  q.distance_max = p.distance_max.template cast<To>();
  q.xi_bar = p.xi_bar.template cast<To>();
  return q;
}

}  // namespace occtrack::test
