#include "occtrack/planners/proj_cem.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <random>
#include <stdexcept>

#include "context.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::planners {

ProjCemSettings ProjCemSettings::offline_expert(int threads) {
  ProjCemSettings s;
  s.samples = 2000;
  s.cem_iterations = 4;
  s.projection.iterations = 50;
  s.projection.threads = std::max(1, threads);
  return s;
}

namespace {
projection::Settings batch_settings(const ProjCemSettings& s) {
  projection::Settings p = s.projection;
  p.batch = s.samples;
  return p;
}
}  // namespace

struct ProjCem::Impl {
  ProjCemSettings settings;
  detail::Context context;
  projection::Projector<float> projector;
  projection::Problem<float> problem;
  projection::Result<float> result;
  detail::Frame frame;
  std::mt19937_64 rng;
  Eigen::RowVectorXd previous;  // last plan, robot-centric at previous_origin
  Eigen::Vector2d previous_origin = Eigen::Vector2d::Zero();
  double previous_time = 0.0;
  bool has_previous = false;

  explicit Impl(const ProjCemSettings& s)
      : settings(s),
        context(batch_settings(s), s.perception, s.ranking),
        projector(batch_settings(s)),
        problem(projector.make_problem()),
        result(projector.make_result()),
        rng(s.seed) {
    if (s.samples < 4) throw std::invalid_argument("projcem: samples must be at least 4");
    if (s.cem_iterations < 1) throw std::invalid_argument("projcem: cem_iterations must be at least 1");
    if (!(s.elite_fraction > 0.0 && s.elite_fraction <= 1.0))
      throw std::invalid_argument("projcem: elite_fraction must be in (0, 1]");
    if (s.perception.nearest_count != s.projection.obstacles)
      throw std::invalid_argument("projcem: perception.nearest_count must equal projection.obstacles");
  }
};

ProjCem::ProjCem(const ProjCemSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
ProjCem::~ProjCem() = default;

void ProjCem::reset() {
  impl_->context.reset();
  impl_->has_previous = false;
  impl_->rng.seed(impl_->settings.seed);
}

PlannerOutput ProjCem::plan(const PlannerInput& input) {
  const auto start = std::chrono::steady_clock::now();
  auto& s = *impl_;
  const auto& cfg = s.settings;
  PlannerOutput out;
  std::string error;
  auto finish = [&]() {
    out.compute_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return out;
  };
  if (!s.context.observe(input, s.frame, &error)) {
    out.ok = false;
    out.message = error;
    return finish();
  }
  const int n = cfg.projection.coefficients(), B = cfg.samples;
  const Eigen::RowVectorXd line = s.context.straight_line(s.context.goal(s.frame));

  // The distribution: mean from the previous plan when there is one, else the straight line to the goal.
  Eigen::RowVectorXd mean = s.has_previous ? s.context.shift(s.previous, s.frame.time - s.previous_time,
                                                             s.previous_origin - s.frame.origin)
                                           : line;
  Eigen::RowVectorXd stddev(2 * n);
  for (int i = 0; i < n; ++i) stddev(i) = stddev(n + i) = cfg.initial_std * double(i) / cfg.projection.degree;

  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> costs(B);
  std::vector<int> order(B);
  Eigen::RowVectorXd best = line;
  double best_cost = INFINITY;
  const int elites = std::max(2, static_cast<int>(cfg.elite_fraction * B));
  Eigen::RowVectorXd sample(2 * n);
  for (int iteration = 0; iteration < cfg.cem_iterations; ++iteration) {
    for (int b = 0; b < B; ++b) {
      if (b == 0) {
        sample = mean;  // keep the distribution's centre, and the straight line, among the candidates
      } else if (b == 1 && iteration == 0) {
        sample = line;
      } else {
        for (int i = 0; i < 2 * n; ++i) sample(i) = mean(i) + stddev(i) * normal(s.rng);
      }
      s.context.fill_row(s.problem, b, sample, s.frame);
    }
    if (!s.projector.solve(s.problem, s.result, &error)) {
      out.ok = false;
      out.message = error;
      return finish();
    }
    for (int b = 0; b < B; ++b) {
      costs[b] = s.context.ranking()
                     .evaluate(s.result.xi.row(b).cast<double>(), s.frame.target, s.frame.nearest, s.frame.occluders,
                               s.frame.scan)
                     .total;
    }
    std::iota(order.begin(), order.end(), 0);
    std::partial_sort(order.begin(), order.begin() + elites, order.end(),
                      [&](int a, int b) { return costs[a] < costs[b]; });
    if (costs[order[0]] < best_cost) {
      best_cost = costs[order[0]];
      best = s.result.xi.row(order[0]).cast<double>();
    }
    // Refit on the projected elites.
    Eigen::RowVectorXd elite_mean = Eigen::RowVectorXd::Zero(2 * n);
    for (int e = 0; e < elites; ++e) elite_mean += s.result.xi.row(order[e]).cast<double>();
    elite_mean /= elites;
    Eigen::RowVectorXd variance = Eigen::RowVectorXd::Zero(2 * n);
    for (int e = 0; e < elites; ++e)
      variance += (s.result.xi.row(order[e]).cast<double>() - elite_mean).array().square().matrix();
    mean = elite_mean;
    stddev = (variance / elites).array().sqrt().max(cfg.min_std).matrix();
  }

  if (!std::isfinite(best_cost)) {
    out.ok = false;
    out.message = "no finite candidate";
    return finish();
  }
  out.command_velocity = s.context.command(best);
  out.plan = s.context.world_positions(best, s.frame);
  const int kept = std::min(cfg.candidates_kept, B);
  // The last iteration's samples, projected, as the figures' "candidates".
  for (int c = 0; c < kept; ++c)
    out.candidates.push_back(s.context.world_positions(s.result.xi.row(c).cast<double>(), s.frame));
  s.previous = best;
  s.previous_origin = s.frame.origin;
  s.previous_time = s.frame.time;
  s.has_previous = true;
  return finish();
}

}  // namespace occtrack::planners
