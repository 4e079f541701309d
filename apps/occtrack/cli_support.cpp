#include "cli_support.hpp"

#include <exception>
#include <fstream>
#include <iostream>
#include <utility>

#include "commands.hpp"

namespace occtrack::app {

std::string command_label(const CLI::App& cmd) {
  // The root app's name is the program path CLI11 read from argv[0]; the messages say "occtrack".
  std::string label;
  for (const CLI::App* app = &cmd; app->get_parent() != nullptr; app = app->get_parent())
    label = " " + app->get_name() + label;
  return "occtrack" + label;
}

CLI::App* add_command_group(CLI::App& parent, const std::string& name, const std::string& description) {
  CLI::App* group = parent.add_subcommand(name, description);
  group->require_subcommand(1);
  return group;
}

CLI::Option* add_choice_option(CLI::App* cmd, const std::string& name, std::string& value,
                               const std::string& description, const std::vector<std::string>& choices) {
  return cmd->add_option(name, value, description)->check(CLI::IsMember(choices))->capture_default_str();
}

void set_command_body(CLI::App* cmd, int& exit_code, std::function<int()> body) {
  cmd->callback([cmd, &exit_code, body = std::move(body)]() {
    try {
      exit_code = body();
    } catch (const std::exception& e) {
      std::cerr << command_label(*cmd) << ": " << e.what() << "\n";
      exit_code = kExitInputError;
    }
  });
}

bool write_text_file(const std::string& who, const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (out << text) return true;
  std::cerr << who << ": " << path << ": cannot write the file\n";
  return false;
}

std::string created_by(const std::string& command) {
  std::string text = "occtrack";
#ifdef OCCTRACK_VERSION
  text += " " OCCTRACK_VERSION;
#endif
  return text + ": " + command;
}

}  // namespace occtrack::app
