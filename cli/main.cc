// pointbake: the engine's CLI with the built-in stages and commands.
#include "cli/cli.h"
#include "stages/builtin.h"
#include "cli/compare_command.h"
#include "cli/scene_command.h"
#include "cli/report/report.h"
#include "cli/report/report_command.h"
#include "cli/serve_command.h"

int main(int argc, char** argv) {
  pb::Registry registry;
  pb::RegisterBuiltinStages(registry);
  return pb::CliMain(argc, argv, registry, {pb::CompareCommand(), pb::ReportCommand(), pb::SceneCommand(), pb::ServeCommand()},
                     [](const std::string& campaign_dir, const std::string& report_dir) {
                       return pb::WriteCampaignReport(campaign_dir, report_dir);
                     });
}
