// Campaign report: reads a finished campaign folder (the contract is in
// report.h) and writes results.json, results.csv, report.md, report.html and
// images/. docs/report.md describes every file, the time grouping (paper
// Fig. 7), the speed-ups and the crop rule.
//
// This file is the order of the work; the pieces are declared in
// report_internal.h: reading and the data files (report_read.cc), images
// (report_images.cc), charts, Markdown and HTML (report_html.cc).
#include "cli/report/report.h"

#include <string>
#include <utility>
#include <vector>

#include "base/env.h"
#include "cli/report/report_internal.h"

namespace pb {

Status WriteCampaignReport(const std::string& campaign_dir, const std::string& report_dir,
                           const ReportOptions& options) {
  namespace ri = report_internal;
  if (options.thumbnail_px < 16 || options.crop_px < 4 || options.max_viewpoints < 0)
    return Status::Invalid(
        "report options: thumbnail_px must be >= 16, crop_px >= 4, max_viewpoints >= 0");
  PB_ASSIGN_OR_RETURN(ri::Campaign campaign, ri::ReadCampaign(campaign_dir));
  Env* env = Env::Default();
  PB_RETURN_IF_ERROR(env->CreateDirs(JoinPath(report_dir, "images")));
  std::vector<ri::SceneImages> images;
  for (const std::string& scene : campaign.scenes) {
    PB_ASSIGN_OR_RETURN(ri::SceneImages s,
                        ri::BuildSceneImages(campaign, scene, report_dir, options));
    images.push_back(std::move(s));
  }
  const std::vector<ri::SpeedUp> speedups = ri::SpeedUps(campaign);
  const std::vector<ri::SpeedUpMean> means = ri::GeometricMeans(speedups);
  const ri::ReportTexts texts = ri::RenderReport(campaign, speedups, means, images, options);
  PB_RETURN_IF_ERROR(
      env->WriteFileAtomic(JoinPath(report_dir, "results.json"),
                           ri::ResultsJson(campaign, speedups, means).dump(2) + "\n"));
  PB_RETURN_IF_ERROR(
      env->WriteFileAtomic(JoinPath(report_dir, "results.csv"), ri::ResultsCsv(campaign)));
  PB_RETURN_IF_ERROR(env->WriteFileAtomic(JoinPath(report_dir, "report.md"), texts.markdown));
  PB_RETURN_IF_ERROR(env->WriteFileAtomic(JoinPath(report_dir, "report.html"), texts.html));
  return ri::WriteViewer(campaign, report_dir);
}

}  // namespace pb
