#include <optional>
#include <sstream>
#include <stdexcept>

#include "occtrack/planners/autochaser.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/learned.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/proj_cem.hpp"
#include "occtrack/planners/safety.hpp"

namespace occtrack::planners {

std::vector<std::string> planner_names() {
  return {"projcem", "projcem-expert", "follower", "cvae", "bc", "cvae-fixed-q", "autochaser"};
}

namespace {

/// The learned variant a planner name stands for ("cvae", "bc", "cvae-fixed-q"); none for the other planners.
std::optional<policy::Variant> learned_variant(const std::string& name) {
  for (const policy::Variant variant : {policy::Variant::cvae, policy::Variant::bc, policy::Variant::fixed_q})
    if (name == learned_planner_name(variant)) return variant;
  return std::nullopt;
}

}  // namespace

double tracking_weight_for(const std::string& name, const PlannerOptions& options) {
  // Only 0 means "the planner's default": anything else is passed on, for the ranking to refuse by name.
  if (options.tracking_weight != 0) return options.tracking_weight;
  if (const auto variant = learned_variant(name)) return learned_tracking_weight(*variant);
  return RankingSettings{}.tracking_weight;
}

double moving_reach_for(const std::string& name, const PlannerOptions& options) {
  if (options.moving_reach) return *options.moving_reach;
  if (!options.shield) return 0.0;
  if (const auto variant = learned_variant(name)) return learned_moving_reach(*variant, options.batch);
  return 0.0;
}

std::string describe_ranking_and_layer(const std::string& name, const PlannerOptions& options) {
  std::ostringstream s;
  s << "tracking weight " << tracking_weight_for(name, options);
  if (const double reach = moving_reach_for(name, options); reach > 0.0) s << ", moving reach " << reach << " s";
  if (options.shield)
    s << ", standoff " << options.standoff << " s, moving obstacles up to " << options.moving_speed_max << " m/s";
  return s.str();
}

double command_lead(const PlannerOptions& options) { return options.response_time + options.latency; }

void rank_as_asked(RankingSettings& ranking, const std::string& name, const PlannerOptions& options) {
  ranking.predict_target = options.predictor;
  ranking.tracking_weight = tracking_weight_for(name, options);
  ranking.moving_reach = moving_reach_for(name, options);
}

namespace {

std::unique_ptr<Planner> make_bare_planner(const std::string& name, const PlannerOptions& options) {
  if (name == "projcem" || name == "projcem-expert") {
    ProjCemSettings s = name == "projcem-expert" || options.offline_expert
                            ? ProjCemSettings::offline_expert(options.threads)
                            : ProjCemSettings{};
    if (options.samples > 0) s.samples = options.samples;
    s.seed = options.seed;
    s.response_time = command_lead(options);
    s.projection.threads = std::max(1, options.threads);
    rank_as_asked(s.ranking, name, options);
    return std::make_unique<ProjCem>(s);
  }
  if (name == "follower") {
    FollowerSettings s;
    s.response_time = command_lead(options);
    rank_as_asked(s.ranking, name, options);
    return std::make_unique<Follower>(s);
  }
  if (name == "autochaser") {
    AutoChaserSettings s;
    s.waypoints = options.waypoints;  // 0: constant-velocity prediction
    s.response_time = command_lead(options);
    return std::make_unique<AutoChaser>(s);
  }
  if (const auto variant = learned_variant(name)) {
    LearnedPolicySettings s;
    s.variant = *variant;
    s.model_path = options.model;  // empty: the shipped model of the variant
    s.batch = options.batch;
    s.keep_last_plan = options.keep_last_plan;
    s.rank_stop = options.rank_stop;
    if (options.iterations > 0) s.projection.iterations = options.iterations;
    s.seed = options.seed;
    s.response_time = command_lead(options);
    rank_as_asked(s.ranking, name, options);
    return std::make_unique<LearnedPolicy>(s);
  }
  std::string known;
  for (const auto& n : planner_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown planner \"" + name + "\" (known: " + known + ")");
}

}  // namespace

std::unique_ptr<Planner> make_planner(const std::string& name, const PlannerOptions& options) {
  std::unique_ptr<Planner> planner = make_bare_planner(name, options);
  if (!options.shield) return planner;
  safety::Settings s;
  s.response_time = options.response_time;
  s.latency = options.latency;
  s.period = options.planning_period;
  s.accel_max = options.accel_max;
  s.moving_turn_max = options.passive_turn;
  s.moving_standoff = options.standoff;
  s.moving_speed_max = options.moving_speed_max;
  return safety::make_shielded(std::move(planner), s);
}

}  // namespace occtrack::planners
