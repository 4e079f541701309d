// Google Benchmark of the projection kernel: one solve of B samples, N = 60 points, K = 50 iterations, on
// random plausible problems (projection/problem_generator.hpp). Reports; never passes or fails.
//   build/bench/occtrack_benchmarks --benchmark_filter=Projection
#include <benchmark/benchmark.h>

#include "occtrack/projection/literal_projector.hpp"
#include "occtrack/projection/problem_generator.hpp"
#include "occtrack/projection/projector.hpp"

namespace {

using namespace occtrack::projection;

template <typename T, typename Solver>
void run(benchmark::State& state, int threads) {
  Settings s;
  s.batch = static_cast<int>(state.range(0));
  s.threads = threads;
  Solver solver(s);
  Problem<T> problem;
  fill_random_problem<T>(s, {42, 0.0}, problem);
  Result<T> result;
  result.resize(s);
  for (auto _ : state) {
    solver.solve(problem, result);
    benchmark::DoNotOptimize(result.xi.data());
  }
  state.counters["samples/s"] = benchmark::Counter(double(s.batch) * state.iterations(), benchmark::Counter::kIsRate);
}

void ProjectionFloat(benchmark::State& state) { run<float, Projector<float>>(state, 1); }
void ProjectionDouble(benchmark::State& state) { run<double, Projector<double>>(state, 1); }
void ProjectionFloatTwoThreads(benchmark::State& state) { run<float, Projector<float>>(state, 2); }
void LiteralProjectionDouble(benchmark::State& state) { run<double, LiteralProjector<double>>(state, 1); }

}  // namespace

BENCHMARK(ProjectionFloat)->Arg(5)->Arg(30)->Arg(200)->Arg(5000)->Unit(benchmark::kMillisecond);
BENCHMARK(ProjectionDouble)->Arg(5)->Arg(30)->Arg(200)->Arg(5000)->Unit(benchmark::kMillisecond);
BENCHMARK(ProjectionFloatTwoThreads)->Arg(200)->Arg(5000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(LiteralProjectionDouble)->Arg(5)->Arg(30)->Unit(benchmark::kMillisecond);
