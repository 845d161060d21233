// Run records: what a run did, per stage, in three files of the output folder:
//   run.json    {"format": "pointbake-run 1", workflow, started, options,
//               stages: [{stage, type, status (hit|ran|failed|skipped), key,
//               start_s, end_s, wall_s, user_s, sys_s, peak_rss_bytes,
//               read_bytes, write_bytes, counters, phases, error, cached_run,
//               group (the stage's `group:`, when it has one), warnings
//               (when the stage gave any: an array of one-line strings; for
//               a hit, those of the run that made the entry), forced (true
//               when --force made it run)}],
//               outputs: {name: "<stage>.<port>"} (the workflow's named
//               outputs, also those this run did not produce),
//               disabled_stages: [ids left out by `when:`] (when any)}
//   run.jsonl   one line per stage, same fields (for appending tools / jq)
//   trace.json  Chrome trace events (chrome://tracing, Perfetto): one lane
//               per parallel slot, phases nested in their stage
// For a cache hit, wall_s etc. are this run's (near zero) and `cached_run`
// holds the figures of the run that produced the entry.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/cache.h"
#include "engine/scheduler.h"

namespace pb {

nlohmann::json StageRecordJson(const StageOutcome& outcome);
nlohmann::json RunRecordJson(const Workflow& workflow, const std::vector<StageOutcome>& outcomes,
                             const nlohmann::json& run_info);
nlohmann::json ChromeTraceJson(const Workflow& workflow, const std::vector<StageOutcome>& outcomes);

// Writes run.json, run.jsonl, trace.json and copies the workflow's named
// outputs that this run produced or hit into `out_dir` (each file by
// temporary name + rename; outputs of failed stages keep their earlier copy).
// Single-file artifacts become <out>/<name>.<ext>; others <out>/<name>/<file>.
Status WriteRunOutputs(const Workflow& workflow, const std::vector<StageOutcome>& outcomes,
                       const nlohmann::json& run_info, Cache& cache, const std::string& out_dir,
                       std::vector<std::string>* written = nullptr);

}  // namespace pb
