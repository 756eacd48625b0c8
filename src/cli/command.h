#pragma once
// Subcommands register themselves: each cli/cmd_*.cpp defines one static CommandRegistration, so a new
// subcommand is one new file. The setup function adds options to its CLI11 subcommand and returns the
// action to run when the subcommand was chosen.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace u3d::cli {

using CommandAction = std::function<void()>;
using CommandSetup = std::function<CommandAction(CLI::App& sub)>;

struct CommandInfo {
  std::string name;
  std::string description;
  CommandSetup setup;
};

std::vector<CommandInfo>& command_registry();

struct CommandRegistration {
  CommandRegistration(std::string name, std::string description, CommandSetup setup) {
    command_registry().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

}  // namespace u3d::cli
