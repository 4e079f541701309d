// occtrack bench projection [--batch B] [--obstacles N] [--iterations K] [--precision float|double]
//                           [--threads T] [--repeats R] [--literal] [--json]
//
// Times repeated solves of random but plausible problems (see projection/problem_generator.hpp) and prints the
// median and p99 in milliseconds (core::summarize_timings). --literal also times the line-by-line reference
// implementation in the same run and prints the speed-up.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "cli_support.hpp"
#include "commands.hpp"
#include "occtrack/core/timing.hpp"
#include "occtrack/projection/literal_projector.hpp"
#include "occtrack/projection/problem_generator.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::app {

namespace {

struct Options {
  int batch = 30;
  int obstacles = 60;
  int iterations = 50;
  std::string precision = "float";
  int threads = 1;
  int repeats = 200;
  int problems = 16;
  double moving_share = 0.0;
  bool literal = false;
  int literal_repeats = 5;
  bool json = false;
};

// Solves problems round-robin; the first pass over them is a warm-up and is not timed.
template <typename Solver, typename T>
core::TimingSummary time_solves(Solver& solver, std::vector<projection::Problem<T>>& problems,
                                projection::Result<T>& result, int repeats) {
  std::string error;
  for (auto& p : problems)
    if (!solver.solve(p, result, &error)) throw std::runtime_error(error);
  std::vector<double> ms;
  ms.reserve(repeats);
  for (int r = 0; r < repeats; ++r) {
    auto& p = problems[r % problems.size()];
    const auto start = std::chrono::steady_clock::now();
    solver.solve(p, result, &error);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  return core::summarize_timings(std::move(ms));
}

template <typename T>
int run(const Options& o) {
  projection::Settings s;
  s.batch = o.batch;
  s.obstacles = o.obstacles;
  s.iterations = o.iterations;
  s.threads = o.threads;
  std::string error;
  if (!s.validate(&error)) {
    std::cerr << "occtrack bench projection: " << error << "\n";
    return kExitInputError;
  }
  std::vector<projection::Problem<T>> problems(o.problems);
  for (int i = 0; i < o.problems; ++i)
    projection::fill_random_problem<T>(s, {static_cast<std::uint64_t>(1000 + i), o.moving_share}, problems[i]);
  projection::Projector<T> projector(s);
  projection::Result<T> result = projector.make_result();
  const core::TimingSummary fast = time_solves(projector, problems, result, o.repeats);

  core::TimingSummary literal;
  if (o.literal) {
    projection::LiteralProjector<T> reference(s);
    std::vector<projection::Problem<T>> few(problems.begin(), problems.begin() + std::min(o.problems, 2));
    literal = time_solves(reference, few, result, o.literal_repeats);
  }

  const char* precision = sizeof(T) == 4 ? "float" : "double";
  if (o.json) {
    nlohmann::json out = {{"benchmark", "projection"}, {"precision", precision}, {"batch", o.batch},
                          {"obstacles", o.obstacles},  {"iterations", o.iterations}, {"threads", o.threads},
                          {"repeats", fast.count},     {"median_ms", fast.median},    {"p99_ms", fast.p99},
                          {"mean_ms", fast.mean},      {"min_ms", fast.min}};
    if (o.literal) {
      out["literal"] = {{"median_ms", literal.median}, {"p99_ms", literal.p99}, {"repeats", literal.count}};
      out["speedup_vs_literal"] = literal.median / fast.median;
    }
    std::cout << out.dump() << "\n";
  } else {
    std::printf("projection, %s: batch %d, %d obstacle points, %d iterations, %d thread(s)\n", precision, o.batch,
                o.obstacles, o.iterations, o.threads);
    std::printf("  fast:    median %.3f ms, p99 %.3f ms, min %.3f ms (%d solves)\n", fast.median, fast.p99, fast.min,
                fast.count);
    if (o.literal)
      std::printf("  literal: median %.3f ms, p99 %.3f ms (%d solves); speed-up %.1fx\n", literal.median,
                  literal.p99, literal.count, literal.median / fast.median);
  }
  return kExitOk;
}

}  // namespace

void add_bench_command(CLI::App& app, int& exit_code) {
  CLI::App* bench = add_command_group(app, "bench", "Measure the speed of occtrack's components");
  add_bench_suite_command(*bench, exit_code);
  add_bench_paper_command(*bench, exit_code);
#ifdef OCCTRACK_HAVE_LEARNING
  add_bench_train_command(*bench, exit_code);
#endif
  add_bench_policy_command(*bench, exit_code);
  auto [cmd, o] =
      add_command<Options>(*bench, "projection", "Time the batched projection on random plausible problems");
  add_bounded_option(cmd, "--batch", o->batch, "Samples per solve (B)", 1, 1000000);
  add_bounded_option(cmd, "--obstacles", o->obstacles, "Obstacle points per sample (N)", 0, 100000);
  add_bounded_option(cmd, "--iterations", o->iterations, "Projection iterations (K)", 1, 1000000);
  add_choice_option(cmd, "--precision", o->precision, "Arithmetic", {"float", "double"});
  add_bounded_option(cmd, "--threads", o->threads, "Threads the batch is split over", 1, 1024);
  add_bounded_option(cmd, "--repeats", o->repeats, "Timed solves", 1, 10000000);
  add_bounded_option(cmd, "--problems", o->problems, "Distinct random problems, solved round-robin", 1, 10000);
  add_bounded_option(cmd, "--moving-share", o->moving_share, "Share of moving obstacles in the random worlds",
                     0.0, 1.0);
  cmd->add_flag("--literal", o->literal, "Also time the line-by-line reference implementation, in the same run");
  add_bounded_option(cmd, "--literal-repeats", o->literal_repeats, "Timed solves of the reference implementation",
                     1, 100000);
  cmd->add_flag("--json", o->json, "Print one JSON object (median_ms, p99_ms, ...) instead of text");
  set_command_body(cmd, exit_code, [o] { return o->precision == "float" ? run<float>(*o) : run<double>(*o); });
}

}  // namespace occtrack::app
