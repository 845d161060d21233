// The `pointbake` command line. The engine's CLI knows no stage: main() fills
// the registry with the built-in stages and hands it over.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "engine/campaign.h"
#include "engine/registry.h"

namespace pb {

// A sub-command added by main() from outside the engine (e.g. `compare`, which
// needs the geometry library the engine does not link). `run` gets the
// arguments after the sub-command's name, parses them itself (including
// -h/--help) and returns the exit status.
struct CliCommand {
  std::string name;
  std::string summary;  // one line for `pointbake --help`
  std::function<int(const std::vector<std::string>& args)> run;
};

// Exit status: 0 success, 1 a stage (or a campaign run) failed, 2 bad input or
// usage. `report` writes campaign reports (`campaign`, `demo`); without it
// campaigns write their runs and campaign.json only.
int CliMain(int argc, char** argv, Registry& registry, const std::vector<CliCommand>& extra = {},
            const CampaignReportWriter& report = {});

}  // namespace pb
