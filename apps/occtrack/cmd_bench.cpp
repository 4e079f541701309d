// occtrack bench projection [--batch B] [--obstacles N] [--iterations K] [--precision float|double]
//                           [--threads T] [--repeats R] [--literal] [--json]
//
// Times repeated solves of random but plausible problems (see projection/problem_generator.hpp) and prints the
// median and p99 in milliseconds. --literal also times the line-by-line reference implementation in the
// same run and prints the speed-up.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <vector>

#include "commands.hpp"
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

struct Timing {
  double median_ms = 0, p99_ms = 0, mean_ms = 0, min_ms = 0;
  int repeats = 0;
};

Timing summarize(std::vector<double> ms) {
  std::sort(ms.begin(), ms.end());
  Timing t;
  t.repeats = static_cast<int>(ms.size());
  t.median_ms = ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
  t.p99_ms = ms[std::min(ms.size() - 1, static_cast<std::size_t>(0.99 * ms.size()))];
  t.min_ms = ms.front();
  double sum = 0;
  for (double x : ms) sum += x;
  t.mean_ms = sum / ms.size();
  return t;
}

// Solves problems round-robin; the first pass over them is a warm-up and is not timed.
template <typename Solver, typename T>
Timing time_solves(Solver& solver, std::vector<projection::Problem<T>>& problems, projection::Result<T>& result,
                   int repeats) {
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
  return summarize(ms);
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
  const Timing fast = time_solves(projector, problems, result, o.repeats);

  Timing literal;
  if (o.literal) {
    projection::LiteralProjector<T> reference(s);
    std::vector<projection::Problem<T>> few(problems.begin(), problems.begin() + std::min(o.problems, 2));
    literal = time_solves(reference, few, result, o.literal_repeats);
  }

  const char* precision = sizeof(T) == 4 ? "float" : "double";
  if (o.json) {
    nlohmann::json out = {{"benchmark", "projection"}, {"precision", precision}, {"batch", o.batch},
                          {"obstacles", o.obstacles},  {"iterations", o.iterations}, {"threads", o.threads},
                          {"repeats", fast.repeats},   {"median_ms", fast.median_ms}, {"p99_ms", fast.p99_ms},
                          {"mean_ms", fast.mean_ms},   {"min_ms", fast.min_ms}};
    if (o.literal) {
      out["literal"] = {{"median_ms", literal.median_ms}, {"p99_ms", literal.p99_ms}, {"repeats", literal.repeats}};
      out["speedup_vs_literal"] = literal.median_ms / fast.median_ms;
    }
    std::cout << out.dump() << "\n";
  } else {
    std::printf("projection, %s: batch %d, %d obstacle points, %d iterations, %d thread(s)\n", precision, o.batch,
                o.obstacles, o.iterations, o.threads);
    std::printf("  fast:    median %.3f ms, p99 %.3f ms, min %.3f ms (%d solves)\n", fast.median_ms, fast.p99_ms,
                fast.min_ms, fast.repeats);
    if (o.literal)
      std::printf("  literal: median %.3f ms, p99 %.3f ms (%d solves); speed-up %.1fx\n", literal.median_ms,
                  literal.p99_ms, literal.repeats, literal.median_ms / fast.median_ms);
  }
  return kExitOk;
}

}  // namespace

void add_bench_command(CLI::App& app, int& exit_code) {
  CLI::App* bench = app.add_subcommand("bench", "Measure the speed of occtrack's components");
  bench->require_subcommand(1);
  add_bench_suite_command(*bench, exit_code);
#ifdef OCCTRACK_HAVE_LEARNING
  add_bench_train_command(*bench, exit_code);
#endif
  add_bench_policy_command(*bench, exit_code);
  auto o = std::make_shared<Options>();
  CLI::App* cmd = bench->add_subcommand("projection", "Time the batched projection on random plausible problems");
  cmd->add_option("--batch", o->batch, "Samples per solve (B)")->check(CLI::Range(1, 1000000))->capture_default_str();
  cmd->add_option("--obstacles", o->obstacles, "Obstacle points per sample (N)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_option("--iterations", o->iterations, "Projection iterations (K)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--precision", o->precision, "Arithmetic")
      ->check(CLI::IsMember({"float", "double"}))
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "Threads the batch is split over")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  cmd->add_option("--repeats", o->repeats, "Timed solves")->check(CLI::Range(1, 10000000))->capture_default_str();
  cmd->add_option("--problems", o->problems, "Distinct random problems, solved round-robin")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  cmd->add_option("--moving-share", o->moving_share, "Share of moving obstacles in the random worlds")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_flag("--literal", o->literal, "Also time the line-by-line reference implementation, in the same run");
  cmd->add_option("--literal-repeats", o->literal_repeats, "Timed solves of the reference implementation")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print one JSON object (median_ms, p99_ms, ...) instead of text");
  cmd->callback([o, &exit_code]() {
    try {
      exit_code = o->precision == "float" ? run<float>(*o) : run<double>(*o);
    } catch (const std::exception& e) {
      std::cerr << "occtrack bench projection: " << e.what() << "\n";
      exit_code = kExitInputError;
    }
  });
}

}  // namespace occtrack::app
