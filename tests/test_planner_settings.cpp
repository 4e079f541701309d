// Planner settings check themselves: every numeric field set to NaN or out of its range makes validate()
// fail with a message that names the field; construction refuses such settings with that message, before it
// builds anything from them. Also the planning cycle's record (PlanRecord).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/learned.hpp"
#include "occtrack/planners/proj_cem.hpp"
#include "occtrack/planners/ranking.hpp"
#include "occtrack/sim/world.hpp"

using namespace occtrack;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One broken field: its name as validate() must spell it, and how to break it.
template <typename Settings>
struct Sentinel {
  std::string field;
  std::function<void(Settings&)> set;
};

/// For each sentinel: the defaults with that one field broken fail validate(), the message names the field,
/// nothing else.
template <typename Settings>
void expect_each_sentinel_named(const std::vector<Sentinel<Settings>>& sentinels) {
  const Settings defaults;
  std::string error;
  ASSERT_TRUE(defaults.validate(&error)) << error;
  for (const auto& sentinel : sentinels) {
    Settings broken = defaults;
    sentinel.set(broken);
    error.clear();
    EXPECT_FALSE(broken.validate(&error)) << sentinel.field << " was accepted";
    EXPECT_NE(error.find(sentinel.field), std::string::npos)
        << "message \"" << error << "\" does not name " << sentinel.field;
  }
}

std::vector<Sentinel<planners::RankingSettings>> ranking_sentinels(const std::string& prefix) {
  using R = planners::RankingSettings;
  return {
      {prefix + "occlusion_weight", [](R& r) { r.occlusion_weight = kNaN; }},
      {prefix + "tracking_weight", [](R& r) { r.tracking_weight = -1.0; }},
      {prefix + "smoothness_weight", [](R& r) { r.smoothness_weight = kNaN; }},
      {prefix + "violation_weight", [](R& r) { r.violation_weight = -2.0; }},
      {prefix + "occlusion_margin", [](R& r) { r.occlusion_margin = 0.0; }},
      {prefix + "occlusion_stride", [](R& r) { r.occlusion_stride = 0; }},
      {prefix + "late_occlusion_weight", [](R& r) { r.late_occlusion_weight = 1.5; }},
      {prefix + "shadow_weight", [](R& r) { r.shadow_weight = kNaN; }},
      {prefix + "shadow_horizon", [](R& r) { r.shadow_horizon = -1.0; }},
      {prefix + "shadow_depth_cap", [](R& r) { r.shadow_depth_cap = 0.0; }},
      {prefix + "near_weight", [](R& r) { r.near_weight = kNaN; }},
      {prefix + "near_horizon", [](R& r) { r.near_horizon = kNaN; }},
      {prefix + "near_clearance", [](R& r) { r.near_clearance = -0.1; }},
      {prefix + "moving_reach", [](R& r) { r.moving_reach = kNaN; }},
      {prefix + "moving_reach_speed_min", [](R& r) { r.moving_reach_speed_min = -0.1; }},
      {prefix + "moving_reach_speed_max", [](R& r) { r.moving_reach_speed_max = kNaN; }},
      {prefix + "band.min", [](R& r) { r.band.min = 0.0; }},
      {prefix + "band.reference", [](R& r) { r.band.reference = kNaN; }},
      // Below the reference: "<prefix>band.reference (2) must not exceed band.max (1.5)".
      {"band.max (1.5)", [](R& r) { r.band.max = 1.5; }},
  };
}

}  // namespace

TEST(PlannerSettings, RankingNamesEveryBrokenField) { expect_each_sentinel_named(ranking_sentinels("")); }

TEST(PlannerSettings, RankingRefusesAStrideOfZeroInsteadOfLoopingForever) {
  planners::RankingSettings r;
  r.occlusion_stride = 0;
  try {
    planners::Ranking ranking(r, projection::Settings{});
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("occlusion_stride (0) must be at least 1"), std::string::npos) << e.what();
  }
}

// The near term's room from moving points (RankingSettings::moving_reach), on a plan that stands at the origin:
// the nearest approach of each point is where it starts, so the term is that reach less that distance.
TEST(PlannerSettings, RankingKeepsMoreRoomFromAMovingPointOnly) {
  const projection::Settings projection;
  const Eigen::RowVectorXd still = Eigen::RowVectorXd::Zero(2 * projection.coefficients());
  const Eigen::Vector4d target(2.0, 0.0, 0.0, 0.0);
  auto near = [&](double reach, const Eigen::RowVector4d& point) {
    planners::RankingSettings r;
    r.moving_reach = reach;
    const planners::Ranking ranking(r, projection);
    planners::PointRows points(2, 4);
    points.row(0) << 1.0, 0.0, 0.0, 0.0;  // a still point 1 m away: beyond near_clearance (0.4 m)
    points.row(1) = point;
    return ranking.evaluate(still, target, points, points).near;
  };
  const Eigen::RowVector4d crossing(0.6, 0.0, 0.0, 0.5), slow(0.6, 0.0, 0.0, 0.2), fast(0.8, 0.0, 0.0, 3.0);
  EXPECT_EQ(near(0.0, crossing), 0.0);                 // 0.6 m away: outside the near clearance
  EXPECT_NEAR(near(0.5, crossing), 0.4 + 0.5 * 0.5 - 0.6, 1e-12);
  EXPECT_EQ(near(0.5, slow), 0.0);                     // under moving_reach_speed_min: a still object's jitter
  EXPECT_NEAR(near(0.5, fast), 0.4 + 1.0 * 0.5 - 0.8, 1e-12);  // speed capped at moving_reach_speed_max
  EXPECT_NEAR(near(1.0, crossing), 0.4 + 0.5 * 1.0 - 0.6, 1e-12);

  // Behind the safety layer only the points its evidence shows moved count, whatever their speed estimates.
  planners::RankingSettings r;
  r.moving_reach = 0.5;
  const planners::Ranking ranking(r, projection);
  planners::PointRows points(2, 4);
  points.row(0) << 1.0, 0.0, 0.0, 0.0;
  points.row(1) = crossing;
  planners::RowMask moving(2);
  moving << false, false;  // the layer's evidence shows the crossing point still (a static wall's drift)
  EXPECT_EQ(ranking.evaluate(still, target, points, points, nullptr, nullptr, &moving).near, 0.0);
  moving << false, true;
  EXPECT_NEAR(ranking.evaluate(still, target, points, points, nullptr, nullptr, &moving).near, 0.4 + 0.25 - 0.6,
              1e-12);
  const planners::RowMask other(3, false);  // not one flag per point: speed alone decides
  EXPECT_NEAR(ranking.evaluate(still, target, points, points, nullptr, nullptr, &other).near, 0.4 + 0.25 - 0.6,
              1e-12);
}

TEST(PlannerSettings, ProjCemNamesEveryBrokenField) {
  using P = planners::ProjCemSettings;
  std::vector<Sentinel<P>> sentinels = {
      {"samples", [](P& p) { p.samples = 0; }},
      {"cem_iterations", [](P& p) { p.cem_iterations = 0; }},
      {"elite_fraction", [](P& p) { p.elite_fraction = kNaN; }},
      {"elite_fraction", [](P& p) { p.elite_fraction = 0.0; }},
      {"initial_std", [](P& p) { p.initial_std = -1.0; }},
      {"min_std", [](P& p) { p.min_std = kNaN; }},
      {"settle_distance", [](P& p) { p.settle_distance = -0.1; }},
      {"candidates_kept", [](P& p) { p.candidates_kept = -1; }},
      {"projection.horizon", [](P& p) { p.projection.horizon = kNaN; }},
      {"projection.iterations", [](P& p) { p.projection.iterations = 0; }},
      {"perception.voxel_size", [](P& p) { p.perception.voxel_size = 0.0; }},
      {"perception.nearest_count", [](P& p) { p.perception.nearest_count = 59; }},  // not the optimizer's 60
      {"response_time", [](P& p) { p.response_time = -0.1; }},
      {"response_time", [](P& p) { p.response_time = kNaN; }},
  };
  for (auto& s : ranking_sentinels("ranking.")) sentinels.push_back({s.field, [set = s.set](P& p) { set(p.ranking); }});
  expect_each_sentinel_named(sentinels);
}

TEST(PlannerSettings, ProjCemRefusesBadSettingsWithTheFieldBeforeBuildingItsOptimizer) {
  planners::ProjCemSettings s;
  s.samples = 0;  // once reported as "projection settings: batch (0)"
  try {
    planners::ProjCem planner(s);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "projcem: samples (0) must be at least 4");
  }
  s = {};
  s.ranking.occlusion_stride = 0;
  EXPECT_THROW(planners::ProjCem{s}, std::invalid_argument);
}

TEST(PlannerSettings, FollowerNamesEveryBrokenField) {
  using F = planners::FollowerSettings;
  std::vector<Sentinel<F>> sentinels = {
      {"projection.steps", [](F& f) { f.projection.steps = 0; }},
      {"projection.speed_max", [](F& f) { f.projection.speed_max = kNaN; }},
      {"response_time", [](F& f) { f.response_time = 1e3; }},  // beyond the horizon
  };
  for (auto& s : ranking_sentinels("ranking.")) sentinels.push_back({s.field, [set = s.set](F& f) { set(f.ranking); }});
  expect_each_sentinel_named(sentinels);
  F broken;
  broken.ranking.band.min = kNaN;
  EXPECT_THROW(planners::Follower{broken}, std::invalid_argument);
}

TEST(PlannerSettings, LearnedPolicyNamesEveryBrokenFieldBeforeReadingAModel) {
  using L = planners::LearnedPolicySettings;
  std::vector<Sentinel<L>> sentinels = {
      {"batch", [](L& l) { l.batch = 0; }},
      {"candidates_kept", [](L& l) { l.candidates_kept = -3; }},
      {"projection.accel_max", [](L& l) { l.projection.accel_max = kNaN; }},
      {"perception.cloud_size", [](L& l) { l.perception.cloud_size = 0; }},
      {"perception.nearest_count", [](L& l) { l.perception.nearest_count = 7; }},
      {"response_time", [](L& l) { l.response_time = -1.0; }},
  };
  for (auto& s : ranking_sentinels("ranking.")) sentinels.push_back({s.field, [set = s.set](L& l) { set(l.ranking); }});
  expect_each_sentinel_named(sentinels);
  L s;
  s.batch = 0;
  s.model_path = "/nonexistent/model.safetensors";  // the settings are refused first, not the missing file
  try {
    planners::LearnedPolicy planner(s);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "planner cvae: batch (0) must be at least 1");
  }
}

TEST(PlannerSettings, EveryPlannerRecordsItsLastCycle) {
  const core::Scenario scenario = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml");
  sim::World world(scenario);
  std::mt19937_64 rng(1);
  const core::Scan scan = world.scan(scenario.robot_position, 0.0, rng);
  planners::PlannerInput input;
  input.robot_position = scenario.robot_position;
  input.robot_velocity = scenario.robot_velocity;
  input.target_position = world.target_position(0.0);
  input.target_velocity = world.target_velocity(0.0);
  input.scan = &scan;

  planners::ProjCemSettings cem;
  cem.samples = 32;
  planners::ProjCem projcem(cem);
  planners::Follower follower;
  for (planners::Planner* planner : std::vector<planners::Planner*>{&projcem, &follower}) {
    EXPECT_FALSE(planner->last_record().valid) << planner->name() << ": no cycle yet";
    const planners::PlannerOutput out = planner->plan(input);
    ASSERT_TRUE(out.ok) << out.message;
    const planners::PlanRecord& record = planner->last_record();
    ASSERT_TRUE(record.valid) << planner->name();
    EXPECT_EQ(record.frame.origin, input.robot_position);
    EXPECT_EQ(record.frame.target.head<2>(), input.target_position - input.robot_position);
    EXPECT_TRUE(std::isfinite(record.terms.total));
    // The record's plan is the plan sent: its coefficients evaluate to the world-frame plan.
    const core::BernsteinBasis basis = core::bernstein_basis(10, 100, 5.0);
    ASSERT_EQ(out.plan.size(), 100u);
    for (int k = 0; k < 100; k += 33) {
      const Eigen::Vector2d p(basis.P.row(k).dot(record.xi.head(11)), basis.P.row(k).dot(record.xi.tail(11)));
      EXPECT_NEAR((input.robot_position + p - out.plan[static_cast<std::size_t>(k)]).norm(), 0.0, 1e-9);
    }
    // A cycle that brakes invalidates it.
    planners::PlannerInput bad = input;
    bad.scan = nullptr;
    EXPECT_FALSE(planner->plan(bad).ok);
    EXPECT_FALSE(planner->last_record().valid) << planner->name();
  }
}
