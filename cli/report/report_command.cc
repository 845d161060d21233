#include "cli/report/report_command.h"

#include <cstdio>

#include "cli/command_args.h"
#include "cli/report/report.h"

namespace pb {
namespace {

int RunReport(const std::vector<std::string>& args) {
  CLI::App app{
      "Writes the report of a finished campaign folder (the --out of `pointbake campaign`,\n"
      "holding campaign.json and runs/) again, runs nothing.",
      "pointbake report"};
  std::string campaign_dir, out_dir;
  app.add_option("CAMPAIGN_DIR", campaign_dir, "The campaign folder")->required();
  app.add_option("--out", out_dir, "Report folder (default CAMPAIGN_DIR/report)");
  ReportOptions options;
  app.add_option("--viewpoints", options.max_viewpoints, "Frames shown per scene")
      ->capture_default_str();
  app.add_option("--thumbnail-px", options.thumbnail_px, "Longest side of a frame thumbnail (>= 16)")
      ->capture_default_str();
  app.add_option("--crop-px", options.crop_px, "Side of the zoomed crop, full-size pixels (>= 4)")
      ->capture_default_str();
  if (const std::optional<int> exit = ParseCommandArgs(app, args)) return *exit;
  if (out_dir.empty()) out_dir = campaign_dir + "/report";
  const Status st = WriteCampaignReport(campaign_dir, out_dir, options);
  if (!st.ok()) {
    std::fprintf(stderr, "pointbake report: %s\n", st.message().c_str());
    return 2;
  }
  std::printf("report: %s/report.html (tables: %s/report.md, %s/results.csv)\n", out_dir.c_str(),
              out_dir.c_str(), out_dir.c_str());
  return 0;
}

}  // namespace

CliCommand ReportCommand() {
  return {"report", "Write the report of a finished campaign folder again (runs nothing)", RunReport};
}

}  // namespace pb
