// Subcommands of the occtrack tool, one source file each. Each adds itself to the app and sets `exit_code`
// when it runs.
#pragma once

#include <CLI/CLI.hpp>

namespace occtrack::app {

void add_project_command(CLI::App& app, int& exit_code);
void add_bench_command(CLI::App& app, int& exit_code);
void add_bench_suite_command(CLI::App& bench, int& exit_code);
void add_bench_paper_command(CLI::App& bench, int& exit_code);  // cmd_bench_paper.cpp
void add_run_command(CLI::App& app, int& exit_code);
void add_scenario_command(CLI::App& app, int& exit_code);
void add_scenario_stats_command(CLI::App& scenario, int& exit_code);  // cmd_scenario_stats.cpp
void add_scenario_predict_command(CLI::App& scenario, int& exit_code);  // cmd_scenario_predict.cpp
void add_dataset_command(CLI::App& app, int& exit_code);       // cmd_dataset.cpp
void add_bench_policy_command(CLI::App& bench, int& exit_code);  // cmd_bench_policy.cpp
#ifdef OCCTRACK_HAVE_LEARNING
void add_train_command(CLI::App& app, int& exit_code);          // learning/cmd_train.cpp
void add_bench_train_command(CLI::App& bench, int& exit_code);  // learning/cmd_bench_train.cpp
#endif

// Exit codes shared by the subcommands.
inline constexpr int kExitOk = 0;
inline constexpr int kExitInputError = 1;     // a file or setting was refused; the message says why
inline constexpr int kExitMismatch = 3;       // a conformance case did not match its expected outputs
inline constexpr int kExitSolveFailed = 4;    // the solver reported a non-finite result

}  // namespace occtrack::app
