#include "cli/command_args.h"

namespace pb {

std::optional<int> ParseCommandArgs(CLI::App& app, const std::vector<std::string>& args) {
  app.failure_message(CLI::FailureMessage::help);
  // CLI11 takes the words last first.
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return std::nullopt;
}

}  // namespace pb
