#include "occtrack/io/results.hpp"

#include <cmath>
#include <cstdint>
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

json suite_object(const core::SuiteResult& result) {
  json j;
  j["suite"] = result.suite;
  j["planner"] = result.planner;
  j["episodes"] = json::array();
  for (const auto& e : result.episodes) j["episodes"].push_back(metrics_object(e, false, 0.0));
  j["summary"] = metrics_object(result.summary, true, result.success_rate);
  return j;
}

json spread_object(const core::Spread& s, const std::vector<std::uint64_t>& seeds) {
  return {{"mean", s.mean}, {"sd", s.sd}, {"min", s.min}, {"max", s.max},
          {"min_seed", seeds.at(s.min_at)}, {"max_seed", seeds.at(s.max_at)}};
}

}  // namespace

std::string episode_json(const core::EpisodeMetrics& metrics, int indent) {
  return metrics_object(metrics, false, 0.0).dump(indent);
}

std::string suite_json(const core::SuiteResult& result, int indent) { return suite_object(result).dump(indent); }

std::string draws_json(const core::DrawsResult& r, int indent) {
  json j;
  j["suite"] = r.suite;
  j["planner"] = r.planner;
  j["sensor_seeds"] = r.sensor_seeds;
  j["draws"] = json::array();
  for (std::size_t i = 0; i < r.draws.size(); ++i) {
    json d = suite_object(r.draws[i]);
    d["sensor_seed"] = r.sensor_seeds.at(i);
    j["draws"].push_back(std::move(d));
  }
  j["over_draws"] = {{"draws", r.draws.size()},
                     {"occlusion_time_s", spread_object(r.occlusion_time_s, r.sensor_seeds)},
                     {"success_rate", spread_object(r.success_rate, r.sensor_seeds)},
                     {"longest_occlusion_s", spread_object(r.longest_occlusion_s, r.sensor_seeds)},
                     {"collisions", spread_object(r.collisions, r.sensor_seeds)},
                     {"draws_with_collision", r.draws_with_collision},
                     {"min_clearance_m", finite_or_zero(r.min_clearance_m)},
                     {"beyond_envelope_cycles", r.beyond_envelope_cycles}};
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

std::string draws_table(const core::DrawsResult& r) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "| %-16s | %-14s | %-11s | %-28s | %-17s | %10s | %-19s |\n", "suite",
                "planner", "sensor seed", "occlusion time (s) / success", "longest spell (s)", "collisions",
                "least clearance (m)");
  out += line;
  out += "|------------------|----------------|-------------|------------------------------|-------------------|"
         "------------|---------------------|\n";
  for (std::size_t i = 0; i < r.draws.size(); ++i) {
    const auto& d = r.draws[i];
    char occlusion[64];
    std::snprintf(occlusion, sizeof occlusion, "%.1f / %.2f", d.summary.occlusion_time_s, d.success_rate);
    std::snprintf(line, sizeof line, "| %-16s | %-14s | %11llu | %-28s | %17.1f | %10d | %19.3f |\n",
                  d.suite.c_str(), d.planner.c_str(), static_cast<unsigned long long>(r.sensor_seeds.at(i)),
                  occlusion, d.summary.longest_occlusion_s, d.summary.collisions,
                  finite_or_zero(d.summary.min_clearance_m));
    out += line;
  }
  std::snprintf(line, sizeof line, "\nover %zu sensor draws (mean / sd / least (seed) / largest (seed)):\n",
                r.draws.size());
  out += line;
  auto row = [&](const char* name, const core::Spread& s, int decimals) {
    std::snprintf(line, sizeof line, "  %-22s %.*f / %.*f / %.*f (%llu) / %.*f (%llu)\n", name, decimals, s.mean,
                  decimals, s.sd, decimals, s.min, static_cast<unsigned long long>(r.sensor_seeds.at(s.min_at)),
                  decimals, s.max, static_cast<unsigned long long>(r.sensor_seeds.at(s.max_at)));
    out += line;
  };
  row("occlusion time (s)", r.occlusion_time_s, 1);
  row("success rate", r.success_rate, 2);
  row("longest spell (s)", r.longest_occlusion_s, 1);
  row("collisions", r.collisions, 1);
  std::snprintf(line, sizeof line, "  %-22s %d of %zu draws; least clearance %.3f m\n", "with a collision",
                r.draws_with_collision, r.draws.size(), finite_or_zero(r.min_clearance_m));
  out += line;
  return out;
}

}  // namespace occtrack::io
