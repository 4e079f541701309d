// Counting heap allocations in a region of a test (tests/allocation_counter.cpp replaces the global operator
// new in every form and wraps the C allocator, so only the executables that link it count).
//
//   {
//     occtrack::test::AllocationCount count;
//     perception.process(scan, robot, out);
//     EXPECT_EQ(count.allocations(), 0);
//   }
//
// A count covers every thread, from construction to destruction: each call of operator new / new[] (plain,
// aligned, nothrow) and each malloc, calloc, realloc, aligned_alloc or posix_memalign made by code linked
// into the executable (Eigen's allocations go through malloc, not operator new). Frees are not counted: an
// allocation freed before the region ends still counts, which a heap-size comparison would miss.
//
// Finding the place: with OCCTRACK_TRACE_ALLOCATIONS=1 in the environment, every counted allocation prints a
// backtrace to stderr (pipe through c++filt).
#pragma once

namespace occtrack::test {

class AllocationCount {
 public:
  AllocationCount();
  ~AllocationCount();
  AllocationCount(const AllocationCount&) = delete;
  AllocationCount& operator=(const AllocationCount&) = delete;

  /// Allocations since construction.
  long allocations() const;

 private:
  long start_;
};

}  // namespace occtrack::test
