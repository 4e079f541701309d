#include "occtrack/io/results.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace occtrack::io {

namespace {

using nlohmann::json;

double finite_or_zero(double x) { return std::isfinite(x) ? x : 0.0; }

json metrics_object(const core::EpisodeMetrics& m, bool summary, double success_rate) {
  json j;
  if (!summary) j["scenario"] = m.scenario;
  j["planner"] = m.planner;
  j["duration_s"] = m.duration_s;
  j["occlusion_time_s"] = m.occlusion_time_s;
  if (summary)
    j["success"] = success_rate;
  else
    j["success"] = m.success;
  j["collisions"] = m.collisions;
  j["collision_time_s"] = m.collision_time_s;
  j["min_clearance_m"] = finite_or_zero(m.min_clearance_m);
  j["acceleration"] = {{"mean", m.acceleration.mean}, {"min", m.acceleration.min}, {"max", m.acceleration.max}};
  j["compute_ms"] = {{"mean", m.compute_ms.mean},
                     {"median", m.compute_ms.median},
                     {"p99", m.compute_ms.p99},
                     {"max", m.compute_ms.max}};
  j["tracking_distance"] = {{"mean_m", m.tracking_distance_mean_m}, {"in_band_share", m.tracking_in_band_share}};
  j["target_out_of_range_s"] = m.target_out_of_range_s;
  j["planner_failures"] = m.planner_failures;
  j["cycles"] = m.cycles;
  return j;
}

}  // namespace

SuiteResult summarize_suite(const std::string& suite, const std::string& planner,
                            const std::vector<core::EpisodeMetrics>& episodes) {
  SuiteResult r;
  r.suite = suite;
  r.planner = planner;
  r.episodes = episodes;
  core::EpisodeMetrics& s = r.summary;
  s.scenario = suite;
  s.planner = planner;
  if (episodes.empty()) return r;
  s.min_clearance_m = INFINITY;
  s.acceleration.min = INFINITY;
  std::vector<double> medians;
  double weighted_compute = 0;
  int successes = 0;
  for (const auto& e : episodes) {
    s.duration_s += e.duration_s;
    s.occlusion_time_s += e.occlusion_time_s;
    s.collisions += e.collisions;
    s.collision_time_s += e.collision_time_s;
    s.min_clearance_m = std::min(s.min_clearance_m, e.min_clearance_m);
    s.acceleration.mean += e.acceleration.mean * e.duration_s;
    s.acceleration.min = std::min(s.acceleration.min, e.acceleration.min);
    s.acceleration.max = std::max(s.acceleration.max, e.acceleration.max);
    weighted_compute += e.compute_ms.mean * e.cycles;
    medians.push_back(e.compute_ms.median);
    s.compute_ms.p99 = std::max(s.compute_ms.p99, e.compute_ms.p99);
    s.compute_ms.max = std::max(s.compute_ms.max, e.compute_ms.max);
    s.tracking_distance_mean_m += e.tracking_distance_mean_m * e.duration_s;
    s.tracking_in_band_share += e.tracking_in_band_share * e.duration_s;
    s.target_out_of_range_s += e.target_out_of_range_s;
    s.planner_failures += e.planner_failures;
    s.cycles += e.cycles;
    successes += e.success;
  }
  const double total = std::max(s.duration_s, 1e-12);
  s.acceleration.mean /= total;
  s.tracking_distance_mean_m /= total;
  s.tracking_in_band_share /= total;
  s.compute_ms.mean = s.cycles > 0 ? weighted_compute / s.cycles : 0.0;
  std::sort(medians.begin(), medians.end());
  const std::size_t n = medians.size();
  s.compute_ms.median = n % 2 ? medians[n / 2] : 0.5 * (medians[n / 2 - 1] + medians[n / 2]);
  r.success_rate = double(successes) / episodes.size();
  s.success = successes == static_cast<int>(episodes.size());
  return r;
}

std::string episode_json(const core::EpisodeMetrics& metrics, int indent) {
  return metrics_object(metrics, false, 0.0).dump(indent);
}

std::string suite_json(const SuiteResult& result, int indent) {
  json j;
  j["suite"] = result.suite;
  j["planner"] = result.planner;
  j["episodes"] = json::array();
  for (const auto& e : result.episodes) j["episodes"].push_back(metrics_object(e, false, 0.0));
  j["summary"] = metrics_object(result.summary, true, result.success_rate);
  return j.dump(indent);
}

std::string suite_table(const std::vector<SuiteResult>& results) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "| %-16s | %-14s | %8s | %-28s | %-26s | %-26s | %10s | %9s |\n", "suite", "planner",
                "episodes", "occlusion time (s) / success", "acceleration mean/min/max", "compute ms median/p99/max",
                "collisions", "in band");
  out += line;
  out += "|------------------|----------------|----------|------------------------------|----------------------------|"
         "----------------------------|------------|-----------|\n";
  for (const auto& r : results) {
    const auto& s = r.summary;
    char occlusion[64], accel[64], compute[64];
    std::snprintf(occlusion, sizeof occlusion, "%.1f / %.2f", s.occlusion_time_s, r.success_rate);
    std::snprintf(accel, sizeof accel, "%.2f / %.2f / %.2f", s.acceleration.mean, s.acceleration.min,
                  s.acceleration.max);
    std::snprintf(compute, sizeof compute, "%.1f / %.1f / %.1f", s.compute_ms.median, s.compute_ms.p99,
                  s.compute_ms.max);
    std::snprintf(line, sizeof line, "| %-16s | %-14s | %8zu | %-28s | %-26s | %-26s | %10d | %8.0f%% |\n",
                  r.suite.c_str(), r.planner.c_str(), r.episodes.size(), occlusion, accel, compute, s.collisions,
                  100.0 * s.tracking_in_band_share);
    out += line;
  }
  return out;
}

}  // namespace occtrack::io
