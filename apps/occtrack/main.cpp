// occtrack: occlusion-aware target tracking from the command line. `occtrack --help` lists the subcommands.
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "launcher.hpp"

int main(int argc, char** argv) {
  CLI::App app{"occtrack: occlusion-aware target tracking with a learned, projection-based policy"};
  app.require_subcommand(1);
  int exit_code = occtrack::app::kExitOk;
  occtrack::app::add_project_command(app, exit_code);
  occtrack::app::add_bench_command(app, exit_code);
  occtrack::app::add_run_command(app, exit_code);
  occtrack::app::add_scenario_command(app, exit_code);
#ifdef OCCTRACK_HAVE_LEARNING
  occtrack::app::add_train_command(app, exit_code);
#endif
  occtrack::app::add_dataset_command(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Under an MPI launcher every rank parses the same command line: rank 0 alone prints help or the error.
    if (const auto launcher = occtrack::app::launcher_ranks(); launcher && launcher->rank > 0) return e.get_exit_code();
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "occtrack: error: " << e.what() << "\n";
    return occtrack::app::kExitInputError;
  }
  return exit_code;
}
