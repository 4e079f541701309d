// Once set up, Projector::solve performs no heap allocation (threads == 1). Two independent witnesses:
// Eigen's own check (EIGEN_RUNTIME_NO_MALLOC, assertions on: any Eigen allocation aborts), and the count of
// every operator new and malloc in this program (allocation_counter.hpp).
#include <gtest/gtest.h>

#include "allocation_counter.hpp"
#include "occtrack/projection/problem_generator.hpp"
#include "occtrack/projection/projector.hpp"

namespace {

using namespace occtrack::projection;

template <typename T>
long allocations_during_solve(int batch, int obstacles, bool history, int steps = 100) {
  Settings s;
  s.steps = steps;
  s.via_step_1 = steps / 2 - 1;
  s.via_step_2 = 3 * steps / 4 - 1;
  s.batch = batch;
  s.obstacles = obstacles;
  s.iterations = 10;
  s.record_residual_history = history;
  Projector<T> projector(s);
  Problem<T> problem;
  fill_random_problem<T>(s, {7, 0.3}, problem);
  Result<T> result = projector.make_result();
  std::string error;
  occtrack::test::AllocationCount count;
  Eigen::internal::set_is_malloc_allowed(false);
  const bool ok = projector.solve(problem, result, &error);
  Eigen::internal::set_is_malloc_allowed(true);
  const long during = count.allocations();
  EXPECT_TRUE(ok) << error;
  EXPECT_EQ(result.status, SolveStatus::solved);
  return during;
}

TEST(NoAllocation, SolveDoesNotAllocateInFloatOrDouble) {
  for (int batch : {1, 5, 30, 200}) {
    EXPECT_EQ(allocations_during_solve<float>(batch, 60, false), 0) << "float, batch " << batch;
    EXPECT_EQ(allocations_during_solve<double>(batch, 60, true), 0) << "double, batch " << batch;
  }
  EXPECT_EQ(allocations_during_solve<float>(30, 0, false), 0) << "no obstacle points";
  // Longer horizons shrink the blocks so that the products' scratch space stays on the stack.
  EXPECT_EQ(allocations_during_solve<double>(40, 20, false, 1000), 0) << "double, 1000 steps";
  EXPECT_EQ(allocations_during_solve<float>(40, 20, false, 5000), 0) << "float, 5000 steps";
}

TEST(NoAllocation, TheWitnessesWork) {
  // The counter sees allocations (setting up a projector makes its workspaces)...
  occtrack::test::AllocationCount count;
  Settings s;
  Projector<float> projector(s);
  EXPECT_GT(count.allocations(), 0);
  // ...and Eigen's check is armed (it aborts on an allocation while forbidden).
  EXPECT_DEATH(
      {
        Eigen::internal::set_is_malloc_allowed(false);
        Eigen::MatrixXd m(50, 50);
        m.setZero();
      },
      "");
}

}  // namespace
