// Campaigns: scenes x workflows x parameter overrides, expanded into runs
// that share one cache and write one folder (docs/campaigns.md).
//
// A campaign file (schemas/campaign.schema.json):
//   name: demo
//   scenes: [../scenes/synthetic-room.yaml, ...]        relative to this file
//   workflows:
//     - ../workflows/hpm.yaml                            a plain run
//     - file: ../workflows/point_transfer.yaml           runs with overrides:
//       set: { transfer.size: 4096 }                     applied to each
//       matrix: { transfer.interpolation: [nearest, splat] }  one run each
//       label: big                                        optional run label
// expands, per scene in order, into one run per workflow entry and matrix
// combination. Run names are readable and unique:
//   <scene name>/<workflow name>[+<variant>]
// where the variant is the label and the matrix values
// (e.g. "interpolation=splat"; "big,interpolation=splat").
//
// The folder <out>/ holds campaign.json (the manifest; format in
// cli/report/report.h), runs/<scene>/<workflow>[+<variant>]/ (each run's
// run.json and named outputs, as `pointbake run --out`) and report/.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "base/status.h"
#include "engine/registry.h"
#include "engine/run_workflow.h"

namespace pb {

struct CampaignRun {
  std::string name;     // "synthetic-room/point_transfer+interpolation=splat"
  std::string dir;      // relative to the campaign folder: "runs/<name with + kept>"
  std::string scene;    // the scene's name
  std::string scene_file;     // absolute
  std::string workflow;       // the workflow's name
  std::string workflow_file;  // absolute
  std::string variant;        // "" or e.g. "interpolation=splat"
  std::vector<std::string> sets;  // STAGE.PARAM=VALUE, as --set
  std::vector<std::string> stages;  // the workflow's stage ids, when the campaign was loaded
};

struct Campaign {
  std::string name;
  std::string file;  // absolute
  std::string description;
  std::vector<CampaignRun> runs;
};

// Reads and validates a campaign file and expands it. Every run's workflow is
// loaded with its scene and overrides (plugins go into `registry`), so a
// typo in any of them is reported before anything runs; errors are
// `file:line:column: message`, all at once.
Expected<Campaign> LoadCampaign(const std::string& path, Registry& registry);

// `campaign --force` (`flag`): every id must name a stage of at least one
// run's workflow (CampaignRun::stages); Status::Invalid naming the others,
// with the stages the runs have.
Status CheckCampaignStageIds(const Campaign& campaign, const std::vector<std::string>& ids,
                             const std::string& flag);

const nlohmann::json& CampaignSchemaJson();

// Writes the report of a finished campaign folder into report_dir.
using CampaignReportWriter =
    std::function<Status(const std::string& campaign_dir, const std::string& report_dir)>;

struct CampaignOptions {
  WorkflowRunOptions run;  // per run: jobs, memory budget, threads, ...
  std::string out_dir;     // default out/<campaign name>
  int parallel_runs = 1;   // runs at once (a cluster executor: many)
};

struct CampaignResult {
  int runs = 0, failed_runs = 0;
  std::string out_dir;
  std::string report_dir;  // empty if no report was written
  Status report;           // writing the manifest and the report
};

// Runs every run (`parallel_runs` at a time, in order) against `cache` (held with a shared lock by the
// caller), then writes <out>/campaign.json and the report (when `report` is
// set). A failed run does not stop the others; its row says "failed".
CampaignResult RunCampaign(const Campaign& campaign, Cache& cache, const CampaignOptions& options,
                           Registry& registry, const CampaignReportWriter& report);

}  // namespace pb
