#include "occtrack/planners/learned.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <random>
#include <stdexcept>

#include "cycle.hpp"
#include "occtrack/projection/projector.hpp"

#ifndef OCCTRACK_MODEL_DIR
#define OCCTRACK_MODEL_DIR "models"
#endif

namespace occtrack::planners {

namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// bc projects nothing, so it has no stop plan: unprojected, a stop is an instant halt the robot cannot follow.
bool ranks_stop(const LearnedPolicySettings& s) { return s.rank_stop && s.variant != policy::Variant::bc; }

projection::Settings batch_settings(const LearnedPolicySettings& s) {
  projection::Settings p = s.projection;
  p.batch = s.batch + (s.keep_last_plan ? 1 : 0) + (ranks_stop(s) ? 1 : 0);
  return p;
}

policy::Model load_model(const LearnedPolicySettings& s) {
  occtrack::detail::checked(s, "planner " + learned_planner_name(s.variant));  // before reading a file
  const std::string path = s.model_path.empty() ? default_model_path(s.variant) : s.model_path;
  const std::string planner = learned_planner_name(s.variant);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw io::InputError("planner " + planner + ": no model file at " + path + ". Train one (`occtrack train`, see " +
                         "README) and pass it with --model FILE, or time the planner on random weights with " +
                         "`occtrack bench policy --random`");
  return policy::Model::load(path);
}

}  // namespace

std::string learned_planner_name(policy::Variant variant) {
  switch (variant) {
    case policy::Variant::cvae: return "cvae";
    case policy::Variant::bc: return "bc";
    case policy::Variant::fixed_q: return "cvae-fixed-q";
  }
  return "?";
}

bool LearnedPolicySettings::validate(std::string* error) const {
  occtrack::detail::SettingsChecker c;
  c.require(batch >= 1, "batch (", batch, ") must be at least 1");
  c.require(candidates_kept >= 0, "candidates_kept (", candidates_kept, ") must not be negative");
  return c.done(error) && detail::validate_cycle(batch_settings(*this), &perception, ranking, response_time, error);
}

std::string default_model_path(policy::Variant variant) {
  return std::string(OCCTRACK_MODEL_DIR) + "/" + policy::to_string(variant) + ".safetensors";
}

double learned_tracking_weight(policy::Variant variant) {
  // fixed-q's nominal d_max already holds its plans inside the band; weighted 5 it hid the target longer on
  // the validation episodes, cvae and bc shorter.
  return variant == policy::Variant::fixed_q ? RankingSettings{}.tracking_weight : 5.0;
}

double learned_moving_reach(policy::Variant variant, int batch) {
  // At B = 30 the cvae has samples to spare for the room; at B = 5 (and for bc's few plans) the room cost
  // sight on the validation episodes.
  return variant == policy::Variant::cvae && batch >= 30 ? 1.0 : 0.0;
}

struct LearnedPolicy::Impl {
  LearnedPolicySettings settings;
  policy::Model model;
  policy::FrameRotation turn;  // the model's network frame
  detail::Context context;
  std::optional<projection::Projector<float>> projector;  // none for bc
  projection::Problem<float> problem;
  projection::Result<float> result;
  PlanRecord record;  // record.frame is the cycle's frame
  std::mt19937_64 rng;
  std::normal_distribution<double> normal{0.0, 1.0};
  Timing timing;
  Choice choice;

  // Per-cycle buffers, sized once.
  policy::Cloud cloud;
  Eigen::VectorXf observation, features;
  policy::Rows z, outputs;
  Eigen::RowVectorXf robot_velocity, target, obstacles;
  Eigen::RowVectorXd xi, nominal, line;
  std::vector<double> costs;
  std::vector<int> order;  // rank_commands' workspace
  std::vector<char> usable;
  // The last plan (robot-centric at last_origin), for keep_last_plan.
  Eigen::RowVectorXd last, warm, stop;
  Eigen::Vector2d last_origin = Eigen::Vector2d::Zero();
  double last_time = 0.0;
  bool has_last = false;

  Impl(const LearnedPolicySettings& s, policy::Model m)
      : settings(occtrack::detail::checked(s, "planner " + learned_planner_name(s.variant))), model(std::move(m)), turn(model.network()), context(batch_settings(s), s.perception, s.ranking, s.response_time), rng(s.seed) {
    settings.rank_stop = ranks_stop(s);
    const std::string planner = learned_planner_name(s.variant);
    model.require_variant(s.variant, planner);
    const projection::Settings p = batch_settings(s);
    model.check_projection(p);
    const policy::NetworkConfig& net = model.network();
    if (net.cloud_points != s.perception.cloud_size)
      throw io::InputError(model.source() + ": network.cloud_points is " + std::to_string(net.cloud_points) +
                           " in the model, the planner's perception gives " + std::to_string(s.perception.cloud_size));
    if (const auto& band = model.band()) {
      const core::TrackingBand& mine = s.ranking.band;
      auto differ = [&](const char* field, double model_value, double planner_value) {
        if (model_value != planner_value)
          throw io::InputError(model.source() + ": band." + field + " is " + std::to_string(model_value) +
                               " in the model, the planner uses " + std::to_string(planner_value));
      };
      differ("min", band->min, mine.min);
      differ("reference", band->reference, mine.reference);
      differ("max", band->max, mine.max);
    }
    if (s.variant != policy::Variant::bc) {
      projector.emplace(p);
      problem = projector->make_problem();
      result = projector->make_result();
    }
    model.reserve(s.batch, s.perception.cloud_size);
    const int n2 = 2 * p.coefficients();
    cloud.resize(s.perception.cloud_size, 2);
    observation.resize(net.observation);
    features.resize(net.features);
    z.resize(s.batch, net.latent);
    outputs.resize(s.batch, net.outputs);
    robot_velocity.resize(2);
    target.resize(4);
    obstacles.resize(4 * p.obstacles);
    xi.resize(n2);
    nominal.resize(n2);
    line.resize(n2);
    record.xi.resize(n2);
    costs.resize(p.batch);
    usable.resize(p.batch);
    last.resize(n2);
    warm.resize(n2);
    stop.resize(n2);
  }

  // Problem row b from decoded sample b (docs/learning.md, post-processing steps 2 and 3). False when the
  // sample is not finite: the row then holds the straight line to the goal, so that the batch stays
  // solvable, and the sample is not ranked.
  bool fill_row(int b) {
    const policy::OutputLayout& y = model.layout();
    const int n2 = static_cast<int>(xi.size()), m = settings.projection.steps;
    const auto row = outputs.row(b);
    const Frame& frame = record.frame;
    if (!row.allFinite()) {
      context.line_to_goal(frame, line);
      context.fill_row(problem, b, line, frame);
      return false;
    }
    if (settings.variant == policy::Variant::fixed_q) {
      // Nominal q read off xi_bar, as Proj-CEM sets it; via points and lambda0 stay the decoder's.
      nominal = row.segment(y.xi_bar, n2).cast<double>();
      context.fill_row(problem, b, nominal, frame);
    } else {
      problem.robot_velocity.row(b) = robot_velocity;
      problem.target.row(b) = target;
      problem.obstacles.row(b) = obstacles;
      problem.terminal.row(b) = row.segment(y.terminal, 4);
      problem.distance_min.row(b) = row.segment(y.distance_min, m);
      problem.distance_max.row(b) = row.segment(y.distance_max, m);
      problem.xi_bar.row(b) = row.segment(y.xi_bar, n2);
    }
    problem.via_points.row(b) = row.segment(y.via, 4);
    problem.lambda0.row(b) = row.segment(y.lambda0, n2);
    return true;
  }
};

LearnedPolicy::LearnedPolicy(const LearnedPolicySettings& settings) : LearnedPolicy(settings, load_model(settings)) {}

LearnedPolicy::LearnedPolicy(const LearnedPolicySettings& settings, policy::Model model)
    : impl_(std::make_unique<Impl>(settings, std::move(model))) {}

LearnedPolicy::~LearnedPolicy() = default;

std::string LearnedPolicy::name() const { return learned_planner_name(impl_->settings.variant); }

void LearnedPolicy::reset() {
  impl_->context.reset();
  impl_->has_last = false;
  impl_->record.valid = false;
  impl_->rng.seed(impl_->settings.seed);
  impl_->normal.reset();
}

const LearnedPolicy::Timing& LearnedPolicy::last_timing() const { return impl_->timing; }
const policy::Model& LearnedPolicy::model() const { return impl_->model; }
const LearnedPolicy::Choice& LearnedPolicy::last_choice() const { return impl_->choice; }
const PlanRecord& LearnedPolicy::last_record() const { return impl_->record; }

void LearnedPolicy::plan(const PlannerInput& input, PlannerOutput& out) {
  detail::CycleClock clock;
  Impl& s = *impl_;
  const LearnedPolicySettings& cfg = s.settings;
  const bool project = cfg.variant != policy::Variant::bc;
  const int B = cfg.batch, n2 = static_cast<int>(s.xi.size());
  // Rows: the B samples, then the last plan shifted to now when there is one (keep_last_plan), then the stop
  // plan (rank_stop).
  const bool warm = cfg.keep_last_plan && s.has_last;
  const int stop_row = B + (cfg.keep_last_plan ? 1 : 0);
  const int rows = stop_row + (cfg.rank_stop ? 1 : 0);
  std::string error;
  s.timing = Timing{};
  s.choice = Choice{};
  auto brake = [&](const std::string& message) {
    s.has_last = false;
    detail::brake(out, s.record, clock, name() + ": " + message);
    s.timing.total = out.compute_ms;
  };

  // 1. Observation (robot-centric). A target never observed: stand still, and no stale plan to warm-start from.
  if (detail::hold_unobserved(input, out, s.record, clock)) {
    s.has_last = false;
    s.timing.total = out.compute_ms;
    return;
  }
  if (!s.context.observe(input, s.record.frame, clock, &error)) return brake(error);
  const auto observed = Clock::now();
  s.timing.perception = ms_between(clock.start(), observed);  // with a shared perception's time (credited)

  // 2. PointNet on the distinct points: the cloud's rows past them repeat its first row, which changes no
  //    max-pooled feature (perception.hpp, fixed cloud).
  const Frame& frame = s.record.frame;
  const Eigen::Index distinct = std::max<Eigen::Index>(1, std::min<Eigen::Index>(frame.occluder_count, frame.cloud.rows()));
  // The observation, and the cloud and the decoder's outputs, in the network's frame (target-frame models).
  s.observation << static_cast<float>(frame.robot_velocity.x()), static_cast<float>(frame.robot_velocity.y()),
      static_cast<float>(frame.target(0)), static_cast<float>(frame.target(1)), static_cast<float>(frame.target(2)),
      static_cast<float>(frame.target(3));
  s.cloud.topRows(distinct) = frame.cloud.topRows(distinct).cast<float>();
  s.turn.aim(frame.target(0), frame.target(1));
  s.turn.into_network(s.observation, s.cloud.topRows(distinct));
  s.model.features(s.cloud.topRows(distinct), s.features);
  const auto encoded = Clock::now();
  s.timing.pointnet = ms_between(observed, encoded);

  // 3-4. Latent samples, decoder, post-processing, one projection problem row per sample.
  for (int b = 0; b < B; ++b)
    for (Eigen::Index j = 0; j < s.z.cols(); ++j) s.z(b, j) = static_cast<float>(s.normal(s.rng));
  s.model.decode(s.z, s.observation, s.features, s.outputs);
  s.turn.out_of_network(s.outputs);
  s.model.postprocess(s.outputs, cfg.projection.speed_max, cfg.ranking.band.min);
  if (project) {
    s.robot_velocity = frame.robot_velocity.transpose().cast<float>();
    s.target = frame.target.transpose().cast<float>();
    s.obstacles = Eigen::Map<const Eigen::RowVectorXd>(frame.nearest.data(), s.obstacles.size()).cast<float>();
    for (int b = 0; b < B; ++b) s.usable[b] = s.fill_row(b);
  } else {
    for (int b = 0; b < B; ++b) s.usable[b] = s.outputs.row(b).allFinite();
  }
  if (cfg.keep_last_plan) {
    // Without a last plan the row repeats the straight line to the goal and is not ranked.
    if (warm)
      s.context.shift(s.last, frame.time - s.last_time, s.last_origin - frame.origin, s.warm);
    else
      s.context.line_to_goal(frame, s.warm);
    if (project) s.context.fill_row(s.problem, B, s.warm, frame);
    s.usable[B] = warm && s.warm.allFinite();
  }
  if (cfg.rank_stop) {
    s.stop.setZero();  // robot-centric: every coefficient at the robot's position
    if (project) s.context.fill_row(s.problem, stop_row, s.stop, frame);
    s.usable[stop_row] = true;
  }
  const auto decoded = Clock::now();
  s.timing.decoder = ms_between(encoded, decoded);

  // 5. Projection from each sample's initial guess.
  if (project) {
    if (!s.projector->solve(s.problem, s.result, &error)) return brake("projection refused its input: " + error);
  }
  const auto projected = Clock::now();
  s.timing.projection = ms_between(decoded, projected);

  // 6. Ranking; the cheapest finite sample is the plan.
  const int xi_bar = s.model.layout().xi_bar;
  auto candidate = [&](int b) -> Eigen::RowVectorXd& {
    if (project)
      s.xi = s.result.xi.row(b).cast<double>();
    else if (b == stop_row)
      s.xi = s.stop;
    else if (b == B)
      s.xi = s.warm;
    else
      s.xi = s.outputs.row(b).segment(xi_bar, n2).cast<double>();
    return s.xi;
  };
  int best = -1;
  RankingTerms best_terms;
  for (int b = 0; b < rows; ++b) {
    s.costs[b] = INFINITY;
    if (!s.usable[b]) continue;
    const Eigen::RowVectorXd& xi = candidate(b);
    if (!xi.allFinite()) continue;
    const RankingTerms terms =
        s.context.ranking().evaluate(xi, frame.target, frame.nearest, frame.occluders_view(), frame.scan,
                                    &frame.forecast, &frame.moving);
    s.costs[b] = terms.total;
    if (std::isfinite(s.costs[b]) && (best < 0 || s.costs[b] < s.costs[best])) {
      best = b;
      best_terms = terms;
    }
  }
  if (best < 0) {
    s.timing.ranking = ms_between(projected, Clock::now());
    return brake("no finite candidate among " + std::to_string(B) + " samples");
  }

  // 7. Command and the world-frame plan.
  s.choice = Choice{best, s.costs[best], cfg.keep_last_plan && best == B, cfg.rank_stop && best == stop_row};
  s.last = candidate(best);
  s.last_origin = frame.origin;
  s.last_time = frame.time;
  s.has_last = true;
  const int kept = std::min(cfg.candidates_kept, B);
  std::size_t shown = 0;
  for (int b = 0; b < kept; ++b) shown += s.usable[b] && std::isfinite(s.costs[b]);
  out.resize_candidates(shown);  // storage of earlier cycles is reused
  for (int b = 0, c = 0; b < kept; ++b)
    if (s.usable[b] && std::isfinite(s.costs[b])) s.context.world_positions(candidate(b), frame, out.candidates[c++]);
  // Every ranked candidate's command, cheapest first, for the safety layer.
  detail::rank_commands(s.costs, s.order, [&](int b) { return s.context.command(candidate(b)); }, out.ranked_commands);
  s.timing.ranking = ms_between(projected, Clock::now());
  s.context.finish_plan(out, s.record, clock, s.last, best_terms);
  s.timing.total = out.compute_ms;
}

}  // namespace occtrack::planners
