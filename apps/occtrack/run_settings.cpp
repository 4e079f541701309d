#include "run_settings.hpp"

#include <sstream>

#include "cli_support.hpp"
#include "sensor_seeds.hpp"

namespace occtrack::app {

namespace {

template <typename T>
nlohmann::json or_null(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

const char* observation_name(sim::TargetObservation o) {
  return o == sim::TargetObservation::line_of_sight ? "line_of_sight" : "always";
}

}  // namespace

nlohmann::json run_settings_json(const std::string& planner, const planners::PlannerOptions& p,
                                 const sim::EpisodeSettings& e, const std::vector<std::uint64_t>& sensor_seeds) {
  nlohmann::json j;
  j["planner"] = {{"name", planner},
                  {"seed", p.seed},
                  {"shield", p.shield},
                  {"predictor", p.predictor},
                  {"response_time_s", p.response_time},
                  {"shield_latency_s", p.latency},
                  {"planning_period_s", p.planning_period},
                  {"accel_max", p.accel_max},
                  {"passive_turn_deg", p.passive_turn},
                  {"standoff_s", p.standoff},
                  {"moving_speed_max_m_s", p.moving_speed_max},
                  {"model", p.model.empty() ? nlohmann::json(nullptr) : nlohmann::json(p.model)},
                  {"batch", p.batch},
                  {"iterations", p.iterations},
                  {"tracking_weight", planners::tracking_weight_for(planner, p)},
                  {"moving_reach_s", planners::moving_reach_for(planner, p)},
                  {"keep_last_plan", p.keep_last_plan},
                  {"rank_stop", p.rank_stop},
                  {"samples", p.samples},
                  {"offline_expert", p.offline_expert},
                  {"threads", p.threads},
                  {"waypoints", p.waypoints}};
  j["episode"] = {{"latency_ms", or_null(e.latency_ms)},
                  {"delay_by_compute", e.delay_by_compute},
                  {"compute_scale", e.compute_scale},
                  {"tau_s", e.tau},
                  {"beams", or_null(e.beams)},
                  {"lidar_noise_m", or_null(e.lidar_noise)},
                  {"beam_dropout", or_null(e.beam_dropout)},
                  {"target_position_noise_m", e.target_position_noise},
                  {"target_velocity_noise_m_s", e.target_velocity_noise},
                  {"target_observation", observation_name(e.target_observation)},
                  {"sensor_seed", e.seed},
                  {"physics_step_s", e.physics_step},
                  {"planning_period_s", e.planning_period},
                  {"robot_accel_max", e.robot_accel_max}};
  if (!sensor_seeds.empty()) {
    j["episode"]["sensor_seed"] = nullptr;
    j["episode"]["sensor_seeds"] = sensor_seeds;
  }
  return j;
}

std::string results_with_settings(const std::string& results_json, const std::string& command,
                                  const std::string& planner, const planners::PlannerOptions& options,
                                  const sim::EpisodeSettings& episode,
                                  const std::vector<std::uint64_t>& sensor_seeds) {
  nlohmann::json j = nlohmann::json::parse(results_json);
  j["created_by"] = created_by(command);
  j["settings"] = run_settings_json(planner, options, episode, sensor_seeds);
  return j.dump(2) + "\n";
}

std::string run_settings_line(const std::string& planner, const planners::PlannerOptions& p,
                              const sim::EpisodeSettings& e, const std::vector<std::uint64_t>& sensor_seeds) {
  std::ostringstream s;
  s << "settings: planner " << planner << " (seed " << p.seed << "), shield " << (p.shield ? "on" : "off")
    << ", predictor " << (p.predictor ? "on" : "off") << ", " << planners::describe_ranking_and_layer(planner, p);
  s << ", latency ";
  if (e.latency_ms)
    s << *e.latency_ms << " ms";
  else
    s << (e.delay_by_compute ? "measured per cycle" : "none");
  s << ", compute scale " << e.compute_scale << ", tau " << e.tau << " s, beams ";
  if (e.beams) s << *e.beams; else s << "the scenario's";
  s << ", LiDAR noise ";
  if (e.lidar_noise) s << *e.lidar_noise << " m"; else s << "the scenario's";
  s << ", beam dropout ";
  if (e.beam_dropout) s << *e.beam_dropout; else s << "the scenario's";
  s << ", target noise " << e.target_position_noise << " m / " << e.target_velocity_noise
    << " m/s, target observation " << observation_name(e.target_observation);
  if (sensor_seeds.empty()) {
    s << ", sensor seed " << e.seed;
  } else {
    s << ", sensor seeds " << sensor_seeds_text(sensor_seeds);
  }
  return s.str();
}

}  // namespace occtrack::app
