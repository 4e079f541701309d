#include "occtrack/planners/proj_cem.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

#include "cycle.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::planners {

ProjCemSettings ProjCemSettings::offline_expert(int threads) {
  ProjCemSettings s;
  s.samples = 120;
  s.cem_iterations = 8;
  s.projection.iterations = 50;
  s.projection.threads = std::max(1, threads);
  return s;
}

namespace {

// The projection runs every sample of a CEM iteration as one batch.
projection::Settings batch_settings(const ProjCemSettings& s) {
  projection::Settings p = s.projection;
  p.batch = s.samples;
  return p;
}

}  // namespace

bool ProjCemSettings::validate(std::string* error) const {
  occtrack::detail::SettingsChecker c;
  c.require(samples >= 4, "samples (", samples, ") must be at least 4");
  c.require(cem_iterations >= 1, "cem_iterations (", cem_iterations, ") must be at least 1");
  c.require(std::isfinite(elite_fraction) && elite_fraction > 0.0 && elite_fraction <= 1.0,
            "elite_fraction must lie in (0, 1], got ", elite_fraction);
  c.non_negative(initial_std, "initial_std");
  c.non_negative(min_std, "min_std");
  c.non_negative(settle_distance, "settle_distance");
  c.require(candidates_kept >= 0, "candidates_kept (", candidates_kept, ") must not be negative");
  return c.done(error) && detail::validate_cycle(batch_settings(*this), &perception, ranking, response_time, error);
}

struct ProjCem::Impl {
  ProjCemSettings settings;
  detail::Context context;
  detail::Optimizer optimizer;
  PlanRecord record;  // record.frame is the cycle's frame
  std::mt19937_64 rng;
  Eigen::RowVectorXd previous;  // last plan, robot-centric at previous_origin
  Eigen::Vector2d previous_origin = Eigen::Vector2d::Zero();
  double previous_time = 0.0;
  bool has_previous = false;
  // Per-cycle buffers, sized once.
  Eigen::RowVectorXd line, mean, stddev, sample, best, scored, elite_mean, variance;
  std::vector<double> costs;
  std::vector<int> order;

  explicit Impl(const ProjCemSettings& s)
      : settings(occtrack::detail::checked(s, "projcem")),
        context(batch_settings(s), s.perception, s.ranking, s.response_time),
        optimizer(batch_settings(s)),
        rng(s.seed) {
    const int n2 = 2 * s.projection.coefficients();
    for (Eigen::RowVectorXd* v : {&previous, &line, &mean, &stddev, &sample, &best, &scored, &elite_mean, &variance})
      v->resize(n2);
    record.xi.resize(n2);
    costs.resize(s.samples);
    order.resize(s.samples);
  }
};

ProjCem::ProjCem(const ProjCemSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
ProjCem::~ProjCem() = default;

void ProjCem::reset() {
  impl_->context.reset();
  impl_->has_previous = false;
  impl_->record.valid = false;
  impl_->rng.seed(impl_->settings.seed);
}

const PlanRecord& ProjCem::last_record() const { return impl_->record; }

void ProjCem::plan(const PlannerInput& input, PlannerOutput& out) {
  detail::CycleClock clock;
  auto& s = *impl_;
  const auto& cfg = s.settings;
  Frame& frame = s.record.frame;
  std::string error;
  if (detail::hold_unobserved(input, out, s.record, clock)) return;
  if (!s.context.observe(input, frame, clock, &error)) return detail::brake(out, s.record, clock, error);
  const int n = cfg.projection.coefficients(), B = cfg.samples;
  s.context.line_to_goal(frame, s.line);

  // The distribution: mean from the previous plan when there is one, else the straight line to the goal.
  if (s.has_previous)
    s.context.shift(s.previous, frame.time - s.previous_time, s.previous_origin - frame.origin, s.mean);
  else
    s.mean = s.line;
  for (int i = 0; i < n; ++i) s.stddev(i) = s.stddev(n + i) = cfg.initial_std * double(i) / cfg.projection.degree;

  std::normal_distribution<double> normal(0.0, 1.0);
  s.best = s.line;
  double best_cost = INFINITY;
  RankingTerms best_terms;
  const int elites = std::max(2, static_cast<int>(cfg.elite_fraction * B));
  for (int iteration = 0; iteration < cfg.cem_iterations; ++iteration) {
    for (int b = 0; b < B; ++b) {
      if (b == 0) {
        s.sample = s.mean;  // keep the distribution's centre, and the straight line, among the candidates
      } else if (b == 1 && iteration == 0) {
        s.sample = s.line;
      } else {
        for (int i = 0; i < 2 * n; ++i) s.sample(i) = s.mean(i) + s.stddev(i) * normal(s.rng);
      }
      s.context.fill_row(s.optimizer.problem, b, s.sample, frame);
    }
    if (!s.optimizer.projector.solve(s.optimizer.problem, s.optimizer.result, &error)) return detail::brake(out, s.record, clock, error);
    for (int b = 0; b < B; ++b) {
      s.scored = s.optimizer.result.xi.row(b).cast<double>();
      const RankingTerms terms =
          s.context.ranking().evaluate(s.scored, frame.target, frame.nearest, frame.occluders_view(), frame.scan,
                                       &frame.forecast, &frame.moving);
      s.costs[b] = terms.total;
      if (terms.total < best_cost) {
        best_cost = terms.total;
        best_terms = terms;
        s.best = s.scored;
      }
    }
    std::iota(s.order.begin(), s.order.end(), 0);
    std::partial_sort(s.order.begin(), s.order.begin() + elites, s.order.end(),
                      [&](int a, int b) { return s.costs[a] < s.costs[b]; });
    // Refit on the projected elites.
    s.elite_mean.setZero();
    for (int e = 0; e < elites; ++e) s.elite_mean += s.optimizer.result.xi.row(s.order[e]).cast<double>();
    s.elite_mean /= elites;
    s.variance.setZero();
    for (int e = 0; e < elites; ++e)
      s.variance += (s.optimizer.result.xi.row(s.order[e]).cast<double>() - s.elite_mean).array().square().matrix();
    const double moved = (s.elite_mean - s.mean).cwiseAbs().maxCoeff();
    s.mean = s.elite_mean;
    s.stddev = (s.variance / elites).array().sqrt().max(cfg.min_std).matrix();
    if (moved < cfg.settle_distance) break;  // the distribution has settled: later iterations would resample it
  }

  if (!std::isfinite(best_cost)) return detail::brake(out, s.record, clock, "no finite candidate");
  // The last iteration's samples, projected, as the figures' "candidates".
  const int kept = std::min(cfg.candidates_kept, B);
  out.resize_candidates(static_cast<std::size_t>(kept));
  for (int c = 0; c < kept; ++c) {
    s.scored = s.optimizer.result.xi.row(c).cast<double>();
    s.context.world_positions(s.scored, frame, out.candidates[static_cast<std::size_t>(c)]);
  }
  // The last iteration's candidates, cheapest first, for the safety layer (the best of all first).
  detail::rank_commands(
      s.costs, s.order,
      [&](int b) {
        s.scored = s.optimizer.result.xi.row(b).cast<double>();
        return s.context.command(s.scored);
      },
      out.ranked_commands);
  out.ranked_commands.insert(out.ranked_commands.begin(), s.context.command(s.best));
  s.previous = s.best;
  s.previous_origin = frame.origin;
  s.previous_time = frame.time;
  s.has_previous = true;
  s.context.finish_plan(out, s.record, clock, s.best, best_terms);
}

}  // namespace occtrack::planners
