#include "cli/report/report_command.h"

#include <charconv>
#include <cstdio>

#include "cli/report/report.h"

namespace pb {
namespace {

constexpr const char* kUsage =
    "Usage: pointbake report CAMPAIGN_DIR [--out DIR] [--viewpoints N] [--thumbnail-px N] [--crop-px N]\n"
    "\n"
    "Writes the report of a finished campaign folder (the --out of `pointbake\n"
    "campaign`, holding campaign.json and runs/) again, runs nothing.\n"
    "\n"
    "Options:\n"
    "  --out DIR           report folder (default CAMPAIGN_DIR/report)\n"
    "  --viewpoints N      frames shown per scene (default 1)\n"
    "  --thumbnail-px N    longest side of a frame thumbnail (default 320, >= 16)\n"
    "  --crop-px N         side of the zoomed crop, full-size pixels (default 96, >= 4)\n"
    "  -h, --help          this text\n";

int Usage(const std::string& problem) {
  std::fprintf(stderr, "pointbake report: %s\n\n%s", problem.c_str(), kUsage);
  return 2;
}

bool ParseInt(const std::string& text, int* value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), *value);
  return ec == std::errc() && end == text.data() + text.size();
}

int RunReport(const std::vector<std::string>& args) {
  std::string campaign_dir, out_dir;
  ReportOptions options;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (a == "--out" || a == "--viewpoints" || a == "--thumbnail-px" || a == "--crop-px") {
      if (i + 1 >= args.size()) return Usage(a + " needs a value");
      const std::string& value = args[++i];
      if (a == "--out") {
        out_dir = value;
        continue;
      }
      int* target = a == "--viewpoints"     ? &options.max_viewpoints
                    : a == "--thumbnail-px" ? &options.thumbnail_px
                                            : &options.crop_px;
      if (!ParseInt(value, target)) return Usage(a + ": expected an integer, got '" + value + "'");
    } else if (!a.empty() && a[0] == '-') {
      return Usage("unknown option " + a);
    } else if (campaign_dir.empty()) {
      campaign_dir = a;
    } else {
      return Usage("one campaign folder only (got '" + campaign_dir + "' and '" + a + "')");
    }
  }
  if (campaign_dir.empty()) return Usage("missing CAMPAIGN_DIR");
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
