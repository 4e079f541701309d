// AutoChaser (planners/autochaser.hpp): its distance field, its viewpoint graph search and its corridor QP on
// small worlds with known answers, and the planner in closed loop.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/autochaser.hpp"
#include "occtrack/planners/follower.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/geometry.hpp"
#include "test_helpers.hpp"

using namespace occtrack;
using planners::AutoChaserSettings;
using planners::Vec2;
namespace ac = planners::autochaser;

namespace {

using occtrack::test::box;

/// One wall, x in [1.3, 1.7], y in [-1, 1].
core::Scenario wall_world() {
  core::Scenario s;
  s.name = "wall";
  s.duration = 10.0;
  s.obstacles.push_back(box({1.5, 0.0}, {0.4, 2.0}));
  s.target = {{0.0, {0.0, 0.0}}, {10.0, {0.0, 0.0}}};
  return s;
}

/// The edge cost of paper_setup.md, restated: length + w_v / sqrt(mean visibility) + w_d |dist - d_des|.
double edge_cost(const AutoChaserSettings& s, const Vec2& a, const Vec2& b, double visibility, const Vec2& target) {
  return (b - a).norm() + s.visibility_weight / std::sqrt(visibility) +
         s.distance_weight * std::abs((b - target).norm() - s.distance_desired);
}

}  // namespace

TEST(AutoChaser, DistanceFieldIsTheExactSignedDistanceAtNodesCappedAndIgnoresMovingObstacles) {
  core::Scenario s = wall_world();
  core::ObstacleSpec mover;
  mover.center = {-3.0, 0.0};
  mover.radius = 0.5;
  mover.path = {{-3.0, 0.0}, {-3.0, 3.0}};
  mover.speed = 1.0;
  s.obstacles.push_back(mover);
  const ac::DistanceField field(s, 0.4, 2.0);
  const sim::Shape wall = sim::shape_of(s.obstacles[0]);
  // Grid-aligned points (the wall's box starts the grid 2.8 m + its bounding radius away; sample widely).
  for (double x = -2.0; x <= 5.0; x += 0.37)
    for (double y = -3.0; y <= 3.0; y += 0.41) {
      const Vec2 p(x, y);
      const double exact = std::min(2.0, sim::signed_distance(wall, p));
      // Bilinear interpolation of a 1-Lipschitz field: within a cell diagonal of the exact value.
      EXPECT_NEAR(field.at(p), exact, 0.4 * std::sqrt(2.0) + 1e-12) << x << ", " << y;
    }
  EXPECT_DOUBLE_EQ(field.at({-3.0, 0.0}), 2.0) << "the moving obstacle is not in the map";
  EXPECT_DOUBLE_EQ(field.at({50.0, 50.0}), 2.0) << "outside the grid: the cap";
  // Nodes carry exact values: the field is exact wherever the exact distance is linear over a cell, e.g.
  // straight out from the wall's face.
  EXPECT_NEAR(field.at({2.9, 0.0}), 1.2, 1e-9);
  const ac::DistanceField empty(core::Scenario{}, 0.4, 2.0);
  EXPECT_EQ(empty.nodes_x(), 0);
  EXPECT_DOUBLE_EQ(empty.at({0.0, 0.0}), 2.0);
}

TEST(AutoChaser, ViewpointsBehindTheWallAreNotCandidates) {
  const core::Scenario s = wall_world();
  const AutoChaserSettings settings;
  const ac::DistanceField field(s, settings.field_resolution, settings.field_truncation);
  const ac::Layer layer = ac::make_layer(field, settings, {0.0, 0.0});
  ASSERT_GT(layer.cells.size(), 50u);
  const sim::Shape wall = sim::shape_of(s.obstacles[0]);
  int right_of_wall = 0;
  for (std::size_t k = 0; k < layer.cells.size(); ++k) {
    const Vec2& c = layer.cells[k];
    const double d = c.norm();
    EXPECT_GT(d, settings.distance_min);
    EXPECT_LT(d, settings.distance_max);
    // Exact geometry: the line of sight is clear and the cell keeps clear of the wall.
    EXPECT_FALSE(sim::segment_intersects(wall, Vec2::Zero(), c)) << c.transpose();
    EXPECT_GT(sim::signed_distance(wall, c), 0.0) << c.transpose();
    EXPECT_GT(layer.visibility[k], settings.visibility_min);
    if (c.x() > 1.7) {
      ++right_of_wall;
      EXPECT_GT(std::abs(c.y()), 1.0) << "behind the wall only around its ends: " << c.transpose();
    }
  }
  EXPECT_GT(right_of_wall, 0);
  // The cell straight behind the wall, at the desired distance, is out.
  for (const Vec2& c : layer.cells) EXPECT_GT((c - Vec2(2.5, 0.0)).norm(), 1e-9);
}

TEST(AutoChaser, GraphSearchFindsTheCheapestPathAroundTheWallAsBruteForceDoes) {
  // The robot stands behind the wall (occluded), a little above its middle; the target stands still. Two
  // layers, so that every path can be enumerated.
  const core::Scenario s = wall_world();
  AutoChaserSettings settings;
  settings.layers = 2;
  const ac::DistanceField field(s, settings.field_resolution, settings.field_truncation);
  const Vec2 robot(3.0, 0.6);
  const std::vector<ac::Layer> layers = {ac::make_layer(field, settings, {0.0, 0.0}),
                                         ac::make_layer(field, settings, {0.0, 0.3})};
  const double spacing = 1.4;
  const ac::ViewpointPath path = ac::search_viewpoints(field, settings, robot, layers, spacing);
  ASSERT_EQ(path.layers_reached, 2);
  ASSERT_EQ(path.waypoints.size(), 2u);

  // Brute force over every pair of cells with the same rules.
  const double connect = path.connect_distance;
  const double step = 0.5 * settings.field_resolution;
  double best = std::numeric_limits<double>::infinity();
  Vec2 best_a, best_b;
  for (std::size_t a = 0; a < layers[0].cells.size(); ++a) {
    const Vec2& ca = layers[0].cells[a];
    if ((ca - robot).norm() >= connect || !(field.min_along(robot, ca, step) > settings.safe_radius)) continue;
    const double first = edge_cost(settings, robot, ca, layers[0].visibility[a], layers[0].target);
    for (std::size_t b = 0; b < layers[1].cells.size(); ++b) {
      const Vec2& cb = layers[1].cells[b];
      if ((cb - ca).norm() >= connect || !(field.min_along(ca, cb, step) > settings.safe_radius)) continue;
      const double c =
          first + edge_cost(settings, ca, cb, 0.5 * (layers[0].visibility[a] + layers[1].visibility[b]), layers[1].target);
      if (c < best) best = c, best_a = ca, best_b = cb;
    }
  }
  EXPECT_NEAR(path.cost, best, 1e-9);
  EXPECT_LT((path.waypoints[0] - best_a).norm(), 1e-12);
  EXPECT_LT((path.waypoints[1] - best_b).norm(), 1e-12);
  // The known answer: around the wall's upper end (the robot is above its middle), in sight of the target.
  const sim::Shape wall = sim::shape_of(s.obstacles[0]);
  EXPECT_GT(path.waypoints[0].y(), 1.0);
  EXPECT_FALSE(sim::segment_intersects(wall, layers[0].target, path.waypoints[0]));
  EXPECT_FALSE(sim::segment_intersects(wall, layers[1].target, path.waypoints[1]));
}

TEST(AutoChaser, GraphSearchWithoutObstaclesStopsAtTheDesiredDistanceOnTheRobotsSide) {
  const AutoChaserSettings settings;
  const ac::DistanceField field;  // no prior map: free everywhere
  const std::vector<ac::Layer> layers(3, ac::make_layer(field, settings, {0.0, 0.0}));
  const ac::ViewpointPath path = ac::search_viewpoints(field, settings, {3.0, 0.0}, layers, 1.4);
  ASSERT_EQ(path.layers_reached, 3);
  for (const Vec2& w : path.waypoints) EXPECT_LT((w - Vec2(2.5, 0.0)).norm(), 1e-12) << w.transpose();
  // 0.5 m to the first cell, then zero-length edges; every edge pays w_v / sqrt(2) (visibility at the cap).
  EXPECT_NEAR(path.cost, 0.5 + 3 * settings.visibility_weight / std::sqrt(2.0), 1e-9);
}

TEST(AutoChaser, GraphSearchLengthensEdgesForAFastTargetAndReportsTheDeepestLayerOtherwise) {
  AutoChaserSettings settings;
  settings.layers = 3;
  const ac::DistanceField field;
  // The target moves 3 m per layer (2.1 m/s): candidate cells lie on a 0.5 m grid about it, strictly within
  // 4 m, so 2 m edges reach the second layer (x <= 1.5, then x <= 3) but not the third (x >= 5.5); the
  // robot's 2 m/s x 1.4 s = 2.8 m edges do.
  std::vector<ac::Layer> layers;
  for (int l = 1; l <= 3; ++l) layers.push_back(ac::make_layer(field, settings, {3.0 * l, 0.0}));
  const ac::ViewpointPath scaled = ac::search_viewpoints(field, settings, {0.0, 0.0}, layers, 1.4);
  EXPECT_EQ(scaled.layers_reached, 3);
  EXPECT_DOUBLE_EQ(scaled.connect_distance, 2.8);
  settings.speed_max = 1.0;  // 1.4 m per layer: no better than d_connect, so no second search
  const ac::ViewpointPath partial = ac::search_viewpoints(field, settings, {0.0, 0.0}, layers, 1.4);
  EXPECT_EQ(partial.layers_reached, 2);
  EXPECT_DOUBLE_EQ(partial.connect_distance, 2.0);
  EXPECT_EQ(partial.waypoints.size(), static_cast<std::size_t>(partial.layers_reached));
}

TEST(AutoChaser, ARobotInsideAnObstacleOnTheMapCanStillLeaveIt) {
  const core::Scenario s = wall_world();
  const AutoChaserSettings settings;
  const ac::DistanceField field(s, settings.field_resolution, settings.field_truncation);
  const Vec2 robot(1.5, 0.9);  // inside the wall, near its upper end
  ASSERT_LT(field.at(robot), 0.0);
  const std::vector<ac::Layer> layers(2, ac::make_layer(field, settings, {0.0, 0.0}));
  const ac::ViewpointPath path = ac::search_viewpoints(field, settings, robot, layers, 1.4);
  EXPECT_EQ(path.layers_reached, 2);
}

namespace {

/// The unconstrained minimum-jerk path with the soft waypoint pull, computed independently of the planner:
/// monomials in seconds, each segment's first three coefficients carried from the previous segment's end,
/// the cost integrated by 4-point Gauss-Legendre (exact for the degree-6 integrand), its quadratic form
/// read off by differences (exact for a quadratic), and the normal equations solved. Returns per segment
/// the coefficients of tau^0 .. tau^6, for one axis.
std::vector<Eigen::Matrix<double, 7, 1>> reference_path(double p0, double v0, double a0, const std::vector<double>& w,
                                                       double T, double weight) {
  const int K = static_cast<int>(w.size());
  auto segments_of = [&](const Eigen::VectorXd& y) {
    std::vector<Eigen::Matrix<double, 7, 1>> c(K);
    double p = p0, v = v0, a = a0;
    for (int s = 0; s < K; ++s) {
      c[s] << p, v, a / 2, y(4 * s), y(4 * s + 1), y(4 * s + 2), y(4 * s + 3);
      double pe = 0, ve = 0, ae = 0;
      for (int i = 0; i <= 6; ++i) {
        pe += c[s](i) * std::pow(T, i);
        if (i >= 1) ve += i * c[s](i) * std::pow(T, i - 1);
        if (i >= 2) ae += i * (i - 1) * c[s](i) * std::pow(T, i - 2);
      }
      p = pe, v = ve, a = ae;
    }
    return c;
  };
  auto cost = [&](const Eigen::VectorXd& y) {
    const auto c = segments_of(y);
    const double nodes[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
    const double weights[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
    double f = 0;
    for (int s = 0; s < K; ++s) {
      for (int q = 0; q < 4; ++q) {
        const double tau = 0.5 * T * (nodes[q] + 1);
        const double jerk = 6 * c[s](3) + 24 * c[s](4) * tau + 60 * c[s](5) * tau * tau + 120 * c[s](6) * tau * tau * tau;
        f += 0.5 * T * weights[q] * jerk * jerk;
      }
      double end = 0;
      for (int i = 0; i <= 6; ++i) end += c[s](i) * std::pow(T, i);
      f += weight * (end - w[s]) * (end - w[s]);
    }
    return f;
  };
  const int n = 4 * K;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd Q(n, n);
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd ei = Eigen::VectorXd::Unit(n, i);
    q(i) = 0.5 * (cost(ei) - cost(-ei));
    for (int j = 0; j < n; ++j) {
      const Eigen::VectorXd ej = Eigen::VectorXd::Unit(n, j);
      Q(i, j) = cost(ei + ej) - cost(ei) - cost(ej) + cost(zero);
    }
  }
  return segments_of(Q.fullPivLu().solve(-q));
}

double evaluate(const Eigen::Matrix<double, 7, 1>& c, double tau, int r) {
  double v = 0;
  for (int i = r; i <= 6; ++i) {
    double f = 1;
    for (int k = 0; k < r; ++k) f *= i - k;
    v += f * c(i) * std::pow(tau, i - r);
  }
  return v;
}

}  // namespace

TEST(AutoChaser, CorridorQpWithLooseCorridorsIsTheUnconstrainedMinimumJerkPath) {
  AutoChaserSettings settings;
  settings.corridor_half_width = 100.0;  // never active
  const Vec2 start(0.5, -1.0), velocity(1.0, 0.3), acceleration(-0.5, 0.8);
  const std::vector<Vec2> waypoints = {{1.5, 0.0}, {2.0, 2.0}, {0.5, 3.0}, {-1.0, 2.5}};
  const double T = 1.4;
  ac::SmoothPath path;
  std::string error;
  ASSERT_TRUE(ac::smooth_path(settings, start, velocity, acceleration, waypoints, T, path, &error)) << error;
  ASSERT_EQ(path.segments, 4);
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<double> w;
    for (const Vec2& p : waypoints) w.push_back(p(axis));
    const auto reference = reference_path(start(axis), velocity(axis), acceleration(axis), w, T, settings.waypoint_weight);
    for (int s = 0; s < 4; ++s)
      for (double f : {0.0, 0.2, 0.5, 0.9, 1.0}) {
        const double t = (s + f) * T;
        if (f == 1.0 && s == 3) continue;
        for (int r = 0; r < 3; ++r)
          EXPECT_NEAR(path.derivative(t, r)(axis), evaluate(reference[s], f * T, r), 1e-7)
              << "axis " << axis << " segment " << s << " fraction " << f << " derivative " << r;
      }
  }
  // The start state is held exactly.
  EXPECT_LT((path.derivative(0.0, 0) - start).norm(), 1e-10);
  EXPECT_LT((path.derivative(0.0, 1) - velocity).norm(), 1e-10);
  EXPECT_LT((path.derivative(0.0, 2) - acceleration).norm(), 1e-9);
}

TEST(AutoChaser, CorridorQpKeepsTightCorridorsAndStaysContinuous) {
  AutoChaserSettings settings;
  settings.corridor_half_width = 0.05;
  const Vec2 start(0.0, 0.0), velocity(0.0, 1.5), acceleration(1.0, 0.0);  // starts sideways: pulls off the line
  const std::vector<Vec2> waypoints = {{2.0, 0.0}, {2.0, 2.0}, {4.0, 2.0}};
  const double T = 1.4;
  ac::SmoothPath tight, loose;
  std::string error;
  ASSERT_TRUE(ac::smooth_path(settings, start, velocity, acceleration, waypoints, T, tight, &error)) << error;
  AutoChaserSettings loose_settings = settings;
  loose_settings.corridor_half_width = 100.0;
  ASSERT_TRUE(ac::smooth_path(loose_settings, start, velocity, acceleration, waypoints, T, loose, &error)) << error;
  double worst_loose = 0.0, worst_tight = 0.0;
  for (int s = 0; s < 3; ++s) {
    const Vec2 from = s == 0 ? start : waypoints[s - 1], to = waypoints[s];
    for (int c = 1; c <= settings.corridor_points; ++c) {
      const double f = c / (settings.corridor_points + 1.0);
      const Vec2 line = from + f * (to - from);
      const Vec2 off_tight = tight.derivative((s + f) * T, 0) - line;
      worst_tight = std::max(worst_tight, off_tight.cwiseAbs().maxCoeff());
      worst_loose = std::max(worst_loose, (loose.derivative((s + f) * T, 0) - line).cwiseAbs().maxCoeff());
    }
    if (s + 1 < 3) {  // continuity at the knot (both sides of it)
      for (int r = 0; r < 3; ++r) {
        EXPECT_LT((tight.derivative((s + 1) * T - 1e-9, r) - tight.derivative((s + 1) * T + 1e-9, r)).norm(), 1e-6);
      }
    }
  }
  EXPECT_GT(worst_loose, 0.2) << "the example must need its corridors";
  EXPECT_LE(worst_tight, 0.05 + 1e-9);
  EXPECT_GT(worst_tight, 0.05 - 1e-6) << "some corridor is active";
}

TEST(AutoChaser, SettingsAreCheckedByName) {
  AutoChaserSettings s;
  std::string error;
  EXPECT_TRUE(s.validate(&error)) << error;
  s.layers = 0;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("layers (0) must be at least 1"), std::string::npos) << error;
  s = {};
  s.distance_min = 5.0;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("distance_min (5) must be less than distance_max (4)"), std::string::npos) << error;
  s = {};
  s.waypoints = -1;
  EXPECT_THROW(planners::AutoChaser{s}, std::invalid_argument);
  planners::PlannerOptions options;
  options.waypoints = -3;
  try {
    planners::make_planner("autochaser", options);
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("autochaser: waypoints (-3) must be >= 0"), std::string::npos) << e.what();
  }
  options.waypoints = 100;
  EXPECT_EQ(planners::make_planner("autochaser", options)->name(), "autochaser-wp100");
  EXPECT_EQ(planners::make_planner("autochaser")->name(), "autochaser");
}

TEST(AutoChaser, HoldsStillForATargetNeverSeenAndBrakesOnANonFiniteRobot) {
  core::Scan scan;
  scan.angle_increment = 2 * M_PI / 360;
  scan.ranges.assign(360, std::numeric_limits<double>::infinity());
  planners::AutoChaser planner;
  planner.use_prior(wall_world());
  planners::PlannerInput input;
  input.scan = &scan;
  input.robot_velocity = {1.0, 0.0};
  input.target_position = {std::nan(""), 0.0};
  input.target_age = std::numeric_limits<double>::infinity();
  planners::PlannerOutput out = planner.plan(input);
  EXPECT_TRUE(out.ok) << out.message;
  EXPECT_EQ(out.command_velocity, Vec2::Zero());
  input.target_age = 0.0;
  input.target_position = {-2.0, 0.0};
  input.robot_position = {std::nan(""), 0.0};
  out = planner.plan(input);
  EXPECT_FALSE(out.ok);
  EXPECT_EQ(out.command_velocity, Vec2::Zero());
  EXPECT_FALSE(planner.last_record().valid);
}

TEST(AutoChaser, PredictsFromTheEstimatesTimeWhenTheTargetIsHidden) {
  core::Scan scan;
  scan.angle_increment = 2 * M_PI / 360;
  scan.ranges.assign(360, std::numeric_limits<double>::infinity());
  AutoChaserSettings settings;
  settings.layers = 1;
  settings.horizon = 1.0;
  planners::AutoChaser planner(settings);  // no prior: free space
  planners::PlannerInput input;
  input.scan = &scan;
  input.target_position = {0.0, 0.0};
  input.target_velocity = {1.0, 0.0};
  input.target_age = 2.0;  // the target is now near (2, 0), at (3, 0) a second later
  planner.plan(input);
  ASSERT_EQ(planner.last_viewpoints().layers_reached, 1);
  // Robot at the origin, target predicted at (3, 0): the cheapest viewpoint is 2.5 m from it towards the robot.
  EXPECT_LT((planner.last_viewpoints().waypoints[0] - Vec2(0.5, 0.0)).norm(), 1e-12);
}

TEST(AutoChaser, TracksTheOrbitTargetWithoutCollisionAndKeepsItMostlyInSight) {
  const core::Scenario scenario = io::read_scenario(OCCTRACK_TEST_DATA_DIR "/scenarios/orbit.yaml");
  sim::EpisodeSettings settings;
  planners::Follower follower;
  const auto naive = sim::run_episode(scenario, follower, settings).metrics;
  for (const int waypoints : {0, 100}) {
    planners::PlannerOptions options;
    options.waypoints = waypoints;
    auto planner = planners::make_planner("autochaser", options);
    planner->use_prior(scenario);  // sim::run_episode does this too once it knows the hook
    const auto m = sim::run_episode(scenario, *planner, settings).metrics;
    EXPECT_EQ(m.collisions, 0) << planner->name();
    EXPECT_EQ(m.planner_failures, 0) << planner->name();
    EXPECT_LT(m.occlusion_time_s, 0.5 * naive.occlusion_time_s) << planner->name();
    EXPECT_GT(m.compute_ms.median, 0.0) << planner->name();
  }
}
