#include <gtest/gtest.h>

#include <Eigen/LU>
#include <stdexcept>

#include "occtrack/core/bernstein.hpp"
#include "occtrack/projection/kkt.hpp"
#include "occtrack/projection/literal_projector.hpp"
#include "occtrack/projection/problem_generator.hpp"
#include "test_helpers.hpp"

using namespace occtrack;
using projection::Problem;
using projection::Projector;
using projection::Result;
using projection::Settings;

namespace {

template <typename T, typename Solver>
Result<T> solve(Solver& solver, const Settings& s, const Problem<T>& problem) {
  Result<T> result;
  result.resize(s);
  std::string error;
  EXPECT_TRUE(solver.solve(problem, result, &error)) << error;
  return result;
}

template <typename T>
Problem<T> random_problem(const Settings& s, std::uint64_t seed, double moving_share = 0.0) {
  Problem<T> p;
  projection::fill_random_problem<T>(s, {seed, moving_share}, p);
  return p;
}

double worst(const Result<double>& a, const Result<double>& b) {
  return std::max({test::worst_error(a.xi_init, b.xi_init), test::worst_error(a.xi, b.xi),
                   test::worst_error(a.residual, b.residual)});
}

}  // namespace

// The fast solver against the line-by-line implementation of the spec, on problems unlike the conformance
// cases: more samples than one block, moving points, other radii, weights and sizes.
TEST(Projector, MatchesLiteralImplementationOnRandomProblems) {
  struct Variant {
    int batch, obstacles, iterations;
    double moving, radius, rho_obstacle;
    int degree, steps, via1, via2;
  };
  const Variant variants[] = {{7, 13, 20, 0.0, 0.4, 1.0, 10, 100, 49, 74},
                              {40, 20, 8, 0.5, 0.6, 2.0, 10, 100, 49, 74},
                              {3, 60, 30, 1.0, 0.3, 0.5, 8, 57, 20, 40},
                              {5, 0, 15, 0.0, 0.4, 1.0, 12, 80, 30, 60}};
  for (const Variant& v : variants) {
    Settings s;
    s.batch = v.batch;
    s.obstacles = v.obstacles;
    s.iterations = v.iterations;
    s.obstacle_radius = v.radius;
    s.rho.obstacle = v.rho_obstacle;
    s.degree = v.degree;
    s.steps = v.steps;
    s.via_step_1 = v.via1;
    s.via_step_2 = v.via2;
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      SCOPED_TRACE("batch " + std::to_string(v.batch) + " obstacles " + std::to_string(v.obstacles) + " seed " +
                   std::to_string(seed));
      const auto problem = random_problem<double>(s, seed, v.moving);
      Projector<double> fast(s);
      projection::LiteralProjector<double> literal(s);
      EXPECT_LE(worst(solve<double>(fast, s, problem), solve<double>(literal, s, problem)), 1e-9);
    }
  }
}

TEST(Projector, FloatAgreesWithDouble) {
  Settings s;  // the defaults: B 30, N 60, K 50
  for (std::uint64_t seed : {11u, 12u, 13u}) {
    const auto problem = random_problem<double>(s, seed, 0.3);
    Projector<double> exact(s);
    Projector<float> fast(s);
    const auto a = solve<double>(exact, s, problem);
    const auto b = solve<float>(fast, s, test::cast_problem<float>(problem));
    EXPECT_EQ(b.status, projection::SolveStatus::solved);
    EXPECT_LE(test::worst_error(b.xi, a.xi), 5e-2) << "seed " << seed;
    EXPECT_LE(test::worst_error(b.residual, a.residual), 5e-2) << "seed " << seed;
  }
}

TEST(Projector, ThreadsAndBatchingDoNotChangeTheAnswer) {
  Settings s;
  s.batch = 70;  // several blocks of 16 samples, the last one partial
  s.iterations = 12;
  const auto problem = random_problem<double>(s, 21, 0.2);
  Projector<double> one(s);
  const auto reference = solve<double>(one, s, problem);
  Settings threaded = s;
  threaded.threads = 2;
  Projector<double> two(threaded);
  EXPECT_LE(worst(solve<double>(two, threaded, problem), reference), 1e-12);

  // Each sample alone gives what it gives in the batch.
  Settings single = s;
  single.batch = 1;
  Projector<double> alone(single);
  for (int b : {0, 15, 16, 69}) {
    Problem<double> one_sample;
    one_sample.resize(single);
    for (auto [dst, src] : {std::pair{&one_sample.robot_velocity, &problem.robot_velocity},
                            {&one_sample.obstacles, &problem.obstacles},
                            {&one_sample.target, &problem.target},
                            {&one_sample.terminal, &problem.terminal},
                            {&one_sample.via_points, &problem.via_points},
                            {&one_sample.lambda0, &problem.lambda0},
                            {&one_sample.distance_min, &problem.distance_min},
                            {&one_sample.distance_max, &problem.distance_max},
                            {&one_sample.xi_bar, &problem.xi_bar}})
      *dst = src->row(b);
    const auto r = solve<double>(alone, single, one_sample);
    EXPECT_LE(test::worst_error(r.xi, reference.xi.row(b)), 1e-12) << "sample " << b;
  }
}

TEST(Projector, ResidualHistoryAveragesToTheResidual) {
  Settings s;
  s.batch = 4;
  s.iterations = 25;
  s.record_residual_history = true;
  const auto problem = random_problem<double>(s, 5);
  Projector<double> projector(s);
  const auto r = solve<double>(projector, s, problem);
  ASSERT_EQ(r.residual_history.rows(), 4);
  ASSERT_EQ(r.residual_history.cols(), 25);
  for (int b = 0; b < 4; ++b) EXPECT_NEAR(r.residual_history.row(b).mean(), r.residual(b), 1e-12);
}

TEST(Projector, IterationsReduceTheConstraintResidual) {
  // The projection's purpose: constraint violation falls. Not to zero for every sample (a random sample's
  // constraint set can be infeasible, e.g. a tracking band that crosses an obstacle), so the check is on
  // the batch: the total residual of the last iteration is below half that of the first.
  Settings s;
  s.iterations = 150;
  s.record_residual_history = true;
  const auto problem = random_problem<double>(s, 8);
  Projector<double> projector(s);
  const auto r = solve<double>(projector, s, problem);
  const double first = r.residual_history.col(0).sum();
  const double last = r.residual_history.col(s.iterations - 1).sum();
  EXPECT_LT(last, 0.5 * first);
}

TEST(Projector, ReportsNonFiniteOutcomeAsStatus) {
  Settings s;
  s.batch = 2;
  s.iterations = 5;
  Projector<float> projector(s);
  auto problem = random_problem<float>(s, 3);
  problem.xi_bar.row(1).setConstant(3e37f);  // finite input whose squares overflow float
  const auto r = solve<float>(projector, s, problem);
  EXPECT_EQ(r.status, projection::SolveStatus::non_finite);
  EXPECT_STREQ(projection::to_string(r.status), "non_finite");
}

// The blocks of the inverse KKT matrices solve their systems (spec "Initial guess" and step 9): for step 9,
// [[Q, A_eq'], [A_eq, 0]] [M11 M12; M21 M22] = I gives A_eq M11 = 0, A_eq M12 = I and Q M11 + A_eq' M21 = I,
// so Q M11 - I has the columns of A_eq' (checked through the projector onto the null space of A_eq); for the
// initial guess, A_init initial_guess = I.
TEST(KktFactors, BlocksSolveTheirSystems) {
  Settings s;
  s.rho.obstacle = 1.5;
  s.obstacles = 17;
  const projection::KktFactors<double> kkt(s);
  const int n = s.coefficients(), m = s.steps;
  const auto basis = core::bernstein_basis(s.degree, m, s.horizon);
  Eigen::MatrixXd A_eq(4, n);
  A_eq << basis.P.row(0), basis.Pd.row(0), basis.P.row(m - 1), basis.Pd.row(m - 1);
  Eigen::MatrixXd A_init(6, n);
  A_init << A_eq, basis.P.row(s.via_step_1), basis.P.row(s.via_step_2);
  const Eigen::MatrixXd Qm = s.rho.obstacle * s.obstacles * basis.P.transpose() * basis.P +
                             s.rho.tracking * basis.P.transpose() * basis.P +
                             s.rho.velocity * basis.Pd.transpose() * basis.Pd +
                             s.rho.acceleration * basis.Pdd.transpose() * basis.Pdd;
  const Eigen::MatrixXd Q = Qm + s.rho.projection * Eigen::MatrixXd::Identity(n, n);
  EXPECT_LE((A_eq * kkt.M11).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LE((A_eq * kkt.M12 - Eigen::MatrixXd::Identity(4, 4)).cwiseAbs().maxCoeff(), 1e-9);
  const Eigen::MatrixXd null_projector =
      Eigen::MatrixXd::Identity(n, n) - A_eq.transpose() * (A_eq * A_eq.transpose()).inverse() * A_eq;
  EXPECT_LE((null_projector * (Q * kkt.M11 - Eigen::MatrixXd::Identity(n, n))).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LE((kkt.M11_Qm - kkt.M11 * Qm).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LE((A_init * kkt.initial_guess - Eigen::MatrixXd::Identity(6, 6)).cwiseAbs().maxCoeff(), 1e-9);

  // The float blocks are the double ones, rounded.
  const projection::KktFactors<float> single(s);
  EXPECT_TRUE(single.M11 == kkt.M11.cast<float>());
  EXPECT_TRUE(single.initial_guess == kkt.initial_guess.cast<float>());
}

TEST(KktFactors, RejectsUnusableSettings) {
  Settings s;
  s.rho.projection = 0.0;
  EXPECT_THROW(projection::KktFactors<double>{s}, std::invalid_argument);
}
