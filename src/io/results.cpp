#include "occtrack/io/results.hpp"

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
  // Protocol v2 (shared/spec/simulation.md, "Suites v2"): 0 and 1 for a v1 run.
  j["latency_ms"] = m.latency_ms;
  j["compute_scale"] = m.compute_scale;
  j["occlusion_stretches"] = m.occlusion_stretches;
  j["longest_occlusion_s"] = m.longest_occlusion_s;
  // Issue 11's safety layer: cycles by what it did; absent without it, so that runs without it are unchanged.
  // With it, also how many cycles it saw moving obstacles faster than it assumes.
  if (m.shield.total() > 0) {
    j["shield"] = {{"plan", m.shield.plan},
                   {"alternative", m.shield.alternative},
                   {"stop", m.shield.stop},
                   {"evasive", m.shield.evasive},
                   {"best_effort", m.shield.best_effort},
                   {"brake", m.shield.brake}};
    j["beyond_envelope_cycles"] = m.beyond_envelope_cycles;
  }
  return j;
}

}  // namespace

std::string episode_json(const core::EpisodeMetrics& metrics, int indent) {
  return metrics_object(metrics, false, 0.0).dump(indent);
}

std::string suite_json(const core::SuiteResult& result, int indent) {
  json j;
  j["suite"] = result.suite;
  j["planner"] = result.planner;
  j["episodes"] = json::array();
  for (const auto& e : result.episodes) j["episodes"].push_back(metrics_object(e, false, 0.0));
  j["summary"] = metrics_object(result.summary, true, result.success_rate);
  return j.dump(indent);
}

std::string suite_table(const std::vector<core::SuiteResult>& results) {
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
