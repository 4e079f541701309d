// Motion statistics of a target's path (include/occtrack/sim/path_stats.hpp, where the definitions are).
#include "occtrack/sim/path_stats.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "generator_support.hpp"
#include "occtrack/core/timing.hpp"

namespace occtrack::sim {

namespace {

// Sorts `values` and returns the nearest-rank percentiles q of them (zeros when empty).
template <std::size_t N>
std::array<double, N> percentiles(std::vector<double> values, const std::array<double, N>& q) {
  std::array<double, N> out{};
  if (values.empty()) return out;
  std::sort(values.begin(), values.end());
  for (std::size_t i = 0; i < N; ++i) out[i] = core::nearest_rank(values, q[i]);
  return out;
}

}  // namespace

void PathSamples::append(const PathSamples& other) {
  duration += other.duration;
  length += other.length;
  speed.insert(speed.end(), other.speed.begin(), other.speed.end());
  acceleration.insert(acceleration.end(), other.acceleration.begin(), other.acceleration.end());
  heading_rate.insert(heading_rate.end(), other.heading_rate.begin(), other.heading_rate.end());
}

PathSamples sample_path(const std::vector<core::TargetWaypoint>& path) {
  PathSamples s;
  if (path.size() < 2) return s;
  const double t0 = path.front().time;
  s.duration = path.back().time - t0;
  const double h = kPathSamplePeriod;
  // Positions every h, walking the waypoints once (the path is linear between them).
  std::vector<core::Vec2> p;
  std::size_t seg = 0;
  for (long k = 0;; ++k) {
    const double t = t0 + static_cast<double>(k) * h;
    if (t > path.back().time + 1e-9) break;
    while (seg + 2 < path.size() && path[seg + 1].time <= t) ++seg;
    const core::TargetWaypoint& a = path[seg];
    const core::TargetWaypoint& b = path[seg + 1];
    const double alpha = std::clamp((t - a.time) / (b.time - a.time), 0.0, 1.0);
    p.push_back(a.position + alpha * (b.position - a.position));
  }
  std::vector<core::Vec2> v;
  for (std::size_t k = 0; k + 1 < p.size(); ++k) {
    v.push_back((p[k + 1] - p[k]) / h);
    s.speed.push_back(v.back().norm());
    s.length += (p[k + 1] - p[k]).norm();
  }
  for (std::size_t k = 0; k + 1 < v.size(); ++k) {
    s.acceleration.push_back((v[k + 1] - v[k]).norm() / h);
    if (s.speed[k] > kMovingSpeed && s.speed[k + 1] > kMovingSpeed) {
      const double turn = generator::wrap_angle(std::atan2(v[k + 1].y(), v[k + 1].x()) - std::atan2(v[k].y(), v[k].x()));
      s.heading_rate.push_back(std::abs(turn) / h);
    }
  }
  return s;
}

PathStats summarize_path(const PathSamples& samples) {
  PathStats r;
  r.duration = samples.duration;
  r.length = samples.length;
  r.speed_samples = static_cast<int>(samples.speed.size());
  r.heading_samples = static_cast<int>(samples.heading_rate.size());
  if (!samples.speed.empty()) {
    r.speed_mean = std::accumulate(samples.speed.begin(), samples.speed.end(), 0.0) /
                   static_cast<double>(samples.speed.size());
    const auto [p90, max] = percentiles(samples.speed, std::array{0.9, 1.0});
    r.speed_p90 = p90;
    r.speed_max = max;
  }
  const auto a = percentiles(samples.acceleration, std::array{0.5, 0.9, 0.99});
  r.acceleration_p50 = a[0], r.acceleration_p90 = a[1], r.acceleration_p99 = a[2];
  const auto w = percentiles(samples.heading_rate, std::array{0.5, 0.9, 0.99});
  r.heading_rate_p50 = w[0], r.heading_rate_p90 = w[1], r.heading_rate_p99 = w[2];
  return r;
}

}  // namespace occtrack::sim
