// Proj-CEM (shared/spec/policy.md, "The expert"): the cross-entropy method over trajectory coefficients,
// with every sample projected onto the constraint set before it is scored. One settings struct covers the
// online baseline (hundreds of samples, one core) and the offline expert that labels demonstrations
// (thousands of samples, all cores).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::planners {

struct ProjCemSettings {
  int samples = 160;             ///< per CEM iteration (the projection's batch)
  int cem_iterations = 3;        ///< sample, project, score, refit
  double elite_fraction = 0.1;   ///< share of samples that refit the distribution
  double initial_std = 1.2;      ///< metres: spread of the last coefficient around the mean; grows linearly
                                 ///< from zero at the first coefficient (the start is fixed)
  double min_std = 0.05;         ///< metres: floor of the refitted spread
  /// metres: stop iterating once a refit moves the mean by less than this (its largest coefficient change);
  /// 0 runs every iteration. The offline expert uses it to spend its iterations where the plan still moves.
  double settle_distance = 0.0;
  int candidates_kept = 24;      ///< projected samples returned for figures
  std::uint64_t seed = 1;
  projection::Settings projection = projection::Settings::with_iterations(30);
  perception::Settings perception = perception::Settings::tracking();
  RankingSettings ranking;
  /// s by which commands lead the plan (0: v1): the robot's velocity time constant, Protocol v2's tau, plus
  /// the command latency when make_planner builds it (command_lead).
  double response_time = 0.0;

  /// The offline expert: 120 samples, 8 CEM iterations, 50 projection iterations, on `threads` cores.
  /// Until issue 12 it was 2000 samples x 4 iterations; the narrower, longer search labels about 6 times
  /// faster and finds a cheaper plan on about 80 % of cycles (docs/learning.md, "The expert's budget").
  static ProjCemSettings offline_expert(int threads);

  /// True when every field is usable: samples at least 4 (and within the projection's batch bound),
  /// cem_iterations at least 1, elite_fraction in (0, 1], spreads finite and >= 0, candidates_kept >= 0, and
  /// projection (with batch = samples), perception and ranking valid and agreeing (perception's nearest points
  /// are the optimizer's obstacles). Otherwise false, and *error names the field and the rule, e.g.
  /// "samples (0) must be at least 4" or "ranking.occlusion_stride (0) must be at least 1".
  bool validate(std::string* error = nullptr) const;
  bool operator==(const ProjCemSettings&) const = default;
};

class ProjCem final : public Planner {
 public:
  /// Throws std::invalid_argument "projcem: <validate's message>" for unusable settings.
  explicit ProjCem(const ProjCemSettings& settings = {});
  ~ProjCem() override;
  std::string name() const override { return "projcem"; }
  void reset() override;
  using Planner::plan;
  /// One cycle; allocates nothing after the first cycles when `out` is reused.
  void plan(const PlannerInput& input, PlannerOutput& out) override;
  const PlanRecord& last_record() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::planners
