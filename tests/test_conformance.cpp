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
