// Episode and suite metrics (include/occtrack/sim/metrics.hpp).
#include "occtrack/sim/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <utility>

namespace occtrack::sim {

EpisodeMetricsAccumulator::EpisodeMetricsAccumulator(const std::string& scenario, const std::string& planner,
                                                     double physics_step, double sensor_range,
                                                     const core::TrackingBand& band, int expected_cycles)
    : physics_step_(physics_step), sensor_range_(sensor_range), band_(band) {
  m_.scenario = scenario;
  m_.planner = planner;
  m_.min_clearance_m = std::numeric_limits<double>::infinity();
  m_.acceleration.min = std::numeric_limits<double>::infinity();
  compute_ms_.reserve(static_cast<std::size_t>(std::max(0, expected_cycles)));
}

void EpisodeMetricsAccumulator::add_state(double clearance, bool occluded, double distance, bool last) {
  m_.min_clearance_m = std::min(m_.min_clearance_m, clearance);
  const bool colliding = clearance < 0.0;
  if (!last) {
    ++steps_;
    if (colliding) m_.collision_time_s += physics_step_;
    if (occluded) m_.occlusion_time_s += physics_step_;
    // Spells of lost sight (Protocol v2): a new one begins at each step blocked after one that was not.
    if (occluded) {
      if (!in_occlusion_) {
        ++m_.occlusion_stretches;
        occlusion_spell_ = 0;
      }
      occlusion_spell_ += physics_step_;
      m_.longest_occlusion_s = std::max(m_.longest_occlusion_s, occlusion_spell_);
    }
    in_occlusion_ = occluded;
    if (distance > sensor_range_) m_.target_out_of_range_s += physics_step_;
    distance_sum_ += distance;
    in_band_ += distance >= band_.min && distance <= band_.max;
  }
  if (colliding && !in_collision_) ++m_.collisions;
  in_collision_ = colliding;
}

void EpisodeMetricsAccumulator::add_cycle(double compute_ms, bool failed) {
  ++m_.cycles;
  compute_ms_.push_back(compute_ms);
  if (failed) ++m_.planner_failures;
}

void EpisodeMetricsAccumulator::add_safety(planners::SafetyAction action, bool beyond_envelope) {
  if (beyond_envelope) ++m_.beyond_envelope_cycles;
  using planners::SafetyAction;
  switch (action) {
    case SafetyAction::off: break;
    case SafetyAction::plan: ++m_.shield.plan; break;
    case SafetyAction::alternative: ++m_.shield.alternative; break;
    case SafetyAction::stop: ++m_.shield.stop; break;
    case SafetyAction::evasive: ++m_.shield.evasive; break;
    case SafetyAction::best_effort: ++m_.shield.best_effort; break;
    case SafetyAction::brake: ++m_.shield.brake; break;
  }
}

void EpisodeMetricsAccumulator::add_acceleration(double norm) {
  acceleration_sum_ += norm;
  m_.acceleration.min = std::min(m_.acceleration.min, norm);
  m_.acceleration.max = std::max(m_.acceleration.max, norm);
}

core::EpisodeMetrics EpisodeMetricsAccumulator::finish() const {
  core::EpisodeMetrics m = m_;
  const int counted = std::max(1, steps_);
  m.duration_s = steps_ * physics_step_;
  m.success = m.occlusion_time_s == 0.0;
  m.acceleration.mean = acceleration_sum_ / counted;
  if (!std::isfinite(m.acceleration.min)) m.acceleration.min = 0;
  m.compute_ms = core::summarize_timings(compute_ms_);
  m.tracking_distance_mean_m = distance_sum_ / counted;
  m.tracking_in_band_share = double(in_band_) / counted;
  return m;
}

core::SuiteResult summarize_suite(const std::string& suite, const std::string& planner,
                                  const std::vector<core::EpisodeMetrics>& episodes) {
  core::SuiteResult r;
  r.suite = suite;
  r.planner = planner;
  r.episodes = episodes;
  core::EpisodeMetrics& s = r.summary;
  s.scenario = suite;
  s.planner = planner;
  if (episodes.empty()) return r;
  s.latency_ms = episodes.front().latency_ms;
  s.compute_scale = episodes.front().compute_scale;
  s.min_clearance_m = std::numeric_limits<double>::infinity();
  s.acceleration.min = std::numeric_limits<double>::infinity();
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
    s.shield.plan += e.shield.plan;
    s.shield.alternative += e.shield.alternative;
    s.shield.stop += e.shield.stop;
    s.shield.evasive += e.shield.evasive;
    s.shield.best_effort += e.shield.best_effort;
    s.shield.brake += e.shield.brake;
    s.beyond_envelope_cycles += e.beyond_envelope_cycles;
    s.cycles += e.cycles;
    s.occlusion_stretches += e.occlusion_stretches;
    s.longest_occlusion_s = std::max(s.longest_occlusion_s, e.longest_occlusion_s);
    successes += e.success;
  }
  const double total = std::max(s.duration_s, 1e-12);
  s.acceleration.mean /= total;
  s.tracking_distance_mean_m /= total;
  s.tracking_in_band_share /= total;
  s.compute_ms.mean = s.cycles > 0 ? weighted_compute / s.cycles : 0.0;
  s.compute_ms.median = core::summarize_timings(std::move(medians)).median;
  r.success_rate = double(successes) / episodes.size();
  s.success = successes == static_cast<int>(episodes.size());
  return r;
}

namespace {

template <typename Figure>
core::Spread spread_of(const std::vector<core::SuiteResult>& draws, Figure figure) {
  core::Spread s;
  const std::size_t n = draws.size();
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = figure(draws[i]);
  s.min_at = static_cast<std::size_t>(std::min_element(x.begin(), x.end()) - x.begin());
  s.max_at = static_cast<std::size_t>(std::max_element(x.begin(), x.end()) - x.begin());
  s.min = x[s.min_at];
  s.max = x[s.max_at];
  for (const double v : x) s.mean += v;
  s.mean /= static_cast<double>(n);
  if (n > 1) {
    double squares = 0;
    for (const double v : x) squares += (v - s.mean) * (v - s.mean);
    s.sd = std::sqrt(squares / static_cast<double>(n - 1));
  }
  return s;
}

}  // namespace

core::DrawsResult summarize_draws(const std::vector<std::uint64_t>& sensor_seeds,
                                  const std::vector<core::SuiteResult>& draws) {
  if (draws.empty()) throw std::invalid_argument("summarize_draws: no draws");
  if (draws.size() != sensor_seeds.size())
    throw std::invalid_argument("summarize_draws: " + std::to_string(draws.size()) + " draws but " +
                                std::to_string(sensor_seeds.size()) + " sensor seeds");
  if (std::set<std::uint64_t>(sensor_seeds.begin(), sensor_seeds.end()).size() != sensor_seeds.size())
    throw std::invalid_argument("summarize_draws: a sensor seed repeats");
  for (const auto& d : draws)
    if (d.suite != draws.front().suite || d.planner != draws.front().planner)
      throw std::invalid_argument("summarize_draws: the draws mix suites or planners (" + d.suite + ", " +
                                  d.planner + " besides " + draws.front().suite + ", " + draws.front().planner +
                                  ")");
  core::DrawsResult r;
  r.suite = draws.front().suite;
  r.planner = draws.front().planner;
  r.sensor_seeds = sensor_seeds;
  r.draws = draws;
  r.occlusion_time_s = spread_of(draws, [](const core::SuiteResult& d) { return d.summary.occlusion_time_s; });
  r.success_rate = spread_of(draws, [](const core::SuiteResult& d) { return d.success_rate; });
  r.longest_occlusion_s = spread_of(draws, [](const core::SuiteResult& d) { return d.summary.longest_occlusion_s; });
  r.collisions = spread_of(draws, [](const core::SuiteResult& d) { return double(d.summary.collisions); });
  r.min_clearance_m = std::numeric_limits<double>::infinity();
  for (const auto& d : draws) {
    r.draws_with_collision += d.summary.collisions > 0;
    r.beyond_envelope_cycles += d.summary.beyond_envelope_cycles;
    r.min_clearance_m = std::min(r.min_clearance_m, d.summary.min_clearance_m);
  }
  return r;
}

}  // namespace occtrack::sim
