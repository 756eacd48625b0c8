#pragma once
// Subcommands register themselves: each cli/cmd_*.cpp defines one static CommandRegistration, so a new
// subcommand is one new file. The setup function adds options to its CLI11 subcommand and returns the
// action to run when the subcommand was chosen.
#include <CLI/CLI.hpp>
#include <cmath>
#include <functional>
#include <sstream>
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

// Checks that an option is a number in [lo, hi]. CLI11's Range and PositiveNumber let NaN through
// (every comparison with it is false); this rejects NaN and infinities too.
inline CLI::Validator number_in(double lo, double hi) {
  std::ostringstream range;
  range << "[" << lo << ", " << hi << "]";
  return CLI::Validator(
      [lo, hi, bounds = range.str()](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        if (!std::isfinite(value) || value < lo || value > hi) return "value " + text + " is not in " + bounds;
        return {};
      },
      "NUMBER in " + range.str());
}

// Thrown by an action whose outcome is an exit status of its own (`batch`: how many objects failed);
// main() returns it after the command printed its summary.
struct ExitStatus {
  int code = 0;
};

struct CommandRegistration {
  CommandRegistration(std::string name, std::string description, CommandSetup setup) {
    command_registry().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

}  // namespace u3d::cli
