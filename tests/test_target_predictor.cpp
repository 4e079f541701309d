// The target predictor (core/target_predictor.hpp, docs/target_prediction.md) on analytic target paths with the
// simulator's estimate noise, against the constant-velocity prediction from the same estimates: a circle (the
// turn model must win), a zig-zag and a straight line (it must not lose much); and the ranking's use of its
// forecast.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include "occtrack/core/target_predictor.hpp"
#include "occtrack/planners/ranking.hpp"

namespace occtrack {
namespace {

using core::TargetPredictor;
using core::TargetPredictorSettings;
using Path = std::function<Eigen::Vector2d(double)>;
constexpr double kPi = std::numbers::pi;

struct MeanErrors {
  double constant_velocity = 0.0, predictor = 0.0;
  double last_turn_weight = 0.0;
};

/// Feeds noisy estimates of `path` every 0.05 s for `duration` s (Gaussian 0.05 m and 0.1 m/s, the spec's
/// sensing noise) and returns the mean error `ahead` seconds ahead over the estimates after the first 5 s.
MeanErrors replay(const Path& path, double duration, double ahead, std::uint64_t seed = 7) {
  TargetPredictor predictor;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  MeanErrors e;
  int count = 0;
  const double h = 1e-4;
  for (int i = 0; i * 0.05 + ahead <= duration; ++i) {
    const double t = i * 0.05;
    const Eigen::Vector2d velocity = (path(t + h) - path(t - h)) / (2 * h);
    const double a = noise(rng), b = noise(rng), c = noise(rng), d = noise(rng);
    const Eigen::Vector2d p = path(t) + 0.05 * Eigen::Vector2d(a, b), v = velocity + 0.1 * Eigen::Vector2d(c, d);
    predictor.observe(t, p, v);
    if (t < 5.0) continue;
    Eigen::Vector2d predicted, predicted_velocity;
    predictor.state_at(ahead, predicted, predicted_velocity);
    e.constant_velocity += (p + v * ahead - path(t + ahead)).norm();
    e.predictor += (predicted - path(t + ahead)).norm();
    ++count;
  }
  e.constant_velocity /= count;
  e.predictor /= count;
  e.last_turn_weight = predictor.motion().turn_weight;
  return e;
}

Eigen::Vector2d circle(double t) {  // radius 3 m at 1.5 m/s: 0.5 rad/s
  return 3.0 * Eigen::Vector2d(std::cos(0.5 * t), std::sin(0.5 * t));
}

Eigen::Vector2d zig_zag(double t) {  // 1.5 m/s, heading +-45 degrees, switching every 2 s
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  const double leg = 2.0;
  for (double s = 0.0; s < t; s += leg) {
    const double along = std::min(leg, t - s);
    const double heading = (static_cast<int>(std::floor(s / leg + 0.5)) % 2 == 0 ? 1.0 : -1.0) * kPi / 4;
    p += 1.5 * along * Eigen::Vector2d(std::cos(heading), std::sin(heading));
  }
  return p;
}

TEST(TargetPredictor, ForeseesACircleBetterThanConstantVelocity) {
  for (const double ahead : {1.0, 2.0}) {
    const MeanErrors e = replay(circle, 40.0, ahead);
    SCOPED_TRACE("ahead " + std::to_string(ahead) + " s: cv " + std::to_string(e.constant_velocity) +
                 " m, predictor " + std::to_string(e.predictor) + " m");
    EXPECT_LT(e.predictor, 0.6 * e.constant_velocity);
    EXPECT_GT(e.last_turn_weight, 0.8);  // the mixture has learnt that the turn model predicts better
  }
}

TEST(TargetPredictor, LosesLittleOnAZigZag) {
  // Turn rate and heading change every 2 s: the turn model foresees nothing; the mixture must fall back.
  for (const double ahead : {0.5, 1.0, 2.0}) {
    const MeanErrors e = replay(zig_zag, 60.0, ahead);
    SCOPED_TRACE("ahead " + std::to_string(ahead) + " s: cv " + std::to_string(e.constant_velocity) +
                 " m, predictor " + std::to_string(e.predictor) + " m");
    EXPECT_LT(e.predictor, 1.1 * e.constant_velocity);
  }
}

TEST(TargetPredictor, IsConstantVelocityOnAStraightLine) {
  const Path line = [](double t) { return Eigen::Vector2d(1.0 + 1.2 * t, -0.5 * t); };
  const MeanErrors e = replay(line, 30.0, 2.0);
  EXPECT_LT(e.predictor, 1.05 * e.constant_velocity);
}

TEST(TargetPredictor, PredictsFromTheNewestEstimateWhenItKnowsNothingElse) {
  TargetPredictor predictor;
  EXPECT_TRUE(predictor.empty());
  predictor.observe(2.0, Eigen::Vector2d(1, 2), Eigen::Vector2d(0.5, 0));
  EXPECT_FALSE(predictor.empty());
  EXPECT_FALSE(predictor.motion().fitted);
  Eigen::Vector2d p, v;
  predictor.state_at(2.0, p, v);
  EXPECT_NEAR(p.x(), 2.0, 1e-12);
  EXPECT_NEAR(p.y(), 2.0, 1e-12);
  // Repeats (a hidden target's estimate), older and non-finite estimates are ignored.
  predictor.observe(2.0, Eigen::Vector2d(9, 9), Eigen::Vector2d(9, 9));
  predictor.observe(1.0, Eigen::Vector2d(9, 9), Eigen::Vector2d(9, 9));
  predictor.observe(3.0, Eigen::Vector2d(NAN, 0), Eigen::Vector2d(0, 0));
  EXPECT_EQ(predictor.motion().position, Eigen::Vector2d(1, 2));
  predictor.reset();
  EXPECT_TRUE(predictor.empty());
}

TEST(TargetPredictor, SpreadGrowsAlongTheHorizonAndPredictMatchesStateAt) {
  TargetPredictor predictor;
  for (int i = 0; i < 60; ++i) predictor.observe(0.05 * i, circle(0.05 * i), 1.5 * Eigen::Vector2d(-std::sin(0.025 * i), std::cos(0.025 * i)));
  Eigen::VectorXd times(5);
  times << 0.0, 0.5, 1.0, 2.0, 3.5;
  Eigen::MatrixX2d positions;
  Eigen::VectorXd sigma;
  predictor.predict(0.3, times, positions, sigma);
  for (Eigen::Index k = 0; k < times.size(); ++k) {
    Eigen::Vector2d p, v;
    predictor.state_at(0.3 + times(k), p, v);
    EXPECT_NEAR((positions.row(k).transpose() - p).norm(), 0.0, 1e-9);
    EXPECT_NEAR(sigma(k), predictor.sigma_at(0.3 + times(k)), 1e-12);
    if (k > 0) {
      EXPECT_GT(sigma(k), sigma(k - 1));
    }
  }
}

TEST(TargetPredictor, SettingsNameTheBrokenField) {
  std::string error;
  TargetPredictorSettings s;
  EXPECT_TRUE(s.validate(&error)) << error;
  s.window = 0.0;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("window"), std::string::npos);
  s = {};
  s.memory = 1.5;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("memory"), std::string::npos);
  s = {};
  s.min_estimates = 1;
  EXPECT_THROW(TargetPredictor{s}, std::invalid_argument);
  planners::RankingSettings r;
  r.predictor.turn_decay = -1.0;
  EXPECT_FALSE(r.validate(&error));
  EXPECT_NE(error.find("predictor.turn_decay"), std::string::npos);
}

TEST(TargetPredictor, RankingWithALinearForecastOfUnitWeightsRanksAsWithoutOne) {
  planners::RankingSettings settings;
  settings.late_occlusion_weight = 1.0;  // the linear ranking's taper off: every step counts fully
  const projection::Settings projection;
  const planners::Ranking ranking(settings, projection);
  const int m = projection.steps, n = projection.coefficients();
  Eigen::RowVectorXd xi(2 * n);
  for (int i = 0; i < n; ++i) xi(i) = 2.0 * i / (n - 1), xi(n + i) = 0.5 * i / (n - 1);
  const Eigen::Vector4d target(2.0, 0.3, 0.4, 0.1);
  planners::PointRows points(3, 4);
  points << 1.0, 0.6, 0.0, 0.0, 1.5, 0.2, 0.0, 0.0, 3.0, -1.0, 0.0, 0.2;
  planners::TargetForecast forecast;
  forecast.positions.resize(m, 2);
  forecast.weights.setOnes(m);
  for (int k = 0; k < m; ++k)
    forecast.positions.row(k) << target(0) + target(2) * ranking.basis().times(k), target(1) + target(3) * ranking.basis().times(k);
  forecast.valid = true;
  const planners::RankingTerms linear = ranking.evaluate(xi, target, points, points);
  const planners::RankingTerms forecasted = ranking.evaluate(xi, target, points, points, nullptr, &forecast);
  EXPECT_NEAR(forecasted.occlusion, linear.occlusion, 1e-12);
  EXPECT_NEAR(forecasted.tracking, linear.tracking, 1e-12);
  EXPECT_NEAR(forecasted.total, linear.total, 1e-9);
  EXPECT_GT(linear.occlusion, 0.0);  // the case does test the occlusion term
  // Weights that drop the far future change the tracking term to the near steps' mean.
  forecast.weights.setZero();
  forecast.weights(0) = 1.0;
  const planners::RankingTerms near = ranking.evaluate(xi, target, points, points, nullptr, &forecast);
  EXPECT_NEAR(near.tracking, std::pow((target.head<2>()).norm() - settings.band.reference, 2), 1e-9);
}

}  // namespace
}  // namespace occtrack
