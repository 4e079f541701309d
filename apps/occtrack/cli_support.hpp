// What every subcommand shares: how it is added with its options, its body run under the documented exit
// codes (README.md, "Exit codes"), its output files, and the provenance line of the files it makes.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace occtrack::app {

/// "occtrack bench projection": the command's name as typed, the prefix of its messages.
std::string command_label(const CLI::App& cmd);

/// Adds the subcommand `name` and a fresh Options for it. The options are shared: CLI11 writes them while
/// parsing, and the command's body reads them when it runs, after add_*_command has returned.
template <typename Options>
std::pair<CLI::App*, std::shared_ptr<Options>> add_command(CLI::App& parent, const std::string& name,
                                                           const std::string& description) {
  return {parent.add_subcommand(name, description), std::make_shared<Options>()};
}

/// A command that only groups subcommands (bench, dataset, scenario): one of them must be given.
CLI::App* add_command_group(CLI::App& parent, const std::string& name, const std::string& description);

/// The largest safety-layer standoff (s) a command takes with --standoff (`run`, `bench suite`, `bench
/// policy`); the layer itself allows up to its horizon.
inline constexpr double kStandoffMax = 2.0;
/// The range of --moving-speed-max (m/s) a command takes; the layer itself takes any speed >= 0.
inline constexpr double kMovingSpeedMin = 0.1, kMovingSpeedMax = 5.0;

/// An option whose value must lie in [low, high] (CLI11 refuses others before the command runs), with its
/// default shown in --help.
template <typename T, typename Bound>
CLI::Option* add_bounded_option(CLI::App* cmd, const std::string& name, T& value, const std::string& description,
                                Bound low, Bound high) {
  return cmd->add_option(name, value, description)->check(CLI::Range(low, high))->capture_default_str();
}

/// An option that takes one of `choices` (CLI11 refuses others before the command runs), with its default
/// shown in --help.
CLI::Option* add_choice_option(CLI::App* cmd, const std::string& name, std::string& value,
                               const std::string& description, const std::vector<std::string>& choices);

/// Makes `body` the command's callback; what it returns is the exit code. An exception out of it (an
/// io::InputError, a std::invalid_argument from a settings check, a file that cannot be read...) means a file
/// or setting was refused: "<label>: <what>" on standard error and kExitInputError (README.md, "Exit codes").
/// Case mismatches (kExitMismatch) and non-finite solves (kExitSolveFailed) are returned by the body itself.
void set_command_body(CLI::App* cmd, int& exit_code, std::function<int()> body);

/// Writes `text` to `path`. False, with "<who>: <path>: cannot write the file" on standard error, when it
/// cannot.
bool write_text_file(const std::string& who, const std::string& path, const std::string& text);

/// The created_by of a file the tool writes: "occtrack[ VERSION]: <command>".
std::string created_by(const std::string& command);

}  // namespace occtrack::app
