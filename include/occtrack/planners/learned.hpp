// The learned policy as a planner (shared/spec/policy.md, "Planning cycle"; docs/learning.md, "Post-processing
// and the cycle"): perception, PointNet once, B latent samples through the decoder, post-processing, the
// projection from each sample's initial guess, ranking; the cheapest projected trajectory is the plan.
//
// One class covers the three variants trained on the same data:
//   cvae     (planner "cvae"):         the decoder predicts xi_bar, lambda0, via points and q = (d_min, d_max,
//                                      terminal); the projection makes every sample feasible.
//   fixed-q  (planner "cvae-fixed-q"): as cvae, but q is nominal, as Proj-CEM sets it.
//   bc       (planner "bc"):           no projection; the decoder's xi_bar are ranked as they are.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/policy/model.hpp"
#include "occtrack/projection/settings.hpp"

namespace occtrack::planners {

struct LearnedPolicySettings {
  policy::Variant variant = policy::Variant::cvae;
  std::string model_path;      ///< the model file; its variant must be `variant` (default_model_path() when empty)
  int batch = 30;              ///< B, latent samples per cycle (5 for constrained hardware)
  std::uint64_t seed = 1;      ///< of the latent samples; reset() starts the sequence over
  int candidates_kept = 30;    ///< projected samples returned for figures (at most B)
  /// Also project and rank the last cycle's plan, shifted to now (Proj-CEM's warm start), as one more row
  /// after the B samples. Not in the paper; it keeps the plan from jumping between cycles when a sample
  /// draw is poor. Off: the paper's policy exactly.
  bool keep_last_plan = true;
  /// Also project and rank a plan that stops where the robot is (braking within the acceleration bound), as
  /// one more row after those. Not in the paper; it is chosen when every other row runs into an obstacle.
  /// Ignored by bc, which projects nothing (an unprojected stop is a halt the robot cannot follow).
  bool rank_stop = true;
  /// The optimizer run at every cycle; must be the one the model was trained through (Model::check_projection),
  /// except for the iteration count, which may exceed training's. batch is set from `batch`.
  projection::Settings projection = projection::Settings::with_iterations(50);
  perception::Settings perception = perception::Settings::tracking();
  RankingSettings ranking;
  /// s by which commands lead the plan (0: v1): the robot's velocity time constant, Protocol v2's tau, plus
  /// the command latency when make_planner builds it (command_lead).
  double response_time = 0.0;

  /// True when batch >= 1, candidates_kept >= 0, and projection (with its batch set from the rows ranked),
  /// perception and ranking are valid and agree (perception's nearest points are the optimizer's obstacles).
  /// Otherwise false, and *error names the field and the rule, e.g. "batch (0) must be at least 1". The
  /// model file is checked by the constructor.
  bool validate(std::string* error = nullptr) const;
  bool operator==(const LearnedPolicySettings&) const = default;
};

/// The planner's name for a variant: "cvae", "bc", "cvae-fixed-q".
std::string learned_planner_name(policy::Variant variant);
/// The shipped model of a variant: OCCTRACK_MODEL_DIR/{cvae,bc,fixed-q}.safetensors.
std::string default_model_path(policy::Variant variant);
/// The ranking's tracking weight a variant runs with when built by name (make_planner): 5 for cvae and bc,
/// the ranking's default of 1 for fixed-q. Chosen in closed loop on validation episodes outside the benchmark
/// seeds (docs/learning.md, "The ranking's tracking weight"). LearnedPolicySettings' own default stays the
/// ranking's, so that a policy built from settings ranks by the spec's cost unless told otherwise.
double learned_tracking_weight(policy::Variant variant);
/// The ranking's moving reach (s, RankingSettings::moving_reach) a variant runs with when built by name behind
/// the safety layer (make_planner, moving_reach_for): 1 for the cvae at a batch of at least 30, else 0 (off).
/// Measured on the v2 dynamic suites and validation episodes (docs/learning.md, "The moving reach by default").
double learned_moving_reach(policy::Variant variant, int batch);

class LearnedPolicy final : public Planner {
 public:
  /// Where one cycle's time went, milliseconds (last plan() call).
  struct Timing {
    double perception = 0, pointnet = 0, decoder = 0, projection = 0, ranking = 0, total = 0;
  };

  /// The last plan() call's choice: the row ranked best (0..B-1 a sample, B the last plan), its ranking cost.
  struct Choice {
    int row = -1;                 ///< -1 when the call braked
    double cost = 0;
    bool last_plan = false;       ///< the row was the last plan, shifted (keep_last_plan)
    bool stop = false;            ///< the row was the stop plan (rank_stop)
  };

  /// Checks the settings first (std::invalid_argument "planner NAME: <validate's message>"), then loads
  /// settings.model_path (default_model_path(variant) when empty). Throws io::InputError when the file
  /// is missing (saying how to get one), refused by policy::Model, of another variant, or trained for other
  /// projection, perception (cloud and nearest sizes) or band settings.
  explicit LearnedPolicy(const LearnedPolicySettings& settings);
  /// With a model already loaded (tests, benchmarks); settings.model_path is ignored. Same checks.
  LearnedPolicy(const LearnedPolicySettings& settings, policy::Model model);
  ~LearnedPolicy() override;

  std::string name() const override;
  void reset() override;
  using Planner::plan;
  /// One cycle. Allocates nothing after the first cycles when `out` is reused (tests/test_allocation_count.cpp).
  void plan(const PlannerInput& input, PlannerOutput& out) override;
  const PlanRecord& last_record() const override;

  const Timing& last_timing() const;
  const policy::Model& model() const;
  const Choice& last_choice() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::planners
