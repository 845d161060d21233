#include "stages/report/report.h"

namespace pb {

Status WriteCampaignReport(const std::string& campaign_dir, const std::string& report_dir,
                           const ReportOptions& options) {
  (void)campaign_dir;
  (void)report_dir;
  (void)options;
  return Status::Unsupported("campaign reports are not written yet");
}

}  // namespace pb
