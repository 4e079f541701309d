// The planning cycle's shared context (src/planners/cycle.hpp, private to the library): what it keeps between
// cycles must give what a fresh evaluation gives.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>

#include "planners/cycle.hpp"

namespace {

using namespace occtrack;

TEST(CycleContext, ShiftGivesWhatAFreshContextGivesWhateverTheIntervalsBefore) {
  // shift keeps the basis at the shifted times for the last dt; a changed dt must not reuse it.
  const projection::Settings ps;
  const perception::Settings perception;
  const planners::RankingSettings ranking;
  planners::detail::Context kept(ps, perception, ranking);
  const int n = ps.coefficients();
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 2.0);
  Eigen::RowVectorXd xi(2 * n);
  for (int i = 0; i < 2 * n; ++i) xi(i) = normal(rng);
  const Eigen::Vector2d offset(0.3, -0.2);
  Eigen::RowVectorXd from_kept, from_fresh, previous;
  double previous_dt = -1.0;
  for (double dt : {0.05, 0.05, 0.1, 0.0, 0.05, 0.3, 0.3, 0.05}) {
    kept.shift(xi, dt, offset, from_kept);
    planners::detail::Context fresh(ps, perception, ranking);
    fresh.shift(xi, dt, offset, from_fresh);
    ASSERT_EQ(from_kept.size(), 2 * n);
    for (int i = 0; i < 2 * n; ++i) EXPECT_EQ(from_kept(i), from_fresh(i)) << "dt " << dt << ", coefficient " << i;
    // Different intervals give different plans (the comparison above can tell a stale basis).
    if (previous_dt >= 0.0 && dt != previous_dt) {
      EXPECT_GT((from_kept - previous).cwiseAbs().maxCoeff(), 1e-6) << "dt " << previous_dt << " then " << dt;
    }
    previous = from_kept;
    previous_dt = dt;
  }
}

}  // namespace
