// Every case file in the conformance folders (tests/data/conformance/projection and ../shared's) must be
// reproduced: double within 1e-9 relative (|got - expected| <= 1e-9 max(1, |expected|)), float within 5e-2
// absolute. The literal reference implementation is held to the same standard, so that the speed baseline
// in docs/benchmarks.md is a faithful one.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "occtrack/io/projection_case.hpp"
#include "occtrack/projection/literal_projector.hpp"
#include "test_helpers.hpp"

namespace fs = std::filesystem;
using namespace occtrack;

namespace {

std::vector<std::string> case_files() { return test::conformance_case_files(); }

template <typename T, template <typename> class Solver>
double solve_and_compare(const io::ProjectionCase& c, double* worst_residual = nullptr) {
  Solver<T> solver(c.settings);
  auto problem = test::cast_problem<T>(c.problem);
  projection::Result<T> result;
  result.resize(c.settings);
  std::string error;
  EXPECT_TRUE(solver.solve(problem, result, &error)) << error;
  EXPECT_EQ(result.status, projection::SolveStatus::solved);
  const auto& e = *c.expected;
  const double residual_error = test::worst_error(result.residual, e.residual);
  if (worst_residual) *worst_residual = residual_error;
  return std::max({test::worst_error(result.xi_init, e.xi_init), test::worst_error(result.xi, e.xi),
                   residual_error});
}

}  // namespace

TEST(Conformance, FindsTheShippedCases) {
  // The three public cases ship in tests/data; a clone without ../shared still runs them.
  EXPECT_GE(case_files().size(), 3u);
}

TEST(Conformance, EveryCaseInDoubleAndFloat) {
  for (const std::string& file : case_files()) {
    SCOPED_TRACE(file);
    const io::ProjectionCase c = io::read_projection_case(file);
    ASSERT_TRUE(c.expected.has_value()) << "a conformance case must hold expected outputs";
    EXPECT_LE((solve_and_compare<double, projection::Projector>(c)), 1e-9);
    EXPECT_LE((solve_and_compare<float, projection::Projector>(c)), 5e-2);
  }
}

TEST(Conformance, LiteralReferenceReproducesEveryCase) {
  for (const std::string& file : case_files()) {
    SCOPED_TRACE(file);
    const io::ProjectionCase c = io::read_projection_case(file);
    ASSERT_TRUE(c.expected.has_value());
    EXPECT_LE((solve_and_compare<double, projection::LiteralProjector>(c)), 1e-9);
  }
}

// residual_history: every implementation fills it when asked, its row means are the residual, and the two
// Eigen implementations agree on it iteration by iteration, as on every other output.
TEST(Conformance, ResidualHistoryIsFilledAndAgreesBetweenImplementations) {
  const std::vector<std::string> files = case_files();
  ASSERT_FALSE(files.empty());
  io::ProjectionCase c = io::read_projection_case(files.front());
  c.settings.record_residual_history = true;
  const int B = c.settings.batch, K = c.settings.iterations;
  auto solve = [&](auto&& solver) {
    projection::Result<double> result;
    result.resize(c.settings);
    result.residual_history.setConstant(-1.0);  // a sentinel that no residual can take
    std::string error;
    EXPECT_TRUE(solver.solve(c.problem, result, &error)) << error;
    return result;
  };
  const projection::Result<double> fast = solve(projection::Projector<double>(c.settings));
  const projection::Result<double> literal = solve(projection::LiteralProjector<double>(c.settings));
  for (const projection::Result<double>* r : {&fast, &literal}) {
    ASSERT_EQ(r->residual_history.rows(), B);
    ASSERT_EQ(r->residual_history.cols(), K);
    EXPECT_GE(r->residual_history.minCoeff(), 0.0);
    EXPECT_GT(r->residual_history.maxCoeff(), 0.0);
    for (int b = 0; b < B; ++b) EXPECT_NEAR(r->residual_history.row(b).mean(), r->residual(b), 1e-12);
  }
  EXPECT_LE(test::worst_error(fast.residual_history, literal.residual_history), 1e-9);
  EXPECT_LE(test::worst_error(literal.residual, c.expected->residual), 1e-9);
}
