// Argument parsing of the commands that parse their own words (compare,
// report) with CLI11, as the engine's commands in cli.cc do.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace pb {

// Parses `args` (the words after the command's name) into `app`'s options.
// Returns nothing to go on, or the exit status to return: 0 after --help
// (printed to stdout), 2 for a usage error (the problem and the help on
// stderr).
std::optional<int> ParseCommandArgs(CLI::App& app, const std::vector<std::string>& args);

}  // namespace pb
